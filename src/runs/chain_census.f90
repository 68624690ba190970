!> An attractor census (docs/model.md section 13): `&census samples` random starts at one
!> parameter point, or at every point of a one-parameter `&sweep`, each run through `&run
!> transient` cycles and `&run cycles` records with its largest Lyapunov exponent, then told
!> apart by the rules of chain_attractor: which attractors there are, and the fraction of the
!> starts that reach each (its basin fraction). With `&census exponents = k` each sample keeps
!> its k leading exponents, and each attractor the mean and the spread of its samples' (section
!> 13.4: an ensemble of spectra).
!>
!> Sample s (1..samples) starts from its own stream of the portable generator of
!> `&initial kind = 'random'` (sample_seed): its start depends on (seed, s) alone, neither on
!> the number of samples nor on the threads. Every point gets the same starts, and every
!> sample starts fresh (a sweep's `mode` plays no part). Samples run in parallel (OpenMP
!> threads) into results of their own; they are then classified one by one, point by point in
!> sample order, so the census is the same bit for bit at any thread count. Until every
!> sample is done the finished ones live in the checkpoint `file.h5.ckpt` (every few seconds
!> and when stopped), from which the same input resumes.
module chain_census
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_positive_inf
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_real, fmt_int
    use chain_engine, only: chain_t, chain_init, chain_positions, chain_velocities, chain_period
    use chain_state, only: chain_state_t, moving_state
    use chain_config, only: config_t, validate_config, plane_coordinate
    use chain_model, only: model_t, bond_gaps
    use chain_record, only: memory_sink_t, record_result_t, record_cycles
    use chain_section, only: chain_at_section, advance_to_point
    use chain_event_log, only: event_log_t, event_log_init
    use chain_sim, only: uniform, initial_state
    use chain_sweep, only: sweep_plan_t, plan_sweep, sweep_point_config
    use chain_attractor, only: attractor_t, kind_periodic, orbit_period, sample_kind, &
                               site_fractions, mirror_symmetric, match_attractor
    use chain_files, only: rename_file, close_checked
    use chain_monitor, only: monitor_t, stage_samples, saving_monitor_t
    implicit none
    private
    public :: census_result_t, census_result_init, census_points, census_point_config
    public :: sample_seed, sample_start, run_sample, run_census_samples, classify_census
    public :: census_starts, plane_starts, plane_value
    public :: sample_record_sizes, pack_sample, unpack_sample, ensemble_statistics
    public :: orbit_states, save_census_checkpoint, load_census_checkpoint
    public :: census_checkpoint_monitor_t

    !> The checkpoint's first bytes; the number changes with its layout.
    character(len=8), parameter :: checkpoint_magic = 'ICCENSU3'

    !> Everything a census finds: per sample (filled in parallel), then the classification.
    !> Arrays are in Fortran order; h5py shows the point first.
    type :: census_result_t
        integer :: n_points = 1
        integer :: n_samples = 1
        integer :: resumed = 0                        !! samples taken from a checkpoint
        integer :: n_exponents = 1                    !! k, the leading exponents of a sample
        real(wp), allocatable :: values(:)            !! values(n_points): a sweep's parameter
        real(wp), allocatable :: x0(:, :, :), v0(:, :, :) !! (n, samples, points): the starts
        logical, allocatable :: done(:, :)            !! (samples, points)
        integer, allocatable :: periods(:, :, :)      !! (n, samples, points), 0 = none
        integer(i8), allocatable :: sites(:, :, :)    !! (n+1, samples, points) impacts/bond
        !> (k, samples, points): the k leading exponents (bits per cycle, descending; the first
        !> is lambda1, the one the classification uses) and their standard errors
        real(wp), allocatable :: exponents(:, :, :), exponents_stderr(:, :, :)
        real(wp), allocatable :: x(:, :, :), v(:, :, :) !! (n, samples, points) last record
        ! the classification (classify_census)
        integer :: n_attractors = 0
        type(attractor_t), allocatable :: attractors(:) !! (n_attractors, or more allocated)
        integer, allocatable :: attractor(:, :)       !! (samples, points): 1-based id
        logical, allocatable :: mirrored(:, :)        !! (samples, points): reached the image
        !> (n_attractors, points): fraction of a point's samples on each attractor, and its
        !> binomial standard error sqrt(f (1 - f) / samples)
        real(wp), allocatable :: fraction(:, :), fraction_stderr(:, :)
        !> (k, n_attractors): the mean of the exponents over the attractor's samples, and their
        !> sample standard deviation (n - 1; 0 with one sample): the spread between trajectories
        real(wp), allocatable :: attractor_exponents(:, :), attractor_spread(:, :)
    end type census_result_t

    !> The census's monitor: the caller's, and a checkpoint every few seconds. It is told
    !> inside run_task's critical section, with `res` consistent. A checkpoint that cannot be
    !> written stops the census with that error (`err`).
    type, extends(saving_monitor_t) :: census_checkpoint_monitor_t
        type(config_t) :: cfg
        type(census_result_t), pointer :: res => null()
        character(len=:), allocatable :: path          !! of the checkpoint
    contains
        procedure :: save => save_census_progress
    end type census_checkpoint_monitor_t

contains

    !> Points of the census of a validated cfg: 1, or those of its (1-D) sweep.
    pure integer function census_points(cfg)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t) :: plan

        census_points = 1
        if (.not. cfg%sweep) return
        plan = plan_sweep(cfg)
        census_points = plan%n_points
    end function census_points

    !> An empty census of cfg: every sample's start, nothing run.
    subroutine census_result_init(res, cfg)
        type(census_result_t), intent(out) :: res
        type(config_t), intent(in) :: cfg
        integer :: n, s, p

        n = cfg%model%n
        res%n_points = census_points(cfg)
        res%n_samples = cfg%census_samples
        res%n_exponents = cfg%census_exponents
        associate (ns => res%n_samples, np => res%n_points, k => res%n_exponents)
            allocate (res%values(np), res%x0(n, ns, np), res%v0(n, ns, np), res%done(ns, np))
            allocate (res%periods(n, ns, np), res%sites(n + 1, ns, np))
            allocate (res%exponents(k, ns, np), res%exponents_stderr(k, ns, np))
            allocate (res%x(n, ns, np), res%v(n, ns, np))
            allocate (res%attractor(ns, np), res%mirrored(ns, np))
        end associate
        res%values = 0
        ! (from the index, as a sweep's points: never by accumulating steps)
        if (cfg%sweep) res%values = [(cfg%sweep_start + (p - 1)*cfg%sweep_step, &
                                      p=1, res%n_points)]
        do s = 1, res%n_samples
            call sample_start(cfg%census_seed, s, cfg%census_x_amp, cfg%census_v_amp, &
                              res%x0(:, s, 1), res%v0(:, s, 1))
        end do
        do p = 2, res%n_points
            res%x0(:, :, p) = res%x0(:, :, 1)
            res%v0(:, :, p) = res%v0(:, :, 1)
        end do
        res%done = .false.
        res%periods = 0
        res%sites = 0
        res%exponents = 0
        res%exponents_stderr = 0
        res%x = 0
        res%v = 0
        res%attractor = 0
        res%mirrored = .false.
        allocate (res%attractors(0), res%fraction(0, res%n_points))
        allocate (res%fraction_stderr(0, res%n_points))
        allocate (res%attractor_exponents(res%n_exponents, 0))
        allocate (res%attractor_spread(res%n_exponents, 0))
    end subroutine census_result_init

    !> An empty census of cfg with its starts: random (census_result_init), or on the grid
    !> of a census plane (plane_starts) around the state &initial gives.
    subroutine census_starts(res, cfg, err)
        type(census_result_t), intent(out) :: res
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        type(chain_state_t) :: fixed
        integer :: p

        call census_result_init(res, cfg)
        if (cfg%census_plane_points == 0) return
        call initial_state(cfg, fixed, err)
        if (allocated(err)) then
            err%message = "&census: the plane's fixed state (&initial): "//err%message
            return
        end if
        call plane_starts(cfg, fixed%x, fixed%v, res%x0(:, :, 1), res%v0(:, :, 1), err)
        if (allocated(err)) return
        do p = 2, res%n_points
            res%x0(:, :, p) = res%x0(:, :, 1)
            res%v0(:, :, p) = res%v0(:, :, 1)
        end do
    end subroutine census_starts

    !> The starts of a census plane (cfg%census_plane, validated): every sample at the fixed
    !> state (x, v) but for the plane's two coordinates; sample s = 1 + i + m j (i, j in
    !> 0..m-1, m = plane_points) at grid value i of the first and j of the second
    !> (plane_value). No start may make a gap negative (an oscillator through a neighbour or
    !> a wall).
    subroutine plane_starts(cfg, x, v, x0, v0, err)
        type(config_t), intent(in) :: cfg
        real(wp), intent(in) :: x(:), v(:)
        real(wp), intent(out) :: x0(:, :), v0(:, :)  !! (n, plane_points**2)
        type(error_t), allocatable, intent(out) :: err
        logical :: velocity(2)
        integer :: coordinate(2), m, s, k, grid(2)
        real(wp) :: value

        m = cfg%census_plane_points
        do k = 1, 2
            call plane_coordinate(cfg%census_plane(k), cfg%model%n, velocity(k), coordinate(k))
        end do
        do s = 1, m*m
            x0(:, s) = x
            v0(:, s) = v
            grid = [modulo(s - 1, m), (s - 1)/m]
            do k = 1, 2
                value = plane_value(cfg%census_plane_range(2*k - 1), &
                                    cfg%census_plane_range(2*k), grid(k), m)
                if (velocity(k)) then
                    v0(coordinate(k), s) = value
                else
                    x0(coordinate(k), s) = value
                end if
            end do
            if (any(bond_gaps(cfg%model%spacing, cfg%model%walls, x0(:, s)) < 0)) then
                call set_error(err, "&census: the plane's start "//fmt_int(s)//" ("// &
                               trim(cfg%census_plane(1))//" = "// &
                               fmt_real(plane_value(cfg%census_plane_range(1), &
                                                    cfg%census_plane_range(2), grid(1), m))// &
                               ", "//trim(cfg%census_plane(2))//" = "// &
                               fmt_real(plane_value(cfg%census_plane_range(3), &
                                                    cfg%census_plane_range(4), grid(2), m))// &
                               ") puts an oscillator through a neighbour or a wall; "// &
                               "narrow plane_range")
                return
            end if
        end do
    end subroutine plane_starts

    !> Grid value k (0..m-1) of m from lo to hi: lo + k (hi - lo) / (m - 1), from the index
    !> (never by accumulating steps), and hi itself at k = m - 1.
    pure real(wp) function plane_value(lo, hi, k, m) result(value)
        real(wp), intent(in) :: lo, hi
        integer, intent(in) :: k, m

        if (k == m - 1) then
            value = hi
        else
            value = lo + k*((hi - lo)/(m - 1))
        end if
    end function plane_value

    !> The generator state of sample s's stream: (seed, s) mixed by a 32-bit integer hash
    !> (h <- h xor (h >> 16), h <- h * 0x45d9f3b mod 2^32, three times over), first of the
    !> seed and then of that xor s, a bijection of 32-bit words; then taken into the MINSTD
    !> range 1 .. 2^31 - 2. Distinct samples of one seed get distinct, unrelated streams.
    pure function sample_seed(seed, s) result(state)
        integer, intent(in) :: seed, s
        integer(i8) :: state
        integer(i8), parameter :: words = 4294967296_i8

        state = hash32(ieor(hash32(modulo(int(seed, i8), words)), modulo(int(s, i8), words)))
        state = modulo(state, 2147483646_i8) + 1
    end function sample_seed

    !> A 32-bit integer hash (held in 64 bits, so no product overflows).
    pure function hash32(word) result(h)
        integer(i8), intent(in) :: word
        integer(i8) :: h
        integer(i8), parameter :: mask = 4294967295_i8, multiplier = 73244475_i8
        integer :: r

        h = iand(word, mask)
        do r = 1, 2
            h = ieor(h, shiftr(h, 16))
            h = iand(h*multiplier, mask)
        end do
        h = ieor(h, shiftr(h, 16))
    end function hash32

    !> The start of sample s: x, v uniform in [-x_amp, x_amp], [-v_amp, v_amp], drawn from its
    !> stream in the order of &initial random (x(1), v(1), x(2), ...).
    subroutine sample_start(seed, s, x_amp, v_amp, x, v)
        integer, intent(in) :: seed, s
        real(wp), intent(in) :: x_amp, v_amp
        real(wp), intent(out) :: x(:), v(:)
        integer(i8) :: state
        integer :: i

        state = sample_seed(seed, s)
        do i = 1, size(x)
            x(i) = x_amp*(2*uniform(state) - 1)
            v(i) = v_amp*(2*uniform(state) - 1)
        end do
    end subroutine sample_start

    !> The plain run of point p (1-based; the only point without a sweep), validated, that
    !> each sample there makes: no events, no Jacobian, the leading k = `&census exponents`
    !> exponents (1 by default: the largest alone), with the input's qr_every and align.
    subroutine census_point_config(cfg, p, point, err)
        type(config_t), intent(in) :: cfg
        integer, intent(in) :: p
        type(config_t), intent(out) :: point
        type(error_t), allocatable, intent(out) :: err

        if (cfg%sweep) then
            call sweep_point_config(cfg, plan_sweep(cfg), p, point, err)
            if (allocated(err)) return
        else
            point = cfg
        end if
        point%census = .false.
        point%record%record_events = .false.
        point%record%jacobian = .false.
        point%record%lyapunov = .true.
        point%record%vectors = cfg%census_exponents
        call validate_config(point, err)
    end subroutine census_point_config

    !> One sample from (x0, v0) at t = 0 under the point's configuration: its oscillators'
    !> periods, impacts per bond, leading exponents (as many as `exponents` holds, the point's
    !> vectors; descending, bits per cycle) and their standard errors, and its state at the
    !> last record. The same run as `&initial kind = 'explicit'` with x0, v0.
    subroutine run_sample(point, x0, v0, periods, sites, exponents, stderr, x, v, err)
        type(config_t), intent(in) :: point
        real(wp), intent(in) :: x0(:), v0(:)
        integer, intent(out) :: periods(:)
        integer(i8), intent(out) :: sites(:)
        real(wp), intent(out) :: exponents(:), stderr(:), x(:), v(:)
        type(error_t), allocatable, intent(out) :: err
        type(chain_t) :: chain
        type(memory_sink_t) :: sink
        type(record_result_t) :: out

        periods = 0
        sites = 0
        exponents = 0
        stderr = 0
        x = 0
        v = 0
        sink%keep_strobe = .false.
        call chain_init(chain, point%model, moving_state(x0, v0, 0_i8, 0.0_wp), err)
        if (allocated(err)) return
        call record_cycles(point%record, chain, sink, out, err)
        if (allocated(err)) return
        periods = out%periods
        sites = out%site_counts
        if (out%has_lyapunov) then
            exponents = out%lyapunov%bits_per_cycle
            stderr = out%lyapunov%stderr_bits
        end if
        x = chain_positions(chain)
        v = chain_velocities(chain)
    end subroutine run_sample

    !> Run every sample not yet done (all points) with OpenMP threads into `res`; the first
    !> error met, if any, is returned after all threads stop. `monitor` is told every finished
    !> sample and may ask to stop (samples running in other threads finish first). `mine`
    !> (points x samples, task order: sample s of point p is task s + samples (p - 1)) runs
    !> only the tasks it marks (the share of one MPI rank); all when absent.
    subroutine run_census_samples(cfg, res, err, monitor, mine)
        type(config_t), intent(in) :: cfg
        type(census_result_t), intent(inout) :: res
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        logical, intent(in), optional :: mine(:)
        type(error_t), allocatable :: task_err
        character(len=:), allocatable :: first_message
        logical :: stop_now
        integer :: t

        stop_now = .false.
        !$omp parallel do schedule(dynamic) private(task_err) shared(stop_now, res)
        do t = 1, res%n_points*res%n_samples
            if (present(mine)) then
                if (.not. mine(t)) cycle
            end if
            call run_task(cfg, t, res, stop_now, task_err, monitor)
            if (allocated(task_err)) then
                !$omp critical (census_results)
                if (.not. allocated(first_message)) first_message = task_err%message
                !$omp atomic write
                stop_now = .true.
                !$omp end critical (census_results)
            end if
        end do
        !$omp end parallel do
        if (allocated(first_message)) call set_error(err, first_message)
    end subroutine run_census_samples

    !> Task t: sample modulo(t - 1, samples) + 1 of point (t - 1) / samples + 1.
    subroutine run_task(cfg, t, res, stop_now, err, monitor)
        type(config_t), intent(in) :: cfg
        integer, intent(in) :: t
        type(census_result_t), intent(inout) :: res
        logical, intent(inout) :: stop_now
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(config_t) :: point
        integer :: s, p, n
        integer :: periods(cfg%model%n)
        integer(i8) :: sites(cfg%model%n + 1)
        real(wp) :: exponents(res%n_exponents), stderr(res%n_exponents)
        real(wp) :: x(cfg%model%n), v(cfg%model%n)
        real(wp), allocatable :: x0(:), v0(:)
        logical :: stopping, done

        n = cfg%model%n
        s = modulo(t - 1, res%n_samples) + 1
        p = (t - 1)/res%n_samples + 1
        !$omp critical (census_results)
        done = res%done(s, p)
        x0 = res%x0(:, s, p)
        v0 = res%v0(:, s, p)
        !$omp end critical (census_results)
        !$omp atomic read
        stopping = stop_now
        if (done .or. stopping) return
        call census_point_config(cfg, p, point, err)
        if (allocated(err)) return
        call run_sample(point, x0, v0, periods, sites, exponents, stderr, x, v, err)
        if (allocated(err)) then
            err%message = "&census: sample "//fmt_int(s)//point_text(cfg, res, p)//": "// &
                          err%message
            return
        end if
        !$omp critical (census_results)
        res%periods(:, s, p) = periods
        res%sites(:, s, p) = sites
        res%exponents(:, s, p) = exponents
        res%exponents_stderr(:, s, p) = stderr
        res%x(:, s, p) = x
        res%v(:, s, p) = v
        res%done(s, p) = .true.
        if (present(monitor)) then
            if (.not. monitor%keep_going(stage_samples, int(count(res%done), i8), &
                                         int(size(res%done), i8))) then
                !$omp atomic write
                stop_now = .true.
            end if
        end if
        !$omp end critical (census_results)
    end subroutine run_task

    !> One sample's record as pack_sample lays it out: nr reals and ni 64-bit integers for a
    !> chain of n oscillators and k exponents per sample.
    pure subroutine sample_record_sizes(n, k, nr, ni)
        integer, intent(in) :: n, k
        integer, intent(out) :: nr, ni

        nr = 2*n + 2*k       ! x(n), v(n), exponents(k), their stderrs(k)
        ni = 2 + 2*n         ! done, periods(n), sites(n+1)
    end subroutine sample_record_sizes

    !> Sample s of point p's results as plain numbers (sent between MPI ranks): values as they
    !> are, so unpack_sample restores them bit for bit.
    pure subroutine pack_sample(res, s, p, reals, ints)
        type(census_result_t), intent(in) :: res
        integer, intent(in) :: s, p
        real(wp), intent(out) :: reals(:)
        integer(i8), intent(out) :: ints(:)
        integer :: n, k

        n = size(res%x, 1)
        k = res%n_exponents
        reals(1:n) = res%x(:, s, p)
        reals(1 + n:2*n) = res%v(:, s, p)
        reals(1 + 2*n:2*n + k) = res%exponents(:, s, p)
        reals(1 + 2*n + k:2*n + 2*k) = res%exponents_stderr(:, s, p)
        ints(1) = merge(1_i8, 0_i8, res%done(s, p))
        ints(2:1 + n) = int(res%periods(:, s, p), i8)
        ints(2 + n:2 + 2*n) = res%sites(:, s, p)
    end subroutine pack_sample

    !> The inverse of pack_sample: sample s of point p takes the record's results.
    pure subroutine unpack_sample(reals, ints, s, p, res)
        real(wp), intent(in) :: reals(:)
        integer(i8), intent(in) :: ints(:)
        integer, intent(in) :: s, p
        type(census_result_t), intent(inout) :: res
        integer :: n, k

        n = size(res%x, 1)
        k = res%n_exponents
        res%x(:, s, p) = reals(1:n)
        res%v(:, s, p) = reals(1 + n:2*n)
        res%exponents(:, s, p) = reals(1 + 2*n:2*n + k)
        res%exponents_stderr(:, s, p) = reals(1 + 2*n + k:2*n + 2*k)
        res%done(s, p) = ints(1) == 1
        res%periods(:, s, p) = int(ints(2:1 + n))
        res%sites(:, s, p) = ints(2 + n:2 + 2*n)
    end subroutine unpack_sample

    !> " at point p (parameter = value)" for a sweep, else nothing.
    function point_text(cfg, res, p) result(text)
        type(config_t), intent(in) :: cfg
        type(census_result_t), intent(in) :: res
        integer, intent(in) :: p
        character(len=:), allocatable :: text

        text = ''
        if (cfg%sweep) text = " at point "//fmt_int(p)//" ("//cfg%sweep_parameter//" = "// &
                              fmt_real(res%values(p))//")"
    end function point_text

    !> Classify every sample (all done), point by point in sample order, by the rules of
    !> chain_attractor; then the fractions. A periodic attractor's states over one period, and
    !> half a drive period after each, come from its representative's last record
    !> (orbit_states). Attractors at different points are distinct.
    subroutine classify_census(cfg, res, err)
        type(config_t), intent(in) :: cfg
        type(census_result_t), intent(inout) :: res
        type(error_t), allocatable, intent(out) :: err
        type(config_t) :: point
        type(attractor_t), allocatable :: grown(:)
        real(wp), allocatable :: sites(:)
        integer :: s, p, a, period, kind, id
        logical :: mirror, mirrored

        res%n_attractors = 0
        if (allocated(res%attractors)) deallocate (res%attractors)
        allocate (res%attractors(8))
        do p = 1, res%n_points
            call census_point_config(cfg, p, point, err)
            if (allocated(err)) return
            mirror = cfg%census_mirror == 'merge' .and. mirror_symmetric(point%model%spacing)
            do s = 1, res%n_samples
                period = orbit_period(res%periods(:, s, p), point%record%max_period)
                kind = sample_kind(period, res%exponents(1, s, p), &
                                   res%exponents_stderr(1, s, p))
                sites = site_fractions(res%sites(:, s, p))
                call match_attractor(res%attractors(:res%n_attractors), p, kind, &
                                     res%periods(:, s, p), res%x(:, s, p), res%v(:, s, p), &
                                     sites, cfg%census_tolerance, mirror, id, mirrored)
                if (id == 0) then
                    if (res%n_attractors == size(res%attractors)) then
                        allocate (grown(2*size(res%attractors)))
                        grown(:res%n_attractors) = res%attractors
                        call move_alloc(grown, res%attractors)
                    end if
                    id = res%n_attractors + 1
                    call new_attractor(point, res, s, p, kind, period, sites, &
                                       res%attractors(id), err)
                    if (allocated(err)) return
                    res%n_attractors = id
                end if
                res%attractor(s, p) = id
                res%mirrored(s, p) = mirrored
            end do
        end do
        res%attractors = res%attractors(:res%n_attractors)
        deallocate (res%fraction, res%fraction_stderr)
        allocate (res%fraction(res%n_attractors, res%n_points))
        allocate (res%fraction_stderr(res%n_attractors, res%n_points))
        do p = 1, res%n_points
            do a = 1, res%n_attractors
                res%fraction(a, p) = real(count(res%attractor(:, p) == a), wp)/res%n_samples
            end do
        end do
        res%fraction_stderr = sqrt(res%fraction*(1 - res%fraction)/res%n_samples)
        call attractor_ensembles(res)
    end subroutine classify_census

    !> Each attractor's samples (at its point, in sample order) as an ensemble of spectra: the
    !> mean of their exponents and the spread between them (ensemble_statistics).
    subroutine attractor_ensembles(res)
        type(census_result_t), intent(inout) :: res
        integer, allocatable :: sizes(:), first(:), filled(:), members(:)
        integer :: s, p, a, na

        na = res%n_attractors
        if (allocated(res%attractor_exponents)) deallocate (res%attractor_exponents)
        if (allocated(res%attractor_spread)) deallocate (res%attractor_spread)
        allocate (res%attractor_exponents(res%n_exponents, na))
        allocate (res%attractor_spread(res%n_exponents, na))
        ! the members of each attractor, one after the other (a counting sort of the samples)
        allocate (sizes(na), first(na), filled(na), members(res%n_samples*res%n_points))
        sizes = 0
        do p = 1, res%n_points
            do s = 1, res%n_samples
                sizes(res%attractor(s, p)) = sizes(res%attractor(s, p)) + 1
            end do
        end do
        if (na > 0) first(1) = 1
        do a = 2, na
            first(a) = first(a - 1) + sizes(a - 1)
        end do
        filled = 0
        do p = 1, res%n_points
            do s = 1, res%n_samples
                a = res%attractor(s, p)
                members(first(a) + filled(a)) = s
                filled(a) = filled(a) + 1
            end do
        end do
        do a = 1, na
            associate (mine => members(first(a):first(a) + sizes(a) - 1))
                call ensemble_statistics(res%exponents(:, mine, res%attractors(a)%point), &
                                         res%attractor_exponents(:, a), &
                                         res%attractor_spread(:, a))
            end associate
        end do
    end subroutine attractor_ensembles

    !> The mean over m members of k exponents each (values(k, m); the members in the order
    !> given; zeros without members) and the spread between them, the sample standard deviation
    !> sqrt(sum (x - mean)**2 / (m - 1)), 0 for one member. An exponent of -infinity in a
    !> member (a direction removed by a rest on a wall, or K = 0) makes that mean -infinity, and
    !> its spread 0 when every member's is -infinity, +infinity when some are finite.
    pure subroutine ensemble_statistics(values, mean, spread)
        real(wp), intent(in) :: values(:, :)
        real(wp), intent(out) :: mean(:), spread(:)
        integer :: j, m

        m = size(values, 2)
        mean = 0
        spread = 0
        if (m == 0) return
        do j = 1, size(values, 1)
            mean(j) = sum(values(j, :))/m
            if (m == 1) then
                spread(j) = 0
            else if (all(ieee_is_finite(values(j, :)))) then
                spread(j) = sqrt(sum((values(j, :) - mean(j))**2)/(m - 1))
            else if (all(values(j, :) == values(j, 1))) then
                spread(j) = 0
            else
                spread(j) = ieee_value(1.0_wp, ieee_positive_inf)
            end if
        end do
    end subroutine ensemble_statistics

    !> The attractor that sample s of point p founds, with it as the representative. When its
    !> state cannot be run again as a fresh chain (chain_at_section refuses it), the orbit is
    !> its own state alone: copies at another cycle offset, and mirror images, then found
    !> attractors of their own.
    subroutine new_attractor(point, res, s, p, kind, period, sites, attractor, err)
        type(config_t), intent(in) :: point
        type(census_result_t), intent(in) :: res
        integer, intent(in) :: s, p, kind, period
        real(wp), intent(in) :: sites(:)
        type(attractor_t), intent(out) :: attractor
        type(error_t), allocatable, intent(out) :: err

        attractor%point = p
        attractor%first_sample = s
        attractor%kind = kind
        attractor%period = period
        attractor%periods = res%periods(:, s, p)
        attractor%lambda1 = res%exponents(1, s, p)
        attractor%stderr1 = res%exponents_stderr(1, s, p)
        attractor%x = res%x(:, s, p)
        attractor%v = res%v(:, s, p)
        attractor%sites = sites
        if (kind /= kind_periodic) return
        call orbit_states(point%model, point%record%phase, attractor%x, attractor%v, period, &
                          attractor%orbit_x, attractor%orbit_v, attractor%half_x, &
                          attractor%half_v, err)
        if (.not. allocated(err)) return
        deallocate (err)
        attractor%orbit_x = reshape(attractor%x, [size(attractor%x), 1])
        attractor%orbit_v = reshape(attractor%v, [size(attractor%v), 1])
        allocate (attractor%half_x(size(attractor%x), 0), attractor%half_v(size(attractor%x), 0))
    end subroutine new_attractor

    !> The states of a period-p orbit through (x, v) on the section (drive phase `phase`):
    !> orbit(:, k+1) k drive cycles later (k = 0..p-1; orbit(:, 1) is (x, v) itself), and
    !> half(:, k+1) half a drive period after each. They are run from (x, v) as a fresh chain
    !> on the section (chain_at_section: every oscillator moving, every bond searched).
    subroutine orbit_states(model, phase, x, v, p, orbit_x, orbit_v, half_x, half_v, err)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase, x(:), v(:)
        integer, intent(in) :: p
        real(wp), allocatable, intent(out) :: orbit_x(:, :), orbit_v(:, :)
        real(wp), allocatable, intent(out) :: half_x(:, :), half_v(:, :)
        type(error_t), allocatable, intent(out) :: err
        type(chain_t) :: chain
        type(event_log_t) :: log
        real(wp) :: s0, s_half, period
        integer(i8) :: cycle_half
        integer :: k

        allocate (orbit_x(size(x), p), orbit_v(size(x), p), half_x(size(x), p))
        allocate (half_v(size(x), p))
        orbit_x(:, 1) = x
        orbit_v(:, 1) = v
        call event_log_init(log, .false., 0)
        call chain_at_section(model, phase, x, v, chain, err)
        if (allocated(err)) return
        period = chain_period(chain)
        s0 = phase/model%omega
        do k = 0, p - 1
            cycle_half = k
            s_half = s0 + period/2
            if (s_half >= period) then
                cycle_half = k + 1
                s_half = s_half - period
            end if
            call advance_to_point(chain, cycle_half, s_half, log, err)
            if (allocated(err)) return
            half_x(:, k + 1) = chain_positions(chain)
            half_v(:, k + 1) = chain_velocities(chain)
            if (k == p - 1) exit
            call advance_to_point(chain, int(k + 1, i8), s0, log, err)
            if (allocated(err)) return
            orbit_x(:, k + 2) = chain_positions(chain)
            orbit_v(:, k + 2) = chain_velocities(chain)
        end do
    end subroutine orbit_states

    ! ---- checkpoints ---------------------------------------------------------------------

    !> The finished samples, written atomically (tmp + rename): a header naming the input and
    !> the census's sizes, then the per-sample arrays whole (values as they are, so bit for
    !> bit). A failed write is an error and leaves the previous checkpoint as it was.
    subroutine save_census_checkpoint(path, cfg, res, err)
        character(len=*), intent(in) :: path
        type(config_t), intent(in) :: cfg
        type(census_result_t), intent(in) :: res
        type(error_t), allocatable, intent(out) :: err
        character(len=256) :: msg
        integer :: u, ios
        integer(i8) :: written

        msg = ''
        open (newunit=u, file=path//'.tmp', access='stream', form='unformatted', &
              status='replace', action='write', iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call set_error(err, "&census: cannot write the checkpoint '"//path//".tmp' ("// &
                           trim(msg)//")")
            return
        end if
        write (u, iostat=ios, iomsg=msg) checkpoint_magic, len(cfg%input_text), &
            cfg%input_text, res%n_points, res%n_samples, cfg%model%n, res%n_exponents
        if (ios == 0) write (u, iostat=ios, iomsg=msg) merge(1, 0, res%done), res%periods, &
            res%sites, res%x0, res%v0, res%x, res%v, &
            res%exponents, res%exponents_stderr
        written = 0
        if (ios == 0) inquire (unit=u, pos=written, iostat=ios, iomsg=msg)
        call close_checked(u, path//'.tmp', written - 1, ios, msg)
        if (ios /= 0) then
            call set_error(err, "&census: cannot write the checkpoint '"//path//".tmp' ("// &
                           trim(msg)//")")
            return
        end if
        call rename_file(path//'.tmp', path, err)
    end subroutine save_census_checkpoint

    !> Resume from a checkpoint of the same input, if there is one (`res` from
    !> census_result_init).
    subroutine load_census_checkpoint(path, cfg, res, err)
        character(len=*), intent(in) :: path
        type(config_t), intent(in) :: cfg
        type(census_result_t), intent(inout) :: res
        type(error_t), allocatable, intent(out) :: err
        character(len=8) :: magic
        character(len=:), allocatable :: text
        integer :: u, ios, length, n_points, n_samples, n, k
        integer, allocatable :: done(:, :)
        logical :: exists, ours
        type(census_result_t) :: got

        inquire (file=path, exist=exists)
        if (.not. exists) return
        open (newunit=u, file=path, access='stream', form='unformatted', status='old', &
              action='read', iostat=ios)
        if (ios /= 0) return
        ours = .false.
        read (u, iostat=ios) magic, length
        if (ios == 0 .and. magic == checkpoint_magic .and. length == len(cfg%input_text)) then
            allocate (character(len=length) :: text)
            read (u, iostat=ios) text, n_points, n_samples, n, k
            ours = ios == 0 .and. text == cfg%input_text .and. n_points == res%n_points .and. &
                   n_samples == res%n_samples .and. n == cfg%model%n .and. k == res%n_exponents
        end if
        if (.not. ours) then
            close (u)
            call set_error(err, "&census: '"//path//"' is a checkpoint of another input "// &
                           "(or of another version); remove it to start afresh")
            return
        end if
        got = res
        allocate (done(n_samples, n_points))
        read (u, iostat=ios) done, got%periods, got%sites, got%x0, &
            got%v0, got%x, got%v, got%exponents, got%exponents_stderr
        close (u)
        if (ios /= 0) then
            call set_error(err, "&census: the checkpoint '"//path//"' is damaged; remove it "// &
                           "to start afresh")
            return
        end if
        got%done = done == 1
        call move_alloc(got%done, res%done)
        call move_alloc(got%periods, res%periods)
        call move_alloc(got%sites, res%sites)
        call move_alloc(got%x0, res%x0)
        call move_alloc(got%v0, res%v0)
        call move_alloc(got%x, res%x)
        call move_alloc(got%v, res%v)
        call move_alloc(got%exponents, res%exponents)
        call move_alloc(got%exponents_stderr, res%exponents_stderr)
    end subroutine load_census_checkpoint

    subroutine save_census_progress(monitor)
        class(census_checkpoint_monitor_t), intent(inout) :: monitor

        call save_census_checkpoint(monitor%path, monitor%cfg, monitor%res, monitor%err)
    end subroutine save_census_progress

end module chain_census
