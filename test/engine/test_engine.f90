!> The event-driven chain (docs/model.md sections 1-3, 5): momentum and restitution at every impact,
!> gaps never negative, the linear response without impacts, free boundaries, and stress tests
!> that drive the engine into chatter, sticking, grazing and plastic multi-body contacts,
!> walked event by event (no gap below its rounding level after any event or at any record).
module test_engine
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_flow, only: flow_t, make_flow, forced_response, propagator, advance_state
    use chain_engine, only: chain_t, chain_advance, chain_sync, chain_new_cycle, &
                            chain_gaps_now, chain_next_event, chain_size, chain_period, &
                            chain_time, chain_positions, chain_velocities, chain_contacts, &
                            chain_counts, chain_reset_counts
    use chain_state, only: contact_free, event_counts_t
    use chain_event_log, only: event_log_t, event_log_init, event_log_clear
    use chain_section, only: advance_to_point
    use test_chains, only: init_chain, flow_of, make_chain
    use test_invariants, only: walk_t, walk_events
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_engine_tests

contains

    subroutine run_engine_tests(t)
        type(tally_t), intent(inout) :: t

        call every_impact(t, .true.)
        call every_impact(t, .false.)
        call linear_response(t)
        call free_boundaries_die_out(t)
        call chatter_and_sticking(t)
        call exact_grazing(t)
        call plastic_cluster(t)
    end subroutine run_engine_tests

    !> Step impact by impact; compare each with the collision law applied to independently
    !> propagated pre-impact states.
    subroutine every_impact(t, walls)
        type(tally_t), intent(inout) :: t
        logical, intent(in) :: walls
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: log
        integer :: bond, ev, l, r, n, checked, bad_momentum, bad_restitution, bad_gap
        real(wp) :: tq, xl, vl, xr, vr, k, period, gaps(0:16), v(16)

        k = 0.7_wp
        call make_chain(chain, 16, 1.7_wp, 1.5_wp, 0.05_wp, k, walls, 0.3_wp, 1.5_wp, err)
        call check(t, .not. allocated(err), 'chain set-up')
        if (allocated(err)) return
        call event_log_init(log, .true., 16)
        n = chain_size(chain)
        period = chain_period(chain)
        checked = 0
        bad_momentum = 0
        bad_restitution = 0
        bad_gap = 0
        do ev = 1, 3000
            call chain_next_event(chain, bond, tq)
            if (tq > period) then
                call chain_advance(chain, period, log, err)
                call chain_new_cycle(chain)
                call event_log_clear(log)
                cycle
            end if
            l = max(bond, 1)
            r = min(bond + 1, n)
            call chain_sync(chain)
            call pre_state(chain, l, tq, xl, vl)
            call pre_state(chain, r, tq, xr, vr)
            call event_log_clear(log)
            call chain_advance(chain, tq, log, err)
            if (allocated(err)) exit
            if (log%count /= 1) cycle
            call chain_sync(chain)
            gaps = chain_gaps_now(chain)
            if (minval(gaps) < -1.0e-12_wp) bad_gap = bad_gap + 1
            if (log%kind(1) /= 0) cycle
            checked = checked + 1
            v = chain_velocities(chain)
            if (bond == 0) then
                if (abs(v(1) + k*vl) > 1.0e-12_wp) bad_restitution = bad_restitution + 1
            else if (bond == n) then
                if (abs(v(n) + k*vr) > 1.0e-12_wp) bad_restitution = bad_restitution + 1
            else
                if (abs(v(l) + v(r) - vl - vr) > 1.0e-12_wp) bad_momentum = bad_momentum + 1
                if (abs((v(r) - v(l)) - k*(vl - vr)) > 1.0e-12_wp) &
                    bad_restitution = bad_restitution + 1
            end if
        end do
        call check(t, .not. allocated(err), 'engine runs 3000 events')
        call check(t, checked > merge(1000, 10, walls), 'enough single impacts checked')
        call check(t, bad_momentum == 0, 'momentum conserved at every pair impact')
        call check(t, bad_restitution == 0, 'relative velocity reversed and scaled by K')
        call check(t, bad_gap == 0, 'no gap below -1e-12 after any impact')
    end subroutine every_impact

    !> State of oscillator i at time tq, propagated independently from the synced chain.
    subroutine pre_state(chain, i, tq, x, v)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: i
        real(wp), intent(in) :: tq
        real(wp), intent(out) :: x, v
        real(wp), allocatable :: xs(:), vs(:)
        integer, allocatable :: contact(:)

        xs = chain_positions(chain)
        vs = chain_velocities(chain)
        contact = chain_contacts(chain)
        x = xs(i)
        v = vs(i)
        if (contact(i) == contact_free) &
            call advance_state(flow_of(chain), chain_time(chain), tq - chain_time(chain), x, v)
    end subroutine pre_state

    !> Small drive, no impacts: every strobe record equals the closed-form linear response
    !> x(jT) = xp(0) + [M(jT) (x0 - xp(0), v0 - vp(0))]_1.
    subroutine linear_response(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: log
        type(flow_t) :: flow
        type(event_counts_t) :: counts
        real(wp) :: xp, vp, m(2, 2), worst, exact_x, exact_v, y0(3), vy0(3), x(3), v(3)
        integer :: j, i

        call make_chain(chain, 3, 0.2_wp, 1.5_wp, 0.05_wp, 0.7_wp, .true., 0.2_wp, 0.1_wp, err)
        flow = flow_of(chain)
        call forced_response(flow, 0.0_wp, xp, vp)
        y0 = chain_positions(chain) - xp
        vy0 = chain_velocities(chain) - vp
        call event_log_init(log, .false., 0)
        worst = 0
        do j = 1, 60
            call advance_to_point(chain, int(j, i8), 0.0_wp, log, err)
            m = propagator(flow, j*flow%period)
            x = chain_positions(chain)
            v = chain_velocities(chain)
            do i = 1, 3
                exact_x = xp + m(1, 1)*y0(i) + m(1, 2)*vy0(i)
                exact_v = vp + m(2, 1)*y0(i) + m(2, 2)*vy0(i)
                worst = max(worst, abs(x(i) - exact_x), abs(v(i) - exact_v))
            end do
        end do
        counts = chain_counts(chain)
        call check(t, .not. allocated(err) .and. counts%impacts == 0, &
                   'linear response case has no impacts')
        call check_close(t, worst, 0.0_wp, 'strobe equals the linear response', 1.0e-12_wp)
    end subroutine linear_response

    !> The paper: with free ends, collisions die out. Stated case: n = 8, A = 1.7, w = 1.5,
    !> b = 0.05, K = 0.7, a = 1, from a start with speeds up to 1.5.
    subroutine free_boundaries_die_out(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: log
        type(event_counts_t) :: early, late

        call make_chain(chain, 8, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, .false., 0.3_wp, 1.5_wp, err)
        call event_log_init(log, .false., 0)
        call advance_to_point(chain, 20_i8, 0.0_wp, log, err)
        early = chain_counts(chain)
        call advance_to_point(chain, 1000_i8, 0.0_wp, log, err)
        call chain_reset_counts(chain)
        call advance_to_point(chain, 1200_i8, 0.0_wp, log, err)
        late = chain_counts(chain)
        call check(t, .not. allocated(err) .and. early%impacts > 0, 'free chain collides at first')
        call check(t, late%impacts == 0, 'free chain: collisions have died out by cycle 1000')
    end subroutine free_boundaries_die_out

    !> One oscillator driven hard into both walls: chatter ends in sticking, sticking ends in
    !> release, and the run neither hangs nor lets a gap go negative.
    subroutine chatter_and_sticking(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: log
        type(event_counts_t) :: counts
        real(wp) :: worst
        integer :: j

        call make_chain(chain, 1, 3.0_wp, 0.6_wp, 0.05_wp, 0.5_wp, .true., 0.0_wp, 0.0_wp, err)
        call run_watching_gaps(chain, 300, worst, err)
        counts = chain_counts(chain)
        call check(t, .not. allocated(err), 'chatter run completes')
        call check(t, counts%sticks > 100 .and. counts%releases > 100, &
                   'chatter ends in sticking contacts that release')
        call check(t, worst >= -1, 'chatter run: no gap below its rounding level at any '// &
                   'event or record')
        call check(t, counts%impacts < 300*200, 'chatter run: bounded number of impacts')
    end subroutine chatter_and_sticking

    !> The steady state touches both walls exactly with zero speed every cycle.
    subroutine exact_grazing(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: log
        type(flow_t) :: flow
        type(event_counts_t) :: counts
        real(wp) :: d2, amplitude, xp, vp, worst
        integer :: j

        d2 = (1 - 1.5_wp**2)**2 + (2*0.05_wp*1.5_wp)**2
        amplitude = sqrt(d2)
        flow = make_flow(0.05_wp, amplitude, 1.5_wp)
        call forced_response(flow, 0.0_wp, xp, vp)
        call init_chain(chain, flow, 0.7_wp, [1.0_wp, 1.0_wp], .true., 1.0e-9_wp, [xp], [vp], &
                        0_i8, 0.0_wp, err)
        call run_watching_gaps(chain, 500, worst, err)
        counts = chain_counts(chain)
        call check(t, .not. allocated(err), 'exact grazing run completes')
        call check(t, worst >= -1, 'exact grazing: no gap below its rounding level at any '// &
                   'event or record')
        call check(t, counts%impacts <= 2*500*4, 'exact grazing: at most a few touches per cycle')
    end subroutine exact_grazing

    !> K = 0: perfectly plastic impacts in a crowded chain (multi-body contacts).
    subroutine plastic_cluster(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: log
        real(wp) :: worst
        integer :: j

        call make_chain(chain, 6, 2.0_wp, 1.2_wp, 0.05_wp, 0.0_wp, .true., 0.05_wp, 2.0_wp, &
                        err, spacing=0.2_wp)
        call run_watching_gaps(chain, 200, worst, err)
        call check(t, .not. allocated(err), 'plastic (K = 0) crowded chain completes')
        call check(t, worst >= -1, 'plastic chain: no gap below its rounding level at any '// &
                   'event or record')
    end subroutine plastic_cluster

    !> Run `cycles` drive cycles event by event; `worst` is the smallest gap seen after any
    !> event or at any strobe point, in units of the gaps' rounding level (below -1: negative).
    subroutine run_watching_gaps(chain, cycles, worst, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: cycles
        real(wp), intent(out) :: worst
        type(error_t), allocatable, intent(out) :: err
        type(walk_t) :: walk

        call walk_events(chain, cycles, walk, err)
        worst = walk%worst_gap
    end subroutine run_watching_gaps

end module test_engine
