!> The recorded part of a run, independent of where the records go (docs/model.md sections 6-7):
!> strobe records at the section, the event stream, the Lyapunov spectrum, periods, and the
!> Poincare-map Jacobian. The CLI sends records to an HDF5 file, sweeps and the Python
!> extension keep them in memory; all go through `record_cycles`, so their numbers agree bit for
!> bit.
!> Where the records are taken: chain_section; where they go: chain_record_sink (its sink types
!> come with record_cycles, which takes them); the Jacobian and multipliers: chain_floquet;
!> covariant Lyapunov vectors (the factors kept at every record, the backward pass at the end,
!> docs/model.md section 14): chain_clv.
module chain_record
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int8
    use chain_engine, only: chain_t, chain_init, chain_snapshot, chain_model, &
                            chain_set_tangent, chain_size, chain_cycle, chain_time, &
                            chain_period, chain_copy_state, chain_counts, &
                            chain_reset_counts, chain_vectors, chain_tangent_frame, &
                            chain_qr_step, chain_reorthonormalise, chain_rank_lost
    use chain_state, only: event_counts_t, chain_state_t
    use chain_model, only: model_t
    use chain_event_log, only: event_log_t, event_log_init
    use chain_lyapunov, only: lyapunov_acc_t, lyapunov_start, lyapunov_due, &
                              lyapunov_result_t, lyapunov_result, initial_frame
    use chain_period, only: detect_period
    use chain_section, only: section_target, advance_to_point, advance_cycles
    use chain_floquet, only: floquet_result
    use chain_monitor, only: monitor_t, stage_records, stage_backward
    use chain_clv, only: clv_pass_t, clv_rows_t, clv_result_t, clv_start, clv_forward, &
                         clv_backward_begin, clv_backward_rows, clv_result, clv_close
    use chain_record_sink, only: record_sink_t, memory_sink_t, record_chunk_t, chunk_start, &
                                 chunk_flush, chunk_take_window, window_buffer_start
    implicit none
    private
    public :: record_sink_t, memory_sink_t, record_result_t, record_cycles
    public :: record_spec_t, vector_count
    public :: period_window, record_state_t, set_window

    integer, parameter :: event_flush = 65536
    !> seconds of a cycle after which the next record is held (a stop within the next cycle
    !> then ends the run at once, at that record)
    real(wp), parameter :: slow_cycle = 0.1_wp

    !> What a run records and how (&run and &lyapunov, docs/model.md sections 6-7).
    type :: record_spec_t
        integer(i8) :: transient = 0         !! cycles run before the first record
        integer(i8) :: cycles = 200          !! strobe records
        real(wp) :: phase = 0                !! drive phase of the section, [0, 2 pi)
        logical :: record_events = .true.    !! keep every event
        integer :: max_period = 16           !! longest period looked for
        real(wp) :: period_tol = 1.0e-6_wp   !! relative tolerance of the period rule
        logical :: lyapunov = .false.        !! carry a tangent frame, average its growth
        integer :: vectors = 0               !! exponents (0: all 2n)
        integer :: qr_every = 0              !! cycles per QR step, 0: adaptive
        !> cycles at the end of the transient over which the tangent frame is carried and
        !> re-orthonormalised, but not averaged, so that it has turned towards the leading
        !> directions when averaging starts (at most the transient)
        integer :: align = 100
        logical :: jacobian = .false.        !! the Poincare-map Jacobian at the end
        integer :: jacobian_cycles = 1       !! of this many drive cycles
        !> covariant Lyapunov vectors (docs/model.md section 14): a QR step at every record
        logical :: covariant = .false.
        integer :: clv_transient = 200       !! last records without vectors (convergence)
        integer :: clv_store = 4             !! vectors whose per-oscillator weights are kept
        integer :: clv_save = 1              !! last records with vectors whose vectors are kept
        !> finite-time exponents over windows of this many recorded cycles (0: none;
        !> docs/model.md section 7.10)
        integer :: window = 0
    end type record_spec_t

    !> Where record_cycles stands after a record, beyond the chain itself (which is then at that
    !> record, synced): with both, a stopped run continues bit for bit.
    type :: record_state_t
        integer(i8) :: cycles_done = 0            !! records done
        type(lyapunov_acc_t) :: acc               !! with &lyapunov
        real(wp), allocatable :: xwin(:, :), vwin(:, :) !! (n, window): the last records, a
                                                  !! ring (record j at modulo(j - 1, window) + 1)
    end type record_state_t

    !> The chain at the last record, held after a slow cycle: a stop asked within the next
    !> cycle (a cycle of millions of events) takes the run back there at once, as if asked
    !> there. Beside a slow cycle the copy costs nothing.
    type :: held_record_t
        logical :: on = .false.      !! a record is held: the monitor may cut the next cycle
        type(chain_state_t) :: state
        integer :: events = 0        !! the event log's count at that record
        integer(i8) :: clock = 0     !! system_clock at the last record
        integer(i8) :: slow = 0      !! clock counts of a slow cycle
    end type held_record_t

    type :: record_result_t
        integer(i8) :: cycles_done = 0
        integer(i8) :: cycles_continued = 0      !! records done before (a continued run)
        logical :: complete = .false.
        real(wp) :: collisions_per_cycle = 0
        integer(i8) :: impacts = 0, sticks = 0, releases = 0, touches = 0
        integer(i8), allocatable :: site_counts(:) !! site_counts(n+1): impacts per bond 0..n
        integer, allocatable :: periods(:)         !! periods(n): 0 = aperiodic
        logical :: has_lyapunov = .false.
        type(lyapunov_result_t) :: lyapunov
        integer(i8), allocatable :: running_cycle(:) !! drive cycle of each running estimate
        real(wp), allocatable :: jacobian(:, :)    !! jacobian(2n, 2n) of the Poincare map
        real(wp), allocatable :: multipliers_re(:), multipliers_im(:)
        logical :: has_clv = .false.               !! covariant vectors (a complete run)
        type(clv_result_t) :: clv
    end type record_result_t

contains

    !> Exponents (tangent vectors) a run of n oscillators computes: none without &lyapunov,
    !> else `vectors`, 0 meaning all 2n.
    pure integer function vector_count(spec, n)
        type(record_spec_t), intent(in) :: spec
        integer, intent(in) :: n

        vector_count = 0
        if (spec%lyapunov) vector_count = merge(2*n, spec%vectors, spec%vectors == 0)
    end function vector_count

    !> Transient, then `spec%cycles` recorded cycles sent to `sink`; the chain ends in the final
    !> state. Summary numbers, periods, spectrum and Jacobian come back in `res`.
    !>
    !> With `state` of a stopped run (cycles_done > 0, the chain at that record with its
    !> counters and tangent frame) the run continues after that record instead; `state` comes
    !> back as the run ends, for a later continuation.
    !>
    !> `monitor` is told every transient cycle and every record. Asked to stop at a record, the
    !> run ends there (res%complete = .false.) and can be continued from `state`; asked during
    !> the transient, where nothing is recorded yet, it returns an error saying so.
    !>
    !> With covariant vectors, a QR step comes at every record and its factors go to scratch
    !> files; a complete run then makes the backward pass, whose per-record numbers go to
    !> `sink` (put_clv) and the rest to res%clv. Such a run cannot be continued (its factors
    !> were in scratch files), and a stopped one has no vectors.
    subroutine record_cycles(spec, chain, sink, res, err, monitor, state, hold_after)
        type(record_spec_t), intent(in) :: spec
        type(chain_t), intent(inout) :: chain
        class(record_sink_t), intent(inout) :: sink
        type(record_result_t), intent(out) :: res
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(record_state_t), intent(inout), optional :: state
        !> seconds of a cycle after which the next record is held (default slow_cycle; 0:
        !> every record, which a test of the stop within a cycle needs on any machine)
        real(wp), intent(in), optional :: hold_after
        type(record_state_t) :: st
        type(clv_pass_t) :: clv
        type(record_chunk_t) :: chunk
        type(held_record_t) :: held
        integer(i8) :: j, target_cycle
        real(wp) :: target_s
        integer :: i
        logical :: stop_now, cut

        call start_records(spec, chain, st, clv, err, monitor, state)
        if (allocated(err)) return
        res%cycles_continued = st%cycles_done
        res%cycles_done = st%cycles_done
        call chunk_start(chunk, chain_size(chain), int(max(1_i8, min(spec%cycles - &
                         st%cycles_done, int(2**20/chain_size(chain), i8)))), &
                         st%cycles_done + 1, spec%record_events)
        if (spec%lyapunov .and. spec%window > 0) &
            call window_buffer_start(chunk%windows, st%acc, spec%cycles/spec%window)
        call hold_start(held, present(monitor), hold_after)
        if (held%on) call hold(held, spec, chain, chunk%log)
        do j = st%cycles_done + 1, spec%cycles
            call section_target(chain, spec%transient, spec%phase, j, target_cycle, target_s)
            cut = .false.
            if (held%on) then
                call advance_to_point(chain, target_cycle, target_s, chunk%log, err, monitor, cut)
            else
                call advance_to_point(chain, target_cycle, target_s, chunk%log, err)
            end if
            if (allocated(err)) exit
            if (cut .and. j == 1) then
                call set_error(err, "run stopped during the drive cycle of its first record, "// &
                               "before that record: nothing was recorded")
                exit
            else if (cut) then
                call back_to_held(held, chain, chunk%log, err)
                if (.not. allocated(err)) &
                    call chunk_flush(chunk, spec%cycles, int(j - chunk%first), sink, err)
                exit
            end if
            i = int(j - chunk%first) + 1
            call keep_record(chain, j, chunk, i, st)
            call tangent_at_record(spec, chain, st%acc, clv, j, chunk%cycle(i), err)
            if (allocated(err)) exit
            call chunk_take_window(chunk, st%acc, chunk%cycle(i), sink, err)
            if (allocated(err)) exit
            res%cycles_done = j
            st%cycles_done = j
            stop_now = .false.
            if (present(monitor)) stop_now = .not. monitor%keep_going(stage_records, j, &
                                                                      spec%cycles)
            if (i == size(chunk%cycle) .or. j == spec%cycles .or. &
                chunk%log%count >= event_flush .or. stop_now) then
                call chunk_flush(chunk, spec%cycles, i, sink, err)
                if (allocated(err)) exit
            end if
            if (stop_now) exit
            call hold_if_slow(held, present(monitor), spec, chain, chunk%log)
        end do
        if (allocated(err)) then
            call clv_close(clv)
            return
        end if
        call summarise_run(spec, chain, st, res)
        if (spec%lyapunov .and. spec%covariant .and. res%complete) &
            call covariant_pass(clv, st%acc, sink, res, err, monitor)
        call clv_close(clv)
        if (allocated(err)) return
        if (present(state)) call move_state(st, state)
        ! (a run stopped early computes it when it is complete)
        if (spec%jacobian .and. res%complete) &
            call floquet_result(chain, spec%jacobian_cycles, res%jacobian, &
                                res%multipliers_re, res%multipliers_im, err)
    end subroutine record_cycles

    !> The run's state before its next record: that of the stopped run in `state`, or a fresh
    !> one after the transient; with covariant vectors, their forward pass opened.
    subroutine start_records(spec, chain, st, clv, err, monitor, state)
        type(record_spec_t), intent(in) :: spec
        type(chain_t), intent(inout) :: chain
        type(record_state_t), intent(inout) :: st
        type(clv_pass_t), intent(inout) :: clv
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(record_state_t), intent(inout), optional :: state

        if (present(state)) then
            if (state%cycles_done > 0) call move_state(state, st)
        end if
        if (st%cycles_done == 0) then
            call begin_records(spec, chain, st, err, monitor)
            if (allocated(err)) return
        else if (spec%lyapunov .and. spec%covariant) then
            call set_error(err, "&lyapunov: a run with covariant = .true. stopped early "// &
                           "cannot be continued (the factors of its records were in scratch "// &
                           "files); run it again from the start")
            return
        end if
        if (spec%lyapunov .and. spec%covariant) then
            call clv_start(clv, chain_size(chain), chain_vectors(chain), spec%cycles, &
                           spec%clv_transient, min(spec%clv_store, chain_vectors(chain)), &
                           spec%clv_save, err)
            if (allocated(err)) call clv_close(clv)
        end if
    end subroutine start_records

    !> Record j, the chain's state now, into column i of the chunk and the period ring.
    subroutine keep_record(chain, j, chunk, i, st)
        type(chain_t), intent(in) :: chain
        integer(i8), intent(in) :: j
        type(record_chunk_t), intent(inout) :: chunk
        integer, intent(in) :: i
        type(record_state_t), intent(inout) :: st
        integer :: w

        call chain_copy_state(chain, chunk%x(:, i), chunk%v(:, i))
        chunk%cycle(i) = chain_cycle(chain)
        w = int(modulo(j - 1, int(size(st%xwin, 2), i8))) + 1
        st%xwin(:, w) = chunk%x(:, i)
        st%vwin(:, w) = chunk%v(:, i)
    end subroutine keep_record

    !> The tangent frame's step at record j (drive cycle `cycle`), if one is due: every record
    !> with covariant vectors, else when the accumulator's schedule says.
    subroutine tangent_at_record(spec, chain, acc, clv, j, cycle, err)
        type(record_spec_t), intent(in) :: spec
        type(chain_t), intent(inout) :: chain
        type(lyapunov_acc_t), intent(inout) :: acc
        type(clv_pass_t), intent(inout) :: clv
        integer(i8), intent(in) :: j, cycle
        type(error_t), allocatable, intent(out) :: err

        if (spec%lyapunov .and. spec%covariant) then
            call covariant_step(chain, acc, clv, j, cycle, err)
        else if (spec%lyapunov) then
            ! (adaptive steps also come at the first section after a rest or a collapse:
            ! the step looks for the lost directions, as every cycle did)
            if (lyapunov_due(acc, j, j == spec%cycles) .or. &
                (spec%qr_every == 0 .and. chain_rank_lost(chain))) &
                call chain_qr_step(chain, acc, int(j - acc%cycles), err)
        end if
    end subroutine tangent_at_record

    !> Hold records from now on after a slow cycle (`slow` seconds, default slow_cycle) when
    !> a monitor can stop the run; the first from the start.
    subroutine hold_start(held, monitored, slow)
        type(held_record_t), intent(out) :: held
        logical, intent(in) :: monitored
        real(wp), intent(in), optional :: slow
        integer(i8) :: rate

        call system_clock(held%clock, rate)
        held%slow = int(slow_cycle*rate, i8)
        if (present(slow)) held%slow = int(slow*rate, i8)
        held%on = monitored
    end subroutine hold_start

    !> The chain now, at a record, to go back to when a stop comes within the next cycle.
    subroutine hold(held, spec, chain, log)
        type(held_record_t), intent(inout) :: held
        type(record_spec_t), intent(in) :: spec
        type(chain_t), intent(in) :: chain
        type(event_log_t), intent(in) :: log

        held%state = chain_snapshot(chain)
        held%state%has_tangent = spec%lyapunov
        held%events = log%count
    end subroutine hold

    !> Hold this record if the cycle before it was slow (and a monitor can stop the run).
    subroutine hold_if_slow(held, monitored, spec, chain, log)
        type(held_record_t), intent(inout) :: held
        logical, intent(in) :: monitored
        type(record_spec_t), intent(in) :: spec
        type(chain_t), intent(in) :: chain
        type(event_log_t), intent(in) :: log
        integer(i8) :: now

        call system_clock(now)
        held%on = monitored .and. now - held%clock >= held%slow
        held%clock = now
        if (held%on) call hold(held, spec, chain, log)
    end subroutine hold_if_slow

    !> The chain and the event log back at the held record.
    subroutine back_to_held(held, chain, log, err)
        type(held_record_t), intent(in) :: held
        type(chain_t), intent(inout) :: chain
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        type(model_t) :: model

        model = chain_model(chain)
        call chain_init(chain, model, held%state, err)
        if (allocated(err)) return
        log%count = held%events
    end subroutine back_to_held

    !> A fresh run up to its first record: the transient, counters from zero, an empty
    !> Lyapunov accumulator and period window.
    subroutine begin_records(spec, chain, st, err, monitor)
        type(record_spec_t), intent(in) :: spec
        type(chain_t), intent(inout) :: chain
        type(record_state_t), intent(inout) :: st
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(event_log_t) :: log
        integer :: nwin

        call transient_part(spec, chain, log, err, monitor)
        if (allocated(err)) return
        call chain_reset_counts(chain)
        ! (covariant vectors: a QR step at every record)
        if (spec%lyapunov) call lyapunov_start(st%acc, chain_vectors(chain), spec%cycles, &
                                              merge(1, spec%qr_every, spec%covariant), &
                                              spec%window)
        nwin = int(min(spec%cycles, int(period_window(spec%max_period), i8)))
        allocate (st%xwin(chain_size(chain), nwin), st%vwin(chain_size(chain), nwin))
    end subroutine begin_records

    !> The numbers of a run that has recorded res%cycles_done records: counters, collisions per
    !> cycle, periods of the last records, and the Lyapunov spectrum.
    subroutine summarise_run(spec, chain, st, res)
        type(record_spec_t), intent(in) :: spec
        type(chain_t), intent(in) :: chain
        type(record_state_t), intent(in) :: st
        type(record_result_t), intent(inout) :: res
        type(event_counts_t) :: counts
        real(wp) :: target_s
        integer :: i, nwin

        res%complete = res%cycles_done == spec%cycles
        counts = chain_counts(chain)
        res%impacts = counts%impacts
        res%sticks = counts%sticks
        res%releases = counts%releases
        res%touches = counts%touches
        res%site_counts = counts%site_counts
        res%collisions_per_cycle = real(counts%impacts, wp)/max(1_i8, res%cycles_done)
        nwin = int(min(res%cycles_done, int(size(st%xwin, 2), i8)))
        allocate (res%periods(chain_size(chain)))
        res%periods = 0
        if (nwin > 0) then
            do i = 1, chain_size(chain)
                res%periods(i) = detect_period(in_order(st%xwin(i, :), res%cycles_done, nwin), &
                                               in_order(st%vwin(i, :), res%cycles_done, nwin), &
                                               spec%max_period, spec%period_tol)
            end do
        end if
        if (spec%lyapunov .and. st%acc%steps > 0) then
            res%has_lyapunov = .true.
            res%lyapunov = lyapunov_result(st%acc, chain_period(chain))
            allocate (res%running_cycle(size(res%lyapunov%running_cycles)))
            do i = 1, size(res%running_cycle)
                call section_target(chain, spec%transient, spec%phase, &
                                    res%lyapunov%running_cycles(i), &
                                    res%running_cycle(i), target_s)
            end do
        end if
    end subroutine summarise_run

    !> The transient: the chain runs to the first record. With exponents, the tangent frame
    !> starts `align` whole cycles before its end, at the end of a cycle (where the state is
    !> synced anyway: the run's own numbers do not depend on whether exponents are
    !> computed), or at the end of the transient.
    subroutine transient_part(spec, chain, log, err, monitor)
        type(record_spec_t), intent(in) :: spec
        type(chain_t), intent(inout) :: chain
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        integer(i8) :: target_cycle, align_start
        real(wp) :: target_s
        logical :: stopped

        call event_log_init(log, .false., 0)
        call section_target(chain, spec%transient, spec%phase, 0_i8, target_cycle, target_s)
        align_start = target_cycle - min(spec%transient, int(spec%align, i8))
        stopped = .false.
        ! (a fresh start at t = 0 is the start of a cycle too)
        if (spec%lyapunov .and. (align_start > chain_cycle(chain) .or. &
                                (align_start == chain_cycle(chain) .and. &
                                 chain_time(chain) == 0))) then
            call advance_cycles(chain, align_start, log, err, monitor=monitor, stopped=stopped, &
                                monitor_total=target_cycle)
            if (stopped) call say_stopped(target_cycle)
            if (allocated(err)) return
            call start_tangent(chain, spec, err)
            if (allocated(err)) return
            call advance_cycles(chain, target_cycle, log, err, spec%qr_every, monitor, stopped)
            if (stopped) call say_stopped(target_cycle)
            if (allocated(err)) return
            call advance_to_point(chain, target_cycle, target_s, log, err, monitor, stopped)
            if (stopped) call say_stopped(target_cycle)
            if (.not. allocated(err)) call chain_reorthonormalise(chain, err)
        else
            ! whole cycles first, so that the monitor is told at each (the same steps as
            ! advance_to_point alone takes)
            call advance_cycles(chain, target_cycle, log, err, monitor=monitor, stopped=stopped)
            if (stopped) call say_stopped(target_cycle)
            if (allocated(err)) return
            call advance_to_point(chain, target_cycle, target_s, log, err, monitor, stopped)
            if (stopped) call say_stopped(target_cycle)
            if (.not. allocated(err) .and. spec%lyapunov) call start_tangent(chain, spec, err)
        end if

    contains

        !> A stop asked by the monitor is an error here: there is no record to keep.
        subroutine say_stopped(last_cycle)
            integer(i8), intent(in) :: last_cycle

            call set_error(err, "run stopped during the transient, at drive cycle "// &
                           fmt_int8(chain_cycle(chain))//" of "//fmt_int8(last_cycle)// &
                           ", before the first record: nothing was recorded")
        end subroutine say_stopped

    end subroutine transient_part

    !> Carry a tangent frame from now: &lyapunov vectors generic orthonormal vectors, or for
    !> the full spectrum the unit vectors (docs/model.md section 7.1), unless covariant vectors
    !> or finite-time exponents need the columns in the order of the exponents.
    subroutine start_tangent(chain, spec, err)
        type(chain_t), intent(inout) :: chain
        type(record_spec_t), intent(in) :: spec
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: frame(:, :)
        integer :: info

        call initial_frame(2*chain_size(chain), vector_count(spec, chain_size(chain)), frame, &
                           info, unit=.not. spec%covariant .and. spec%window == 0)
        if (info /= 0) then
            call set_error(err, "lyapunov: cannot build the initial tangent frame")
            return
        end if
        call chain_set_tangent(chain, frame, orthonormalise_jumps=.true., &
                               keep_r_factors=spec%covariant)
    end subroutine start_tangent

    !> The QR step of record j of a run with covariant vectors (docs/model.md section 14.2):
    !> the R of the map from the last record's frame and the new frame go to the forward pass.
    subroutine covariant_step(chain, acc, clv, j, cycle, err)
        type(chain_t), intent(inout) :: chain
        type(lyapunov_acc_t), intent(inout) :: acc
        type(clv_pass_t), intent(inout) :: clv
        integer(i8), intent(in) :: j, cycle
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: r_factor(:, :), r_log(:)
        integer :: k, collapsed

        k = chain_vectors(chain)
        allocate (r_factor(k, k), r_log(k))
        collapsed = acc%collapsed
        call chain_qr_step(chain, acc, 1, err, r_factor, r_log)
        if (allocated(err)) return
        if (acc%collapsed > collapsed) then
            call set_error(err, "&lyapunov: covariant vectors need an invertible tangent "// &
                           "map, but at record "//fmt_int8(j)//" a rest or a collapse "// &
                           "removed a direction (docs/model.md section 7.8); run this chain "// &
                           "with covariant = .false.")
            return
        end if
        call clv_forward(clv, j, cycle, r_factor, r_log, chain_tangent_frame(chain), err)
    end subroutine covariant_step

    !> The backward pass of a complete run with covariant vectors: per-record numbers to the
    !> sink, block by block, the rest to res%clv. The unstable subspace is spanned by as many
    !> leading vectors as the run's QR exponents have positive ones. `monitor` is told the
    !> records done after each block, and may stop the pass (an error: nothing to keep).
    subroutine covariant_pass(clv, acc, sink, res, err, monitor)
        type(clv_pass_t), intent(inout) :: clv
        type(lyapunov_acc_t), intent(in) :: acc
        class(record_sink_t), intent(inout) :: sink
        type(record_result_t), intent(inout) :: res
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(clv_rows_t) :: rows

        call clv_backward_begin(clv, count(acc%total > 0), err)
        if (allocated(err)) return
        do
            call clv_backward_rows(clv, rows, err)
            if (allocated(err)) return
            if (rows%count == 0) exit
            call sink%put_clv(rows, err)
            if (allocated(err)) return
            if (.not. present(monitor)) cycle
            ! (the records are done from the last back to the first)
            if (.not. monitor%keep_going(stage_backward, rows%total - rows%first + 1, &
                                         rows%total)) then
                call set_error(err, "run stopped during the backward pass of the covariant "// &
                               "vectors, after all its records: nothing was written (such a "// &
                               "run cannot be continued); run it again from the start")
                return
            end if
        end do
        res%has_clv = .true.
        res%clv = clv_result(clv)
    end subroutine covariant_pass

    !> Hand a run state over (the windows moved, the accumulator, of bounded size, copied).
    subroutine move_state(from, to)
        type(record_state_t), intent(inout) :: from, to

        to%cycles_done = from%cycles_done
        call move_alloc(from%xwin, to%xwin)
        call move_alloc(from%vwin, to%vwin)
        to%acc = from%acc
    end subroutine move_state

    !> The period-detection ring of `state` from the last records before a continuation:
    !> x(:, i), v(:, i) are records cycles_done - size(x, 2) + i (the ring keeps the last
    !> window of them, as record_cycles would have).
    subroutine set_window(spec, state, x, v)
        type(record_spec_t), intent(in) :: spec
        type(record_state_t), intent(inout) :: state
        real(wp), intent(in) :: x(:, :), v(:, :)
        integer(i8) :: j
        integer :: nwin, w, i

        nwin = int(min(spec%cycles, int(period_window(spec%max_period), i8)))
        if (allocated(state%xwin)) deallocate (state%xwin, state%vwin)
        allocate (state%xwin(size(x, 1), nwin), state%vwin(size(x, 1), nwin))
        state%xwin = 0
        state%vwin = 0
        do i = max(1, size(x, 2) - nwin + 1), size(x, 2)
            j = state%cycles_done - size(x, 2) + i
            w = int(modulo(j - 1, int(nwin, i8))) + 1
            state%xwin(:, w) = x(:, i)
            state%vwin(:, w) = v(:, i)
        end do
    end subroutine set_window

    !> Records kept in memory for period detection: enough to see every period up to
    !> max_period repeat several times, and no more (memory is n x window x 16 bytes).
    pure integer function period_window(max_period)
        integer, intent(in) :: max_period

        period_window = 4*max_period + 16
    end function period_window

    !> The last `nwin` values of a ring buffer in time order.
    pure function in_order(ring, done, nwin) result(series)
        real(wp), intent(in) :: ring(:)
        integer(i8), intent(in) :: done
        integer, intent(in) :: nwin
        real(wp) :: series(nwin)
        integer :: j, w

        do j = 1, nwin
            w = int(modulo(done - nwin + j - 1, int(size(ring), i8))) + 1
            series(j) = ring(w)
        end do
    end function in_order

end module chain_record
