!> One run from a configuration to an HDF5 file: the initial state (rest, seeded random,
!> explicit, or the final state of an earlier run), the records of `chain_record` streamed to
!> disk, then the final state, statistics, periods, spectrum and Floquet multipliers.
!> The library never prints: progress goes to an optional monitor (chain_monitor), which may
!> also ask the run to stop (at a record, the file is then kept, marked complete = 0, with
!> /resume; during the transient nothing is written).
!>
!> A run whose output file is such a stopped run of the same input text continues it into the
!> same file, bit for bit as if it had never stopped: the engine from /final, the rest of
!> record_cycles's state from /resume, /stats and the last strobe records (`continue_chain`,
!> `write_resume`: the one pair that saves and restores it).
!> Implements docs/model.md section 10.2 (initial conditions); records as in sections 6-7.
module chain_sim
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error
    use chain_engine, only: chain_t, chain_init, chain_snapshot, chain_model, chain_positions, &
                            chain_velocities, chain_contacts, chain_cycle, chain_time, &
                            chain_period
    use chain_state, only: chain_state_t, moving_state
    use chain_event_log, only: event_log_t
    use chain_config, only: config_t, config_summary, check_size
    use chain_input_values, only: real_input
    use chain_model, only: model_t, model_walls
    use chain_lyapunov, only: lyapunov_pack, lyapunov_unpack
    use chain_record, only: record_sink_t, record_result_t, record_cycles, record_state_t, &
                            set_window, period_window
    use chain_clv, only: clv_rows_t
    use chain_monitor, only: monitor_t, stage_records, checkpoint_every
    use chain_section, only: chain_at_section
    use chain_output, only: output_t, output_check, output_begin, output_header, &
                            output_strobe_write, output_events_append, output_final, &
                            output_stats, output_periods, output_lyapunov, output_jacobian, &
                            output_end, output_abort, output_clv_rows, output_clv, &
                            read_final_state, output_truncate_strobe, resume_data_t, &
                            output_windows_write, output_truncate_windows, &
                            output_resume, read_resume, output_inspect, output_continue, &
                            output_checkpoint, &
                            file_absent, file_continuable, file_other_input
    implicit none
    private
    public :: simulate_to_file, check_run, check_run_start, initial_state, start_chain
    public :: checkpoint_cost_share
    public :: write_run_header
    public :: chain_on_section, restart_chain, continuation_start, uniform

    !> Sends records to the HDF5 file as they come.
    type, extends(record_sink_t) :: file_sink_t
        type(output_t) :: out
        integer :: window = 0    !! cycles per finite-time window
    contains
        procedure :: put_strobe => file_put_strobe
        procedure :: put_events => file_put_events
        procedure :: put_clv => file_put_clv
        procedure :: put_windows => file_put_windows
    end type file_sink_t

    !> A checkpoint of a run costs at most 1/checkpoint_cost_share of its time: the interval
    !> between checkpoints grows to that many times the last one's cost (from the stop to the
    !> next record: closing the file, a copy of it to go on in, reading the state back).
    integer, parameter :: checkpoint_cost_share = 50

    !> The caller's monitor, and a stop at a record whenever a checkpoint is due (`asked`
    !> then says the stop was this monitor's: simulate_to_file saves and goes on).
    type, extends(monitor_t) :: checkpoint_monitor_t
        class(monitor_t), pointer :: outer => null()
        integer(i8) :: every = huge(1_i8) !! system_clock counts between checkpoints (at least)
        integer(i8) :: due = huge(1_i8)   !! of the next checkpoint (huge: none)
        integer(i8) :: asked_at = -1      !! of the last stop asked for one (-1: none since)
        logical :: asked = .false.
    contains
        procedure :: keep_going => checkpoint_keep_going
    end type checkpoint_monitor_t

contains

    !> The caller's answer; at a record with a checkpoint due, a stop (asked). The first
    !> record after a checkpoint sets the next one's time from what that one cost.
    logical function checkpoint_keep_going(monitor, stage, done, total) result(keep_going)
        class(checkpoint_monitor_t), intent(inout) :: monitor
        integer, intent(in) :: stage
        integer(i8), intent(in) :: done, total
        integer(i8) :: now

        keep_going = .true.
        if (associated(monitor%outer)) keep_going = monitor%outer%keep_going(stage, done, total)
        if (.not. keep_going .or. stage /= stage_records .or. &
            monitor%due == huge(1_i8)) return
        call system_clock(now)
        if (monitor%asked_at >= 0) then
            monitor%due = now + max(monitor%every, checkpoint_cost_share*(now - monitor%asked_at))
            monitor%asked_at = -1
        end if
        monitor%asked = now >= monitor%due .and. done < total
        if (monitor%asked) monitor%asked_at = now
        keep_going = .not. monitor%asked
    end function checkpoint_keep_going

    !> The initial state of a configuration (rest, seeded random, explicit, or an earlier run),
    !> with &initial kick added to oscillator 1's velocity (but to an earlier run's).
    subroutine initial_state(cfg, state, err)
        type(config_t), intent(in) :: cfg
        type(chain_state_t), intent(out) :: state
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: x(:), v(:)
        real(wp) :: kick
        integer(i8) :: seed
        integer :: i

        allocate (x(cfg%model%n), v(cfg%model%n))
        x = 0
        v = 0
        select case (cfg%initial_kind)
        case ('random')
            seed = seed_state(cfg%seed)
            do i = 1, cfg%model%n
                x(i) = cfg%x_amp*(2*uniform(seed) - 1)
                v(i) = cfg%v_amp*(2*uniform(seed) - 1)
            end do
        case ('explicit')
            x = cfg%x0
            if (size(cfg%v0) == cfg%model%n) v = cfg%v0
        case ('file')
            call file_state(cfg, state, err)
            return
        end select
        ! an impulse at the left end, the classic way to send a wave down the chain (none:
        ! v untouched, even a -0.0 of a random start)
        kick = real_input(cfg%inputs, 'initial', 'kick')
        if (kick /= 0) v(1) = v(1) + kick
        state = moving_state(x, v, 0_i8, 0.0_wp)
    end subroutine initial_state

    !> The final state of the run in cfg%initial_file. Its event schedule belongs to the
    !> file's model: with other parameters (a continuation step of a sweep) every bond is
    !> searched again.
    subroutine file_state(cfg, state, err)
        type(config_t), intent(in) :: cfg
        type(chain_state_t), intent(out) :: state
        type(error_t), allocatable, intent(out) :: err
        logical :: same_model

        call read_final_chain_state(cfg%initial_file, cfg, state, same_model, err)
        if (allocated(err) .or. same_model) return
        state%has_schedule = .false.
        deallocate (state%event_time, state%event_action)
    end subroutine file_state

    !> The final state (/final) of the run in the file at `path`, with its event schedule;
    !> `same_model`: that run had the model of cfg.
    subroutine read_final_chain_state(path, cfg, state, same_model, err)
        character(len=*), intent(in) :: path
        type(config_t), intent(in) :: cfg
        type(chain_state_t), intent(out) :: state
        logical, intent(out) :: same_model
        type(error_t), allocatable, intent(out) :: err
        type(model_t) :: file_model

        same_model = .false.
        call read_final_state(path, cfg%model%n, state, file_model, err)
        if (allocated(err)) return
        same_model = file_model%damping == cfg%model%damping .and. &
                     file_model%restitution == cfg%model%restitution .and. &
                     file_model%amplitude == cfg%model%amplitude .and. &
                     file_model%omega == cfg%model%omega .and. &
                     all(file_model%spacing == cfg%model%spacing) .and. &
                     (file_model%walls .eqv. cfg%model%walls)
    end subroutine read_final_chain_state

    !> A chain ready to run from the configuration's initial state.
    subroutine start_chain(cfg, chain, err)
        type(config_t), intent(in) :: cfg
        type(chain_t), intent(out) :: chain
        type(error_t), allocatable, intent(out) :: err
        type(chain_state_t) :: state

        call initial_state(cfg, state, err)
        if (allocated(err)) return
        call chain_init(chain, cfg%model, state, err)
    end subroutine start_chain

    !> A fresh chain in state (x, v) on the section (drive phase cfg%record%phase of cycle 0), every
    !> oscillator moving and every bond scheduled from scratch: where the Poincare-map Jacobian
    !> of an arbitrary state is taken.
    subroutine chain_on_section(cfg, x, v, chain, err)
        type(config_t), intent(in) :: cfg
        real(wp), intent(in) :: x(:), v(:)
        type(chain_t), intent(out) :: chain
        type(error_t), allocatable, intent(out) :: err

        call chain_at_section(cfg%model, cfg%record%phase, x, v, chain, err)
    end subroutine chain_on_section

    !> The chain goes on from where it stands (positions, velocities, rests, cycle and time)
    !> under the model of `cfg`, as a new run: counters from zero, every bond searched afresh
    !> (a continuation step of a sweep, kept in memory).
    subroutine restart_chain(cfg, chain, err)
        type(config_t), intent(in) :: cfg
        type(chain_t), intent(inout) :: chain
        type(error_t), allocatable, intent(out) :: err
        type(chain_state_t) :: state

        state = continuation_start(chain)
        call chain_init(chain, cfg%model, state, err)
    end subroutine restart_chain

    !> Where the next point of a continuation starts: the chain's positions, velocities and
    !> contacts, at its cycle and time; its schedule is searched afresh (other parameters) and
    !> its clock and counters start there.
    function continuation_start(chain) result(state)
        type(chain_t), intent(in) :: chain
        type(chain_state_t) :: state

        state = moving_state(chain_positions(chain), chain_velocities(chain), chain_cycle(chain), &
                             chain_time(chain))
        state%contact = chain_contacts(chain)
    end function continuation_start

    !> Root attributes, /params and /initial of the run described by cfg (for a sweep file: of
    !> its starting configuration).
    subroutine write_run_header(out, cfg, err)
        type(output_t), intent(inout) :: out
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        type(chain_t) :: chain

        call start_chain(cfg, chain, err)
        if (.not. allocated(err)) call header_for(out, cfg, chain, err)
    end subroutine write_run_header

    subroutine header_for(out, cfg, chain, err)
        type(output_t), intent(inout) :: out
        type(config_t), intent(in) :: cfg
        type(chain_t), intent(in) :: chain
        type(error_t), allocatable, intent(out) :: err

        call output_header(out, cfg%input_text, config_summary(cfg), cfg%model%n, &
                           cfg%model%spacing, cfg%model%damping, cfg%model%restitution, &
                           cfg%model%amplitude, cfg%model%omega, model_walls(cfg%model), &
                           chain_period(chain), cfg%record%phase, cfg%record%transient, &
                           cfg%record%cycles, chain_positions(chain), &
                           chain_velocities(chain), err)
    end subroutine header_for

    !> The whole run described by `cfg`, written to cfg%output_file; or, when that file is a
    !> run of the same input stopped early, the rest of it, continued into that file.
    !>
    !> Checkpoints: every `checkpoint_seconds` (default checkpoint_every; longer when a
    !> checkpoint costs more than 1/checkpoint_cost_share of that) the run stops at a record
    !> as if asked, its file is closed under the final name as a run stopped early, and the
    !> run goes on from that file, as a second command would. A kill then loses at most the
    !> records since, and the same command continues from there; the result is the
    !> uninterrupted run's, bit for bit. (Not with covariant vectors: such a run cannot be
    !> continued.)
    subroutine simulate_to_file(cfg, res, err, monitor, checkpoint_seconds)
        type(config_t), intent(in) :: cfg
        type(record_result_t), intent(out) :: res
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional, target :: monitor
        real(wp), intent(in), optional :: checkpoint_seconds
        type(chain_t) :: chain
        type(file_sink_t) :: sink
        type(record_state_t) :: state
        type(checkpoint_monitor_t) :: watch
        integer(i8) :: continued, clock_now, clock_rate
        real(wp) :: every
        integer :: found

        call check_run(cfg, err, found)
        if (allocated(err)) return
        if (found == file_continuable .and. .not. cfg%record%covariant) then
            call continue_chain(cfg, chain, state, err)
            if (allocated(err)) return
            call output_continue(sink%out, cfg%output_file, cfg%model%n, cfg%record%cycles, &
                                 planned_windows(cfg), err)
            if (allocated(err)) return
        else
            call start_chain(cfg, chain, err)
            if (allocated(err)) return
            call output_begin(sink%out, cfg%output_file, cfg%overwrite, err)
            if (allocated(err)) return
            call header_for(sink%out, cfg, chain, err)
            if (allocated(err)) then
                call output_abort(sink%out)
                return
            end if
        end if
        sink%window = cfg%record%window
        if (present(monitor)) watch%outer => monitor
        every = real(checkpoint_every, wp)
        if (present(checkpoint_seconds)) every = checkpoint_seconds
        call system_clock(clock_now, clock_rate)
        watch%every = int(min(max(every, 0.0_wp)*clock_rate, 1.0e18_wp), i8)
        if (.not. cfg%record%covariant) watch%due = clock_now + watch%every
        continued = -1
        do
            call record_part(cfg, chain, sink, state, watch, res, err)
            if (allocated(err)) return
            if (continued < 0) continued = res%cycles_continued
            if (res%complete .or. .not. watch%asked) exit
            ! a checkpoint: the file under the final name gets the run so far, which goes on
            ! from there as a second command would
            call output_checkpoint(sink%out, cfg%record%cycles, planned_windows(cfg), err)
            if (.not. allocated(err)) call continue_chain(cfg, chain, state, err)
            if (allocated(err)) then
                call output_abort(sink%out)
                return
            end if
            watch%asked = .false.
        end do
        call output_end(sink%out, res%complete, err)
        res%cycles_continued = continued

    end subroutine simulate_to_file

    !> Records from where the chain stands until the run ends or is stopped, then the results
    !> (and /resume for a run stopped early, to continue it) into the `.part` file, which is
    !> deleted on an error.
    subroutine record_part(cfg, chain, sink, state, watch, res, err)
        type(config_t), intent(in) :: cfg
        type(chain_t), intent(inout) :: chain
        type(file_sink_t), intent(inout) :: sink
        type(record_state_t), intent(inout) :: state
        type(checkpoint_monitor_t), intent(inout) :: watch
        type(record_result_t), intent(out) :: res
        type(error_t), allocatable, intent(out) :: err

        call record_cycles(cfg%record, chain, sink, res, err, watch, state)
        if (.not. allocated(err)) &
            call write_results(sink%out, chain, res, cfg%record%jacobian_cycles, err)
        if (.not. allocated(err) .and. .not. res%complete) then
            call output_truncate_strobe(sink%out, res%cycles_done, err)
            if (.not. allocated(err) .and. cfg%record%window > 0) &
                call output_truncate_windows(sink%out, state%acc%windows, err)
            if (.not. allocated(err)) call write_resume(sink%out, cfg, chain, state, err)
        end if
        if (allocated(err)) call output_abort(sink%out)
    end subroutine record_part

    !> Every check simulate_to_file makes before it starts, creating nothing (also what
    !> `--check` runs): the sizes, and what the output's name holds (`found`, output_inspect's
    !> answer): a run of the same input stopped early is continued (but not one with covariant
    !> vectors), any other file there is refused unless overwrite; then its directory.
    subroutine check_run(cfg, err, found)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        integer, intent(out), optional :: found
        integer :: holds

        if (present(found)) found = file_absent
        call check_size(cfg, err)
        if (allocated(err)) return
        call output_inspect(cfg%output_file, cfg%input_text, holds)
        if (present(found)) found = holds
        if (holds == file_other_input .and. .not. cfg%overwrite) then
            call set_error(err, "&output: file = '"//cfg%output_file//"' is a run stopped "// &
                           "early from another input (its input_namelist differs), so it "// &
                           "cannot be continued; choose another name, or set overwrite = "// &
                           ".true. to replace it")
        else if (holds == file_continuable .and. cfg%record%covariant .and. &
                 .not. cfg%overwrite) then
            call set_error(err, "&output: file = '"//cfg%output_file//"' is a run with "// &
                           "covariant vectors stopped early, which cannot be continued (the "// &
                           "factors of its records were in scratch files); set overwrite = "// &
                           ".true. to run it again from the start")
        else
            ! a continued run's file exists by design: only its directory is checked
            call output_check(cfg%output_file, cfg%overwrite .or. (holds == file_continuable &
                              .and. .not. cfg%record%covariant), err)
        end if
    end subroutine check_run

    !> check_run, then the chain the run would start from, built and dropped: the initial
    !> state (an overlap, a start file that does not fit) or the stopped run it would continue
    !> (its /final and /resume). Every refusal simulate_to_file can make before it writes.
    subroutine check_run_start(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        type(chain_t) :: chain
        type(record_state_t) :: state
        integer :: found

        call check_run(cfg, err, found)
        if (allocated(err)) return
        if (found == file_continuable .and. .not. cfg%record%covariant) then
            call continue_chain(cfg, chain, state, err)
        else
            call start_chain(cfg, chain, err)
        end if
    end subroutine check_run_start

    !> /resume of a run stopped at a record: what the engine holds beyond /final, the tangent
    !> frame and the Lyapunov accumulator (undone by continue_chain).
    subroutine write_resume(out, cfg, chain, state, err)
        type(output_t), intent(inout) :: out
        type(config_t), intent(in) :: cfg
        type(chain_t), intent(in) :: chain
        type(record_state_t), intent(in) :: state
        type(error_t), allocatable, intent(out) :: err
        type(resume_data_t) :: data
        type(chain_state_t) :: now

        now = chain_snapshot(chain)
        now%has_tangent = cfg%record%lyapunov
        if (cfg%record%lyapunov) call lyapunov_pack(state%acc, data%lyapunov_int, &
                                                    data%lyapunov_real)
        call output_resume(out, now, data, err)
    end subroutine write_resume

    !> The chain and record_cycles's state where the run stopped early in cfg%output_file left
    !> them (written by write_results and write_resume).
    subroutine continue_chain(cfg, chain, state, err)
        type(config_t), intent(in) :: cfg
        type(chain_t), intent(out) :: chain
        type(record_state_t), intent(out) :: state
        type(error_t), allocatable, intent(out) :: err
        type(resume_data_t) :: data
        type(chain_state_t) :: stopped
        integer :: info

        call read_stopped_run(cfg, stopped, data, err)
        if (allocated(err)) return
        call chain_init(chain, cfg%model, stopped, err)
        if (allocated(err)) return
        if (cfg%record%lyapunov) then
            call lyapunov_unpack(data%lyapunov_int, data%lyapunov_real, state%acc, info)
            if (info /= 0) then
                call set_error(err, "&output: cannot continue '"//cfg%output_file//"': "// &
                               "/resume/lyapunov_int and lyapunov_real are not a Lyapunov "// &
                               "accumulator of this version")
                return
            end if
        end if
        state%cycles_done = data%cycles_done
        call set_window(cfg%record, state, data%x_last, data%v_last)
    end subroutine continue_chain

    !> The complete state of the chain where the run in cfg%output_file stopped (/final and
    !> /resume), and the rest of /resume.
    subroutine read_stopped_run(cfg, stopped, data, err)
        type(config_t), intent(in) :: cfg
        type(chain_state_t), intent(out) :: stopped
        type(resume_data_t), intent(out) :: data
        type(error_t), allocatable, intent(out) :: err
        logical :: same_model

        ! (the same input, so the same model: the schedule goes on)
        call read_final_chain_state(cfg%output_file, cfg, stopped, same_model, err)
        if (allocated(err)) then
            err%message = "&output: cannot continue '"//cfg%output_file//"': "//err%message
            return
        end if
        call read_resume(cfg%output_file, cfg%model%n, cfg%record%lyapunov, &
                         int(min(cfg%record%cycles, int(period_window(cfg%record%max_period), &
                             i8))), stopped, data, err)
        if (allocated(err)) return
        if (data%cycles_done >= cfg%record%cycles) then
            call set_error(err, "&output: file = '"//cfg%output_file//"' holds all "// &
                           "its records but is marked complete = 0; set overwrite = .true. "// &
                           "to run it again")
            return
        end if
        if (.not. cfg%record%lyapunov) return
        if (size(stopped%tangent%frame, 2) /= 2*cfg%model%n) &
            call set_error(err, "&output: cannot continue '"//cfg%output_file//"': "// &
                           "/resume/tangent is not a frame of the chain's 2n coordinates")
    end subroutine read_stopped_run

    subroutine write_results(out, chain, res, jacobian_cycles, err)
        type(output_t), intent(inout) :: out
        type(chain_t), intent(in) :: chain
        type(record_result_t), intent(in) :: res
        integer, intent(in) :: jacobian_cycles
        type(error_t), allocatable, intent(out) :: err
        type(chain_state_t) :: final
        type(model_t) :: model

        final = chain_snapshot(chain)
        model = chain_model(chain)
        call output_final(out, final, model%omega, err)
        if (allocated(err)) return
        call output_stats(out, res%collisions_per_cycle, res%impacts, res%sticks, &
                          res%releases, res%touches, res%site_counts, res%cycles_done, err)
        if (allocated(err)) return
        if (res%cycles_done > 0) call output_periods(out, res%periods, err)
        if (allocated(err)) return
        if (res%has_lyapunov) then
            associate (l => res%lyapunov)
                call output_lyapunov(out, l%bits_per_cycle, l%nats_per_time, l%stderr_bits, &
                                     l%stderr_cycles, l%running_bits, res%running_cycle, &
                                     l%ky_dimension, &
                                     l%positive_sum, res%collisions_per_cycle, err)
            end associate
            if (allocated(err)) return
        end if
        if (res%has_clv) then
            associate (c => res%clv)
                call output_clv(out, c%exponents, c%stderr, c%stderr_block, c%vectors, &
                                c%saved_cycle, c%transient, c%unstable, err)
            end associate
            if (allocated(err)) return
        end if
        if (allocated(res%jacobian)) call output_jacobian(out, res%jacobian, &
                                                          res%multipliers_re, &
                                                          res%multipliers_im, &
                                                          jacobian_cycles, err)
    end subroutine write_results

    subroutine file_put_strobe(sink, n_records, first, x, v, cycle, err)
        class(file_sink_t), intent(inout) :: sink
        integer(i8), intent(in) :: n_records, first
        real(wp), intent(in), contiguous :: x(:, :), v(:, :)
        integer(i8), intent(in), contiguous :: cycle(:)
        type(error_t), allocatable, intent(out) :: err

        call output_strobe_write(sink%out, n_records, first, x, v, cycle, err)
    end subroutine file_put_strobe

    subroutine file_put_windows(sink, n_windows, first, exponents, cycle, err)
        class(file_sink_t), intent(inout) :: sink
        integer(i8), intent(in) :: n_windows, first
        real(wp), intent(in), contiguous :: exponents(:, :)
        integer(i8), intent(in), contiguous :: cycle(:)
        type(error_t), allocatable, intent(out) :: err

        call output_windows_write(sink%out, n_windows, first, sink%window, exponents, cycle, err)
    end subroutine file_put_windows

    !> Finite-time windows of the run (&lyapunov window; 0 without).
    pure integer(i8) function planned_windows(cfg)
        type(config_t), intent(in) :: cfg

        planned_windows = 0
        if (cfg%record%lyapunov .and. cfg%record%window > 0) &
            planned_windows = cfg%record%cycles/cfg%record%window
    end function planned_windows

    subroutine file_put_clv(sink, rows, err)
        class(file_sink_t), intent(inout) :: sink
        type(clv_rows_t), intent(in) :: rows
        type(error_t), allocatable, intent(out) :: err

        call output_clv_rows(sink%out, rows%first, rows%total, rows%cycle, rows%ipr, &
                             rows%site_weight, rows%min_angle, err)
    end subroutine file_put_clv

    subroutine file_put_events(sink, log, err)
        class(file_sink_t), intent(inout) :: sink
        type(event_log_t), intent(in) :: log
        type(error_t), allocatable, intent(out) :: err

        call output_events_append(sink%out, log%time(:log%count), log%site(:log%count), &
                                  log%speed(:log%count), log%kind(:log%count), err)
    end subroutine file_put_events

    !> MINSTD generator: portable and reproducible seeded starts.
    pure function seed_state(seed) result(state)
        integer, intent(in) :: seed
        integer(i8) :: state

        state = modulo(int(seed, i8)*7919_i8 + 12345_i8, 2147483646_i8) + 1
    end function seed_state

    function uniform(state) result(u)
        integer(i8), intent(inout) :: state
        real(wp) :: u

        state = modulo(48271_i8*state, 2147483647_i8)
        u = real(state, wp)/2147483647.0_wp
    end function uniform

end module chain_sim
