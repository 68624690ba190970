!> Codim-2 points on fold and period-doubling curves (docs/model.md section 12.6), confirmed by
!> what the multipliers say, not by the test function that located them. A chain of two
!> oscillators with unequal spacings (1, 0.7, 1.3: no mirror symmetry, so no multiplier is
!> doubled), K = 0.8, b = 0.02: the first period doubling of its period-1 orbit from rest at
!> A = 0.3, w = 1.4 upwards, followed up in w, meets a fold curve: the fold-flip point is
!> located on it, its orbit with multipliers +1 and -1, each to 1e-8.
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

        call doubling_fold_flip(t)
    end subroutine run_curve_codim2_tests

    !> The period-doubling curve from w = 1.4 up in w: one fold-flip point, a point of the
    !> curve with multipliers +1 and -1 (each to 1e-8), between its neighbours in w.
    subroutine doubling_fold_flip(t)
        type(tally_t), intent(inout) :: t
        type(branches_t) :: pd
        type(curve_t) :: curve
        type(curve_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: k, j

        call first_special(1.4_wp, 'period-doubling', pd, k)
        call check(t, k > 0, 'fold-flip: a period doubling at w = 1.4')
        if (k == 0) return
        opt%follow = 'period-doubling'
        opt%parameter = 'amplitude'
        opt%parameter2 = 'omega'
        opt%stop2 = 2.6_wp
        opt%step2 = 0.03_wp
        opt%max_points = 40
        call follow_curve(two_oscillators(pd%points(k)%value, 1.4_wp), 0.0_wp, 1, &
                          pd%points(k)%orbit%x, pd%points(k)%orbit%v, pd%points(k)%value, opt, &
                          curve, err)
        call check(t, .not. allocated(err), 'fold-flip: doubling curve followed')
        if (allocated(err)) then
            print '(a)', '    '//err%message
            return
        end if
        print '(a,i0,a,i0,a)', '    doubling curve: ', curve%n_points, ' points, ', &
            curve%n_codim2, ' codim-2, '//curve%end_reason
        call check(t, curve%n_codim2 == 1, 'fold-flip: one codim-2 point on the curve')
        if (curve%n_codim2 /= 1) return
        call check(t, curve%codim2_kind(1) == 'fold-flip', "fold-flip: its kind 'fold-flip'")
        j = curve%codim2_index(1)
        call check(t, j > 1 .and. j < curve%n_points, 'fold-flip: between two points')
        if (j <= 1 .or. j >= curve%n_points) return
        write (*, '(a,f16.12,a,f16.12,a,es9.2,a,es9.2)') '    fold-flip at A = ', &
            curve%values(j), ', w = ', curve%values2(j), '; |mu - 1| = ', &
            multiplier_distance(curve%orbits(j), 1.0_wp), ', |mu + 1| = ', &
            multiplier_distance(curve%orbits(j), -1.0_wp)
        call check(t, (curve%values2(j) - curve%values2(j - 1))* &
                   (curve%values2(j + 1) - curve%values2(j)) > 0, &
                   'fold-flip: between its neighbours in w')
        call check_close(t, multiplier_distance(curve%orbits(j), 1.0_wp), 0.0_wp, &
                         'fold-flip: a multiplier +1', 1.0e-8_wp)
        call check_close(t, multiplier_distance(curve%orbits(j), -1.0_wp), 0.0_wp, &
                         'fold-flip: a multiplier -1', 1.0e-8_wp)
    end subroutine doubling_fold_flip

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
