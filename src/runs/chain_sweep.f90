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
!>
!> This module plans a sweep (its points, branches and results), refuses one before any work
!> and writes its file; chain_sweep_run runs it, chain_sweep_checkpoint keeps it on disk.
module chain_sweep
    use chain_kinds, only: wp, i8, two_pi
    use chain_error, only: error_t, set_error, fmt_real, fmt_int
    use chain_model, only: set_model_parameter
    use chain_config, only: config_t, validate_config, lyapunov_vectors, check_size, &
                            sweep_axis_points
    use chain_sim, only: write_run_header
    use chain_output, only: output_t, output_group, output_unset_param
    use chain_hdf5, only: h5_write, h5_write_attr, h5_set_scale
    use chain_describe, only: describe, index_coordinate, bare_dimension
    implicit none
    private
    public :: sweep_plan_t, sweep_result_t, plan_sweep, sweep_point_config
    public :: sweep_result_init, write_sweep_file, validate_sweep_points
    public :: check_sweep, check_sweep_size

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

end module chain_sweep
