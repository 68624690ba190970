!> Fold curves in two parameters (docs/model.md section 12.6), against what cannot be tuned:
!> figure 10's fold (A = 2.8851913 at w = 1.9) followed in (A, w) passes through the folds that
!> one-parameter runs locate at two other points' w, to 1e-8 in A; at every point of the curve
!> J has a multiplier +1.
module test_curve
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_model, only: model_t, set_model_parameter
    use chain_engine, only: chain_t, chain_positions, chain_velocities
    use chain_event_log, only: event_log_t, event_log_init
    use chain_section, only: advance_to_point, chain_at_section
    use chain_orbit, only: orbit_t, find_orbit
    use chain_branch, only: branch_options_t, branches_t, follow_branches
    use chain_curve, only: curve_options_t, curve_t, follow_fold_curve
    use test_chains, only: fig10_model
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_curve_tests

contains

    subroutine run_curve_tests(t)
        type(tally_t), intent(inout) :: t
        type(branches_t) :: fold
        type(curve_t) :: curve
        type(curve_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: k, j

        call fold_at(1.9_wp, fold)
        call check(t, fold%n_specials >= 1, 'fold curve: a fold at w = 1.9')
        if (fold%n_specials < 1) return
        k = fold%specials(1)%point
        opt%parameter = 'amplitude'
        opt%parameter2 = 'omega'
        opt%stop2 = 1.95_wp
        opt%step2 = 0.01_wp
        opt%max_points = 8
        call follow_fold_curve(fig10_model(fold%points(k)%value), 0.0_wp, 1, &
                               fold%points(k)%orbit%x, fold%points(k)%orbit%v, &
                               fold%points(k)%value, opt, curve, err)
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
                curve%values2(j), ', |multiplier - 1| = ', distance_to_one(curve%orbits(j))
        end do
        call check_close(t, maxval([(distance_to_one(curve%orbits(j)), j=1, curve%n_points)]), &
                         0.0_wp, 'fold curve: a multiplier +1 at every point', 1.0e-7_wp)
        call compare_with_branch(t, curve, 2)
        call compare_with_branch(t, curve, curve%n_points)
    end subroutine run_curve_tests

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
        call settle(model, 5_i8, start)
        opt%parameter = 'amplitude'
        opt%stop = 2
        opt%step = -0.05_wp
        call follow_branches(model, 0.0_wp, 1, start%x, start%v, opt, res, err)
    end subroutine fold_at

    !> Newton for a period-1 orbit from the state `transient` cycles after a start at rest.
    subroutine settle(model, transient, orbit)
        type(model_t), intent(in) :: model
        integer(i8), intent(in) :: transient
        type(orbit_t), intent(out) :: orbit
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: events
        integer :: i

        call chain_at_section(model, 0.0_wp, [(0.0_wp, i=1, model%n)], [(0.0_wp, i=1, model%n)], &
                              chain, err)
        call event_log_init(events, .false., 0)
        call advance_to_point(chain, transient, 0.0_wp, events, err)
        call find_orbit(model, 0.0_wp, 1, chain_positions(chain), chain_velocities(chain), &
                        orbit, err)
    end subroutine settle

    !> The distance of the multiplier nearest +1 from +1.
    pure real(wp) function distance_to_one(orbit)
        type(orbit_t), intent(in) :: orbit

        distance_to_one = minval(abs(cmplx(orbit%multipliers_re - 1, orbit%multipliers_im, wp)))
    end function distance_to_one

end module test_curve
