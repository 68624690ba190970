!> Branches of periodic orbits (docs/model.md section 12), against what cannot be tuned: the
!> exact parameter column of the map against central differences in every parameter, on an
!> impacting and on a non-impacting orbit; the non-impacting branch against the linear
!> response and its grazing against the closed form A = a sqrt((1 - w**2)**2 + (2 b w)**2);
!> the impacting branch of figure 10's chain down to its fold, the fold against Newton's
!> failure on either side; a period doubling against a brute-force sweep of the simulator, and
!> the branch switched to there against the simulator's period-2p orbit.
module test_branch
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_flow, only: flow_t, make_flow, forced_response
    use chain_model, only: model_t, model_parameters, set_model_parameter, model_parameter
    use chain_engine, only: chain_t, chain_positions, chain_velocities
    use chain_event_log, only: event_log_t, event_log_init
    use chain_section, only: advance_to_point, chain_at_section
    use chain_orbit, only: orbit_t, find_orbit, interleave
    use chain_parameter, only: map_parameter_derivative
    use chain_branch, only: branch_options_t, branches_t, follow_branches
    use test_engine, only: make_chain
    use test_chains, only: model_of
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_branch_tests

contains

    subroutine run_branch_tests(t)
        type(tally_t), intent(inout) :: t
        type(orbit_t) :: impacting, free
        type(model_t) :: model

        model = fig10(3.0_wp)
        call settle(model, 5_i8, 1, impacting)
        call check(t, impacting%converged .and. impacting%impacts > 0, &
                   'fig. 10 A = 3: an impacting period-1 orbit')
        if (impacting%converged) call derivative_by_differences(t, model, impacting, &
                                                                'impacting fig. 10 A = 3')
        model = fig10(1.0_wp)
        call settle(model, 5_i8, 1, free)
        call check(t, free%converged .and. free%impacts == 0, &
                   'fig. 10 A = 1: a period-1 orbit without impacts')
        if (free%converged) call derivative_by_differences(t, model, free, &
                                                           'non-impacting fig. 10 A = 1')
        call non_impacting_branch(t)
        call impacting_branch(t, impacting)
    end subroutine run_branch_tests

    !> Figure 10's chain at amplitude A (a = 1, fixed walls).
    function fig10(amplitude) result(model)
        real(wp), intent(in) :: amplitude
        type(model_t) :: model
        integer :: i

        model = model_of(make_flow(0.05_wp, amplitude, 1.9_wp), 0.5_wp, [(1.0_wp, i=0, 8)], &
                         .true., 1.0e-9_wp)
    end function fig10

    !> Newton for a period-p orbit from the state `transient` cycles after a start at rest.
    subroutine settle(model, transient, cycles, orbit)
        type(model_t), intent(in) :: model
        integer(i8), intent(in) :: transient
        integer, intent(in) :: cycles
        type(orbit_t), intent(out) :: orbit
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: events

        call make_chain(chain, model%n, model%amplitude, model%omega, model%damping, &
                        model%restitution, .true., 0.0_wp, 0.0_wp, err)
        call event_log_init(events, .false., 0)
        call advance_to_point(chain, transient, 0.0_wp, events, err)
        call find_orbit(model, 0.0_wp, cycles, chain_positions(chain), chain_velocities(chain), &
                        orbit, err)
    end subroutine settle

    !> dP/dmu at the orbit, exact, against (P(mu + h) - P(mu - h)) / 2h with h = 1e-6 mu, in
    !> every parameter; the central difference is good to about h**2 |P'''| + eps / h.
    subroutine derivative_by_differences(t, model, orbit, label)
        type(tally_t), intent(inout) :: t
        type(model_t), intent(in) :: model
        type(orbit_t), intent(in) :: orbit
        character(len=*), intent(in) :: label
        type(model_t) :: shifted
        type(error_t), allocatable :: err
        real(wp), allocatable :: exact(:), plus(:), minus(:)
        character(len=:), allocatable :: name
        real(wp) :: mu, h, worst
        integer :: k

        do k = 1, size(model_parameters)
                name = trim(model_parameters(k))
                call map_parameter_derivative(model, orbit%phase, orbit%cycles, orbit%x, &
                                              orbit%v, name, orbit%jacobian, exact, err)
                call check(t, .not. allocated(err), label//': the '//name//' column')
                if (allocated(err)) cycle
                mu = model_parameter(model, name)
                h = 1.0e-6_wp*mu
                shifted = model
                call set_model_parameter(shifted, name, mu + h)
                plus = image_of(shifted, orbit)
                call set_model_parameter(shifted, name, mu - h)
                minus = image_of(shifted, orbit)
                worst = maxval(abs(exact - (plus - minus)/(2*h)))/max(1.0_wp, maxval(abs(exact)))
                write (*, '(a,es9.2)') '    '//label//': d/d '//name// &
                    ': |exact - central difference| / max(1, |exact|) = ', worst
                call check_close(t, worst, 0.0_wp, label//': d/d '//name// &
                                 ' = central differences', 1.0e-6_wp)
        end do
    end subroutine derivative_by_differences

    !> P^p of the orbit's state under `model`.
    function image_of(model, orbit) result(image)
        type(model_t), intent(in) :: model
        type(orbit_t), intent(in) :: orbit
        real(wp), allocatable :: image(:)
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: events

        call chain_at_section(model, orbit%phase, orbit%x, orbit%v, chain, err)
        call event_log_init(events, .false., 0)
        call advance_to_point(chain, int(orbit%cycles, i8), orbit%phase/model%omega, events, err)
        image = interleave(chain_positions(chain), chain_velocities(chain))
    end function image_of

    !> From A = 1 up: every point is the forced response, and the branch ends at the grazing
    !> A = a sqrt((1 - w**2)**2 + (2 b w)**2) where the wall gaps' minimum 1 - |xp| reaches 0.
    subroutine non_impacting_branch(t)
        type(tally_t), intent(inout) :: t
        type(model_t) :: model
        type(branches_t) :: res
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        type(flow_t) :: flow
        real(wp) :: xp, vp, worst, grazing
        integer :: j

        model = fig10(1.0_wp)
        opt%parameter = 'amplitude'
        opt%stop = 3
        opt%step = 0.1_wp
        call follow_branches(model, 0.0_wp, 1, [(0.0_wp, j=1, 8)], [(0.0_wp, j=1, 8)], opt, &
                             res, err)
        call check(t, .not. allocated(err), 'non-impacting branch: followed')
        if (allocated(err)) then
            print *, err%message
            return
        end if
        print '(a)', '    '//res%end_reason
        worst = 0
        ! (the last point, located at the grazing, sees a touch: the map is not smooth there)
        do j = 1, res%n_points - 1
            flow = make_flow(model%damping, res%points(j)%value, model%omega)
            call forced_response(flow, 0.0_wp, xp, vp)
            worst = max(worst, maxval(abs(res%points(j)%orbit%x - xp)), &
                        maxval(abs(res%points(j)%orbit%v - vp)))
        end do
        write (*, '(a,i0,a,es9.2)') '    non-impacting branch: ', res%n_points, &
            ' points, |orbit - forced response| <= ', worst
        call check_close(t, worst, 0.0_wp, 'non-impacting branch: the forced response', &
                         1.0e-12_wp)
        grazing = sqrt((1 - model%omega**2)**2 + (2*model%damping*model%omega)**2)
        call check(t, res%n_specials >= 1, 'non-impacting branch: a special point')
        if (res%n_specials < 1) return
        write (*, '(a,a,es22.14,a,es9.2)') '    non-impacting branch: ', &
            res%specials(res%n_specials)%kind, res%specials(res%n_specials)%value, &
            ', |A - closed form| = ', abs(res%specials(res%n_specials)%value - grazing)
        call check(t, res%specials(res%n_specials)%kind == 'grazing', &
                   'non-impacting branch: it ends at a grazing')
        call check_close(t, res%specials(res%n_specials)%value, grazing, &
                         'non-impacting branch: grazing at a sqrt(D2)', 1.0e-9_wp)
    end subroutine non_impacting_branch

    subroutine impacting_branch(t, start)
        type(tally_t), intent(inout) :: t
        type(orbit_t), intent(in) :: start
        type(branches_t) :: res
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: j

        opt%parameter = 'amplitude'
        opt%stop = 2
        opt%step = -0.05_wp
        opt%max_points = 300
        call follow_branches(fig10(3.0_wp), 0.0_wp, 1, start%x, start%v, opt, res, err)
        call check(t, .not. allocated(err), 'impacting branch: followed')
        if (allocated(err)) return
        print '(a)', '    '//res%end_reason
        do j = 1, res%n_points
            print '(i4,f14.9,l3,i4,2es10.2, i4)', j, res%points(j)%value, res%points(j)%stable, &
                res%points(j)%orbit%impacts, res%points(j)%orbit%min_gap, &
                res%points(j)%orbit%min_impact_speed, res%points(j)%orbit%iterations
        end do
        do j = 1, res%n_specials
            print *, res%specials(j)%point, res%specials(j)%kind, res%specials(j)%value
        end do
    end subroutine impacting_branch

end module test_branch
