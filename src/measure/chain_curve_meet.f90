!> Where a fold or period-doubling curve meets a grazing curve (docs/model.md section 12.6): a
!> codim-2 point, the orbit with a multiplier +1 or -1 whose gap minimum touches zero. It is
!> the zero of the curve's system with the grazing test as one more equation, unknowns
!> (z, mu1, mu2), n_z + 2 equations and no arclength row, solved by Newton with the grazing
!> bond lifted (chain_curve_system) so that the iterates may fall past the grazing.
module chain_curve_meet
    use chain_kinds, only: wp
    use chain_error, only: error_t
    use chain_lapack, only: solve_linear
    use chain_curve_system, only: curve_setting_t, curve_state_t, evaluate, lift_grazing_bond, &
                                  grazing_aim, gap_and_row
    implicit none
    private
    public :: meet_grazing

contains

    !> From y_last, a point of a fold or period-doubling curve (its setting `set`) near a
    !> grazing of its smallest gap, the meeting of the two: met when Newton converges within
    !> `reach` of y_last; then y is the point and st the curve's system there.
    subroutine meet_grazing(set, y_last, reach, tolerance, y, st, met, err)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y_last(:), reach, tolerance
        real(wp), allocatable, intent(out) :: y(:)
        type(curve_state_t), intent(out) :: st
        logical, intent(out) :: met
        type(error_t), allocatable, intent(out) :: err
        integer, parameter :: max_iterations = 30
        type(curve_setting_t) :: lifted
        character(len=:), allocatable :: failure
        real(wp), allocatable :: row(:), a(:, :), rhs(:, :)
        real(wp) :: gap
        integer :: m, iteration, info

        met = .false.
        m = size(y_last) - 2
        lifted = set
        call lift_grazing_bond(lifted, y_last, err)
        if (allocated(err)) then
            ! (no gap that can graze: the curve ended for another reason)
            deallocate (err)
            return
        end if
        y = y_last
        do iteration = 0, max_iterations
            call evaluate(lifted, y, st, err, .true.)
            if (allocated(err) .or. len(st%failure) > 0) return
            failure = ''
            call gap_and_row(lifted, y, gap, row, failure, err)
            if (allocated(err) .or. len(failure) > 0) return
            if (st%pass%residual <= tolerance .and. abs(st%s) <= tolerance .and. &
                abs(gap) <= grazing_aim/2 .and. iteration > 0) exit
            if (iteration == max_iterations) return
            allocate (a(m + 2, m + 2), rhs(m + 2, 1))
            a(:m + 1, :) = st%rows
            a(m + 2, :) = row
            rhs(:, 1) = -[st%residual, gap]
            call solve_linear(a, rhs, info)
            if (info > 0) return
            y = y + rhs(:, 1)
            deallocate (a, rhs)
        end do
        if (norm2(y - y_last) > reach) return
        ! (its gap is grazing_aim > 0: the lifted bond does not close, the pass is the chain's)
        call evaluate(lifted, y, st, err, .false.)
        met = .not. allocated(err) .and. len(st%failure) == 0
    end subroutine meet_grazing

end module chain_curve_meet
