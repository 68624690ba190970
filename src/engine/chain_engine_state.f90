!> A chain from a model and a state, its complete state back, and what the rest of the library
!> reads of it (docs/model.md sections 2.5 and 10.2): the clock, positions and velocities,
!> contacts and counters. A state saved by chain_snapshot and given back to chain_init goes on
!> bit for bit as if the chain had never stopped: its event schedule, its record of
!> simultaneous impacts, its counters and its tangent frame come back with it.
submodule(chain_engine) chain_engine_state
    use chain_error, only: set_error, fmt_int
    use chain_flow, only: make_flow
    use chain_queue, only: queue_set, queue_top
    use chain_state, only: contact_free
    implicit none

contains

    module procedure check_sizes
        integer :: n

        n = size(state%x)
        if (size(state%v) /= n .or. size(model%spacing) /= n + 1) then
            call set_error(err, "initial state: "//fmt_int(n)//" positions, "// &
                           fmt_int(size(state%v))//" velocities and "// &
                           fmt_int(size(model%spacing))//" spacings do not make a chain "// &
                           "(n, n and n + 1)")
        else if (allocated(state%contact)) then
            if (size(state%contact) /= n) call set_error(err, "initial state: "// &
                fmt_int(size(state%contact))//" contacts for "//fmt_int(n)//" oscillators")
        end if
        if (allocated(err)) return
        if (allocated(state%counts%site_counts)) then
            if (size(state%counts%site_counts) /= n + 1) call set_error(err, &
                "initial state: impact counts of "//fmt_int(size(state%counts%site_counts))// &
                " bonds for "//fmt_int(n + 1))
        end if
        if (allocated(err)) return
        if (state%has_schedule) then
            if (size(state%event_time) /= n + 1 .or. size(state%event_action) /= n + 1) &
                call set_error(err, "initial state: a schedule of "// &
                               fmt_int(size(state%event_time))//" bonds for "//fmt_int(n + 1))
        end if
        if (allocated(err) .or. .not. state%has_tangent) return
        if (size(state%tangent%frame, 2) /= 2*n) &
            call set_error(err, "initial state: a tangent frame of "// &
                           fmt_int(size(state%tangent%frame, 2))//" coordinates for "// &
                           fmt_int(2*n))
    end procedure check_sizes

    module procedure take_state
        integer :: n

        n = size(state%x)
        chain%n = n
        chain%flow = make_flow(model%damping, model%amplitude, model%omega)
        chain%restitution = model%restitution
        chain%impact_volume = 2*log(max(model%restitution, tiny(1.0_wp)))
        chain%stick_speed = model%stick_speed
        chain%walls = model%walls
        allocate (chain%spacing(0:n))
        chain%spacing = model%spacing
        chain%x = state%x
        chain%v = state%v
        chain%cycle = state%cycle
        chain%s = state%time
        allocate (chain%contact(n), chain%action(0:n), chain%counts%site_counts(0:n))
        allocate (chain%free(n))
        allocate (chain%row_stamp(n), chain%touched(n))
        chain%row_stamp = -1
        chain%contact = contact_free
        if (allocated(state%contact)) chain%contact = state%contact
        chain%counts%site_counts = 0
    end procedure take_state

    module procedure restore_schedule
        integer :: j

        do j = 0, chain%n
            chain%action(j) = event_action(j)
            call queue_set(chain%queue, j, event_time(j))
        end do
    end procedure restore_schedule

    module procedure restore_bookkeeping
        chain%start_cycle = state%start_cycle
        chain%start_s = state%start_time
        chain%last_event = state%last_event
        chain%same_instant = state%same_instant
        chain%counts%impacts = state%counts%impacts
        chain%counts%sticks = state%counts%sticks
        chain%counts%releases = state%counts%releases
        chain%counts%touches = state%counts%touches
        ! (:) keeps the engine's bounds 0:n whatever those of the state
        if (allocated(state%counts%site_counts)) &
            chain%counts%site_counts(:) = state%counts%site_counts
        if (.not. state%has_tangent) return
        associate (tangent => state%tangent)
            ! (the state keeps the frame as rows, tangent%frame(k, 2n): the layout of /resume)
            call chain_set_tangent(chain, transpose(tangent%frame), tangent%orthonormalise_jumps)
            chain%tangent_scale_bits = tangent%scale_bits
            chain%tangent_log = tangent%growth_log
            chain%rank_losses = tangent%rank_losses
            chain%jumps_volume = tangent%jumps_volume
        end associate
    end procedure restore_bookkeeping

    module procedure chain_snapshot
        state%cycle = chain%cycle
        state%time = chain%s
        state%x = chain%x
        state%v = chain%v
        state%contact = chain%contact
        state%has_schedule = .true.
        state%event_time = chain%queue%time
        state%event_action = chain%action
        state%start_cycle = chain%start_cycle
        state%start_time = chain%start_s
        state%last_event = chain%last_event
        state%same_instant = chain%same_instant
        state%counts = chain_counts(chain)
        state%has_tangent = allocated(chain%tangent)
        if (.not. state%has_tangent) return
        state%tangent%frame = transpose(chain%tangent)
        state%tangent%scale_bits = chain%tangent_scale_bits
        state%tangent%growth_log = chain%tangent_log
        state%tangent%rank_losses = chain%rank_losses
        state%tangent%jumps_volume = chain%jumps_volume
        state%tangent%orthonormalise_jumps = chain%orthonormalise_jumps
    end procedure chain_snapshot

    module procedure chain_model
        model%n = chain%n
        model%damping = chain%flow%damping
        model%restitution = chain%restitution
        model%amplitude = chain%flow%amplitude
        model%omega = chain%flow%omega
        model%spacing = chain%spacing(0:chain%n)
        model%walls = chain%walls
        model%stick_speed = chain%stick_speed
    end procedure chain_model

    module procedure chain_size
        chain_size = chain%n
    end procedure chain_size

    module procedure chain_cycle
        cycle = chain%cycle
    end procedure chain_cycle

    module procedure chain_time
        s = chain%s
    end procedure chain_time

    module procedure chain_start
        cycle = chain%start_cycle
        s = chain%start_s
    end procedure chain_start

    module procedure chain_period
        period = chain%flow%period
    end procedure chain_period

    module procedure chain_section_time
        s = phase/chain%flow%omega
    end procedure chain_section_time

    module procedure chain_elapsed
        t = real(chain%cycle - chain%start_cycle, wp)*chain%flow%period + (s - chain%start_s)
    end procedure chain_elapsed

    module procedure chain_positions
        x = chain%x
    end procedure chain_positions

    module procedure chain_velocities
        v = chain%v
    end procedure chain_velocities

    module procedure chain_copy_state
        x = chain%x
        v = chain%v
    end procedure chain_copy_state

    module procedure chain_contacts
        contact = chain%contact
    end procedure chain_contacts

    module procedure chain_counts
        counts = chain%counts
    end procedure chain_counts

    module procedure chain_reset_counts
        chain%counts%impacts = 0
        chain%counts%sticks = 0
        chain%counts%releases = 0
        chain%counts%touches = 0
        chain%counts%site_counts = 0
    end procedure chain_reset_counts

    module procedure chain_next_event
        call queue_top(chain%queue, bond, time)
    end procedure chain_next_event

end submodule chain_engine_state
