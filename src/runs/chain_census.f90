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
!>
!> This module makes a census's starts and runs its samples; chain_census_classify tells them
!> apart, chain_census_checkpoint keeps them on disk, chain_census_file writes the file.
module chain_census
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_real, fmt_int
    use chain_engine, only: chain_t, chain_init, chain_positions, chain_velocities
    use chain_state, only: chain_state_t, moving_state
    use chain_config, only: config_t, validate_config, plane_coordinate
    use chain_model, only: bond_gaps
    use chain_record, only: memory_sink_t, record_result_t, record_cycles
    use chain_sim, only: uniform, initial_state
    use chain_sweep, only: sweep_plan_t, plan_sweep, sweep_point_config
    use chain_attractor, only: attractor_t
    use chain_monitor, only: monitor_t, stage_samples
    use chain_task_farm, only: task_runner_t, task_output_t, run_tasks
    implicit none
    private
    public :: census_result_t, census_result_init, census_points, census_point_config
    public :: sample_seed, sample_start, run_sample, run_census_samples
    public :: census_starts, plane_starts, plane_value

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

    !> A census as the task farm runs it: task t is one sample (task_sample).
    type, extends(task_runner_t) :: census_runner_t
        type(config_t) :: cfg
        type(census_result_t), pointer :: res => null()
    contains
        procedure :: units => one_sample
        procedure :: done => sample_done
        procedure :: run_unit => run_task_sample
        procedure :: store => store_sample
        procedure :: progress => samples_done
    end type census_runner_t

    !> One sample's results (run_sample's).
    type, extends(task_output_t) :: sample_output_t
        integer, allocatable :: periods(:)
        integer(i8), allocatable :: sites(:)
        real(wp), allocatable :: exponents(:), stderr(:), x(:), v(:)
    end type sample_output_t

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

    !> Run every sample not yet done (all points) with OpenMP threads into `res` (the tasks
    !> of chain_task_farm, one sample each); the first error by task order, if any, is
    !> returned after all threads stop. `monitor` is told every finished sample and may ask
    !> to stop (samples running in other threads finish first). `mine` (points x samples, task
    !> order: sample s of point p is task s + samples (p - 1)) runs only the tasks it marks
    !> (the share of one MPI rank); all when absent.
    subroutine run_census_samples(cfg, res, err, monitor, mine)
        type(config_t), intent(in) :: cfg
        type(census_result_t), intent(inout), target :: res
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        logical, intent(in), optional :: mine(:)
        type(census_runner_t) :: runner

        runner%stage = stage_samples
        runner%cfg = cfg
        runner%res => res
        call run_tasks(runner, res%n_points*res%n_samples, err, mine, monitor)
    end subroutine run_census_samples

    !> Task t is sample modulo(t - 1, samples) + 1 of point (t - 1) / samples + 1.
    pure subroutine task_sample(res, t, s, p)
        type(census_result_t), intent(in) :: res
        integer, intent(in) :: t
        integer, intent(out) :: s, p

        s = modulo(t - 1, res%n_samples) + 1
        p = (t - 1)/res%n_samples + 1
    end subroutine task_sample

    integer function one_sample(runner, t)
        class(census_runner_t), intent(in) :: runner
        integer, intent(in) :: t

        one_sample = 1
    end function one_sample

    logical function sample_done(runner, t, u)
        class(census_runner_t), intent(in) :: runner
        integer, intent(in) :: t, u
        integer :: s, p

        call task_sample(runner%res, t, s, p)
        sample_done = runner%res%done(s, p)
    end function sample_done

    !> The sample of task t from its start.
    subroutine run_task_sample(runner, t, u, output, err)
        class(census_runner_t), intent(in) :: runner
        integer, intent(in) :: t, u
        class(task_output_t), allocatable, intent(out) :: output
        type(error_t), allocatable, intent(out) :: err
        type(config_t) :: point
        type(sample_output_t), allocatable :: got
        integer :: s, p, n, k

        call task_sample(runner%res, t, s, p)
        call census_point_config(runner%cfg, p, point, err)
        if (allocated(err)) return
        n = runner%cfg%model%n
        k = runner%res%n_exponents
        allocate (got)
        allocate (got%periods(n), got%sites(n + 1), got%exponents(k), got%stderr(k))
        allocate (got%x(n), got%v(n))
        call run_sample(point, runner%res%x0(:, s, p), runner%res%v0(:, s, p), got%periods, &
                        got%sites, got%exponents, got%stderr, got%x, got%v, err)
        if (allocated(err)) then
            err%message = "&census: sample "//fmt_int(s)//point_text(runner%cfg, runner%res, p)// &
                          ": "//err%message
            return
        end if
        call move_alloc(got, output)
    end subroutine run_task_sample

    subroutine store_sample(runner, t, u, output)
        class(census_runner_t), intent(inout) :: runner
        integer, intent(in) :: t, u
        class(task_output_t), intent(in) :: output
        integer :: s, p

        call task_sample(runner%res, t, s, p)
        select type (output)
        type is (sample_output_t)
            associate (res => runner%res)
                res%periods(:, s, p) = output%periods
                res%sites(:, s, p) = output%sites
                res%exponents(:, s, p) = output%exponents
                res%exponents_stderr(:, s, p) = output%stderr
                res%x(:, s, p) = output%x
                res%v(:, s, p) = output%v
                res%done(s, p) = .true.
            end associate
        end select
    end subroutine store_sample

    subroutine samples_done(runner, done, total)
        class(census_runner_t), intent(in) :: runner
        integer(i8), intent(out) :: done, total

        done = count(runner%res%done)
        total = size(runner%res%done)
    end subroutine samples_done

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

end module chain_census
