!> impactchain benchmark:
!> `impactchain-bench [--case NAME] [--yardsticks] [--provenance] [--tsv] [--quick] [--list]`.
!>
!> Times the event engine through the same entry points as a real run (`start_chain`,
!> `record_cycles` with an in-memory sink) and prints one Markdown table: collisions per cycle,
!> microseconds per drive cycle, collisions per second, nanoseconds per collision and peak
!> memory. Each case is warmed up, then run long enough (>= 0.5 s) three times; the best
!> repetition is reported (a case whose cycles take seconds: fewer, see time_cycles). Run
!> whole (no --case) or with --yardsticks it first measures the machine's yardsticks
!> (bench_yardsticks), the units of run_bench.py's targets. `bench/run_bench.py` runs every
!> case in its own process (so the peak memory is per case) and adds the scipy baseline; this
!> program alone reports the process high-water mark after each case. Timings are never asserted.
!>
!> Not timed: HDF5 output and the event log (record_events = .false.); strobe records are
!> kept in memory only where a sweep would keep them.
program bench
    use, intrinsic :: iso_fortran_env, only: int64, output_unit, error_unit
    use impactchain, only: wp, i8, error_t, config_t, validate_config, chain_t, event_log_t, &
                           memory_sink_t, record_result_t, record_cycles, start_chain, &
                           restart_chain, advance_to_point, event_counts_t, chain_cycle, &
                           chain_start, chain_period, chain_positions, chain_velocities, &
                           chain_copy_state, chain_contacts, chain_counts
    use impactchain, only: branch_options_t, branches_t, follow_branches
    use impactchain_drivers, only: continuation_guess, fmt_int
    use impactchain, only: census_result_t
    use impactchain_drivers, only: census_result_init, run_census_samples, classify_census
    !$ use omp_lib, only: omp_set_num_threads
    use bench_kit, only: row_t, wall_seconds, peak_memory_kib, print_machine, &
                         print_table_head, print_row_markdown, print_row_tsv
    use bench_yardsticks, only: transcendental_ns, dgemm_gflops, qr_seconds
    use bench_curve, only: curve_ratio
    implicit none

    character(len=*), parameter :: case_names(22) = [character(len=16) :: &
        'default', 'default-lyap', 'default-adaptive', 'heavy-16', 'heavy-1024', 'heavy-16384', &
        'n1024-lyap10', &
        'n64-full', 'n256-full', 'n1024-full', 'n4096-lyap10', 'n4096-lyap64', 'n4096-lyap256', &
        'fig10-sweep', 'fig13-scan', 'strobe', 'strobe-record', 'orbit-n16', 'orbit-n64-p8', &
        'census-fig3', 'clv-default', 'clv-n64']
    character(len=:), allocatable :: only
    logical :: tsv, quick, yardsticks_only, provenance_only, flat_only, ratio_only, curve_only
    real(wp) :: min_time, budget
    integer :: reps, j

    call parse_arguments(only, tsv, quick, yardsticks_only, provenance_only, flat_only, &
                         ratio_only, curve_only)
    ! budget: the most a row spends on timed cycles; a row whose cycle takes seconds (the full
    ! spectrum at n = 1024) is timed in fewer repetitions, or in its calibration block alone
    min_time = 0.5_wp
    reps = 3
    budget = 20
    if (quick) then
        min_time = 0.02_wp
        reps = 1
        budget = 1
    end if
    call print_machine(tsv)
    if (provenance_only) stop
    if (flat_only) then
        call heavy_flat(7)
        stop
    end if
    if (ratio_only) then
        call exponents_ratio(7)
        stop
    end if
    if (curve_only) then
        call curve_ratio([make_config(8, 3.0_wp, 1.9_wp, 0.05_wp, 0.5_wp, 0.0_wp, 0.0_wp), &
                          make_config(16, 3.0_wp, 1.9_wp, 0.05_wp, 0.5_wp, 0.0_wp, 0.0_wp)], 5)
        stop
    end if
    if (yardsticks_only .or. len(only) == 0) call print_yardsticks()
    if (yardsticks_only) stop
    if (.not. tsv) call print_table_head()
    do j = 1, size(case_names)
        if (len(only) > 0 .and. only /= trim(case_names(j))) cycle
        call run_case(trim(case_names(j)))
    end do
    if (.not. tsv) then
        write (output_unit, '(a)') ''
        write (output_unit, '(a)') 'Best of '//itoa(reps)//' repetitions of >= '// &
            trim(real_fmt(min_time))//' s each after a warm-up (fewer, within '// &
            trim(real_fmt(budget))//' s, when one cycle takes long); peak memory is the '// &
            'process high-water mark (VmHWM) after the case.'
    end if

contains

    subroutine run_case(name)
        character(len=*), intent(in) :: name
        type(row_t) :: row

        row%name = name
        row%unit_name = ''
        select case (name)
        case ('default')
            call case_chain(row, 'paper default (A=1.7, w=1.5, b=0.05, K=0.7), no exponents', &
                            16, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, 0.3_wp, 0.3_wp, 500_i8, 0, &
                            emit_state=.true.)
        case ('default-lyap')
            call case_chain(row, 'paper default, all 32 exponents (QR every cycle)', &
                            16, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, 0.3_wp, 0.3_wp, 500_i8, 32)
        case ('default-adaptive')
            call case_chain(row, 'paper default, all 32 exponents (adaptive QR, the default)', &
                            16, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, 0.3_wp, 0.3_wp, 500_i8, 32, &
                            qr_every=0)
        case ('heavy-16', 'heavy-1024', 'heavy-16384')
            call case_heavy(row, name)
        case ('n1024-lyap10')
            call case_chain(row, 'paper default parameters, 10 leading exponents', &
                            1024, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, 0.3_wp, 0.3_wp, 200_i8, 10)
        case ('n64-full', 'n256-full', 'n1024-full', 'n4096-lyap10', 'n4096-lyap64', &
              'n4096-lyap256')
            call case_spectrum(row, name)
        case ('fig10-sweep')
            call case_fig10(row)
        case ('fig13-scan')
            call case_fig13(row)
        case ('strobe')
            call case_strobe(row)
        case ('strobe-record')
            call case_strobe_record(row)
        case ('orbit-n16')
            call case_orbit(row, 16, 1)
        case ('orbit-n64-p8')
            call case_orbit(row, 64, 8)
        case ('census-fig3')
            call case_census(row)
        case ('clv-default')
            call case_covariant(row, 16, 2000_i8)
        case ('clv-n64')
            call case_covariant(row, 64, 1000_i8)
        end select
        row%peak_kib = peak_memory_kib()
        if (tsv) then
            call print_row_tsv(row)
        else
            call print_row_markdown(row)
        end if
        flush (output_unit)
    end subroutine run_case

    !> A configuration that passes `validate_config`: fixed walls, a = 1, seeded random start.
    function make_config(n, amplitude, omega, damping, restitution, x_amp, v_amp) result(cfg)
        integer, intent(in) :: n
        real(wp), intent(in) :: amplitude, omega, damping, restitution, x_amp, v_amp
        type(config_t) :: cfg
        type(error_t), allocatable :: err
        integer :: k

        cfg%model%n = n
        cfg%model%spacing = [(1.0_wp, k=0, n)]
        cfg%model%amplitude = amplitude
        cfg%model%omega = omega
        cfg%model%damping = damping
        cfg%model%restitution = restitution
        cfg%model%walls = .true.
        cfg%initial_kind = 'random'
        if (x_amp == 0 .and. v_amp == 0) cfg%initial_kind = 'rest'
        cfg%seed = 1
        cfg%x_amp = x_amp
        cfg%v_amp = v_amp
        allocate (cfg%x0(0), cfg%v0(0))
        cfg%initial_file = ''
        cfg%output_file = 'bench.h5'
        cfg%sweep_mode = 'continuation'
        cfg%sweep_parameter = ''
        cfg%sweep_parameter2 = ''
        cfg%input_text = ''
        cfg%record%record_events = .false.
        cfg%record%transient = 0
        cfg%record%cycles = 1
        call validate_config(cfg, err)
        if (allocated(err)) call fail(err%message)
    end function make_config

    function new_chain(cfg) result(chain)
        type(config_t), intent(in) :: cfg
        type(chain_t) :: chain
        type(error_t), allocatable :: err

        call start_chain(cfg, chain, err)
        if (allocated(err)) call fail(err%message)
    end function new_chain

    !> `cycles` recorded cycles from where the chain stands (on the section), timed.
    subroutine run_block(cfg, chain, cycles, seconds, res, cpu)
        type(config_t), intent(inout) :: cfg
        type(chain_t), intent(inout) :: chain
        integer(int64), intent(in) :: cycles
        real(wp), intent(out) :: seconds
        type(record_result_t), intent(out) :: res
        logical, intent(in), optional :: cpu !! time in the process's CPU time
        logical :: use_cpu
        type(memory_sink_t) :: sink
        type(error_t), allocatable :: err
        real(wp) :: t0, start_s
        integer(i8) :: start_cycle

        sink%keep_strobe = .false.
        call chain_start(chain, start_cycle, start_s)
        cfg%record%transient = chain_cycle(chain) - start_cycle
        cfg%record%cycles = cycles
        use_cpu = .false.
        if (present(cpu)) use_cpu = cpu
        t0 = wall_seconds()
        if (use_cpu) call cpu_time(t0)
        call record_cycles(cfg%record, chain, sink, res, err)
        if (use_cpu) then
            call cpu_time(seconds)
            seconds = seconds - t0
        else
            seconds = wall_seconds() - t0
        end if
        if (allocated(err)) call fail(err%message)
    end subroutine run_block

    !> Warm-up and calibration (from one cycle, doubling until a block takes a fifth of
    !> min_time), then the best of `reps` blocks of >= min_time. A row whose cycles are slow
    !> stays within `budget` seconds of timed blocks: a calibration block that already took
    !> min_time is its own warm-up and counts as the first repetition, and only as many more
    !> follow as fit in what is left of the budget (at least the calibration block is timed).
    subroutine time_cycles(cfg, chain, row)
        type(config_t), intent(inout) :: cfg
        type(chain_t), intent(inout) :: chain
        type(row_t), intent(inout) :: row
        type(record_result_t) :: res
        integer(int64) :: cycles
        real(wp) :: seconds, spent
        integer :: r, more

        row%seconds = huge(1.0_wp)
        row%reps = 0
        cycles = 1
        do
            call run_block(cfg, chain, cycles, seconds, res)
            if (seconds >= 0.2_wp*min_time) exit
            cycles = 2*cycles
        end do
        spent = 0
        if (seconds >= min_time .and. cycles == 1) then
            call time_by_difference(cfg, chain, row, seconds)
            return
        else if (seconds >= min_time) then
            call keep_best(row, seconds, res)
            spent = seconds
            more = min(reps - 1, floor((budget - spent)/seconds))
        else
            cycles = max(cycles, ceiling(1.1_wp*min_time*cycles/max(seconds, 1.0e-9_wp), int64))
            more = max(1, min(reps, floor(budget/(1.1_wp*min_time))))
        end if
        do r = 1, more
            call run_block(cfg, chain, cycles, seconds, res)
            call keep_best(row, seconds, res)
        end do

    end subroutine time_cycles

    !> A row whose one cycle already takes min_time (the full spectrum at n = 1024): a block's
    !> start, a Lyapunov row's fresh frame and its orthonormalisation (one more QR), would
    !> weigh as much as its cycle, so the row is the difference of the best blocks of two
    !> cycles and of one, in the process's CPU time (a difference of wall times takes the
    !> load's noise twice), in as many pairs as fit in the budget, at least one; the
    !> calibration block, the first to touch the frame's memory, is not one of them. Stated as
    !> two cycles of twice that difference.
    subroutine time_by_difference(cfg, chain, row, one)
        type(config_t), intent(inout) :: cfg
        type(chain_t), intent(inout) :: chain
        type(row_t), intent(inout) :: row
        real(wp), intent(in) :: one !! the calibration block, of one cycle
        type(record_result_t) :: res, res_two
        real(wp) :: best_one, best_two, seconds
        integer :: r, pairs

        best_one = huge(1.0_wp)
        best_two = huge(1.0_wp)
        pairs = max(1, min(reps, floor((budget - one)/(4*one))))
        do r = 1, pairs
            call run_block(cfg, chain, 1_int64, seconds, res, cpu=.true.)
            best_one = min(best_one, seconds)
            call run_block(cfg, chain, 2_int64, seconds, res, cpu=.true.)
            if (seconds < best_two) then
                best_two = seconds
                res_two = res
            end if
        end do
        call keep_best(row, 2*max(best_two - best_one, 0.0_wp), res_two)
        row%reps = pairs
    end subroutine time_by_difference

    !> Count one timed repetition; keep its counts if it is the fastest so far.
    subroutine keep_best(row, seconds, res)
        type(row_t), intent(inout) :: row
        real(wp), intent(in) :: seconds
        type(record_result_t), intent(in) :: res

        row%reps = row%reps + 1
        if (seconds >= row%seconds) return
        row%seconds = seconds
        row%cycles = res%cycles_done
        row%collisions = res%impacts
        if (size(res%site_counts) > 2) row%min_bond_share = &
            real(minval(res%site_counts), wp)/max(1.0_wp, sum(res%site_counts) &
                                                  /real(size(res%site_counts), wp))
    end subroutine keep_best

    !> Cases 1, 2 and 4: one chain, a transient, then timed record_cycles blocks.
    subroutine case_chain(row, label, n, amplitude, omega, damping, restitution, x_amp, &
                          v_amp, transient, vectors, emit_state, qr_every)
        type(row_t), intent(inout) :: row
        character(len=*), intent(in) :: label
        integer, intent(in) :: n, vectors
        real(wp), intent(in) :: amplitude, omega, damping, restitution, x_amp, v_amp
        integer(int64), intent(in) :: transient
        logical, intent(in), optional :: emit_state
        integer, intent(in), optional :: qr_every !! 0: adaptive (default: every cycle)
        type(config_t) :: cfg
        type(chain_t) :: chain
        type(record_result_t) :: res
        real(wp) :: seconds

        row%label = label
        row%n = n
        cfg = make_config(n, amplitude, omega, damping, restitution, x_amp, v_amp)
        chain = new_chain(cfg)
        call run_block(cfg, chain, transient, seconds, res)
        if (present(emit_state) .and. tsv) then
            if (emit_state) call print_state(chain)
        end if
        if (vectors > 0) then
            cfg%record%lyapunov = .true.
            cfg%record%vectors = vectors
            cfg%record%qr_every = 1
            if (present(qr_every)) cfg%record%qr_every = qr_every
        end if
        row%vectors = vectors
        call time_cycles(cfg, chain, row)
    end subroutine case_chain

    !> The Lyapunov rows of the scaling fit, all at the paper's default parameters (A = 1.7,
    !> w = 1.5, b = 0.05, K = 0.7, spacing 1), QR every cycle: the full spectrum (k = 2n) at
    !> n = 64, 256 and 1024, and k = 10, 64 and 256 leading exponents at n = 4096. The
    !> transient (without exponents) brings the chain onto its attractor; at n >= 256 the
    !> collisions stay near the walls, so the cost of a cycle is the frame's.
    subroutine case_spectrum(row, name)
        type(row_t), intent(inout) :: row
        character(len=*), intent(in) :: name
        integer :: n, k
        integer(int64) :: transient

        select case (name)
        case ('n64-full')
            n = 64
            k = 2*n
        case ('n256-full')
            n = 256
            k = 2*n
        case ('n1024-full')
            n = 1024
            k = 2*n
        case ('n4096-lyap10')
            n = 4096
            k = 10
        case ('n4096-lyap64')
            n = 4096
            k = 64
        case default
            n = 4096
            k = 256
        end select
        transient = 200
        if (k == 2*n) then
            row%label = 'paper default parameters, full spectrum ('//itoa(k)// &
                        ' exponents, QR every cycle)'
        else
            row%label = 'paper default parameters, '//itoa(k)//' leading exponents'
        end if
        call case_chain(row, row%label, n, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, 0.3_wp, 0.3_wp, &
                        transient, k)
    end subroutine case_spectrum

    !> Covariant Lyapunov vectors (docs/model.md section 14) of the full spectrum at the paper's
    !> default parameters against the spectrum alone on the same cycles: from the same state
    !> (after 200 cycles without exponents) `cycles` records, the last 200 without vectors
    !> (clv_transient), with covariant vectors (QR every record, the factors to scratch
    !> files, the backward pass with its per-record numbers kept in memory) and with the
    !> spectrum alone (adaptive QR, the default), timed alternately (a loaded machine slows
    !> both alike), 7 times, the best of each. The row is the covariant run's; the spectrum's time is
    !> its baseline, and the label gives their ratio.
    subroutine case_covariant(row, n, cycles)
        type(row_t), intent(inout) :: row
        integer, intent(in) :: n
        integer(int64), intent(in) :: cycles
        type(config_t) :: cfg
        type(chain_t) :: chain, copy
        type(record_result_t) :: res
        real(wp) :: seconds
        integer(int64) :: records
        integer :: r

        row%n = n
        row%vectors = 2*n
        cfg = make_config(n, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, 0.3_wp, 0.3_wp)
        chain = new_chain(cfg)
        call run_block(cfg, chain, 200_int64, seconds, res)
        cfg%record%lyapunov = .true.
        cfg%record%vectors = 2*n
        cfg%record%qr_every = 0
        cfg%record%clv_transient = 200
        records = cycles
        if (quick) then
            records = 250
            cfg%record%clv_transient = 50
        end if
        row%seconds = huge(1.0_wp)
        row%baseline_seconds = huge(1.0_wp)
        ! (2 reps + 1 alternations: runs of 40 ms at n = 16 have outliers on a shared machine)
        do r = 1, 2*reps + 1
            copy = chain
            cfg%record%covariant = .false.
            call run_block(cfg, copy, records, seconds, res)
            row%baseline_seconds = min(row%baseline_seconds, seconds)
            copy = chain
            cfg%record%covariant = .true.
            call run_block(cfg, copy, records, seconds, res)
            call keep_best(row, seconds, res)
        end do
        row%label = 'paper default, covariant vectors of all '//itoa(2*n)//' exponents ('// &
                    itoa(int(records))//' records, the last '// &
                    itoa(cfg%record%clv_transient)//' without vectors); '// &
                    trim(real_fmt(row%seconds/row%baseline_seconds))//' x the spectrum '// &
                    'alone (adaptive QR) on the same records'
    end subroutine case_covariant

    !> The yardsticks of bench_yardsticks, each measured here: ns per sin + cos + exp and the
    !> dgemm rate at n = 256 and 512, and a 512 x 512 QR with its Q.
    subroutine print_yardsticks()
        real(wp) :: ns, gflops, checksum, total, seconds
        integer :: m
        character(len=32) :: buf

        call transcendental_ns(min_time, reps, ns, total)
        call print_yardstick('sincos-exp', ns, 'ns per sin(y) + cos(y) + exp(-b y), '// &
                             'y varying')
        do m = 256, 512, 256
            call dgemm_gflops(m, min_time, reps, gflops, checksum)
            total = total + checksum
            call print_yardstick('dgemm-'//itoa(m), gflops, 'GFLOP/s of dgemm, '//itoa(m)// &
                                 ' x '//itoa(m)//', one core')
        end do
        call qr_seconds(512, min_time, reps, seconds, checksum)
        total = total + checksum
        call print_yardstick('qr-512', 1.0e3_wp*seconds, 'ms per QR of a 512 x 512 frame '// &
                             'with its Q (qr_orthonormalise: dgeqrf, then Q), one core')
        ! every result feeds this sum, so no call can be optimised away
        if (.not. (abs(total) < huge(1.0_wp))) call fail('yardsticks: result is not finite')
        write (buf, '(es12.4)') total
        if (.not. tsv) write (output_unit, '(a)') '(checksum '//trim(adjustl(buf))//')', ''
    end subroutine print_yardsticks

    subroutine print_yardstick(name, value, what)
        character(len=*), intent(in) :: name, what
        real(wp), intent(in) :: value
        character(len=32) :: buf

        write (buf, '(es24.16)') value
        if (tsv) then
            write (output_unit, '(a)') 'yardstick'//achar(9)//name//achar(9)// &
                trim(adjustl(buf))//achar(9)//what
        else
            write (buf, '(f0.3)') value
            write (output_unit, '(a)') 'Yardstick: '//trim(adjustl(buf))//' '//what
        end if
        flush (output_unit)
    end subroutine print_yardstick

    !> Case 3: a collision-heavy chain. With A = 0, b = 0 and K = 1 the chain conserves
    !> energy, so a random start with large velocities keeps every bond colliding for ever at
    !> a stationary rate, the same per bond for every n: the cost per collision can be
    !> compared across n. (With the drive on, b = 0 and K = 1 heat up through the walls, so
    !> the rate drifts; with b > 0 or K < 1 the interior of a long chain falls silent.)
    subroutine case_heavy(row, name)
        type(row_t), intent(inout) :: row
        character(len=*), intent(in) :: name
        integer :: n

        select case (name)
        case ('heavy-16')
            n = 16
        case ('heavy-1024')
            n = 1024
        case default
            n = 16384
        end select
        call case_chain(row, 'collision-heavy, conservative: A=0, b=0, K=1, random start '// &
                        'x_amp=0.3, v_amp=4', n, 0.0_wp, 1.5_wp, 0.0_wp, 1.0_wp, 0.3_wp, &
                        4.0_wp, 50_i8, 0)
    end subroutine case_heavy

    !> Issue #34's item 4, the cost per collision flat in n, measured on a shared machine: the
    !> collision-heavy chains at n = 16, 1024 and 16384 in one process, each block about the
    !> same number of collisions, timed alternately (`rounds` rounds) in the process's CPU time
    !> (other jobs' load stretches wall time, not CPU time); the best block of each n.
    subroutine heavy_flat(rounds)
        integer, intent(in) :: rounds
        integer, parameter :: sizes(3) = [16, 1024, 16384]
        type(config_t) :: cfg(3)
        type(chain_t) :: chains(3)
        type(record_result_t) :: res
        real(wp) :: seconds, best(3)
        integer(int64) :: cycles(3)
        integer :: j, r

        do j = 1, 3
            cfg(j) = make_config(sizes(j), 0.0_wp, 1.5_wp, 0.0_wp, 1.0_wp, 0.3_wp, 4.0_wp)
            chains(j) = new_chain(cfg(j))
            call run_block(cfg(j), chains(j), 50_i8, seconds, res)
            ! about 2 million collisions per block (62 per cycle at n = 16, 3.9 per bond)
            cycles(j) = max(1_int64, 2000000_int64/(4_int64*(sizes(j) + 1)))
        end do
        best = huge(1.0_wp)
        do r = 1, rounds
            do j = 1, 3
                call run_block(cfg(j), chains(j), cycles(j), seconds, res, cpu=.true.)
                best(j) = min(best(j), 1.0e9_wp*seconds/real(res%impacts, wp))
            end do
        end do
        write (output_unit, '(a)') '| n | CPU ns per collision (best of '//itoa(rounds)// &
            ' alternating blocks) | over n = 16 |', '|---:|---:|---:|'
        do j = 1, 3
            write (output_unit, '(a, i0, a, f0.1, a, f0.3, a)') '| ', sizes(j), ' | ', best(j), &
                ' | ', best(j)/best(1), ' |'
        end do
    end subroutine heavy_flat

    !> Issue #34's item 3, the paper's default case with all 32 exponents against the case
    !> without, measured like heavy_flat: from one state after the transient, the three runs
    !> (no exponents, adaptive QR, QR every cycle) timed alternately in CPU time, the best
    !> block of each.
    subroutine exponents_ratio(rounds)
        integer, intent(in) :: rounds
        character(len=*), parameter :: names(3) = [character(len=28) :: 'no exponents', &
            '32 exponents, adaptive QR', '32 exponents, QR every cycle']
        type(config_t) :: cfg(3)
        type(chain_t) :: chains(3)
        type(record_result_t) :: res
        real(wp) :: seconds, best(3)
        integer(int64), parameter :: cycles = 20000
        integer :: j, r

        cfg(1) = make_config(16, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, 0.3_wp, 0.3_wp)
        chains(1) = new_chain(cfg(1))
        call run_block(cfg(1), chains(1), 500_i8, seconds, res)
        do j = 2, 3
            cfg(j) = cfg(1)
            chains(j) = chains(1)
            cfg(j)%record%lyapunov = .true.
            cfg(j)%record%vectors = 32
            cfg(j)%record%qr_every = merge(0, 1, j == 2)
        end do
        best = huge(1.0_wp)
        do r = 1, rounds
            do j = 1, 3
                call run_block(cfg(j), chains(j), cycles, seconds, res, cpu=.true.)
                best(j) = min(best(j), 1.0e6_wp*seconds/real(res%cycles_done, wp))
            end do
        end do
        write (output_unit, '(a)') '| n = 16, paper default | CPU us per drive cycle (best of '// &
            itoa(rounds)//' alternating blocks) | over no exponents |', '|---|---:|---:|'
        do j = 1, 3
            write (output_unit, '(a, f0.2, a, f0.3, a)') '| '//trim(names(j))//' | ', best(j), &
                ' | ', best(j)/best(1), ' |'
        end do
    end subroutine exponents_ratio

    !> Figure 10 (n = 8, K = 0.5, w = 1.9, b = 0.05): A from 6 down to 1, 300 cycles per
    !> point of which the last 50 are kept, continuing each point from the previous one's
    !> final state. Step 0.01 instead of the figure's 0.001 (501 of its 5001 points: the same
    !> range, a tenth of the points).
    subroutine case_fig10(row)
        type(row_t), intent(inout) :: row
        integer, parameter :: points = 501
        integer :: r
        integer(int64) :: cycles, impacts, done
        real(wp) :: seconds, t0, best

        row%label = 'fig 10 sweep (n=8, K=0.5, w=1.9; A 6 -> 1 step 0.01, 300 cycles/point, '// &
                    'continuation)'
        row%n = 8
        row%unit_name = 'points'
        call fig10_pass(50, cycles, impacts)
        best = huge(1.0_wp)
        do r = 1, reps
            t0 = wall_seconds()
            done = 0
            row%cycles = 0
            row%collisions = 0
            do
                call fig10_pass(points, cycles, impacts)
                done = done + points
                row%cycles = row%cycles + cycles
                row%collisions = row%collisions + impacts
                seconds = wall_seconds() - t0
                if (seconds >= min_time) exit
            end do
            if (seconds < best) then
                best = seconds
                row%units = done
            end if
        end do
        row%seconds = best
    end subroutine case_fig10

    subroutine fig10_pass(points, cycles, impacts)
        integer, intent(in) :: points
        integer(int64), intent(out) :: cycles, impacts
        type(config_t) :: cfg
        type(chain_t) :: chain
        type(memory_sink_t) :: sink
        type(record_result_t) :: res
        type(error_t), allocatable :: err
        integer :: p

        cfg = make_config(8, 6.0_wp, 1.9_wp, 0.05_wp, 0.5_wp, 0.3_wp, 0.3_wp)
        cfg%record%transient = 250
        cfg%record%cycles = 50
        cycles = 0
        impacts = 0
        chain = new_chain(cfg)
        do p = 1, points
            cfg%model%amplitude = 6 - 0.01_wp*(p - 1)
            if (p > 1) then
                ! from the previous point's final state, every bond searched afresh
                call restart_chain(cfg, chain, err)
                if (allocated(err)) call fail(err%message)
            end if
            call record_cycles(cfg%record, chain, sink, res, err)
            if (allocated(err)) call fail(err%message)
            cycles = cycles + cfg%record%transient + cfg%record%cycles
            impacts = impacts + res%impacts
        end do
    end subroutine fig10_pass

    !> Figure 13 (n = 16, w = 1.9, b = 0.05, K = 0.7): all 32 exponents per point, 100
    !> An attractor census of figure 3's chain (n = 15, A = 2.2, w = 1.5, b = 0.05, K = 0.7):
    !> samples from random starts (x_amp = 0.3, v_amp = 1, as the figure's recipes), each
    !> 2000 transient and 500 recorded cycles with the largest exponent, then classified (two
    !> mirror-image period-8 patterns and a chaotic attractor). On one thread: samples per
    !> second per core (the samples run in parallel, so a census scales with the cores).
    subroutine case_census(row)
        type(row_t), intent(inout) :: row
        integer, parameter :: samples = 8
        type(config_t) :: cfg
        type(census_result_t) :: res
        type(error_t), allocatable :: err
        real(wp) :: t0, seconds, best
        integer :: r, done, pass

        row%label = 'census of fig 3 (n=15, A=2.2; 2000 + 500 cycles per sample with '// &
                    'lambda1, classified), one thread'
        row%n = 15
        row%unit_name = 'samples'
        cfg = make_config(15, 2.2_wp, 1.5_wp, 0.05_wp, 0.7_wp, 0.3_wp, 1.0_wp)
        cfg%record%transient = 2000
        cfg%record%cycles = 500
        cfg%census = .true.
        cfg%census_samples = samples
        cfg%census_x_amp = 0.3_wp
        cfg%census_v_amp = 1.0_wp
        cfg%census_mirror = 'merge'
        call validate_config(cfg, err)
        if (allocated(err)) call fail(err%message)
        !$ call omp_set_num_threads(1)
        ! warm-up: one census of other starts, untimed
        cfg%census_seed = 0
        call census_result_init(res, cfg)
        call run_census_samples(cfg, res, err)
        if (allocated(err)) call fail(err%message)
        best = huge(1.0_wp)
        do r = 1, reps
            t0 = wall_seconds()
            done = 0
            pass = 0
            do
                ! a new seed each pass: other starts, the same chain
                pass = pass + 1
                cfg%census_seed = pass
                call census_result_init(res, cfg)
                call run_census_samples(cfg, res, err)
                if (.not. allocated(err)) call classify_census(cfg, res, err)
                if (allocated(err)) call fail(err%message)
                done = done + samples
                seconds = wall_seconds() - t0
                if (seconds >= min_time) exit
            end do
            if (seconds < best) then
                best = seconds
                row%units = done
                row%cycles = done*(cfg%record%transient + cfg%record%cycles)
                ! (impacts are counted over the records: scaled to the whole sample)
                row%collisions = sum(res%sites)*(done/samples)* &
                                 (cfg%record%transient + cfg%record%cycles)/cfg%record%cycles
            end if
        end do
        row%seconds = best
    end subroutine case_census

    !> Continuation points of a branch of periodic orbits: figure 10's parameters (w = 1.9,
    !> K = 0.5) on n oscillators at A = 3, the period-1 orbit reached from rest in 300 cycles,
    !> followed down in A (step -0.01) as a fixed point of P^p; p = 8 at n = 64 (the period-1
    !> orbit as a period-8 one: the shooting, Jacobian and parameter column of 8 cycles, as for
    !> a true period-8 orbit with the same impacts per cycle). Each point: Newton's corrector
    !> (each iterate one pass with the 2n x 2n Jacobian and one with the parameter column), the
    !> tangent, the multipliers (dgeev) and the gap monitor.
    subroutine case_orbit(row, n, period)
        type(row_t), intent(inout) :: row
        integer, intent(in) :: n, period
        integer, parameter :: points = 6
        type(config_t) :: cfg
        type(branch_options_t) :: opt
        type(branches_t) :: res
        type(error_t), allocatable :: err
        real(wp), allocatable :: x(:), v(:)
        real(wp) :: t0, seconds, best
        integer :: r, done

        row%label = 'continuation points of a period-'//fmt_int(period)//' orbit (fig. 10 '// &
                    'parameters, A = 3 down, step 0.01; exact Jacobian and parameter column)'
        row%n = n
        row%unit_name = 'points'
        cfg = make_config(n, 3.0_wp, 1.9_wp, 0.05_wp, 0.5_wp, 0.0_wp, 0.0_wp)
        cfg%record%transient = 300
        call continuation_guess(cfg, x, v, err)
        if (allocated(err)) call fail(err%message)
        opt%parameter = 'amplitude'
        opt%stop = 1
        opt%step = -0.01_wp
        opt%max_points = points
        best = huge(1.0_wp)
        do r = 1, reps
            t0 = wall_seconds()
            done = 0
            do
                call follow_branches(cfg%model, 0.0_wp, period, x, v, opt, res, err)
                if (allocated(err)) call fail(err%message)
                if (res%n_points < 2) call fail('orbit case: the branch has '// &
                                                fmt_int(res%n_points)//' points: '// &
                                                res%end_reason)
                done = done + res%n_points
                seconds = wall_seconds() - t0
                if (seconds >= min_time) exit
            end do
            if (seconds < best) then
                best = seconds
                row%units = done
            end if
        end do
        row%seconds = best
    end subroutine case_orbit

    !> transient + 300 averaged cycles, each point from the same seeded start. The paper does
    !> not give the A range; A = 1.0 .. 3.0 step 0.05 (41 points) stands in for it.
    subroutine case_fig13(row)
        type(row_t), intent(inout) :: row
        integer, parameter :: points = 41
        integer :: r
        integer(int64) :: cycles, impacts, done
        real(wp) :: seconds, t0, best

        row%label = 'fig 13 scan (n=16, w=1.9, 32 exponents; A 1.0 -> 3.0 step 0.05, '// &
                    '100 + 300 cycles/point, independent)'
        row%n = 16
        row%unit_name = 'points'
        call fig13_pass(5, cycles, impacts)
        best = huge(1.0_wp)
        do r = 1, reps
            t0 = wall_seconds()
            done = 0
            row%cycles = 0
            row%collisions = 0
            do
                call fig13_pass(points, cycles, impacts)
                done = done + points
                row%cycles = row%cycles + cycles
                row%collisions = row%collisions + impacts
                seconds = wall_seconds() - t0
                if (seconds >= min_time) exit
            end do
            if (seconds < best) then
                best = seconds
                row%units = done
            end if
        end do
        row%seconds = best
    end subroutine case_fig13

    subroutine fig13_pass(points, cycles, impacts)
        integer, intent(in) :: points
        integer(int64), intent(out) :: cycles, impacts
        type(config_t) :: cfg
        type(chain_t) :: chain
        type(memory_sink_t) :: sink
        type(record_result_t) :: res
        type(error_t), allocatable :: err
        integer :: p

        cfg = make_config(16, 1.0_wp, 1.9_wp, 0.05_wp, 0.7_wp, 0.3_wp, 0.3_wp)
        cfg%record%transient = 100
        cfg%record%cycles = 300
        cfg%record%lyapunov = .true.
        cfg%record%vectors = 0
        cfg%record%qr_every = 1
        sink%keep_strobe = .false.
        cycles = 0
        impacts = 0
        do p = 1, points
            cfg%model%amplitude = 1 + 0.05_wp*(p - 1)
            chain = new_chain(cfg)
            call record_cycles(cfg%record, chain, sink, res, err)
            if (allocated(err)) call fail(err%message)
            cycles = cycles + cfg%record%transient + cfg%record%cycles
            impacts = impacts + res%impacts
        end do
    end subroutine fig13_pass

    !> A strobe snapshot on its own: bring every oscillator to one time (`advance_to_point`,
    !> which ends in the engine's sync) and copy x and v out, for n = 100000 with a drive too
    !> weak for any impact. Snapshots are taken at 16 times within each cycle so every one of
    !> them finds every oscillator out of date.
    subroutine case_strobe(row)
        type(row_t), intent(inout) :: row
        integer, parameter :: n = 100000, per_cycle = 16
        type(config_t) :: cfg
        type(chain_t) :: chain
        type(event_log_t) :: log  ! (disabled: no event is logged)
        type(event_counts_t) :: counts
        type(error_t), allocatable :: err
        real(wp), allocatable :: xs(:), vs(:)
        real(wp) :: elapsed, t0, best, checksum, period
        integer(int64) :: snaps
        integer :: r, k

        row%label = 'strobe snapshot: sync + copy x, v (A=1e-3, no impacts)'
        row%n = n
        row%unit_name = 'oscillator snapshot'
        cfg = make_config(n, 1.0e-3_wp, 1.5_wp, 0.05_wp, 0.7_wp, 0.0_wp, 0.0_wp)
        chain = new_chain(cfg)
        period = chain_period(chain)
        allocate (xs(n), vs(n))
        checksum = 0
        best = huge(1.0_wp)
        do r = 0, reps
            elapsed = 0
            snaps = 0
            do while (elapsed < merge(0.2_wp, 1.0_wp, r == 0)*min_time)
                do k = 1, per_cycle
                    t0 = wall_seconds()
                    call advance_to_point(chain, chain_cycle(chain), &
                                          k*period/(per_cycle + 1), log, err)
                    call chain_copy_state(chain, xs, vs)
                    elapsed = elapsed + (wall_seconds() - t0)
                    if (allocated(err)) call fail(err%message)
                    checksum = checksum + xs(n/2) + vs(1)
                end do
                snaps = snaps + per_cycle
                call advance_to_point(chain, chain_cycle(chain) + 1, 0.0_wp, log, err)
                if (allocated(err)) call fail(err%message)
            end do
            if (r > 0 .and. elapsed < best) then
                best = elapsed
                row%units = snaps*n
                row%cycles = 0
                counts = chain_counts(chain)
                row%collisions = counts%impacts
            end if
        end do
        row%seconds = best
        if (.not. (abs(checksum) < huge(1.0_wp))) call fail('strobe: state is not finite')
    end subroutine case_strobe

    !> What one strobe record costs inside `record_cycles` for the same n = 100000 chain: the
    !> sync at the end of each cycle plus the copies into the record buffer and the
    !> period-detection window.
    subroutine case_strobe_record(row)
        type(row_t), intent(inout) :: row
        integer, parameter :: n = 100000
        type(config_t) :: cfg
        type(chain_t) :: chain
        type(record_result_t) :: res
        real(wp) :: seconds

        row%label = 'strobe record inside record_cycles (same chain, one record per cycle)'
        row%n = n
        row%unit_name = 'oscillator record'
        cfg = make_config(n, 1.0e-3_wp, 1.5_wp, 0.05_wp, 0.7_wp, 0.0_wp, 0.0_wp)
        chain = new_chain(cfg)
        call run_block(cfg, chain, 2_i8, seconds, res)
        call time_cycles(cfg, chain, row)
        row%units = row%cycles*n
    end subroutine case_strobe_record

    !> The chain's state on the section, for the scipy baseline of run_bench.py.
    subroutine print_state(chain)
        type(chain_t), intent(in) :: chain
        integer :: i
        character(len=32) :: buf
        character(len=:), allocatable :: line
        real(wp), allocatable :: z(:)

        if (any(chain_contacts(chain) /= 0)) call fail('default case: an oscillator rests on '// &
                                                       'a wall at the baseline start')
        z = [chain_positions(chain), chain_velocities(chain)]
        line = 'state'
        do i = 1, size(z)
            write (buf, '(es24.16)') z(i)
            line = line//achar(9)//trim(adjustl(buf))
        end do
        write (output_unit, '(a)') line
    end subroutine print_state

    subroutine parse_arguments(only, tsv, quick, yardsticks_only, provenance_only, flat_only, &
                               ratio_only, curve_only)
        character(len=:), allocatable, intent(out) :: only
        logical, intent(out) :: tsv, quick, yardsticks_only, provenance_only, flat_only
        logical, intent(out) :: ratio_only, curve_only
        integer :: j, length
        character(len=:), allocatable :: arg
        logical :: want_case

        only = ''
        tsv = .false.
        provenance_only = .false.
        flat_only = .false.
        ratio_only = .false.
        curve_only = .false.
        quick = .false.
        yardsticks_only = .false.
        want_case = .false.
        do j = 1, command_argument_count()
            call get_command_argument(j, length=length)
            allocate (character(len=length) :: arg)
            call get_command_argument(j, arg)
            if (want_case) then
                if (.not. any(case_names == arg)) call fail("unknown case '"//arg// &
                                                            "' (see --list)")
                only = arg
                want_case = .false.
            else
                select case (arg)
                case ('--case')
                    want_case = .true.
                case ('--tsv')
                    tsv = .true.
                case ('--quick')
                    quick = .true.
                case ('--yardsticks')
                    yardsticks_only = .true.
                case ('--provenance')
                    provenance_only = .true.
                case ('--flat')
                    flat_only = .true.
                case ('--ratio')
                    ratio_only = .true.
                case ('--curve')
                    curve_only = .true.
                case ('--list')
                    do length = 1, size(case_names)
                        write (output_unit, '(a)') trim(case_names(length))
                    end do
                    stop
                case ('-h', '--help')
                    write (output_unit, '(a)') 'usage: impactchain-bench [--case NAME] '// &
                        '[--yardsticks] [--tsv] [--quick] [--list]', &
                        '  Times the engine and prints a Markdown table (see bench/README.md);', &
                        '  --yardsticks: only the yardsticks (sin+cos+exp, dgemm, QR).', &
                        '  --provenance: only where it runs (compiler, BLAS, kernels, CPU).', &
                        '  --flat: the collision-heavy chains at n = 16, 1024, 16384 in one', &
                        '          process, timed alternately in CPU time: ns per collision', &
                        '  --ratio: the paper default case with all 32 exponents (adaptive QR,', &
                        '          and QR every cycle) over the case without, the same way', &
                        '  --curve: one point of a fold curve in (A, w) over one Newton solve', &
                        '          at n = 8 and 16, the same way'
                    stop
                case default
                    call fail("unknown argument '"//arg//"' (see --help)")
                end select
            end if
            deallocate (arg)
        end do
        if (want_case) call fail('--case needs a name (see --list)')
    end subroutine parse_arguments

    pure function itoa(i) result(text)
        integer, intent(in) :: i
        character(len=:), allocatable :: text
        character(len=16) :: buf

        write (buf, '(i0)') i
        text = trim(buf)
    end function itoa

    pure function real_fmt(x) result(text)
        real(wp), intent(in) :: x
        character(len=32) :: text

        write (text, '(f0.2)') x
        if (text(1:1) == '.') text = '0'//text
    end function real_fmt

    subroutine fail(message)
        character(len=*), intent(in) :: message

        write (error_unit, '(a)') 'impactchain-bench: error: '//message
        error stop 1
    end subroutine fail

end program bench
