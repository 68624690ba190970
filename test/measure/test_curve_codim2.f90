!> Codim-2 points on fold and period-doubling curves (docs/model.md section 12.6), confirmed by
!> what the multipliers say, not by the test function that located them. A chain of two
!> oscillators with unequal spacings (1, 0.7, 1.3: no mirror symmetry, so no multiplier is
!> doubled), K = 0.8, b = 0.02: the first period doubling of its period-1 orbit from rest at
!> A = 0.3, w = 1.4 upwards, followed up in w, meets a fold curve: the fold-flip point is
!> located on it, its orbit with multipliers +1 and -1, each to 1e-8; further on a second
!> multiplier comes to -1: the 1:2 point, two multipliers -1 to 1e-5. The first fold of the same
!> orbit, followed up in w, meets a second multiplier +1: the 1:1 point, two multipliers +1.
module test_curve_codim2
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_model, only: model_t
    use chain_orbit, only: orbit_t, multiplier_distance
    use chain_branch, only: branch_options_t, branches_t, follow_branches
    use chain_curve, only: curve_options_t, curve_t, follow_curve
    use chain_flow, only: make_flow
    use test_chains, only: model_of
    use test_branch, only: settle
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_curve_codim2_tests

contains

    subroutine run_curve_codim2_tests(t)
        type(tally_t), intent(inout) :: t

        call doubling_codim2(t)
        call fold_one_to_one(t)
    end subroutine run_curve_codim2_tests

    !> The fold curve from w = 1.4 up in w: its second real multiplier (4.5 at the start) comes
    !> down to +1, a 1:1 point, two multipliers within 1e-5 of +1, between its neighbours.
    subroutine fold_one_to_one(t)
        type(tally_t), intent(inout) :: t
        type(branches_t) :: fold
        type(curve_t) :: curve
        type(curve_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: k

        call first_special(1.4_wp, 'fold', fold, k)
        call check(t, k > 0, '1:1: a fold at w = 1.4')
        if (k == 0) return
        opt%follow = 'fold'
        opt%parameter = 'amplitude'
        opt%parameter2 = 'omega'
        opt%stop2 = 1.7_wp
        opt%step2 = 0.03_wp
        opt%max_points = 30
        call follow_curve(two_oscillators(fold%points(k)%value, 1.4_wp), 0.0_wp, 1, &
                          fold%points(k)%orbit%x, fold%points(k)%orbit%v, fold%points(k)%value, &
                          opt, curve, err)
        call check(t, .not. allocated(err), '1:1: the fold curve followed')
        if (allocated(err)) then
            print '(a)', '    '//err%message
            return
        end if
        print '(a,i0,a,i0,a)', '    fold curve: ', curve%n_points, ' points, ', &
            curve%n_codim2, ' codim-2, '//curve%end_reason
        call check(t, curve%n_codim2 == 1, '1:1: one codim-2 point on the curve')
        if (curve%n_codim2 /= 1) return
        call check(t, curve%codim2_kind(1) == '1:1', "1:1: its kind '1:1'")
        call check_point(t, curve, curve%codim2_index(1))
        call check_close(t, nearest(curve%orbits(curve%codim2_index(1)), 1.0_wp, 2), 0.0_wp, &
                         '1:1: two multipliers +1', 1.0e-5_wp)
    end subroutine fold_one_to_one

    !> The period-doubling curve from w = 1.4 up in w: a fold-flip point, a point of the curve
    !> with multipliers +1 and -1 (each to 1e-8), and then a 1:2 point, two multipliers within
    !> 1e-5 of -1 (a Jordan block: see chain_curve_codim2), each between its neighbours in w.
    subroutine doubling_codim2(t)
        type(tally_t), intent(inout) :: t
        type(branches_t) :: pd
        type(curve_t) :: curve
        type(curve_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: k, j

        call first_special(1.4_wp, 'period-doubling', pd, k)
        call check(t, k > 0, 'doubling codim-2: a period doubling at w = 1.4')
        if (k == 0) return
        opt%follow = 'period-doubling'
        opt%parameter = 'amplitude'
        opt%parameter2 = 'omega'
        opt%stop2 = 2.6_wp
        opt%step2 = 0.03_wp
        opt%max_points = 60
        call follow_curve(two_oscillators(pd%points(k)%value, 1.4_wp), 0.0_wp, 1, &
                          pd%points(k)%orbit%x, pd%points(k)%orbit%v, pd%points(k)%value, opt, &
                          curve, err)
        call check(t, .not. allocated(err), 'doubling codim-2: the curve followed')
        if (allocated(err)) then
            print '(a)', '    '//err%message
            return
        end if
        print '(a,i0,a,i0,a)', '    doubling curve: ', curve%n_points, ' points, ', &
            curve%n_codim2, ' codim-2, '//curve%end_reason
        call check(t, curve%n_codim2 == 2, 'doubling codim-2: two codim-2 points on the curve')
        if (curve%n_codim2 /= 2) return
        call check(t, curve%codim2_kind(1) == 'fold-flip' .and. curve%codim2_kind(2) == '1:2', &
                   "doubling codim-2: 'fold-flip', then '1:2'")
        do j = 1, 2
            call check_point(t, curve, curve%codim2_index(j))
        end do
        j = curve%codim2_index(1)
        call check_close(t, multiplier_distance(curve%orbits(j), 1.0_wp), 0.0_wp, &
                         'fold-flip: a multiplier +1', 1.0e-8_wp)
        call check_close(t, multiplier_distance(curve%orbits(j), -1.0_wp), 0.0_wp, &
                         'fold-flip: a multiplier -1', 1.0e-8_wp)
        j = curve%codim2_index(2)
        call check_close(t, nearest(curve%orbits(j), -1.0_wp, 2), 0.0_wp, &
                         '1:2: two multipliers -1', 1.0e-5_wp)
    end subroutine doubling_codim2

    !> The codim-2 point j of the curve lies between its neighbours in the second parameter;
    !> where it is and its multipliers' distances from +1 and -1 are printed.
    subroutine check_point(t, curve, j)
        type(tally_t), intent(inout) :: t
        type(curve_t), intent(in) :: curve
        integer, intent(in) :: j

        call check(t, j > 1 .and. j < curve%n_points, 'codim-2: a point between two points')
        if (j <= 1 .or. j >= curve%n_points) return
        write (*, '(a,f16.12,a,f16.12,a,2es9.2,a,2es9.2)') '    at A = ', curve%values(j), &
            ', w = ', curve%values2(j), '; two nearest to +1: ', nearest(curve%orbits(j), &
            1.0_wp, 1), nearest(curve%orbits(j), 1.0_wp, 2), ', to -1: ', &
            nearest(curve%orbits(j), -1.0_wp, 1), nearest(curve%orbits(j), -1.0_wp, 2)
        call check(t, (curve%values2(j) - curve%values2(j - 1))* &
                   (curve%values2(j + 1) - curve%values2(j)) > 0, &
                   'codim-2: between its neighbours in w')
    end subroutine check_point

    !> The distance of the orbit's `rank`-th nearest multiplier (1 or 2) from `target`.
    pure real(wp) function nearest(orbit, target, rank)
        type(orbit_t), intent(in) :: orbit
        real(wp), intent(in) :: target
        integer, intent(in) :: rank
        real(wp), allocatable :: d(:)
        integer :: i

        d = abs(cmplx(orbit%multipliers_re - target, orbit%multipliers_im, wp))
        nearest = minval(d)
        if (rank == 2) nearest = minval(d, mask=[(i /= minloc(d, 1), i=1, size(d))])
    end function nearest

    !> The period-1 orbit of the two oscillators from rest at A = 0.3, frequency w, followed up
    !> to A = 6; k the point of its first special point of this kind (0: none).
    subroutine first_special(omega, kind, res, k)
        real(wp), intent(in) :: omega
        character(len=*), intent(in) :: kind
        type(branches_t), intent(out) :: res
        integer, intent(out) :: k
        type(orbit_t) :: start
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: j

        k = 0
        call settle(two_oscillators(0.3_wp, omega), 20_i8, 1, start)
        opt%parameter = 'amplitude'
        opt%stop = 6.0_wp
        opt%step = 0.05_wp
        opt%max_points = 300
        call follow_branches(two_oscillators(0.3_wp, omega), 0.0_wp, 1, start%x, start%v, opt, &
                             res, err)
        if (allocated(err)) return
        do j = res%n_specials, 1, -1
            if (res%specials(j)%kind == kind .and. res%points(res%specials(j)%point)%branch == 0) &
                k = res%specials(j)%point
        end do
    end subroutine first_special

    !> Two oscillators, spacings 1, 0.7, 1.3 (walls at both ends), K = 0.8, b = 0.02.
    function two_oscillators(amplitude, omega) result(model)
        real(wp), intent(in) :: amplitude, omega
        type(model_t) :: model

        model = model_of(make_flow(0.02_wp, amplitude, omega), 0.8_wp, &
                         [1.0_wp, 0.7_wp, 1.3_wp], .true., 1.0e-9_wp)
    end function two_oscillators

end module test_curve_codim2
