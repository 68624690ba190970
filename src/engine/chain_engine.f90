!> The event-driven chain (docs/model.md sections 2.3-2.6 and 3, with 4.7 and 5 in its
!> submodules): exact flow between impacts, impacts in time order, sticking contacts on the
!> walls, and an optional tangent frame carried alongside. The type `chain_t` keeps its
!> components to the engine; everything outside goes through the procedures below.
!>
!> This module holds the type, the interfaces of its submodules and the event loop itself:
!> the clock (the shared epoch, the propagator and drive of the current time, sync, the start
!> of a cycle), the schedule of every bond, and the handlers of impacts, releases and the
!> cluster rule. The loop stays here because every event runs through these small steps
!> many times, and gfortran inlines a procedure only into its own file and only when it is
!> private to a module: every procedure of a submodule is global, and the -fPIC build of the
!> library never inlines a global procedure (as a submodule, the loop ran 9 to 10 % more
!> instructions). A submodule cannot call this module's private procedures either (gfortran
!> 12 does not export them), so what calls the loop's steps, chain_init too, is here. What is
!> reached at most a few times per event lives in submodules, one concern each:
!>
!> - chain_engine_contact: rests on a wall or a stack, touches, release times (section 5.2-5.5);
!> - chain_engine_instants: simultaneous contacts, their order, the cluster rule (5.6-5.7);
!> - chain_engine_tangent: the tangent frame (sections 4.7 and 7);
!> - chain_engine_state: a chain's state out and in, and what the library reads of a chain.
!>
!> Size: this file holds the type, the interfaces of its submodules and the whole event loop
!> with what calls its steps, since a loop split across files would lose gfortran's inlining.
!>
!> Design for speed: every moving oscillator keeps the free part of its motion, (x - xp,
!> v - vp), referred back to one common time, the epoch. Its state at any later time s is then
!> one 2x2 product with the propagator M(s - epoch), which is computed once per event time and
!> shared by every oscillator (and every tangent row): an impact costs no sine or exponential
!> per oscillator, and nothing is touched but the two oscillators involved. After an impact the
!> new free part is referred back to the epoch with M^-1. `chain_sync` moves the epoch to the
!> current time and fills x, v; it also keeps e^(b (s - epoch)) bounded in long cycles. Every
!> bond keeps its next event in the queue (blocks of bonds under a tournament tree); an impact
!> reschedules only the neighbouring bonds. Times are times within the current drive cycle;
!> `chain_new_cycle` moves the frame on by one period.
module chain_engine
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int
    use chain_flow, only: flow_t, propagator_pair, forced_response_at, acceleration_at
    use chain_phases, only: drive_phase
    use chain_gaps, only: gap_t, gap_search_t, next_gap_zero, search_root, search_horizon, &
                          resolvable_speed, surely_resolvable, earliest_closing
    use chain_impact, only: pair_impact, wall_impact, pair_reset_jacobian, &
                            wall_reset_jacobian, saltation_matrix
    use chain_model, only: model_t, bond_gaps
    use chain_state, only: chain_state_t, event_counts_t, contact_free, contact_left, &
                           contact_right
    use chain_queue, only: queue_t, queue_init, queue_set, queue_top, queue_shift, queue_ties
    use chain_lapack, only: qr_workspace_t
    use chain_lyapunov, only: lyapunov_acc_t
    use chain_event_log, only: event_log_t, event_log_append, event_impact, event_release
    use chain_monitor, only: monitor_t, stage_events, events_per_poll
    implicit none
    private
    public :: chain_t, chain_init, chain_snapshot, chain_model
    public :: chain_advance, chain_sync, chain_new_cycle, chain_gaps_now, chain_next_event
    public :: chain_size, chain_cycle, chain_time, chain_start, chain_period, chain_section_time
    public :: chain_elapsed, chain_positions, chain_velocities, chain_copy_state, chain_contacts
    public :: chain_counts, chain_reset_counts
    public :: chain_set_tangent, chain_vectors, chain_tangent_frame, chain_qr_step
    public :: chain_reorthonormalise, chain_rank_lost

    !> What the next event of a bond is (stored with the schedule as chain_state's
    !> event_action).
    integer, parameter :: action_none = 0    !! nothing scheduled on the bond
    integer, parameter :: action_impact = 1  !! the bond closes
    integer, parameter :: action_release = 2 !! a sticking contact on a wall bond lets go
    integer, parameter :: action_recheck = 3 !! the search horizon: look again from here

    real(wp), parameter :: never = huge(1.0_wp)
    !> After this many impacts at one instant, a touching cluster is resolved at once (its
    !> inelastic collapse).
    integer, parameter :: collapse_after = 1000
    !> The epoch moves to the current time once b (s - epoch) exceeds this, so that the
    !> free parts referred back to it (growing like e^(b (s - epoch))) stay far from overflow.
    real(wp), parameter :: rebase_after = 64
    !> A separating pair is looked at again later only if it cannot close before this time.
    real(wp), parameter :: defer_after = 0.25_wp

    !> The free part of one oscillator, all an impact reads and writes of it side by side: an
    !> impact on a long chain touches one record (a cache line or two) instead of one line
    !> in each of five arrays.
    type :: free_part_t
        real(wp) :: y = 0, vy = 0 !! referred back to the epoch
        !> as set at instant `stamp`, kept as they were set: several impacts at one instant (a
        !> cascade, K = 0) must see exactly the velocities the last one left, not their round
        !> trip through the epoch
        real(wp) :: y_now = 0, vy_now = 0
        integer(i8) :: stamp = -1
    end type free_part_t

    type :: chain_t
        private
        integer :: n = 0
        type(flow_t) :: flow
        real(wp) :: restitution = 0.7_wp
        real(wp) :: impact_volume = 2*log(0.7_wp) !! ln |det S| = ln K**2 of every impact (4.5)
        real(wp) :: stick_speed = 1.0e-9_wp !! rebound speed below which chatter ends in sticking
        logical :: walls = .true.           !! fixed (true) or free (false) boundaries
        real(wp), allocatable :: spacing(:) !! spacing(0:n), bond k between osc k and k+1
        integer(i8) :: cycle = 0            !! drive cycles completed since t = 0
        real(wp) :: s = 0                   !! current time within the drive cycle
        integer(i8) :: start_cycle = 0      !! cycle of the run's initial state
        real(wp) :: start_s = 0             !! time within the cycle of the run's initial state
        real(wp), allocatable :: x(:), v(:) !! x(n), v(n): state at time s after chain_sync
        type(free_part_t), allocatable :: free(:) !! free(n): free part of each moving oscillator
        real(wp) :: epoch = 0               !! time within the cycle that free%y, free%vy refer to
        integer(i8) :: instant = 0           !! counts the distinct instants of the frame
        logical :: synced = .false.         !! x, v hold the state at time s = epoch
        real(wp) :: propagator_time = -huge(1.0_wp) !! time of the cached propagators below
        real(wp) :: m(2, 2) = 0, m_inv(2, 2) = 0 !! M(propagator_time - epoch) and its inverse
        real(wp) :: drive_s = -huge(1.0_wp) !! time of the cached drive below
        real(wp) :: drive_x = 0, drive_v = 0, drive_sin = 0 !! xp, vp, sin(w s) at drive_s
        integer, allocatable :: contact(:)  !! contact(n): contact_free / left / right
        type(queue_t) :: queue              !! next event time of each bond
        integer, allocatable :: action(:)   !! action(0:n): what that event is
        integer :: n_vectors = 0            !! tangent vectors carried (0: none)
        real(wp), allocatable :: tangent(:, :) !! tangent(2n, n_vectors): the frame, columns
                                               !! as LAPACK factorises them (no copies);
                                               !! moving rows referred back to the epoch
        integer :: tangent_scale_bits = 0   !! the frame is the true one times 2**(-bits)
        !> A square frame (all 2n vectors, no R factors kept) knows which bonds an impact or a
        !> cluster has joined since it started (joined(n - 1), bond i between oscillators i and
        !> i + 1). A piece, a maximal run of oscillators joined by such bonds [a, b], keeps its
        !> rows and columns 2a - 1 .. 2b to itself (a full spectrum started from unit vectors):
        !> QR steps factorise each piece alone, jumps and epoch moves touch only its columns
        !> (docs/model.md section 7.2). Not allocated for any other frame.
        logical, allocatable :: joined(:)
        !> For Lyapunov spectra: re-orthonormalise the frame right after a large jump (a slow
        !> impact, |S| ~ 1/u) instead of carrying its spread of scales to the next QR step,
        !> where later jumps and the factorisation would lose the directions it squeezed. The
        !> logarithms of the diagonal of R are kept in tangent_log(k), per column, for that
        !> step. (Not for a Poincare-map Jacobian, which must be the plain product.)
        logical :: orthonormalise_jumps = .false.
        !> ln |det| of the jumps since the frame's piece was orthonormal, per column: a jump's
        !> on the first column of its piece (of the frame, without pieces); a piece's volume is
        !> the sum over its columns (pieces that merge add theirs)
        real(wp), allocatable :: jumps_volume(:)
        real(wp), allocatable :: tangent_log(:)
        real(wp), allocatable :: r_diag(:)
        !> For covariant Lyapunov vectors (docs/model.md section 14.2): the whole R factors of
        !> those re-orthonormalisations, multiplied up since the frame was last orthonormal,
        !> P = R_m ... R_1 = r_product diag(exp(r_product_log)), r_product(k, k) upper
        !> triangular with unit columns; the QR step multiplies its own R by it.
        logical :: keep_r_factors = .false.
        logical :: r_folded = .false.   !! P /= I: a re-orthonormalisation since
        real(wp), allocatable :: r_product(:, :), r_product_log(:)
        type(qr_workspace_t) :: qr
        !> Tangent rows hit at the current instant are kept in the coordinates of now (not of
        !> the epoch) until the instant ends: the saltation matrices of a collapse cascade are
        !> huge (1/u) and cancel in their product only if applied without round trips.
        integer(i8), allocatable :: row_stamp(:) !! instant at which rows were moved to now
        integer, allocatable :: touched(:)  !! the oscillators whose rows are now "now"
        integer :: n_touched = 0
        type(event_counts_t) :: counts      !! impacts, sticks, releases, touches, per bond
        !> Events whose tangent map is singular (a rest zeroes rows, a collapse averages them,
        !> K = 0 kills relative velocities): the QR step then looks for collapsed directions.
        integer(i8) :: rank_losses = 0
        real(wp) :: last_event = -huge(1.0_wp)
        integer :: same_instant = 0
    end type chain_t

    ! --------------------------------------------------------------- chain_engine_contact
    interface
        !> Oscillator i comes to rest on the fixed side of `bond`, on the `side` wall, arriving
        !> at speed u.
        module subroutine stick_event(chain, bond, i, side, u, log)
            type(chain_t), intent(inout) :: chain
            integer, intent(in) :: bond, i, side
            real(wp), intent(in) :: u
            type(event_log_t), intent(inout) :: log
        end subroutine stick_event

        !> A contact closing slower than the resolvable speed u_min of its gap: a touch.
        module subroutine touch_event(chain, bond, u, u_min, curvature, log)
            type(chain_t), intent(inout) :: chain
            integer, intent(in) :: bond
            real(wp), intent(in) :: u, u_min, curvature
            type(event_log_t), intent(inout) :: log
        end subroutine touch_event

        !> Does the net force press oscillator i, at rest in a stack on the `side` wall,
        !> towards that wall (now, or from now on)?
        pure module logical function pressed(chain, i, side)
            type(chain_t), intent(in) :: chain
            integer, intent(in) :: i, side
        end function pressed

        !> Next time the force on resting oscillator i turns away from its wall.
        pure module function release_time(chain, i) result(s_release)
            type(chain_t), intent(in) :: chain
            integer, intent(in) :: i
            real(wp) :: s_release
        end function release_time

        !> Position x of oscillator i resting in a stack on the `side` wall.
        pure module function rest_position(chain, i, side) result(x)
            type(chain_t), intent(in) :: chain
            integer, intent(in) :: i, side
            real(wp) :: x
        end function rest_position
    end interface

    ! -------------------------------------------------------------- chain_engine_instants
    interface
        !> Another event at the current instant: count it, and guard against an unbounded
        !> number of impacts at one instant.
        module subroutine count_instant(chain, time, err)
            type(chain_t), intent(inout) :: chain
            real(wp), intent(in) :: time
            type(error_t), allocatable, intent(out) :: err
        end subroutine count_instant

        !> Of the bonds `ties` due at one instant, closing at `speeds` now (-huge: not an
        !> impact), the one that goes first in a chain of n oscillators.
        pure module function tie_winner(ties, speeds, n) result(first)
            integer, intent(in) :: ties(:), n
            real(wp), intent(in) :: speeds(:)
            integer :: first
        end function tie_winner

        !> The cluster of the cluster rule at `bond` (moving oscillators first..last; none if
        !> first > last), its velocity after the rule, and whether a wall stopped it.
        pure module subroutine find_cluster(chain, bond, gaps, first, last, mean, stopped)
            type(chain_t), intent(in) :: chain
            integer, intent(in) :: bond
            real(wp), intent(in) :: gaps(0:)
            integer, intent(out) :: first, last
            real(wp), intent(out) :: mean
            logical, intent(out) :: stopped
        end subroutine find_cluster
    end interface

    ! --------------------------------------------------------------- chain_engine_tangent
    interface
        !> Start carrying a tangent frame (columns of `frame`, shape (2n, k)) from now; with
        !> `keep_r_factors` (and orthonormalise_jumps) the QR steps can give their whole R.
        module subroutine chain_set_tangent(chain, frame, orthonormalise_jumps, keep_r_factors)
            type(chain_t), intent(inout) :: chain
            real(wp), intent(in) :: frame(:, :)
            logical, intent(in), optional :: orthonormalise_jumps, keep_r_factors
        end subroutine chain_set_tangent

        !> Number of tangent vectors carried (0: none).
        pure module integer function chain_vectors(chain)
            type(chain_t), intent(in) :: chain
        end function chain_vectors

        !> The tangent frame (2n, k) as it stands after chain_sync, the engine's power-of-two
        !> scaling undone (an entry that would overflow saturates at the largest double).
        pure module function chain_tangent_frame(chain) result(frame)
            type(chain_t), intent(in) :: chain
            real(wp), allocatable :: frame(:, :)
        end function chain_tangent_frame

        !> One QR step of the tangent frame into `acc`, closing an interval of `cycles` drive
        !> cycles; the engine's bookkeeping restarts. With keep_r_factors, `r_factor` and
        !> `r_log` (k x k, k) get the R of the whole interval, r_factor diag(exp(r_log)): the
        !> frame at the last step times it is the tangent map applied to the frame before
        !> (not when the step dropped collapsed directions: both are then zero).
        module subroutine chain_qr_step(chain, acc, cycles, err, r_factor, r_log)
            type(chain_t), intent(inout) :: chain
            type(lyapunov_acc_t), intent(inout) :: acc
            integer, intent(in) :: cycles
            type(error_t), allocatable, intent(out) :: err
            real(wp), intent(out), optional :: r_factor(:, :), r_log(:)
        end subroutine chain_qr_step

        !> Re-orthonormalise the tangent frame without averaging (while it aligns); `growth`,
        !> if present, gets each column's ln growth since the frame was last orthonormal
        !> (-huge for a column that vanished).
        module subroutine chain_reorthonormalise(chain, err, growth)
            type(chain_t), intent(inout) :: chain
            type(error_t), allocatable, intent(out) :: err
            real(wp), intent(out), optional :: growth(:)
        end subroutine chain_reorthonormalise

        !> Has an event with a singular tangent map (a rest, a collapse, K = 0) happened since
        !> the frame was last orthonormal? The next QR step then looks for lost directions.
        pure module logical function chain_rank_lost(chain)
            type(chain_t), intent(in) :: chain
        end function chain_rank_lost

        !> The jump S of an impact now on the rows of oscillator i (s 2x2) or of i and i + 1
        !> (s 4x4).
        module subroutine jump_rows(chain, i, s)
            type(chain_t), intent(inout) :: chain
            integer, intent(in) :: i
            real(wp), intent(in), contiguous :: s(:, :) !! (2, 2) or (4, 4)
        end subroutine jump_rows

        !> Tangent rows of moving oscillators from the epoch to now.
        pure module subroutine move_tangent_epoch(chain)
            type(chain_t), intent(inout) :: chain
        end subroutine move_tangent_epoch

        !> At the end of an instant: rows moved to now go back to the epoch.
        pure module subroutine rows_back_to_epoch(chain)
            type(chain_t), intent(inout) :: chain
        end subroutine rows_back_to_epoch

        !> Oscillator i comes to rest: its tangent rows become zero.
        pure module subroutine forget_rows(chain, i)
            type(chain_t), intent(inout) :: chain
            integer, intent(in) :: i
        end subroutine forget_rows

        !> The cluster rule on the tangent rows of oscillators first..last.
        pure module subroutine average_rows(chain, first, last, stopped)
            type(chain_t), intent(inout) :: chain
            integer, intent(in) :: first, last
            logical, intent(in) :: stopped
        end subroutine average_rows
    end interface

    ! ----------------------------------------------------------------- chain_engine_state
    interface
        !> Refuse a state that does not fit the model (sizes), before anything is set up.
        module subroutine check_sizes(model, state, err)
            type(model_t), intent(in) :: model
            type(chain_state_t), intent(in) :: state
            type(error_t), allocatable, intent(out) :: err
        end subroutine check_sizes

        !> The model, the state (x, v, contacts, clock) and room for the engine's bookkeeping,
        !> the counters at zero.
        pure module subroutine take_state(chain, model, state)
            type(chain_t), intent(inout) :: chain
            type(model_t), intent(in) :: model
            type(chain_state_t), intent(in) :: state
        end subroutine take_state

        !> The schedule of an earlier run: event times and kinds of bonds 0..n in order.
        module subroutine restore_schedule(chain, event_time, event_action)
            type(chain_t), intent(inout) :: chain
            real(wp), intent(in) :: event_time(0:)
            integer, intent(in) :: event_action(0:)
        end subroutine restore_schedule

        !> Where the run started, the record of simultaneous impacts, the counters and the
        !> tangent frame of `state`.
        module subroutine restore_bookkeeping(chain, state)
            type(chain_t), intent(inout) :: chain
            type(chain_state_t), intent(in) :: state
        end subroutine restore_bookkeeping

        !> The complete state of a chain (synced), from which chain_init goes on bit for bit.
        pure module function chain_snapshot(chain) result(state)
            type(chain_t), intent(in) :: chain
            type(chain_state_t) :: state
        end function chain_snapshot

        !> The model the chain runs.
        pure module function chain_model(chain) result(model)
            type(chain_t), intent(in) :: chain
            type(model_t) :: model
        end function chain_model

        !> Number of oscillators.
        pure module integer function chain_size(chain)
            type(chain_t), intent(in) :: chain
        end function chain_size

        !> Drive cycles completed since t = 0.
        pure module function chain_cycle(chain) result(cycle)
            type(chain_t), intent(in) :: chain
            integer(i8) :: cycle
        end function chain_cycle

        !> The current time within the drive cycle.
        pure module function chain_time(chain) result(s)
            type(chain_t), intent(in) :: chain
            real(wp) :: s
        end function chain_time

        !> Where the run started: its cycle and time within that cycle.
        pure module subroutine chain_start(chain, cycle, s)
            type(chain_t), intent(in) :: chain
            integer(i8), intent(out) :: cycle
            real(wp), intent(out) :: s
        end subroutine chain_start

        !> The drive period T.
        pure module function chain_period(chain) result(period)
            type(chain_t), intent(in) :: chain
            real(wp) :: period
        end function chain_period

        !> The time within a cycle at drive phase `phase` (radians, 0 <= phase < 2 pi).
        pure module function chain_section_time(chain, phase) result(s)
            type(chain_t), intent(in) :: chain
            real(wp), intent(in) :: phase
            real(wp) :: s
        end function chain_section_time

        !> Time since the run's initial state of time s within the current cycle.
        pure module function chain_elapsed(chain, s) result(t)
            type(chain_t), intent(in) :: chain
            real(wp), intent(in) :: s
            real(wp) :: t
        end function chain_elapsed

        !> Positions at the last chain_sync (chain_init and advance_to_point end in one).
        pure module function chain_positions(chain) result(x)
            type(chain_t), intent(in) :: chain
            real(wp), allocatable :: x(:)
        end function chain_positions

        !> Velocities at the last chain_sync.
        pure module function chain_velocities(chain) result(v)
            type(chain_t), intent(in) :: chain
            real(wp), allocatable :: v(:)
        end function chain_velocities

        !> Positions and velocities at the last chain_sync into the caller's arrays (no
        !> temporaries: a record of a long chain).
        pure module subroutine chain_copy_state(chain, x, v)
            type(chain_t), intent(in) :: chain
            real(wp), intent(out) :: x(:), v(:)
        end subroutine chain_copy_state

        !> Which oscillators rest on a wall: contact_free / left / right of chain_state.
        pure module function chain_contacts(chain) result(contact)
            type(chain_t), intent(in) :: chain
            integer, allocatable :: contact(:)
        end function chain_contacts

        !> Impacts, rests, releases, touches and impacts per bond since the counters started.
        pure module function chain_counts(chain) result(counts)
            type(chain_t), intent(in) :: chain
            type(event_counts_t) :: counts
        end function chain_counts

        !> Start the counters from zero (the first record of a run).
        pure module subroutine chain_reset_counts(chain)
            type(chain_t), intent(inout) :: chain
        end subroutine chain_reset_counts

        !> The bond whose event comes next, and its time within the cycle (beyond T: none in
        !> this cycle), for walking a run event by event.
        pure module subroutine chain_next_event(chain, bond, time)
            type(chain_t), intent(in) :: chain
            integer, intent(out) :: bond
            real(wp), intent(out) :: time
        end subroutine chain_next_event
    end interface

contains

    ! ------------------------------------------------------- the loop and the chain's start

    !> Process every event up to time s_target within the current cycle (s_target <= T).
    !> With `watch`, it is told every events_per_poll events (stage_events, done = events so
    !> far in this call) and may stop the chain there, between two events: `stopped` then
    !> comes back .true. and the chain is left between its events, fit only to be replaced
    !> (by the state of a record held for that, see record_cycles).
    subroutine chain_advance(chain, s_target, log, err, watch, stopped)
        type(chain_t), intent(inout) :: chain
        real(wp), intent(in) :: s_target
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: watch
        logical, intent(out), optional :: stopped
        integer :: bond, since_poll
        integer(i8) :: events
        real(wp) :: time
        logical :: tied

        if (present(stopped)) stopped = .false.
        since_poll = 0
        events = 0
        do
            call queue_top(chain%queue, bond, time, tied)
            if (time > s_target) exit
            if (present(watch)) then
                since_poll = since_poll + 1
                if (since_poll == events_per_poll) then
                    events = events + since_poll
                    since_poll = 0
                    ! (without `stopped` to say so, the monitor shows progress but cannot stop)
                    if (.not. watch%keep_going(stage_events, events, 0_i8) .and. &
                        present(stopped)) then
                        stopped = .true.
                        return
                    end if
                end if
            end if
            if (tied) bond = first_of_ties(chain, time)
            chain%s = time
            ! events closer than the rounding of times within a cycle are simultaneous; a new
            ! instant (nearly every event) needs no call into chain_engine_instants
            if (.not. (time <= chain%last_event + 16*epsilon(1.0_wp)*chain%flow%period)) then
                chain%same_instant = 0
                chain%last_event = time
            else
                call count_instant(chain, time, err)
                if (allocated(err)) return
            end if
            if (chain%same_instant > 0 .and. modulo(chain%same_instant, collapse_after) == 0) then
                call collapse_event(chain, bond, log, err)
                if (allocated(err)) return
                cycle
            end if
            select case (chain%action(bond))
            case (action_impact)
                call impact_event(chain, bond, log, err)
            case (action_release)
                call release_event(chain, bond, log, err)
            case default
                call schedule(chain, bond, err)
            end select
            if (allocated(err)) return
        end do
        chain%s = s_target
    end subroutine chain_advance

    !> Move the epoch to the current time and fill x, v (and the tangent rows) with the state
    !> now. The free parts are re-derived from x, v exactly as a start does (start_epoch), and a
    !> second sync at the same time changes nothing, so a run continued from a saved state
    !> follows the uninterrupted one bit for bit.
    pure subroutine chain_sync(chain)
        type(chain_t), intent(inout) :: chain
        integer :: i

        if (chain%synced .and. chain%epoch == chain%s) return
        call propagators_now(chain)
        call drive_now(chain)
        do i = 1, chain%n
            call state_now(chain, i, chain%x(i), chain%v(i))
        end do
        call move_tangent_epoch(chain)
        chain%free%y = chain%x - chain%drive_x
        chain%free%vy = chain%v - chain%drive_v
        call set_epoch_here(chain)
        chain%synced = .true.
        ! from here on the free parts are the ones just derived from x, v
        chain%instant = chain%instant + 1
    end subroutine chain_sync

    !> At the end of a drive cycle (s = T): sync, and restart the in-cycle clock at 0, with the
    !> free parts taken from x, v and the drive at s = 0, as a start from this state would.
    pure subroutine chain_new_cycle(chain)
        type(chain_t), intent(inout) :: chain

        call chain_sync(chain)
        chain%s = 0
        chain%propagator_time = -huge(1.0_wp)
        chain%drive_s = -huge(1.0_wp)
        call start_epoch(chain)
        call queue_shift(chain%queue, chain%flow%period, never)
        chain%cycle = chain%cycle + 1
        chain%last_event = chain%last_event - chain%flow%period
    end subroutine chain_new_cycle

    !> The epoch is the current time, and the free parts come from x, v (a start).
    pure subroutine start_epoch(chain)
        type(chain_t), intent(inout) :: chain

        chain%epoch = chain%s
        call propagators_now(chain)
        call drive_now(chain)
        chain%free%y = chain%x - chain%drive_x
        chain%free%vy = chain%v - chain%drive_v
        chain%synced = .true.
    end subroutine start_epoch

    !> Gaps of all bonds at the current time, bond 0 first (n + 1 values; moves the epoch
    !> here).
    function chain_gaps_now(chain) result(gaps)
        type(chain_t), intent(inout) :: chain
        real(wp), allocatable :: gaps(:)

        call chain_sync(chain)
        allocate (gaps(0:chain%n))
        gaps = bond_gaps(chain%spacing, chain%walls, chain%x)
    end function chain_gaps_now

    !> A chain of `model` in `state`, every bond scheduled. A state with a schedule (an
    !> earlier run's final state, chain_snapshot) has it restored instead, with its record of
    !> simultaneous impacts, its counters and its tangent frame, so that a continued run is
    !> bit-identical to an uninterrupted one.
    subroutine chain_init(chain, model, state, err)
        type(chain_t), intent(out) :: chain
        type(model_t), intent(in) :: model
        type(chain_state_t), intent(in) :: state
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: gaps(0:size(state%x))
        integer :: n, j
        character(len=64) :: buf

        call check_sizes(model, state, err)
        if (allocated(err)) return
        call take_state(chain, model, state)
        n = chain%n
        ! the same rounding as chain_sync, so that a run continued from its saved state
        ! follows the uninterrupted one bit for bit
        call start_epoch(chain)
        gaps = chain_gaps_now(chain)
        do j = 0, n
            if (gaps(j) < 0) then
                write (buf, '(es12.4)') gaps(j)
                call set_error(err, "initial state: the gap of bond "//fmt_int(j)//" is " &
                               //trim(adjustl(buf))//" < 0 (oscillators overlap a neighbour " &
                               //"or a wall); bond k lies between oscillators k and k+1")
                return
            end if
        end do
        call queue_init(chain%queue, n + 1, never)
        chain%action = action_none
        if (state%has_schedule) then
            call restore_schedule(chain, state%event_time, state%event_action)
        else
            call schedule_around(chain, 1, n, err)
            if (allocated(err)) return
        end if
        call restore_bookkeeping(chain, state)
    end subroutine chain_init

    ! ------------------------------------------------------------------------------ clock

    !> The propagator from the epoch to the current time (and its inverse), once per event time.
    pure subroutine propagators_now(chain)
        type(chain_t), intent(inout) :: chain
        real(wp) :: tau, y, vy
        integer :: i

        if (chain%propagator_time == chain%s) return
        if (chain%n_touched > 0) call rows_back_to_epoch(chain)
        chain%propagator_time = chain%s
        chain%instant = chain%instant + 1
        tau = chain%s - chain%epoch
        call propagator_pair(chain%flow, tau, chain%m, chain%m_inv)
        if (chain%flow%damping*tau > rebase_after) then
            do i = 1, chain%n
                if (chain%contact(i) /= contact_free) cycle
                call free_part_now(chain, i, y, vy)
                chain%free(i)%y = y
                chain%free(i)%vy = vy
            end do
            call move_tangent_epoch(chain)
            call set_epoch_here(chain)
            chain%synced = .false.
        end if
    end subroutine propagators_now

    !> The epoch is now: M = identity (after the free parts were moved here).
    pure subroutine set_epoch_here(chain)
        type(chain_t), intent(inout) :: chain

        chain%epoch = chain%s
        chain%m(:, 1) = [1.0_wp, 0.0_wp]
        chain%m(:, 2) = [0.0_wp, 1.0_wp]
        chain%m_inv = chain%m
    end subroutine set_epoch_here

    !> The forced response at the current time, once per event time; only impacts on walls or
    !> resting oscillators and the tangent frame need it (a pair impact does not).
    pure subroutine drive_now(chain)
        type(chain_t), intent(inout) :: chain

        real(wp) :: cos_wt

        if (chain%drive_s == chain%s) return
        chain%drive_s = chain%s
        call drive_phase(chain%flow%phases, chain%s, cos_wt, chain%drive_sin)
        call forced_response_at(chain%flow, chain%drive_sin, cos_wt, chain%drive_x, &
                                chain%drive_v)
    end subroutine drive_now

    !> Free part (x - xp, v - vp) of moving oscillator i now (after propagators_now).
    pure subroutine free_part_now(chain, i, y, vy)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: i
        real(wp), intent(out) :: y, vy

        associate (free => chain%free(i))
            if (free%stamp == chain%instant) then
                y = free%y_now
                vy = free%vy_now
            else
                y = chain%m(1, 1)*free%y + chain%m(1, 2)*free%vy
                vy = chain%m(2, 1)*free%y + chain%m(2, 2)*free%vy
            end if
        end associate
    end subroutine free_part_now

    !> State of oscillator i now (after propagators_now and drive_now): moving, or resting in a
    !> stack on a wall.
    pure subroutine state_now(chain, i, x, v)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: i
        real(wp), intent(out) :: x, v

        if (chain%contact(i) == contact_free) then
            call free_part_now(chain, i, x, v)
            x = x + chain%drive_x
            v = v + chain%drive_v
        else
            x = rest_position(chain, i, chain%contact(i))
            v = 0
        end if
    end subroutine state_now

    !> Oscillator i moves on from state (x, v) now (after propagators_now and drive_now).
    pure subroutine set_moving_state(chain, i, x, v)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: i
        real(wp), intent(in) :: x, v

        call set_free_part(chain, i, x - chain%drive_x, v - chain%drive_v)
    end subroutine set_moving_state

    !> Oscillator i moves on with free part (y, vy) now: referred back to the epoch.
    pure subroutine set_free_part(chain, i, y, vy)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: i
        real(wp), intent(in) :: y, vy

        chain%free(i) = free_part_t(chain%m_inv(1, 1)*y + chain%m_inv(1, 2)*vy, &
                                    chain%m_inv(2, 1)*y + chain%m_inv(2, 2)*vy, y, vy, &
                                    chain%instant)
        chain%contact(i) = contact_free
        chain%synced = .false.
    end subroutine set_free_part

    !> Acceleration of a free oscillator in state (x, v) now (after `propagators_now`).
    pure function acceleration_now(chain, x, v) result(acc)
        type(chain_t), intent(in) :: chain
        real(wp), intent(in) :: x, v
        real(wp) :: acc

        acc = acceleration_at(chain%flow, chain%drive_sin, x, v)
    end function acceleration_now

    !> Acceleration of oscillator i in state (x, v) now (zero while it rests on a wall).
    pure function field(chain, i, x, v) result(acc)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: i
        real(wp), intent(in) :: x, v
        real(wp) :: acc

        acc = 0
        if (chain%contact(i) == contact_free) acc = acceleration_now(chain, x, v)
    end function field

    ! --------------------------------------------------------------------------- schedule

    !> Find and queue the next event of a bond from the current time.
    subroutine schedule(chain, bond, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(error_t), allocatable, intent(out) :: err
        type(gap_t) :: gap
        type(gap_search_t) :: found
        logical :: closes
        integer :: resting

        call gap_now(chain, bond, gap, closes, resting)
        if (resting /= 0) then
            chain%action(bond) = action_release
            call queue_set(chain%queue, bond, release_time(chain, resting))
            return
        end if
        if (.not. closes) then
            chain%action(bond) = action_none
            call queue_set(chain%queue, bond, never)
            return
        end if
        found = next_gap_zero(chain%flow, gap, chain%s, chain%flow%period)
        if (found%info /= 0) then
            call set_error(err, "impact search: no convergence on bond "//fmt_int(bond)// &
                           " (a gap grazing zero for too long); please report the input")
            return
        end if
        select case (found%status)
        case (search_root)
            chain%action(bond) = action_impact
            call queue_set(chain%queue, bond, chain%s + found%tau)
        case (search_horizon)
            chain%action(bond) = action_recheck
            call queue_set(chain%queue, bond, chain%s + found%tau)
        case default
            chain%action(bond) = action_none
            call queue_set(chain%queue, bond, never)
        end select
    end subroutine schedule

    !> Reschedule every bond touching oscillators first..last (bonds first-1 .. last).
    subroutine schedule_around(chain, first, last, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: first, last
        type(error_t), allocatable, intent(out) :: err
        integer :: bond

        do bond = first - 1, last
            call schedule(chain, bond, err)
            if (allocated(err)) return
        end do
    end subroutine schedule_around

    !> Schedule a pair bond of two moving oscillators, with gap `gap` now, that is opening:
    !> rather than searching its next impact now, look again when it could first close at the
    !> earliest (chain_gaps' earliest_closing), as long as that is not soon; a neighbour's
    !> impact usually reschedules it before then.
    subroutine schedule_separating(chain, bond, gap, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(gap_t), intent(in) :: gap
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: earliest

        if (gap%vy > 0) then
            earliest = earliest_closing(chain%flow, gap)
            if (earliest > defer_after) then
                chain%action(bond) = action_recheck
                call queue_set(chain%queue, bond, chain%s + earliest)
                return
            end if
        end if
        call schedule(chain, bond, err)
    end subroutine schedule_separating

    !> The gap function of a bond as it stands now: a(bond) + x(right) - x(left), where each
    !> side is a moving oscillator or a fixed position (a wall, or an oscillator resting in a
    !> stack on a wall). `closes` is false when both sides are fixed or the bond is a free end;
    !> `resting` /= 0 names the oscillator that rests on this bond (its next event is release).
    subroutine gap_now(chain, bond, gap, closes, resting)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(gap_t), intent(out) :: gap
        logical, intent(out) :: closes
        integer, intent(out) :: resting
        integer :: l, r
        real(wp) :: y, vy, yl, vyl, fixed_l, fixed_r
        logical :: moving_l, moving_r

        l = bond
        r = bond + 1
        resting = 0
        closes = .true.
        ! nearly every call, so first: an inner bond between two moving oscillators, whose
        ! gap is the difference of their free parts (the drive cancels)
        if (l >= 1 .and. r <= chain%n) then
            if (chain%contact(l) == contact_free .and. chain%contact(r) == contact_free) then
                call propagators_now(chain)
                call free_part_now(chain, r, y, vy)
                call free_part_now(chain, l, yl, vyl)
                gap = gap_t(chain%spacing(bond), y - yl, vy - vyl, 0.0_wp)
                return
            end if
        end if
        if (.not. chain%walls .and. (bond == 0 .or. bond == chain%n)) then
            closes = .false.
            return
        end if
        if (r <= chain%n) then
            if (chain%contact(r) == contact_left) then
                resting = r
                return
            end if
        end if
        if (l >= 1) then
            if (chain%contact(l) == contact_right) then
                resting = l
                return
            end if
        end if
        call side_position(chain, l, moving_l, fixed_l)
        call side_position(chain, r, moving_r, fixed_r)
        call propagators_now(chain)
        ! (both sides moving was the first case: a wall or a resting side is fixed here)
        if (moving_r) then
            call free_part_now(chain, r, y, vy)
            gap = gap_t(chain%spacing(bond) - fixed_l, y, vy, 1.0_wp)
        else if (moving_l) then
            call free_part_now(chain, l, y, vy)
            gap = gap_t(chain%spacing(bond) + fixed_r, -y, -vy, -1.0_wp)
        else
            closes = .false.
        end if
    end subroutine gap_now

    !> Is side i of a bond a moving oscillator, or a fixed position (wall at x = 0 in the
    !> bond's frame, or a resting oscillator at its rest position)?
    pure subroutine side_position(chain, i, moving, fixed)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: i
        logical, intent(out) :: moving
        real(wp), intent(out) :: fixed

        moving = .false.
        fixed = 0
        if (i < 1 .or. i > chain%n) return
        if (chain%contact(i) == contact_free) then
            moving = .true.
        else
            fixed = rest_position(chain, i, chain%contact(i))
        end if
    end subroutine side_position

    !> Of several contacts due at one instant, the one that goes first: chain_engine_instants'
    !> tie_winner, given the bonds and how fast each closes now.
    function first_of_ties(chain, time) result(first)
        type(chain_t), intent(inout) :: chain
        real(wp), intent(in) :: time
        integer :: first, count, j
        integer :: ties(0:chain%n)
        real(wp) :: speeds(0:chain%n)

        chain%s = time
        call queue_ties(chain%queue, ties, count)
        do j = 0, count - 1
            speeds(j) = -huge(1.0_wp)
            if (chain%action(ties(j)) == action_impact) speeds(j) = approach_speed(chain, ties(j))
        end do
        first = tie_winner(ties(:count - 1), speeds(:count - 1), chain%n)
    end function first_of_ties

    !> The rate at which a bond's gap closes now (negative: opening).
    function approach_speed(chain, bond) result(u)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        real(wp) :: u
        type(gap_t) :: gap
        logical :: closes
        integer :: resting

        u = -huge(1.0_wp)
        call gap_now(chain, bond, gap, closes, resting)
        if (.not. closes .or. resting /= 0) return
        call drive_now(chain)
        u = -(gap%vy + gap%beta*chain%drive_v)
    end function approach_speed

    ! --------------------------------------------------------------------------- impacts

    !> An impact on a bond: two moving oscillators, or one moving against a fixed side.
    subroutine impact_event(chain, bond, log, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        integer :: l, r
        logical :: moving_l, moving_r
        real(wp) :: fixed_l, fixed_r

        l = bond
        r = bond + 1
        call side_position(chain, l, moving_l, fixed_l)
        call side_position(chain, r, moving_r, fixed_r)
        if (moving_l .and. moving_r) then
            call pair_event(chain, bond, log, err)
        else if (moving_r) then
            call contact_event(chain, bond, r, contact_left, log, err)
        else if (moving_l) then
            call contact_event(chain, bond, l, contact_right, log, err)
        else
            call schedule(chain, bond, err)
        end if
    end subroutine impact_event

    !> Oscillator i reaches the fixed side of a bond (a wall, or the top of a resting stack) on
    !> the `side` wall. An arrival too slow to resolve (below the resolvable speed of the gap)
    !> ends in rest if the net force presses it there, and is a touch otherwise; so does an
    !> arrival below `stick_speed` while pressed (chatter ends). Otherwise it bounces off a
    !> wall, or hits the resting oscillator (which then moves).
    subroutine contact_event(chain, bond, i, side, log, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond, i, side
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: sgn, x, v_minus, u, acc_minus, curvature, u_min
        type(gap_t) :: gap
        logical :: closes
        integer :: resting

        call propagators_now(chain)
        call drive_now(chain)
        call state_now(chain, i, x, v_minus)
        sgn = merge(-1.0_wp, 1.0_wp, side == contact_left)
        u = sgn*v_minus
        acc_minus = acceleration_now(chain, x, v_minus)
        ! the gap is a(bond) +- x(i) + const: its curvature is the acceleration, signed
        curvature = -sgn*acc_minus
        call gap_now(chain, bond, gap, closes, resting)
        u_min = 0
        if (.not. surely_resolvable(chain%flow, gap, curvature, u)) &
            u_min = resolvable_speed(chain%flow, gap, curvature)
        if (u < max(chain%stick_speed, u_min)) then
            if (pressed(chain, i, side)) then
                call stick_event(chain, bond, i, side, u, log)
                call schedule_around(chain, i, i, err)
                return
            end if
        end if
        if (u > 0 .and. u < u_min) then
            call touch_event(chain, bond, u, u_min, curvature, log)
            return
        else if (u > 0 .and. (bond == 0 .or. bond == chain%n)) then
            call wall_event(chain, bond, i, x, v_minus, acc_minus, sgn, log)
        else if (u > 0) then
            call pair_event(chain, bond, log, err)
            return
        end if
        call schedule_around(chain, i, i, err)
    end subroutine contact_event

    !> Oscillator i, at x with velocity v_minus and acceleration acc_minus, bounces off the
    !> wall of bond 0 (sgn = -1) or n (sgn = 1).
    subroutine wall_event(chain, bond, i, x, v_minus, acc_minus, sgn, log)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond, i
        real(wp), intent(in) :: x, v_minus, acc_minus, sgn
        type(event_log_t), intent(inout) :: log
        real(wp) :: v_plus, acc_plus, s(2, 2)
        integer :: info

        v_plus = v_minus
        call wall_impact(chain%restitution, v_plus)
        acc_plus = acceleration_now(chain, x, v_plus)
        call set_moving_state(chain, i, x, v_plus)
        if (chain%n_vectors > 0) then
            call saltation_matrix(wall_reset_jacobian(chain%restitution), &
                                  [v_minus, acc_minus], [v_plus, acc_plus], &
                                  [-sgn, 0.0_wp], s, info)
            if (chain%restitution == 0) chain%rank_losses = chain%rank_losses + 1
            call jump_rows(chain, i, s)
        end if
        call count_impact(chain, bond, sgn*v_minus, log)
    end subroutine wall_event

    !> Impact of oscillators `bond` and `bond`+1 (either may be resting; it then moves).
    subroutine pair_event(chain, bond, log, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        integer :: l, r
        real(wp) :: u, yl, wl, yr, wr, curvature, u_min
        type(gap_t) :: gap
        logical :: both_moving

        l = bond
        r = bond + 1
        call propagators_now(chain)
        both_moving = chain%contact(l) == contact_free .and. chain%contact(r) == contact_free
        ! the impact law is Galilean invariant: it acts on the free parts (x - xp, v - vp)
        ! alone, so two moving oscillators collide without the drive being evaluated
        if (both_moving) then
            call free_part_now(chain, l, yl, wl)
            call free_part_now(chain, r, yr, wr)
        else
            call drive_now(chain)
            call state_now(chain, l, yl, wl)
            call state_now(chain, r, yr, wr)
            yl = yl - chain%drive_x
            wl = wl - chain%drive_v
            yr = yr - chain%drive_x
            wr = wr - chain%drive_v
        end if
        u = wl - wr
        if (u > 0 .and. both_moving) then
            ! the pair gap a + (yr - yl) is a free damped oscillation: g'' = -(yr - yl) - 2 b g'
            curvature = -(yr - yl) - 2*chain%flow%damping*(wr - wl)
            gap = gap_t(chain%spacing(bond), yr - yl, wr - wl, 0.0_wp)
            if (.not. surely_resolvable(chain%flow, gap, curvature, u)) then
                u_min = resolvable_speed(chain%flow, gap, curvature)
                if (u < u_min) then
                    call touch_event(chain, bond, u, u_min, curvature, log)
                    return
                end if
            end if
        end if
        if (u > 0) then
            call pair_bounce(chain, bond, u, yl, wl, yr, wr, log)
            ! the pair just separated: its next impact is far, and usually pre-empted (its gap
            ! now is the one gap_now would give: both free parts were set at this instant)
            call schedule(chain, l - 1, err)
            if (.not. allocated(err)) call schedule_separating(chain, bond, &
                gap_t(chain%spacing(bond), yr - yl, wr - wl, 0.0_wp), err)
            if (.not. allocated(err)) call schedule(chain, r, err)
            return
        end if
        call schedule_around(chain, l, r, err)
    end subroutine pair_event

    !> The pair impact itself on free parts (yl, wl), (yr, wr) now, approach speed u: new
    !> velocities, the jump of the tangent rows, the count.
    subroutine pair_bounce(chain, bond, u, yl, wl, yr, wr, log)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        real(wp), intent(in) :: u, yl, yr
        real(wp), intent(inout) :: wl, wr
        type(event_log_t), intent(inout) :: log
        integer :: l, r, info
        real(wp) :: k, xp, vp, f_minus(4), f_plus(4), s(4, 4)

        l = bond
        r = bond + 1
        k = chain%restitution
        if (chain%n_vectors > 0) then
            call drive_now(chain)
            xp = chain%drive_x
            vp = chain%drive_v
            ! S needs velocities only through differences (offset-free): the free
            ! parts keep grad h . f- = -u exactly
            f_minus = [wl, field(chain, l, yl + xp, wl + vp), &
                       wr, field(chain, r, yr + xp, wr + vp)]
        end if
        call pair_impact(k, wl, wr)
        ! both move on (a resting one is knocked off its stack)
        call set_free_part(chain, l, yl, wl)
        call set_free_part(chain, r, yr, wr)
        if (chain%n_vectors > 0) then
            f_plus = [wl, field(chain, l, yl + xp, wl + vp), &
                      wr, field(chain, r, yr + xp, wr + vp)]
            call saltation_matrix(pair_reset_jacobian(k), f_minus, f_plus, &
                                  [-1.0_wp, 0.0_wp, 1.0_wp, 0.0_wp], s, info)
            if (k == 0) chain%rank_losses = chain%rank_losses + 1
            ! (a resting oscillator's rows are zero in any coordinates)
            call jump_rows(chain, l, s)
        end if
        call count_impact(chain, bond, u, log)
    end subroutine pair_bounce

    !> A resting oscillator leaves its stack.
    subroutine release_event(chain, bond, log, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        integer :: i

        ! the oscillator above the bond rests on the left stack, or the one below on the right
        i = bond
        if (bond < chain%n) then
            if (chain%contact(bond + 1) == contact_left) i = bond + 1
        end if
        call propagators_now(chain)
        call drive_now(chain)
        call set_moving_state(chain, i, rest_position(chain, i, chain%contact(i)), 0.0_wp)
        chain%counts%releases = chain%counts%releases + 1
        call event_log_append(log, chain_elapsed(chain, chain%s), bond, 0.0_wp, event_release)
        call schedule_around(chain, i, i, err)
    end subroutine release_event

    !> Inelastic collapse (the cluster rule, chain_engine_instants' find_cluster): the cluster
    !> of touching moving oscillators at the bond moves on with its mean velocity, or stops
    !> against a wall or a resting stack; its tangent rows are averaged like the velocities.
    subroutine collapse_event(chain, bond, log, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        integer :: first, last, i
        real(wp) :: mean, gaps(0:chain%n)
        logical :: stopped

        gaps = chain_gaps_now(chain)
        call find_cluster(chain, bond, gaps, first, last, mean, stopped)
        if (first > last) then
            ! both sides fixed: nothing moves here
            call schedule(chain, bond, err)
            return
        end if
        chain%v(first:last) = mean
        do i = first, last
            if (chain%contact(i) == contact_free) &
                call set_moving_state(chain, i, chain%x(i), chain%v(i))
        end do
        if (chain%n_vectors > 0) call average_rows(chain, first, last, stopped)
        call count_impact(chain, bond, 0.0_wp, log)
        call schedule_around(chain, first, last, err)
    end subroutine collapse_event

    !> Count and log an impact of approach speed u on a bond.
    subroutine count_impact(chain, bond, u, log)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        real(wp), intent(in) :: u
        type(event_log_t), intent(inout) :: log

        chain%counts%impacts = chain%counts%impacts + 1
        chain%counts%site_counts(bond) = chain%counts%site_counts(bond) + 1
        ! (the elapsed time is a call into a submodule: only when there is a log to keep)
        if (log%enabled) &
            call event_log_append(log, chain_elapsed(chain, chain%s), bond, u, event_impact)
    end subroutine count_impact

end module chain_engine
