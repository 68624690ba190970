!> Support for the f2py layer (`impactchain_f2py.f90`); f2py never sees this module.
!>
!> It turns plain arguments into namelist text read by the CLI's own reader, so that the
!> configuration, its checks and their messages are the CLI's; it provides a record sink
!> that writes strobe records and events straight into arrays owned by the caller (numpy); and
!> it copies error messages into a buffer of byte values; it shares a small control array with
!> the Python caller during a call (stop requests, progress). There is no physics here: every
!> number comes from `chain_record` / `chain_sweep`, exactly as for the CLI.
module chain_bridge
    use, intrinsic :: iso_c_binding, only: c_int, c_int64_t, c_double
    use impactchain, only: wp, i8, error_t, config_t, lyapunov_vectors, event_log_t, chain_t, &
                           record_sink_t, record_result_t, chain_copy_state, monitor_t, &
                           stage_events, branches_t
    use impactchain_drivers, only: set_error, fmt_real, fmt_int, fmt_int8, read_config_text, &
                                   exact, exact_list, fmt_logical, namelist_string, &
                                   continuation_table_t, finite_or_inf, curve_table_t
    !$ use omp_lib, only: omp_set_num_threads
    implicit none
    private
    public :: array_sink_t, shared_monitor_t, make_config, sweep_group, continuation_group
    public :: put_message, put_text
    public :: run_sizes_ok, put_run_results, put_continuation_results, use_threads
    public :: put_curve_results
    public :: call_ended
    public :: status_ok, status_invalid, status_failed, status_capacity, status_internal
    public :: status_stopped, message_capacity

    integer(c_int), parameter :: status_ok = 0        !! success
    integer(c_int), parameter :: status_invalid = 1   !! a bad argument (Python: ValueError)
    integer(c_int), parameter :: status_failed = 2    !! the run itself failed (RuntimeError)
    integer(c_int), parameter :: status_capacity = 3  !! the event buffer is too small
    integer(c_int), parameter :: status_internal = 4  !! the caller broke the layer's protocol
    integer(c_int), parameter :: status_stopped = 5   !! the caller asked to stop (control(1))
    integer, parameter :: message_capacity = 1024     !! bytes of the message buffer

    !> Strobe records and events go straight into the caller's arrays (pointers valid during
    !> one layer call only). Events beyond the capacity are counted but not stored, so memory
    !> stays bounded by what the caller allocated; the caller retries with the full count.
    type, extends(record_sink_t) :: array_sink_t
        real(wp), pointer :: x(:, :) => null()      !! x(n, cycles), or size 0: not kept
        real(wp), pointer :: v(:, :) => null()
        integer(i8), pointer :: cycle(:) => null()  !! cycle(cycles)
        real(wp), pointer :: time(:) => null()      !! time(capacity)
        real(wp), pointer :: speed(:) => null()
        integer, pointer :: site(:) => null()
        integer, pointer :: kind(:) => null()
        integer(i8) :: n_events = 0                 !! events seen so far (may exceed capacity)
        real(wp), pointer :: windows(:, :) => null() !! windows(k, n_windows): finite-time
                                                     !! exponents, bits per drive cycle
        integer(i8), pointer :: window_cycle(:) => null() !! (n_windows) cycle at each end
    contains
        procedure :: put_strobe => array_put_strobe
        procedure :: put_events => array_put_events
        procedure :: put_windows => array_put_windows
        procedure :: attach => array_attach
    end type array_sink_t

    !> A control array shared with the caller while a call runs (the Python layer polls it from
    !> another thread; pointer valid during one layer call only): the caller sets control(1) to
    !> a nonzero value to ask for a stop; the layer writes control(2) the stage
    !> (chain_monitor's stage_*), control(3) the units done and control(4) their total.
    type, extends(monitor_t) :: shared_monitor_t
        integer(c_int64_t), pointer :: control(:) => null()
    contains
        procedure :: keep_going => shared_keep_going
    end type shared_monitor_t

contains

    logical function shared_keep_going(monitor, stage, done, total) result(keep_going)
        class(shared_monitor_t), intent(inout) :: monitor
        integer, intent(in) :: stage
        integer(i8), intent(in) :: done, total
        ! volatile: the other thread's write must be seen at every call
        integer(c_int64_t), pointer, volatile :: control(:)

        control => monitor%control
        keep_going = control(1) == 0
        ! (within a cycle only the stop is looked at: the count stays the caller's)
        if (stage == stage_events) return
        control(2) = stage
        control(3) = done
        control(4) = total
        keep_going = control(1) == 0
    end function shared_keep_going

    !> After a watched call: status 5 when the caller asked to stop (whatever the library said
    !> then: a stop in the transient is an error there), else 2 with the library's message
    !> when it failed. .true. in either case.
    logical function call_ended(control, err, status, msg_len, message) result(ended)
        integer(c_int64_t), intent(in) :: control(:)
        type(error_t), allocatable, intent(in) :: err
        integer(c_int), intent(inout) :: status, msg_len !! (unchanged when not ended)
        integer(c_int), intent(inout) :: message(:)

        ended = control(1) /= 0 .or. allocated(err)
        if (control(1) /= 0) then
            call put_message("stopped at the caller's request", status_stopped, status, &
                             msg_len, message)
        else if (allocated(err)) then
            call put_message(err%message, status_failed, status, msg_len, message)
        end if
    end function call_ended

    !> OpenMP threads for the sweeps of this call's thread: `threads` > 0, or the default
    !> (OMP_NUM_THREADS, else every core) for 0.
    subroutine use_threads(threads)
        integer, intent(in) :: threads

        !$ if (threads > 0) call omp_set_num_threads(threads)
    end subroutine use_threads

    !> The &sweep group with these values (names as byte values, lower case; parameter2
    !> empty for a 1-D sweep), for make_config's `groups`.
    function sweep_group(parameter, start, stop, step, mode, parameter2, start2, stop2, &
                         step2) result(text)
        integer(c_int), intent(in) :: parameter(:), mode(:), parameter2(:)
        real(wp), intent(in) :: start, stop, step, start2, stop2, step2
        character(len=:), allocatable :: text

        !$omp critical (chain_bridge_config_text)
        text = "&sweep parameter = "//namelist_string(text_of(parameter))//", start = "// &
               exact(start)//", stop = "//exact(stop)//", step = "//exact(step)//", mode = "// &
               namelist_string(text_of(mode))
        if (len_trim(text_of(parameter2)) > 0) text = text//", parameter2 = "// &
            namelist_string(text_of(parameter2))//", start2 = "//exact(start2)//", stop2 = "// &
            exact(stop2)//", step2 = "//exact(step2)
        text = text//" /"//new_line('a')
        !$omp end critical (chain_bridge_config_text)
    end function sweep_group

    !> The &continuation group with these values (the parameter's name as byte values, lower
    !> case), for make_config's `groups`.
    function continuation_group(parameter, stop, step, period, max_points, doublings) &
        result(text)
        integer(c_int), intent(in) :: parameter(:)
        real(wp), intent(in) :: stop, step
        integer, intent(in) :: period, max_points, doublings
        character(len=:), allocatable :: text

        !$omp critical (chain_bridge_config_text)
        text = "&continuation parameter = "//namelist_string(text_of(parameter))// &
               ", stop = "//exact(stop)//", step = "//exact(step)//", period = "// &
               fmt_int(period)//", max_points = "//fmt_int(max_points)//", doublings = "// &
               fmt_int(doublings)//" /"//new_line('a')
        !$omp end critical (chain_bridge_config_text)
    end function continuation_group

    !> Byte values 0..255 as text.
    pure function text_of(bytes) result(text)
        integer(c_int), intent(in) :: bytes(:)
        character(len=size(bytes)) :: text
        integer :: j

        do j = 1, size(bytes)
            text(j:j) = achar(iand(int(bytes(j)), 255))
        end do
    end function text_of

    !> The lines of `text` (none for empty text), as a list of equal length.
    pure function lines_of(text) result(lines)
        character(len=*), intent(in) :: text
        character(len=:), allocatable :: lines(:)
        integer :: n, j, first, last

        n = count([(text(j:j) == new_line('a'), j=1, len(text))])
        if (len(text) > 0 .and. text(len(text):) /= new_line('a')) n = n + 1
        allocate (character(len=max(len(text), 1)) :: lines(n))
        first = 1
        do j = 1, n
            last = index(text(first:), new_line('a')) + first - 2
            if (last < first - 1) last = len(text)
            lines(j) = text(first:last)
            first = last + 2
        end do
    end function lines_of

    !> The configuration of the namelist with these values, read by the CLI's reader (so its
    !> checks and messages are the CLI's, and its values the same bits: reals are written to
    !> full precision). `spacing` has one value (uniform) or n+1 values, as in &chain;
    !> `boundary` is the lower-cased name as byte values; `explicit` selects &initial kind =
    !> 'explicit' (x0, v0) rather than 'rest', and seed, x_amp, v_amp kind = 'random';
    !> `window` is &lyapunov's; `groups`, more groups (sweep_group, continuation_group);
    !> `overrides`, byte values of `group.key=value` lines applied to the text as the CLI's
    !> `--set` (any key of the input table).
    subroutine make_config(cfg, n, spacing, damping, restitution, amplitude, omega, boundary, &
                           explicit, x0, v0, transient, cycles, phase, stick_speed, &
                           max_size_mb, record_events, lyapunov, vectors, qr_every, jacobian, &
                           jacobian_cycles, err, window, seed, x_amp, v_amp, groups, overrides)
        type(config_t), intent(out) :: cfg
        integer, intent(in) :: n, vectors, qr_every, jacobian_cycles
        real(wp), intent(in) :: spacing(:), damping, restitution, amplitude, omega
        real(wp), intent(in) :: x0(:), v0(:), phase, stick_speed, max_size_mb
        integer(c_int), intent(in) :: boundary(:)   !! byte values 0..255
        logical, intent(in) :: explicit, record_events, lyapunov, jacobian
        integer(i8), intent(in) :: transient, cycles
        type(error_t), allocatable, intent(out) :: err
        integer, intent(in), optional :: window, seed
        real(wp), intent(in), optional :: x_amp, v_amp
        character(len=*), intent(in), optional :: groups
        integer(c_int), intent(in), optional :: overrides(:)
        character(len=:), allocatable :: text
        character(len=*), parameter :: nl = new_line('a')

        ! one thread at a time (here, in sweep_group and continuation_group): the Python
        ! layer's threads writing and reading numbers as text at once garbled some (internal
        ! I/O of gfortran 12 is not safe in threads); the kernels then run in parallel
        !$omp critical (chain_bridge_config_text)
        text = "&chain n = "//fmt_int(n)//", spacing = "//exact_list(spacing)//", damping = "// &
               exact(damping)//", restitution = "//exact(restitution)//", amplitude = "// &
               exact(amplitude)//", omega = "//exact(omega)//", boundary = "// &
               namelist_string(text_of(boundary))//" /"//nl
        if (present(seed)) then
            text = text//"&initial kind = 'random', seed = "//fmt_int(seed)//", x_amp = "// &
                   exact(x_amp)//", v_amp = "//exact(v_amp)//" /"//nl
        else if (explicit) then
            text = text//"&initial kind = 'explicit'"
            if (size(x0) > 0) text = text//", x0 = "//exact_list(x0)
            if (size(v0) > 0) text = text//", v0 = "//exact_list(v0)
            text = text//" /"//nl
        end if
        text = text//"&run transient = "//fmt_int8(transient)//", cycles = "// &
               fmt_int8(cycles)//", phase = "//exact(phase)//", stick_speed = "// &
               exact(stick_speed)//", record_events = "//fmt_logical(record_events)//" /"//nl// &
               "&lyapunov enabled = "//fmt_logical(lyapunov)//", vectors = "// &
               fmt_int(vectors)//", qr_every = "//fmt_int(qr_every)//", jacobian = "// &
               fmt_logical(jacobian)//", jacobian_cycles = "//fmt_int(jacobian_cycles)
        if (present(window)) text = text//", window = "//fmt_int(window)
        text = text//" /"//nl//"&output file = '(python)', max_size_mb = "// &
               exact(max_size_mb)//" /"//nl
        if (present(groups)) text = text//groups
        if (present(overrides)) then
            call read_config_text('python arguments', text, cfg, err, &
                                  lines_of(text_of(overrides)))
        else
            call read_config_text('python arguments', text, cfg, err)
        end if
        !$omp end critical (chain_bridge_config_text)
    end subroutine make_config

    !> Do ic_run's caller-given sizes fit the (validated) configuration? nf = n always; the
    !> strobe records, when kept, are (n, cycles); kcap exponents with &lyapunov; a 2n x 2n
    !> Jacobian when asked.
    pure logical function run_sizes_ok(cfg, keep_strobe, nr, nc, nf, kcap, mj)
        type(config_t), intent(in) :: cfg
        logical, intent(in) :: keep_strobe
        integer, intent(in) :: nr, nf, kcap, mj
        integer(i8), intent(in) :: nc

        run_sizes_ok = nf == cfg%model%n .and. &
                       (.not. keep_strobe .or. (nr == cfg%model%n .and. nc == cfg%record%cycles))
        if (cfg%record%lyapunov) run_sizes_ok = run_sizes_ok .and. kcap == lyapunov_vectors(cfg)
        if (cfg%record%jacobian) run_sizes_ok = run_sizes_ok .and. mj == 2*cfg%model%n
    end function run_sizes_ok

    !> ic_run's outputs besides the records and events: the final state, counters, periods,
    !> spectrum and Jacobian of a run (`res`, `chain`), or all zero without one (an invalid
    !> configuration, a dry run, a failed run).
    subroutine put_run_results(final_x, final_v, periods, site_counts, counts, &
                               collisions_per_cycle, k, exponents, stderr_bits, per_time, ky, &
                               jac, mult_re, mult_im, res, chain)
        real(c_double), intent(out) :: final_x(:), final_v(:), collisions_per_cycle, ky
        integer(c_int), intent(out) :: periods(:), k
        integer(c_int64_t), intent(out) :: site_counts(:), counts(:)
        real(c_double), intent(out) :: exponents(:), stderr_bits(:), per_time(:)
        real(c_double), intent(out) :: jac(:, :), mult_re(:), mult_im(:)
        type(record_result_t), intent(in), optional :: res
        type(chain_t), intent(in), optional :: chain

        final_x = 0
        final_v = 0
        periods = 0
        site_counts = 0
        counts = 0
        collisions_per_cycle = 0
        k = 0
        ky = 0
        exponents = 0
        stderr_bits = 0
        per_time = 0
        jac = 0
        mult_re = 0
        mult_im = 0
        if (.not. (present(res) .and. present(chain))) return
        call chain_copy_state(chain, final_x, final_v)
        periods = res%periods
        site_counts = res%site_counts
        counts = [res%impacts, res%sticks, res%releases, res%touches]
        collisions_per_cycle = res%collisions_per_cycle
        if (res%has_lyapunov) then
            k = size(res%lyapunov%bits_per_cycle)
            exponents = res%lyapunov%bits_per_cycle
            stderr_bits = res%lyapunov%stderr_bits
            per_time = res%lyapunov%nats_per_time
            ky = res%lyapunov%ky_dimension
        end if
        if (allocated(res%jacobian)) then
            jac = res%jacobian
            mult_re = res%multipliers_re
            mult_im = res%multipliers_im
        end if
    end subroutine put_run_results

    !> ic_continuation's outputs: the points and special points of the branches (`res`, its
    !> `table`) and Newton's start with the bonds of its impacts (`bonds`), or all zero without
    !> them; the caller checked the capacities. `strobe_x` is the caller's array: written,
    !> never zeroed.
    subroutine put_continuation_results(values, x, v, strobe_x, periods, branch, mult_re, &
                                        mult_im, stable, symmetric, min_gap, min_impact_speed, &
                                        impacts, residual, iterations, special_index, &
                                        special_kind, special_value, end_reason, end_kind, &
                                        parent, origin_point, origin_kind, &
                                        start_x, start_v, start_jac, &
                                        start_mult_re, start_mult_im, start_residuals, &
                                        start_bonds, start_min_gap, start_min_impact_speed, &
                                        start_reason, res, table, bonds)
        real(c_double), intent(out) :: values(:), x(:, :), v(:, :)
        real(c_double), intent(inout) :: strobe_x(:, :, :)
        integer(c_int), intent(out) :: periods(:), branch(:), stable(:), symmetric(:)
        integer(c_int), intent(out) :: impacts(:), end_kind(:)
        integer(c_int), intent(out) :: iterations(:), special_index(:), special_kind(:, :)
        integer(c_int), intent(out) :: parent(:), origin_point(:), origin_kind(:, :)
        real(c_double), intent(out) :: mult_re(:, :), mult_im(:, :), min_gap(:)
        real(c_double), intent(out) :: min_impact_speed(:), residual(:), special_value(:)
        integer(c_int), intent(out) :: end_reason(:), start_reason(:), start_bonds(:)
        real(c_double), intent(out) :: start_x(:), start_v(:), start_jac(:, :)
        real(c_double), intent(out) :: start_mult_re(:), start_mult_im(:), start_residuals(:)
        real(c_double), intent(out) :: start_min_gap, start_min_impact_speed
        type(branches_t), intent(in), optional :: res
        type(continuation_table_t), intent(in), optional :: table
        integer, intent(in), optional :: bonds(:)
        integer :: np, ns, j

        values = 0
        x = 0
        v = 0
        periods = 0
        branch = 0
        mult_re = 0
        mult_im = 0
        stable = 0
        symmetric = 0
        min_gap = 0
        min_impact_speed = 0
        impacts = 0
        residual = 0
        iterations = 0
        special_index = 0
        special_kind = 0
        special_value = 0
        call put_origins(parent, origin_point, origin_kind)
        end_reason = 0
        end_kind = 0
        start_reason = 0
        start_x = 0
        start_v = 0
        start_jac = 0
        start_mult_re = 0
        start_mult_im = 0
        start_residuals = 0
        start_bonds = 0
        start_min_gap = 0
        start_min_impact_speed = 0
        if (.not. (present(res) .and. present(table) .and. present(bonds))) return
        np = res%n_points
        ns = res%n_specials
        values(:np) = table%values
        x(:, :np) = table%x
        v(:, :np) = table%v
        strobe_x(:, :table%longest, :np) = table%strobe_x
        periods(:np) = table%period
        branch(:np) = table%branch
        mult_re(:, :np) = table%multipliers_re
        mult_im(:, :np) = table%multipliers_im
        stable(:np) = table%stable
        symmetric(:np) = table%symmetric
        min_gap(:np) = table%min_gap
        min_impact_speed(:np) = table%min_impact_speed
        impacts(:np) = table%impacts
        residual(:np) = table%residual
        iterations(:np) = table%iterations
        special_index(:ns) = table%special_index
        do j = 1, ns
            call put_text(trim(table%special_kind(j)), special_kind(:, j))
        end do
        special_value(:ns) = table%special_value
        call put_origins(parent, origin_point, origin_kind, table)
        call put_text(res%end_reason, end_reason)
        call put_text(res%end_kind, end_kind)

        associate (o => res%start)
            start_x = o%x
            start_v = o%v
            start_jac = o%jacobian
            if (o%converged) then
                start_mult_re = o%multipliers_re
                start_mult_im = o%multipliers_im
            end if
            start_residuals(:size(o%residuals)) = o%residuals
            start_bonds(:size(bonds)) = bonds
            start_min_gap = finite_or_inf(o%min_gap)
            start_min_impact_speed = finite_or_inf(o%min_impact_speed)
            call put_text(o%reason, start_reason)
        end associate
    end subroutine put_continuation_results

    !> Where each branch began (continuation_table's parent, origin_point and origin_kind, the
    !> kind's name as bytes, then zeros), or all zero without `table`; the caller checked the
    !> capacity.
    subroutine put_origins(parent, origin_point, origin_kind, table)
        integer(c_int), intent(out) :: parent(:), origin_point(:), origin_kind(:, :)
        type(continuation_table_t), intent(in), optional :: table
        integer :: nb, j

        parent = 0
        origin_point = 0
        origin_kind = 0
        if (.not. present(table)) return
        nb = size(table%parent)
        parent(:nb) = table%parent
        origin_point(:nb) = table%origin_point
        do j = 1, nb
            call put_text(trim(table%origin_kind(j)), origin_kind(:, j))
        end do
    end subroutine put_origins

    !> /curve's arrays (curve_table) and its end_reason into the caller's, sizes = (points,
    !> codim-2 points, length of end_reason); status_capacity when one does not fit (only
    !> sizes is set then).
    subroutine put_curve_results(table, end_reason_text, sizes, values, values2, x, v, &
                                 mult_re, mult_im, codim2_index, codim2_kind, end_reason, &
                                 status, msg_len, message)
        type(curve_table_t), intent(in) :: table
        character(len=*), intent(in) :: end_reason_text
        integer(c_int), intent(out) :: sizes(3), codim2_index(:), codim2_kind(:, :)
        real(c_double), intent(out) :: values(:), values2(:), x(:, :), v(:, :)
        real(c_double), intent(out) :: mult_re(:, :), mult_im(:, :)
        integer(c_int), intent(out) :: end_reason(:), status, msg_len, message(:)
        integer :: np, nc, j

        np = size(table%values)
        nc = size(table%codim2_index)
        sizes = [np, nc, len(end_reason_text)]
        values = 0
        values2 = 0
        x = 0
        v = 0
        mult_re = 0
        mult_im = 0
        codim2_index = 0
        codim2_kind = 0
        end_reason = 0
        call put_message('', status_ok, status, msg_len, message)
        if (np > size(values) .or. nc > size(codim2_index) .or. &
            len(table%codim2_kind) > size(codim2_kind, 1) .or. &
            len(end_reason_text) > size(end_reason)) then
            call put_message("python layer: more results than the capacities", &
                             status_capacity, status, msg_len, message)
            return
        end if
        values(:np) = table%values
        values2(:np) = table%values2
        x(:, :np) = table%x
        v(:, :np) = table%v
        mult_re(:, :np) = table%multipliers_re
        mult_im(:, :np) = table%multipliers_im
        codim2_index(:nc) = table%codim2_index
        do j = 1, nc
            call put_text(trim(table%codim2_kind(j)), codim2_kind(:, j))
        end do
        call put_text(end_reason_text, end_reason)
    end subroutine put_curve_results

    !> Copy `text` into the message buffer (truncated to its size) and set the status.
    subroutine put_message(text, code, status, msg_len, message)
        character(len=*), intent(in) :: text
        integer(c_int), intent(in) :: code
        integer(c_int), intent(out) :: status, msg_len
        integer(c_int), intent(out) :: message(:)  !! byte values 0..255

        status = code
        msg_len = int(min(len(text), size(message)), c_int)
        call put_text(text, message)
    end subroutine put_message

    !> `text` as byte values 0..255 at the start of `bytes` (the rest 0); the caller made
    !> room for all of it.
    pure subroutine put_text(text, bytes)
        character(len=*), intent(in) :: text
        integer(c_int), intent(out) :: bytes(:)
        integer :: j

        bytes = 0
        do j = 1, min(len(text), size(bytes))
            bytes(j) = iachar(text(j:j))
        end do
    end subroutine put_text

    !> Point the sink at the caller's arrays: strobe records when `strobe`, events when
    !> `events`, finite-time exponents when `windows_kept`.
    subroutine array_attach(sink, strobe, events, windows_kept, x, v, cycle, time, speed, site, &
                            kind, windows, window_cycle)
        class(array_sink_t), intent(inout) :: sink
        logical, intent(in) :: strobe, events, windows_kept
        real(wp), intent(inout), target :: x(:, :), v(:, :), time(:), speed(:), windows(:, :)
        integer(i8), intent(inout), target :: cycle(:), window_cycle(:)
        integer, intent(inout), target :: site(:), kind(:)

        if (strobe) then
            sink%x => x
            sink%v => v
            sink%cycle => cycle
        end if
        if (events) then
            sink%time => time
            sink%speed => speed
            sink%site => site
            sink%kind => kind
        end if
        if (windows_kept) then
            sink%windows => windows
            sink%window_cycle => window_cycle
        end if
    end subroutine array_attach

    subroutine array_put_strobe(sink, n_records, first, x, v, cycle, err)
        class(array_sink_t), intent(inout) :: sink
        integer(i8), intent(in) :: n_records, first
        real(wp), intent(in), contiguous :: x(:, :), v(:, :)
        integer(i8), intent(in), contiguous :: cycle(:)
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: last

        if (.not. associated(sink%x)) return
        if (size(sink%x, 2) == 0) return
        last = first + size(x, 2) - 1
        if (size(sink%x, 2) /= n_records .or. last > n_records .or. &
            size(sink%x, 1) /= size(x, 1)) then
            call set_error(err, "python layer: strobe arrays of the wrong shape")
            return
        end if
        sink%x(:, first:last) = x
        sink%v(:, first:last) = v
        sink%cycle(first:last) = cycle
    end subroutine array_put_strobe

    subroutine array_put_windows(sink, n_windows, first, exponents, cycle, err)
        class(array_sink_t), intent(inout) :: sink
        integer(i8), intent(in) :: n_windows, first
        real(wp), intent(in), contiguous :: exponents(:, :)
        integer(i8), intent(in), contiguous :: cycle(:)
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: last

        if (.not. associated(sink%windows)) return
        last = first + size(cycle) - 1
        if (size(sink%windows, 2) /= n_windows .or. last > n_windows .or. &
            size(sink%windows, 1) /= size(exponents, 1)) then
            call set_error(err, "python layer: finite-time arrays of the wrong shape")
            return
        end if
        sink%windows(:, first:last) = exponents
        sink%window_cycle(first:last) = cycle
    end subroutine array_put_windows

    subroutine array_put_events(sink, log, err)
        class(array_sink_t), intent(inout) :: sink
        type(event_log_t), intent(in) :: log
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: room, take, first

        if (.not. associated(sink%time)) return
        room = max(0_i8, size(sink%time, kind=i8) - sink%n_events)
        take = min(room, int(log%count, i8))
        first = sink%n_events + 1
        if (take > 0) then
            sink%time(first:first + take - 1) = log%time(1:take)
            sink%site(first:first + take - 1) = log%site(1:take)
            sink%speed(first:first + take - 1) = log%speed(1:take)
            sink%kind(first:first + take - 1) = log%kind(1:take)
        end if
        sink%n_events = sink%n_events + log%count
    end subroutine array_put_events

end module chain_bridge
