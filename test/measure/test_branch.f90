!> Branches of periodic orbits (docs/model.md section 12), against what cannot be tuned: the
!> exact parameter column of the map against central differences in every parameter, on an
!> impacting and on a non-impacting orbit; the impacting branch of figure 10's chain down to its fold (a multiplier +1 there); a period
!> doubling against the simulator on either side of it, and the branch switched to there (its
!> own doubling, the product of its multipliers); one branch from two starts, its special
!> points located at the same parameter. Newton's result from the guess is kept, converged
!> (the first point) or not (no point, the reason said). Each branch says where it began: on
!> its parent's special point, whose orbit is its first point.
!> A continuation run tells its monitor the transient's cycles, then its points, and stops
!> when asked.
module test_branch
    use chain_kinds, only: wp, i8, two_pi
    use chain_error, only: error_t
    use chain_flow, only: flow_t, make_flow, forced_response
    use chain_model, only: model_t, model_parameters, set_model_parameter, model_parameter
    use chain_engine, only: chain_t, chain_positions, chain_velocities
    use chain_event_log, only: event_log_t, event_log_init
    use chain_section, only: advance_to_point, chain_at_section
    use chain_orbit, only: orbit_t, find_orbit, interleave, impact_bonds
    use chain_parameter, only: map_parameter_derivative
    use chain_branch, only: branch_options_t, branches_t, follow_branches
    use chain_config, only: config_t
    use chain_monitor, only: monitor_t, stage_transient, stage_points, stage_events
    use chain_branch_file, only: run_continuation, continuation_table_t, continuation_table
    use test_chains, only: model_of, fig10_model
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_branch_tests, chain12_orbit, settle, check_origins

    !> Records what it is told and asks to stop at a given count of one stage.
    type, extends(monitor_t) :: counting_monitor_t
        integer :: stop_stage = 0
        integer(i8) :: stop_at = 0
        integer :: transient_calls = 0, point_calls = 0
        logical :: in_order = .true.  !! cycles 1, 2, ... of the total, then points 1, 2, ...
        integer(i8) :: transient_total = 0
    contains
        procedure :: keep_going => counting_keep_going
    end type counting_monitor_t

contains

    subroutine run_branch_tests(t)
        type(tally_t), intent(inout) :: t
        type(orbit_t) :: impacting, free
        type(model_t) :: model

        model = fig10_model(3.0_wp)
        call settle(model, 5_i8, 1, impacting)
        call check(t, impacting%converged .and. impacting%impacts > 0, &
                   'fig. 10 A = 3: an impacting period-1 orbit')
        call check(t, size(impact_bonds(impacting)) == impacting%impacts, &
                   'fig. 10 A = 3: one bond per impact')
        if (impacting%converged) call derivative_by_differences(t, model, impacting, &
                                                                'impacting fig. 10 A = 3')
        model = fig10_model(1.0_wp)
        call settle(model, 5_i8, 1, free)
        call check(t, free%converged .and. free%impacts == 0, &
                   'fig. 10 A = 1: a period-1 orbit without impacts')
        if (free%converged) call derivative_by_differences(t, model, free, &
                                                           'non-impacting fig. 10 A = 1')
        call impacting_branch(t, impacting)
        call period_doubling(t)
        call two_starts(t)
        call failed_start(t)
        call branch_point(t)
        call monitored_run(t)
    end subroutine run_branch_tests

    !> Newton for a period-p orbit from the state `transient` cycles after a start at rest.
    subroutine settle(model, transient, cycles, orbit)
        type(model_t), intent(in) :: model
        integer(i8), intent(in) :: transient
        integer, intent(in) :: cycles
        type(orbit_t), intent(out) :: orbit
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: events
        integer :: i

        call chain_at_section(model, 0.0_wp, [(0.0_wp, i=1, model%n)], [(0.0_wp, i=1, model%n)], &
                              chain, err)
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

    !> Figure 10's impacting period-1 orbit at A = 3 followed down: it folds (a turning point
    !> of the parameter) and comes back unstable to the start's value, a bound. At the located
    !> fold the tangent has no parameter component and J has a multiplier +1.
    subroutine impacting_branch(t, start)
        type(tally_t), intent(inout) :: t
        type(orbit_t), intent(in) :: start
        type(branches_t) :: res
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: k

        opt%parameter = 'amplitude'
        opt%stop = 2
        opt%step = -0.05_wp
        call follow_branches(fig10_model(3.0_wp), 0.0_wp, 1, start%x, start%v, opt, res, err)
        call check(t, .not. allocated(err), 'impacting branch: followed')
        if (allocated(err)) return
        print '(a)', '    '//res%end_reason
        call check(t, res%n_specials == 1, 'impacting branch: one special point')
        if (res%n_specials /= 1) return
        call check(t, res%specials(1)%kind == 'fold', 'impacting branch: a fold')
        associate (fold => res%points(res%specials(1)%point))
            k = minloc(abs(cmplx(fold%orbit%multipliers_re - 1, fold%orbit%multipliers_im, wp)), &
                       1)
            write (*, '(a,f15.11,a,es9.2)') '    impacting branch: fold at A = ', fold%value, &
                ', |multiplier - 1| = ', abs(cmplx(fold%orbit%multipliers_re(k) - 1, &
                                                   fold%orbit%multipliers_im(k), wp))
            call check_close(t, abs(cmplx(fold%orbit%multipliers_re(k) - 1, &
                                          fold%orbit%multipliers_im(k), wp)), 0.0_wp, &
                             'impacting branch: a multiplier +1 at the fold', 1.0e-6_wp)
            call check(t, all(res%points(:res%specials(1)%point - 1)%stable) .and. &
                       .not. any(res%points(res%specials(1)%point + 1:res%n_points)%stable), &
                       'impacting branch: stable before the fold, unstable after')
            call check(t, all(res%points(:res%n_points)%value <= 3) .and. &
                       all(res%points(:res%n_points)%value >= fold%value), &
                       'impacting branch: the fold is the smallest amplitude on it')
        end associate
        call check_close(t, res%points(res%n_points)%value, 3.0_wp, &
                         'impacting branch: it ends on the bound A = 3', 0.0_wp)
    end subroutine impacting_branch

    !> A single impact oscillator (n = 1, wall gap 0.5 on the left, 100 on the right, w = 2.5,
    !> K = 0.8) followed down from A = 8: its period-1 orbit doubles; the period-2 branch
    !> switched to there doubles again. At each located doubling J has a multiplier -1; the
    !> simulator, started on the orbit at A = doubling + 0.02 and - 0.02, keeps period 1 above
    !> and settles on period 2 below (a brute-force sweep with a step of 0.04 around it); the
    !> period-2 orbits' multipliers multiply to exp(-2 b n p T) K**(2c).
    subroutine period_doubling(t)
        type(tally_t), intent(inout) :: t
        type(model_t) :: model
        type(orbit_t) :: start
        type(branches_t) :: res
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        real(wp) :: product_want, product_got
        integer :: j, k, doubling

        model = model_of(make_flow(0.05_wp, 8.0_wp, 2.5_wp), 0.8_wp, [0.5_wp, 100.0_wp], &
                         .true., 1.0e-9_wp)
        call settle(model, 1000_i8, 1, start)
        call check(t, start%converged, 'impact oscillator A = 8: a period-1 orbit')
        if (.not. start%converged) return
        opt%parameter = 'amplitude'
        opt%stop = 4.5_wp
        opt%step = -0.05_wp
        opt%doublings = 1
        call follow_branches(model, 0.0_wp, 1, start%x, start%v, opt, res, err)
        call check(t, .not. allocated(err), 'impact oscillator: followed')
        if (allocated(err)) return
        print '(a)', '    '//res%end_reason
        call check(t, res%n_specials == 2, 'impact oscillator: two special points')
        if (res%n_specials /= 2) return
        call check(t, res%specials(1)%kind == 'period-doubling' .and. &
                   res%specials(2)%kind == 'period-doubling', &
                   'impact oscillator: both period doublings')
        do j = 1, 2
            associate (pd => res%points(res%specials(j)%point))
                k = minloc(abs(cmplx(pd%orbit%multipliers_re + 1, pd%orbit%multipliers_im, wp)), 1)
                write (*, '(a,i0,a,f15.11,a,es9.2)') '    impact oscillator: period ', &
                    pd%orbit%cycles, ' doubles at A = ', pd%value, ', |multiplier + 1| = ', &
                    abs(cmplx(pd%orbit%multipliers_re(k) + 1, pd%orbit%multipliers_im(k), wp))
                call check_close(t, abs(cmplx(pd%orbit%multipliers_re(k) + 1, &
                                              pd%orbit%multipliers_im(k), wp)), 0.0_wp, &
                                 'impact oscillator: a multiplier -1 at the doubling', 1.0e-6_wp)
                call check(t, pd%branch == j - 1 .and. pd%orbit%cycles == j, &
                           'impact oscillator: the doubling of branch '//merge('0', '1', j == 1))
            end associate
        end do
        doubling = res%specials(1)%point
        call check_origins(t, res, 'impact oscillator')
        call check(t, res%n_branches == 2, 'impact oscillator: two branches')
        if (res%n_branches == 2) call check(t, res%origins(2)%parent == 0 .and. &
                                            res%origins(2)%point == doubling .and. &
                                            res%origins(2)%kind == 'period-doubling', &
                                            'impact oscillator: branch 1 began at branch 0''s '// &
                                            'doubling')
        call sweep_across(t, model, res%points(doubling)%value, res%points(doubling)%orbit)
        ! the product of the multipliers on the period-2 branch
        do j = 1, res%n_points
            if (res%points(j)%branch /= 1 .or. j == doubling) cycle
            associate (o => res%points(j)%orbit)
                product_want = exp(-2*model%damping*model%n*o%cycles*two_pi/model%omega)* &
                               model%restitution**(2*o%impacts)
                product_got = real(product(cmplx(o%multipliers_re, o%multipliers_im, wp)), wp)
            end associate
            call check_close(t, product_got, product_want, 'impact oscillator: period-2 '// &
                             'multipliers multiply to exp(-2 b n p T) K**(2c)', &
                             1.0e-10_wp*product_want)
            exit
        end do
    end subroutine period_doubling

    !> The simulator from the doubling orbit at A = a_pd + 0.02 (period 1 expected) and
    !> a_pd - 0.02 (period 2): 3000 cycles, then the strobe map's return after 1 and 2 cycles.
    subroutine sweep_across(t, model, a_pd, orbit)
        type(tally_t), intent(inout) :: t
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: a_pd
        type(orbit_t), intent(in) :: orbit
        type(model_t) :: near
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: events
        real(wp), allocatable :: z0(:), z1(:), z2(:)
        real(wp) :: offset
        integer :: side
        logical :: period_one

        call event_log_init(events, .false., 0)
        do side = 1, 2
            offset = merge(0.02_wp, -0.02_wp, side == 1)
            near = model
            near%amplitude = a_pd + offset
            call chain_at_section(near, 0.0_wp, orbit%x + 1.0e-3_wp, orbit%v, chain, err)
            call advance_to_point(chain, 3000_i8, 0.0_wp, events, err)
            z0 = interleave(chain_positions(chain), chain_velocities(chain))
            call advance_to_point(chain, 3001_i8, 0.0_wp, events, err)
            z1 = interleave(chain_positions(chain), chain_velocities(chain))
            call advance_to_point(chain, 3002_i8, 0.0_wp, events, err)
            z2 = interleave(chain_positions(chain), chain_velocities(chain))
            period_one = maxval(abs(z1 - z0)) < 1.0e-6_wp
            write (*, '(a,f8.4,a,2es9.2)') '    impact oscillator: simulator at A = ', &
                near%amplitude, ': |P(z) - z|, |P2(z) - z| = ', maxval(abs(z1 - z0)), &
                maxval(abs(z2 - z0))
            if (side == 1) then
                call check(t, period_one, 'impact oscillator: period 1 just above the doubling')
            else
                call check(t, .not. period_one .and. maxval(abs(z2 - z0)) < 1.0e-6_wp, &
                           'impact oscillator: period 2 just below the doubling')
            end if
        end do
    end subroutine sweep_across

    !> Figure 10's six-impact period-1 orbit followed down from A = 2.6 and from 2.7 (two
    !> different starts, two different sets of points): one Neimark-Sacker point (two pairs of
    !> the mirror-symmetric chain cross the unit circle together; the pairs that turn real
    !> outside it later are no Neimark-Sacker point), then a grazing where an impact's speed
    !> vanishes. Both runs must locate both at the same amplitude: the Neimark-Sacker point to
    !> 1e-9 and the grazing (located again past it, where the impact is gone) to 1e-10.
    subroutine two_starts(t)
        type(tally_t), intent(inout) :: t
        type(branches_t) :: res(2)
        type(branch_options_t) :: opt
        type(orbit_t) :: start
        type(error_t), allocatable :: err
        real(wp) :: amplitude(2)
        integer :: r

        amplitude = [2.6_wp, 2.7_wp]
        opt%parameter = 'amplitude'
        opt%stop = 1
        opt%step = -0.02_wp
        opt%max_points = 400
        do r = 1, 2
            call settle(fig10_model(amplitude(r)), 500_i8, 1, start)
            call follow_branches(fig10_model(amplitude(r)), 0.0_wp, 1, start%x, start%v, opt, &
                                 res(r), err)
            call check(t, .not. allocated(err), 'two starts: followed')
            if (allocated(err)) return
            print '(a)', '    '//res(r)%end_reason
        end do
        ! (the branch goes on through the grazing: special points beyond it may follow)
        call check(t, all(res%n_specials >= 2), 'two starts: two special points each')
        if (any(res%n_specials < 2)) return
        call check(t, res(1)%specials(1)%kind == 'neimark-sacker' .and. &
                   res(2)%specials(1)%kind == 'neimark-sacker' .and. &
                   res(1)%specials(2)%kind == 'grazing' .and. &
                   res(2)%specials(2)%kind == 'grazing', &
                   'two starts: a Neimark-Sacker point, then a grazing')
        write (*, '(a,2es22.14)') '    two starts: Neimark-Sacker at ', &
            res(1)%specials(1)%value, res(2)%specials(1)%value
        write (*, '(a,2es22.14)') '    two starts: grazing at ', res(1)%specials(2)%value, &
            res(2)%specials(2)%value
        call check_close(t, res(1)%specials(1)%value, res(2)%specials(1)%value, &
                         'two starts: the same Neimark-Sacker point', 1.0e-9_wp)
        call check_close(t, res(1)%specials(2)%value, res(2)%specials(2)%value, &
                         'two starts: the same grazing', 1.0e-10_wp)
    end subroutine two_starts

    !> A guess from which Newton fails (test_corners' chain, resting on the left wall once
    !> per cycle): no point, Newton's result kept with its reason, which the end reason says.
    subroutine failed_start(t)
        type(tally_t), intent(inout) :: t
        type(model_t) :: model
        type(branches_t) :: res
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err

        model = model_of(make_flow(0.1_wp, 1.0_wp, 0.4_wp), 0.5_wp, [0.5_wp, 0.5_wp, 3.0_wp], &
                         .true., 1.0e-9_wp)
        opt%parameter = 'amplitude'
        opt%max_points = 1
        call follow_branches(model, 0.0_wp, 1, [0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp], opt, res, err)
        call check(t, .not. allocated(err) .and. res%n_points == 0 .and. &
                   .not. res%start%converged, 'failed start: no point, not converged')
        if (allocated(err) .or. res%start%converged) return
        call check(t, index(res%start%reason, 'sticks on a wall') > 0 .and. &
                   index(res%end_reason, res%start%reason) > 0 .and. &
                   size(res%start%residuals) == res%start%iterations + 1, &
                   'failed start: the reason kept and said: '//res%end_reason)
        call check_origins(t, res, 'failed start')
    end subroutine failed_start

    !> Where each branch of `res` began: one origin per branch (per line of end_reason);
    !> branch 0 has none (parent -1, no point, no kind); branch b > 0 began on an earlier
    !> branch at a point located there as a special point of the origin's kind (a period
    !> doubling or a branch point), whose parameter and state are b's first point's (the
    !> doubled orbit: Newton's, from that state, to 1e-10).
    subroutine check_origins(t, res, label)
        type(tally_t), intent(inout) :: t
        type(branches_t), intent(in) :: res
        character(len=*), intent(in) :: label
        integer :: b, j, first
        logical :: special

        call check(t, res%n_branches == 1 + count([(res%end_reason(j:j) == new_line('a'), &
                                                    j=1, len(res%end_reason))]), &
                   label//': one origin per branch, one line of end_reason per branch')
        associate (r => res%origins(1))
            call check(t, r%parent == -1 .and. r%point == 0 .and. r%kind == '', &
                       label//': branch 0 began at no branch''s point')
        end associate
        do b = 1, res%n_branches - 1
            associate (r => res%origins(b + 1))
                call check(t, r%parent >= 0 .and. r%parent < b .and. r%point >= 1 .and. &
                           r%point <= res%n_points, label//': each branch began at a point '// &
                           'of an earlier branch')
                if (.not. (r%point >= 1 .and. r%point <= res%n_points)) cycle
                special = .false.
                do j = 1, res%n_specials
                    if (res%specials(j)%point == r%point .and. res%specials(j)%kind == r%kind) &
                        special = .true.
                end do
                call check(t, res%points(r%point)%branch == r%parent .and. special .and. &
                           (r%kind == 'period-doubling' .or. r%kind == 'branch-point'), &
                           label//': its origin is its parent''s special point of its kind')
                first = findloc(res%points(:res%n_points)%branch, b, 1)
                if (first == 0) cycle
                associate (o => res%points(r%point), f => res%points(first))
                    write (*, '(a,i0,a,es9.2)') '    '//label//': branch ', b, &
                        ' starts off its origin''s state by ', &
                        max(maxval(abs(f%orbit%x - o%orbit%x)), maxval(abs(f%orbit%v - o%orbit%v)))
                    call check(t, f%value == o%value, label//': its first point is at its '// &
                               'origin''s parameter')
                    call check_close(t, max(maxval(abs(f%orbit%x - o%orbit%x)), &
                                            maxval(abs(f%orbit%v - o%orbit%v))), 0.0_wp, &
                                     label//': its first point is its origin''s orbit', &
                                     1.0e-10_wp)
                end associate
            end associate
        end do
    end subroutine check_origins

    !> A chain of 12 (b = 0.02, K = 0.85, w = 2.3, a = 1, walls) at A = 5 and its unstable
    !> 22-impact period-1 orbit, by Newton from rest after 500 cycles.
    subroutine chain12_orbit(model, start)
        type(model_t), intent(out) :: model
        type(orbit_t), intent(out) :: start
        integer :: i

        model = model_of(make_flow(0.02_wp, 5.0_wp, 2.3_wp), 0.85_wp, [(1.0_wp, i=0, 12)], &
                         .true., 1.0e-9_wp)
        call settle(model, 500_i8, 1, start)
    end subroutine chain12_orbit

    !> The same orbit continued up from A = 5: a real multiplier crosses +1 at A = 5.0040468
    !> while the parameter keeps its direction, the pitchfork of the mirror symmetry. It is
    !> located as a branch point with a multiplier 1 to 1e-8; the orbits before it are their
    !> own mirror images, and the branch goes on through it.
    subroutine branch_point(t)
        type(tally_t), intent(inout) :: t
        type(model_t) :: model
        type(orbit_t) :: start
        type(branches_t) :: res
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: i, s, p

        call chain12_orbit(model, start)
        if (.not. start%converged) return
        opt%parameter = 'amplitude'
        opt%stop = 5.01_wp
        opt%step = 0.001_wp
        call follow_branches(model, 0.0_wp, 1, start%x, start%v, opt, res, err)
        call check(t, .not. allocated(err), 'branch point: a result, not an error')
        if (allocated(err)) return
        print '(a)', '    '//res%end_reason
        s = 0
        do i = 1, res%n_specials
            if (res%specials(i)%kind == 'branch-point') s = i
        end do
        call check(t, s > 0, 'branch point: found')
        if (s == 0) return
        p = res%specials(s)%point
        associate (o => res%points(p)%orbit)
            write (*, '(a,f15.11,a,es9.2)') '    branch point at A = ', res%specials(s)%value, &
                ', |multiplier - 1| = ', minval(abs(cmplx(o%multipliers_re - 1, &
                                                          o%multipliers_im, wp)))
            call check_close(t, res%specials(s)%value, 5.0040468_wp, &
                             'branch point: at A = 5.0040468', 1.0e-7_wp)
            call check(t, minval(abs(cmplx(o%multipliers_re - 1, o%multipliers_im, wp))) < &
                       1.0e-8_wp, 'branch point: a multiplier 1 to 1e-8')
        end associate
        call check(t, all(res%points(:p)%symmetric), 'branch point: symmetric orbits up to it')
        call check(t, res%n_points > p .and. res%end_kind == 'bound', &
                   'branch point: the branch goes on through it to the bound')
    end subroutine branch_point

    !> Figure 10's chain at A = 1 from rest after 50 transient cycles, continued in A up to
    !> three points: the monitor sees every transient cycle, then every point; a stop asked
    !> in the transient or at the first point ends the run there, stopped.
    subroutine monitored_run(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg
        type(branches_t) :: res
        type(error_t), allocatable :: err
        type(counting_monitor_t) :: watch
        type(continuation_table_t) :: table

        cfg%model = fig10_model(1.0_wp)
        cfg%initial_kind = 'rest'
        cfg%initial_file = ''
        allocate (cfg%x0(0), cfg%v0(0))
        cfg%record%transient = 50
        cfg%continuation = .true.
        cfg%cont_parameter = 'amplitude'
        cfg%cont_stop = 2
        cfg%cont_step = 0.1_wp
        cfg%cont_max_points = 3
        call run_continuation(cfg, res, err, watch)
        call check(t, .not. allocated(err) .and. .not. res%stopped .and. res%n_points == 3 .and. &
                   watch%transient_calls == 50 .and. watch%transient_total == 50 .and. &
                   watch%point_calls == 3 .and. watch%in_order, &
                   'continuation run: the monitor is told 50 transient cycles, then 3 points')
        if (res%n_points /= 3) return
        call continuation_table(8, res, table)
        call check(t, table%residual(1) == res%start%residuals(res%start%iterations) .and. &
                   all(table%residual <= 100*1.0e-11_wp) .and. all(table%residual >= 0), &
                   "continuation table: every point's last residual, the first one's from Newton")
        call check(t, all(shape(table%strobe_x) == [8, 1, 3]) .and. &
                   all(table%strobe_x(:, 1, :) == table%x) .and. all(table%stable == 1) .and. &
                   size(table%special_kind) == 0 .and. all(table%min_impact_speed > huge(1.0_wp)), &
                   'continuation table: shapes, strobe = state for period 1, no impacts: inf')
        watch = counting_monitor_t(stop_stage=stage_transient, stop_at=7)
        call run_continuation(cfg, res, err, watch)
        call check(t, .not. allocated(err) .and. res%stopped .and. res%n_points == 0 .and. &
                   watch%transient_calls == 7 .and. watch%point_calls == 0, &
                   'continuation run: stopped in the transient')
        watch = counting_monitor_t(stop_stage=stage_points, stop_at=1)
        call run_continuation(cfg, res, err, watch)
        call check(t, .not. allocated(err) .and. res%stopped .and. res%n_points == 1 .and. &
                   watch%point_calls == 1, 'continuation run: stopped at the first point')
    end subroutine monitored_run

    logical function counting_keep_going(monitor, stage, done, total) result(keep_going)
        class(counting_monitor_t), intent(inout) :: monitor
        integer, intent(in) :: stage
        integer(i8), intent(in) :: done, total

        select case (stage)
        case (stage_transient)
            monitor%transient_calls = monitor%transient_calls + 1
            monitor%transient_total = total
            monitor%in_order = monitor%in_order .and. monitor%point_calls == 0 .and. &
                               done == monitor%transient_calls
        case (stage_points)
            monitor%point_calls = monitor%point_calls + 1
            monitor%in_order = monitor%in_order .and. done == monitor%point_calls
        case (stage_events) ! (within a long cycle: not counted)
            keep_going = .true.
            return
        case default
            monitor%in_order = .false.
        end select
        keep_going = .not. (stage == monitor%stop_stage .and. done == monitor%stop_at)
    end function counting_keep_going

end module test_branch
