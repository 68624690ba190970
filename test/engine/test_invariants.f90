!> Invariants that hold for every run and cannot be tuned (issue #15): mirror symmetry of the
!> fixed-wall chain, no negative gap at any event, zero tangent rows for every resting
!> oscillator, momentum at every inelastic collapse, the three-particle collapse threshold
!> K = 7 - 4 sqrt(3), the Lyapunov sum rule, and its Poincare-map form (the Jacobian's
!> determinant at any section phase). The walker `walk_events` and the sum-rule check
!> `check_sum_rule` are shared with the engine and Lyapunov suites.
module test_invariants
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, fmt_int
    use chain_sim, only: uniform
    use chain_flow, only: flow_t, make_flow, advance_state, propagator
    use chain_model, only: model_t
    use chain_state, only: chain_state_t, event_counts_t, contact_free, contact_left, &
                           contact_right
    use chain_engine, only: chain_t, chain_init, chain_advance, chain_sync, chain_new_cycle, &
                            chain_set_tangent, chain_gaps_now, chain_next_event, chain_size, &
                            chain_cycle, chain_time, chain_period, chain_model, &
                            chain_positions, chain_velocities, chain_contacts, chain_counts, &
                            chain_reset_counts, chain_vectors, chain_tangent_frame, &
                            chain_qr_step, chain_snapshot
    use chain_event_log, only: event_log_t, event_log_init, event_log_clear, event_impact, &
                            event_stick, event_release, event_log_append
    use chain_lyapunov, only: lyapunov_acc_t, lyapunov_start, lyapunov_step, &
                              lyapunov_result_t, lyapunov_result, initial_frame
    use chain_section, only: advance_to_point
    use chain_floquet, only: poincare_jacobian, floquet_multipliers
    use test_chains, only: init_chain, flow_of
    use testing, only: tally_t, check, check_close
    use test_sum_rule, only: check_sum_rule, real_text
    implicit none
    private
    public :: run_invariant_tests, walk_t, walk_events

    !> What a walk through a run, instant by instant, saw.
    type :: walk_t
        integer :: instants = 0             !! event times visited
        real(wp) :: worst_gap = huge(1.0_wp) !! smallest gap after any event or at any record,
                                             !! in units of gap_rounding (below -1: negative)
        integer :: negative_gaps = 0        !! instants and records with a gap below -rounding
        integer :: resting = 0              !! instants with at least one resting oscillator
        integer :: nonzero_rows = 0         !! instants where a resting one's rows were not 0
        integer :: stacks_left = 0          !! instants with two or more at rest on a wall
        integer :: stacks_right = 0
        integer :: collapses = 0            !! cluster-rule events (impacts of speed 0)
        integer :: momentum_instants = 0    !! instants whose momentum was compared
        real(wp) :: worst_momentum = 0      !! largest momentum change across one instant,
                                            !! in units of its rounding (free ends only)
        integer(i8) :: impacts = 0, sticks = 0
        real(wp), allocatable :: bits_per_cycle(:) !! spectrum, when the chain had a frame
    end type walk_t

    real(wp), parameter :: eps = epsilon(1.0_wp)
    !> Impacts at one instant after which the engine applies the cluster rule (README,
    !> "Simultaneous contacts").
    integer, parameter :: collapse_after = 1000
    !> Zhou and Kadanoff (1996): three free particles collapse for K below 7 - 4 sqrt(3).
    real(wp), parameter :: collapse_threshold = 7 - 4*sqrt(3.0_wp)

contains

    subroutine run_invariant_tests(t)
        type(tally_t), intent(inout) :: t

        call mirror_symmetry(t)
        call stress_walks(t)
        call three_particle_collapse(t)
        call momentum_at_collapse(t)
        call collapse_next_to_rest(t)
        call sum_rule_free_ends(t)
        call jacobian_at_any_phase(t)
    end subroutine run_invariant_tests

    ! ------------------------------------------------------------------ shared helpers

    !> The rounding level of the gaps of a chain now: a gap is a difference of positions built
    !> from a free part and the forced response, each rounded relative to its size.
    pure function gap_rounding(chain) result(tol)
        type(chain_t), intent(in) :: chain
        real(wp) :: tol
        type(model_t) :: model
        type(flow_t) :: flow

        model = chain_model(chain)
        flow = flow_of(chain)
        tol = 64*eps*(maxval(model%spacing) + maxval(abs(chain_positions(chain))) + &
                      hypot(flow%p_sin, flow%q_cos))
    end function gap_rounding

    function k_text(k) result(text)
        real(wp), intent(in) :: k
        character(len=:), allocatable :: text
        character(len=16) :: buf

        write (buf, '(f6.3)') k
        text = trim(adjustl(buf))
    end function k_text

    !> Run `cycles` drive cycles one event time at a time, with records at every cycle end
    !> (phase 0), as record_cycles does; after every event time and at every record look at the
    !> gaps, the tangent rows of resting oscillators and, for free ends, the momentum across the
    !> instant. A chain carrying a full tangent frame also gets its spectrum (QR every cycle).
    !> Stopping at each event time changes nothing: chain_advance to an event time processes
    !> exactly the events up to it, and every probe looks at a copy. The chain's impact and
    !> stick counters restart.
    subroutine walk_events(chain, cycles, walk, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: cycles
        type(walk_t), intent(out) :: walk
        type(error_t), allocatable, intent(out) :: err
        type(event_log_t) :: log
        type(lyapunov_acc_t) :: acc
        type(lyapunov_result_t) :: res
        type(event_counts_t) :: counts
        type(flow_t) :: flow
        integer(i8) :: last_cycle
        integer :: bond
        real(wp) :: tq, before
        logical :: spectrum, walls

        call event_log_init(log, .true., 64)
        spectrum = chain_vectors(chain) == 2*chain_size(chain)
        if (spectrum) call lyapunov_start(acc, chain_vectors(chain), int(cycles, i8), 1)
        call chain_reset_counts(chain)
        flow = flow_of(chain)
        walls = chain_walls(chain)
        last_cycle = chain_cycle(chain) + cycles
        do while (chain_cycle(chain) < last_cycle)
            call chain_next_event(chain, bond, tq)
            if (tq > flow%period) then
                ! a record: the state at the end of the cycle
                call chain_advance(chain, flow%period, log, err)
                if (allocated(err)) return
                call chain_new_cycle(chain)
                call look_at_gaps(chain, walk)
                if (spectrum) then
                    call chain_qr_step(chain, acc, 1, err)
                    if (allocated(err)) return
                end if
                cycle
            end if
            ! (free ends) momentum just before the instant
            if (.not. walls) before = momentum_at(chain, flow, tq)
            call event_log_clear(log)
            call chain_advance(chain, tq, log, err)
            if (allocated(err)) return
            call look_at_instant(chain, log, walls, before, walk)
        end do
        counts = chain_counts(chain)
        walk%impacts = counts%impacts
        walk%sticks = counts%sticks
        if (spectrum) then
            res = lyapunov_result(acc, flow%period)
            walk%bits_per_cycle = res%bits_per_cycle
        end if
    end subroutine walk_events

    logical function chain_walls(chain) result(walls)
        type(chain_t), intent(in) :: chain
        type(model_t) :: model

        model = chain_model(chain)
        walls = model%walls
    end function chain_walls

    !> Total momentum at time tq (before any event there), propagated exactly from a synced
    !> copy of the chain.
    function momentum_at(chain, flow, tq) result(total)
        type(chain_t), intent(in) :: chain
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: tq
        real(wp) :: total, x, v
        real(wp), allocatable :: xs(:), vs(:)
        type(chain_t) :: probe
        integer :: i

        probe = chain
        call chain_sync(probe)
        xs = chain_positions(probe)
        vs = chain_velocities(probe)
        total = 0
        do i = 1, size(xs)
            x = xs(i)
            v = vs(i)
            call advance_state(flow, chain_time(probe), tq - chain_time(probe), x, v)
            total = total + v
        end do
    end function momentum_at

    !> What an instant just processed (its events in `log`) left: the gaps (of a synced copy),
    !> for free ends the momentum against `before`, rests and stacks, and the tangent rows of
    !> resting oscillators.
    subroutine look_at_instant(chain, log, walls, before, walk)
        type(chain_t), intent(in) :: chain
        type(event_log_t), intent(in) :: log
        logical, intent(in) :: walls
        real(wp), intent(in) :: before
        type(walk_t), intent(inout) :: walk
        type(chain_t) :: probe
        real(wp) :: rounding
        real(wp), allocatable :: v(:), frame(:, :)
        integer, allocatable :: contact(:)
        integer :: i

        walk%instants = walk%instants + 1
        walk%collapses = walk%collapses + count(log%kind(:log%count) == event_impact .and. &
                                                log%speed(:log%count) == 0)
        probe = chain
        call look_at_gaps(probe, walk)
        if (.not. walls) then
            ! free ends: only pair impacts and the cluster rule, both keep momentum
            v = chain_velocities(probe)
            rounding = max(8*eps*max(1, log%count)*sum(abs(v)), tiny(1.0_wp))
            walk%worst_momentum = max(walk%worst_momentum, abs(sum(v) - before)/rounding)
            walk%momentum_instants = walk%momentum_instants + 1
        end if
        contact = chain_contacts(chain)
        if (any(contact /= contact_free)) walk%resting = walk%resting + 1
        if (count(contact == contact_left) >= 2) walk%stacks_left = walk%stacks_left + 1
        if (count(contact == contact_right) >= 2) walk%stacks_right = walk%stacks_right + 1
        if (chain_vectors(chain) == 0) return
        frame = chain_tangent_frame(chain)
        do i = 1, size(contact)
            if (contact(i) == contact_free) cycle
            if (any(frame(2*i - 1:2*i, :) /= 0)) then
                walk%nonzero_rows = walk%nonzero_rows + 1
                exit
            end if
        end do
    end subroutine look_at_instant

    !> Smallest gap of a (synced) copy of the chain, in units of its rounding level.
    subroutine look_at_gaps(probe, walk)
        type(chain_t), intent(inout) :: probe
        type(walk_t), intent(inout) :: walk
        real(wp) :: rounding, smallest
        real(wp), allocatable :: gaps(:)

        gaps = chain_gaps_now(probe)
        rounding = gap_rounding(probe)
        ! (free ends: the end bonds are never closed, their gaps are huge)
        smallest = min(1.0_wp, minval(gaps))
        walk%worst_gap = min(walk%worst_gap, smallest/rounding)
        if (smallest < -rounding) walk%negative_gaps = walk%negative_gaps + 1
    end subroutine look_at_gaps

    !> A MINSTD step: portable, reproducible random chains.

    !> A random fixed-wall chain that rests and stacks on both walls: a slow drive (w in
    !> [0.15, 0.45]) strong enough (A in [1.5, 4]) to push oscillators into the walls for a
    !> good part of each cycle, modest restitution (chatter ends in rests), one spacing per bond.
    subroutine random_chain(seed, flow, restitution, spacing, x, v)
        integer, intent(in) :: seed
        type(flow_t), intent(out) :: flow
        real(wp), intent(out) :: restitution
        real(wp), allocatable, intent(out) :: spacing(:), x(:), v(:)
        integer(i8) :: state
        integer :: n, i
        real(wp) :: damping, omega, amplitude

        state = seed*7919_i8 + 12345_i8
        n = 1 + int(6*uniform(state))
        allocate (spacing(0:n), x(n), v(n))
        do i = 0, n
            spacing(i) = 0.6_wp + 0.8_wp*uniform(state)
        end do
        damping = 0.02_wp + 0.13_wp*uniform(state)
        restitution = 0.1_wp + 0.6_wp*uniform(state)
        omega = 0.15_wp + 0.3_wp*uniform(state)
        amplitude = 1.5_wp + 2.5_wp*uniform(state)
        do i = 1, n
            x(i) = 0.4_wp*minval(spacing)*(2*uniform(state) - 1)
            v(i) = 0.5_wp*(2*uniform(state) - 1)
        end do
        flow = make_flow(damping, amplitude, omega)
    end subroutine random_chain

    ! ------------------------------------------------------------------ mirror symmetry

    !> The fixed-wall chain is symmetric under x(i) -> -x(n+1-i), v(i) -> -v(n+1-i), a(k) ->
    !> a(n-k), with the drive shifted by half a period (A sin(w t) -> -A sin(w t)): the mirror
    !> chain starts at time T/2 within the cycle. On random chains with rests and stacks on
    !> both walls, run and mirror must give mirror-image states (sampled four times a cycle)
    !> and event streams (site k -> n - k) to rounding. Contacts due at one instant (cascades
    !> through touching oscillators and stacks) are resolved in an order that the mirror image
    !> keeps (docs/model.md section 5). Bounces slower than 1e-4 (the tail of a chatter,
    !> touches) are not compared one by one: their speeds carry the rounding of the decision
    !> where a chatter ends (about 1e-7, the resolvable speed), so how many of them come
    !> before a rest may differ by one; the rest then resets the oscillator exactly.
    subroutine mirror_symmetry(t)
        type(tally_t), intent(inout) :: t
        integer, parameter :: chains = 32, cycles = 6, samples = 4
        type(flow_t) :: flow
        type(chain_t) :: run, mirror
        type(error_t), allocatable :: err
        type(event_log_t) :: log, mirror_log
        real(wp), allocatable :: spacing(:), x(:), v(:)
        real(wp) :: restitution, period, worst_state, tol_time, scale
        real(wp) :: diff_at(samples*cycles)
        integer :: seed, n, j, q, sticks_left, sticks_right, stacks_left, stacks_right
        integer, allocatable :: contact(:)
        integer :: failing
        character(len=:), allocatable :: label, mismatch
        logical :: contacts_mirror

        sticks_left = 0
        sticks_right = 0
        stacks_left = 0
        stacks_right = 0
        failing = 0
        do seed = 1, chains
            call random_chain(seed, flow, restitution, spacing, x, v)
            n = size(x)
            label = 'mirror seed '//fmt_int(seed)//' (n = '//fmt_int(n)//')'
            period = flow%period
            call init_chain(run, flow, restitution, spacing, .true., 1.0e-9_wp, x, v, 0_i8, &
                            0.0_wp, err)
            call init_chain(mirror, flow, restitution, spacing(n:0:-1), .true., 1.0e-9_wp, &
                            -x(n:1:-1), -v(n:1:-1), 0_i8, 0.5_wp*period, err)
            call event_log_init(log, .true., 1024)
            call event_log_init(mirror_log, .true., 1024)
            worst_state = 0
            diff_at = 0
            contacts_mirror = .true.
            do j = 1, samples*cycles
                ! elapsed time j T / samples: the mirror's clock is half a period ahead
                call advance_to_point(run, int(j/samples, i8), &
                                      real(mod(j, samples), wp)*period/samples, log, err)
                if (allocated(err)) exit
                q = j + samples/2
                call advance_to_point(mirror, int(q/samples, i8), &
                                      real(mod(q, samples), wp)*period/samples, mirror_log, err)
                if (allocated(err)) exit
                diff_at(j) = mirror_distance(run, mirror)
                contact = chain_contacts(run)
                if (count(contact == contact_left) >= 2) stacks_left = stacks_left + 1
                if (count(contact == contact_right) >= 2) stacks_right = stacks_right + 1
            end do
            do j = 1, samples*cycles
                if (diff_at(j) == huge(1.0_wp)) contacts_mirror = .false.
                if (diff_at(j) < huge(1.0_wp)) worst_state = max(worst_state, diff_at(j))
            end do
            call check(t, .not. allocated(err), label//': both runs complete')
            if (allocated(err)) cycle
            sticks_left = sticks_left + count(log%kind(:log%count) == event_stick .and. &
                                              log%site(:log%count) == 0)
            sticks_right = sticks_right + count(log%kind(:log%count) == event_stick .and. &
                                                log%site(:log%count) == n)
            ! states are O(1) and every rest resets an oscillator exactly, so rounding does not
            ! grow over these few cycles, except for a sample taken inside a chatter: its
            ! bounces, down to the resolvable speed (1e-7), shear the rounding by a / u. Seed
            ! 26 chatters through thousands of bounces and peaks at 5e-10 to 1e-9 within one
            ! cycle, depending only on how the flow's functions round (then its rests reset it
            ! to 1e-12); every other seed stays below 1e-11. 1e-8 is rounding times 10^8
            call check_close(t, worst_state, 0.0_wp, label//': mirror-image states', &
                             abs_tol=1.0e-8_wp)
            call check(t, contacts_mirror, label//': resting on mirror-image walls')
            ! an event time is fixed by its gap to (error of the gap) / (approach speed): gaps
            ! here round at 1e-15 and gather rounding over a run's hundreds of events (a
            ! grazing wall impact at u = 2e-3 was seen 1.1e-9 apart: 3e-12 in the gap); allowed
            ! 1e-11 / u, or 10 times the states' difference if larger, and speeds to the same
            ! time times an acceleration scale
            scale = 1 + flow%amplitude + maxval(spacing)
            tol_time = max(1.0e-11_wp, 10*worst_state)
            mismatch = event_mismatch(resolved_events(log), resolved_events(mirror_log), n, &
                                      tol_time, scale)
            call check(t, len(mismatch) == 0, label//': mirror-image events'//mismatch)
            if (worst_state > 1.0e-8_wp .or. len(mismatch) > 0 .or. .not. contacts_mirror) &
                failing = failing + 1
        end do
        ! the set must exercise what the symmetry is about
        call check(t, sticks_left > 0 .and. sticks_right > 0, 'mirror chains: rests on '// &
                   'both walls ('//fmt_int(sticks_left)//' left, '//fmt_int(sticks_right)// &
                   ' right)')
        call check(t, stacks_left > 0 .and. stacks_right > 0, 'mirror chains: stacks on '// &
                   'both walls ('//fmt_int(stacks_left)//' left, '//fmt_int(stacks_right)// &
                   ' right, samples)')
        if (failing > 0) write (*, '(a,i0,a,i0,a)') '  mirror symmetry: ', failing, ' of ', &
            chains, ' random chains differ from their mirror image'
    end subroutine mirror_symmetry

    !> The largest difference between the state of `run` and the mirror image of `mirror`'s;
    !> huge if their contacts are not mirror images.
    function mirror_distance(run, mirror) result(distance)
        type(chain_t), intent(in) :: run, mirror
        real(wp) :: distance
        real(wp), allocatable :: x(:), v(:), x_mirror(:), v_mirror(:)
        integer, allocatable :: contact(:), contact_mirror(:)
        integer :: n

        n = chain_size(run)
        x = chain_positions(run)
        v = chain_velocities(run)
        contact = chain_contacts(run)
        x_mirror = chain_positions(mirror)
        v_mirror = chain_velocities(mirror)
        contact_mirror = chain_contacts(mirror)
        distance = max(maxval(abs(x + x_mirror(n:1:-1))), maxval(abs(v + v_mirror(n:1:-1))))
        if (any(contact /= -contact_mirror(n:1:-1))) distance = huge(1.0_wp)
    end function mirror_distance

    pure logical function resolved(log, i)
        type(event_log_t), intent(in) :: log
        integer, intent(in) :: i

        resolved = log%speed(i) >= 1.0e-4_wp .or. log%kind(i) == event_release
    end function resolved

    !> The resolved events of a log (approach speed 1e-6 or more, or releases).
    function resolved_events(log) result(kept)
        type(event_log_t), intent(in) :: log
        type(event_log_t) :: kept
        integer :: i

        call event_log_init(kept, .true., max(1, log%count))
        do i = 1, log%count
            if (resolved(log, i)) call event_log_append(kept, log%time(i), log%site(i), &
                                                        log%speed(i), log%kind(i))
        end do
    end function resolved_events

    !> '' if the event streams are mirror images, else where they first differ. Each event's
    !> time must agree to tol_gap (1 + 1/u), u its approach speed floored at 1e-6; events
    !> closer together than the loosest of these tolerances may come in either order (a
    !> triple contact resolved in another order of disjoint pairs, a chatter sequence shifted
    !> by rounding), so such a group is compared as a set.
    function event_mismatch(a, b, n, tol_gap, scale) result(text)
        type(event_log_t), intent(in) :: a, b
        integer, intent(in) :: n
        real(wp), intent(in) :: tol_gap, scale
        character(len=:), allocatable :: text
        integer :: i, j, ea, eb, k
        integer, allocatable :: oa(:), ob(:)
        real(wp) :: tol, window

        window = tol_gap*(1 + 1/1.0e-6_wp)
        text = ''
        if (a%count /= b%count) text = ' (counts '//fmt_int(a%count)//' and '// &
                                       fmt_int(b%count)//')'
        i = 1
        j = 1
        do while (i <= a%count .and. j <= b%count)
            ea = group_end(a, i, window)
            eb = group_end(b, j, window)
            if (ea - i /= eb - j) then
                text = ' (at event '//fmt_int(i)//', t = '//real_text(a%time(i))// &
                       ': a group of '//fmt_int(ea - i + 1)//' events against '// &
                       fmt_int(eb - j + 1)//')'//text
                return
            end if
            oa = group_order(a, i, ea, n, .false.)
            ob = group_order(b, j, eb, n, .true.)
            do k = 1, size(oa)
                associate (p => oa(k), r => ob(k))
                    tol = tol_gap*(1 + 1/max(a%speed(p), 1.0e-6_wp))
                    if (a%site(p) /= n - b%site(r) .or. a%kind(p) /= b%kind(r) .or. &
                        abs(a%time(p) - b%time(r)) > tol .or. &
                        abs(a%speed(p) - b%speed(r)) > 10*scale*tol) then
                        text = ' (event '//fmt_int(p)//' at t = '//real_text(a%time(p))// &
                               ': site '//fmt_int(a%site(p))//', kind '// &
                               fmt_int(a%kind(p))//', speed '//real_text(a%speed(p))// &
                               '; mirror t = '//real_text(b%time(r))//', site '// &
                               fmt_int(n - b%site(r))//', kind '//fmt_int(b%kind(r))// &
                               ', speed '//real_text(b%speed(r))//')'//text
                        return
                    end if
                end associate
            end do
            i = ea + 1
            j = eb + 1
        end do
    end function event_mismatch

    !> Last event of the group that starts at event i: events each closer than `window` to
    !> the one before.
    pure integer function group_end(log, i, window) result(e)
        type(event_log_t), intent(in) :: log
        integer, intent(in) :: i
        real(wp), intent(in) :: window

        e = i
        do while (e < log%count)
            if (log%time(e + 1) - log%time(e) > window) exit
            e = e + 1
        end do
    end function group_end

    !> Events first..last sorted by (site seen from the run's left wall, kind, speed); a
    !> mirror run's sites are read as n - site.
    pure function group_order(log, first, last, n, mirrored) result(order)
        type(event_log_t), intent(in) :: log
        integer, intent(in) :: first, last, n
        logical, intent(in) :: mirrored
        integer :: order(last - first + 1), i, j, m

        order = [(i, i=first, last)]
        do i = 2, size(order)
            m = order(i)
            j = i - 1
            do while (j >= 1)
                if (.not. before(m, order(j))) exit
                order(j + 1) = order(j)
                j = j - 1
            end do
            order(j + 1) = m
        end do
    contains
        pure logical function before(p, r)
            integer, intent(in) :: p, r
            integer :: sp, sr

            sp = merge(n - log%site(p), log%site(p), mirrored)
            sr = merge(n - log%site(r), log%site(r), mirrored)
            if (sp /= sr) then
                before = sp < sr
            else if (log%kind(p) /= log%kind(r)) then
                before = log%kind(p) < log%kind(r)
            else
                before = log%speed(p) < log%speed(r)
            end if
        end function before
    end function group_order

    ! ------------------------------------------------------------------ stress walks

    !> Stress runs with rests, stacks and inelastic collapse, each carrying a full tangent
    !> frame, walked event by event: no gap below its rounding level at any event or record,
    !> and after every event the tangent rows of every resting oscillator exactly zero (a
    !> rest forgets perturbations; nothing may bring them back while it lasts).
    subroutine stress_walks(t)
        type(tally_t), intent(inout) :: t
        type(flow_t) :: flow
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(walk_t) :: walk
        real(wp), allocatable :: spacing(:), x(:), v(:)
        real(wp) :: restitution
        integer :: seed, resting, stacks_left, stacks_right
        character(len=:), allocatable :: label

        resting = 0
        stacks_left = 0
        stacks_right = 0
        do seed = 1, 16
            call random_chain(seed, flow, restitution, spacing, x, v)
            label = 'random chain '//fmt_int(seed)
            call init_chain(chain, flow, restitution, spacing, .true., 1.0e-9_wp, x, v, 0_i8, &
                            0.0_wp, err)
            call walk_with_frame(chain, 6, walk, err)
            call check(t, .not. allocated(err), label//' walks')
            call report_walk(t, label, walk)
            call check_sum_rule(t, label, size(x), flow, restitution, &
                                real(walk%impacts, wp)/6, walk%bits_per_cycle, walk%sticks)
            resting = resting + walk%resting
            stacks_left = stacks_left + walk%stacks_left
            stacks_right = stacks_right + walk%stacks_right
        end do
        call check(t, resting > 0 .and. stacks_left > 0 .and. stacks_right > 0, &
                   'random chains walked: rests ('//fmt_int(resting)//' instants) and '// &
                   'stacks on both walls ('//fmt_int(stacks_left)//', '// &
                   fmt_int(stacks_right)//')')
        ! K = 0 in a crowded chain against the walls: plastic cascades, rests, the cluster rule
        spacing = [(0.2_wp, seed=0, 6)]
        x = [(0.05_wp*sin(1.7_wp*seed + 0.3_wp), seed=1, 6)]
        v = [(2.0_wp*cos(2.3_wp*seed), seed=1, 6)]
        call init_chain(chain, make_flow(0.05_wp, 2.0_wp, 1.2_wp), 0.0_wp, spacing, .true., &
                        1.0e-9_wp, x, v, 0_i8, 0.0_wp, err)
        call walk_with_frame(chain, 40, walk, err)
        call check(t, .not. allocated(err), 'plastic chain walks')
        call check(t, walk%collapses > 0 .and. walk%resting > 0, 'plastic chain: the '// &
                   'cluster rule fires ('//fmt_int(walk%collapses)//') and oscillators rest')
        call report_walk(t, 'plastic chain', walk)
        call check_sum_rule(t, 'plastic chain', 6, flow_of(chain), 0.0_wp, &
                            real(walk%impacts, wp)/40, walk%bits_per_cycle, walk%sticks)
    end subroutine stress_walks

    subroutine walk_with_frame(chain, cycles, walk, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: cycles
        type(walk_t), intent(out) :: walk
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: frame(:, :)
        integer :: info

        call initial_frame(2*chain_size(chain), 2*chain_size(chain), frame, info)
        ! as a Lyapunov run carries it (re-orthonormalised after large jumps)
        call chain_set_tangent(chain, frame, orthonormalise_jumps=.true.)
        call walk_events(chain, cycles, walk, err)
    end subroutine walk_with_frame

    subroutine report_walk(t, label, walk)
        type(tally_t), intent(inout) :: t
        character(len=*), intent(in) :: label
        type(walk_t), intent(in) :: walk

        call check(t, walk%negative_gaps == 0, label//': no gap below its rounding level '// &
                   'at any event or record (worst '//real_text(walk%worst_gap)// &
                   ' roundings)')
        call check(t, walk%nonzero_rows == 0, label//': tangent rows of resting '// &
                   'oscillators zero after every event ('//fmt_int(walk%nonzero_rows)// &
                   ' of '//fmt_int(walk%resting)//' instants with rests break it)')
    end subroutine report_walk

    ! ------------------------------------------------------------------ inelastic collapse

    !> Number of impacts of the ballistic three-particle cascade from approach speeds
    !> (u1, u2) on bonds 1 and 2 (springs negligible: the sequence alternates, each impact
    !> reverses its bond's relative velocity times K and adds (1 + K)/2 of it to the other's),
    !> as long as the next bond closes; `cap` if it never stops. Computed on the relative
    !> velocities, which keeps full relative precision however small they get.
    pure integer function ballistic_impacts(k, u1, u2, cap) result(impacts)
        real(wp), intent(in) :: k, u1, u2
        integer, intent(in) :: cap
        real(wp) :: a, b, h

        a = u1
        b = u2
        h = 0.5_wp*(1 + k)
        impacts = 0
        do while (impacts < cap)
            if (modulo(impacts, 2) == 0) then
                if (a <= 0) exit
                b = b + h*a
                a = -k*a
            else
                if (b <= 0) exit
                a = a + h*b
                b = -k*b
            end if
            impacts = impacts + 1
            ! keep the pair O(1): only the signs and ratios matter
            if (max(abs(a), abs(b)) < 1.0e-100_wp) then
                a = a*1.0e100_wp
                b = b*1.0e100_wp
            end if
        end do
    end function ballistic_impacts

    !> Three free particles (no walls, A = 0, b = 0, spacing 1e-3, gaps 1e-3 and 1.5e-3,
    !> v = (3, 2, 1): approach speeds 1 on both bonds) collide in a cascade lasting 1e-4 of a
    !> period, so the springs barely act during it. Above K = 7 - 4 sqrt(3) it is finite and
    !> separates the three: as many impacts as the ballistic sequence, growing without bound
    !> as K falls to the threshold. Below, the ballistic sequence never ends (inelastic
    !> collapse): the engine must carry the cascade until the three move together, however it
    !> ends it (the cluster rule after 1000 impacts at one instant, or approach speeds lost
    !> below what the gaps resolve). The centre of mass moves as one free oscillator whatever
    !> the impacts do (momentum conservation) and is checked against that exactly.
    subroutine three_particle_collapse(t)
        type(tally_t), intent(inout) :: t
        real(wp), parameter :: above(3) = [0.2_wp, 0.1_wp, 0.08_wp]
        real(wp), parameter :: below(2) = [0.05_wp, 0.02_wp]
        real(wp), parameter :: near(5) = [0.1_wp, 0.08_wp, 0.075_wp, 0.072_wp, 0.0719_wp]
        integer, parameter :: cap = 100000
        integer :: j, counts(size(near)), impacts
        real(wp) :: spread, last_speed, first_speed
        logical :: together
        character(len=16) :: kt

        ! the ballistic sequence itself: finite above the threshold, growing towards it,
        ! endless below
        do j = 1, size(near)
            counts(j) = ballistic_impacts(near(j), 1.0_wp, 1.0_wp, cap)
        end do
        call check(t, all(counts < cap) .and. all(counts(2:) > counts(:size(near) - 1)), &
                   'ballistic cascade: finite above 7 - 4 sqrt(3), longer towards it')
        ! near the threshold the two-impact map has complex eigenvalues of angle ~ sqrt(K -
        ! threshold): a hundred times closer, ten times as many impacts
        call check_close(t, real(ballistic_impacts(collapse_threshold*(1 + 1.0e-6_wp), 1.0_wp, &
                                                   1.0_wp, cap), wp) / &
                         ballistic_impacts(collapse_threshold*(1 + 1.0e-4_wp), 1.0_wp, 1.0_wp, &
                                           cap), 10.0_wp, 'ballistic cascade: impacts grow as '// &
                         '1/sqrt(K - threshold)', rel_tol=0.05_wp)
        call check(t, ballistic_impacts(0.05_wp, 1.0_wp, 1.0_wp, cap) == cap .and. &
                   ballistic_impacts(collapse_threshold*0.999_wp, 1.0_wp, 1.0_wp, cap) == cap, &
                   'ballistic cascade: endless below 7 - 4 sqrt(3) (inelastic collapse)')
        do j = 1, size(above)
            write (kt, '(f6.3)') above(j)
            call three_particles(t, above(j), impacts, spread, first_speed, last_speed)
            call check(t, impacts == ballistic_impacts(above(j), 1.0_wp, 1.0_wp, cap), &
                       'three particles, K = '//trim(adjustl(kt))//': '//fmt_int(impacts)// &
                       ' impacts, as the ballistic cascade')
            call check(t, spread > 1.0e-6_wp, 'three particles, K = '//trim(adjustl(kt))// &
                       ': they separate (relative speed '//real_text(spread)//')')
        end do
        do j = 1, size(below)
            write (kt, '(f6.3)') below(j)
            call three_particles(t, below(j), impacts, spread, first_speed, last_speed)
            ! together: relative velocities below 1e-8 of the approach speeds, which the
            ! finite cascades above leave at 1e-2 .. 1e-6 (K**(impacts/2))
            together = spread <= 1.0e-8_wp
            call check(t, together .and. last_speed <= 1.0e-8_wp*first_speed, &
                       'three particles, K = '//trim(adjustl(kt))//' (below 7 - 4 sqrt(3)): '// &
                       'collapse, '//fmt_int(impacts)//' impacts down to approach speed '// &
                       real_text(last_speed)//', relative speed after '//real_text(spread))
        end do
    end subroutine three_particle_collapse

    !> One three-particle cascade: its impacts, the largest relative velocity just after it,
    !> and the approach speeds of its first and last impact; checks momentum.
    subroutine three_particles(t, k, impacts, spread, first_speed, last_speed)
        type(tally_t), intent(inout) :: t
        real(wp), intent(in) :: k
        integer, intent(out) :: impacts
        real(wp), intent(out) :: spread, first_speed, last_speed
        real(wp), parameter :: a = 1.0e-3_wp, x0(3) = [0.0_wp, 0.0_wp, 0.5e-3_wp], &
                               v0(3) = [3.0_wp, 2.0_wp, 1.0_wp]
        type(flow_t) :: flow
        type(chain_t) :: chain, after
        type(error_t), allocatable :: err
        type(event_log_t) :: log, rest_of
        real(wp) :: m(2, 2), centre(2), end_time
        real(wp), allocatable :: v_after(:)
        character(len=16) :: kt

        write (kt, '(f6.3)') k
        flow = make_flow(0.0_wp, 0.0_wp, 1.5_wp)
        call init_chain(chain, flow, k, [a, a, a, a], .false., 1.0e-9_wp, x0, v0, 0_i8, &
                        0.0_wp, err)
        after = chain
        call event_log_init(log, .true., 64)
        ! the whole cascade is over by 2e-3; the next impact is a quarter period away
        call chain_advance(chain, 0.01_wp, log, err)
        call check(t, .not. allocated(err) .and. log%count > 0, 'three particles, K = '// &
                   trim(adjustl(kt))//': the cascade runs')
        if (allocated(err) .or. log%count == 0) then
            impacts = 0
            spread = 0
            first_speed = 1
            last_speed = 1
            return
        end if
        impacts = count(log%kind(:log%count) == event_impact)
        first_speed = log%speed(1)
        last_speed = log%speed(log%count)
        ! the state just after the cascade, before the springs act on it
        end_time = log%time(log%count)
        call event_log_init(rest_of, .false., 0)
        call chain_advance(after, end_time, rest_of, err)
        call chain_sync(after)
        v_after = chain_velocities(after)
        spread = max(abs(v_after(2) - v_after(1)), abs(v_after(3) - v_after(2)))
        ! the centre of mass is one free oscillator: impacts conserve momentum and positions
        m = propagator(flow, end_time)
        centre = matmul(m, [sum(x0), sum(v0)])/3
        call check_close(t, sum(v_after)/3, centre(2), 'three particles, K = '// &
                         trim(adjustl(kt))//': momentum conserved through the cascade', &
                         abs_tol=8*eps*max(impacts, 1)*maxval(abs(v0)))
    end subroutine three_particles

    !> Free ends, K = 0 and K = 0.05 in a crowded chain (spacing 0.2): plastic cascades and
    !> inelastic collapse of a five-particle cluster (the cluster rule). Without walls every
    !> impact and the cluster rule conserve momentum: checked across every instant, the
    !> cluster rule's included.
    subroutine momentum_at_collapse(t)
        type(tally_t), intent(inout) :: t
        real(wp), parameter :: ks(2) = [0.0_wp, 0.05_wp]
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(walk_t) :: walk
        real(wp) :: x(6), v(6)
        integer :: i, j
        character(len=:), allocatable :: label

        do j = 1, size(ks)
            label = 'free crowded chain, K = '//k_text(ks(j))
            do i = 1, 6
                x(i) = 0.05_wp*sin(1.7_wp*i + 0.3_wp)
                v(i) = 2.0_wp*cos(2.3_wp*i)
            end do
            call init_chain(chain, make_flow(0.05_wp, 2.0_wp, 1.2_wp), ks(j), &
                            [(0.2_wp, i=0, 6)], .false., 1.0e-9_wp, x, v, 0_i8, 0.0_wp, err)
            call walk_with_frame(chain, 20, walk, err)
            ! (the cascades end by touches once the approach is too slow to resolve; the
            ! cluster rule is the engine's backstop after 1000 impacts at one instant)
            call check(t, .not. allocated(err), label//': walks')
            call check(t, walk%momentum_instants > 0 .and. walk%worst_momentum <= 1, &
                       label//': momentum kept across every instant, collapses included '// &
                       '(worst '//real_text(walk%worst_momentum)//' roundings)')
            call report_walk(t, label, walk)
            call check_sum_rule(t, label, 6, flow_of(chain), ks(j), real(walk%impacts, wp)/20, &
                                walk%bits_per_cycle, walk%sticks)
        end do
    end subroutine momentum_at_collapse

    !> The cluster rule next to a resting oscillator. n = 4, oscillator 1 at rest on the left
    !> wall (the drive presses it there: a(0) + A sin(w t) = 1 - 3 < 0), oscillators 2 and 3
    !> touching it and each other with v = -0.2 and +0.8 (the touching cluster's momentum is
    !> 0.6), oscillator 4 apart; the resting oscillator's tangent rows zero.
    !> 1. Run by the engine: 2 hits the stack, 3 separates untouched; rests keep zero rows.
    !> 2. The cluster rule applied to this very state (as after 999 impacts at this instant):
    !>    the moving oscillators 2 and 3 move with their mean velocity, keeping momentum 0.6,
    !>    unless the cluster is pressed into the wall (then they stop); the resting oscillator
    !>    keeps zero rows.
    subroutine collapse_next_to_rest(t)
        type(tally_t), intent(inout) :: t
        real(wp), parameter :: ks(2) = [0.0_wp, 0.05_wp]
        type(chain_t) :: chain
        type(event_log_t) :: log
        type(error_t), allocatable :: err
        type(chain_state_t) :: state
        type(model_t) :: model
        real(wp) :: s0, gaps(0:4), momentum
        real(wp), allocatable :: v(:)
        integer :: j, collapses
        character(len=:), allocatable :: label

        do j = 1, size(ks)
            label = 'cluster beside a rest, K = '//k_text(ks(j))
            call resting_cluster(chain, ks(j), s0, err)
            call check(t, .not. allocated(err), label//': the state is admissible')
            if (allocated(err)) return
            call event_log_init(log, .true., 64)
            ! the instant at s0, and 1e-12 beyond it (drive and springs change v by < 1e-11)
            call chain_advance(chain, s0 + 1.0e-12_wp, log, err)
            gaps = chain_gaps_now(chain)
            call check(t, .not. allocated(err) .and. minval(gaps) >= -gap_rounding(chain), &
                       label//': runs, no negative gap')
            v = chain_velocities(chain)
            call check_close(t, v(3), 0.8_wp, label//': oscillator 3 separates '// &
                             'untouched', abs_tol=1.0e-10_wp)
            call check(t, all_resting_rows_zero(chain), label//': resting rows stay zero')
        end do
        label = 'cluster rule beside a rest'
        call resting_cluster(chain, 0.05_wp, s0, err)
        ! as after 999 impacts at this instant
        state = chain_snapshot(chain)
        state%last_event = s0
        state%same_instant = collapse_after - 1
        model = chain_model(chain)
        call chain_init(chain, model, state, err)
        call event_log_init(log, .true., 64)
        call chain_advance(chain, s0, log, err)
        collapses = count(log%kind(:log%count) == event_impact .and. log%speed(:log%count) == 0)
        call check(t, .not. allocated(err) .and. collapses == 1, label//': the rule fires')
        call chain_sync(chain)
        v = chain_velocities(chain)
        momentum = sum(v(1:3))
        call check(t, abs(momentum - 0.6_wp) <= 8*eps .or. all(v(2:3) == 0), &
                   label//': momentum 0.6 kept (or the cluster stopped against the wall), '// &
                   'got '//real_text(momentum)//' with v = '//real_text(v(1))//', '// &
                   real_text(v(2))//', '//real_text(v(3)))
        call check(t, all_resting_rows_zero(chain), label//': the resting oscillator''s '// &
                   'tangent rows stay zero')
    end subroutine collapse_next_to_rest

    !> The state of collapse_next_to_rest at s0 = 3T/4 (sin(w s0) = -1), with a full tangent
    !> frame whose rows of the resting oscillator are zero.
    subroutine resting_cluster(chain, k, s0, err)
        type(chain_t), intent(out) :: chain
        real(wp), intent(in) :: k
        real(wp), intent(out) :: s0
        type(error_t), allocatable, intent(out) :: err
        type(flow_t) :: flow
        real(wp) :: frame(8, 8)
        integer :: i

        flow = make_flow(0.05_wp, 3.0_wp, 1.5_wp)
        s0 = 0.75_wp*flow%period
        call init_chain(chain, flow, k, [(1.0_wp, i=0, 4)], .true., 1.0e-9_wp, &
                        [-1.0_wp, -2.0_wp, -3.0_wp, 0.0_wp], [0.0_wp, -0.2_wp, 0.8_wp, 0.0_wp], &
                        0_i8, s0, err, contact=[contact_left, contact_free, contact_free, &
                                                contact_free])
        if (allocated(err)) return
        frame = 0
        do i = 3, 8
            frame(i, i) = 1
        end do
        call chain_set_tangent(chain, frame)
    end subroutine resting_cluster

    logical function all_resting_rows_zero(chain) result(zero)
        type(chain_t), intent(in) :: chain
        integer, allocatable :: contact(:)
        real(wp), allocatable :: frame(:, :)
        integer :: i

        zero = .true.
        contact = chain_contacts(chain)
        frame = chain_tangent_frame(chain)
        do i = 1, size(contact)
            if (contact(i) /= contact_free) zero = zero .and. all(frame(2*i - 1:2*i, :) == 0)
        end do
    end function all_resting_rows_zero

    ! ------------------------------------------------------------------ sum rule

    !> Free ends: impacts die out (the paper), so the mean impacts per cycle c is small and
    !> falls; the sum rule holds over any stretch of cycles, dying collisions included.
    subroutine sum_rule_free_ends(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(walk_t) :: walk
        real(wp) :: x(8), v(8)
        integer :: i

        do i = 1, 8
            x(i) = 0.3_wp*sin(1.7_wp*i + 0.3_wp)
            v(i) = 1.5_wp*cos(2.3_wp*i)
        end do
        call init_chain(chain, make_flow(0.05_wp, 1.7_wp, 1.5_wp), 0.7_wp, [(1.0_wp, i=0, 8)], &
                        .false., 1.0e-9_wp, x, v, 0_i8, 0.0_wp, err)
        call walk_with_frame(chain, 40, walk, err)
        call check(t, .not. allocated(err) .and. walk%impacts > 0, &
                   'free ends, n = 8: collisions in the first 40 cycles')
        call check(t, walk%worst_momentum <= 1, 'free ends, n = 8: momentum kept across '// &
                   'every instant (worst '//real_text(walk%worst_momentum)//' roundings)')
        call check_sum_rule(t, 'free ends n = 8, dying collisions', 8, flow_of(chain), 0.7_wp, &
                            real(walk%impacts, wp)/40, walk%bits_per_cycle, walk%sticks)
    end subroutine sum_rule_free_ends

    !> The volume rule of the Poincare map: its Jacobian's determinant over one cycle is
    !> exp(-2 b n T) K**(2 c), c the impacts of that cycle, wherever the section lies in the
    !> drive cycle (a chaotic chain without rests, n = 4, A = 4.15, w = 0.9; sections at drive
    !> phases 0, 1 and 4).
    subroutine jacobian_at_any_phase(t)
        type(tally_t), intent(inout) :: t
        real(wp), parameter :: phases(3) = [0.0_wp, 1.0_wp, 4.0_wp]
        type(chain_t) :: chain, copy
        type(error_t), allocatable :: err
        type(event_log_t) :: events
        type(event_counts_t) :: counts
        type(flow_t) :: flow
        real(wp), allocatable :: jac(:, :)
        real(wp) :: x(4), v(4), s, re(8), im(8), expected
        integer :: i, j, info
        character(len=:), allocatable :: label

        do i = 1, 4
            x(i) = 0.3_wp*sin(1.7_wp*i + 0.3_wp)
            v(i) = 0.5_wp*cos(2.3_wp*i)
        end do
        flow = make_flow(0.05_wp, 4.15_wp, 0.9_wp)
        call init_chain(chain, flow, 0.7_wp, [(1.0_wp, i=0, 4)], .true., 1.0e-9_wp, x, v, 0_i8, &
                        0.0_wp, err)
        call event_log_init(events, .false., 0)
        do j = 1, size(phases)
            label = 'one-cycle Jacobian at drive phase '//k_text(phases(j))
            s = phases(j)/flow%omega
            call advance_to_point(chain, 50_i8*j, s, events, err)
            call poincare_jacobian(chain, 1, jac, err)
            ! the impacts of the cycle it spans (s passed by value: the chain's own clock
            ! moves while it runs)
            copy = chain
            call chain_reset_counts(copy)
            call advance_to_point(copy, chain_cycle(chain) + 1, s, events, err)
            counts = chain_counts(copy)
            call check(t, .not. allocated(err) .and. counts%impacts > 0 .and. &
                       counts%sticks == 0, label//': a cycle with impacts and no rest')
            call floquet_multipliers(jac, re, im, info)
            expected = -2*flow%damping*4*flow%period + 2*counts%impacts*log(0.7_wp)
            call check_close(t, sum(log(hypot(re, im))), expected, label// &
                             ': log det = -2 b n T + 2 c ln K', rel_tol=1.0e-8_wp)
        end do
    end subroutine jacobian_at_any_phase

end module test_invariants
