!> The thin layer wrapped by f2py into `impactchain._kernels` (SHTOOLS' PythonWrapper
!> pattern): plain external subroutines with explicit-shape c_double / c_int / c_int64_t
!> arrays. Only these routines cross into Python; `impactchain.api`
!> (python/impactchain/api.py) is the interface people use.
!>
!> Each routine writes the namelist of its arguments and reads it with the CLI's reader
!> (chain_bridge's make_config: the same checks, messages and values as the CLI), and calls the
!> same kernels as the CLI: `start_chain` and `record_cycles` (what `simulate_to_file` runs, with a
!> sink writing into the caller's arrays instead of an HDF5 file), `poincare_jacobian`, the
!> sweep's `run_sweep_branches` or the continuation's `run_continuation`.
!>
!> Protocol (every routine):
!> - `status` = 0 ok, 1 bad argument (ValueError), 2 the run failed (RuntimeError), 3 the event
!>   buffer (or a continuation's capacities) was too small, 4 the caller broke this protocol,
!>   5 stopped at the caller's request;
!>   `message(1:msg_len)` holds the library's message as byte values when status /= 0.
!>   Nothing is printed, nothing stops.
!> - Long routines (`ic_run`, `ic_sweep`, `ic_continuation`) share `control(4)` (int64,
!>   intent(inout): f2py passes the caller's buffer itself) with the caller, who polls it from
!>   another thread while the routine runs with the GIL released: the caller sets control(1)
!>   /= 0 to ask for a stop (seen at the next transient cycle, record, sweep point or orbit);
!>   the routine keeps control(2:4) = stage (1 transient, 2 records, 3 sweep points or orbits
!>   of a branch), units done, their total.
!> - `overrides`: `group.key=value` lines (byte values) applied after the arguments, as the
!>   CLI's `--set`: any key of the input table, checked and refused with the CLI's messages.
!> - Booleans are c_int 0 / 1. No strings cross: `boundary` (the lower-cased name) and
!>   `message` are c_int arrays of byte values 0..255 (f2py 2.x cannot declare c_int8_t).
!> - Sizes of outputs are caller-given. With `dry_run = 1` a routine only validates (`ic_run`
!>   and `ic_jacobian` also build the chain, which checks the initial state), so the caller
!>   allocates outputs only for a valid configuration, then calls again with dry_run = 0.
!> - Events, whose number is not known in advance: the caller gives a capacity `ncap`; `nev`
!>   returns the number of events of the run; when nev > ncap the first ncap are stored,
!>   status = 3, and the caller calls again with ncap >= nev (runs are deterministic: the
!>   second call repeats the first exactly). Memory stays bounded by what the caller gave.
!> - The routines keep no state between calls (nor does the library), so f2py releases the GIL
!>   while they run (`threadsafe`): Python threads can run several chains at once.

!> One run: transient, then `cycles` recorded cycles, as `fpm run` on the equivalent namelist.
!> Strobe records are kept when keep_strobe (then nr = n, nc = cycles), events when
!> record_events, in arrays the caller gives (x, v, cycle; ev_*: f2py refuses a size 0 there,
!> so give at least 1 where nothing is kept);
!> the Lyapunov spectrum (kcap = number of exponents) and the Jacobian of the `jacobian_cycles`
!> Poincare map at the final state with its eigenvalues (mj = 2n) when asked. nf = n always.
!> With window > 0 the finite-time exponents of the nw = cycles / window windows go to
!> windows(kw = kcap, nw) and window_cycle(nw) (caller-allocated; kw = nw = 1 and unused
!> without).
!> (Long because f2py's protocol flattens a whole run into 66 plain arguments: their list and
!> declarations are half of it; the rest validates, runs and hands the results over.)
subroutine ic_run(n, nsp, spacing, damping, restitution, amplitude, omega, nb, boundary, &
                  explicit, nx0, x0, nv0, v0, transient, cycles, phase, stick_speed, &
                  max_size_mb, record_events, lyapunov, vectors, qr_every, jacobian, &
                  jacobian_cycles, window, nov, overrides, dry_run, keep_strobe, nr, nc, nf, &
                  ncap, kcap, mj, kw, nw, x, v, cycle, final_x, final_v, periods, site_counts, &
                  counts, collisions_per_cycle, nev, ev_time, ev_site, ev_speed, ev_kind, k, &
                  exponents, stderr_bits, stderr_cycles, per_time, ky, jac, mult_re, mult_im, &
                  windows, window_cycle, control, status, msg_len, message)
    use, intrinsic :: iso_c_binding, only: c_int, c_int64_t, c_double
    use impactchain, only: i8, error_t, config_t, chain_t, record_result_t, &
                           record_cycles, start_chain
    use impactchain_drivers, only: check_size
    use chain_bridge, only: array_sink_t, shared_monitor_t, make_config, put_message, &
                            run_sizes_ok, put_run_results, call_ended, status_ok, &
                            status_invalid, status_capacity, status_internal
    implicit none
    !f2py threadsafe
    integer(c_int), intent(in) :: nov
    integer(c_int), intent(in) :: overrides(nov) !! `group.key=value` lines, byte values
    integer(c_int), intent(in) :: n, nsp, nb, nx0, nv0, explicit, record_events, lyapunov
    integer(c_int), intent(in) :: vectors, qr_every, jacobian, jacobian_cycles, dry_run
    integer(c_int), intent(in) :: keep_strobe, nr, nf, kcap, mj, window, kw
    integer(c_int64_t), intent(in) :: transient, cycles, nc, ncap, nw
    real(c_double), intent(in) :: spacing(nsp), damping, restitution, amplitude, omega
    real(c_double), intent(in) :: x0(nx0), v0(nv0), phase, stick_speed, max_size_mb
    integer(c_int), intent(in) :: boundary(nb)
    ! records and events: arrays the caller allocated (inout, so that f2py does not allocate
    ! and zero them while holding the GIL: Ctrl-C would wait for gigabytes of zeros)
    real(c_double), intent(inout), target :: x(nr, nc), v(nr, nc)
    integer(c_int64_t), intent(inout), target :: cycle(nc)
    real(c_double), intent(out) :: final_x(nf), final_v(nf)
    integer(c_int), intent(out) :: periods(nf)
    integer(c_int64_t), intent(out) :: site_counts(nf + 1), counts(4), nev
    real(c_double), intent(out) :: collisions_per_cycle, ky
    real(c_double), intent(inout), target :: ev_time(ncap), ev_speed(ncap)
    integer(c_int), intent(inout), target :: ev_site(ncap), ev_kind(ncap)
    integer(c_int), intent(out) :: k
    real(c_double), intent(out) :: exponents(kcap), stderr_bits(kcap), per_time(kcap)
    integer(c_int64_t), intent(out) :: stderr_cycles(kcap)
    real(c_double), intent(out) :: jac(mj, mj), mult_re(mj), mult_im(mj)
    ! finite-time exponents (&lyapunov window): caller-allocated as the records
    real(c_double), intent(inout), target :: windows(kw, nw)
    integer(c_int64_t), intent(inout), target :: window_cycle(nw)
    integer(c_int64_t), intent(inout), target :: control(4)
    integer(c_int), intent(out) :: status, msg_len
    integer(c_int), intent(out) :: message(1024)
    type(config_t) :: cfg
    type(chain_t) :: chain
    type(array_sink_t) :: sink
    type(shared_monitor_t) :: monitor
    type(record_result_t) :: res
    type(error_t), allocatable :: err

    call put_message('', status_ok, status, msg_len, message)
    nev = 0
    stderr_cycles = 0
    call put_run_results(final_x, final_v, periods, site_counts, counts, collisions_per_cycle, &
                         k, exponents, stderr_bits, per_time, ky, jac, mult_re, mult_im)
    call make_config(cfg, int(n), spacing, damping, restitution, amplitude, omega, boundary, &
                     explicit /= 0, x0, v0, int(transient, i8), int(cycles, i8), phase, &
                     stick_speed, max_size_mb, record_events /= 0, lyapunov /= 0, &
                     int(vectors), int(qr_every), jacobian /= 0, int(jacobian_cycles), err, &
                     window=int(window), &
                     overrides=overrides)
    if (.not. allocated(err)) call check_size(cfg, err)
    if (.not. allocated(err)) call start_chain(cfg, chain, err)
    if (allocated(err)) then
        call put_message(err%message, status_invalid, status, msg_len, message)
        return
    end if
    if (dry_run /= 0) return

    if (.not. run_sizes_ok(cfg, keep_strobe /= 0, int(nr), int(nc, i8), int(nf), int(kcap), &
                           int(mj)) .or. (window > 0 .and. (nw /= cycles/window .or. &
                                                            kw /= kcap))) then
        call put_message("python layer: output sizes do not match the configuration", &
                         status_internal, status, msg_len, message)
        return
    end if
    call sink%attach(keep_strobe /= 0, cfg%record%record_events, window > 0, x, v, cycle, &
                     ev_time, ev_speed, ev_site, ev_kind, windows, window_cycle)
    monitor%control => control
    call record_cycles(cfg%record, chain, sink, res, err, monitor)
    if (call_ended(control, err, status, msg_len, message)) return

    call put_run_results(final_x, final_v, periods, site_counts, counts, collisions_per_cycle, &
                         k, exponents, stderr_bits, per_time, ky, jac, mult_re, mult_im, res, &
                         chain)
    if (res%has_lyapunov) stderr_cycles(:k) = res%lyapunov%stderr_cycles
    nev = sink%n_events
    if (nev > ncap) call put_message("python layer: more events than the capacity ncap", &
                                     status_capacity, status, msg_len, message)
end subroutine ic_run

!> Jacobian (2n x 2n, n = nx0) of the `jacobian_cycles`-cycle Poincare map at the state
!> (x0, v0) on the section of drive phase `phase`; v0 may be empty (at rest). The state is
!> taken as a fresh start (no sticking contacts, bonds scheduled from scratch).
subroutine ic_jacobian(nsp, spacing, damping, restitution, amplitude, omega, nb, boundary, &
                       nx0, x0, nv0, v0, phase, stick_speed, max_size_mb, jacobian_cycles, &
                       nov, overrides, dry_run, mj, jac, status, msg_len, message)
    use, intrinsic :: iso_c_binding, only: c_int, c_double
    use impactchain, only: wp, i8, error_t, config_t, chain_t, &
                           chain_on_section, poincare_jacobian
    use impactchain_drivers, only: check_size
    use chain_bridge, only: make_config, put_message, status_ok, &
                            status_invalid, status_failed, status_internal
    implicit none
    !f2py threadsafe
    integer(c_int), intent(in) :: nov
    integer(c_int), intent(in) :: overrides(nov) !! `group.key=value` lines, byte values
    integer(c_int), intent(in) :: nsp, nb, nx0, nv0, jacobian_cycles, dry_run, mj
    real(c_double), intent(in) :: spacing(nsp), damping, restitution, amplitude, omega
    real(c_double), intent(in) :: x0(nx0), v0(nv0), phase, stick_speed, max_size_mb
    integer(c_int), intent(in) :: boundary(nb)
    real(c_double), intent(out) :: jac(mj, mj)
    integer(c_int), intent(out) :: status, msg_len
    integer(c_int), intent(out) :: message(1024)
    type(config_t) :: cfg
    type(chain_t) :: chain
    type(error_t), allocatable :: err
    real(wp), allocatable :: j_out(:, :), v_start(:)

    call put_message('', status_ok, status, msg_len, message)
    call make_config(cfg, int(nx0), spacing, damping, restitution, amplitude, omega, boundary, &
                     .true., x0, v0, 0_i8, 1_i8, phase, stick_speed, max_size_mb, .false., &
                     .false., 0, 1, .true., int(jacobian_cycles), err, &
                     overrides=overrides)
    if (.not. allocated(err)) call check_size(cfg, err)
    if (.not. allocated(err)) then
        allocate (v_start(cfg%model%n))
        v_start = 0
        if (size(cfg%v0) == cfg%model%n) v_start = cfg%v0
        call chain_on_section(cfg, cfg%x0, v_start, chain, err)
    end if
    if (allocated(err)) then
        call put_message(err%message, status_invalid, status, msg_len, message)
        return
    end if
    if (dry_run /= 0) return
    if (mj /= 2*cfg%model%n) then
        call put_message("python layer: output sizes do not match the configuration", &
                         status_internal, status, msg_len, message)
        return
    end if
    call poincare_jacobian(chain, cfg%record%jacobian_cycles, j_out, err)
    if (allocated(err)) then
        call put_message(err%message, status_failed, status, msg_len, message)
        return
    end if
    jac = j_out
end subroutine ic_jacobian

!> The seeded random start of &initial kind = 'random' (the CLI's generator): x(i) uniform in
!> [-x_amp, x_amp), v(i) in [-v_amp, v_amp). nf = n when the arguments are valid.
subroutine ic_random_start(n, nsp, spacing, seed, x_amp, v_amp, nov, overrides, dry_run, nf, &
                           x, v, status, msg_len, message)
    use, intrinsic :: iso_c_binding, only: c_int, c_double
    use impactchain, only: wp, i8, error_t, config_t, initial_state, &
                           chain_state_t
    use chain_bridge, only: make_config, put_message, status_ok, status_invalid, &
                            status_internal
    implicit none
    !f2py threadsafe
    integer(c_int), intent(in) :: nov
    integer(c_int), intent(in) :: overrides(nov) !! `group.key=value` lines, byte values
    integer(c_int), intent(in) :: n, nsp, seed, dry_run, nf
    real(c_double), intent(in) :: spacing(nsp), x_amp, v_amp
    real(c_double), intent(out) :: x(nf), v(nf)
    integer(c_int), intent(out) :: status, msg_len
    integer(c_int), intent(out) :: message(1024)
    type(config_t) :: cfg
    type(error_t), allocatable :: err
    type(chain_state_t) :: start
    real(wp), allocatable :: no_list(:)

    call put_message('', status_ok, status, msg_len, message)
    x = 0
    v = 0
    allocate (no_list(0))
    call make_config(cfg, int(n), spacing, 0.05_wp, 0.7_wp, 0.0_wp, 1.0_wp, &
                     [iachar('f'), iachar('i'), iachar('x'), iachar('e'), iachar('d')], &
                     .false., no_list, &
                     no_list, 0_i8, 1_i8, 0.0_wp, 1.0e-9_wp, 4096.0_wp, .false., .false., 0, &
                     1, .false., 1, err, seed=int(seed), x_amp=x_amp, v_amp=v_amp, &
                     overrides=overrides)
    if (.not. allocated(err)) call initial_state(cfg, start, err)
    if (allocated(err)) then
        call put_message(err%message, status_invalid, status, msg_len, message)
        return
    end if
    if (dry_run /= 0) return
    if (nf /= n) then
        call put_message("python layer: output sizes do not match the configuration", &
                         status_internal, status, msg_len, message)
        return
    end if
    x = start%x
    v = start%v
end subroutine ic_random_start

!> A sweep, as `fpm run` on a namelist with this &sweep group (chain_sweep, OpenMP threads over
!> the branches: `threads`, 0 for the default), kept in memory: the arrays of the file's /sweep
!> in the library's order, point p = i + (j - 1) n1 for index i along `parameter`, j along
!> `parameter2`. A dry run checks the sweep as the CLI does (check_sweep: its sizes within
!> max_size_mb, every point) and returns sizes = (n1, n2, k); then the caller gives nf = n,
!> nc = cycles, npts = n1 n2, kcap = k, and x of that shape (of shape (1, 1, 1) with
!> nf = nc = npts = 1 for the dry run: f2py refuses a size 0 there). Names are
!> lower-case byte values; parameter2 empty for a 1-D sweep. Events and the Jacobian are not
!> kept (as in a sweep file).
subroutine ic_sweep(n, nsp, spacing, damping, restitution, amplitude, omega, nb, boundary, &
                    explicit, nx0, x0, nv0, v0, transient, cycles, phase, stick_speed, &
                    max_size_mb, lyapunov, vectors, qr_every, npar, parameter, start, stop, &
                    step, nmode, mode, npar2, parameter2, start2, stop2, step2, threads, &
                    nov, overrides, dry_run, nf, nc, npts, kcap, sizes, values, x, collisions, &
                    period, exponents, stderr_bits, stderr_cycles, ky, control, status, &
                    msg_len, message)
    use, intrinsic :: iso_c_binding, only: c_int, c_int64_t, c_double
    use impactchain, only: i8, error_t, config_t, chain_state_t
    use impactchain_drivers, only: check_sweep, plan_sweep, sweep_plan_t, sweep_result_t, &
                                   sweep_result_init, run_sweep_branches
    use chain_bridge, only: shared_monitor_t, make_config, sweep_group, put_message, use_threads, &
                            call_ended, status_ok, status_invalid, status_internal
    implicit none
    !f2py threadsafe
    integer(c_int), intent(in) :: nov
    integer(c_int), intent(in) :: overrides(nov) !! `group.key=value` lines, byte values
    integer(c_int), intent(in) :: n, nsp, nb, nx0, nv0, explicit, lyapunov, vectors, qr_every
    integer(c_int), intent(in) :: npar, nmode, npar2, threads, dry_run, nf, npts, kcap
    integer(c_int64_t), intent(in) :: transient, cycles, nc
    real(c_double), intent(in) :: spacing(nsp), damping, restitution, amplitude, omega
    real(c_double), intent(in) :: x0(nx0), v0(nv0), phase, stick_speed, max_size_mb
    real(c_double), intent(in) :: start, stop, step, start2, stop2, step2
    integer(c_int), intent(in) :: boundary(nb), parameter(npar), mode(nmode), parameter2(npar2)
    integer(c_int), intent(out) :: sizes(3)
    real(c_double), intent(out) :: values(2, npts), collisions(npts)
    real(c_double), intent(inout) :: x(nf, nc, npts) ! caller-allocated, as ic_run's records
    integer(c_int), intent(out) :: period(nf, npts)
    real(c_double), intent(out) :: exponents(kcap, npts), stderr_bits(kcap, npts), ky(npts)
    integer(c_int64_t), intent(out) :: stderr_cycles(kcap, npts)
    integer(c_int64_t), intent(inout), target :: control(4)
    integer(c_int), intent(out) :: status, msg_len
    integer(c_int), intent(out) :: message(1024)
    type(config_t) :: cfg
    type(sweep_plan_t) :: plan
    type(sweep_result_t) :: res
    type(chain_state_t), allocatable :: starts(:)
    type(shared_monitor_t) :: monitor
    type(error_t), allocatable :: err

    call put_message('', status_ok, status, msg_len, message)
    sizes = 0
    values = 0
    collisions = 0
    period = 0
    exponents = 0
    stderr_bits = 0
    stderr_cycles = 0
    ky = 0
    call make_config(cfg, int(n), spacing, damping, restitution, amplitude, omega, boundary, &
                     explicit /= 0, x0, v0, int(transient, i8), int(cycles, i8), phase, &
                     stick_speed, max_size_mb, .false., lyapunov /= 0, int(vectors), &
                     int(qr_every), .false., 1, err, groups=sweep_group(parameter, start, &
                     stop, step, mode, parameter2, start2, stop2, step2), &
                     overrides=overrides)
    ! the CLI's checks (sizes against max_size_mb, every point), before the caller allocates x
    if (.not. allocated(err)) then
        plan = plan_sweep(cfg)
        call check_sweep(cfg, plan, err)
    end if
    if (allocated(err)) then
        call put_message(err%message, status_invalid, status, msg_len, message)
        return
    end if
    sizes = [plan%n_axis1, plan%n_axis2, plan%k]
    if (dry_run /= 0) return

    if (nf /= n .or. nc /= cycles .or. npts /= plan%n_points .or. kcap /= plan%k) then
        call put_message("python layer: output sizes do not match the configuration", &
                         status_internal, status, msg_len, message)
        return
    end if
    call sweep_result_init(res, cfg, plan)
    allocate (starts(plan%n_branches))
    monitor%control => control
    call use_threads(int(threads))
    call run_sweep_branches(cfg, plan, res, starts, err, monitor=monitor)
    if (call_ended(control, err, status, msg_len, message)) return
    values(:plan%n_axes, :) = res%values
    x = res%x
    collisions = res%collisions
    period = res%period
    exponents = res%exponents
    stderr_bits = res%stderr
    stderr_cycles = res%stderr_block
    ky = res%ky
end subroutine ic_sweep

!> A continuation of periodic orbits, as `fpm run` on a namelist with this &continuation group
!> (chain_branch_file's run_continuation: Newton from the state on the section after
!> `transient` cycles, then the branches), kept in memory: the datasets of the file's
!> /continuation as continuation_table builds them for the file, and Newton's result from
!> the guess (start_*, converged or not). `parameter` is a lower-case name as byte values.
!>
!> Sizes: sizes = (points, special points, longest period, length of end_reason, start
!> converged 0/1, start residuals (iterations + 1), start impacts, length of start_reason, of
!> end_kind, branches). The caller gives nf = n and capacities: npcap points, nlong crossings
!> per period, nscap special points, ntext bytes of each text, nrcap residuals, nbcap impacts,
!> nocap branches (each >= 1: f2py
!> refuses a size 0 for strobe_x). When a capacity is too small, status = 3 and only sizes is
!> set: the caller calls again with room for them (the run repeats itself exactly). A dry run
!> validates and returns.
!>
!> Per point (of npcap, the first sizes(1) set): values, x, v, strobe_x (NaN beyond the point's
!> period), periods, branch, mult_re, mult_im, stable (0/1), min_gap and min_impact_speed
!> (+inf: none), impacts, residual, iterations; per special point: special_index (0-based),
!> special_kind (the kind's name as bytes, then zeros), special_value; per branch: parent,
!> origin_point (0-based) and origin_kind (as special_kind). Newton's start: x, v,
!> the Jacobian (2n x 2n), the multipliers (when converged), residuals, the bonds of the
!> impacts of one period in time order, the grazing monitors (+inf: none) and the reason it
!> failed ('' when converged).
subroutine ic_continuation(n, nsp, spacing, damping, restitution, amplitude, omega, nb, &
                           boundary, explicit, nx0, x0, nv0, v0, transient, phase, stick_speed, &
                           npar, parameter, stop, step, period, max_points, doublings, nov, &
                           overrides, dry_run, nf, npcap, nlong, nscap, ntext, nrcap, nbcap, &
                           nocap, sizes, values, x, v, strobe_x, periods, branch, mult_re, &
                           mult_im, stable, symmetric, min_gap, min_impact_speed, impacts, &
                           residual, iterations, special_index, special_kind, special_value, &
                           end_reason, end_kind, parent, origin_point, origin_kind, start_x, &
                           start_v, start_jac, start_mult_re, start_mult_im, start_residuals, &
                           start_bonds, start_min_gap, start_min_impact_speed, start_reason, &
                           control, status, msg_len, message)
    use, intrinsic :: iso_c_binding, only: c_int, c_int64_t, c_double
    use impactchain, only: i8, error_t, config_t, branches_t, run_continuation, &
                           impact_bonds
    use impactchain_drivers, only: continuation_table_t, continuation_table
    use chain_bridge, only: shared_monitor_t, make_config, continuation_group, put_message, &
                            put_continuation_results, call_ended, status_ok, status_invalid, &
                            status_capacity, status_internal
    implicit none
    !f2py threadsafe
    integer(c_int), intent(in) :: n, nsp, nb, nx0, nv0, explicit, npar, period, max_points, nov
    integer(c_int), intent(in) :: doublings, dry_run, nf, npcap, nlong, nscap, ntext, nrcap, nbcap
    integer(c_int), intent(in) :: overrides(nov) !! `group.key=value` lines, byte values
    integer(c_int64_t), intent(in) :: transient
    real(c_double), intent(in) :: spacing(nsp), damping, restitution, amplitude, omega
    real(c_double), intent(in) :: x0(nx0), v0(nv0), phase, stick_speed, stop, step
    integer(c_int), intent(in) :: boundary(nb), parameter(npar), nocap
    integer(c_int), intent(out) :: sizes(10)
    real(c_double), intent(out) :: values(npcap), x(nf, npcap), v(nf, npcap)
    real(c_double), intent(inout) :: strobe_x(nf, nlong, npcap) ! caller-allocated
    integer(c_int), intent(out) :: periods(npcap), branch(npcap), stable(npcap), symmetric(npcap)
    integer(c_int), intent(out) :: impacts(npcap), iterations(npcap)
    real(c_double), intent(out) :: mult_re(2*nf, npcap), mult_im(2*nf, npcap)
    real(c_double), intent(out) :: min_gap(npcap), min_impact_speed(npcap), residual(npcap)
    integer(c_int), intent(out) :: special_index(nscap), special_kind(16, nscap)
    real(c_double), intent(out) :: special_value(nscap)
    integer(c_int), intent(out) :: parent(nocap), origin_point(nocap), origin_kind(16, nocap)
    integer(c_int), intent(out) :: end_reason(ntext), end_kind(ntext), start_reason(ntext)
    real(c_double), intent(out) :: start_x(nf), start_v(nf), start_jac(2*nf, 2*nf)
    real(c_double), intent(out) :: start_mult_re(2*nf), start_mult_im(2*nf)
    real(c_double), intent(out) :: start_residuals(nrcap), start_min_gap, start_min_impact_speed
    integer(c_int), intent(out) :: start_bonds(nbcap)
    integer(c_int64_t), intent(inout), target :: control(4)
    integer(c_int), intent(out) :: status, msg_len, message(1024)
    type(config_t) :: cfg
    type(branches_t) :: res
    type(continuation_table_t) :: table
    type(shared_monitor_t) :: monitor
    type(error_t), allocatable :: err
    integer, allocatable :: bonds(:)

    call put_message('', status_ok, status, msg_len, message)
    sizes = 0
    call put_continuation_results(values, x, v, strobe_x, periods, branch, mult_re, mult_im, &
                                  stable, symmetric, min_gap, min_impact_speed, impacts, &
                                  residual, iterations, special_index, special_kind, &
                                  special_value, end_reason, end_kind, parent, origin_point, &
                                  origin_kind, start_x, start_v, start_jac, start_mult_re, &
                                  start_mult_im, start_residuals, start_bonds, start_min_gap, &
                                  start_min_impact_speed, start_reason)
    call make_config(cfg, int(n), spacing, damping, restitution, amplitude, omega, boundary, &
                     explicit /= 0, x0, v0, int(transient, i8), 1_i8, phase, stick_speed, &
                     4096.0_c_double, .false., .false., 0, 1, .false., 1, err, &
                     groups=continuation_group(parameter, stop, step, int(period), &
                                               int(max_points), int(doublings)), &
                     overrides=overrides)
    if (allocated(err)) then
        call put_message(err%message, status_invalid, status, msg_len, message)
        return
    end if
    if (dry_run /= 0) return
    if (nf /= n) then
        call put_message("python layer: output sizes do not match the configuration", &
                         status_internal, status, msg_len, message)
        return
    end if

    monitor%control => control
    call run_continuation(cfg, res, err, monitor)
    if (call_ended(control, err, status, msg_len, message)) return
    call continuation_table(cfg%model%n, res, table)
    bonds = impact_bonds(res%start)
    sizes = [res%n_points, res%n_specials, table%longest, len(res%end_reason), &
             merge(1, 0, res%start%converged), size(res%start%residuals), size(bonds), &
             len(res%start%reason), len(res%end_kind), res%n_branches]
    if (any(sizes([1, 2, 3, 4, 6, 7, 8, 9, 10]) > [npcap, nscap, nlong, ntext, nrcap, nbcap, &
                                                    ntext, ntext, nocap])) then
        call put_message("python layer: more results than the capacities", status_capacity, &
                         status, msg_len, message)
        return
    end if

    call put_continuation_results(values, x, v, strobe_x, periods, branch, mult_re, mult_im, &
                                  stable, symmetric, min_gap, min_impact_speed, impacts, &
                                  residual, iterations, special_index, special_kind, &
                                  special_value, end_reason, end_kind, parent, origin_point, &
                                  origin_kind, start_x, start_v, start_jac, start_mult_re, &
                                  start_mult_im, start_residuals, start_bonds, start_min_gap, &
                                  start_min_impact_speed, start_reason, res, table, bonds)
end subroutine ic_continuation

!> A continuation's curve in two parameters, in memory: ic_continuation's inputs with
!> &continuation follow, parameter2, stop2 and step2 among the overrides; /curve's arrays as
!> chain_curve_file's curve_table, sizes = (points, codim-2 points, length of end_reason).
!> Capacities: npcap points (max_points), nccap codim-2 points, nkind bytes of each codim-2
!> kind, ntext of end_reason; status 3 when one is short (then only sizes is set).
subroutine ic_curve(n, nsp, spacing, damping, restitution, amplitude, omega, nb, boundary, &
                    explicit, nx0, x0, nv0, v0, transient, phase, stick_speed, npar, &
                    parameter, stop, step, period, max_points, doublings, nov, overrides, nf, &
                    npcap, nccap, nkind, ntext, sizes, values, values2, x, v, mult_re, &
                    mult_im, codim2_index, codim2_kind, end_reason, control, status, msg_len, &
                    message)
    use, intrinsic :: iso_c_binding, only: c_int, c_int64_t, c_double
    use impactchain, only: i8, error_t, config_t, branches_t, run_continuation
    use impactchain_drivers, only: curve_t, curve_table_t, curve_table, run_curve
    use chain_bridge, only: shared_monitor_t, make_config, continuation_group, put_message, &
                            put_curve_results, call_ended, status_invalid, status_internal
    implicit none
    !f2py threadsafe
    integer(c_int), intent(in) :: n, nsp, nb, nx0, nv0, explicit, npar, period, max_points, nov
    integer(c_int), intent(in) :: doublings, nf, npcap, nccap, nkind, ntext
    integer(c_int), intent(in) :: overrides(nov), boundary(nb), parameter(npar)
    integer(c_int64_t), intent(in) :: transient
    real(c_double), intent(in) :: spacing(nsp), damping, restitution, amplitude, omega
    real(c_double), intent(in) :: x0(nx0), v0(nv0), phase, stick_speed, stop, step
    integer(c_int), intent(out) :: sizes(3), codim2_index(nccap), codim2_kind(nkind, nccap)
    real(c_double), intent(out) :: values(npcap), values2(npcap), x(nf, npcap), v(nf, npcap)
    real(c_double), intent(out) :: mult_re(2*nf, npcap), mult_im(2*nf, npcap)
    integer(c_int), intent(out) :: end_reason(ntext)
    integer(c_int64_t), intent(inout), target :: control(4)
    integer(c_int), intent(out) :: status, msg_len, message(1024)
    type(config_t) :: cfg
    type(branches_t) :: res
    type(curve_t) :: curve
    type(curve_table_t) :: table
    type(shared_monitor_t) :: monitor
    type(error_t), allocatable :: err

    sizes = 0
    call make_config(cfg, int(n), spacing, damping, restitution, amplitude, omega, boundary, &
                     explicit /= 0, x0, v0, int(transient, i8), 1_i8, phase, stick_speed, &
                     4096.0_c_double, .false., .false., 0, 1, .false., 1, err, &
                     groups=continuation_group(parameter, stop, step, int(period), &
                                               int(max_points), int(doublings)), &
                     overrides=overrides)
    if (.not. allocated(err) .and. nf /= n) &
        err = error_t("python layer: output sizes do not match the configuration")
    if (allocated(err)) then
        call put_message(err%message, merge(status_internal, status_invalid, nf /= n), &
                         status, msg_len, message)
        return
    end if
    monitor%control => control
    call run_continuation(cfg, res, err, monitor)
    if (call_ended(control, err, status, msg_len, message)) return
    call run_curve(cfg, res, curve)
    call curve_table(cfg%model%n, curve, table)
    call put_curve_results(table, curve%end_reason, sizes, values, values2, x, v, mult_re, &
                           mult_im, codim2_index, codim2_kind, end_reason, status, msg_len, &
                           message)
end subroutine ic_curve

!> Where the extension runs (chain_provenance: code version, compiler and flags, BLAS and the
!> kernels it selected, CPU model), as the `key: value` lines of `impactchain --version`,
!> byte values in text(1:text_len) (at most 4096; longer text is cut there).
subroutine ic_provenance(text_len, text)
    use, intrinsic :: iso_c_binding, only: c_int
    use impactchain, only: provenance_text
    implicit none
    !f2py threadsafe
    integer(c_int), intent(out) :: text_len
    integer(c_int), intent(out) :: text(4096)
    character(len=:), allocatable :: lines
    integer :: i

    lines = provenance_text()
    text = 0
    text_len = min(len(lines), size(text))
    do i = 1, text_len
        text(i) = iachar(lines(i:i))
    end do
end subroutine ic_provenance

!> The file schema (chain_file_schema: every dataset and attribute of the four kinds of file)
!> as the JSON array of `impactchain --schema`'s "outputs", byte values in text(1:text_len);
!> text_len > size(text) says the buffer was too small (nothing is cut silently).
subroutine ic_output_schema(text_len, text)
    use, intrinsic :: iso_c_binding, only: c_int
    use impactchain_drivers, only: output_schema_json
    use chain_bridge, only: put_text
    implicit none
    !f2py threadsafe
    integer(c_int), intent(out) :: text_len
    integer(c_int), intent(out) :: text(262144)
    character(len=:), allocatable :: json

    json = output_schema_json()
    text_len = len(json)
    call put_text(json, text)
end subroutine ic_output_schema

!> The input schema as JSON (the "inputs" of `impactchain --schema`, chain_inputs), as byte
!> values in text(1:text_len); text_len = -(the length needed) when the buffer is too small.
subroutine ic_input_schema(text_len, text)
    use, intrinsic :: iso_c_binding, only: c_int
    use impactchain_drivers, only: input_schema_json
    implicit none
    !f2py threadsafe
    integer(c_int), intent(out) :: text_len
    integer(c_int), intent(out) :: text(65536)
    character(len=:), allocatable :: json
    integer :: i

    json = input_schema_json()
    text = 0
    if (len(json) > size(text)) then
        text_len = -len(json)
        return
    end if
    text_len = len(json)
    do i = 1, text_len
        text(i) = iachar(json(i:i))
    end do
end subroutine ic_input_schema
