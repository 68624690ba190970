!> Lyapunov spectra and Poincare-map Jacobians (docs/model.md sections 7, 9): the exact sum rule,
!> the spectrum without impacts, finite differences of the one-cycle map, leading vectors
!> against the full spectrum (and the sum rule on every full
!> spectrum computed here), Floquet multipliers of a period-1 state, and a chaotic and a
!> periodic case of the paper separated by their error bars. Also a run watched by a monitor
!> (chain_monitor): told every transient cycle and record, the same numbers, and its stops.
module test_lyapunov
    use chain_kinds, only: wp, i8
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use chain_error, only: error_t
    use chain_flow, only: flow_t
    use chain_model, only: model_t
    use chain_state, only: event_counts_t, moving_state
    use chain_engine, only: chain_t, chain_init, chain_model, chain_cycle, chain_time, &
                            chain_positions, chain_velocities, chain_counts, chain_reset_counts, &
                            chain_set_tangent, chain_reorthonormalise, chain_tangent_frame, &
                            chain_snapshot
    use chain_event_log, only: event_log_t, event_log_init
    use chain_config, only: config_t, check_size
    use chain_record, only: record_cycles, memory_sink_t, record_result_t, record_state_t
    use chain_section, only: advance_to_point
    use chain_floquet, only: poincare_jacobian, floquet_multipliers
    use chain_lyapunov, only: ky_dimension, lyapunov_acc_t, &
                              lyapunov_start, lyapunov_step, lyapunov_result_t, &
                              lyapunov_result, running_capacity, running_rows, &
                              lyapunov_pack, lyapunov_unpack
    use chain_lapack, only: qr_orthonormalise, qr_orthonormalise_blocks, qr_orthonormalise_piece, &
                            qr_workspace_t
    use test_chains, only: make_chain
    use test_sum_rule, only: check_sum_rule
    use test_chains, only: flow_of
    use chain_monitor, only: monitor_t, stage_transient, stage_records, stage_events
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_lyapunov_tests

    !> Writes down what it is told; asks to stop at (stage, done) = (stop_stage, stop_at).
    type, extends(monitor_t) :: watching_monitor_t
        integer :: stop_stage = 0
        integer(i8) :: stop_at = -1
        integer(i8) :: transient_calls = 0, record_calls = 0
        integer(i8) :: last_done = -1, last_total = -1
        logical :: in_order = .true.   !! stages never go back, counts rise by one
    contains
        procedure :: keep_going => watching_keep_going
    end type watching_monitor_t

    !> Asks to stop at its `stop_at`-th look within a cycle after record `after` (and counts
    !> those looks).
    type, extends(monitor_t) :: cutting_monitor_t
        integer(i8) :: after = 0, records = 0
        integer :: stop_at = 0, looks = 0
    contains
        procedure :: keep_going => cutting_keep_going
    end type cutting_monitor_t

contains

    subroutine run_lyapunov_tests(t)
        type(tally_t), intent(inout) :: t

        call sum_rule(t, 4, 4.15_wp, 0.9_wp)
        call sum_rule(t, 16, 1.7_wp, 1.5_wp)
        call no_impacts(t)
        call finite_differences(t, 2, .true.)
        call finite_differences(t, 4, .true.)
        call finite_differences(t, 16, .true.)
        call finite_differences(t, 4, .false.)
        call finite_differences(t, 16, .false.)
        ! a section inside the drive cycle (the map crosses the end of a cycle)
        call finite_differences(t, 4, .true., 2.0_wp)
        call leading_vectors(t)
        call unit_frame_spectrum(t)
        call unit_frame_continued(t)
        call block_factorisation(t, 9)
        call block_factorisation(t, 40)
        call adaptive_matches_every_cycle(t, 4, 4.15_wp, 0.9_wp, 200_i8, 1000_i8, 0, .true.)
        call adaptive_matches_every_cycle(t, 16, 1.7_wp, 1.5_wp, 200_i8, 1000_i8, 0, .true.)
        call adaptive_matches_every_cycle(t, 16, 1.7_wp, 1.5_wp, 100_i8, 300_i8, 6, .false.)
        call adaptive_matches_every_cycle(t, 16, 1.7_wp, 1.5_wp, 500_i8, 2000_i8, 2, .false.)
        call adaptive_matches_every_cycle(t, 3, 0.2_wp, 1.5_wp, 0_i8, 2000_i8, 0, .true.)
        call adaptive_matches_every_cycle(t, 8, 3.0_wp, 1.9_wp, 500_i8, 2000_i8, 2, .false.)
        call floquet_period_one(t)
        call chaotic_and_periodic(t)
        call kaplan_yorke(t)
        call qr_factors(t)
        call qr_in_threads(t)
        call running_memory_is_bounded(t)
        call running_estimates_decimated(t, 10000, 10000)
        call running_estimates_decimated(t, 10001, 10001)
        call running_estimates_decimated(t, 5000, 1000000)
        call running_estimates_decimated(t, 300, 300)
        call size_check_matches_storage(t)
        call pack_round_trip(t)
        call stderr_at_the_plateau(t)
        call collapsed_has_no_error_bar(t)
        call finite_time_windows(t)
        call monitored_run(t, .false.)
        call monitored_run(t, .true.)
        call stop_within_a_cycle(t)
    end subroutine run_lyapunov_tests

    !> An accumulator packed to plain arrays and unpacked goes on exactly as the original
    !> (a run stopped and continued); arrays of another layout are refused.
    subroutine pack_round_trip(t)
        type(tally_t), intent(inout) :: t
        type(lyapunov_acc_t) :: acc, copy
        type(lyapunov_result_t) :: a, b
        integer(i8), allocatable :: ints(:)
        real(wp), allocatable :: reals(:)
        real(wp), allocatable :: frame_t(:, :)
        integer :: q, info

        call lyapunov_start(acc, 3, 9000_i8, window=100)
        do q = 1, 9000
            if (q == 5000) then
                call lyapunov_pack(acc, ints, reals)
                call lyapunov_unpack(ints, reals, copy, info)
                call check(t, info == 0, 'pack: unpacked')
            end if
            call step(acc, q)
            if (q >= 5000) call step(copy, q)
        end do
        a = lyapunov_result(acc, 1.0_wp)
        b = lyapunov_result(copy, 1.0_wp)
        call check(t, all(a%bits_per_cycle == b%bits_per_cycle) .and. &
                   all(a%stderr_bits == b%stderr_bits) .and. &
                   all(a%stderr_cycles == b%stderr_cycles) .and. &
                   all(acc%window_last == copy%window_last) .and. &
                   acc%windows == copy%windows .and. acc%windows == 90 .and. &
                   all(a%running_bits == b%running_bits) .and. &
                   all(a%running_cycles == b%running_cycles), &
                   'pack: packed, unpacked and continued = never packed, bit for bit')
        ints(1) = ints(1) + 1
        call lyapunov_unpack(ints, reals, copy, info)
        call check(t, info /= 0, 'pack: arrays of another layout are refused')
        call lyapunov_pack(acc, ints, reals)
        call lyapunov_unpack(ints, reals(2:), copy, info)
        call check(t, info /= 0, 'pack: arrays of the wrong size are refused')

    contains

        subroutine step(acc, q)
            type(lyapunov_acc_t), intent(inout) :: acc
            integer, intent(in) :: q

            frame_t = reshape([1.0_wp + modulo(q, 7), 0.3_wp, 0.1_wp, 0.2_wp, 0.5_wp, 0.0_wp, &
                               0.1_wp, 0.2_wp, 1.0_wp/(1 + modulo(q, 5))], [3, 3])
            call lyapunov_step(acc, frame_t, info)
        end subroutine step

    end subroutine pack_round_trip

    !> Growths that repeat for `run` = 256 consecutive steps (each run's value drawn uniformly
    !> from [0.5, 1.5)) have a known standard error of their mean: sigma / sqrt(runs), sigma =
    !> 1 / sqrt(12). The blocking plateau finds it (to 15 %, the scatter of an error estimate
    !> from ~100 independent blocks) at blocks of at least one run, and says so (the naive
    !> error of single steps would be 16 times too small).
    subroutine stderr_at_the_plateau(t)
        type(tally_t), intent(inout) :: t
        integer, parameter :: run = 256, runs = 1024
        type(lyapunov_acc_t) :: acc
        type(lyapunov_result_t) :: res
        real(wp), allocatable :: frame(:, :)
        real(wp) :: g, expected
        integer(i8) :: state
        integer :: q, info
        character(len=80) :: label

        call lyapunov_start(acc, 1, int(run, i8)*runs)
        state = 12345
        g = 0
        allocate (frame(1, 1))
        do q = 0, run*runs - 1
            if (modulo(q, run) == 0) then
                state = modulo(48271_i8*state, 2147483647_i8)
                g = 0.5_wp + real(state, wp)/2147483647.0_wp
            end if
            frame = exp(g)
            call lyapunov_step(acc, frame, info)
        end do
        res = lyapunov_result(acc, 1.0_wp)
        expected = 1/sqrt(12.0_wp)/sqrt(real(runs, wp))/log(2.0_wp)
        write (label, '(a,es9.3,a,es9.3,a,i0,a)') ' (', res%stderr_bits(1), ' against ', &
            expected, ', read at blocks of ', res%stderr_cycles(1), ' cycles)'
        call check(t, abs(res%stderr_bits(1)/expected - 1) < 0.15_wp, &
                   'standard error of a correlated series at the plateau'//trim(label))
        call check(t, res%stderr_cycles(1) >= run, &
                   'the plateau is read at blocks at least as long as the correlation')
    end subroutine stderr_at_the_plateau

    !> A direction that collapses midway (its exponent -infinity) has no error bar: stderr 0
    !> and blocks of one unit (docs/model.md section 7.4), whatever its units held before.
    subroutine collapsed_has_no_error_bar(t)
        type(tally_t), intent(inout) :: t
        type(lyapunov_acc_t) :: acc
        type(lyapunov_result_t) :: res
        real(wp), allocatable :: frame(:, :)
        integer :: q, info
        logical :: ok

        call lyapunov_start(acc, 2, 4096_i8, 1)
        ok = .true.
        do q = 1, 4096
            if (q < 2000) then
                frame = reshape([2.0_wp + modulo(q, 3), 0.0_wp, 0.3_wp, 0.5_wp], [2, 2])
            else if (q == 2000) then
                ! the second column parallel to the first: removed by a singular event
                frame = reshape([2.0_wp, 0.0_wp, 1.0_wp, 0.0_wp], [2, 2])
            else
                frame = reshape([2.0_wp + modulo(q, 3), 0.0_wp], [2, 1])
            end if
            call lyapunov_step(acc, frame, info, singular=q == 2000)
            ok = ok .and. info == 0
        end do
        res = lyapunov_result(acc, 1.0_wp)
        call check(t, ok .and. acc%collapsed == 1 .and. .not. ieee_is_finite( &
                   res%bits_per_cycle(2)), 'collapse midway: the second exponent is -infinity')
        call check(t, res%stderr_bits(2) == 0 .and. res%stderr_cycles(2) == acc%unit .and. &
                   res%stderr_bits(1) > 0, &
                   'collapse midway: no error bar, blocks of one unit')
    end subroutine collapsed_has_no_error_bar

    !> Finite-time exponents over windows of 100 cycles (docs/model.md section 7.10) on fig.
    !> 1c's chain, adaptive QR: the windows' mean is the exponents (to rounding); they equal the
    !> windows of a QR step every cycle (the steps never cross a window); each window ends 100
    !> cycles after the last; a window of the whole run is the exponents; and the scatter of
    !> the windows, sd / sqrt(windows), agrees with the plateau's standard error (to 30 %).
    subroutine finite_time_windows(t)
        type(tally_t), intent(inout) :: t
        integer, parameter :: window = 100, cycles = 6000
        type(chain_t) :: chain, copy, whole
        type(error_t), allocatable :: err
        type(record_result_t) :: adaptive, every, one
        type(memory_sink_t) :: sink_adaptive, sink_every, sink_one
        type(config_t) :: cfg
        real(wp), allocatable :: mean(:), sd(:)
        integer :: nw
        character(len=80) :: label

        call make_chain(chain, 16, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, 0.5_wp, err)
        copy = chain
        whole = chain
        cfg = spectrum_config(16, 500_i8, int(cycles, i8), 4)
        cfg%record%qr_every = 0
        cfg%record%window = window
        sink_adaptive%keep_strobe = .false.
        call record_cycles(cfg%record, chain, sink_adaptive, adaptive, err)
        call check(t, .not. allocated(err), 'finite-time windows: adaptive run')
        if (allocated(err)) return
        nw = cycles/window
        call check(t, size(sink_adaptive%window_cycle) == nw .and. &
                   all(sink_adaptive%window_cycle(2:) - sink_adaptive%window_cycle(:nw - 1) &
                       == window), 'finite-time windows: 60 windows, 100 cycles apart')
        mean = sum(sink_adaptive%window_exponents, dim=2)/nw
        call check_close(t, maxval(abs(mean - adaptive%lyapunov%bits_per_cycle)), 0.0_wp, &
                         'finite-time windows: their mean is the exponents', 1.0e-12_wp)
        cfg%record%qr_every = 1
        sink_every%keep_strobe = .false.
        call record_cycles(cfg%record, copy, sink_every, every, err)
        call check_close(t, maxval(abs(sink_every%window_exponents - &
                                       sink_adaptive%window_exponents)), 0.0_wp, &
                         'finite-time windows: adaptive QR = QR every cycle', 1.0e-10_wp)
        cfg%record%qr_every = 0
        cfg%record%window = cycles
        sink_one%keep_strobe = .false.
        call record_cycles(cfg%record, whole, sink_one, one, err)
        call check_close(t, maxval(abs(sink_one%window_exponents(:, 1) - &
                                       one%lyapunov%bits_per_cycle)), 0.0_wp, &
                         'finite-time windows: one window of the whole run is the exponents', &
                         1.0e-12_wp)
        sd = sqrt(sum((sink_adaptive%window_exponents - spread(mean, 2, nw))**2, dim=2)/ &
                  (nw - 1))/sqrt(real(nw, wp))
        write (label, '(a,es9.3,a,es9.3,a)') ' (', sd(1), ' and ', &
            adaptive%lyapunov%stderr_bits(1), ' bits/cycle)'
        call check(t, all(abs(sd/adaptive%lyapunov%stderr_bits - 1) < 0.3_wp), &
                   'finite-time windows: their scatter is the standard error'//trim(label))
    end subroutine finite_time_windows

    !> The running estimates take the same memory for a run of 10^4 QR steps as for one of
    !> 10^9: the accumulator's buffer is bounded, not sized by the planned steps.
    subroutine running_memory_is_bounded(t)
        type(tally_t), intent(inout) :: t
        type(lyapunov_acc_t) :: short, long

        call lyapunov_start(short, 32, 10000_i8)
        call lyapunov_start(long, 32, 1000000000_i8)
        call check(t, size(long%running) == size(short%running) .and. &
                   size(long%running, 2) <= running_capacity, &
                   'running estimates: the buffer does not grow with the planned steps')
    end subroutine running_memory_is_bounded

    !> `steps` QR steps of a run planned for `planned`, on a 2x2 frame stretched by 2**m(q)
    !> at step q (a known running mean): the kept rows are the multiples of a power-of-two
    !> stride, plus the last step; each equals the exact running mean at its step; the last
    !> equals the final exponents; the row count is what running_rows predicts.
    subroutine running_estimates_decimated(t, steps, planned)
        type(tally_t), intent(inout) :: t
        integer, intent(in) :: steps, planned
        type(lyapunov_acc_t) :: acc
        type(lyapunov_result_t) :: res
        real(wp) :: sums(0:steps)
        real(wp), allocatable :: frame_t(:, :)
        integer :: q, info, stride, rows
        logical :: ok
        character(len=40) :: label

        write (label, '(a,i0,a,i0,a)') ' (', steps, ' of ', planned, ' steps)'
        call lyapunov_start(acc, 2, int(planned, i8))
        sums(0) = 0
        ok = .true.
        allocate (frame_t(2, 2))
        do q = 1, steps
            frame_t = 0
            frame_t(1, 1) = 2.0_wp**(1 + modulo(q, 3))
            frame_t(2, 2) = 0.5_wp
            call lyapunov_step(acc, frame_t, info)
            ok = ok .and. info == 0
            sums(q) = sums(q - 1) + (1 + modulo(q, 3))
        end do
        call check(t, ok, 'running estimates: QR steps'//trim(label))
        res = lyapunov_result(acc, 1.0_wp)
        rows = size(res%running_cycles)
        call check(t, rows == running_rows(int(steps, i8)) .and. &
                   size(res%running_bits, 2) == rows .and. rows <= running_capacity + 1, &
                   'running estimates: running_rows predicts the rows kept'//trim(label))
        stride = 1
        do while (steps/stride > running_capacity)
            stride = 2*stride
        end do
        ok = res%running_cycles(rows) == steps
        do q = 1, rows - 1
            ok = ok .and. res%running_cycles(q) == q*stride
        end do
        if (modulo(steps, stride) == 0) ok = ok .and. res%running_cycles(rows - 1) == steps - stride
        call check(t, ok, 'running estimates: every stride-th step and the last'//trim(label))
        ok = .true.
        do q = 1, rows
            ok = ok .and. abs(res%running_bits(1, q) - sums(res%running_cycles(q)) &
                              /res%running_cycles(q)) <= 1.0e-12_wp
            ok = ok .and. abs(res%running_bits(2, q) + 1) <= 1.0e-12_wp
        end do
        call check(t, ok, 'running estimates: each row is the mean up to its step'//trim(label))
        call check(t, all(res%running_bits(:, rows) == res%bits_per_cycle), &
                   'running estimates: the last row is the final spectrum'//trim(label))
    end subroutine running_estimates_decimated

    !> check_size refuses exactly what would be stored: the strobe records and the kept
    !> running estimates (with their cycles), not one row per QR step.
    subroutine size_check_matches_storage(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg
        type(error_t), allocatable :: err
        real(wp) :: stored_mb
        integer :: k

        cfg = spectrum_config(16, 0_i8, 10000000_i8, 0)
        k = 32
        stored_mb = ((16*16 + 8)*real(cfg%record%cycles, wp) + &
                     (8*k + 8)*real(running_rows(cfg%record%cycles), wp))/1.0e6_wp
        cfg%max_size_mb = stored_mb*(1 + 1.0e-9_wp)
        call check_size(cfg, err)
        call check(t, .not. allocated(err), 'size check: a run that fits is accepted')
        cfg%max_size_mb = stored_mb*(1 - 1.0e-9_wp)
        call check_size(cfg, err)
        call check(t, allocated(err), 'size check: a run just beyond the limit is refused')
    end subroutine size_check_matches_storage

    !> A run watched by a monitor (with exponents: the transient's aligning part is its own
    !> loop) is told every transient cycle and every record, in order, and has the numbers of
    !> the same run unwatched, bit for bit. Asked to stop at a record, it ends there,
    !> incomplete; asked during the transient, it says so in an error.
    subroutine monitored_run(t, exponents)
        type(tally_t), intent(inout) :: t
        logical, intent(in) :: exponents
        type(chain_t) :: plain_chain, chain
        type(config_t) :: cfg
        type(record_result_t) :: plain, res
        type(memory_sink_t) :: plain_sink, sink
        type(watching_monitor_t) :: watch
        type(error_t), allocatable :: err
        character(len=:), allocatable :: label

        label = ' (no exponents)'
        if (exponents) label = ' (exponents)'
        cfg = spectrum_config(4, 150_i8, 40_i8, 0)
        cfg%record%lyapunov = exponents
        call make_chain(plain_chain, 4, 4.15_wp, 0.9_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, &
                        0.5_wp, err)
        call record_cycles(cfg%record, plain_chain, plain_sink, plain, err)
        call make_chain(chain, 4, 4.15_wp, 0.9_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, 0.5_wp, err)
        call record_cycles(cfg%record, chain, sink, res, err, watch)
        call check(t, .not. allocated(err) .and. res%complete, 'a watched run completes'//label)
        if (allocated(err)) return
        call check(t, watch%transient_calls == 150 .and. watch%record_calls == 40 .and. &
                   watch%in_order .and. watch%last_done == 40 .and. watch%last_total == 40, &
                   'the monitor is told every transient cycle and every record'//label)
        call check(t, all(sink%x == plain_sink%x) .and. all(sink%v == plain_sink%v) .and. &
                   all(chain_positions(chain) == chain_positions(plain_chain)), &
                   'a watched run has the records of the unwatched one, bit for bit'//label)
        if (exponents) call check(t, all(res%lyapunov%bits_per_cycle == &
                                          plain%lyapunov%bits_per_cycle), &
                                  'and its exponents, bit for bit')

        watch = watching_monitor_t(stop_stage=stage_records, stop_at=7)
        call make_chain(chain, 4, 4.15_wp, 0.9_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, 0.5_wp, err)
        call record_cycles(cfg%record, chain, sink, res, err, watch)
        call check(t, .not. allocated(err) .and. .not. res%complete .and. &
                   res%cycles_done == 7 .and. watch%record_calls == 7, &
                   'a run asked to stop at record 7 ends there, incomplete'//label)
        call check(t, all(sink%x(:, 7) == plain_sink%x(:, 7)), &
                   'its records up to the stop are those of the whole run'//label)

        watch = watching_monitor_t(stop_stage=stage_transient, stop_at=30)
        call make_chain(chain, 4, 4.15_wp, 0.9_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, 0.5_wp, err)
        call record_cycles(cfg%record, chain, sink, res, err, watch)
        call check(t, allocated(err) .and. watch%record_calls == 0, &
                   'a run asked to stop during the transient stops with an error'//label)
        if (allocated(err)) call check(t, index(err%message, 'transient') > 0 .and. &
                                       index(err%message, 'cycle 30 of 150') > 0, &
                                       'which says where: '//err%message)
    end subroutine monitored_run

    !> A stop asked within a drive cycle (a dense elastic chain: about 18000 impacts per cycle,
    !> so the monitor is told several times within each) ends the run at the record before,
    !> as a stop there would: the records so far and the chain are the uninterrupted run's,
    !> and the run continued from `state` ends as that run, bit for bit (records, counts,
    !> exponents). Records are held at every record here (hold_after = 0), as the run does
    !> after a slow cycle, so that this holds on any machine.
    subroutine stop_within_a_cycle(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: plain_chain, chain
        type(config_t) :: cfg
        type(record_result_t) :: plain, res
        type(memory_sink_t) :: plain_sink, sink, rest
        type(record_state_t) :: state
        type(cutting_monitor_t) :: cut
        type(error_t), allocatable :: err

        cfg = spectrum_config(40, 0_i8, 5_i8, 4)
        call make_chain(plain_chain, 40, 1.7_wp, 1.5_wp, 0.0_wp, 1.0_wp, .true., 1.0e-4_wp, &
                        0.3_wp, err, spacing=1.0e-3_wp)
        call record_cycles(cfg%record, plain_chain, plain_sink, plain, err)
        call check(t, .not. allocated(err) .and. plain%impacts > 5*3*4096, &
                   'stop within a cycle: a chain of more than three looks per cycle')
        if (allocated(err)) return
        cut = cutting_monitor_t(after=2, stop_at=2)
        call make_chain(chain, 40, 1.7_wp, 1.5_wp, 0.0_wp, 1.0_wp, .true., 1.0e-4_wp, &
                        0.3_wp, err, spacing=1.0e-3_wp)
        call record_cycles(cfg%record, chain, sink, res, err, cut, state, hold_after=0.0_wp)
        call check(t, .not. allocated(err) .and. .not. res%complete .and. &
                   res%cycles_done == 2 .and. cut%looks == 2, &
                   'a stop asked within cycle 3 ends the run at record 2')
        if (allocated(err)) return
        call check(t, all(sink%x(:, :2) == plain_sink%x(:, :2)) .and. &
                   all(chain_positions(chain) == plain_sink%x(:, 2)), &
                   'its records and its chain are the whole run''s at record 2, bit for bit')
        call record_cycles(cfg%record, chain, rest, res, err, state=state)
        call check(t, .not. allocated(err) .and. res%complete, 'the stopped run continues')
        if (allocated(err)) return
        call check(t, all(rest%x(:, 3:) == plain_sink%x(:, 3:)) .and. &
                   res%impacts == plain%impacts .and. &
                   all(res%lyapunov%bits_per_cycle == plain%lyapunov%bits_per_cycle), &
                   'to the whole run''s records, counts and exponents, bit for bit')
    end subroutine stop_within_a_cycle

    logical function cutting_keep_going(monitor, stage, done, total) result(keep_going)
        class(cutting_monitor_t), intent(inout) :: monitor
        integer, intent(in) :: stage
        integer(i8), intent(in) :: done, total

        keep_going = .true.
        if (stage == stage_records) monitor%records = done
        if (stage /= stage_events .or. monitor%records < monitor%after) return
        monitor%looks = monitor%looks + 1
        keep_going = monitor%looks < monitor%stop_at
    end function cutting_keep_going

    logical function watching_keep_going(monitor, stage, done, total) result(keep_going)
        class(watching_monitor_t), intent(inout) :: monitor
        integer, intent(in) :: stage
        integer(i8), intent(in) :: done, total

        select case (stage)
        case (stage_transient)
            monitor%in_order = monitor%in_order .and. monitor%record_calls == 0 .and. &
                               done == monitor%transient_calls + 1 .and. total == 150
            monitor%transient_calls = monitor%transient_calls + 1
        case (stage_records)
            monitor%in_order = monitor%in_order .and. done == monitor%record_calls + 1
            monitor%record_calls = monitor%record_calls + 1
        case (stage_events) ! (within a long cycle: not counted)
            keep_going = .true.
            return
        case default
            monitor%in_order = .false.
        end select
        monitor%last_done = done
        monitor%last_total = total
        keep_going = .not. (stage == monitor%stop_stage .and. done == monitor%stop_at)
    end function watching_keep_going

    !> A configuration for record_cycles: transient, recorded cycles, Lyapunov vectors (0 = all).
    function spectrum_config(n, transient, cycles, vectors) result(cfg)
        integer, intent(in) :: n, vectors
        integer(i8), intent(in) :: transient, cycles
        type(config_t) :: cfg

        cfg%model%n = n
        cfg%record%transient = transient
        cfg%record%cycles = cycles
        cfg%record%record_events = .false.
        cfg%record%lyapunov = .true.
        cfg%record%vectors = vectors
        cfg%record%qr_every = 1
    end function spectrum_config

    subroutine spectrum(chain, cfg, res, err)
        type(chain_t), intent(inout) :: chain
        type(config_t), intent(in) :: cfg
        type(record_result_t), intent(out) :: res
        type(error_t), allocatable, intent(out) :: err
        type(memory_sink_t) :: sink

        sink%keep_strobe = .false.
        call record_cycles(cfg%record, chain, sink, res, err)
    end subroutine spectrum

    !> Sum of all 2n exponents (nats per cycle) = -2 b n T + 2 ln(K) c, c = impacts per cycle.
    subroutine sum_rule(t, n, amplitude, omega)
        type(tally_t), intent(inout) :: t
        integer, intent(in) :: n
        real(wp), intent(in) :: amplitude, omega
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(record_result_t) :: res
        character(len=8) :: label

        write (label, '(i0)') n
        call make_chain(chain, n, amplitude, omega, 0.05_wp, 0.7_wp, .true., 0.3_wp, 0.5_wp, err)
        call spectrum(chain, spectrum_config(n, 200_i8, 1000_i8, 0), res, err)
        call check(t, .not. allocated(err) .and. res%sticks == 0, &
                   'sum rule run n = '//trim(label)//' completes without sticking')
        if (allocated(err)) return
        call check(t, res%collisions_per_cycle > 1, 'sum rule run n = '//trim(label)//' impacts')
        call check(t, res%lyapunov%bits_per_cycle(1) > 0, &
                   'sum rule run n = '//trim(label)//' is chaotic')
        call check_sum_rule(t, 'n = '//trim(label)//', chaotic', n, flow_of(chain), &
                            0.7_wp, res%collisions_per_cycle, &
                            res%lyapunov%bits_per_cycle, res%sticks)
    end subroutine sum_rule

    !> Without impacts every exponent tends to -b T nats per cycle; their mean is exact.
    subroutine no_impacts(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(record_result_t) :: res
        type(flow_t) :: flow
        real(wp) :: bt, nats(6)

        call make_chain(chain, 3, 0.2_wp, 1.5_wp, 0.05_wp, 0.7_wp, .true., 0.2_wp, 0.1_wp, err)
        call spectrum(chain, spectrum_config(3, 0_i8, 2000_i8, 0), res, err)
        flow = flow_of(chain)
        bt = flow%damping*flow%period
        nats = res%lyapunov%bits_per_cycle*log(2.0_wp)
        call check(t, res%impacts == 0, 'no-impact spectrum run has no impacts')
        call check_close(t, sum(nats)/6, -bt, 'no impacts: mean exponent is -b T', 1.0e-12_wp)
        call check(t, maxval(abs(nats + bt)) < 1.0e-4_wp, &
                   'no impacts: every exponent within 1e-4 of -b T after 2000 cycles')
        call check_sum_rule(t, 'no impacts', 3, flow, 0.7_wp, &
                            res%collisions_per_cycle, res%lyapunov%bits_per_cycle, res%sticks)
    end subroutine no_impacts

    !> The analytic Poincare-map Jacobian equals central differences of the one-cycle map,
    !> from a section at time `section` in the cycle (default 0).
    subroutine finite_differences(t, n, walls, section)
        type(tally_t), intent(inout) :: t
        integer, intent(in) :: n
        logical, intent(in) :: walls
        real(wp), intent(in), optional :: section
        type(chain_t) :: chain, plus, minus
        type(error_t), allocatable :: err
        type(event_log_t) :: events
        real(wp), allocatable :: jac(:, :), fd(:, :)
        real(wp) :: h, worst, scale, s
        integer :: j, m, attempts
        integer(i8) :: start
        logical :: same, found
        character(len=40) :: label

        write (label, '(a,i0,a)') 'n = ', n, merge(' fixed', ' free ', walls)
        s = 0
        if (present(section)) then
            s = section
            label = trim(label)//' mid-cycle section'
        end if
        ! free ends: collisions die out, so start hard and look at the first cycles
        call make_chain(chain, n, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, walls, 0.3_wp, &
                        merge(1.2_wp, 3.0_wp, walls), err)
        call event_log_init(events, .false., 0)
        h = 1.0e-7_wp
        m = 2*n
        start = merge(2, 0, walls)
        found = .false.
        do attempts = 1, 40
            call advance_to_point(chain, start + attempts, s, events, err)
            call poincare_jacobian(chain, 1, jac, err)
            allocate (fd(m, m))
            same = .true.
            do j = 1, m
                call perturbed_map(chain, j, h, plus, same)
                call perturbed_map(chain, j, -h, minus, same)
                fd(:, j) = (state_of(plus) - state_of(minus))/(2*h)
            end do
            found = same .and. chain_impacts_one_cycle(chain) > 0
            if (found) exit
            deallocate (fd)
        end do
        call check(t, found, 'finite differences '//trim(label)//': a cycle with impacts and '// &
                   'one impact sequence for all perturbations')
        if (.not. found) return
        scale = max(1.0_wp, maxval(abs(jac)))
        worst = maxval(abs(jac - fd))
        call check_close(t, worst/scale, 0.0_wp, 'Jacobian equals finite differences '// &
                         trim(label), 2.0e-6_wp)
    end subroutine finite_differences

    function state_of(chain) result(state)
        type(chain_t), intent(in) :: chain
        real(wp), allocatable :: state(:)
        real(wp), allocatable :: x(:)

        x = chain_positions(chain)
        allocate (state(2*size(x)))
        state(1::2) = x
        state(2::2) = chain_velocities(chain)
    end function state_of

    !> The one-cycle map from the chain's state with coordinate j moved by h (a fresh chain,
    !> so the schedule is searched anew); `same` turns false if the impact sequence differs.
    subroutine perturbed_map(chain, j, h, moved, same)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: j
        real(wp), intent(in) :: h
        type(chain_t), intent(out) :: moved
        logical, intent(inout) :: same
        type(error_t), allocatable :: err
        type(event_log_t) :: events, base_log
        real(wp), allocatable :: x(:), v(:)
        type(chain_t) :: base
        type(model_t) :: model
        integer(i8) :: cycle
        real(wp) :: s

        model = chain_model(chain)
        cycle = chain_cycle(chain)
        s = chain_time(chain)
        x = chain_positions(chain)
        v = chain_velocities(chain)
        call chain_init(base, model, moving_state(x, v, cycle, s), err)
        if (modulo(j, 2) == 1) then
            x((j + 1)/2) = x((j + 1)/2) + h
        else
            v(j/2) = v(j/2) + h
        end if
        call chain_init(moved, model, moving_state(x, v, cycle, s), err)
        call event_log_init(events, .true., 64)
        call event_log_init(base_log, .true., 64)
        call advance_to_point(moved, cycle + 1, s, events, err)
        call advance_to_point(base, cycle + 1, s, base_log, err)
        if (events%count /= base_log%count) then
            same = .false.
        else if (any(events%site(:events%count) /= base_log%site(:events%count))) then
            same = .false.
        end if
    end subroutine perturbed_map

    integer function chain_impacts_one_cycle(chain)
        type(chain_t), intent(in) :: chain
        type(chain_t) :: copy
        type(error_t), allocatable :: err
        type(event_log_t) :: events
        type(event_counts_t) :: counts

        copy = chain
        call chain_reset_counts(copy)
        call event_log_init(events, .false., 0)
        call advance_to_point(copy, chain_cycle(chain) + 1, chain_time(chain), events, err)
        counts = chain_counts(copy)
        chain_impacts_one_cycle = int(counts%impacts)
    end function chain_impacts_one_cycle

    !> The full spectrum from unit vectors (the default: its QR steps factorise only the
    !> oscillators impacts have joined) and from the generic frame (kept when finite-time
    !> exponents are asked for) are one spectrum: every exponent within four combined
    !> standard errors, on the paper's default chain at n = 16 and at n = 48 (where the middle
    !> of the chain never collides and stays decoupled), and the sum rule holds for both.
    subroutine unit_frame_spectrum(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain, copy
        type(error_t), allocatable :: err
        type(record_result_t) :: unit, generic
        type(config_t) :: cfg
        real(wp) :: worst
        character(len=8) :: label
        integer :: n, q

        do q = 1, 2
            n = merge(16, 48, q == 1)
            write (label, '(i0)') n
            call make_chain(chain, n, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, 0.5_wp, &
                            err)
            copy = chain
            cfg = spectrum_config(n, 300_i8, 4000_i8, 0)
            cfg%record%qr_every = 0
            call spectrum(chain, cfg, unit, err)
            call check(t, .not. allocated(err), 'unit frame spectrum runs, n = '//trim(label))
            cfg%record%window = 4000
            call spectrum(copy, cfg, generic, err)
            call check(t, .not. allocated(err), 'generic frame spectrum runs, n = '//trim(label))
            associate (a => unit%lyapunov, b => generic%lyapunov)
                worst = maxval(abs(a%bits_per_cycle - b%bits_per_cycle)/ &
                               sqrt(a%stderr_bits**2 + b%stderr_bits**2 + 1.0e-24_wp))
                call check(t, worst < 4, 'unit and generic frames: one full spectrum within '// &
                           '4 standard errors, n = '//trim(label))
                call check(t, size(a%bits_per_cycle) == 2*n, 'unit frame: all 2n exponents')
            end associate
        end do
    end subroutine unit_frame_spectrum

    !> A full spectrum from unit vectors stopped at a record and continued from its saved state
    !> in a new chain (the frame finds its pieces from its own entries, and gets each piece's
    !> shrinking since its last factorisation) ends as the run that was never stopped, bit for
    !> bit: on the default chain at n = 48, whose middle stays decoupled, with adaptive QR
    !> steps.
    subroutine unit_frame_continued(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: plain_chain, chain, continued
        type(config_t) :: cfg
        type(record_result_t) :: plain, res
        type(memory_sink_t) :: plain_sink, sink, rest
        type(record_state_t) :: state
        type(watching_monitor_t) :: watch
        type(error_t), allocatable :: err

        cfg = spectrum_config(48, 300_i8, 200_i8, 0)
        cfg%record%qr_every = 0
        call make_chain(plain_chain, 48, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, &
                        0.5_wp, err)
        call record_cycles(cfg%record, plain_chain, plain_sink, plain, err)
        call check(t, .not. allocated(err), 'unit frame, n = 48: the whole run')
        if (allocated(err)) return
        watch = watching_monitor_t(stop_stage=stage_records, stop_at=77)
        call make_chain(chain, 48, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, 0.5_wp, err)
        call record_cycles(cfg%record, chain, sink, res, err, watch, state)
        call check(t, .not. allocated(err) .and. .not. res%complete .and. &
                   res%cycles_done == 77, 'unit frame, n = 48: stopped at record 77')
        if (allocated(err)) return
        call chain_init(continued, chain_model(chain), chain_snapshot(chain), err)
        call check(t, .not. allocated(err), 'unit frame, n = 48: a new chain from the state')
        if (allocated(err)) return
        call record_cycles(cfg%record, continued, rest, res, err, state=state)
        call check(t, .not. allocated(err) .and. res%complete, &
                   'unit frame, n = 48: the stopped run continues')
        if (allocated(err)) return
        call check(t, all(res%lyapunov%bits_per_cycle == plain%lyapunov%bits_per_cycle) .and. &
                   all(res%lyapunov%stderr_bits == plain%lyapunov%stderr_bits) .and. &
                   res%impacts == plain%impacts, 'unit frame, n = 48: continued = whole run''s '// &
                   'exponents and errors, bit for bit')
    end subroutine unit_frame_continued

    !> qr_orthonormalise_blocks on a frame of independent pieces (single oscillators' 2 x 2
    !> blocks and longer pieces of several sizes, at both ends and in between) is the dense
    !> factorisation: R's diagonal and Q to rounding; a single oscillator with a zero
    !> lower-left entry (Q = I) included. Dense and blocked differ if the structure is false.
    !> n = 9: pieces 1-3, 4, 5-6, 7-9 (the written-out reflections); n = 40: one piece of 50
    !> rows (dgeqrf) among pieces of 2 to 8. A chain given the frame finds its pieces from the
    !> frame's entries (as when a run is restored) and re-orthonormalises it as the dense
    !> factorisation does.
    subroutine block_factorisation(t, n)
        type(tally_t), intent(inout) :: t
        integer, intent(in) :: n
        real(wp) :: dense(2*n, 2*n), blocks(2*n, 2*n), r_dense(2*n), r_blocks(2*n), h
        real(wp) :: frame(2*n, 2*n), single(2*n, 2*n), outside(2*n, 2*n), r_single(2*n)
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        logical :: joined(n - 1)
        integer :: piece(n)
        type(qr_workspace_t) :: ws_dense, ws_blocks, ws_single
        integer :: i, j, q, info, low, high

        joined = [(modulo(i, 7) /= 3 .and. modulo(i, 7) /= 4 .and. modulo(i, 7) /= 6 .or. &
                   i > 6 .and. i < 30, i=1, n - 1)]
        piece = [(1 + count(.not. joined(:i - 1)), i=1, n)]
        dense = 0
        do j = 1, 2*n
            do i = 1, 2*n
                if (piece((i + 1)/2) == piece((j + 1)/2)) then
                    h = sin(3.1_wp*i + 7.7_wp*j)*917.3_wp
                    dense(i, j) = h - floor(h) - 0.5_wp
                end if
            end do
        end do
        ! (oscillator 4 is a piece of its own)
        dense(8, 7) = 0
        frame = dense
        blocks = dense
        call qr_orthonormalise(dense, r_dense, ws_dense, info)
        call qr_orthonormalise_blocks(blocks, joined, r_blocks, ws_blocks, info)
        call check(t, info == 0, 'block factorisation: info 0')
        ! one piece alone (oscillators 5 and 6 at n = 9): its block as the blocks' factorisation
        ! has it, every other entry untouched, bit for bit
        single = frame
        low = 2*findloc(piece, piece(6), dim=1) - 1
        high = 2*findloc(piece, piece(6), dim=1, back=.true.)
        call qr_orthonormalise_piece(single, low, high, r_single(low:high), ws_single, info)
        outside = frame
        outside(low:high, low:high) = single(low:high, low:high)
        call check(t, info == 0 .and. high - low > 2 .and. &
                   all(single(low:high, low:high) == blocks(low:high, low:high)) .and. &
                   all(r_single(low:high) == r_blocks(low:high)) .and. all(single == outside), &
                   'block factorisation: one piece alone = its block of all, the rest untouched')
        ! a singular piece (a zero column: an exactly zero R(j,j)) with keep_singular leaves
        ! the frame as it was, for one piece (2 x 2: oscillator 4; 4 x 4: oscillators 5 and 6)
        ! and for all pieces, whichever piece is singular
        do q = 8, 12, 4
            single = frame
            single(:, q) = 0
            outside = single
            low = merge(7, 9, q == 8)
            call qr_orthonormalise_piece(single, low, q, r_single(low:q), ws_single, info, &
                                         keep_singular=.true.)
            call check(t, info == 0 .and. any(r_single(low:q) == 0) .and. all(single == outside), &
                       'block factorisation: a singular piece alone is kept as it was')
            call qr_orthonormalise_blocks(single, joined, r_single, ws_single, info, &
                                          keep_singular=.true.)
            call check(t, info == 0 .and. any(r_single == 0) .and. all(single == outside), &
                       'block factorisation: a frame with a singular piece is kept as it was')
        end do
        call check_close(t, maxval(abs(abs(r_blocks) - abs(r_dense))/abs(r_dense)), 0.0_wp, &
                         'block factorisation: |R(j,j)| of the dense one', 1.0e-12_wp)
        ! (columns may differ in sign between two Householder orders: compare |Q^T Q'|)
        call check_close(t, maxval(abs(abs(matmul(transpose(dense), blocks)) - &
                                       identity(2*n))), 0.0_wp, &
                         'block factorisation: Q of the dense one, column for column', 1.0e-12_wp)
        ! the frame as it is, then with a coupling that crosses cut 3 only above the diagonal
        ! (a row of oscillator 1, a column of oscillator 4), then one only below it: it joins
        ! them
        do q = 1, 3
            if (q > 1) then
                frame(1, 7) = merge(0.3_wp, 0.0_wp, q == 2)
                frame(7, 1) = merge(0.3_wp, 0.0_wp, q == 3)
                dense = frame
                call qr_orthonormalise(dense, r_dense, ws_dense, info)
            end if
            call make_chain(chain, n, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, 0.5_wp, &
                            err)
            call chain_set_tangent(chain, frame)
            call chain_reorthonormalise(chain, err)
            call check(t, .not. allocated(err), 'block factorisation: a chain given the '// &
                       'frame re-orthonormalises it')
            call check_close(t, maxval(abs(abs(matmul(transpose(dense), &
                                                      chain_tangent_frame(chain))) - &
                                           identity(2*n))), 0.0_wp, &
                             'block factorisation: the pieces a chain finds from its frame '// &
                             'give the dense Q', 1.0e-12_wp)
        end do
        ! a frame that is not block-structured is not factorised by it
        blocks = dense
        blocks(7, 1) = 0.3_wp
        dense = blocks
        call qr_orthonormalise(dense, r_dense, ws_dense, info)
        call qr_orthonormalise_blocks(blocks, joined, r_blocks, ws_blocks, info)
        call check(t, maxval(abs(abs(r_blocks) - abs(r_dense))) > 1.0e-3_wp, &
                   'block factorisation: a coupling outside the blocks is not kept')
    contains
        pure function identity(m) result(e)
            integer, intent(in) :: m
            real(wp) :: e(m, m)
            integer :: q

            e = 0
            do q = 1, m
                e(q, q) = 1
            end do
        end function identity
    end subroutine block_factorisation

    !> The k leading exponents from a frame of k vectors equal the first k of the spectrum.
    subroutine leading_vectors(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain, copy
        type(error_t), allocatable :: err
        type(record_result_t) :: full, lead
        real(wp) :: worst
        integer :: j

        type(config_t) :: generic

        call make_chain(chain, 16, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, 0.5_wp, err)
        copy = chain
        ! (finite-time exponents keep the generic frame for the full spectrum too, 7.1)
        generic = spectrum_config(16, 100_i8, 300_i8, 0)
        generic%record%window = 100
        call spectrum(chain, generic, full, err)
        call spectrum(copy, spectrum_config(16, 100_i8, 300_i8, 6), lead, err)
        call check(t, size(lead%lyapunov%bits_per_cycle) == 6, 'six leading exponents')
        ! column j of a k-frame is column j of the full frame (QR keeps nested spans), but
        ! both lists are sorted: nearly equal exponents can trade places over a short run
        worst = 0
        do j = 1, 6
            worst = max(worst, minval(abs(full%lyapunov%bits_per_cycle - &
                                          lead%lyapunov%bits_per_cycle(j))))
        end do
        call check_close(t, worst, 0.0_wp, &
                         'k leading exponents are k of the full spectrum', 1.0e-10_wp)
        call check_sum_rule(t, 'n = 16, full spectrum beside the leading vectors', 16, &
                            flow_of(chain), 0.7_wp, full%collisions_per_cycle, &
                            full%lyapunov%bits_per_cycle, full%sticks)
    end subroutine leading_vectors

    !> QR steps at the adaptive interval (qr_every = 0) give the exponents of a QR step every
    !> cycle to 1e-10 bits per cycle (the R factors telescope: only rounding differs), and their
    !> standard errors, with fewer steps, on the chains of the tests above; full spectra keep
    !> the sum rule.
    subroutine adaptive_matches_every_cycle(t, n, amplitude, omega, transient, cycles, vectors, &
                                            full)
        type(tally_t), intent(inout) :: t
        integer, intent(in) :: n, vectors
        real(wp), intent(in) :: amplitude, omega
        integer(i8), intent(in) :: transient, cycles
        logical, intent(in) :: full
        type(chain_t) :: chain, copy
        type(error_t), allocatable :: err
        type(record_result_t) :: every, adaptive
        type(config_t) :: cfg
        real(wp) :: x_amp, v_amp
        character(len=60) :: label

        write (label, '(a,i0,a,f0.2,a,f0.2,a,i0)') 'n = ', n, ', A = ', amplitude, ', w = ', &
            omega, ', vectors ', vectors
        x_amp = merge(0.3_wp, 0.0_wp, n /= 8 .and. n /= 3)
        v_amp = merge(0.5_wp, 0.0_wp, n /= 8 .and. n /= 3)
        if (n == 3) then
            x_amp = 0.2_wp
            v_amp = 0.1_wp
        end if
        call make_chain(chain, n, amplitude, omega, 0.05_wp, merge(0.5_wp, 0.7_wp, n == 8), &
                        .true., x_amp, v_amp, err)
        copy = chain
        cfg = spectrum_config(n, transient, cycles, vectors)
        call spectrum(chain, cfg, every, err)
        call check(t, .not. allocated(err), 'adaptive QR: every-cycle run '//trim(label))
        if (allocated(err)) return
        cfg%record%qr_every = 0
        call spectrum(copy, cfg, adaptive, err)
        call check(t, .not. allocated(err), 'adaptive QR: adaptive run '//trim(label))
        if (allocated(err)) return
        call check_close(t, maxval(abs(adaptive%lyapunov%bits_per_cycle - &
                                       every%lyapunov%bits_per_cycle)), 0.0_wp, &
                         'adaptive QR = QR every cycle to 1e-10 bits/cycle, '//trim(label), &
                         1.0e-10_wp)
        ! (steps never cross a block: each block holds the cycles it holds every cycle; the
        ! errors agree to 1e-9 bits per cycle or, where they are large, to 1e-8 of their size:
        ! a unit's value sums up to 64 cycles' logarithms, whose rounding reaches 1e-9 bits per
        ! cycle, where the exponents, averages over every unit, agree to 1e-10)
        call check(t, all(abs(adaptive%lyapunov%stderr_bits - every%lyapunov%stderr_bits) <= &
                          max(1.0e-9_wp, 1.0e-8_wp*every%lyapunov%stderr_bits)), &
                   'adaptive QR: the standard errors of every cycle, '//trim(label))
        if (any(abs(adaptive%lyapunov%stderr_bits - every%lyapunov%stderr_bits) > &
                max(1.0e-9_wp, 1.0e-8_wp*every%lyapunov%stderr_bits))) &
            print '(a, es10.2, a, es10.2)', '    largest difference of the errors', &
                maxval(abs(adaptive%lyapunov%stderr_bits - every%lyapunov%stderr_bits)), &
                ', relative ', maxval(abs(adaptive%lyapunov%stderr_bits - &
                                          every%lyapunov%stderr_bits)/every%lyapunov%stderr_bits)
        call check(t, size(adaptive%lyapunov%running_cycles) < &
                   size(every%lyapunov%running_cycles), &
                   'adaptive QR takes fewer steps, '//trim(label))
        if (full) call check_sum_rule(t, 'adaptive QR, '//trim(label), n, flow_of(copy), &
                                      merge(0.5_wp, 0.7_wp, n == 8), &
                                      adaptive%collisions_per_cycle, &
                                      adaptive%lyapunov%bits_per_cycle, adaptive%sticks)
    end subroutine adaptive_matches_every_cycle

    !> Fig. 10's chain (n = 8, K = 0.5, w = 1.9, b = 0.05) at A = 3 from rest: a period-1 state
    !> with 8 impacts per cycle. Its multipliers lie inside the unit circle and their product
    !> is exp(-2 b n T) K**(2 c).
    subroutine floquet_period_one(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: events
        real(wp), allocatable :: jac(:, :), re(:), im(:), before(:)
        real(wp) :: log_det, expected
        type(flow_t) :: flow
        type(event_counts_t) :: counts
        integer :: info, c

        call make_chain(chain, 8, 3.0_wp, 1.9_wp, 0.05_wp, 0.5_wp, .true., 0.0_wp, 0.0_wp, err)
        call event_log_init(events, .false., 0)
        call advance_to_point(chain, 1000_i8, 0.0_wp, events, err)
        before = [chain_positions(chain), chain_velocities(chain)]
        c = chain_impacts_one_cycle(chain)
        call poincare_jacobian(chain, 1, jac, err)
        call advance_to_point(chain, 1001_i8, 0.0_wp, events, err)
        counts = chain_counts(chain)
        call check(t, maxval(abs([chain_positions(chain), chain_velocities(chain)] - before)) &
                   < 1.0e-9_wp .and. counts%sticks == 0 .and. c == 8, &
                   'fig. 10 chain at A = 3 settles on a '// &
                   'period-1 state with 8 impacts per cycle')
        allocate (re(16), im(16))
        call floquet_multipliers(jac, re, im, info)
        call check(t, info == 0 .and. maxval(hypot(re, im)) < 1, &
                   'period-1 multipliers lie inside the unit circle')
        log_det = sum(log(hypot(re, im)))
        flow = flow_of(chain)
        expected = -2*flow%damping*8*flow%period + 2*c*log(0.5_wp)
        call check_close(t, log_det, expected, 'product of multipliers is exp(-2bnT) K**(2c)', &
                         rel_tol=1.0e-8_wp)
    end subroutine floquet_period_one

    !> Fig. 1c (n = 16, A = 1.7, w = 1.5) is chaotic; fig. 10's chain at A = 3 is periodic: the
    !> largest exponent and its standard error separate both from zero (3 sigma).
    subroutine chaotic_and_periodic(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(record_result_t) :: res
        real(wp) :: l1, s1

        call make_chain(chain, 16, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, 0.5_wp, err)
        call spectrum(chain, spectrum_config(16, 500_i8, 2000_i8, 2), res, err)
        l1 = res%lyapunov%bits_per_cycle(1)
        s1 = res%lyapunov%stderr_bits(1)
        call check(t, l1 - 3*s1 > 0, 'fig. 1c: largest exponent positive beyond 3 sigma')
        call make_chain(chain, 8, 3.0_wp, 1.9_wp, 0.05_wp, 0.5_wp, .true., 0.0_wp, 0.0_wp, err)
        call spectrum(chain, spectrum_config(8, 500_i8, 2000_i8, 2), res, err)
        l1 = res%lyapunov%bits_per_cycle(1)
        s1 = res%lyapunov%stderr_bits(1)
        call check(t, l1 + 3*s1 < 0, 'fig. 10 at A = 3: largest exponent negative beyond 3 sigma')
    end subroutine chaotic_and_periodic

    subroutine kaplan_yorke(t)
        type(tally_t), intent(inout) :: t

        call check_close(t, ky_dimension([1.0_wp, -0.5_wp, -2.0_wp]), 2.25_wp, 'D_KY example', &
                         1.0e-15_wp)
        call check_close(t, ky_dimension([-0.1_wp, -0.5_wp]), 0.0_wp, 'D_KY all negative', &
                         1.0e-15_wp)
        call check_close(t, ky_dimension([0.3_wp, -0.1_wp]), 2.0_wp, 'D_KY full', 1.0e-15_wp)
    end subroutine kaplan_yorke

    !> qr_orthonormalise on frames of every kind it meets: Q orthonormal, Q^T A upper
    !> triangular with the returned diagonal, whether Q comes from the triangular solve (a
    !> narrow diagonal) or from dorgqr (a graded frame; rows zeroed by a rest; a frame whose
    !> R diagonal is narrow although the frame is nearly singular, where a R^-1 would lose
    !> orthogonality: a column swamped by a multiple of another, and U times Kahan's matrix).
    subroutine qr_factors(t)
        type(tally_t), intent(inout) :: t
        real(wp) :: a(32, 32)

        call check_qr(t, graded(32, 32, 0.25_wp, 0), 'square frame, narrow R diagonal', .true.)
        call check_qr(t, graded(32, 32, 2.0_wp, 0), 'square frame, R diagonal spanning 1e19', &
                      .true.)
        call check_qr(t, graded(32, 32, 0.6_wp, 0), 'square frame, R diagonal spanning 4e5', &
                      .false.)
        call check_qr(t, graded(32, 32, 0.25_wp, 2), 'square frame with two zero rows', .true.)
        call check_qr(t, graded(2048, 10, 0.5_wp, 0), 'tall frame', .false.)
        a = graded(32, 32, 0.0_wp, 0)
        a(:, 32) = a(:, 32) + 1.0e12_wp*a(:, 1)
        call check_qr(t, a, 'column swamped by a multiple of another', .false.)
        ! two nearly parallel columns: unit lengths hide q1.q2 of 3e-8 (span 1e8) and of 1e-6
        ! (span 1e10), which only the span test refuses
        call check_qr(t, nearly_parallel(1.59e-8_wp, 5), 'nearly parallel pair, span 1e8', .true.)
        call check_qr(t, nearly_parallel(1.21e-10_wp, 2), 'nearly parallel pair, span 1e10', &
                      .true.)
        call check_qr(t, reflected_kahan(32, 0.8_wp), 'U Kahan(0.8), cond 1e12', .false.)
        call check_qr(t, reflected_kahan(32, 1.0_wp), 'U Kahan(1.0), cond 4e8', .false.)
        ! the three ways a frame is factorised (chain_lapack: by hand up to 40 columns, dgeqrf,
        ! dgeqrt from 1024 columns), each with a safe solve and with Q by dorgqr
        call check_qr(t, graded(96, 96, 0.25_wp, 0), 'dgeqrf frame (96 columns)', .true.)
        call check_qr(t, graded(96, 96, 0.25_wp, 2), 'dgeqrf frame with two zero rows', .true.)
        call check_qr(t, graded(1100, 1024, 0.01_wp, 0), 'dgeqrt frame (1024 columns)', .true.)
        call check_qr(t, graded(1100, 1024, 0.05_wp, 0), 'dgeqrt frame, R diagonal spanning '// &
                      '4e15 (Q by dorgqr)', .true.)
    end subroutine qr_factors

    !> Sweep threads factorise their frames at the same time: the BLAS and LAPACK linked in
    !> must be thread-safe (BLIS is reentrant; Debian's single-threaded OpenBLAS 0.3.21 is not:
    !> it fails this check). Two threads, 200 factorisations of a 200 x 100 frame: every one
    !> equal to the serial result bit for bit.
    subroutine qr_in_threads(t)
        type(tally_t), intent(inout) :: t
        integer, parameter :: repeats = 200
        real(wp) :: a(200, 100), serial(200, 100), r_diag(100)
        type(qr_workspace_t) :: ws
        integer :: j, info, differing

        a = graded(200, 100, 0.05_wp, 0)
        serial = a
        call qr_orthonormalise(serial, r_diag, ws, info)
        differing = 0
        !$omp parallel do num_threads(2) reduction(+:differing) schedule(static, 1)
        do j = 1, repeats
            block
                real(wp) :: q(200, 100), d(100)
                type(qr_workspace_t) :: own
                integer :: status

                q = a
                call qr_orthonormalise(q, d, own, status)
                if (status /= 0 .or. any(q /= serial)) differing = differing + 1
            end block
        end do
        !$omp end parallel do
        call check(t, info == 0 .and. differing == 0, &
                   'QR in 2 threads equals the serial QR bit for bit (a thread-safe BLAS)')
    end subroutine qr_in_threads

    !> A pseudo-random m x k matrix with columns scaled by 2**(-grading*j) (j = column) and
    !> the first `zero_rows` rows zeroed.
    pure function graded(m, k, grading, zero_rows) result(a)
        integer, intent(in) :: m, k, zero_rows
        real(wp), intent(in) :: grading
        real(wp) :: a(m, k), h
        integer :: i, j

        do j = 1, k
            do i = 1, m
                h = sin(7.31_wp*i + 3.17_wp*j*j)*9973.1_wp
                a(i, j) = (h - floor(h) - 0.5_wp)*2.0_wp**(-grading*j)
            end do
        end do
        a(1:zero_rows, :) = 0
    end function graded

    !> Columns g1 and g1 + eps g_other of graded(32, 5, 0, 0).
    pure function nearly_parallel(eps, other) result(a)
        real(wp), intent(in) :: eps
        integer, intent(in) :: other
        real(wp) :: a(32, 2), g(32, 5)

        g = graded(32, 5, 0.0_wp, 0)
        a(:, 1) = g(:, 1)
        a(:, 2) = g(:, 1) + eps*g(:, other)
    end function nearly_parallel

    !> A Householder reflection U times Kahan's k x k matrix diag(s**(j-1)) (I - c N), N the
    !> strictly upper ones, s = sin(theta), c = cos(theta): a diagonal that spans only
    !> s**(1-k) but a condition number that grows much faster.
    pure function reflected_kahan(k, theta) result(a)
        integer, intent(in) :: k
        real(wp), intent(in) :: theta
        real(wp) :: a(k, k), kahan(k, k), v(k)
        integer :: i, j

        kahan = 0
        do j = 1, k
            kahan(j, j) = 1
            kahan(1:j - 1, j) = -cos(theta)
        end do
        do i = 1, k
            kahan(i, :) = kahan(i, :)*sin(theta)**(i - 1)
            v(i) = sin(7.31_wp*i)
        end do
        a = kahan - 2*spread(v, 2, k)*spread(matmul(v, kahan), 1, k)/dot_product(v, v)
    end function reflected_kahan

    !> Q from qr_orthonormalise(a) orthonormal (to 1e-9, or to rounding when `exact`: Q
    !> from dorgqr or a well-conditioned solve), Q^T a upper triangular, diagonal returned.
    subroutine check_qr(t, a, label, exact)
        type(tally_t), intent(inout) :: t
        real(wp), intent(in) :: a(:, :)
        character(len=*), intent(in) :: label
        logical, intent(in) :: exact
        ! (allocatable: the large frames would not fit on the stack)
        real(wp), allocatable :: q(:, :), r_diag(:), eye(:, :), qta(:, :)
        real(wp) :: lower, orthonormal
        type(qr_workspace_t) :: ws
        integer :: j, k, info

        k = size(a, 2)
        q = a
        allocate (r_diag(k), eye(k, k))
        call qr_orthonormalise(q, r_diag, ws, info)
        eye = 0
        do j = 1, k
            eye(j, j) = 1
        end do
        qta = matmul(transpose(q), a)
        lower = 0
        do j = 1, k - 1
            lower = max(lower, maxval(abs(qta(j + 1:k, j)))/norm2(a(:, j)))
        end do
        orthonormal = maxval(abs(matmul(transpose(q), q) - eye))
        call check(t, info == 0 .and. all(ieee_is_finite(q)), 'QR, '//label//': finite')
        call check_close(t, orthonormal, 0.0_wp, 'QR, '//label//': Q orthonormal', 1.0e-9_wp)
        if (exact) call check_close(t, orthonormal, 0.0_wp, &
                                    'QR, '//label//': Q orthonormal to rounding', 1.0e-13_wp)
        call check_close(t, lower, 0.0_wp, 'QR, '//label//': Q^T A upper triangular', &
                         1.0e-9_wp)
        call check_close(t, maxval(abs([(qta(j, j) - r_diag(j), j=1, k)]/ &
                                       [(norm2(a(:, j)), j=1, k)])), 0.0_wp, &
                         'QR, '//label//': R diagonal returned', 1.0e-12_wp)
    end subroutine check_qr

end module test_lyapunov
