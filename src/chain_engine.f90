!> The event-driven chain (docs/model.md sections 1-5): exact flow between impacts, impacts in time
!> order, sticking contacts on the walls, and an optional tangent frame carried alongside.
!>
!> Design for speed: every moving oscillator keeps the free part of its motion, (x - xp,
!> v - vp), referred back to one common time, the epoch. Its state at any later time s is then
!> one 2x2 product with the propagator M(s - epoch), which is computed once per event time and
!> shared by every oscillator (and every tangent row): an impact costs no sine or exponential
!> per oscillator, and nothing is touched but the two oscillators involved. After an impact the
!> new free part is referred back to the epoch with M^-1. `chain_sync` moves the epoch to the
!> current time and fills x, v; it also keeps e^(b (s - epoch)) bounded in long cycles. Every
!> bond keeps its next event in an indexed heap; an impact reschedules only the neighbouring
!> bonds. Times are times within the current drive cycle; `chain_new_cycle` moves the frame on
!> by one period.
!>
!> Contacts at the limit of resolution (docs/model.md section 5): an approach slower than the
!> resolvable speed of its gap (chain_gaps) is decided by rounding. Pressed into a wall or a
!> resting stack it ends in rest (as does one below `stick_speed`: chatter ends); otherwise it
!> is a touch, with no impulse and no jump of the tangent. Oscillators can stack on a resting
!> one: oscillator i rests at x = -(a(0) + ... + a(i-1)), where its acceleration is
!> a(0) + ... + a(i-1) + A sin(w t) (mirror image on the right wall). Each resting oscillator
!> leaves when that force turns away from the wall, a time known in closed form; the top of a
!> stack always leaves first. An impact on a resting oscillator sets it moving again. Two
!> moving oscillators in contact always separate (their springs differ by a at contact), so
!> sticking happens only against walls.
!>
!> Simultaneous contacts (triple contacts) are resolved as a sequence of pair impacts in time
!> order; contacts due at exactly one time go fastest first, then nearest the middle (a rule
!> the mirror image keeps); after each, the neighbouring bonds are re-examined and any that is
!> closed and closing fires at the same instant.
module chain_engine
    use chain_kinds, only: wp, i8, two_pi
    use chain_error, only: error_t, set_error, fmt_int
    use chain_flow, only: flow_t, propagator_pair, forced_response_at, acceleration_at
    use chain_gaps, only: gap_t, gap_search_t, next_gap_zero, search_root, search_horizon, &
                          resolvable_speed, earliest_closing
    use chain_impact, only: pair_impact, wall_impact, pair_reset_jacobian, &
                            wall_reset_jacobian, saltation_matrix
    use chain_queue, only: queue_t, queue_init, queue_set, queue_top, queue_shift, queue_ties
    use chain_lapack, only: qr_orthonormalise, qr_workspace_t
    use chain_events, only: event_log_t, event_log_append, event_impact, event_stick, &
                            event_release, event_touch
    implicit none
    private
    public :: chain_t, chain_init, chain_advance, chain_sync, chain_new_cycle
    public :: chain_set_tangent, chain_gaps_now, chain_elapsed
    public :: contact_free, contact_left, contact_right
    public :: action_none, action_impact, action_release, action_recheck

    integer, parameter :: contact_free = 0   !! moving freely
    integer, parameter :: contact_left = -1  !! resting on the left wall
    integer, parameter :: contact_right = 1  !! resting on the right wall

    integer, parameter :: action_none = 0    !! nothing scheduled on the bond
    integer, parameter :: action_impact = 1  !! the bond closes
    integer, parameter :: action_release = 2 !! a sticking contact on a wall bond lets go
    integer, parameter :: action_recheck = 3 !! the search horizon: look again from here

    real(wp), parameter :: never = huge(1.0_wp)
    !> After this many impacts at one instant, a touching cluster is resolved at once (its
    !> inelastic collapse); far more means the engine is stuck, which is reported.
    integer, parameter :: collapse_after = 1000
    integer, parameter :: max_same_instant = 100000
    !> The epoch moves to the current time once b (s - epoch) exceeds this, so that the
    !> free parts referred back to it (growing like e^(b (s - epoch))) stay far from overflow.
    real(wp), parameter :: rebase_after = 64
    !> A separating pair is looked at again later only if it cannot close before this time.
    real(wp), parameter :: defer_after = 0.25_wp
    !> A saltation matrix with an entry above this re-orthonormalises a Lyapunov frame at once.
    real(wp), parameter :: large_jump = 64
    !> ... and so does a run of jumps that shrank the frame's volume by more than e**(-18).
    real(wp), parameter :: small_volume = -18
    !> ... and so does a frame entry above this (the frame was orthonormal: entries <= 1).
    real(wp), parameter :: large_growth = 1024

    type :: chain_t
        integer :: n = 0
        type(flow_t) :: flow
        real(wp) :: restitution = 0.7_wp
        real(wp) :: stick_speed = 1.0e-9_wp !! rebound speed below which chatter ends in sticking
        logical :: walls = .true.           !! fixed (true) or free (false) boundaries
        real(wp), allocatable :: spacing(:) !! spacing(0:n), bond k between osc k and k+1
        integer(i8) :: cycle = 0            !! drive cycles completed since t = 0
        real(wp) :: s = 0                   !! current time within the drive cycle
        integer(i8) :: start_cycle = 0      !! cycle of the run's initial state
        real(wp) :: start_s = 0             !! time within the cycle of the run's initial state
        real(wp), allocatable :: x(:), v(:) !! x(n), v(n): state at time s after chain_sync
        real(wp), allocatable :: y(:), vy(:) !! y(n), vy(n): free part of each moving
                                             !! oscillator, referred back to the epoch
        real(wp) :: epoch = 0               !! time within the cycle that y, vy refer to
        !> Free parts set at the current instant, kept as they were set: several impacts at one
        !> instant (a cascade, K = 0) must see exactly the velocities the last one left, not
        !> their round trip through the epoch.
        real(wp), allocatable :: y_now(:), vy_now(:)
        integer(i8), allocatable :: stamp(:) !! instant at which y_now, vy_now were set
        integer(i8) :: instant = 0           !! counts the distinct instants of the frame
        logical :: synced = .false.         !! x, v hold the state at time s = epoch
        real(wp) :: frame_s = -huge(1.0_wp) !! time of the cached propagators below
        real(wp) :: m(2, 2) = 0, m_inv(2, 2) = 0 !! M(frame_s - epoch) and its inverse
        real(wp) :: drive_s = -huge(1.0_wp) !! time of the cached drive below
        real(wp) :: drive_x = 0, drive_v = 0, drive_sin = 0 !! xp, vp, sin(w s) at drive_s
        integer, allocatable :: contact(:)  !! contact(n): contact_free / left / right
        type(queue_t) :: queue              !! next event time of each bond
        integer, allocatable :: action(:)   !! action(0:n): what that event is
        integer :: n_vectors = 0            !! tangent vectors carried (0: none)
        real(wp), allocatable :: tangent(:, :) !! tangent(n_vectors, 2n): frame, transposed;
                                               !! moving rows referred back to the epoch
        integer :: tangent_scale_bits = 0   !! the frame is the true one times 2**(-bits)
        !> For Lyapunov spectra: re-orthonormalise the frame right after a large jump (a slow
        !> impact, |S| ~ 1/u) instead of carrying its spread of scales to the next QR step,
        !> where later jumps and the factorisation would lose the directions it squeezed. The
        !> logarithms of the diagonal of R are kept in tangent_log(k), per column, for that
        !> step. (Not for a Poincare-map Jacobian, which must be the plain product.)
        logical :: orthonormalise_jumps = .false.
        real(wp) :: jumps_volume = 0 !! ln |det| of the jumps since the frame was orthonormal
        real(wp), allocatable :: tangent_log(:)
        real(wp), allocatable :: frame_work(:, :), r_diag(:)
        type(qr_workspace_t) :: qr
        !> Tangent rows hit at the current instant are kept in the coordinates of now (not of
        !> the epoch) until the instant ends: the saltation matrices of a collapse cascade are
        !> huge (1/u) and cancel in their product only if applied without round trips.
        integer(i8), allocatable :: row_stamp(:) !! instant at which rows were moved to now
        integer, allocatable :: touched(:)  !! the oscillators whose rows are now "now"
        integer :: n_touched = 0
        integer(i8) :: impacts = 0, sticks = 0, releases = 0, touches = 0
        !> Events whose tangent map is singular (a rest zeroes rows, a collapse averages them,
        !> K = 0 kills relative velocities): the QR step then looks for collapsed directions.
        integer(i8) :: rank_losses = 0
        integer(i8), allocatable :: site_counts(:) !! site_counts(0:n): impacts per bond
        real(wp) :: last_event = -huge(1.0_wp)
        integer :: same_instant = 0
    end type chain_t

contains

    !> Set up a chain in state (x, v) at (cycle, s) and schedule every bond. With `queue_time`
    !> and `queue_action` (from an earlier run's final state) the schedule is restored instead
    !> of searched, so that a continued run is bit-identical to an uninterrupted one.
    subroutine chain_init(chain, flow, restitution, spacing, walls, stick_speed, x, v, cycle, &
                          s, err, contact, queue_time, queue_action)
        type(chain_t), intent(out) :: chain
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: restitution, spacing(0:), stick_speed, x(:), v(:), s
        logical, intent(in) :: walls
        integer(i8), intent(in) :: cycle
        type(error_t), allocatable, intent(out) :: err
        integer, intent(in), optional :: contact(:), queue_action(0:)
        real(wp), intent(in), optional :: queue_time(0:)
        real(wp) :: gaps(0:size(x))
        integer :: n, j
        character(len=64) :: buf

        n = size(x)
        chain%n = n
        chain%flow = flow
        chain%restitution = restitution
        chain%stick_speed = stick_speed
        chain%walls = walls
        chain%spacing = spacing
        chain%x = x
        chain%v = v
        chain%cycle = cycle
        chain%s = s
        chain%start_cycle = cycle
        chain%start_s = s
        allocate (chain%contact(n), chain%action(0:n), chain%site_counts(0:n))
        allocate (chain%y_now(n), chain%vy_now(n), chain%stamp(n))
        chain%stamp = -1
        allocate (chain%row_stamp(n), chain%touched(n))
        chain%row_stamp = -1
        chain%contact = contact_free
        if (present(contact)) chain%contact = contact
        ! the same rounding as chain_sync, so that a run continued from its saved state
        ! follows the uninterrupted one bit for bit
        chain%epoch = s
        call frame_now(chain)
        call drive_now(chain)
        chain%y = chain%x - chain%drive_x
        chain%vy = chain%v - chain%drive_v
        chain%synced = .true.
        chain%site_counts = 0
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
        if (present(queue_time) .and. present(queue_action)) then
            do j = 0, n
                chain%action(j) = queue_action(j)
                call queue_set(chain%queue, j, queue_time(j))
            end do
        else
            do j = 0, n
                call schedule(chain, j, err)
                if (allocated(err)) return
            end do
        end if
    end subroutine chain_init

    !> Start carrying a tangent frame (columns of `frame`, shape (2n, k)) from now; with
    !> `orthonormalise_jumps`, re-orthonormalised after every large jump (Lyapunov spectra).
    pure subroutine chain_set_tangent(chain, frame, orthonormalise_jumps)
        type(chain_t), intent(inout) :: chain
        real(wp), intent(in) :: frame(:, :)
        logical, intent(in), optional :: orthonormalise_jumps
        integer :: i

        chain%orthonormalise_jumps = .false.
        if (present(orthonormalise_jumps)) chain%orthonormalise_jumps = orthonormalise_jumps
        chain%tangent_log = [(0.0_wp, i=1, size(frame, 2))]
        chain%jumps_volume = 0
        chain%n_vectors = 0
        call chain_sync(chain)
        chain%n_vectors = size(frame, 2)
        chain%rank_losses = 0
        chain%n_touched = 0
        chain%row_stamp = -1
        chain%tangent = transpose(frame)
        ! a resting oscillator's state does not depend on where it came from
        do i = 1, chain%n
            if (chain%contact(i) /= contact_free) then
                chain%tangent(:, 2*i - 1:2*i) = 0
                chain%rank_losses = chain%rank_losses + 1
            end if
        end do
    end subroutine chain_set_tangent

    !> Gaps of all bonds at the current time (moves the epoch here).
    function chain_gaps_now(chain) result(gaps)
        type(chain_t), intent(inout) :: chain
        real(wp) :: gaps(0:chain%n)
        integer :: n

        call chain_sync(chain)
        n = chain%n
        gaps(1:n - 1) = chain%spacing(1:n - 1) + chain%x(2:n) - chain%x(1:n - 1)
        if (chain%walls) then
            gaps(0) = chain%spacing(0) + chain%x(1)
            gaps(n) = chain%spacing(n) - chain%x(n)
        else
            gaps(0) = huge(1.0_wp)
            gaps(n) = huge(1.0_wp)
        end if
    end function chain_gaps_now

    !> Time since the run's initial state of time s within the current cycle.
    pure function chain_elapsed(chain, s) result(t)
        type(chain_t), intent(in) :: chain
        real(wp), intent(in) :: s
        real(wp) :: t

        t = real(chain%cycle - chain%start_cycle, wp)*chain%flow%period + (s - chain%start_s)
    end function chain_elapsed

    !> Process every event up to time s_target within the current cycle (s_target <= T).
    subroutine chain_advance(chain, s_target, log, err)
        type(chain_t), intent(inout) :: chain
        real(wp), intent(in) :: s_target
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        integer :: bond
        real(wp) :: time

        do
            call queue_top(chain%queue, bond, time)
            if (time > s_target) exit
            if (has_tie(chain%queue)) bond = first_of_ties(chain, time)
            chain%s = time
            call count_instant(chain, time, err)
            if (allocated(err)) return
            if (chain%same_instant > 0 .and. modulo(chain%same_instant, collapse_after) == 0) then
                call collapse_cluster(chain, bond, log, err)
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

    !> Is another bond due at exactly the time of the heap's top? (Its children hold the next
    !> earliest keys.)
    pure logical function has_tie(q)
        type(queue_t), intent(in) :: q
        integer :: c

        has_tie = .false.
        do c = 2, min(5, q%size)
            if (q%key(c) == q%key(1)) has_tie = .true.
        end do
    end function has_tie

    !> Of several contacts due at one instant (a cascade through touching oscillators: one
    !> impact makes both neighbouring bonds close at once), the one that closes fastest goes
    !> first; then the one nearer the middle of the chain; then the lower bond. The first two
    !> keys are the same for a chain and its mirror image, so the two resolve their cascades
    !> alike (the bond index alone would reverse the order).
    function first_of_ties(chain, time) result(first)
        type(chain_t), intent(inout) :: chain
        real(wp), intent(in) :: time
        integer :: first, count, j, bond
        integer :: ties(0:chain%n)
        real(wp) :: best, u, middle

        chain%s = time
        call queue_ties(chain%queue, ties, count)
        middle = 0.5_wp*chain%n
        first = ties(0)
        best = -huge(1.0_wp)
        do j = 0, count - 1
            bond = ties(j)
            u = -huge(1.0_wp)
            if (chain%action(bond) == action_impact) u = approach_speed(chain, bond)
            if (u > best .or. (u == best .and. (abs(bond - middle) < abs(first - middle) .or. &
                (abs(bond - middle) == abs(first - middle) .and. bond < first)))) then
                best = u
                first = bond
            end if
        end do
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

    !> Move the epoch to the current time and fill x, v (and the tangent rows) with the state
    !> now. The free parts are re-derived from x, v exactly as chain_init does, and a second
    !> sync at the same time changes nothing, so a run continued from a saved state follows
    !> the uninterrupted one bit for bit.
    pure subroutine chain_sync(chain)
        type(chain_t), intent(inout) :: chain
        integer :: i

        if (chain%synced .and. chain%epoch == chain%s) return
        call frame_now(chain)
        call drive_now(chain)
        do i = 1, chain%n
            call state_now(chain, i, chain%x(i), chain%v(i))
        end do
        call move_tangent_epoch(chain)
        chain%y = chain%x - chain%drive_x
        chain%vy = chain%v - chain%drive_v
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
        chain%epoch = 0
        chain%frame_s = -huge(1.0_wp)
        chain%drive_s = -huge(1.0_wp)
        call frame_now(chain)
        call drive_now(chain)
        chain%y = chain%x - chain%drive_x
        chain%vy = chain%v - chain%drive_v
        call queue_shift(chain%queue, chain%flow%period, never)
        chain%cycle = chain%cycle + 1
        chain%last_event = chain%last_event - chain%flow%period
    end subroutine chain_new_cycle

    !> The propagator from the epoch to the current time (and its inverse), once per event time.
    pure subroutine frame_now(chain)
        type(chain_t), intent(inout) :: chain
        real(wp) :: tau
        integer :: i

        if (chain%frame_s == chain%s) return
        call rows_back_to_epoch(chain)
        chain%frame_s = chain%s
        chain%instant = chain%instant + 1
        tau = chain%s - chain%epoch
        call propagator_pair(chain%flow, tau, chain%m, chain%m_inv)
        if (chain%flow%damping*tau > rebase_after) then
            do i = 1, chain%n
                if (chain%contact(i) /= contact_free) cycle
                call free_part_now(chain, i, chain%y(i), chain%vy(i))
            end do
            call move_tangent_epoch(chain)
            call set_epoch_here(chain)
            chain%synced = .false.
        end if
    end subroutine frame_now

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

        if (chain%drive_s == chain%s) return
        chain%drive_s = chain%s
        chain%drive_sin = sin(chain%flow%omega*chain%s)
        call forced_response_at(chain%flow, chain%drive_sin, cos(chain%flow%omega*chain%s), &
                                chain%drive_x, chain%drive_v)
    end subroutine drive_now

    !> Tangent rows of moving oscillators from the epoch to now (after frame_now); rows already
    !> moved to now at this instant stay. Afterwards every row is in the coordinates of now.
    pure subroutine move_tangent_epoch(chain)
        type(chain_t), intent(inout) :: chain
        integer :: i

        if (chain%n_vectors > 0) then
            do i = 1, chain%n
                if (chain%row_stamp(i) == chain%instant) cycle
                if (chain%contact(i) == contact_free) &
                    call apply_jump(chain, 2*i - 1, chain%m)
            end do
        end if
        chain%n_touched = 0
    end subroutine move_tangent_epoch

    !> The tangent rows of oscillator i in the coordinates of now, for an impact (after
    !> frame_now); they go back to the epoch when the instant ends.
    pure subroutine rows_to_now(chain, i)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: i

        if (chain%row_stamp(i) == chain%instant) return
        call apply_jump(chain, 2*i - 1, chain%m)
        chain%row_stamp(i) = chain%instant
        chain%n_touched = chain%n_touched + 1
        chain%touched(chain%n_touched) = i
    end subroutine rows_to_now

    !> The jump S of an impact now (after frame_now) on the rows of oscillator i (s 2x2) or
    !> of i and i + 1 (s 4x4). The first impact of an instant takes M^-1 S M on rows still in
    !> the coordinates of the epoch: one pass over them instead of three (to now, S, back when
    !> the instant ends), if S is moderate: forming M^-1 S M spreads rounding of size eps |S|
    !> into every entry, while S applied in the coordinates of now keeps it in the direction
    !> S amplifies (a slow impact before a rest has |S| ~ 1/u). Those, and any later impact
    !> of the same instant (a triple contact, a collapse cascade), move their rows to now.
    subroutine jump_rows(chain, i, s)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: i
        real(wp), intent(in) :: s(:, :)
        real(wp), parameter :: moderate_jump = 16
        real(wp) :: in_epoch(4, 4), largest  ! (fixed size: automatic arrays are allocated)
        integer :: last, j, p, ns

        ns = size(s, 1)
        last = i + ns/2 - 1
        if (chain%same_instant == 0 .and. maxval(abs(s)) <= moderate_jump .and. &
            all(chain%row_stamp(i:last) /= chain%instant)) then
            if (ns == 2) then
                call apply_jump(chain, 2*i - 1, conjugated(s, chain%m, chain%m_inv), largest)
            else
                do p = 1, ns, 2
                    do j = 1, ns, 2
                        in_epoch(j:j + 1, p:p + 1) = conjugated(s(j:j + 1, p:p + 1), chain%m, &
                                                                chain%m_inv)
                    end do
                end do
                call apply_jump(chain, 2*i - 1, in_epoch, largest)
            end if
        else
            do j = i, last
                call rows_to_now(chain, j)
            end do
            call apply_jump(chain, 2*i - 1, s, largest)
        end if
        call keep_tangent_finite(chain, largest)
        ! (not while a direction removed by a rest waits for the QR step to find it: a
        ! factorisation here would turn it into a unit vector)
        ! (nor after many strongly inelastic impacts: each shrinks the frame's volume by K**2, and
        ! a frame shrunk by 1e-8 within one interval keeps its smallest directions poorly)
        chain%jumps_volume = chain%jumps_volume + 2*log(max(chain%restitution, tiny(1.0_wp)))
        ! (nor while the frame grows fast: once an entry passes large_growth, its leading
        ! direction outgrows the others by about as much, and their digits go)
        if (chain%orthonormalise_jumps .and. chain%rank_losses == 0 .and. &
            (maxval(abs(s)) > large_jump .or. chain%jumps_volume < small_volume .or. &
             largest > large_growth)) call orthonormalise_tangent(chain)
    end subroutine jump_rows

    !> Re-orthonormalise the frame now, keeping ln |R(j,j)| in tangent_log. Any upper
    !> triangular change of the columns commutes with the rows' own coordinates (epoch or
    !> now), so the frame need not be synced first.
    subroutine orthonormalise_tangent(chain)
        type(chain_t), intent(inout) :: chain
        integer :: info, j

        chain%frame_work = transpose(chain%tangent)
        if (.not. allocated(chain%r_diag)) allocate (chain%r_diag(chain%n_vectors))
        if (size(chain%r_diag) /= chain%n_vectors) then
            deallocate (chain%r_diag)
            allocate (chain%r_diag(chain%n_vectors))
        end if
        call qr_orthonormalise(chain%frame_work, chain%r_diag, chain%qr, info)
        ! a zero diagonal (a direction lost exactly) is left to the QR step to report
        if (info /= 0 .or. any(chain%r_diag == 0)) return
        chain%tangent = transpose(chain%frame_work)
        chain%jumps_volume = 0
        do j = 1, chain%n_vectors
            chain%tangent_log(j) = chain%tangent_log(j) + log(abs(chain%r_diag(j)))
        end do
    end subroutine orthonormalise_tangent

    !> M^-1 B M for 2x2 blocks (written out: a section of s passed to fixed-shape dummies
    !> would be copied into an allocated temporary).
    pure function conjugated(b, m, m_inv) result(c)
        real(wp), intent(in) :: b(:, :), m(2, 2), m_inv(2, 2)
        real(wp) :: c(2, 2), bm(2, 2)
        integer :: j

        do j = 1, 2
            bm(:, j) = b(:, 1)*m(1, j) + b(:, 2)*m(2, j)
        end do
        do j = 1, 2
            c(:, j) = m_inv(:, 1)*bm(1, j) + m_inv(:, 2)*bm(2, j)
        end do
    end function conjugated

    !> At the end of an instant: rows moved to now go back to the epoch (M^-1 of that instant).
    pure subroutine rows_back_to_epoch(chain)
        type(chain_t), intent(inout) :: chain
        integer :: j, i

        do j = 1, chain%n_touched
            i = chain%touched(j)
            call apply_jump(chain, 2*i - 1, chain%m_inv)
        end do
        chain%n_touched = 0
    end subroutine rows_back_to_epoch

    !> Free part (x - xp, v - vp) of moving oscillator i now (after frame_now).
    pure subroutine free_part_now(chain, i, y, vy)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: i
        real(wp), intent(out) :: y, vy

        if (chain%stamp(i) == chain%instant) then
            y = chain%y_now(i)
            vy = chain%vy_now(i)
        else
            y = chain%m(1, 1)*chain%y(i) + chain%m(1, 2)*chain%vy(i)
            vy = chain%m(2, 1)*chain%y(i) + chain%m(2, 2)*chain%vy(i)
        end if
    end subroutine free_part_now

    !> State of oscillator i now (after frame_now and drive_now): moving, or resting in a stack on a wall.
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

    !> Oscillator i moves on from state (x, v) now (after frame_now and drive_now).
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

        chain%y(i) = chain%m_inv(1, 1)*y + chain%m_inv(1, 2)*vy
        chain%vy(i) = chain%m_inv(2, 1)*y + chain%m_inv(2, 2)*vy
        chain%y_now(i) = y
        chain%vy_now(i) = vy
        chain%stamp(i) = chain%instant
        chain%contact(i) = contact_free
        chain%synced = .false.
    end subroutine set_free_part

    !> Acceleration of a free oscillator in state (x, v) now (after `frame_now`).
    pure function acceleration_now(chain, x, v) result(acc)
        type(chain_t), intent(in) :: chain
        real(wp), intent(in) :: x, v
        real(wp) :: acc

        acc = acceleration_at(chain%flow, chain%drive_sin, x, v)
    end function acceleration_now

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
        call frame_now(chain)
        if (moving_l .and. moving_r) then
            ! the drive cancels in a pair gap: the difference of the free parts
            call free_part_now(chain, r, y, vy)
            call free_part_now(chain, l, yl, vyl)
            gap = gap_t(chain%spacing(bond), y - yl, vy - vyl, 0.0_wp)
        else if (moving_r) then
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

    !> Position x of oscillator i resting in a stack on the left (-a(0) - ... - a(i-1)) or the
    !> right wall (a(i) + ... + a(n)).
    pure function rest_position(chain, i, side) result(x)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: i, side
        real(wp) :: x

        if (side == contact_left) then
            x = -sum(chain%spacing(0:i - 1))
        else
            x = sum(chain%spacing(i:chain%n))
        end if
    end function rest_position

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
        real(wp) :: sgn, x, v_minus, v_plus, u, acc_minus, acc_plus, s(2, 2), curvature, u_min
        type(gap_t) :: gap
        logical :: closes, pushed
        integer :: info, resting

        call frame_now(chain)
        call drive_now(chain)
        call state_now(chain, i, x, v_minus)
        sgn = merge(-1.0_wp, 1.0_wp, side == contact_left)
        u = sgn*v_minus
        acc_minus = acceleration_now(chain, x, v_minus)
        ! the gap is a(bond) +- x(i) + const: its curvature is the acceleration, signed
        curvature = -sgn*acc_minus
        call gap_now(chain, bond, gap, closes, resting)
        u_min = resolvable_speed(chain%flow, gap, curvature)
        pushed = pressed(chain, i, side)
        if (pushed .and. u < max(chain%stick_speed, u_min)) then
            chain%contact(i) = side
            chain%synced = .false.
            chain%sticks = chain%sticks + 1
            if (chain%n_vectors > 0) then
                chain%tangent(:, 2*i - 1:2*i) = 0
                chain%rank_losses = chain%rank_losses + 1
            end if
            if (u > 0) then
                chain%impacts = chain%impacts + 1
                chain%site_counts(bond) = chain%site_counts(bond) + 1
            end if
            call event_log_append(log, chain_elapsed(chain, chain%s), bond, max(u, 0.0_wp), &
                                  event_stick)
        else if (u > 0 .and. u < u_min) then
            call touch_event(chain, bond, u, curvature, log)
            return
        else if (u > 0 .and. (bond == 0 .or. bond == chain%n)) then
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
            call count_impact(chain, bond, u, log)
        else if (u > 0) then
            call pair_event(chain, bond, log, err)
            return
        end if
        call schedule_around(chain, i, i, err)
    end subroutine contact_event

    !> A contact closing slower than the resolvable speed u_min of its gap (and not pressed
    !> into it): whether it is an impact at all is decided by rounding, so it is a touch, with
    !> no impulse and no jump of the tangent (the derivative of the map on its no-impact side).
    !> The gap dips below zero by at most u**2 / (2 g'') < its rounding level and opens again;
    !> the bond is looked at again once it is clearly open (4 u_min / g'' later: the gap is then
    !> above 8 times its rounding level and opening at 3 u_min or more).
    subroutine touch_event(chain, bond, u, curvature, log)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        real(wp), intent(in) :: u, curvature
        type(event_log_t), intent(inout) :: log
        type(gap_t) :: gap
        logical :: closes
        integer :: resting
        real(wp) :: wait

        call gap_now(chain, bond, gap, closes, resting)
        wait = 4*resolvable_speed(chain%flow, gap, curvature)/max(abs(curvature), tiny(1.0_wp))
        wait = max(wait, 64*epsilon(1.0_wp)*chain%flow%period)
        chain%action(bond) = action_recheck
        call queue_set(chain%queue, bond, chain%s + min(wait, 0.25_wp*chain%flow%period))
        chain%touches = chain%touches + 1
        call event_log_append(log, chain_elapsed(chain, chain%s), bond, u, event_touch)
    end subroutine touch_event

    !> Impact of oscillators `bond` and `bond`+1 (either may be resting; it then moves).
    subroutine pair_event(chain, bond, log, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        integer :: l, r, info
        real(wp) :: u, k, yl, wl, yr, wr, xp, vp, f_minus(4), f_plus(4), s(4, 4), curvature

        l = bond
        r = bond + 1
        call frame_now(chain)
        ! the impact law is Galilean invariant: it acts on the free parts (x - xp, v - vp)
        ! alone, so two moving oscillators collide without the drive being evaluated
        if (chain%contact(l) == contact_free .and. chain%contact(r) == contact_free) then
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
        if (u > 0 .and. chain%contact(l) == contact_free .and. chain%contact(r) == contact_free) then
            ! the pair gap a + (yr - yl) is a free damped oscillation: g'' = -(yr - yl) - 2 b g'
            curvature = -(yr - yl) - 2*chain%flow%damping*(wr - wl)
            if (u < resolvable_speed(chain%flow, gap_t(chain%spacing(bond), yr - yl, wr - wl, &
                                                       0.0_wp), curvature)) then
                call touch_event(chain, bond, u, curvature, log)
                return
            end if
        end if
        if (u > 0) then
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
            ! the pair just separated: its next impact is far, and usually pre-empted
            call schedule(chain, l - 1, err)
            if (.not. allocated(err)) call schedule_separating(chain, bond, err)
            if (.not. allocated(err)) call schedule(chain, r, err)
            return
        end if
        call schedule_around(chain, l, r, err)
    end subroutine pair_event

    !> Schedule a pair bond that is opening: rather than searching its next impact now, look
    !> again when it could first close at the earliest (chain_gaps' earliest_closing), as long
    !> as that is not soon; a neighbour's impact usually reschedules it before then.
    subroutine schedule_separating(chain, bond, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(error_t), allocatable, intent(out) :: err
        type(gap_t) :: gap
        logical :: closes
        integer :: resting
        real(wp) :: earliest

        call gap_now(chain, bond, gap, closes, resting)
        if (closes .and. resting == 0 .and. gap%beta == 0 .and. gap%vy > 0) then
            earliest = earliest_closing(chain%flow, gap)
            if (earliest > defer_after) then
                chain%action(bond) = action_recheck
                call queue_set(chain%queue, bond, chain%s + earliest)
                return
            end if
        end if
        call schedule(chain, bond, err)
    end subroutine schedule_separating

    !> Count and log an impact of approach speed u on a bond.
    subroutine count_impact(chain, bond, u, log)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        real(wp), intent(in) :: u
        type(event_log_t), intent(inout) :: log

        chain%impacts = chain%impacts + 1
        chain%site_counts(bond) = chain%site_counts(bond) + 1
        call event_log_append(log, chain_elapsed(chain, chain%s), bond, u, event_impact)
    end subroutine count_impact

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
        call frame_now(chain)
        call drive_now(chain)
        call set_moving_state(chain, i, rest_position(chain, i, chain%contact(i)), 0.0_wp)
        chain%releases = chain%releases + 1
        call event_log_append(log, chain_elapsed(chain, chain%s), bond, 0.0_wp, event_release)
        call schedule_around(chain, i, i, err)
    end subroutine release_event

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

    !> Acceleration of oscillator i in state (x, v) now (zero while it rests on a wall).
    pure function field(chain, i, x, v) result(acc)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: i
        real(wp), intent(in) :: x, v
        real(wp) :: acc

        acc = 0
        if (chain%contact(i) == contact_free) acc = acceleration_now(chain, x, v)
    end function field

    !> Replace the tangent rows first, first + 1, ... (one oscillator, s 2x2, or a neighbour
    !> pair, s 4x4) by S times them; `largest` is the largest magnitude written. The frame
    !> is stored transposed, so these rows are adjacent columns of chain%tangent and the
    !> loops run over contiguous memory.
    pure subroutine apply_jump(chain, first, s, largest)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: first
        real(wp), intent(in) :: s(:, :)
        real(wp), intent(out), optional :: largest
        real(wp) :: biggest

        if (size(s, 1) == 2) then
            call jump_two_rows(chain%tangent(:, first:first + 1), s, biggest)
        else
            call jump_four_rows(chain%tangent(:, first:first + 3), s, biggest)
        end if
        if (present(largest)) largest = biggest
    end subroutine apply_jump

    pure subroutine jump_two_rows(t, s, largest)
        real(wp), contiguous, intent(inout) :: t(:, :)
        real(wp), intent(in) :: s(2, 2)
        real(wp), intent(out) :: largest
        real(wp) :: a, b
        integer :: j

        largest = 0
        do j = 1, size(t, 1)
            a = t(j, 1)
            b = t(j, 2)
            t(j, 1) = s(1, 1)*a + s(1, 2)*b
            t(j, 2) = s(2, 1)*a + s(2, 2)*b
            largest = max(largest, abs(t(j, 1)), abs(t(j, 2)))
        end do
    end subroutine jump_two_rows

    pure subroutine jump_four_rows(t, s, largest)
        real(wp), contiguous, intent(inout) :: t(:, :)
        real(wp), intent(in) :: s(4, 4)
        real(wp), intent(out) :: largest
        real(wp) :: a, b, c, d
        integer :: j

        largest = 0
        do j = 1, size(t, 1)
            a = t(j, 1)
            b = t(j, 2)
            c = t(j, 3)
            d = t(j, 4)
            t(j, 1) = s(1, 1)*a + s(1, 2)*b + s(1, 3)*c + s(1, 4)*d
            t(j, 2) = s(2, 1)*a + s(2, 2)*b + s(2, 3)*c + s(2, 4)*d
            t(j, 3) = s(3, 1)*a + s(3, 2)*b + s(3, 3)*c + s(3, 4)*d
            t(j, 4) = s(4, 1)*a + s(4, 2)*b + s(4, 3)*c + s(4, 4)*d
            largest = max(largest, abs(t(j, 1)), abs(t(j, 2)), abs(t(j, 3)), abs(t(j, 4)))
        end do
    end subroutine jump_four_rows

    !> Impacts at nearly zero approach speed (the last steps of an inelastic collapse) have
    !> saltation matrices of size 1/u, and a cascade of them can overflow the frame within one
    !> QR interval. The whole frame is then scaled by a power of two (exact), and the factor is
    !> kept in tangent_scale_bits for the next QR step to add back. The threshold leaves room
    !> for rows checked in the coordinates of now to be moved back to the epoch (|M^-1| up to
    !> about 2**93 before the epoch is moved) and then hit once more.
    pure subroutine keep_tangent_finite(chain, largest)
        type(chain_t), intent(inout) :: chain
        real(wp), intent(in) :: largest  !! of the rows just changed
        integer, parameter :: bits = 512

        if (largest < 2.0_wp**800) return
        chain%tangent = scale(chain%tangent, -bits)
        chain%tangent_scale_bits = chain%tangent_scale_bits + bits
    end subroutine keep_tangent_finite

    !> Does the net force press oscillator i, at rest in a stack on the `side` wall, towards
    !> that wall (now, or from now on)? At rest x = -S (left), so its acceleration is
    !> S + A sin(w t); on the right, x = S and it is A sin(w t) - S.
    pure logical function pressed(chain, i, side)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: i, side
        real(wp) :: depth, push, rate, tol, phase

        phase = chain%flow%omega*chain%s
        depth = abs(rest_position(chain, i, side))
        if (side == contact_left) then
            push = depth + chain%flow%amplitude*sin(phase)
            rate = chain%flow%amplitude*chain%flow%omega*cos(phase)
        else
            push = depth - chain%flow%amplitude*sin(phase)
            rate = -chain%flow%amplitude*chain%flow%omega*cos(phase)
        end if
        tol = 64*epsilon(1.0_wp)*(depth + chain%flow%amplitude)
        pressed = push < -tol .or. (abs(push) <= tol .and. rate <= 0)
    end function pressed

    !> Next time the force on resting oscillator i turns away from its wall (closed form).
    pure function release_time(chain, i) result(s_release)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: i
        real(wp) :: s_release, ratio, target_phase
        integer :: side

        side = chain%contact(i)
        ratio = min(1.0_wp, abs(rest_position(chain, i, side))/chain%flow%amplitude)
        ! left: the force a + A sin(wt) turns positive as sin rises through -ratio; right (the
        ! mirror image, drive shifted by half a period): A sin(wt) - a turns negative as sin
        ! falls through +ratio
        if (side == contact_left) then
            target_phase = -asin(ratio)
        else
            target_phase = 0.5_wp*two_pi - asin(ratio)
        end if
        s_release = chain%s + modulo(target_phase - chain%flow%omega*chain%s, two_pi) &
                    /chain%flow%omega
    end function release_time

    !> Inelastic collapse: a cluster of touching oscillators meets infinitely many impacts in
    !> no time (a crowded chain with small K). Its limit is applied at once: the cluster moves
    !> with its mean velocity, or comes to rest if it is pressed into a wall or a resting stack.
    !> The cluster holds moving oscillators only: a resting one is a fixed side, like a wall
    !> (its velocity and its zero tangent rows stay out of the averages). The tangent rows of
    !> the cluster are averaged like the velocities (no saltation term).
    subroutine collapse_cluster(chain, bond, log, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        integer :: first, last, i, j, m
        real(wp) :: mean, tol, gaps(0:chain%n)
        logical :: against_left, against_right, stopped
        real(wp), allocatable :: rows(:)

        gaps = chain_gaps_now(chain)
        ! touching, to within the rounding of positions built from free part and drive (large
        ! near resonance)
        tol = 1.0e-12_wp + 256*epsilon(1.0_wp)*(maxval(chain%spacing) + maxval(abs(chain%x)) + &
                                                 hypot(chain%flow%p_sin, chain%flow%q_cos))
        first = max(1, bond)
        last = min(chain%n, bond + 1)
        if (chain%contact(first) /= contact_free) first = first + 1
        if (chain%contact(last) /= contact_free) last = last - 1
        if (first > last) then
            ! both sides fixed: nothing moves here
            call schedule(chain, bond, err)
            return
        end if
        do while (first > 1)
            if (gaps(first - 1) > tol .or. chain%contact(first - 1) /= contact_free) exit
            first = first - 1
        end do
        do while (last < chain%n)
            if (gaps(last) > tol .or. chain%contact(last + 1) /= contact_free) exit
            last = last + 1
        end do
        m = last - first + 1
        mean = sum(chain%v(first:last))/m
        against_left = gaps(first - 1) <= tol .and. (first == 1 .and. chain%walls .or. first > 1)
        against_right = gaps(last) <= tol .and. &
                        (last == chain%n .and. chain%walls .or. last < chain%n)
        stopped = (against_left .and. mean < 0) .or. (against_right .and. mean > 0)
        if (stopped) mean = 0
        chain%v(first:last) = mean
        do i = first, last
            if (chain%contact(i) == contact_free) &
                call set_moving_state(chain, i, chain%x(i), chain%v(i))
        end do
        if (chain%n_vectors > 0) then
            if (m > 1 .or. stopped) chain%rank_losses = chain%rank_losses + 1
            allocate (rows(chain%n_vectors))
            rows = 0
            do i = first, last
                rows = rows + chain%tangent(:, 2*i)
            end do
            ! a cluster stopped by a wall has v = 0 whatever the perturbation
            if (stopped) rows = 0
            do i = first, last
                chain%tangent(:, 2*i) = rows/m
            end do
        end if
        call count_impact(chain, bond, 0.0_wp, log)
        do j = first - 1, last
            call schedule(chain, j, err)
            if (allocated(err)) return
        end do
    end subroutine collapse_cluster

    !> Guard against an unbounded number of impacts at one instant.
    subroutine count_instant(chain, time, err)
        type(chain_t), intent(inout) :: chain
        real(wp), intent(in) :: time
        type(error_t), allocatable, intent(out) :: err
        character(len=32) :: buf

        ! impacts closer than the rounding of times within a cycle are simultaneous
        if (time <= chain%last_event + 16*epsilon(1.0_wp)*chain%flow%period) then
            chain%same_instant = chain%same_instant + 1
            if (chain%same_instant > max_same_instant) then
                write (buf, '(es14.6)') chain_elapsed(chain, time)
                call set_error(err, "event loop: more than "//fmt_int(max_same_instant)// &
                               " impacts at t = "//trim(adjustl(buf))//" (inelastic collapse "// &
                               "of a multi-body contact); raise restitution")
            end if
        else
            chain%same_instant = 0
            chain%last_event = time
        end if
    end subroutine count_instant

end module chain_engine
