!> Parameter sweeps: bifurcation diagrams and Lyapunov scans along one parameter, or a 2-D
!> grid of two (docs/model.md section 8; the paper's figures 10-13).
!>
!> Points are grouped in branches. Along `parameter` a branch is a continuation: each point
!> starts from the final state of the one before (the paper's procedure; the drive phase and
!> the cycle count run on), exactly as a run with `&initial kind = 'file'` on the previous
!> point's output would. Each value of `parameter2` is its own branch; in mode 'independent'
!> every point is its own branch and starts from the run's initial condition. Branches are
!> independent, so they run in parallel (OpenMP threads here, MPI ranks in mpi/) and every
!> point's numbers are the same whatever the number of threads or ranks.
!>
!> Continuation precisely: the next point starts from the previous point's final state (x, v,
!> the resting contacts, the cycle index and the time within the cycle, i.e. its last strobe
!> record), with the event schedule searched again under the new parameters; `chain_sim`
!> does the same for a start from a file whose /params differ. With `&run phase` /= 0 in an
!> 'omega' sweep, the time within the cycle is kept, so the drive phase of the start scales
!> with omega; records are then taken at the new section time phase / omega as usual.
!>
!> A sweep keeps, per point, only what /sweep stores (no events, no Jacobian). The HDF5 file
!> is written when every point is done (root `complete` = 1); until then the finished points
!> live in the checkpoint `file.h5.ckpt` (written every `checkpoint_every` seconds and when
!> stopped), from which the same input resumes.
module chain_sweep
    use chain_kinds, only: wp, i8, two_pi
    use chain_error, only: error_t, set_error, fmt_real, fmt_int
    use chain_engine, only: chain_t, chain_init
    use chain_model, only: set_model_parameter
    use chain_state, only: chain_state_t, moving_state
    use chain_config, only: config_t, validate_config, lyapunov_vectors, check_size, &
                            sweep_axis_points
    use chain_record, only: memory_sink_t, record_result_t, record_cycles
    use chain_sim, only: start_chain, write_run_header, continuation_start
    use chain_output, only: output_t, output_begin, output_group, output_end, output_abort, &
                            output_unset_param
    use chain_hdf5, only: h5_write, h5_write_attr, h5_set_scale
    use chain_describe, only: describe, index_coordinate, bare_dimension
    use chain_files, only: rename_file, remove_file, close_checked
    use chain_monitor, only: monitor_t, stage_points, saving_monitor_t
    implicit none
    private
    public :: sweep_plan_t, sweep_result_t, plan_sweep, sweep_point_config, run_branch
    public :: run_sweep_branches, sweep_result_init
    public :: run_sweep, write_sweep_file, sweep_summary_t, validate_sweep_points
    public :: check_sweep, check_sweep_size
    public :: checkpoint_path
    public :: save_checkpoint, load_checkpoint
    ! (chain_files' remove_file, for the drivers that delete a finished sweep's checkpoint)
    public :: branch_record_sizes, pack_branch, unpack_branch

    !> The checkpoint's first bytes; the number changes with the layout of pack_branch.
    character(len=8), parameter :: checkpoint_magic = 'ICSWEEP3'
    !> Seconds between checkpoints of a running sweep (and between MPI gathers in mpi/).

    type :: sweep_summary_t
        integer :: n_points = 0
        integer :: points_done = 0
        integer :: points_resumed = 0      !! points taken from a checkpoint
        logical :: complete = .false.
        real(wp) :: mean_collisions = 0
    end type sweep_summary_t

    type :: sweep_plan_t
        integer :: n_axis1 = 1          !! points along `parameter`
        integer :: n_axis2 = 1          !! values of `parameter2` (1 for a 1-D sweep)
        integer :: n_points = 1
        integer :: n_branches = 1
        integer :: points_per_branch = 1
        integer :: n_axes = 1
        integer :: k = 0                !! Lyapunov exponents per point (0: none)
    end type sweep_plan_t

    !> Everything stored per point (Fortran order; h5py shows the point index first).
    type :: sweep_result_t
        real(wp), allocatable :: values(:, :)        !! values(n_axes, n_points)
        real(wp), allocatable :: x(:, :, :)          !! x(n, cycles, n_points)
        real(wp), allocatable :: collisions(:)       !! collisions per cycle (n_points)
        integer, allocatable :: period(:, :)         !! period(n, n_points)
        real(wp), allocatable :: exponents(:, :)     !! exponents(k, n_points), bits/cycle
        real(wp), allocatable :: stderr(:, :)        !! stderr(k, n_points)
        integer(i8), allocatable :: stderr_block(:, :) !! (k, n_points): cycles per block of
                                                       !! the blocking plateau
        real(wp), allocatable :: ky(:)               !! ky(n_points)
        logical, allocatable :: done(:)              !! done(n_points)
    end type sweep_result_t

    !> run_sweep's monitor: the caller's, and a checkpoint every few seconds. It is told
    !> inside run_branch's critical section, so one thread at a time, with `res` and `starts`
    !> consistent. A checkpoint that cannot be written stops the sweep with that error (`err`):
    !> going on would risk hours of points on a full disk.
    type, extends(saving_monitor_t) :: checkpoint_monitor_t
        type(config_t) :: cfg
        type(sweep_plan_t) :: plan
        type(sweep_result_t), pointer :: res => null()
        type(chain_state_t), pointer :: starts(:) => null()
        character(len=:), allocatable :: path          !! of the checkpoint
    contains
        procedure :: save => save_sweep_checkpoint
    end type checkpoint_monitor_t

contains

    !> Sizes of the sweep described by cfg (validated: &sweep present).
    pure function plan_sweep(cfg) result(plan)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t) :: plan

        plan%n_axis1 = sweep_axis_points(cfg%sweep_start, cfg%sweep_stop, cfg%sweep_step)
        plan%n_axes = 1
        if (len(cfg%sweep_parameter2) > 0) then
            plan%n_axis2 = sweep_axis_points(cfg%sweep_start2, cfg%sweep_stop2, cfg%sweep_step2)
            plan%n_axes = 2
        end if
        plan%n_points = plan%n_axis1*plan%n_axis2
        if (cfg%sweep_mode == 'independent') then
            plan%n_branches = plan%n_points
            plan%points_per_branch = 1
        else
            plan%n_branches = plan%n_axis2
            plan%points_per_branch = plan%n_axis1
        end if
        plan%k = lyapunov_vectors(cfg)
    end function plan_sweep

    pure subroutine sweep_result_init(res, cfg, plan)
        type(sweep_result_t), intent(out) :: res
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        integer :: p

        allocate (res%values(plan%n_axes, plan%n_points))
        do p = 1, plan%n_points
            res%values(:, p) = point_values(cfg, plan, p)
        end do
        allocate (res%x(cfg%model%n, int(cfg%record%cycles), plan%n_points))
        allocate (res%collisions(plan%n_points), res%period(cfg%model%n, plan%n_points))
        allocate (res%exponents(plan%k, plan%n_points), res%stderr(plan%k, plan%n_points))
        allocate (res%stderr_block(plan%k, plan%n_points))
        allocate (res%ky(plan%n_points), res%done(plan%n_points))
        res%x = 0
        res%collisions = 0
        res%period = 0
        res%exponents = 0
        res%stderr = 0
        res%stderr_block = 0
        res%ky = 0
        res%done = .false.
    end subroutine sweep_result_init

    !> Parameter values of point p: index i along `parameter`, j along `parameter2`, computed
    !> from the indices (never by accumulating steps).
    pure function point_values(cfg, plan, p) result(values)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        integer, intent(in) :: p
        real(wp) :: values(plan%n_axes)
        integer :: i, j

        i = modulo(p - 1, plan%n_axis1) + 1
        j = (p - 1)/plan%n_axis1 + 1
        values(1) = cfg%sweep_start + (i - 1)*cfg%sweep_step
        if (plan%n_axes == 2) values(2) = cfg%sweep_start2 + (j - 1)*cfg%sweep_step2
    end function point_values

    !> The configuration of one point, validated (a value outside its range is an error
    !> naming the parameter and the point). A sweep stores neither events nor the Poincare-map
    !> Jacobian, so neither is collected (neither changes the motion).
    subroutine sweep_point_config(cfg, plan, p, point, err)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        integer, intent(in) :: p
        type(config_t), intent(out) :: point
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: values(plan%n_axes)

        point = cfg
        point%sweep = .false.
        point%record%record_events = .false.
        point%record%jacobian = .false.
        values = point_values(cfg, plan, p)
        call set_parameter(point, cfg%sweep_parameter, values(1))
        if (plan%n_axes == 2) call set_parameter(point, cfg%sweep_parameter2, values(2))
        call validate_config(point, err)
        if (allocated(err)) err%message = "&sweep: point "//fmt_int(p)//" ("// &
                                          cfg%sweep_parameter//" = "//fmt_real(values(1))// &
                                          "): "//err%message
    end subroutine sweep_point_config

    pure subroutine set_parameter(cfg, name, value)
        type(config_t), intent(inout) :: cfg
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: value

        call set_model_parameter(cfg%model, name, value)
    end subroutine set_parameter

    !> Run the points of branch b in order into `res`, skipping those already done (a resumed
    !> sweep); starts(b) holds where a continuation resumes. Results, the done flag and the
    !> resume state are written in one critical section, where `monitor` is then told the
    !> points done, the whole sweep being consistent (for progress and checkpoints); it may ask
    !> to stop (the points running in other threads finish first).
    subroutine run_branch(cfg, plan, b, res, starts, stop_now, err, monitor)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        integer, intent(in) :: b
        type(sweep_result_t), intent(inout) :: res
        type(chain_state_t), intent(inout) :: starts(:)
        logical, intent(inout) :: stop_now
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(config_t) :: point
        type(chain_t) :: chain
        type(memory_sink_t) :: sink
        type(record_result_t) :: out
        integer :: q, p
        logical :: stopping

        do q = 1, plan%points_per_branch
            p = (b - 1)*plan%points_per_branch + q
            if (res%done(p)) cycle
            !$omp atomic read
            stopping = stop_now
            if (stopping) return
            call sweep_point_config(cfg, plan, p, point, err)
            if (allocated(err)) return
            if (allocated(starts(b)%x)) then
                call chain_init(chain, point%model, starts(b), err)
            else
                ! a start from a file reads HDF5, which is not thread-safe
                !$omp critical (sweep_hdf5)
                call start_chain(point, chain, err)
                !$omp end critical (sweep_hdf5)
            end if
            if (allocated(err)) return
            call record_cycles(point%record, chain, sink, out, err)
            if (allocated(err)) return
            !$omp critical (sweep_results)
            res%x(:, :, p) = sink%x
            res%collisions(p) = out%collisions_per_cycle
            res%period(:, p) = out%periods
            if (out%has_lyapunov) then
                res%exponents(:, p) = out%lyapunov%bits_per_cycle
                res%stderr(:, p) = out%lyapunov%stderr_bits
                res%stderr_block(:, p) = out%lyapunov%stderr_cycles
                res%ky(p) = out%lyapunov%ky_dimension
            end if
            res%done(p) = .true.
            if (cfg%sweep_mode == 'continuation') then
                starts(b) = continuation_start(chain)
            end if
            if (present(monitor)) then
                if (.not. monitor%keep_going(stage_points, int(count(res%done), i8), &
                                             int(plan%n_points, i8))) then
                    !$omp atomic write
                    stop_now = .true.
                end if
            end if
            !$omp end critical (sweep_results)
            deallocate (sink%x, sink%v, sink%cycle)
        end do
    end subroutine run_branch

    !> Run the branches selected by `mine` (all when absent) with OpenMP threads; the first
    !> error met, if any, is returned after all threads stop.
    subroutine run_sweep_branches(cfg, plan, res, starts, err, mine, monitor)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(sweep_result_t), intent(inout) :: res
        type(chain_state_t), intent(inout) :: starts(:)
        type(error_t), allocatable, intent(out) :: err
        logical, intent(in), optional :: mine(:)
        class(monitor_t), intent(inout), optional :: monitor
        type(error_t), allocatable :: branch_err
        character(len=:), allocatable :: first_message
        logical :: stop_now
        integer :: b

        call check_size(cfg, err)
        if (allocated(err)) return
        stop_now = .false.
        !$omp parallel do schedule(dynamic) private(branch_err) shared(stop_now, res, starts)
        do b = 1, plan%n_branches
            if (present(mine)) then
                if (.not. mine(b)) cycle
            end if
            call run_branch(cfg, plan, b, res, starts, stop_now, branch_err, monitor)
            if (allocated(branch_err)) then
                !$omp critical (sweep_results)
                if (.not. allocated(first_message)) first_message = branch_err%message
                !$omp atomic write
                stop_now = .true.
                !$omp end critical (sweep_results)
            end if
        end do
        !$omp end parallel do
        if (allocated(first_message)) call set_error(err, first_message)
    end subroutine run_sweep_branches

    !> The whole sweep described by cfg: resumes from `file.ckpt` when one exists for the same
    !> input, checkpoints every few seconds, and writes the HDF5 file when every point is done.
    !> `monitor`, told the points done, may ask to stop: the checkpoint then keeps the finished
    !> points.
    subroutine run_sweep(cfg, summary, err, monitor)
        type(config_t), intent(in) :: cfg
        type(sweep_summary_t), intent(out) :: summary
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional, target :: monitor
        type(sweep_plan_t) :: plan
        type(sweep_result_t), target :: res
        type(chain_state_t), allocatable, target :: starts(:)
        type(output_t) :: out
        type(error_t), allocatable :: err2
        character(len=:), allocatable :: checkpoint
        type(checkpoint_monitor_t) :: watch

        plan = plan_sweep(cfg)
        call check_sweep(cfg, plan, err)
        if (allocated(err)) return
        call output_begin(out, cfg%output_file, cfg%overwrite, err)
        if (allocated(err)) return
        checkpoint = checkpoint_path(cfg)
        call sweep_result_init(res, cfg, plan)
        allocate (starts(plan%n_branches))
        call load_checkpoint(checkpoint, cfg, plan, res, starts, err)
        if (allocated(err)) then
            call output_abort(out)
            return
        end if
        summary%n_points = plan%n_points
        summary%points_resumed = count(res%done)
        if (present(monitor)) watch%outer => monitor
        watch%cfg = cfg
        watch%plan = plan
        watch%res => res
        watch%starts => starts
        watch%path = checkpoint
        call system_clock(watch%clock_last, watch%clock_rate)
        call run_sweep_branches(cfg, plan, res, starts, err, monitor=watch)
        ! a periodic checkpoint that could not be written stopped the sweep
        if (allocated(watch%err) .and. .not. allocated(err)) call move_alloc(watch%err, err)
        summary%points_done = count(res%done)
        summary%complete = all(res%done)
        ! (the partial file goes first: on a full disk its space is the checkpoint's room)
        if (.not. summary%complete .or. allocated(err)) then
            call output_abort(out)
            call save_checkpoint(checkpoint, cfg, plan, res, starts, err2)
            if (allocated(err2) .and. .not. allocated(err)) call move_alloc(err2, err)
            return
        end if
        summary%mean_collisions = sum(res%collisions)/plan%n_points
        call write_sweep_file(out, cfg, plan, res, err)
        if (.not. allocated(err)) call output_end(out, .true., err)
        if (allocated(err)) then
            ! every point is done: the checkpoint keeps them all, and the same command
            ! writes the file from it without computing anything again
            call output_abort(out)
            call save_checkpoint(checkpoint, cfg, plan, res, starts, err2)
            if (allocated(err2)) err%message = err%message//"; the checkpoint of the "// &
                                               "finished points could not be written either: "// &
                                               err2%message
            return
        end if
        call remove_file(checkpoint)
    end subroutine run_sweep

    subroutine save_sweep_checkpoint(monitor)
        class(checkpoint_monitor_t), intent(inout) :: monitor

        call save_checkpoint(monitor%path, monitor%cfg, monitor%plan, monitor%res, &
                             monitor%starts, monitor%err)
    end subroutine save_sweep_checkpoint

    !> Everything that refuses the sweep itself before any work, cheapest first: its results
    !> against &output max_size_mb, one point's records and tangent vectors (check_size), and
    !> every point's configuration. (The output file is output_begin's, or output_check's.)
    subroutine check_sweep(cfg, plan, err)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(error_t), allocatable, intent(out) :: err

        call check_sweep_size(cfg, plan, err)
        if (.not. allocated(err)) call check_size(cfg, err)
        if (.not. allocated(err)) call validate_sweep_points(cfg, plan, err)
    end subroutine check_sweep

    !> Refuse a sweep whose results exceed &output max_size_mb, as check_size does a run's:
    !> first /sweep in the file (x, collisions_per_cycle, period as 4-byte integers, and with
    !> exponents exponents, stderr, stderr_block, ky_dimension), then the memory, which holds
    !> every point's results (sweep_result_t) until the file is written, plus the largest copy
    !> made of them: a branch packed for a checkpoint (pack_branch: 8-byte values), or in a
    !> 2-D sweep /sweep/x reordered for the file. (The MPI driver's rank 0 also holds the
    !> gathered branches; the per-thread records of a running point are check_size's.)
    subroutine check_sweep_size(cfg, plan, err)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: points, n, k, records, file_mb, held, copy
        character(len=:), allocatable :: keys

        points = plan%n_points
        n = cfg%model%n
        k = plan%k
        records = 8*n*real(cfg%record%cycles, wp)  ! bytes of one point's /sweep/x
        keys = '&sweep start, stop, step'
        if (plan%n_axes == 2) keys = keys//', start2, stop2, step2'
        file_mb = points*(records + 8 + 4*n + merge(24*k + 8, 0.0_wp, plan%k > 0))/1.0e6_wp
        if (file_mb > cfg%max_size_mb) then
            call set_error(err, "&sweep: the records of this sweep need about "// &
                           fmt_real(file_mb)//" MB in the file ("//fmt_int(plan%n_points)// &
                           " points x n x cycles x 8 bytes, plus periods and exponents), "// &
                           "more than &output max_size_mb = "//fmt_real(cfg%max_size_mb)// &
                           "; lower the points ("//keys//") or &run cycles, or raise "// &
                           "max_size_mb")
            return
        end if
        ! values, x, collisions, period, exponents, stderr, stderr_block, ky, done
        held = points*(8*plan%n_axes + records + 8 + 4*n + 24*k + 8 + 4)
        ! pack_branch: per point 2 + n cycles + 2k reals and 1 + n + k integers; the resume
        ! state 2n + 1 reals and n + 2 integers
        copy = 8*(plan%points_per_branch*(3 + records/8 + n + 3*k) + 3*n + 3)
        if (plan%n_axes == 2) copy = max(copy, points*records)
        if ((held + copy)/1.0e6_wp > cfg%max_size_mb) &
            call set_error(err, "&sweep: this sweep needs about "// &
                           fmt_real((held + copy)/1.0e6_wp)//" MB of memory (every point's "// &
                           "records, kept until the file is written, and the copy a "// &
                           "checkpoint or the file's layout makes), more than &output "// &
                           "max_size_mb = "//fmt_real(cfg%max_size_mb)//"; lower the points ("// &
                           keys//") or &run cycles, or raise max_size_mb")
        ! (with max_size_mb raised far above its default: a branch's packed records and a
        ! point's records are counted in default integers, by the checkpoint and MPI too)
        if (.not. allocated(err) .and. max(copy/8, records/8) > huge(1)) &
            call set_error(err, "&sweep: a branch of this sweep holds about "// &
                           fmt_real(max(copy/8, records/8))//" values, more than the "// &
                           "2147483647 its checkpoint record counts; lower the points ("// &
                           keys//") or &run cycles")
    end subroutine check_sweep_size

    !> Validate every point before any work (an out-of-range point is an error up front).
    subroutine validate_sweep_points(cfg, plan, err)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(error_t), allocatable, intent(out) :: err
        type(config_t) :: point
        integer :: p

        do p = 1, plan%n_points
            call sweep_point_config(cfg, plan, p, point, err)
            if (allocated(err)) return
        end do
    end subroutine validate_sweep_points

    !> The checkpoint of the sweep writing cfg%output_file (the same for every driver, so that
    !> any of them resumes any other's).
    pure function checkpoint_path(cfg) result(path)
        type(config_t), intent(in) :: cfg
        character(len=:), allocatable :: path

        path = cfg%output_file//'.ckpt'
    end function checkpoint_path

    !> Header of a normal run (for the sweep's starting configuration, without the swept
    !> parameters, which /params cannot hold as one number) and the /sweep group: the swept
    !> parameters and the mode as attributes; the coordinates `point` (the values of
    !> `parameter`) and, in a 2-D sweep, `point2` (those of `parameter2`); per point the
    !> records, the periods, any exponents, and the drive period in an omega sweep. The point
    !> axes come first in h5py's order: (point, record, oscillator), or (point, point2,
    !> record, oscillator) in a 2-D sweep.
    subroutine write_sweep_file(out, cfg, plan, res, err)
        type(output_t), intent(inout) :: out
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(sweep_result_t), intent(in) :: res
        type(error_t), allocatable, intent(out) :: err
        integer :: n1

        call write_run_header(out, cfg, err)
        if (allocated(err)) return
        call output_unset_param(out, cfg%sweep_parameter, err)
        if (plan%n_axes == 2 .and. .not. allocated(err)) &
            call output_unset_param(out, cfg%sweep_parameter2, err)
        if (.not. allocated(err)) call output_group(out, 'sweep', err)
        if (allocated(err)) return
        n1 = plan%n_axis1
        associate (f => out%file)
            call h5_write_attr(f, 'sweep', 'parameter', cfg%sweep_parameter, err)
            call h5_write_attr(f, 'sweep', 'parameter2', cfg%sweep_parameter2, err)
            call h5_write_attr(f, 'sweep', 'mode', cfg%sweep_mode, err)
            call sweep_axis(out, 'sweep/point', cfg%sweep_parameter, res%values(1, :n1), err)
            if (plan%n_axes == 2) then
                call sweep_axis(out, 'sweep/point2', cfg%sweep_parameter2, &
                                res%values(2, ::n1), err)
            end if
            if (allocated(err)) return
            call bare_dimension(f, 'sweep/record', int(cfg%record%cycles, i8), .false., err)
            call index_coordinate(f, 'sweep/oscillator', 1, cfg%model%n, err)
        end associate
        if (.not. allocated(err)) call write_sweep_records(out, cfg, plan, res, err)
        if (.not. allocated(err)) call write_drive_periods(out, cfg, plan, res, err)
        if (plan%k > 0 .and. .not. allocated(err)) &
            call write_sweep_exponents(out, plan, res, err)
    end subroutine write_sweep_file

    !> /sweep/x, collisions_per_cycle and period. A 2-D sweep's points (index i along
    !> parameter, j along parameter2) are stored in order p = i + (j - 1) n1; in the file their
    !> axes are (point, point2).
    subroutine write_sweep_records(out, cfg, plan, res, err)
        type(output_t), intent(inout) :: out
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(sweep_result_t), intent(in) :: res
        type(error_t), allocatable, intent(inout) :: err
        integer :: n, c, n1, n2

        n = cfg%model%n
        c = int(cfg%record%cycles)
        n1 = plan%n_axis1
        n2 = plan%n_axis2
        associate (f => out%file)
            if (plan%n_axes == 1) then
                call h5_write(f, 'sweep/x', res%x, err)
                call h5_write(f, 'sweep/collisions_per_cycle', res%collisions, err)
                call h5_write(f, 'sweep/period', res%period, err)
            else
                call h5_write(f, 'sweep/x', reshape(res%x, [n, c, n2, n1], order=[1, 2, 4, 3]), err)
                call h5_write(f, 'sweep/collisions_per_cycle', &
                              reshape(res%collisions, [n2, n1], order=[2, 1]), err)
                call h5_write(f, 'sweep/period', reshape(res%period, [n, n2, n1], &
                                                         order=[1, 3, 2]), err)
            end if
        end associate
        if (allocated(err)) return
        call describe(out%file, 'sweep/x', err, axes=plan%n_axes)
        call describe(out%file, 'sweep/collisions_per_cycle', err, axes=plan%n_axes)
        call describe(out%file, 'sweep/period', err, axes=plan%n_axes)
    end subroutine write_sweep_records

    !> /sweep/exponents, stderr, stderr_block and ky_dimension, in the layout of
    !> write_sweep_records.
    subroutine write_sweep_exponents(out, plan, res, err)
        type(output_t), intent(inout) :: out
        type(sweep_plan_t), intent(in) :: plan
        type(sweep_result_t), intent(in) :: res
        type(error_t), allocatable, intent(inout) :: err
        integer :: n1, n2

        n1 = plan%n_axis1
        n2 = plan%n_axis2
        call index_coordinate(out%file, 'sweep/exponent', 1, plan%k, err)
        if (allocated(err)) return
        associate (f => out%file)
            if (plan%n_axes == 1) then
                call h5_write(f, 'sweep/exponents', res%exponents, err)
                call h5_write(f, 'sweep/stderr', res%stderr, err)
                call h5_write(f, 'sweep/stderr_block', res%stderr_block, err)
                call h5_write(f, 'sweep/ky_dimension', res%ky, err)
            else
                call h5_write(f, 'sweep/exponents', reshape(res%exponents, [plan%k, n2, n1], &
                                                            order=[1, 3, 2]), err)
                call h5_write(f, 'sweep/stderr', reshape(res%stderr, [plan%k, n2, n1], &
                                                         order=[1, 3, 2]), err)
                call h5_write(f, 'sweep/stderr_block', reshape(res%stderr_block, &
                                                               [plan%k, n2, n1], &
                                                               order=[1, 3, 2]), err)
                call h5_write(f, 'sweep/ky_dimension', reshape(res%ky, [n2, n1], &
                                                               order=[2, 1]), err)
            end if
        end associate
        if (allocated(err)) return
        call describe(out%file, 'sweep/exponents', err, axes=plan%n_axes)
        call describe(out%file, 'sweep/stderr', err, axes=plan%n_axes)
        call describe(out%file, 'sweep/stderr_block', err, axes=plan%n_axes)
        call describe(out%file, 'sweep/ky_dimension', err, axes=plan%n_axes)
    end subroutine write_sweep_exponents

    !> /sweep/drive_period along the omega axis of an omega sweep (2 pi / w, as
    !> chain_flow's make_flow computes it).
    subroutine write_drive_periods(out, cfg, plan, res, err)
        type(output_t), intent(inout) :: out
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(sweep_result_t), intent(in) :: res
        type(error_t), allocatable, intent(inout) :: err
        integer :: n1

        n1 = plan%n_axis1
        if (cfg%sweep_parameter == 'omega') then
            call h5_write(out%file, 'sweep/drive_period', two_pi/res%values(1, :n1), err)
            call describe(out%file, 'sweep/drive_period', err, along=1)
        else if (plan%n_axes == 2 .and. cfg%sweep_parameter2 == 'omega') then
            call h5_write(out%file, 'sweep/drive_period', two_pi/res%values(2, ::n1), err)
            call describe(out%file, 'sweep/drive_period', err, along=2)
        end if
    end subroutine write_drive_periods

    !> The coordinate variable `name` of a sweep axis: the values of `parameter` there.
    subroutine sweep_axis(out, name, parameter, values, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: name, parameter
        real(wp), intent(in) :: values(:)
        type(error_t), allocatable, intent(inout) :: err
        real(wp), allocatable :: coordinates(:) ! (values may be strided: a contiguous copy)

        if (allocated(err)) return
        coordinates = values
        call h5_write(out%file, name, coordinates, err)
        call h5_set_scale(out%file, name, err)
        call describe(out%file, name, err, parameter=parameter)
    end subroutine sweep_axis

    !> Finished points and where each branch resumes, written atomically (tmp + rename): a
    !> header naming the input and the sweep's sizes, then every branch as pack_branch lays
    !> it out. A failed write is an error and leaves the previous checkpoint as it was; since
    !> a full disk can go unreported by buffered writes, the file's size is checked before it
    !> replaces the previous one.
    subroutine save_checkpoint(path, cfg, plan, res, starts, err)
        character(len=*), intent(in) :: path
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(sweep_result_t), intent(in) :: res
        type(chain_state_t), intent(in) :: starts(:)
        type(error_t), allocatable, intent(out) :: err
        character(len=256) :: msg
        integer :: u, ios, b, nr, ni
        integer(i8) :: written
        real(wp), allocatable :: reals(:)
        integer(i8), allocatable :: ints(:)

        msg = ''
        open (newunit=u, file=path//'.tmp', access='stream', form='unformatted', &
              status='replace', action='write', iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call set_error(err, "&sweep: cannot write the checkpoint '"//path//".tmp' ("// &
                           trim(msg)//")")
            return
        end if
        write (u, iostat=ios, iomsg=msg) checkpoint_magic, len(cfg%input_text), &
            cfg%input_text, plan%n_points, cfg%model%n, cfg%record%cycles, plan%k, plan%n_branches
        call branch_record_sizes(cfg, plan, nr, ni)
        allocate (reals(nr), ints(ni))
        do b = 1, plan%n_branches
            if (ios /= 0) exit
            call pack_branch(cfg, plan, res, starts, b, reals, ints)
            write (u, iostat=ios, iomsg=msg) reals, ints
        end do
        written = 0
        if (ios == 0) inquire (unit=u, pos=written, iostat=ios, iomsg=msg)
        call close_checked(u, path//'.tmp', written - 1, ios, msg)
        if (ios /= 0) then
            call set_error(err, "&sweep: cannot write the checkpoint '"//path//".tmp' ("// &
                           trim(msg)//")")
            return
        end if
        call rename_file(path//'.tmp', path, err)
    end subroutine save_checkpoint

    !> Resume from a checkpoint of the same input, if there is one.
    subroutine load_checkpoint(path, cfg, plan, res, starts, err)
        character(len=*), intent(in) :: path
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(sweep_result_t), intent(inout) :: res
        type(chain_state_t), intent(inout) :: starts(:)
        type(error_t), allocatable, intent(out) :: err
        character(len=8) :: magic
        character(len=:), allocatable :: text
        integer :: u, ios, length, n_points, n, k, n_branches, b, nr, ni
        integer(i8) :: cycles
        real(wp), allocatable :: reals(:)
        integer(i8), allocatable :: ints(:)
        logical :: exists, ours

        inquire (file=path, exist=exists)
        if (.not. exists) return
        open (newunit=u, file=path, access='stream', form='unformatted', status='old', &
              action='read', iostat=ios)
        if (ios /= 0) return
        ours = .false.
        read (u, iostat=ios) magic, length
        if (ios == 0 .and. magic == checkpoint_magic .and. length == len(cfg%input_text)) then
            allocate (character(len=length) :: text)
            read (u, iostat=ios) text, n_points, n, cycles, k, n_branches
            ours = ios == 0 .and. text == cfg%input_text .and. n_points == plan%n_points .and. &
                   n == cfg%model%n .and. cycles == cfg%record%cycles .and. k == plan%k .and. &
                   n_branches == plan%n_branches
        end if
        if (.not. ours) then
            close (u)
            call set_error(err, "&sweep: '"//path//"' is a checkpoint of another input "// &
                           "(or of another version); remove it to start afresh")
            return
        end if
        call branch_record_sizes(cfg, plan, nr, ni)
        allocate (reals(nr), ints(ni))
        do b = 1, n_branches
            read (u, iostat=ios) reals, ints
            if (ios /= 0) exit
            call unpack_branch(cfg, plan, b, reals, ints, res, starts)
        end do
        close (u)
        if (ios /= 0) call set_error(err, "&sweep: the checkpoint '"//path//"' is damaged; "// &
                                     "remove it to start afresh")
    end subroutine load_checkpoint

    !> Lengths of one branch in pack_branch's layout: nr reals and ni integers.
    pure subroutine branch_record_sizes(cfg, plan, nr, ni)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        integer, intent(out) :: nr, ni

        nr = plan%points_per_branch*point_reals(cfg, plan) + 2*cfg%model%n + 1
        ni = plan%points_per_branch*point_ints(cfg, plan) + cfg%model%n + 2
    end subroutine branch_record_sizes

    !> Reals per point: collisions, x (n x cycles), exponents, stderr, Kaplan-Yorke dimension.
    pure integer function point_reals(cfg, plan)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan

        point_reals = 2 + cfg%model%n*int(cfg%record%cycles) + 2*plan%k
    end function point_reals

    !> Integers per point: done, periods (n), the standard errors' blocks (k).
    pure integer function point_ints(cfg, plan)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan

        point_ints = 1 + cfg%model%n + plan%k
    end function point_ints

    !> Branch b of a sweep, its points and the state it resumes from, as two plain arrays
    !> (sizes from branch_record_sizes): the one layout of the sweep's results outside
    !> memory, for the checkpoint and for MPI (values as they are, so bit for bit). Point
    !> by point, the reals of point_reals and the integers of point_ints; then the resume
    !> state, reals x, v, s and integers resume, contact, cycle (zeros when not resuming).
    pure subroutine pack_branch(cfg, plan, res, starts, b, reals, ints)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(sweep_result_t), intent(in) :: res
        type(chain_state_t), intent(in) :: starts(:)
        integer, intent(in) :: b
        real(wp), intent(out) :: reals(:)
        integer(i8), intent(out) :: ints(:)
        integer :: q, p, nr, ni

        nr = point_reals(cfg, plan)
        ni = point_ints(cfg, plan)
        do q = 1, plan%points_per_branch
            p = (b - 1)*plan%points_per_branch + q
            reals((q - 1)*nr + 1:q*nr) = [res%collisions(p), &
                                          reshape(res%x(:, :, p), &
                                              [cfg%model%n*int(cfg%record%cycles)]), &
                                          res%exponents(:, p), res%stderr(:, p), res%ky(p)]
            ints((q - 1)*ni + 1:q*ni) = [merge(1_i8, 0_i8, res%done(p)), &
                                         int(res%period(:, p), i8), res%stderr_block(:, p)]
        end do
        reals(plan%points_per_branch*nr + 1:) = 0
        ints(plan%points_per_branch*ni + 1:) = 0
        if (.not. allocated(starts(b)%x)) return
        reals(plan%points_per_branch*nr + 1:) = [starts(b)%x, starts(b)%v, starts(b)%time]
        ints(plan%points_per_branch*ni + 1:) = [1_i8, int(starts(b)%contact, i8), &
                                                starts(b)%cycle]
    end subroutine pack_branch

    !> Branch b of a sweep back from pack_branch's arrays into `res` and `starts`.
    pure subroutine unpack_branch(cfg, plan, b, reals, ints, res, starts)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        integer, intent(in) :: b
        real(wp), intent(in) :: reals(:)
        integer(i8), intent(in) :: ints(:)
        type(sweep_result_t), intent(inout) :: res
        type(chain_state_t), intent(inout) :: starts(:)
        integer :: q, p, n, m, k, j, i

        n = cfg%model%n
        m = n*int(cfg%record%cycles)
        k = plan%k
        do q = 1, plan%points_per_branch
            p = (b - 1)*plan%points_per_branch + q
            j = (q - 1)*point_reals(cfg, plan)
            i = (q - 1)*point_ints(cfg, plan)
            res%collisions(p) = reals(j + 1)
            res%x(:, :, p) = reshape(reals(j + 2:j + 1 + m), [n, int(cfg%record%cycles)])
            res%exponents(:, p) = reals(j + 2 + m:j + 1 + m + k)
            res%stderr(:, p) = reals(j + 2 + m + k:j + 1 + m + 2*k)
            res%ky(p) = reals(j + 2 + m + 2*k)
            res%done(p) = ints(i + 1) == 1
            res%period(:, p) = int(ints(i + 2:i + 1 + n))
            res%stderr_block(:, p) = ints(i + 2 + n:i + 1 + n + k)
        end do
        j = plan%points_per_branch*point_reals(cfg, plan)
        i = plan%points_per_branch*point_ints(cfg, plan)
        if (ints(i + 1) /= 1) then
            starts(b) = chain_state_t()
            return
        end if
        starts(b) = moving_state(reals(j + 1:j + n), reals(j + n + 1:j + 2*n), ints(i + 2 + n), &
                                 reals(j + 2*n + 1))
        starts(b)%contact = int(ints(i + 2:i + 1 + n))
    end subroutine unpack_branch


end module chain_sweep
