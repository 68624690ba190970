!> Fold and period-doubling curves in two parameters (docs/model.md section 12.6), against
!> what cannot be tuned: figure 10's fold (A = 2.8851913 at w = 1.9) followed in (A, w) passes
!> through the folds that one-parameter runs locate at two other points' w, to 1e-8 in A, and
!> at every point of the curve J has a multiplier +1; the same for the period doubling of a
!> single impact oscillator (n = 1, walls 0.5 and 100 away, K = 0.8, w = 2.5) and a
!> multiplier -1.
module test_curve
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_model, only: model_t, set_model_parameter
    use chain_orbit, only: orbit_t, multiplier_distance
    use chain_branch, only: branch_options_t, branches_t, follow_branches
    use chain_curve, only: curve_options_t, curve_t, follow_curve
    use chain_flow, only: make_flow
    use test_chains, only: fig10_model, model_of
    use test_branch, only: settle
    use test_curve_graze, only: grazing_curve, impacting_grazing_curve, fold_meets_grazing
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_curve_tests

contains

    subroutine run_curve_tests(t)
        type(tally_t), intent(inout) :: t

        call fold_curve(t)
        call doubling_curve(t)
        call grazing_curve(t)
        call impacting_grazing_curve(t)
        call fold_meets_grazing(t)
        call fold_curve_grazes(t)
        call unknown_kind(t)
    end subroutine run_curve_tests

    !> A kind no curve follows is an error that names it and the kinds allowed.
    subroutine unknown_kind(t)
        type(tally_t), intent(inout) :: t
        type(curve_options_t) :: opt
        type(curve_t) :: curve
        type(error_t), allocatable :: err
        integer :: k

        opt%follow = 'cusp'
        opt%parameter = 'amplitude'
        opt%parameter2 = 'omega'
        opt%step2 = 0.01_wp
        call follow_curve(fig10_model(3.0_wp), 0.0_wp, 1, [(0.0_wp, k=1, 8)], &
                          [(0.0_wp, k=1, 8)], 3.0_wp, opt, curve, err)
        call check(t, allocated(err), 'curve: follow = cusp refused')
        if (.not. allocated(err)) return
        call check(t, index(err%message, "'cusp'") > 0 .and. &
                   index(err%message, 'period-doubling') > 0, &
                   'curve: the error names the value and the kinds allowed')
    end subroutine unknown_kind

    subroutine fold_curve(t)
        type(tally_t), intent(inout) :: t
        type(curve_t) :: curve
        type(error_t), allocatable :: err
        logical :: found
        integer :: j

        call fold_curve_up(1.95_wp, 0.01_wp, 8, found, curve, err)
        call check(t, found, 'fold curve: a fold at w = 1.9')
        if (.not. found) return
        call check(t, .not. allocated(err), 'fold curve: followed')
        if (allocated(err)) then
            print '(a)', '    '//err%message
            return
        end if
        print '(a,i0,a)', '    fold curve: ', curve%n_points, ' points, '//curve%end_reason
        call check(t, curve%n_points >= 4, 'fold curve: at least four points')
        if (curve%n_points < 4) return
        do j = 1, curve%n_points
            write (*, '(a,f15.11,a,f15.11,a,es9.2)') '    A = ', curve%values(j), ', w = ', &
                curve%values2(j), ', |multiplier - 1| = ', multiplier_distance(curve%orbits(j), 1.0_wp)
        end do
        call check_close(t, maxval([(multiplier_distance(curve%orbits(j), 1.0_wp), j=1, curve%n_points)]), &
                         0.0_wp, 'fold curve: a multiplier +1 at every point', 1.0e-7_wp)
        call compare_with_branch(t, curve, 2)
        call compare_with_branch(t, curve, curve%n_points)
    end subroutine fold_curve

    !> Figure 10's fold followed up in w: the curve ends where an impact's speed on its orbit
    !> vanishes (a grazing), named so, its last orbit's speed small and the extrapolated
    !> point just past it.
    subroutine fold_curve_grazes(t)
        type(tally_t), intent(inout) :: t
        type(curve_t) :: curve
        type(error_t), allocatable :: err
        logical :: found
        integer :: k

        call fold_curve_up(2.6_wp, 0.05_wp, 100, found, curve, err)
        if (.not. found) return
        call check(t, .not. allocated(err), 'fold curve to a grazing: followed')
        if (allocated(err)) return
        k = curve%n_points
        print '(a,i0,a)', '    fold curve up in w: ', k, ' points, '//curve%end_reason
        write (*, '(a,f13.9,a,f13.9,a,es9.2)') '    last point A = ', curve%values(k), &
            ', w = ', curve%values2(k), ', smallest impact speed ', &
            curve%orbits(k)%min_impact_speed
        call check(t, index(curve%end_reason, "grazing: an impact's speed vanishes near "// &
                            "amplitude = ") == 1, &
                   "fold curve to a grazing: the end named (an impact's speed vanishes)")
        call check(t, curve%orbits(k)%min_impact_speed < 0.05_wp .and. &
                   all(curve%orbits(k)%multipliers_re /= 0), &
                   'fold curve to a grazing: the last orbit impacts slowly')
    end subroutine fold_curve_grazes

    !> Figure 10's fold at w = 1.9 (found: located by fold_at) followed in (A, w) up to
    !> w = stop2 with steps step2, at most max_points points.
    subroutine fold_curve_up(stop2, step2, max_points, found, curve, err)
        real(wp), intent(in) :: stop2, step2
        integer, intent(in) :: max_points
        logical, intent(out) :: found
        type(curve_t), intent(out) :: curve
        type(error_t), allocatable, intent(out) :: err
        type(branches_t) :: fold
        type(curve_options_t) :: opt
        integer :: k

        call fold_at(1.9_wp, fold)
        found = fold%n_specials >= 1
        if (.not. found) return
        k = fold%specials(1)%point
        opt%follow = 'fold'
        opt%parameter = 'amplitude'
        opt%parameter2 = 'omega'
        opt%stop2 = stop2
        opt%step2 = step2
        opt%max_points = max_points
        call follow_curve(fig10_model(fold%points(k)%value), 0.0_wp, 1, &
                          fold%points(k)%orbit%x, fold%points(k)%orbit%v, &
                          fold%points(k)%value, opt, curve, err)
    end subroutine fold_curve_up

    !> The impact oscillator's first period doubling from A = 8 down, followed in (A, w).
    subroutine doubling_curve(t)
        type(tally_t), intent(inout) :: t
        type(branches_t) :: pd
        type(curve_t) :: curve
        type(curve_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: k, j

        call doubling_at(2.5_wp, pd, k)
        call check(t, k > 0, 'doubling curve: a period doubling at w = 2.5')
        if (k == 0) return
        opt%follow = 'period-doubling'
        opt%parameter = 'amplitude'
        opt%parameter2 = 'omega'
        opt%stop2 = 2.6_wp
        opt%step2 = 0.01_wp
        opt%max_points = 6
        call follow_curve(oscillator(pd%points(k)%value, 2.5_wp), 0.0_wp, 1, &
                          pd%points(k)%orbit%x, pd%points(k)%orbit%v, pd%points(k)%value, opt, &
                          curve, err)
        call check(t, .not. allocated(err), 'doubling curve: followed')
        if (allocated(err)) then
            print '(a)', '    '//err%message
            return
        end if
        print '(a,i0,a)', '    doubling curve: ', curve%n_points, ' points, '//curve%end_reason
        call check(t, curve%n_points >= 4, 'doubling curve: at least four points')
        if (curve%n_points < 4) return
        call check_close(t, maxval([(multiplier_distance(curve%orbits(j), -1.0_wp), &
                                     j=1, curve%n_points)]), 0.0_wp, &
                         'doubling curve: a multiplier -1 at every point', 1.0e-7_wp)
        do j = 2, curve%n_points, curve%n_points - 2
            call doubling_at(curve%values2(j), pd, k)
            call check(t, k > 0, 'doubling curve: a one-parameter doubling at its w')
            if (k == 0) cycle
            write (*, '(a,f15.11,a,es9.2)') '    one-parameter doubling at w = ', &
                curve%values2(j), ': |A - curve| = ', abs(pd%points(k)%value - curve%values(j))
            call check_close(t, pd%points(k)%value, curve%values(j), &
                             'doubling curve: through the one-parameter doubling', 1.0e-8_wp)
        end do
    end subroutine doubling_curve

    !> The impact oscillator's period-1 orbit at A = 8, frequency w, followed down to 4.5; k the
    !> point of its first period doubling (0: none).
    subroutine doubling_at(omega, res, k)
        real(wp), intent(in) :: omega
        type(branches_t), intent(out) :: res
        integer, intent(out) :: k
        type(orbit_t) :: start
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: j

        k = 0
        call settle(oscillator(8.0_wp, omega), 1000_i8, 1, start)
        opt%parameter = 'amplitude'
        opt%stop = 4.5_wp
        opt%step = -0.05_wp
        call follow_branches(oscillator(8.0_wp, omega), 0.0_wp, 1, start%x, start%v, opt, res, &
                             err)
        if (allocated(err)) return
        do j = res%n_specials, 1, -1
            if (res%specials(j)%kind == 'period-doubling') k = res%specials(j)%point
        end do
    end subroutine doubling_at

    !> The single impact oscillator of the period-doubling test at amplitude A, frequency w.
    function oscillator(amplitude, omega) result(model)
        real(wp), intent(in) :: amplitude, omega
        type(model_t) :: model

        model = model_of(make_flow(0.05_wp, amplitude, omega), 0.8_wp, [0.5_wp, 100.0_wp], &
                         .true., 1.0e-9_wp)
    end function oscillator

    !> The one-parameter fold at the w of the curve's point j equals the curve's A there.
    subroutine compare_with_branch(t, curve, j)
        type(tally_t), intent(inout) :: t
        type(curve_t), intent(in) :: curve
        integer, intent(in) :: j
        type(branches_t) :: fold

        call fold_at(curve%values2(j), fold)
        call check(t, fold%n_specials >= 1, 'fold curve: a one-parameter fold at its w')
        if (fold%n_specials < 1) return
        write (*, '(a,f15.11,a,es9.2)') '    one-parameter fold at w = ', curve%values2(j), &
            ': |A - curve| = ', abs(fold%specials(1)%value - curve%values(j))
        call check_close(t, fold%specials(1)%value, curve%values(j), &
                         'fold curve: through the one-parameter fold', 1.0e-8_wp)
    end subroutine compare_with_branch

    !> Figure 10's impacting orbit at A = 3, frequency w, followed down to its fold.
    subroutine fold_at(omega, res)
        real(wp), intent(in) :: omega
        type(branches_t), intent(out) :: res
        type(model_t) :: model
        type(orbit_t) :: start
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err

        model = fig10_model(3.0_wp)
        call set_model_parameter(model, 'omega', omega)
        call settle(model, 5_i8, 1, start)
        opt%parameter = 'amplitude'
        opt%stop = 2
        opt%step = -0.05_wp
        call follow_branches(model, 0.0_wp, 1, start%x, start%v, opt, res, err)
    end subroutine fold_at

end module test_curve
