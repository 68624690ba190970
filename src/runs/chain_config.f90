!> The run configuration: namelist input, defaults, and validation with messages that name the
!> group, the key, the value and the allowed range.
!>
!> Groups: &chain (the model, required), &initial, &run, &lyapunov, &output, &sweep,
!> &continuation, &census (optional).
!> Every key is documented in the README. A group may appear at most once; an unknown group or
!> key is an error, never silently ignored.
!> The model's parameters are those of docs/model.md section 1; run, Lyapunov and sweep keys
!> those of sections 6-8; &census those of section 13.
module chain_config
    use, intrinsic :: iso_fortran_env, only: iostat_end
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use chain_kinds, only: wp, i8, two_pi
    use chain_error, only: error_t, set_error, fmt_real, fmt_int, fmt_int8
    use chain_files, only: same_file
    use chain_gaps, only: max_steps
    use chain_model, only: model_t, model_walls, model_parameters, model_parameter, &
                           set_model_parameter
    use chain_record, only: record_spec_t, vector_count
    use chain_lyapunov, only: running_rows
    use chain_clv, only: clv_scratch_bytes
    use chain_namelist, only: key_spec_t, key_integer, key_real, key_logical, key_string, &
                              alias_t, check_namelist, apply_override, groups_in, lower
    implicit none
    private
    public :: config_t, read_config, validate_config, config_summary, lyapunov_vectors
    public :: max_list, fmt_real, fmt_int, sweep_parameters, set_boundary, check_size
    public :: plane_coordinate, sweep_axis_points

    !> Longest explicit list in a namelist (spacing, x0, v0); longer chains use a file start.
    integer, parameter :: max_list = 100001
    integer, parameter :: max_n = 10000000
    real(wp), parameter :: unset = -huge(1.0_wp)
    !> An integer key not given in the input (for defaults that depend on other keys).
    integer, parameter :: not_given = -huge(1)
    character(len=*), parameter :: group_names(8) = &
        [character(len=12) :: 'chain', 'initial', 'run', 'lyapunov', 'output', 'sweep', &
         'continuation', 'census']
    !> Most points of a sweep, along one parameter or in a 2-D grid.
    integer, parameter :: max_sweep_points = 10000000
    !> Most samples of a census (per point).
    integer, parameter :: max_samples = 10000000
    !> Most points along each side of a census plane (max_plane_points**2 <= max_samples).
    integer, parameter :: max_plane_points = 3162
    !> Every key of every group with its type: what the namelist statements of the read_*
    !> procedures below declare (test/python/test_namelist_errors.py checks the two agree).
    type(key_spec_t), parameter :: input_keys(*) = [ &
        key_spec_t('chain', 'n', key_integer, .false.), &
        key_spec_t('chain', 'spacing', key_real, .true., most=max_list), &
        key_spec_t('chain', 'damping', key_real, .false.), &
        key_spec_t('chain', 'restitution', key_real, .false.), &
        key_spec_t('chain', 'amplitude', key_real, .false.), &
        key_spec_t('chain', 'omega', key_real, .false.), &
        key_spec_t('chain', 'boundary', key_string, .false.), &
        key_spec_t('initial', 'kind', key_string, .false.), &
        key_spec_t('initial', 'seed', key_integer, .false.), &
        key_spec_t('initial', 'x_amp', key_real, .false.), &
        key_spec_t('initial', 'v_amp', key_real, .false.), &
        key_spec_t('initial', 'x0', key_real, .true., most=max_list), &
        key_spec_t('initial', 'v0', key_real, .true., most=max_list), &
        key_spec_t('initial', 'file', key_string, .false.), &
        key_spec_t('run', 'transient', key_integer, .false., .true.), &
        key_spec_t('run', 'cycles', key_integer, .false., .true.), &
        key_spec_t('run', 'phase', key_real, .false.), &
        key_spec_t('run', 'record_events', key_logical, .false.), &
        key_spec_t('run', 'stick_speed', key_real, .false.), &
        key_spec_t('run', 'max_period', key_integer, .false.), &
        key_spec_t('run', 'period_tol', key_real, .false.), &
        key_spec_t('lyapunov', 'enabled', key_logical, .false.), &
        key_spec_t('lyapunov', 'vectors', key_integer, .false.), &
        key_spec_t('lyapunov', 'qr_every', key_integer, .false.), &
        key_spec_t('lyapunov', 'align', key_integer, .false.), &
        key_spec_t('lyapunov', 'jacobian', key_logical, .false.), &
        key_spec_t('lyapunov', 'jacobian_cycles', key_integer, .false.), &
        key_spec_t('lyapunov', 'covariant', key_logical, .false.), &
        key_spec_t('lyapunov', 'clv_transient', key_integer, .false.), &
        key_spec_t('lyapunov', 'clv_store', key_integer, .false.), &
        key_spec_t('lyapunov', 'clv_save', key_integer, .false.), &
        key_spec_t('lyapunov', 'window', key_integer, .false.), &
        key_spec_t('output', 'file', key_string, .false.), &
        key_spec_t('output', 'overwrite', key_logical, .false.), &
        key_spec_t('output', 'max_size_mb', key_real, .false.), &
        key_spec_t('sweep', 'parameter', key_string, .false.), &
        key_spec_t('sweep', 'start', key_real, .false.), &
        key_spec_t('sweep', 'stop', key_real, .false.), &
        key_spec_t('sweep', 'step', key_real, .false.), &
        key_spec_t('sweep', 'mode', key_string, .false.), &
        key_spec_t('sweep', 'parameter2', key_string, .false.), &
        key_spec_t('sweep', 'start2', key_real, .false.), &
        key_spec_t('sweep', 'stop2', key_real, .false.), &
        key_spec_t('sweep', 'step2', key_real, .false.), &
        key_spec_t('continuation', 'parameter', key_string, .false.), &
        key_spec_t('continuation', 'stop', key_real, .false.), &
        key_spec_t('continuation', 'step', key_real, .false.), &
        key_spec_t('continuation', 'period', key_integer, .false.), &
        key_spec_t('continuation', 'max_points', key_integer, .false.), &
        key_spec_t('continuation', 'doublings', key_integer, .false.), &
        key_spec_t('census', 'samples', key_integer, .false.), &
        key_spec_t('census', 'seed', key_integer, .false.), &
        key_spec_t('census', 'x_amp', key_real, .false.), &
        key_spec_t('census', 'v_amp', key_real, .false.), &
        key_spec_t('census', 'tolerance', key_real, .false.), &
        key_spec_t('census', 'mirror', key_string, .false.), &
        key_spec_t('census', 'plane', key_string, .true., most=2), &
        key_spec_t('census', 'plane_range', key_real, .true., most=4), &
        key_spec_t('census', 'plane_points', key_integer, .false.), &
        key_spec_t('census', 'exponents', key_integer, .false.)]
    character(len=*), parameter :: sweep_parameters(*) = model_parameters
    !> The paper's symbols for the keys of &chain (docs/model.md section 1), named in the
    !> message that refuses one (`&chain A = 1.7` is an unknown key): A amplitude, a spacing,
    !> w omega, K restitution, b damping (n is the key itself). Keys are case-blind, so the
    !> paper's A and a are one name to the reader, which the message says.
    type(alias_t), parameter :: paper_symbols(*) = [ &
        alias_t('chain', 'A', 'amplitude', "the paper's drive amplitude"), &
        alias_t('chain', 'a', 'spacing', "the paper's spacing"), &
        alias_t('chain', 'w', 'omega', "the paper's drive frequency"), &
        alias_t('chain', 'K', 'restitution', "the paper's coefficient of restitution"), &
        alias_t('chain', 'b', 'damping', "the paper's damping coefficient")]

    type :: config_t
        !> &chain, and &run stick_speed: everything the dynamics depends on
        type(model_t) :: model
        ! &initial
        character(len=:), allocatable :: initial_kind
        integer :: seed = 1
        real(wp) :: x_amp = 0, v_amp = 0
        real(wp), allocatable :: x0(:), v0(:)
        character(len=:), allocatable :: initial_file
        !> &run (but stick_speed, a parameter of the model) and &lyapunov
        type(record_spec_t) :: record
        ! &output
        character(len=:), allocatable :: output_file
        logical :: overwrite = .false.
        real(wp) :: max_size_mb = 4096
        ! &sweep
        logical :: sweep = .false.
        character(len=:), allocatable :: sweep_parameter, sweep_parameter2, sweep_mode
        real(wp) :: sweep_start = 0, sweep_stop = 0, sweep_step = 0
        real(wp) :: sweep_start2 = 0, sweep_stop2 = 0, sweep_step2 = 0
        ! &continuation: periodic orbits and their branches (chain_branch)
        logical :: continuation = .false.
        character(len=:), allocatable :: cont_parameter
        real(wp) :: cont_stop = 0, cont_step = 0
        integer :: cont_period = 1, cont_max_points = 200, cont_doublings = 0
        ! &census: the attractors reached from random starts (chain_census)
        logical :: census = .false.
        integer :: census_samples = 100, census_seed = 1
        real(wp) :: census_x_amp = 0.3_wp, census_v_amp = 0.3_wp
        real(wp) :: census_tolerance = 1.0e-6_wp
        character(len=:), allocatable :: census_mirror   !! 'merge' or 'separate'
        !> A census on a plane of two initial coordinates ('x<i>' or 'v<i>'; '' without a
        !> plane): plane_points**2 starts on a grid over plane_range (first coordinate's
        !> min, max, then the second's), the other coordinates those of &initial.
        character(len=16) :: census_plane(2) = ''
        real(wp) :: census_plane_range(4) = 0
        integer :: census_plane_points = 0
        !> Leading Lyapunov exponents of each sample (1 .. 2n): an ensemble of spectra
        integer :: census_exponents = 1
        ! the input as read
        character(len=:), allocatable :: input_text
    end type config_t

contains

    !> Read and validate the namelist file at `path`, with `overrides` (`group.key=value`,
    !> in order) applied to its text first.
    subroutine read_config(path, cfg, err, overrides)
        character(len=*), intent(in) :: path
        type(config_t), intent(out) :: cfg
        type(error_t), allocatable, intent(out) :: err
        character(len=*), intent(in), optional :: overrides(:)
        integer :: u, ios, j
        character(len=512) :: msg
        logical :: present_groups(size(group_names))

        call read_text(path, cfg%input_text, err)
        if (allocated(err)) return
        call check_namelist(path, cfg%input_text, input_keys, err, paper_symbols)
        if (allocated(err)) return
        if (present(overrides)) then
            do j = 1, size(overrides)
                call apply_override(cfg%input_text, trim(overrides(j)), input_keys, err, &
                                    paper_symbols)
                if (allocated(err)) return
            end do
        end if
        present_groups = [(any(groups_in(cfg%input_text) == group_names(j)), &
                           j=1, size(group_names))]
        if (.not. present_groups(1)) then
            call set_error(err, trim(path)//": the required group &chain is missing")
            return
        end if
        ! read the groups from a scratch copy that surely ends with a newline
        open (newunit=u, status='scratch', action='readwrite', form='formatted', &
              iostat=ios, iomsg=msg)
        if (ios == 0) write (u, '(a)', iostat=ios, iomsg=msg) cfg%input_text
        if (ios /= 0) then
            call set_error(err, trim(path)//": cannot read: "//trim(msg))
            return
        end if
        call read_chain(u, cfg, err)
        if (.not. allocated(err) .and. present_groups(2)) call read_initial(u, cfg, err)
        if (.not. allocated(err) .and. present_groups(3)) call read_run(u, cfg, err)
        if (.not. allocated(err) .and. present_groups(4)) call read_lyapunov(u, cfg, err)
        if (.not. allocated(err) .and. present_groups(5)) call read_output(u, cfg, err)
        if (.not. allocated(err) .and. present_groups(6)) call read_sweep(u, cfg, err)
        if (.not. allocated(err) .and. present_groups(7)) call read_continuation(u, cfg, err)
        if (.not. allocated(err) .and. present_groups(8)) call read_census(u, cfg, err)
        close (u)
        if (allocated(err)) return
        if (.not. allocated(cfg%initial_kind)) cfg%initial_kind = 'rest'
        if (.not. allocated(cfg%initial_file)) cfg%initial_file = ''
        if (.not. allocated(cfg%output_file)) cfg%output_file = default_output(path)
        if (.not. allocated(cfg%sweep_mode)) cfg%sweep_mode = 'continuation'
        if (.not. allocated(cfg%sweep_parameter)) cfg%sweep_parameter = ''
        if (.not. allocated(cfg%sweep_parameter2)) cfg%sweep_parameter2 = ''
        if (.not. allocated(cfg%cont_parameter)) cfg%cont_parameter = ''
        if (.not. allocated(cfg%census_mirror)) cfg%census_mirror = 'merge'
        if (.not. allocated(cfg%x0)) allocate (cfg%x0(0))
        if (.not. allocated(cfg%v0)) allocate (cfg%v0(0))
        if (same_file(path, cfg%output_file) .or. same_file(path, cfg%output_file//'.part')) then
            call set_error(err, "&output: file = '"//cfg%output_file//"' is the input file "// &
                           "'"//trim(path)//"' (or its .part); overwrite never replaces the "// &
                           "input: choose another name")
            return
        end if
        call validate_config(cfg, err)
    end subroutine read_config

    !> Whole file as text; refuses directories, empty files and files with NUL bytes.
    subroutine read_text(path, text, err)
        character(len=*), intent(in) :: path
        character(len=:), allocatable, intent(out) :: text
        type(error_t), allocatable, intent(out) :: err
        integer :: u, ios, nbytes
        logical :: exists
        character(len=512) :: msg

        inquire (file=path, exist=exists)
        if (.not. exists) then
            call set_error(err, trim(path)//": no such input file")
            return
        end if
        open (newunit=u, file=path, status='old', action='read', access='stream', &
              form='unformatted', iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call set_error(err, trim(path)//": cannot open as an input file: "//trim(msg))
            return
        end if
        inquire (unit=u, size=nbytes)
        if (nbytes <= 0) then
            close (u)
            call set_error(err, trim(path)//": is empty or not a regular file; "// &
                           "an input needs at least a &chain group")
            return
        end if
        if (nbytes > 64*1024*1024) then
            close (u)
            call set_error(err, trim(path)//": is larger than 64 MiB; not a namelist input")
            return
        end if
        allocate (character(len=nbytes) :: text)
        read (u, iostat=ios, iomsg=msg) text
        close (u)
        if (ios /= 0) then
            call set_error(err, trim(path)//": cannot read: "//trim(msg))
            return
        end if
        if (index(text, achar(0)) > 0) then
            call set_error(err, trim(path)//": contains NUL bytes; not a text namelist file")
        end if
    end subroutine read_text

    subroutine read_chain(u, cfg, err)
        integer, intent(in) :: u
        type(config_t), intent(inout) :: cfg
        type(error_t), allocatable, intent(out) :: err
        integer :: n, ios, m
        real(wp) :: damping, restitution, amplitude, omega
        real(wp), allocatable :: spacing(:)
        character(len=64) :: boundary
        character(len=512) :: msg
        namelist /chain/ n, spacing, damping, restitution, amplitude, omega, boundary

        allocate (spacing(max_list))
        n = -huge(1)
        spacing = unset
        damping = 0.05_wp
        restitution = 0.7_wp
        amplitude = unset
        omega = unset
        boundary = 'fixed'
        rewind (u)
        read (u, nml=chain, iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call group_error(err, 'chain', ios, msg)
            return
        end if
        if (n == -huge(1)) then
            call set_error(err, "&chain: n (number of oscillators) is required, in [1, "// &
                           fmt_int(max_n)//"]")
            return
        end if
        call check_n(err, n)
        if (allocated(err)) return
        if (amplitude == unset) then
            call set_error(err, "&chain: amplitude (A, drive amplitude) is required, >= 0")
            return
        end if
        if (omega == unset) then
            call set_error(err, "&chain: omega (w, drive frequency) is required, > 0")
            return
        end if
        m = count_given(spacing)
        if (m < 0) then
            call set_error(err, "&chain: spacing must be given as one value, or as n+1 "// &
                           "consecutive values from spacing(1) (bond 0, the left wall)")
            return
        end if
        if (m == 0) then
            cfg%model%spacing = [(1.0_wp, m=0, n)]
        else if (m == 1) then
            cfg%model%spacing = [(spacing(1), m=0, n)]
        else if (m == n + 1) then
            cfg%model%spacing = spacing(1:n + 1)
        else
            call check_spacing_count(err, n, m)
            return
        end if
        cfg%model%n = n
        cfg%model%damping = damping
        cfg%model%restitution = restitution
        cfg%model%amplitude = amplitude
        cfg%model%omega = omega
        call set_boundary(cfg%model, boundary, err)
    end subroutine read_chain

    subroutine read_initial(u, cfg, err)
        integer, intent(in) :: u
        type(config_t), intent(inout) :: cfg
        type(error_t), allocatable, intent(out) :: err
        integer :: seed, ios, mx, mv
        real(wp) :: x_amp, v_amp
        real(wp), allocatable :: x0(:), v0(:)
        character(len=64) :: kind
        character(len=4096) :: file
        character(len=512) :: msg
        namelist /initial/ kind, seed, x_amp, v_amp, x0, v0, file

        allocate (x0(max_list), v0(max_list))
        kind = 'rest'
        seed = 1
        x_amp = 0
        v_amp = 0
        x0 = unset
        v0 = unset
        file = ''
        rewind (u)
        read (u, nml=initial, iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call group_error(err, 'initial', ios, msg)
            return
        end if
        mx = count_given(x0)
        mv = count_given(v0)
        if (mx < 0 .or. mv < 0) then
            call set_error(err, "&initial: x0 and v0 must be given as consecutive values "// &
                           "from index 1")
            return
        end if
        cfg%initial_kind = lower(trim(adjustl(kind)))
        cfg%seed = seed
        cfg%x_amp = x_amp
        cfg%v_amp = v_amp
        cfg%x0 = x0(1:mx)
        cfg%v0 = v0(1:mv)
        cfg%initial_file = trim(file)
    end subroutine read_initial

    subroutine read_run(u, cfg, err)
        integer, intent(in) :: u
        type(config_t), intent(inout) :: cfg
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: transient, cycles
        real(wp) :: phase, stick_speed, period_tol
        logical :: record_events
        integer :: max_period, ios
        character(len=512) :: msg
        namelist /run/ transient, cycles, phase, record_events, stick_speed, max_period, &
            period_tol

        transient = cfg%record%transient
        cycles = cfg%record%cycles
        phase = cfg%record%phase
        record_events = cfg%record%record_events
        stick_speed = cfg%model%stick_speed
        max_period = cfg%record%max_period
        period_tol = cfg%record%period_tol
        rewind (u)
        read (u, nml=run, iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call group_error(err, 'run', ios, msg)
            return
        end if
        cfg%record%transient = transient
        cfg%record%cycles = cycles
        cfg%record%phase = phase
        cfg%record%record_events = record_events
        cfg%model%stick_speed = stick_speed
        cfg%record%max_period = max_period
        cfg%record%period_tol = period_tol
    end subroutine read_run

    subroutine read_lyapunov(u, cfg, err)
        integer, intent(in) :: u
        type(config_t), intent(inout) :: cfg
        type(error_t), allocatable, intent(out) :: err
        logical :: enabled, jacobian, covariant
        integer :: vectors, qr_every, align, jacobian_cycles, ios
        integer :: clv_transient, clv_store, clv_save, window
        character(len=512) :: msg
        namelist /lyapunov/ enabled, vectors, qr_every, align, jacobian, jacobian_cycles, &
            covariant, clv_transient, clv_store, clv_save, window

        enabled = .true.
        vectors = cfg%record%vectors
        qr_every = cfg%record%qr_every
        align = cfg%record%align
        jacobian = cfg%record%jacobian
        jacobian_cycles = cfg%record%jacobian_cycles
        covariant = cfg%record%covariant
        ! (not given: defaults that fit the run, set below once cycles and vectors are known)
        clv_transient = not_given
        clv_store = not_given
        clv_save = cfg%record%clv_save
        window = cfg%record%window
        rewind (u)
        read (u, nml=lyapunov, iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call group_error(err, 'lyapunov', ios, msg)
            return
        end if
        cfg%record%lyapunov = enabled
        cfg%record%vectors = vectors
        cfg%record%qr_every = qr_every
        cfg%record%align = align
        cfg%record%jacobian = jacobian
        cfg%record%jacobian_cycles = jacobian_cycles
        cfg%record%covariant = covariant
        cfg%record%clv_transient = clv_transient
        cfg%record%clv_store = clv_store
        cfg%record%clv_save = clv_save
        cfg%record%window = window
        ! (&chain and &run are read before this group)
        if (clv_transient == not_given) &
            cfg%record%clv_transient = int(max(1_i8, min(200_i8, cfg%record%cycles/2)))
        if (clv_store == not_given) cfg%record%clv_store = min(4, lyapunov_vectors(cfg))
    end subroutine read_lyapunov

    subroutine read_output(u, cfg, err)
        integer, intent(in) :: u
        type(config_t), intent(inout) :: cfg
        type(error_t), allocatable, intent(out) :: err
        character(len=4096) :: file
        logical :: overwrite
        real(wp) :: max_size_mb
        integer :: ios
        character(len=512) :: msg
        namelist /output/ file, overwrite, max_size_mb

        file = ''
        overwrite = cfg%overwrite
        max_size_mb = cfg%max_size_mb
        rewind (u)
        read (u, nml=output, iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call group_error(err, 'output', ios, msg)
            return
        end if
        if (len_trim(file) > 0) cfg%output_file = trim(file)
        cfg%overwrite = overwrite
        cfg%max_size_mb = max_size_mb
    end subroutine read_output

    subroutine read_sweep(u, cfg, err)
        integer, intent(in) :: u
        type(config_t), intent(inout) :: cfg
        type(error_t), allocatable, intent(out) :: err
        character(len=64) :: parameter, parameter2, mode
        real(wp) :: start, stop, step, start2, stop2, step2
        integer :: ios
        character(len=512) :: msg
        namelist /sweep/ parameter, start, stop, step, mode, parameter2, start2, stop2, step2

        parameter = ''
        parameter2 = ''
        mode = 'continuation'
        start = unset
        stop = unset
        step = unset
        start2 = unset
        stop2 = unset
        step2 = unset
        rewind (u)
        read (u, nml=sweep, iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call group_error(err, 'sweep', ios, msg)
            return
        end if
        if (start == unset .or. stop == unset .or. step == unset) then
            call set_error(err, "&sweep: start, stop and step are all required")
            return
        end if
        if (len_trim(parameter2) > 0 .and. &
            (start2 == unset .or. stop2 == unset .or. step2 == unset)) then
            call set_error(err, "&sweep: parameter2 needs start2, stop2 and step2")
            return
        end if
        cfg%sweep = .true.
        cfg%sweep_parameter = lower(trim(adjustl(parameter)))
        cfg%sweep_parameter2 = lower(trim(adjustl(parameter2)))
        cfg%sweep_mode = lower(trim(adjustl(mode)))
        cfg%sweep_start = start
        cfg%sweep_stop = stop
        cfg%sweep_step = step
        if (len_trim(parameter2) > 0) then
            cfg%sweep_start2 = start2
            cfg%sweep_stop2 = stop2
            cfg%sweep_step2 = step2
        end if
    end subroutine read_sweep

    subroutine read_continuation(u, cfg, err)
        integer, intent(in) :: u
        type(config_t), intent(inout) :: cfg
        type(error_t), allocatable, intent(out) :: err
        character(len=64) :: parameter
        real(wp) :: stop, step
        integer :: period, max_points, doublings, ios
        character(len=512) :: msg
        namelist /continuation/ parameter, stop, step, period, max_points, doublings

        parameter = ''
        stop = unset
        step = unset
        period = 1
        max_points = 200
        doublings = 0
        rewind (u)
        read (u, nml=continuation, iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call group_error(err, 'continuation', ios, msg)
            return
        end if
        if (max_points /= 1 .and. (stop == unset .or. step == unset)) then
            call set_error(err, "&continuation: stop and step are required (unless "// &
                           "max_points = 1: Newton only)")
            return
        end if
        cfg%continuation = .true.
        cfg%cont_parameter = lower(trim(adjustl(parameter)))
        cfg%cont_stop = stop
        cfg%cont_step = step
        if (stop == unset) cfg%cont_stop = 0
        if (step == unset) cfg%cont_step = 0
        cfg%cont_period = period
        cfg%cont_max_points = max_points
        cfg%cont_doublings = doublings
    end subroutine read_continuation

    subroutine read_census(u, cfg, err)
        integer, intent(in) :: u
        type(config_t), intent(inout) :: cfg
        type(error_t), allocatable, intent(out) :: err
        integer, parameter :: unset_int = -huge(1)
        integer :: samples, seed, plane_points, exponents, ios
        real(wp) :: x_amp, v_amp, tolerance, plane_range(4)
        character(len=64) :: mirror
        character(len=16) :: plane(2)
        character(len=512) :: msg
        namelist /census/ samples, seed, x_amp, v_amp, tolerance, mirror, plane, plane_range, &
            plane_points, exponents

        samples = unset_int
        seed = cfg%census_seed
        x_amp = cfg%census_x_amp
        v_amp = cfg%census_v_amp
        tolerance = cfg%census_tolerance
        mirror = 'merge'
        plane = ''
        plane_range = unset
        plane_points = unset_int
        exponents = cfg%census_exponents
        rewind (u)
        read (u, nml=census, iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call group_error(err, 'census', ios, msg)
            return
        end if
        if (all(plane == '')) then
            if (plane_points /= unset_int .or. any(plane_range /= unset)) then
                call set_error(err, "&census: plane_range and plane_points need a plane "// &
                               "(plane = 'x<i>', 'v<j>')")
                return
            end if
            if (samples == unset_int) samples = cfg%census_samples
        else
            if (any(plane_range == unset)) then
                call set_error(err, "&census: a plane needs plane_range = min, max of the "// &
                               "first coordinate, min, max of the second")
                return
            end if
            if (plane_points == unset_int) plane_points = 100
            ! samples follow from the grid; an out-of-range plane_points is named by
            ! validate_census
            if (plane_points >= 1 .and. plane_points <= max_plane_points) then
                if (samples /= unset_int .and. samples /= plane_points**2) then
                    call set_error(err, "&census: samples = "//fmt_int(samples)//" with a "// &
                                   "plane must be left out or equal plane_points**2 = "// &
                                   fmt_int(plane_points**2))
                    return
                end if
                samples = plane_points**2
            else if (samples == unset_int) then
                samples = cfg%census_samples
            end if
            cfg%census_plane = plane
            cfg%census_plane_range = plane_range
            cfg%census_plane_points = plane_points
        end if
        cfg%census = .true.
        cfg%census_samples = samples
        cfg%census_seed = seed
        cfg%census_x_amp = x_amp
        cfg%census_v_amp = v_amp
        cfg%census_tolerance = tolerance
        cfg%census_mirror = lower(trim(adjustl(mirror)))
        cfg%census_exponents = exponents
    end subroutine read_census

    !> Check every value against its allowed range (also used for values given from Python),
    !> group by group; the first value out of range is the error.
    subroutine validate_config(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err

        call validate_chain(cfg, err)
        if (.not. allocated(err)) call validate_initial(cfg, err)
        if (.not. allocated(err)) call validate_run(cfg, err)
        if (.not. allocated(err)) call validate_lyapunov(cfg, err)
        if (.not. allocated(err)) call validate_output(cfg, err)
        if (.not. allocated(err) .and. cfg%sweep) call validate_sweep(cfg, err)
        if (.not. allocated(err) .and. cfg%continuation) call validate_continuation(cfg, err)
        if (.not. allocated(err) .and. cfg%census) call validate_census(cfg, err)
    end subroutine validate_config

    subroutine validate_chain(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        integer :: j

        call check_n(err, cfg%model%n)
        if (allocated(err)) return
        call check_spacing_count(err, cfg%model%n, size(cfg%model%spacing))
        if (allocated(err)) return
        do j = 1, size(cfg%model%spacing)
            if (.not. (ieee_is_finite(cfg%model%spacing(j)) .and. cfg%model%spacing(j) > 0)) then
                call set_error(err, "&chain: spacing of bond "//fmt_int(j - 1)//" = "// &
                               fmt_real(cfg%model%spacing(j))//" must be finite and > 0")
                return
            end if
        end do
        call check_range(err, 'chain', 'damping', cfg%model%damping, 0.0_wp, 1.0_wp, '[0, 1)', &
                         open_high=.true.)
        if (allocated(err)) return
        call check_range(err, 'chain', 'restitution', cfg%model%restitution, 0.0_wp, 1.0_wp, &
            '[0, 1]')
        if (allocated(err)) return
        call check_range(err, 'chain', 'amplitude', cfg%model%amplitude, 0.0_wp, 1.0e6_wp, &
                         '[0, 1e6]')
        if (allocated(err)) return
        call check_range(err, 'chain', 'omega', cfg%model%omega, 1.0e-3_wp, 1.0e3_wp, '[1e-3, 1e3]')
        if (allocated(err)) return
        if (cfg%model%damping == 0 .and. cfg%model%omega == 1 .and. cfg%model%amplitude /= 0) then
            call set_error(err, "&chain: omega = 1 with damping = 0 is exact resonance: the "// &
                           "linear response grows without bound; use damping > 0 or omega /= 1")
            return
        end if
        call check_near_resonance(err, cfg%model%amplitude, cfg%model%omega, &
                                  cfg%model%damping, minval(cfg%model%spacing))
    end subroutine validate_chain

    !> Near resonance the engine's gap search cannot finish (chain_gaps, forced_gap_zero): it
    !> bounds a gap's curvature by its share of the drive, (1 + w**2) rp with rp = A / d,
    !> d = sqrt((1 - w**2)**2 + (2 b w)**2) the steady response's amplitude, and so steps
    !> h = sqrt(2 g / ((1 + w**2) rp)) at a gap g. A gap that stays at g for a drive period
    !> 2 pi / w takes (2 pi / w) / h steps, at most max_steps:
    !>     rp / g <= (max_steps w / (2 pi))**2 * 2 / (1 + w**2).
    !> Gaps linger far below their offset c (the spacing): with g = c / 100 the bound is
    !> rp / c <= 1.0e7 at w = 1, and it holds what was measured on the engine (undamped, 200
    !> cycles of 4 oscillators failed from rp / c = 2.5e8 to 7e8 whatever A and c; 2000 cycles
    !> of 16 failed at 1e8 and ran at 1e7). Refused above it, naming the keys and the range:
    !> (computed without dividing, so that no d, however small, overflows).
    subroutine check_near_resonance(err, amplitude, omega, damping, spacing)
        type(error_t), allocatable, intent(inout) :: err
        real(wp), intent(in) :: amplitude, omega, damping, spacing !! spacing: the smallest
        real(wp), parameter :: linger = 0.01_wp !! g / c
        real(wp) :: limit, s, d

        if (allocated(err) .or. amplitude == 0) return
        limit = (max_steps*omega/two_pi)**2*2/(1 + omega**2)*linger
        s = max(abs(1 - omega**2), 2*damping*omega)
        d = 0
        if (s > 0) d = s*sqrt((abs(1 - omega**2)/s)**2 + (2*damping*omega/s)**2)
        if (amplitude <= limit*spacing*d) return
        call set_error(err, "&chain: omega = "//fmt_real(omega)//" with damping = "// &
                       fmt_real(damping)//" is too near resonance for amplitude = "// &
                       fmt_real(amplitude)//" and the smallest spacing "// &
                       fmt_real(spacing)//": the gap search cannot resolve a steady "// &
                       "response of more than "//fmt_real(limit)//" spacings; keep "// &
                       "sqrt((1 - omega**2)**2 + (2 damping omega)**2) >= amplitude / ("// &
                       fmt_real(limit)//" spacing) = "// &
                       fmt_real(amplitude/(limit*spacing)))
    end subroutine check_near_resonance

    subroutine validate_initial(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: smallest

        select case (cfg%initial_kind)
        case ('rest', 'random', 'explicit', 'file')
        case default
            call set_error(err, "&initial: kind = '"//cfg%initial_kind// &
                           "' is not one of 'rest', 'random', 'explicit', 'file'")
            return
        end select
        if (cfg%initial_kind == 'random') then
            smallest = minval(cfg%model%spacing)
            call check_range(err, 'initial', 'x_amp', cfg%x_amp, 0.0_wp, &
                             0.5_wp*smallest, '[0, half the smallest spacing = '// &
                             fmt_real(0.5_wp*smallest)//') so that no start overlaps', &
                             open_high=.true.)
            if (allocated(err)) return
            call check_range(err, 'initial', 'v_amp', cfg%v_amp, 0.0_wp, 1.0e6_wp, '[0, 1e6]')
            if (allocated(err)) return
            ! both 0 (their defaults) is rest whatever the seed: a study that changes only
            ! the seed would get identical runs
            if (cfg%x_amp == 0 .and. cfg%v_amp == 0) then
                call set_error(err, "&initial: kind = 'random' needs x_amp or v_amp above 0 "// &
                               "(both are 0: every seed would start from rest); "// &
                               amplitudes_allowed(smallest))
                return
            end if
        end if
        if (cfg%initial_kind == 'explicit') then
            if (size(cfg%x0) /= cfg%model%n) then
                call set_error(err, "&initial: kind = 'explicit' needs x0 with n = "// &
                               fmt_int(cfg%model%n)//" values, got "//fmt_int(size(cfg%x0)))
                return
            end if
            if (size(cfg%v0) /= cfg%model%n .and. size(cfg%v0) /= 0) then
                call set_error(err, "&initial: v0 needs n = "//fmt_int(cfg%model%n)// &
                               " values (or none for rest), got "//fmt_int(size(cfg%v0)))
                return
            end if
            if (.not. (all(ieee_is_finite(cfg%x0)) .and. all(ieee_is_finite(cfg%v0)))) then
                call set_error(err, "&initial: x0 and v0 must be finite")
                return
            end if
        end if
        if (cfg%initial_kind == 'file' .and. len_trim(cfg%initial_file) == 0) then
            call set_error(err, "&initial: kind = 'file' needs file = 'earlier-run.h5'")
        end if
    end subroutine validate_initial

    subroutine validate_run(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err

        if (cfg%record%transient < 0 .or. cfg%record%transient > 10_i8**12) then
            call set_error(err, "&run: transient = "//fmt_int8(cfg%record%transient)// &
                           " is outside [0, 1e12]")
            return
        end if
        if (cfg%record%cycles < 1 .or. cfg%record%cycles > 10_i8**12) then
            call set_error(err, &
                "&run: cycles = "//fmt_int8(cfg%record%cycles)//" is outside [1, 1e12]")
            return
        end if
        call check_range(err, 'run', 'phase', cfg%record%phase, 0.0_wp, two_pi, '[0, 2 pi)', &
                         open_high=.true.)
        if (allocated(err)) return
        call check_range(err, 'run', 'stick_speed', cfg%model%stick_speed, tiny(1.0_wp), 1.0_wp, &
                         '(0, 1]')
        if (allocated(err)) return
        if (cfg%record%max_period < 1 .or. cfg%record%max_period > 10000) then
            call set_error(err, "&run: max_period = "//fmt_int(cfg%record%max_period)// &
                           " is outside [1, 10000]")
            return
        end if
        call check_range(err, 'run', 'period_tol', cfg%record%period_tol, tiny(1.0_wp), 1.0_wp, &
                         '(0, 1)', open_high=.true.)
    end subroutine validate_run

    subroutine validate_lyapunov(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err

        if (cfg%record%vectors < 0 .or. cfg%record%vectors > 2*cfg%model%n) then
            call set_error(err, "&lyapunov: vectors = "//fmt_int(cfg%record%vectors)// &
                           " is outside [0, 2n = "//fmt_int(2*cfg%model%n)//"] (0 means all 2n)")
            return
        end if
        if (cfg%record%qr_every < 0 .or. cfg%record%qr_every > cfg%record%cycles) then
            call set_error(err, "&lyapunov: qr_every = "//fmt_int(cfg%record%qr_every)// &
                           " is outside [0, cycles = "//fmt_int8(cfg%record%cycles)// &
                           "] (0: adaptive)")
            return
        end if
        if (cfg%record%align < 0 .or. cfg%record%align > 100000) then
            call set_error(err, "&lyapunov: align = "//fmt_int(cfg%record%align)// &
                           " is outside [0, 100000] (cycles, taken from the end of the transient)")
            return
        end if
        if (cfg%record%jacobian_cycles < 1 .or. cfg%record%jacobian_cycles > 1000) then
            call set_error(err, "&lyapunov: jacobian_cycles = "// &
                           fmt_int(cfg%record%jacobian_cycles)//" is outside [1, 1000]")
            return
        end if
        if (cfg%record%window /= 0) call validate_window(cfg, err)
        if (allocated(err)) return
        if (cfg%record%covariant) call validate_covariant(cfg, err)
    end subroutine validate_lyapunov

    !> The window of finite-time exponents (docs/model.md section 7.10).
    subroutine validate_window(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err

        associate (r => cfg%record)
            if (r%window < 0 .or. r%window > r%cycles) then
                call set_error(err, "&lyapunov: window = "//fmt_int(r%window)// &
                               " is outside [0, cycles = "//fmt_int8(r%cycles)//"] (recorded "// &
                               "cycles per finite-time exponent; 0: none)")
            else if (.not. r%lyapunov) then
                call set_error(err, "&lyapunov: window = "//fmt_int(r%window)// &
                               " needs enabled = .true.")
            else if (cfg%sweep .or. cfg%census) then
                call set_error(err, "&lyapunov: window = "//fmt_int(r%window)//" is for a "// &
                               "single run, not a &sweep or a &census")
            else if (r%qr_every > 1) then
                if (modulo(r%window, r%qr_every) /= 0) &
                    call set_error(err, "&lyapunov: window = "//fmt_int(r%window)// &
                                   " must be a multiple of qr_every = "// &
                                   fmt_int(r%qr_every)//" (a window ends at a QR step)")
            end if
        end associate
    end subroutine validate_window

    !> The keys of covariant Lyapunov vectors (docs/model.md section 14.5).
    subroutine validate_covariant(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: kept

        associate (r => cfg%record)
            if (.not. r%lyapunov) then
                call set_error(err, "&lyapunov: covariant = .true. needs enabled = .true.")
            else if (cfg%sweep .or. cfg%census) then
                call set_error(err, "&lyapunov: covariant = .true. is for a single run, not "// &
                               "a &sweep or a &census")
            else if (r%qr_every > 1) then
                call set_error(err, "&lyapunov: covariant = .true. takes a QR step at every "// &
                               "record: qr_every = "//fmt_int(r%qr_every)//" must be 0 or 1")
            else if (r%cycles < 2) then
                call set_error(err, "&lyapunov: covariant = .true. needs &run cycles >= 2 "// &
                               "(records with vectors, then records over which the "// &
                               "backward pass converges), not "//fmt_int8(r%cycles))
            else if (r%clv_transient < 1 .or. r%clv_transient >= r%cycles) then
                call set_error(err, "&lyapunov: clv_transient = "//fmt_int(r%clv_transient)// &
                               " is outside [1, cycles - 1 = "//fmt_int8(r%cycles - 1)// &
                               "] (the last records, without vectors, over which the "// &
                               "backward pass converges)")
            else if (r%clv_store < 0 .or. r%clv_store > lyapunov_vectors(cfg)) then
                call set_error(err, "&lyapunov: clv_store = "//fmt_int(r%clv_store)// &
                               " is outside [0, vectors = "//fmt_int(lyapunov_vectors(cfg))// &
                               "] (the vectors whose per-oscillator weights are stored)")
            else
                kept = r%cycles - r%clv_transient
                if (r%clv_save < 0 .or. r%clv_save > kept) &
                    call set_error(err, "&lyapunov: clv_save = "//fmt_int(r%clv_save)// &
                                   " is outside [0, cycles - clv_transient = "// &
                                   fmt_int8(kept)//"] (the last records with vectors whose "// &
                                   "vectors are stored)")
            end if
        end associate
    end subroutine validate_covariant

    subroutine validate_output(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err

        if (len_trim(cfg%output_file) == 0) then
            call set_error(err, "&output: file must not be empty")
            return
        end if
        ! open below: 0 would refuse every run, so it is out of range like a negative value
        call check_range(err, 'output', 'max_size_mb', cfg%max_size_mb, tiny(1.0_wp), &
                         1.0e9_wp, '(0, 1e9]')
    end subroutine validate_output

    !> n, the number of oscillators, within [1, max_n].
    subroutine check_n(err, n)
        type(error_t), allocatable, intent(out) :: err
        integer, intent(in) :: n

        if (n < 1 .or. n > max_n) call set_error(err, "&chain: n = "//fmt_int(n)// &
                                                 " is outside [1, "//fmt_int(max_n)//"]")
    end subroutine check_n

    !> m spacings for n oscillators: one per bond, 0..n (a single value is expanded on reading).
    subroutine check_spacing_count(err, n, m)
        type(error_t), allocatable, intent(out) :: err
        integer, intent(in) :: n, m

        if (m /= n + 1) call set_error(err, "&chain: spacing has "//fmt_int(m)// &
                                       " values; give one (uniform) or n+1 = "// &
                                       fmt_int(n + 1)//" (one per bond, 0..n)")
    end subroutine check_spacing_count

    subroutine validate_sweep(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err

        if (.not. any(sweep_parameters == cfg%sweep_parameter)) then
            call set_error(err, "&sweep: parameter = '"//cfg%sweep_parameter//"' is not one "// &
                           "of 'amplitude', 'omega', 'damping', 'restitution', 'spacing'")
            return
        end if
        if (cfg%sweep_mode /= 'continuation' .and. cfg%sweep_mode /= 'independent') then
            call set_error(err, "&sweep: mode = '"//cfg%sweep_mode//"' is not one of "// &
                           "'continuation', 'independent'")
            return
        end if
        call check_axis(err, '', cfg%sweep_start, cfg%sweep_stop, cfg%sweep_step)
        if (allocated(err)) return
        if (len(cfg%sweep_parameter2) > 0) then
            if (.not. any(sweep_parameters == cfg%sweep_parameter2) .or. &
                cfg%sweep_parameter2 == cfg%sweep_parameter) then
                call set_error(err, "&sweep: parameter2 = '"//cfg%sweep_parameter2// &
                               "' must be another of 'amplitude', 'omega', 'damping', "// &
                               "'restitution', 'spacing'")
                return
            end if
            call check_axis(err, '2', cfg%sweep_start2, cfg%sweep_stop2, cfg%sweep_step2)
            if (allocated(err)) return
        end if
        call check_sweep_points(err, cfg)
    end subroutine validate_sweep

    !> The points of the whole sweep (in a 2-D grid the product of its axes) within
    !> max_sweep_points; each axis is already within 1e7 steps.
    subroutine check_sweep_points(err, cfg)
        type(error_t), allocatable, intent(out) :: err
        type(config_t), intent(in) :: cfg
        integer(i8) :: n1, n2

        n1 = sweep_axis_points(cfg%sweep_start, cfg%sweep_stop, cfg%sweep_step)
        if (len(cfg%sweep_parameter2) == 0) then
            if (n1 > max_sweep_points) call set_error(err, "&sweep: start, stop, step give "// &
                fmt_int8(n1)//" points; a sweep has at most 1e7")
            return
        end if
        n2 = sweep_axis_points(cfg%sweep_start2, cfg%sweep_stop2, cfg%sweep_step2)
        if (n1*n2 > max_sweep_points) call set_error(err, "&sweep: start, stop, step and "// &
            "start2, stop2, step2 give "//fmt_int8(n1)//" x "//fmt_int8(n2)//" = "// &
            fmt_int8(n1*n2)//" points; a sweep has at most 1e7")
    end subroutine check_sweep_points

    !> Number of points from start to stop in steps of step (rounding-safe), for a checked
    !> axis (finite, step towards stop, at most 1e7 steps).
    pure integer function sweep_axis_points(start, stop, step) result(points)
        real(wp), intent(in) :: start, stop, step

        points = nint((stop - start)/step) + 1
        if (start + (points - 1)*step > max(start, stop) + 1.0e-9_wp*abs(step) .or. &
            start + (points - 1)*step < min(start, stop) - 1.0e-9_wp*abs(step)) &
            points = points - 1
    end function sweep_axis_points

    !> The start value is the one in &chain; the branch runs from it towards `stop`.
    subroutine validate_continuation(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        type(config_t) :: far

        if (cfg%sweep) then
            call set_error(err, "&continuation cannot be combined with &sweep (run them as "// &
                             "two inputs)")
        else if (.not. any(sweep_parameters == cfg%cont_parameter)) then
            call set_error(err, "&continuation: parameter = '"//cfg%cont_parameter// &
                           "' is not one of amplitude, omega, damping, restitution, spacing")
        else if (cfg%cont_period < 1 .or. cfg%cont_period > 10000) then
            call set_error(err, "&continuation: period = "//fmt_int(cfg%cont_period)// &
                           " must be in 1..10000 (drive cycles)")
        else if (cfg%cont_max_points < 1) then
            call set_error(err, "&continuation: max_points = "//fmt_int(cfg%cont_max_points)// &
                           " must be >= 1")
        else if (cfg%cont_doublings < 0 .or. cfg%cont_doublings > 8) then
            call set_error(err, "&continuation: doublings = "//fmt_int(cfg%cont_doublings)// &
                           " must be in 0..8")
        else if (cfg%cont_parameter == 'spacing' .and. &
                 any(cfg%model%spacing /= cfg%model%spacing(1))) then
            call set_error(err, "&continuation: parameter = 'spacing' needs one spacing for "// &
                           "every bond (&chain spacing = one value)")
        end if
        if (allocated(err) .or. cfg%cont_max_points == 1) return
        associate (start => model_parameter(cfg%model, cfg%cont_parameter))
        if (.not. (ieee_is_finite(cfg%cont_stop) .and. cfg%cont_stop /= start)) then
            call set_error(err, "&continuation: stop = "//fmt_real(cfg%cont_stop)// &
                           " must be finite and differ from the start, &chain "// &
                           cfg%cont_parameter//" = "//fmt_real(start))
        else if (.not. (ieee_is_finite(cfg%cont_step) .and. cfg%cont_step /= 0 .and. &
                        (cfg%cont_step > 0 .eqv. cfg%cont_stop > start))) then
            call set_error(err, "&continuation: step = "//fmt_real(cfg%cont_step)// &
                           " must be nonzero with the sign of stop - start ("// &
                           fmt_real(cfg%cont_stop)//" - "//fmt_real(start)//")")
        else if (abs(cfg%cont_step) > abs(cfg%cont_stop - start)) then
            call set_error(err, "&continuation: |step| = "//fmt_real(abs(cfg%cont_step))// &
                           " is larger than |stop - start| = "// &
                           fmt_real(abs(cfg%cont_stop - start)))
        end if
        end associate
        if (allocated(err)) return
        ! the far end must be a valid chain too
        far = cfg
        far%continuation = .false.
        call set_model_parameter(far%model, cfg%cont_parameter, cfg%cont_stop)
        call validate_chain(far, err)
        if (allocated(err)) err%message = "&continuation: stop = "//fmt_real(cfg%cont_stop)// &
                                          ": "//err%message
    end subroutine validate_continuation

    !> A census's starts must not overlap (as &initial random's), and it runs at one point
    !> or along one swept parameter.
    subroutine validate_census(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: half

        if (cfg%census_samples < 1 .or. cfg%census_samples > max_samples) then
            call set_error(err, "&census: samples = "//fmt_int(cfg%census_samples)// &
                           " is outside [1, "//fmt_int(max_samples)//"]")
            return
        end if
        half = 0.5_wp*minval(cfg%model%spacing)
        call check_range(err, 'census', 'x_amp', cfg%census_x_amp, 0.0_wp, half, &
                         '[0, half the smallest spacing = '//fmt_real(half)// &
                         ') so that no start overlaps', open_high=.true.)
        if (allocated(err)) return
        call check_range(err, 'census', 'v_amp', cfg%census_v_amp, 0.0_wp, 1.0e6_wp, '[0, 1e6]')
        if (allocated(err)) return
        ! (a plane's starts take the coordinates off the plane from &initial, not these)
        if (cfg%census_x_amp == 0 .and. cfg%census_v_amp == 0 .and. &
            all(cfg%census_plane == '')) then
            call set_error(err, "&census: x_amp or v_amp must be above 0 (both are 0: every "// &
                           "sample would start from rest); "// &
                           amplitudes_allowed(minval(cfg%model%spacing)))
            return
        end if
        call check_range(err, 'census', 'tolerance', cfg%census_tolerance, tiny(1.0_wp), &
                         1.0_wp, '(0, 1)', open_high=.true.)
        if (allocated(err)) return
        if (cfg%census_exponents < 1 .or. cfg%census_exponents > 2*cfg%model%n) then
            call set_error(err, "&census: exponents = "//fmt_int(cfg%census_exponents)// &
                           " is outside [1, 2n = "//fmt_int(2*cfg%model%n)//"] (the leading "// &
                           "Lyapunov exponents of each sample)")
            return
        end if
        if (cfg%census_mirror /= 'merge' .and. cfg%census_mirror /= 'separate') then
            call set_error(err, "&census: mirror = '"//cfg%census_mirror//"' is not one of "// &
                           "'merge', 'separate'")
        else if (cfg%continuation) then
            call set_error(err, "&census cannot be combined with &continuation (run them as "// &
                           "two inputs)")
        else if (cfg%sweep .and. len(cfg%sweep_parameter2) > 0) then
            call set_error(err, "&census runs at one point or along one parameter: a &sweep "// &
                           "with parameter2 is not supported")
        end if
        if (.not. allocated(err) .and. any(cfg%census_plane /= '')) call validate_plane(cfg, err)
    end subroutine validate_census

    !> A census plane: two distinct coordinates of the chain, a grid of 2 .. max_plane_points
    !> points along each with samples = plane_points**2, over finite ranges min < max.
    subroutine validate_plane(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        logical :: velocity
        integer :: k, i
        character(len=*), parameter :: sides(2) = [character(len=6) :: 'first', 'second']

        do k = 1, 2
            call plane_coordinate(cfg%census_plane(k), cfg%model%n, velocity, i)
            if (i == 0) then
                call set_error(err, "&census: plane = '"//trim(cfg%census_plane(k))// &
                               "' is not a coordinate 'x<i>' or 'v<i>' with i in 1.."// &
                               fmt_int(cfg%model%n))
                return
            end if
        end do
        if (lower(trim(adjustl(cfg%census_plane(1)))) == &
            lower(trim(adjustl(cfg%census_plane(2))))) then
            call set_error(err, "&census: plane = '"//trim(cfg%census_plane(1))//"', '"// &
                           trim(cfg%census_plane(2))//"' names one coordinate twice")
            return
        end if
        if (cfg%census_plane_points < 2 .or. cfg%census_plane_points > max_plane_points) then
            call set_error(err, "&census: plane_points = "//fmt_int(cfg%census_plane_points)// &
                           " is outside [2, "//fmt_int(max_plane_points)//"]")
            return
        end if
        if (cfg%census_samples /= cfg%census_plane_points**2) then
            call set_error(err, "&census: samples = "//fmt_int(cfg%census_samples)// &
                           " with a plane must equal plane_points**2 = "// &
                           fmt_int(cfg%census_plane_points**2))
            return
        end if
        do k = 1, 2
            associate (lo => cfg%census_plane_range(2*k - 1), hi => cfg%census_plane_range(2*k))
                if (.not. (ieee_is_finite(lo) .and. ieee_is_finite(hi)) .or. .not. lo < hi) then
                    call set_error(err, "&census: plane_range of the "//trim(sides(k))// &
                                   " coordinate ("//trim(cfg%census_plane(k))//") = "// &
                                   fmt_real(lo)//", "//fmt_real(hi)//" must be finite "// &
                                   "with min < max")
                    return
                end if
            end associate
        end do
    end subroutine validate_plane

    !> The coordinate a census plane names: 'x<i>' (velocity false) or 'v<i>' (true), i in
    !> 1..n, any case, blanks around ignored; i = 0 when `name` is none of these.
    pure subroutine plane_coordinate(name, n, velocity, i)
        character(len=*), intent(in) :: name
        integer, intent(in) :: n
        logical, intent(out) :: velocity
        integer, intent(out) :: i
        character(len=:), allocatable :: text
        integer :: k

        i = 0
        velocity = .false.
        text = lower(trim(adjustl(name)))
        if (len(text) < 2 .or. len(text) > 10) return
        if (text(1:1) /= 'x' .and. text(1:1) /= 'v') return
        if (verify(text(2:), '0123456789') /= 0) return
        velocity = text(1:1) == 'v'
        k = 0
        read (text(2:), *) k
        if (k >= 1 .and. k <= n) i = k
    end subroutine plane_coordinate

    subroutine check_axis(err, suffix, start, stop, step)
        type(error_t), allocatable, intent(out) :: err
        character(len=*), intent(in) :: suffix
        real(wp), intent(in) :: start, stop, step

        if (.not. (ieee_is_finite(start) .and. ieee_is_finite(stop) .and. &
                   ieee_is_finite(step))) then
            call set_error(err, "&sweep: start"//suffix//", stop"//suffix//" and step"// &
                           suffix//" must be finite")
        else if (step == 0 .or. (stop - start)*step < 0) then
            call set_error(err, "&sweep: step"//suffix//" = "//fmt_real(step)// &
                           " must be nonzero and point from start"//suffix//" to stop"//suffix)
        else if ((stop - start)/step > 1.0e7_wp) then
            call set_error(err, "&sweep: more than 1e7 points along parameter"//suffix)
        end if
    end subroutine check_axis

    !> The boundary from its input name, 'fixed' or 'free' (any case; blanks around ignored).
    subroutine set_boundary(model, name, err)
        type(model_t), intent(inout) :: model
        character(len=*), intent(in) :: name
        type(error_t), allocatable, intent(inout) :: err

        select case (lower(trim(adjustl(name))))
        case ('fixed')
            model%walls = .true.
        case ('free')
            model%walls = .false.
        case default
            call set_error(err, "&chain: boundary = '"//trim(adjustl(name))// &
                           "' is not one of 'fixed', 'free'")
        end select
    end subroutine set_boundary

    !> The configuration actually used, every key of every group, as a namelist input that
    !> reads back to the same configuration (reals to full precision, lists in full; &sweep
    !> only when there is one).
    function config_summary(cfg) result(text)
        type(config_t), intent(in) :: cfg
        character(len=:), allocatable :: text

        text = chain_group(cfg%model)//initial_group(cfg)//run_group(cfg)// &
               lyapunov_group(cfg)//output_group(cfg)
        if (cfg%sweep) text = text//sweep_group(cfg)
        if (cfg%continuation) text = text//continuation_group(cfg)
        if (cfg%census) text = text//census_group(cfg)
    end function config_summary

    function census_group(cfg) result(text)
        type(config_t), intent(in) :: cfg
        character(len=:), allocatable :: text

        text = "&census samples = "//fmt_int(cfg%census_samples)//", seed = "// &
               fmt_int(cfg%census_seed)//", x_amp = "//exact(cfg%census_x_amp)//", v_amp = "// &
               exact(cfg%census_v_amp)//", tolerance = "//exact(cfg%census_tolerance)// &
               ", mirror = '"//cfg%census_mirror//"'"
        if (any(cfg%census_plane /= '')) text = text//", plane = '"// &
            trim(cfg%census_plane(1))//"', '"//trim(cfg%census_plane(2))// &
            "', plane_range = "//exact_list(cfg%census_plane_range)//", plane_points = "// &
            fmt_int(cfg%census_plane_points)
        ! (the default, 1, left out: the summary of a census without the key stays as it was)
        if (cfg%census_exponents /= 1) text = text//", exponents = "// &
                                              fmt_int(cfg%census_exponents)
        text = text//" /"//new_line('a')
    end function census_group

    function continuation_group(cfg) result(text)
        type(config_t), intent(in) :: cfg
        character(len=:), allocatable :: text

        text = "&continuation parameter = '"//cfg%cont_parameter//"', stop = "// &
               exact(cfg%cont_stop)//", step = "//exact(cfg%cont_step)//", period = "// &
               fmt_int(cfg%cont_period)//", max_points = "//fmt_int(cfg%cont_max_points)// &
               ", doublings = "//fmt_int(cfg%cont_doublings)//" /"//new_line('a')
    end function continuation_group

    function chain_group(model) result(text)
        type(model_t), intent(in) :: model
        character(len=:), allocatable :: text

        text = "&chain n = "//fmt_int(model%n)//", spacing = "
        if (all(model%spacing == model%spacing(1))) then
            text = text//exact(model%spacing(1))
        else
            text = text//exact_list(model%spacing)
        end if
        text = text//", damping = "//exact(model%damping)//", restitution = "// &
               exact(model%restitution)//", amplitude = "//exact(model%amplitude)// &
               ", omega = "//exact(model%omega)//", boundary = '"//model_walls(model)// &
               "' /"//new_line('a')
    end function chain_group

    function initial_group(cfg) result(text)
        type(config_t), intent(in) :: cfg
        character(len=:), allocatable :: text

        text = "&initial kind = '"//cfg%initial_kind//"'"
        select case (cfg%initial_kind)
        case ('random')
            text = text//", seed = "//fmt_int(cfg%seed)//", x_amp = "//exact(cfg%x_amp)// &
                   ", v_amp = "//exact(cfg%v_amp)
        case ('explicit')
            text = text//", x0 = "//exact_list(cfg%x0)
            if (size(cfg%v0) > 0) text = text//", v0 = "//exact_list(cfg%v0)
        case ('file')
            text = text//", file = '"//cfg%initial_file//"'"
        end select
        text = text//" /"//new_line('a')
    end function initial_group

    function run_group(cfg) result(text)
        type(config_t), intent(in) :: cfg
        character(len=:), allocatable :: text

        associate (r => cfg%record)
            text = "&run transient = "//fmt_int8(r%transient)//", cycles = "// &
                   fmt_int8(r%cycles)//", phase = "//exact(r%phase)//", record_events = "// &
                   fmt_logical(r%record_events)//", stick_speed = "// &
                   exact(cfg%model%stick_speed)//", max_period = "//fmt_int(r%max_period)// &
                   ", period_tol = "//exact(r%period_tol)//" /"//new_line('a')
        end associate
    end function run_group

    function lyapunov_group(cfg) result(text)
        type(config_t), intent(in) :: cfg
        character(len=:), allocatable :: text

        associate (r => cfg%record)
            text = "&lyapunov enabled = "//fmt_logical(r%lyapunov)//", vectors = "// &
                   fmt_int(r%vectors)//", qr_every = "//fmt_int(r%qr_every)//", align = "// &
                   fmt_int(r%align)//", jacobian = "//fmt_logical(r%jacobian)// &
                   ", jacobian_cycles = "//fmt_int(r%jacobian_cycles)
            if (r%covariant) text = text//", covariant = "//fmt_logical(r%covariant)// &
                ", clv_transient = "//fmt_int(r%clv_transient)//", clv_store = "// &
                fmt_int(r%clv_store)//", clv_save = "//fmt_int(r%clv_save)
            if (r%window > 0) text = text//", window = "//fmt_int(r%window)
            text = text//" /"//new_line('a')
        end associate
    end function lyapunov_group

    function output_group(cfg) result(text)
        type(config_t), intent(in) :: cfg
        character(len=:), allocatable :: text

        text = "&output file = '"//cfg%output_file//"', overwrite = "// &
               fmt_logical(cfg%overwrite)//", max_size_mb = "//exact(cfg%max_size_mb)// &
               " /"//new_line('a')
    end function output_group

    function sweep_group(cfg) result(text)
        type(config_t), intent(in) :: cfg
        character(len=:), allocatable :: text

        text = "&sweep parameter = '"//cfg%sweep_parameter//"', start = "// &
               exact(cfg%sweep_start)//", stop = "//exact(cfg%sweep_stop)//", step = "// &
               exact(cfg%sweep_step)//", mode = '"//cfg%sweep_mode//"'"
        if (len(cfg%sweep_parameter2) > 0) &
            text = text//", parameter2 = '"//cfg%sweep_parameter2//"', start2 = "// &
                   exact(cfg%sweep_start2)//", stop2 = "//exact(cfg%sweep_stop2)// &
                   ", step2 = "//exact(cfg%sweep_step2)
        text = text//" /"//new_line('a')
    end function sweep_group

    !> A real in the fewest significant digits that read back to the same value: positional
    !> for 1e-4 <= |x| < 1e15 (2.2, 0.05, 1000.0), else with an exponent (1e-09).
    pure function exact(x) result(text)
        real(wp), intent(in) :: x
        character(len=:), allocatable :: text
        character(len=40) :: buf
        character(len=:), allocatable :: digits
        real(wp) :: back
        integer :: d, ios, e, point

        if (x == 0 .or. .not. ieee_is_finite(x)) then
            write (buf, '(g0)') x
            text = trim(adjustl(buf))
            if (x == 0) text = merge('-0.0', ' 0.0', sign(1.0_wp, x) < 0)
            text = trim(adjustl(text))
            return
        end if
        do d = 1, 17
            write (buf, '(es30.'//fmt_int(max(d - 1, 1))//'e4)') x
            read (buf, *, iostat=ios) back
            if (ios == 0 .and. back == x) exit
        end do
        buf = adjustl(buf)
        e = index(buf, 'E')
        read (buf(e + 1:), *) point
        digits = buf(:e - 1)
        if (abs(x) >= 1.0e-4_wp .and. abs(x) < 1.0e15_wp) then
            text = positional(digits, point)
        else
            text = trim(strip_zeros(digits))//'e'//fmt_int(point)
        end if
    end function exact

    !> "d.ddd" (with sign) times 10**point, written without an exponent: 2.2, 0.05, 1000.0.
    pure function positional(mantissa, point) result(text)
        character(len=*), intent(in) :: mantissa
        integer, intent(in) :: point
        character(len=:), allocatable :: text, m, sign_text

        sign_text = ''
        m = mantissa
        if (m(1:1) == '-') then
            sign_text = '-'
            m = m(2:)
        end if
        m = m(1:1)//m(3:)
        do while (len(m) > 1 .and. m(len(m):len(m)) == '0')
            m = m(:len(m) - 1)
        end do
        if (point < 0) then
            text = sign_text//'0.'//repeat('0', -point - 1)//m
        else if (len(m) <= point + 1) then
            text = sign_text//m//repeat('0', point + 1 - len(m))//'.0'
        else
            text = sign_text//m(:point + 1)//'.'//m(point + 2:)
        end if
    end function positional

    !> "d.dd000" -> "d.dd" (at least one digit after the point).
    pure function strip_zeros(mantissa) result(text)
        character(len=*), intent(in) :: mantissa
        character(len=:), allocatable :: text

        text = trim(mantissa)
        do while (text(len(text):len(text)) == '0' .and. text(len(text) - 1:len(text) - 1) /= '.')
            text = text(:len(text) - 1)
        end do
    end function strip_zeros

    !> The values as a namelist list, "v1, v2, ...". Built in a buffer that doubles, so that a
    !> list of 10^5 values costs linear time, not a copy of the text per value.
    pure function exact_list(values) result(text)
        real(wp), intent(in) :: values(:)
        character(len=:), allocatable :: text, buffer, piece
        integer :: i, used

        allocate (character(len=max(64, 24*size(values))) :: buffer)
        used = 0
        do i = 1, size(values)
            piece = exact(values(i))
            if (i > 1) piece = ', '//piece
            if (used + len(piece) > len(buffer)) buffer = buffer//repeat(' ', len(buffer))
            buffer(used + 1:used + len(piece)) = piece
            used = used + len(piece)
        end do
        text = buffer(:used)
    end function exact_list

    pure function fmt_logical(flag) result(text)
        logical, intent(in) :: flag
        character(len=:), allocatable :: text

        text = merge('.true. ', '.false.', flag)
        text = trim(text)
    end function fmt_logical

    !> The ranges of a random start's x_amp and v_amp, for a message.
    pure function amplitudes_allowed(smallest_spacing) result(text)
        real(wp), intent(in) :: smallest_spacing
        character(len=:), allocatable :: text

        text = "x_amp in [0, half the smallest spacing = "//fmt_real(0.5_wp*smallest_spacing)// &
               "), v_amp in [0, 1e6]"
    end function amplitudes_allowed

    subroutine check_range(err, group, key, value, low, high, allowed, open_high)
        type(error_t), allocatable, intent(out) :: err
        character(len=*), intent(in) :: group, key, allowed
        real(wp), intent(in) :: value, low, high
        logical, intent(in), optional :: open_high
        logical :: inside

        inside = ieee_is_finite(value) .and. value >= low .and. value <= high
        if (present(open_high)) then
            if (open_high) inside = inside .and. value < high
        end if
        if (.not. inside) call set_error(err, "&"//group//": "//key//" = "//fmt_real(value)// &
                                         " is outside "//allowed)
    end subroutine check_range

    !> How many leading entries of a namelist list were given; -1 if they are not consecutive.
    pure integer function count_given(values)
        real(wp), intent(in) :: values(:)
        integer :: m

        m = 0
        do while (m < size(values))
            if (values(m + 1) == unset) exit
            m = m + 1
        end do
        count_given = m
        if (m < size(values)) then
            if (any(values(m + 1:) /= unset)) count_given = -1
        end if
    end function count_given

    subroutine group_error(err, group, ios, msg)
        type(error_t), allocatable, intent(out) :: err
        character(len=*), intent(in) :: group, msg
        integer, intent(in) :: ios

        if (ios == iostat_end) then
            call set_error(err, "&"//group//": the group is incomplete (no closing '/') or "// &
                           "a value is malformed")
        else
            call set_error(err, "&"//group//": "//trim(msg))
        end if
    end subroutine group_error

    !> Lyapunov exponents (tangent vectors) a validated configuration computes: none without
    !> &lyapunov, else `vectors`, 0 meaning all 2n.
    pure integer function lyapunov_vectors(cfg)
        type(config_t), intent(in) :: cfg

        lyapunov_vectors = vector_count(cfg%record, cfg%model%n)
    end function lyapunov_vectors

    !> Refuse, before anything is written, records larger than &output max_size_mb.
    subroutine check_size(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: mb
        integer :: k

        k = lyapunov_vectors(cfg)
        ! strobe x, v, cycle; running estimates (k values and a cycle per kept row)
        mb = (16.0_wp*cfg%model%n + 8)*real(cfg%record%cycles, wp)/1.0e6_wp
        if (cfg%record%lyapunov) mb = mb + (8.0_wp*k + 8)* &
                                      running_rows(cfg%record%cycles/ &
                                                   max(1, cfg%record%qr_every))/1.0e6_wp
        ! finite-time exponents: k values and a cycle per window
        if (cfg%record%lyapunov .and. cfg%record%window > 0) &
            mb = mb + (8.0_wp*k + 8)*(cfg%record%cycles/cfg%record%window)/1.0e6_wp
        if (mb > cfg%max_size_mb) then
            call set_error(err, "&output: the strobe records of this run need about "// &
                           fmt_real(mb)//" MB (n x cycles x 16 bytes, plus Lyapunov "// &
                           "estimates and finite-time exponents), more than max_size_mb = "// &
                           fmt_real(cfg%max_size_mb)//"; lower &run cycles (or raise "// &
                           "&lyapunov window) or raise &output max_size_mb")
            return
        end if
        ! tangent frames in memory: the frame, the QR's copy, the copy kept while lost
        ! directions are looked for, and a bound on the rest; for the Poincare-map Jacobian the
        ! same for a full 2n x 2n frame
        mb = 32.0_wp*k*2*cfg%model%n/1.0e6_wp
        if (cfg%record%jacobian) mb = max(mb, 32.0_wp*(2.0_wp*cfg%model%n)**2/1.0e6_wp)
        if (mb > cfg%max_size_mb) then
            call set_error(err, "&lyapunov: the tangent vectors of this run need about "// &
                           fmt_real(mb)//" MB of memory, more than &output max_size_mb = "// &
                           fmt_real(cfg%max_size_mb)//"; lower vectors, leave jacobian off, "// &
                           "or raise max_size_mb")
            return
        end if
        if (cfg%record%lyapunov .and. cfg%record%covariant) call check_clv_size(cfg, k, err)
    end subroutine check_size

    !> Covariant vectors: /clv in the file, and the scratch files of the forward pass
    !> (docs/model.md section 14.3), each within max_size_mb.
    subroutine check_clv_size(cfg, k, err)
        type(config_t), intent(in) :: cfg
        integer, intent(in) :: k
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: mb
        integer :: n

        n = cfg%model%n
        associate (r => cfg%record)
            mb = (8.0_wp*(k + 2) + 8.0_wp*min(r%clv_store, k)*n)*(r%cycles - r%clv_transient)
            mb = (mb + 8.0_wp*r%clv_save*k*2*n)/1.0e6_wp
            if (mb > cfg%max_size_mb) then
                call set_error(err, "&output: /clv of this run needs about "//fmt_real(mb)// &
                               " MB, more than max_size_mb = "//fmt_real(cfg%max_size_mb)// &
                               "; lower &run cycles, &lyapunov vectors, clv_store or "// &
                               "clv_save, or raise max_size_mb")
                return
            end if
            mb = clv_scratch_bytes(n, k, r%cycles, r%clv_transient)/1.0e6_wp
            if (mb > cfg%max_size_mb) &
                call set_error(err, "&lyapunov: the covariant vectors' scratch files need "// &
                               "about "//fmt_real(mb)//" MB of disk (2n x vectors x 8 bytes "// &
                               "per record), more than &output max_size_mb = "// &
                               fmt_real(cfg%max_size_mb)//"; lower &run cycles or vectors, "// &
                               "or raise max_size_mb")
        end associate
    end subroutine check_clv_size

    !> `dir/run.nml` -> `dir/run.h5`: next to the input, wherever the program runs.
    pure function default_output(path) result(out)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: out
        integer :: slash, dot

        slash = index(path, '/', back=.true.)
        dot = index(path, '.', back=.true.)
        out = path
        ! (a dot of the directory's name, or a name that starts with one, is no extension)
        if (dot > slash + 1) out = path(:dot - 1)
        out = out//'.h5'
    end function default_output

end module chain_config
