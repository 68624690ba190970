!> The event-driven chain (MODEL.md sections 1-4): exact flow between impacts, impacts in time
!> order, sticking contacts on the walls, and an optional tangent frame carried alongside.
!>
!> Design for speed: every oscillator keeps its state at its own last-update time (lazy
!> update); every bond keeps its next event in an indexed heap; an impact touches only the
!> two oscillators involved and reschedules only the neighbouring bonds. Times are times within
!> the current drive cycle; `chain_new_cycle` moves the frame on by one period.
!>
!> Chatter and sticking: a wall impact whose rebound speed K*u falls below `stick_speed` while
!> the drive presses the oscillator against the wall ends the (otherwise infinite) chatter
!> sequence: the oscillator rests on the wall (x = -a(0) or a(n), v = 0) until the contact
!> force a(0) + A sin(w t) (left) or a(n) - A sin(w t) (right) changes sign, a time known in
!> closed form. A pair contact always pushes apart (the springs differ by a at contact), so
!> pairs never stick.
!>
!> Simultaneous contacts (triple contacts) are resolved as a sequence of pair impacts in time
!> order, ties by bond index; after each, the neighbouring bonds are re-examined and any that
!> is closed and closing fires at the same instant.
module chain_engine
    use chain_kinds, only: wp, i8, two_pi
    use chain_error, only: error_t, set_error
    use chain_flow, only: flow_t, forced_response, forced_acceleration, propagator
    use chain_gaps, only: gap_t, gap_search_t, next_gap_zero, search_root, search_horizon
    use chain_impact, only: pair_impact, wall_impact, pair_reset_jacobian, &
                            wall_reset_jacobian, saltation_matrix
    use chain_queue, only: queue_t, queue_init, queue_set, queue_top, queue_shift
    use chain_events, only: event_log_t, event_log_append, event_impact, event_stick, &
                            event_release
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
    !> More impacts than this at one instant means inelastic collapse of a multi-body contact.
    integer, parameter :: max_same_instant = 100000

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
        real(wp), allocatable :: x(:), v(:) !! x(n), v(n): state of each oscillator at t(i)
        real(wp), allocatable :: t(:)       !! t(n): last-update time of each oscillator
        integer, allocatable :: contact(:)  !! contact(n): contact_free / left / right
        type(queue_t) :: queue              !! next event time of each bond
        integer, allocatable :: action(:)   !! action(0:n): what that event is
        integer :: n_vectors = 0            !! tangent vectors carried (0: none)
        real(wp), allocatable :: tangent(:, :) !! tangent(n_vectors, 2n): frame, transposed
        integer(i8) :: impacts = 0, sticks = 0, releases = 0
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
        allocate (chain%t(n), chain%contact(n), chain%action(0:n), chain%site_counts(0:n))
        chain%t = s
        chain%contact = contact_free
        if (present(contact)) chain%contact = contact
        chain%site_counts = 0
        gaps = chain_gaps_now(chain)
        do j = 0, n
            if (gaps(j) < 0) then
                write (buf, '(es12.4)') gaps(j)
                call set_error(err, "initial state: the gap of bond "//itoa(j)//" is " &
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

    !> Start carrying a tangent frame (columns of `frame`, shape (2n, k)).
    pure subroutine chain_set_tangent(chain, frame)
        type(chain_t), intent(inout) :: chain
        real(wp), intent(in) :: frame(:, :)

        chain%n_vectors = size(frame, 2)
        chain%tangent = transpose(frame)
    end subroutine chain_set_tangent

    !> Gaps of all bonds at the current time (bringing every oscillator up to date).
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
            chain%s = time
            call count_instant(chain, time, err)
            if (allocated(err)) return
            select case (chain%action(bond))
            case (action_impact)
                if (bond == 0 .or. bond == chain%n) then
                    call wall_event(chain, bond, log, err)
                else
                    call pair_event(chain, bond, log, err)
                end if
            case (action_release)
                call release_event(chain, bond, log, err)
            case default
                call schedule(chain, bond, err)
            end select
            if (allocated(err)) return
        end do
        chain%s = s_target
    end subroutine chain_advance

    !> Bring every oscillator (and its tangent rows) to the current time.
    pure subroutine chain_sync(chain)
        type(chain_t), intent(inout) :: chain
        integer :: i

        do i = 1, chain%n
            call bring(chain, i)
        end do
    end subroutine chain_sync

    !> At the end of a drive cycle (s = T): sync, and restart the in-cycle clock at 0.
    pure subroutine chain_new_cycle(chain)
        type(chain_t), intent(inout) :: chain

        call chain_sync(chain)
        chain%t = 0
        chain%s = 0
        chain%start_s = chain%start_s - chain%flow%period
        call queue_shift(chain%queue, chain%flow%period, never)
        chain%cycle = chain%cycle + 1
        chain%last_event = chain%last_event - chain%flow%period
    end subroutine chain_new_cycle

    !> Move oscillator i (and its tangent rows) from its own time to the current time.
    pure subroutine bring(chain, i)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: i
        real(wp) :: m(2, 2), xp0, vp0, xp1, vp1, y, vy, tau, c1
        integer :: j

        tau = chain%s - chain%t(i)
        if (tau == 0) return
        if (chain%contact(i) == contact_free) then
            m = propagator(chain%flow, tau)
            call forced_response(chain%flow, chain%t(i), xp0, vp0)
            call forced_response(chain%flow, chain%s, xp1, vp1)
            y = chain%x(i) - xp0
            vy = chain%v(i) - vp0
            chain%x(i) = m(1, 1)*y + m(1, 2)*vy + xp1
            chain%v(i) = m(2, 1)*y + m(2, 2)*vy + vp1
            do j = 1, chain%n_vectors
                c1 = chain%tangent(j, 2*i - 1)
                chain%tangent(j, 2*i - 1) = m(1, 1)*c1 + m(1, 2)*chain%tangent(j, 2*i)
                chain%tangent(j, 2*i) = m(2, 1)*c1 + m(2, 2)*chain%tangent(j, 2*i)
            end do
        end if
        chain%t(i) = chain%s
    end subroutine bring

    !> Find and queue the next event of a bond from the current time.
    subroutine schedule(chain, bond, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(error_t), allocatable, intent(out) :: err
        type(gap_t) :: gap
        type(gap_search_t) :: found
        logical :: closes
        integer :: side

        call gap_now(chain, bond, gap, closes, side)
        if (side /= contact_free) then
            chain%action(bond) = action_release
            call queue_set(chain%queue, bond, release_time(chain, side))
            return
        end if
        if (.not. closes) then
            chain%action(bond) = action_none
            call queue_set(chain%queue, bond, never)
            return
        end if
        found = next_gap_zero(chain%flow, gap, chain%s, chain%flow%period)
        if (found%info /= 0) then
            call set_error(err, "impact search: no convergence on bond "//itoa(bond)// &
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

    !> The gap function of a bond as it stands now. `closes` is false when the bond can never
    !> close (free boundary, or constant gap); `side` /= contact_free when the bond is a wall
    !> on which its oscillator rests (its next event is the release).
    subroutine gap_now(chain, bond, gap, closes, side)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(gap_t), intent(out) :: gap
        logical, intent(out) :: closes
        integer, intent(out) :: side
        integer :: n, l, r
        real(wp) :: xp, vp

        n = chain%n
        closes = .true.
        side = contact_free
        call forced_response(chain%flow, chain%s, xp, vp)
        if (bond == 0 .or. bond == n) then
            closes = chain%walls
            if (.not. closes) return
            if (bond == 0) then
                call bring(chain, 1)
                if (chain%contact(1) == contact_left) side = contact_left
                closes = chain%contact(1) /= contact_right
                gap = gap_t(chain%spacing(0), chain%x(1) - xp, chain%v(1) - vp, 1.0_wp)
            else
                call bring(chain, n)
                if (chain%contact(n) == contact_right) side = contact_right
                closes = chain%contact(n) /= contact_left
                gap = gap_t(chain%spacing(n), xp - chain%x(n), vp - chain%v(n), -1.0_wp)
            end if
            return
        end if
        l = bond
        r = bond + 1
        call bring(chain, l)
        call bring(chain, r)
        if (chain%contact(l) == contact_free .and. chain%contact(r) == contact_free) then
            gap = gap_t(chain%spacing(bond), chain%x(r) - chain%x(l), &
                        chain%v(r) - chain%v(l), 0.0_wp)
        else if (chain%contact(l) /= contact_free .and. chain%contact(r) /= contact_free) then
            closes = .false.
        else if (chain%contact(l) /= contact_free) then
            ! l rests on the left wall at x = -a(0)
            gap = gap_t(chain%spacing(bond) + chain%spacing(0), chain%x(r) - xp, &
                        chain%v(r) - vp, 1.0_wp)
        else
            ! r rests on the right wall at x = a(n)
            gap = gap_t(chain%spacing(bond) + chain%spacing(n), xp - chain%x(l), &
                        vp - chain%v(l), -1.0_wp)
        end if
    end subroutine gap_now

    !> Wall impact of oscillator 1 (bond 0) or n (bond n).
    subroutine wall_event(chain, bond, log, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        integer :: i, side, kind, info
        real(wp) :: sgn, v_minus, u, acc_minus, acc_plus, s(2, 2)

        if (bond == 0) then
            i = 1
            side = contact_left
            sgn = -1
        else
            i = chain%n
            side = contact_right
            sgn = 1
        end if
        call bring(chain, i)
        v_minus = chain%v(i)
        u = sgn*v_minus
        if (u > 0) then
            acc_minus = forced_acceleration(chain%flow, chain%s, chain%x(i), v_minus)
            call wall_impact(chain%restitution, chain%v(i))
            acc_plus = forced_acceleration(chain%flow, chain%s, chain%x(i), chain%v(i))
            kind = event_impact
            if (chain%restitution*u < chain%stick_speed .and. &
                pressed_on_wall(chain, side)) then
                kind = event_stick
                chain%contact(i) = side
                chain%x(i) = sgn*chain%spacing(bond)
                chain%v(i) = 0
                chain%sticks = chain%sticks + 1
                if (chain%n_vectors > 0) chain%tangent(:, 2*i - 1:2*i) = 0
            else if (chain%n_vectors > 0) then
                call saltation_matrix(wall_reset_jacobian(chain%restitution), &
                                      [v_minus, acc_minus], [chain%v(i), acc_plus], &
                                      [-sgn, 0.0_wp], s, info)
                call apply_jump(chain, [2*i - 1, 2*i], s)
            end if
            chain%impacts = chain%impacts + 1
            chain%site_counts(bond) = chain%site_counts(bond) + 1
            call event_log_append(log, chain_elapsed(chain, chain%s), bond, u, kind)
        end if
        call schedule_around(chain, i, i, err)
    end subroutine wall_event

    !> Impact of oscillators `bond` and `bond`+1 (either may be resting on a wall).
    subroutine pair_event(chain, bond, log, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        integer :: l, r, info
        real(wp) :: u, f_minus(4), f_plus(4), s(4, 4)

        l = bond
        r = bond + 1
        call bring(chain, l)
        call bring(chain, r)
        u = chain%v(l) - chain%v(r)
        if (u > 0) then
            f_minus = [chain%v(l), field(chain, l), chain%v(r), field(chain, r)]
            chain%contact(l) = contact_free
            chain%contact(r) = contact_free
            call pair_impact(chain%restitution, chain%v(l), chain%v(r))
            f_plus = [chain%v(l), field(chain, l), chain%v(r), field(chain, r)]
            if (chain%n_vectors > 0) then
                call saltation_matrix(pair_reset_jacobian(chain%restitution), f_minus, f_plus, &
                                      [-1.0_wp, 0.0_wp, 1.0_wp, 0.0_wp], s, info)
                call apply_jump(chain, [2*l - 1, 2*l, 2*r - 1, 2*r], s)
            end if
            chain%impacts = chain%impacts + 1
            chain%site_counts(bond) = chain%site_counts(bond) + 1
            call event_log_append(log, chain_elapsed(chain, chain%s), bond, u, event_impact)
        end if
        call schedule_around(chain, l, r, err)
    end subroutine pair_event

    !> A resting oscillator leaves the wall.
    subroutine release_event(chain, bond, log, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: bond
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        integer :: i

        i = merge(1, chain%n, bond == 0)
        call bring(chain, i)
        chain%contact(i) = contact_free
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

    !> Acceleration of oscillator i now (zero while it rests on a wall).
    pure function field(chain, i) result(acc)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: i
        real(wp) :: acc

        acc = 0
        if (chain%contact(i) == contact_free) &
            acc = forced_acceleration(chain%flow, chain%s, chain%x(i), chain%v(i))
    end function field

    !> Replace the tangent rows `rows` by S times them.
    pure subroutine apply_jump(chain, rows, s)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: rows(:)
        real(wp), intent(in) :: s(:, :)

        chain%tangent(:, rows) = matmul(chain%tangent(:, rows), transpose(s))
    end subroutine apply_jump

    !> Does the contact force press an oscillator at rest on this wall (now, or from now on)?
    pure logical function pressed_on_wall(chain, side)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: side
        real(wp) :: a, push, rate, tol, phase

        phase = chain%flow%omega*chain%s
        if (side == contact_left) then
            a = chain%spacing(0)
            push = a + chain%flow%amplitude*sin(phase)
            rate = chain%flow%amplitude*chain%flow%omega*cos(phase)
        else
            a = chain%spacing(chain%n)
            push = a - chain%flow%amplitude*sin(phase)
            rate = -chain%flow%amplitude*chain%flow%omega*cos(phase)
        end if
        tol = 64*epsilon(1.0_wp)*(a + chain%flow%amplitude)
        pressed_on_wall = push < -tol .or. (abs(push) <= tol .and. rate <= 0)
    end function pressed_on_wall

    !> Next time the wall contact force changes sign towards letting go (closed form).
    pure function release_time(chain, side) result(s_release)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: side
        real(wp) :: s_release, ratio, target_phase

        if (side == contact_left) then
            ratio = min(1.0_wp, chain%spacing(0)/chain%flow%amplitude)
            target_phase = -asin(ratio)
        else
            ratio = min(1.0_wp, chain%spacing(chain%n)/chain%flow%amplitude)
            target_phase = asin(ratio) + 0.5_wp*two_pi
        end if
        s_release = chain%s + modulo(target_phase - chain%flow%omega*chain%s, two_pi) &
                    /chain%flow%omega
    end function release_time

    !> Guard against an unbounded number of impacts at one instant.
    subroutine count_instant(chain, time, err)
        type(chain_t), intent(inout) :: chain
        real(wp), intent(in) :: time
        type(error_t), allocatable, intent(out) :: err
        character(len=32) :: buf

        if (time <= chain%last_event) then
            chain%same_instant = chain%same_instant + 1
            if (chain%same_instant > max_same_instant) then
                write (buf, '(es14.6)') chain_elapsed(chain, time)
                call set_error(err, "event loop: more than "//itoa(max_same_instant)// &
                               " impacts at t = "//trim(adjustl(buf))//" (inelastic collapse "// &
                               "of a multi-body contact); raise restitution")
            end if
        else
            chain%same_instant = 0
            chain%last_event = time
        end if
    end subroutine count_instant

    pure function itoa(i) result(str)
        integer, intent(in) :: i
        character(len=:), allocatable :: str
        character(len=16) :: buf

        write (buf, '(i0)') i
        str = trim(buf)
    end function itoa

end module chain_engine
