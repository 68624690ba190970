!> One run from a configuration: initial state, transient, recorded cycles with strobe records,
!> events, Lyapunov spectrum, Floquet multipliers, periods, and the HDF5 file (MODEL.md
!> section 5 for the section and the spectrum).
!>
!> Strobe record j (j = 1..cycles) is the state at elapsed time (transient + j) T + delta, with
!> delta the offset from the initial drive phase to the section phase (0 for a fresh run with
!> phase = 0). The library never prints: progress goes to an optional callback, which may also
!> ask the run to stop (the file is then kept, marked complete = 0).
module chain_sim
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error
    use chain_flow, only: flow_t, make_flow
    use chain_engine, only: chain_t, chain_init, chain_advance, chain_sync, chain_new_cycle, &
                            chain_set_tangent, contact_free
    use chain_events, only: event_log_t, event_log_init, event_log_clear
    use chain_lyapunov, only: lyapunov_acc_t, lyapunov_start, lyapunov_step, &
                              lyapunov_result_t, lyapunov_result, floquet_multipliers
    use chain_period, only: detect_period
    use chain_config, only: run_config_t, config_summary, fmt_real
    use chain_output, only: output_t, output_begin, output_header, output_strobe_write, &
                            output_events_append, output_final, output_stats, output_periods, &
                            output_lyapunov, output_jacobian, output_end, output_abort, &
                            read_final_state
    implicit none
    private
    public :: run_simulation, run_summary_t, initial_state, section_target, advance_to_point
    public :: poincare_jacobian, start_chain, progress_callback, period_window

    !> Records kept in memory for period detection (the last ones of the run).
    integer, parameter :: period_window = 1024
    integer, parameter :: event_flush = 65536

    abstract interface
        !> Called after every strobe record; return .false. to stop the run early.
        function progress_callback(done, total) result(keep_going)
            import :: i8
            integer(i8), intent(in) :: done, total
            logical :: keep_going
        end function progress_callback
    end interface

    type :: run_summary_t
        integer(i8) :: cycles_done = 0
        real(wp) :: collisions_per_cycle = 0
        integer(i8) :: impacts = 0, sticks = 0, releases = 0
        logical :: complete = .false.
        character(len=:), allocatable :: output_file
        real(wp), allocatable :: exponents(:)
    end type run_summary_t

contains

    !> The initial state of a configuration (rest, seeded random, explicit, or an earlier run).
    subroutine initial_state(cfg, x, v, cycle, s, contact, queue_time, queue_action, err)
        type(run_config_t), intent(in) :: cfg
        real(wp), allocatable, intent(out) :: x(:), v(:), queue_time(:)
        integer(i8), intent(out) :: cycle
        real(wp), intent(out) :: s
        integer, allocatable, intent(out) :: contact(:), queue_action(:)
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: state
        integer :: i
        real(wp) :: phase

        cycle = 0
        s = 0
        allocate (x(cfg%n), v(cfg%n), contact(cfg%n))
        x = 0
        v = 0
        contact = contact_free
        select case (cfg%initial_kind)
        case ('random')
            state = seed_state(cfg%seed)
            do i = 1, cfg%n
                x(i) = cfg%x_amp*(2*uniform(state) - 1)
                v(i) = cfg%v_amp*(2*uniform(state) - 1)
            end do
        case ('explicit')
            x = cfg%x0
            if (size(cfg%v0) == cfg%n) v = cfg%v0
        case ('file')
            call read_final_state(cfg%initial_file, cfg%n, x, v, cycle, phase, contact, &
                                  queue_time, queue_action, s, err)
        end select
    end subroutine initial_state

    !> A chain ready to run from the configuration's initial state.
    subroutine start_chain(cfg, chain, err)
        type(run_config_t), intent(in) :: cfg
        type(chain_t), intent(out) :: chain
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: x(:), v(:), queue_time(:)
        integer, allocatable :: contact(:), queue_action(:)
        integer(i8) :: cycle
        real(wp) :: s
        type(flow_t) :: flow

        call initial_state(cfg, x, v, cycle, s, contact, queue_time, queue_action, err)
        if (allocated(err)) return
        flow = make_flow(cfg%damping, cfg%amplitude, cfg%omega)
        if (allocated(queue_time)) then
            call chain_init(chain, flow, cfg%restitution, cfg%spacing, cfg%boundary == 'fixed', &
                            cfg%stick_speed, x, v, cycle, s, err, contact, queue_time, &
                            queue_action)
        else
            call chain_init(chain, flow, cfg%restitution, cfg%spacing, cfg%boundary == 'fixed', &
                            cfg%stick_speed, x, v, cycle, s, err, contact)
        end if
    end subroutine start_chain

    !> Cycle and in-cycle time of strobe point j (j = 0: the end of the transient).
    pure subroutine section_target(chain, transient, phase, j, cycle, s)
        type(chain_t), intent(in) :: chain
        integer(i8), intent(in) :: transient, j
        real(wp), intent(in) :: phase
        integer(i8), intent(out) :: cycle
        real(wp), intent(out) :: s
        real(wp) :: s_section, period

        period = chain%flow%period
        s_section = phase/chain%flow%omega
        cycle = chain%start_cycle + transient + j
        s = s_section
        ! the start is already on the section (a continued run): keep its exact time
        if (abs(s_section - chain%start_s) <= 1.0e-12_wp*period) then
            s = chain%start_s
        else if (s_section < chain%start_s) then
            cycle = cycle + 1
        end if
    end subroutine section_target

    !> Run the chain to (cycle, s) and bring every oscillator there.
    subroutine advance_to_point(chain, cycle, s, log, err)
        type(chain_t), intent(inout) :: chain
        integer(i8), intent(in) :: cycle
        real(wp), intent(in) :: s
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err

        do while (chain%cycle < cycle)
            call chain_advance(chain, chain%flow%period, log, err)
            if (allocated(err)) return
            call chain_new_cycle(chain)
        end do
        call chain_advance(chain, s, log, err)
        if (allocated(err)) return
        call chain_sync(chain)
    end subroutine advance_to_point

    !> Jacobian (2n x 2n) of the p-cycle Poincare map at the chain's current (synced) state;
    !> the chain itself is not moved.
    subroutine poincare_jacobian(chain, cycles, jacobian, err)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: cycles
        real(wp), allocatable, intent(out) :: jacobian(:, :)
        type(error_t), allocatable, intent(out) :: err
        type(chain_t) :: copy
        type(event_log_t) :: log
        real(wp), allocatable :: frame(:, :)
        integer :: i, m
        integer(i8) :: target_cycle

        copy = chain
        m = 2*chain%n
        allocate (frame(m, m))
        frame = 0
        do i = 1, m
            frame(i, i) = 1
        end do
        call chain_set_tangent(copy, frame)
        call event_log_init(log, .false., 0)
        target_cycle = copy%cycle + cycles
        call advance_to_point(copy, target_cycle, copy%s, log, err)
        if (allocated(err)) return
        jacobian = transpose(copy%tangent)
    end subroutine poincare_jacobian

    !> The whole run described by `cfg`, written to cfg%output_file.
    subroutine run_simulation(cfg, summary, err, progress)
        type(run_config_t), intent(in) :: cfg
        type(run_summary_t), intent(out) :: summary
        type(error_t), allocatable, intent(out) :: err
        procedure(progress_callback), optional :: progress
        type(chain_t) :: chain
        type(output_t) :: out
        type(error_t), allocatable :: err2

        call check_size(cfg, err)
        if (allocated(err)) return
        call start_chain(cfg, chain, err)
        if (allocated(err)) return
        call output_begin(out, cfg%output_file, cfg%overwrite, err)
        if (allocated(err)) return
        summary%output_file = cfg%output_file
        call output_header(out, cfg%input_text, config_summary(cfg), cfg%n, cfg%spacing, &
                           cfg%damping, cfg%restitution, cfg%amplitude, cfg%omega, &
                           cfg%boundary, chain%flow%period, cfg%phase, cfg%transient, &
                           cfg%cycles, chain%x, chain%v, err)
        if (.not. allocated(err)) call record_run(cfg, chain, out, summary, err, progress)
        if (allocated(err)) then
            call output_abort(out)
            return
        end if
        call output_end(out, summary%complete, err2)
        if (allocated(err2)) call move_alloc(err2, err)
    end subroutine run_simulation

    subroutine record_run(cfg, chain, out, summary, err, progress)
        type(run_config_t), intent(in) :: cfg
        type(chain_t), intent(inout) :: chain
        type(output_t), intent(inout) :: out
        type(run_summary_t), intent(inout) :: summary
        type(error_t), allocatable, intent(out) :: err
        procedure(progress_callback), optional :: progress
        type(event_log_t) :: log
        type(lyapunov_acc_t) :: acc
        type(lyapunov_result_t) :: lyap
        real(wp), allocatable :: xbuf(:, :), vbuf(:, :), xwin(:, :), vwin(:, :), frame(:, :)
        integer(i8), allocatable :: cbuf(:)
        integer(i8) :: j, target_cycle, first
        real(wp) :: target_s
        integer :: m, k, info, i, nwin, w
        integer, allocatable :: periods(:)

        call event_log_init(log, .false., 0)
        call section_target(chain, cfg%transient, cfg%phase, 0_i8, target_cycle, target_s)
        call advance_to_point(chain, target_cycle, target_s, log, err)
        if (allocated(err)) return
        call event_log_init(log, cfg%record_events, 1024)
        chain%impacts = 0
        chain%sticks = 0
        chain%releases = 0
        chain%site_counts = 0
        k = 0
        if (cfg%lyapunov) then
            k = cfg%vectors
            if (k == 0) k = 2*cfg%n
            allocate (frame(2*cfg%n, k))
            frame = 0
            do i = 1, k
                frame(i, i) = 1
            end do
            call chain_set_tangent(chain, frame)
            call lyapunov_start(acc, k, int(cfg%cycles/cfg%qr_every))
        end if
        m = int(max(1_i8, min(cfg%cycles, int(2**20/cfg%n, i8))))
        allocate (xbuf(cfg%n, m), vbuf(cfg%n, m), cbuf(m))
        nwin = int(min(cfg%cycles, int(period_window, i8)))
        allocate (xwin(nwin, cfg%n), vwin(nwin, cfg%n))
        first = 1
        do j = 1, cfg%cycles
            call section_target(chain, cfg%transient, cfg%phase, j, target_cycle, target_s)
            call advance_to_point(chain, target_cycle, target_s, log, err)
            if (allocated(err)) return
            i = int(j - first) + 1
            xbuf(:, i) = chain%x
            vbuf(:, i) = chain%v
            cbuf(i) = chain%cycle
            w = int(modulo(j - 1, int(nwin, i8))) + 1
            xwin(w, :) = chain%x
            vwin(w, :) = chain%v
            if (cfg%lyapunov .and. modulo(j, int(cfg%qr_every, i8)) == 0) then
                call lyapunov_step(acc, chain%tangent, info)
                if (info /= 0) then
                    call set_error(err, "lyapunov: QR factorisation failed (LAPACK info "// &
                                   fmt_real(real(info, wp))//")")
                    return
                end if
            end if
            summary%cycles_done = j
            if (i == m .or. j == cfg%cycles .or. log%count >= event_flush) then
                call flush_records(out, cfg%cycles, first, xbuf(:, :i), vbuf(:, :i), &
                                   cbuf(:i), log, err)
                if (allocated(err)) return
                first = j + 1
            end if
            if (present(progress)) then
                if (.not. progress(j, cfg%cycles)) then
                    if (i /= m .and. j /= cfg%cycles .and. first <= j) then
                        call flush_records(out, cfg%cycles, first, xbuf(:, :i), &
                                           vbuf(:, :i), cbuf(:i), log, err)
                        if (allocated(err)) return
                    end if
                    exit
                end if
            end if
        end do
        summary%complete = summary%cycles_done == cfg%cycles
        summary%impacts = chain%impacts
        summary%sticks = chain%sticks
        summary%releases = chain%releases
        summary%collisions_per_cycle = real(chain%impacts, wp)/max(1_i8, summary%cycles_done)
        call output_final(out, chain%x, chain%v, chain%cycle, chain%s*chain%flow%omega, &
                          chain%s, chain%contact, chain%queue%time, chain%action, err)
        if (allocated(err)) return
        call output_stats(out, summary%collisions_per_cycle, chain%impacts, chain%sticks, &
                          chain%releases, chain%site_counts, err)
        if (allocated(err)) return
        if (summary%cycles_done > 0) then
            nwin = int(min(summary%cycles_done, int(nwin, i8)))
            allocate (periods(cfg%n))
            do i = 1, cfg%n
                periods(i) = detect_period(in_order(xwin(:, i), summary%cycles_done, nwin), &
                                           in_order(vwin(:, i), summary%cycles_done, nwin), &
                                           cfg%max_period, cfg%period_tol)
            end do
            call output_periods(out, periods, err)
            if (allocated(err)) return
        end if
        if (cfg%lyapunov .and. acc%steps > 0) then
            lyap = lyapunov_result(acc, cfg%qr_every, chain%flow%period)
            summary%exponents = lyap%bits_per_cycle
            call output_lyapunov(out, lyap%bits_per_cycle, lyap%nats_per_time, lyap%stderr_bits, &
                                 lyap%running_bits, lyap%ky_dimension, lyap%positive_sum, &
                                 summary%collisions_per_cycle, err)
            if (allocated(err)) return
        end if
        if (cfg%jacobian) call write_floquet(cfg, chain, out, err)
    end subroutine record_run

    subroutine write_floquet(cfg, chain, out, err)
        type(run_config_t), intent(in) :: cfg
        type(chain_t), intent(in) :: chain
        type(output_t), intent(inout) :: out
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: jac(:, :), re(:), im(:)
        integer :: info

        call poincare_jacobian(chain, cfg%jacobian_cycles, jac, err)
        if (allocated(err)) return
        allocate (re(size(jac, 1)), im(size(jac, 1)))
        call floquet_multipliers(jac, re, im, info)
        if (info /= 0) then
            call set_error(err, "floquet: the eigenvalue solver (LAPACK dgeev) failed")
            return
        end if
        call output_jacobian(out, jac, re, im, cfg%jacobian_cycles, err)
    end subroutine write_floquet

    subroutine flush_records(out, n_records, first, x, v, cycle, log, err)
        type(output_t), intent(inout) :: out
        integer(i8), intent(in) :: n_records, first
        real(wp), intent(in) :: x(:, :), v(:, :)
        integer(i8), intent(in) :: cycle(:)
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err

        call output_strobe_write(out, n_records, first, x, v, cycle, err)
        if (allocated(err)) return
        if (log%enabled) then
            call output_events_append(out, log%time(:log%count), log%site(:log%count), &
                                      log%speed(:log%count), log%kind(:log%count), err)
            call event_log_clear(log)
        end if
    end subroutine flush_records

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

    !> Refuse, before anything is written, records larger than &output max_size_mb.
    subroutine check_size(cfg, err)
        type(run_config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: mb
        integer :: k

        k = 0
        if (cfg%lyapunov) k = merge(2*cfg%n, cfg%vectors, cfg%vectors == 0)
        mb = (16.0_wp*cfg%n + 8)*real(cfg%cycles, wp)/1.0e6_wp &
             + 8.0_wp*k*real(cfg%cycles/cfg%qr_every, wp)/1.0e6_wp
        if (mb > cfg%max_size_mb) then
            call set_error(err, "&output: the strobe records of this run need about "// &
                           fmt_real(mb)//" MB (n x cycles x 16 bytes, plus Lyapunov "// &
                           "estimates), more than max_size_mb = "//fmt_real(cfg%max_size_mb)// &
                           "; lower &run cycles or raise &output max_size_mb")
        end if
    end subroutine check_size

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
