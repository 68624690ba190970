!> Reading the run configuration: the input's text is checked against the input schema
!> (chain_namelist, chain_inputs), its values read key by key with the schema's defaults
!> (chain_input_values), copied into `config_t` with the defaults that depend on other keys,
!> and checked (chain_config_checks). Groups: &chain (the model, required), &initial, &run,
!> &lyapunov, &output, &sweep, &continuation, &census (optional); a group may appear at most
!> once; an unknown group or key is an error, never silently ignored. docs/model.md
!> sections 1, 6-8 and 13 give the keys' meaning.
module chain_config
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_real, fmt_int, fmt_int8
    use chain_files, only: same_file
    use chain_model, only: model_t
    use chain_namelist, only: alias_t, check_namelist, apply_override, groups_in, lower, &
                              schema_keys
    use chain_inputs, only: input_key_t, input_keys, input_specs, max_list
    use chain_input_values, only: read_inputs, check_inputs, echo_inputs, set_input, is_given, &
                                  has_value, list_count, real_input, int_input, int8_input, &
                                  flag_input, string_input, reals_input, strings_input
    use chain_config_type, only: config_t, lyapunov_vectors
    use chain_config_checks, only: validate_config, sweep_parameters, sweep_axis_points, &
                                   plane_coordinate, check_spacing_count
    use chain_config_size, only: check_size
    implicit none
    private
    public :: config_t, read_config, read_config_text, validate_config, config_summary
    public :: lyapunov_vectors, max_list, fmt_real, fmt_int, sweep_parameters, set_boundary
    public :: check_size, plane_coordinate, sweep_axis_points

    character(len=*), parameter :: group_names(8) = &
        [character(len=12) :: 'chain', 'initial', 'run', 'lyapunov', 'output', 'sweep', &
         'continuation', 'census']
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

contains

    !> Read and validate the namelist file at `path`, with `overrides` (`group.key=value`,
    !> in order) applied to its text first.
    subroutine read_config(path, cfg, err, overrides)
        character(len=*), intent(in) :: path
        type(config_t), intent(out) :: cfg
        type(error_t), allocatable, intent(out) :: err
        character(len=*), intent(in), optional :: overrides(:)
        character(len=:), allocatable :: text

        call read_text(path, text, err)
        if (allocated(err)) return
        call read_config_text(path, text, cfg, err, overrides)
    end subroutine read_config

    !> Read and validate the namelist `text`; `source` names it in messages and, when it is a
    !> file, gives the default output file its name (`dir/run.nml` -> `dir/run.h5`).
    subroutine read_config_text(source, text, cfg, err, overrides)
        character(len=*), intent(in) :: source, text
        type(config_t), intent(out) :: cfg
        type(error_t), allocatable, intent(out) :: err
        character(len=*), intent(in), optional :: overrides(:)
        logical :: present_groups(size(group_names))
        integer :: j

        cfg%input_text = text
        call check_namelist(source, cfg%input_text, input_specs(), err, paper_symbols)
        if (allocated(err)) return
        if (present(overrides)) then
            call check_override_keys(source, overrides, err)
            if (allocated(err)) return
            do j = 1, size(overrides)
                call apply_override(cfg%input_text, trim(overrides(j)), input_specs(), err, &
                                    paper_symbols)
                if (allocated(err)) return
            end do
        end if
        present_groups = [(any(groups_in(cfg%input_text) == group_names(j)), &
                           j=1, size(group_names))]
        if (.not. present_groups(1)) then
            call set_error(err, trim(source)//": the required group &chain is missing")
            return
        end if
        call read_inputs(cfg%input_text, cfg%inputs, err)
        if (.not. allocated(err)) call check_required(cfg, present_groups, err)
        if (.not. allocated(err)) call check_inputs(cfg%inputs, err)
        if (allocated(err)) return
        call copy_chain(cfg, err)
        if (.not. allocated(err)) call copy_initial(cfg, err)
        if (allocated(err)) return
        call copy_run(cfg)
        call copy_lyapunov(cfg, present_groups(4))
        call copy_output(cfg, source)
        if (present_groups(6)) call copy_sweep(cfg, err)
        if (.not. allocated(err) .and. present_groups(7)) call copy_continuation(cfg, err)
        if (.not. allocated(err) .and. present_groups(8)) call copy_census(cfg, err)
        if (allocated(err)) return
        if (same_file(source, cfg%output_file) .or. &
            same_file(source, cfg%output_file//'.part')) then
            call set_error(err, "&output: file = '"//cfg%output_file//"' is the input file "// &
                           "'"//trim(source)//"' (or its .part); overwrite never replaces the "// &
                           "input: choose another name")
            return
        end if
        call validate_config(cfg, err)
    end subroutine read_config_text

    !> Two or more overrides with unknown keys (of known groups) are named at once, as the
    !> reader names those of a file (one is named by apply_override, with the override
    !> written out): each group's unknown keys go into a namelist that check_namelist reads.
    subroutine check_override_keys(source, overrides, err)
        character(len=*), intent(in) :: source
        character(len=*), intent(in) :: overrides(:)
        type(error_t), allocatable, intent(out) :: err
        character(len=:), allocatable :: text, group, keys, key
        integer :: j, g, dot, eq, n_unknown

        text = ''
        n_unknown = 0
        do g = 1, size(group_names)
            group = trim(group_names(g))
            keys = ''
            do j = 1, size(overrides)
                dot = index(overrides(j), '.')
                eq = index(overrides(j), '=')
                if (dot < 2 .or. eq < dot + 2) cycle
                if (lower(overrides(j)(:dot - 1)) /= group) cycle
                key = trim(adjustl(overrides(j)(dot + 1:eq - 1)))
                if (any(schema_keys(input_specs(), group) == lower(key))) cycle
                keys = keys//" "//key//" = 0"
                n_unknown = n_unknown + 1
            end do
            if (len(keys) > 0) text = text//"&"//group//keys//" /"//new_line('a')
        end do
        if (n_unknown > 1) call check_namelist(trim(source)//" (overrides)", text, &
                                               input_specs(), err, paper_symbols)
    end subroutine check_override_keys

    !> The keys the schema marks required, in each group given: "&chain: n (number of
    !> oscillators) is required, in [1, 10000000]".
    subroutine check_required(cfg, present_groups, err)
        type(config_t), intent(in) :: cfg
        logical, intent(in) :: present_groups(:)
        type(error_t), allocatable, intent(out) :: err
        type(input_key_t) :: spec
        integer :: k

        do k = 1, size(input_keys)
            spec = input_keys(k)
            if (.not. spec%required) cycle
            if (.not. any(present_groups .and. group_names == spec%group)) cycle
            if (is_given(cfg%inputs, trim(spec%group), trim(spec%name))) cycle
            call set_error(err, "&"//trim(spec%group)//": "//trim(spec%name)//" ("// &
                           trim(spec%help)//") is required")
            if (len_trim(spec%range) > 0) err%message = err%message//", in "//trim(spec%range)
            return
        end do
    end subroutine check_required

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

    subroutine copy_chain(cfg, err)
        type(config_t), intent(inout) :: cfg
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: spacing(:)
        integer :: n, m

        associate (s => cfg%inputs, model => cfg%model)
            n = int_input(s, 'chain', 'n')
            m = list_count(s, 'chain', 'spacing')
            if (m < 0) then
                call set_error(err, "&chain: spacing must be given as one value, or as n+1 "// &
                               "consecutive values from spacing(1) (bond 0, the left wall)")
                return
            end if
            spacing = reals_input(s, 'chain', 'spacing')
            if (m == 1) then
                model%spacing = [(spacing(1), m=0, n)]
            else if (m == n + 1) then
                model%spacing = spacing
            else
                call check_spacing_count(err, n, m)
                return
            end if
            model%n = n
            model%damping = real_input(s, 'chain', 'damping')
            model%restitution = real_input(s, 'chain', 'restitution')
            model%amplitude = real_input(s, 'chain', 'amplitude')
            model%omega = real_input(s, 'chain', 'omega')
            model%stick_speed = real_input(s, 'run', 'stick_speed')
            call set_boundary(model, string_input(s, 'chain', 'boundary'), err)
        end associate
    end subroutine copy_chain

    subroutine copy_initial(cfg, err)
        type(config_t), intent(inout) :: cfg
        type(error_t), allocatable, intent(out) :: err

        associate (s => cfg%inputs)
            if (list_count(s, 'initial', 'x0') < 0 .or. list_count(s, 'initial', 'v0') < 0) then
                call set_error(err, "&initial: x0 and v0 must be given as consecutive values "// &
                               "from index 1")
                return
            end if
            cfg%initial_kind = lower(trim(adjustl(string_input(s, 'initial', 'kind'))))
            cfg%seed = int_input(s, 'initial', 'seed')
            cfg%x_amp = real_input(s, 'initial', 'x_amp')
            cfg%v_amp = real_input(s, 'initial', 'v_amp')
            cfg%x0 = reals_input(s, 'initial', 'x0')
            cfg%v0 = reals_input(s, 'initial', 'v0')
            cfg%initial_file = trim(string_input(s, 'initial', 'file'))
        end associate
    end subroutine copy_initial

    subroutine copy_run(cfg)
        type(config_t), intent(inout) :: cfg

        associate (s => cfg%inputs, r => cfg%record)
            r%transient = int8_input(s, 'run', 'transient')
            r%cycles = int8_input(s, 'run', 'cycles')
            r%phase = real_input(s, 'run', 'phase')
            r%record_events = flag_input(s, 'run', 'record_events')
            r%max_period = int_input(s, 'run', 'max_period')
            r%period_tol = real_input(s, 'run', 'period_tol')
        end associate
    end subroutine copy_run

    !> Without &lyapunov no exponents; the covariant vectors' defaults fit the run (&run is
    !> read before this group).
    subroutine copy_lyapunov(cfg, given)
        type(config_t), intent(inout) :: cfg
        logical, intent(in) :: given

        associate (s => cfg%inputs, r => cfg%record)
            if (.not. given) then
                call set_input(s, 'lyapunov', 'enabled', '.false.')
                return
            end if
            r%lyapunov = flag_input(s, 'lyapunov', 'enabled')
            r%vectors = int_input(s, 'lyapunov', 'vectors')
            r%qr_every = int_input(s, 'lyapunov', 'qr_every')
            r%align = int_input(s, 'lyapunov', 'align')
            r%jacobian = flag_input(s, 'lyapunov', 'jacobian')
            r%jacobian_cycles = int_input(s, 'lyapunov', 'jacobian_cycles')
            r%covariant = flag_input(s, 'lyapunov', 'covariant')
            r%clv_save = int_input(s, 'lyapunov', 'clv_save')
            r%window = int_input(s, 'lyapunov', 'window')
            if (.not. has_value(s, 'lyapunov', 'clv_transient')) call set_input(s, 'lyapunov', &
                'clv_transient', fmt_int8(max(1_i8, min(200_i8, r%cycles/2))))
            r%clv_transient = int_input(s, 'lyapunov', 'clv_transient')
            if (.not. has_value(s, 'lyapunov', 'clv_store')) call set_input(s, 'lyapunov', &
                'clv_store', fmt_int(min(4, lyapunov_vectors(cfg))))
            r%clv_store = int_input(s, 'lyapunov', 'clv_store')
        end associate
    end subroutine copy_lyapunov

    subroutine copy_output(cfg, source)
        type(config_t), intent(inout) :: cfg
        character(len=*), intent(in) :: source

        associate (s => cfg%inputs)
            cfg%output_file = trim(string_input(s, 'output', 'file'))
            if (len(cfg%output_file) == 0) then
                cfg%output_file = default_output(source)
                call set_input(s, 'output', 'file', "'"//cfg%output_file//"'")
            end if
            cfg%overwrite = flag_input(s, 'output', 'overwrite')
            cfg%max_size_mb = real_input(s, 'output', 'max_size_mb')
        end associate
    end subroutine copy_output

    subroutine copy_sweep(cfg, err)
        type(config_t), intent(inout) :: cfg
        type(error_t), allocatable, intent(out) :: err

        associate (s => cfg%inputs)
            cfg%sweep_parameter2 = lower(trim(adjustl(string_input(s, 'sweep', 'parameter2'))))
            if (len(cfg%sweep_parameter2) > 0 .and. .not. (has_value(s, 'sweep', 'start2') &
                .and. has_value(s, 'sweep', 'stop2') .and. has_value(s, 'sweep', 'step2'))) then
                call set_error(err, "&sweep: parameter2 needs start2, stop2 and step2")
                return
            end if
            cfg%sweep = .true.
            cfg%sweep_parameter = lower(trim(adjustl(string_input(s, 'sweep', 'parameter'))))
            cfg%sweep_mode = lower(trim(adjustl(string_input(s, 'sweep', 'mode'))))
            cfg%sweep_start = real_input(s, 'sweep', 'start')
            cfg%sweep_stop = real_input(s, 'sweep', 'stop')
            cfg%sweep_step = real_input(s, 'sweep', 'step')
            if (len(cfg%sweep_parameter2) > 0) then
                cfg%sweep_start2 = real_input(s, 'sweep', 'start2')
                cfg%sweep_stop2 = real_input(s, 'sweep', 'stop2')
                cfg%sweep_step2 = real_input(s, 'sweep', 'step2')
            end if
        end associate
    end subroutine copy_sweep

    subroutine copy_continuation(cfg, err)
        type(config_t), intent(inout) :: cfg
        type(error_t), allocatable, intent(out) :: err

        associate (s => cfg%inputs)
            cfg%cont_max_points = int_input(s, 'continuation', 'max_points')
            if (cfg%cont_max_points /= 1 .and. .not. (has_value(s, 'continuation', 'stop') &
                .and. has_value(s, 'continuation', 'step'))) then
                call set_error(err, "&continuation: stop and step are required (unless "// &
                               "max_points = 1: Newton only)")
                return
            end if
            cfg%continuation = .true.
            cfg%cont_parameter = lower(trim(adjustl(string_input(s, 'continuation', &
                                                                 'parameter'))))
            ! (not given with max_points = 1: 0, unused)
            cfg%cont_stop = real_input(s, 'continuation', 'stop')
            cfg%cont_step = real_input(s, 'continuation', 'step')
            cfg%cont_period = int_input(s, 'continuation', 'period')
            cfg%cont_doublings = int_input(s, 'continuation', 'doublings')
            cfg%cont_branch_points = int_input(s, 'continuation', 'branch_points')
            cfg%cont_follow = lower(trim(adjustl(string_input(s, 'continuation', 'follow'))))
            cfg%cont_parameter2 = lower(trim(adjustl(string_input(s, 'continuation', &
                                                                  'parameter2'))))
            if (len(cfg%cont_follow) > 0) then
                if (.not. (has_value(s, 'continuation', 'stop2') .and. &
                           has_value(s, 'continuation', 'step2') .and. &
                           len(cfg%cont_parameter2) > 0)) then
                    call set_error(err, "&continuation: follow = '"//cfg%cont_follow// &
                                   "' needs parameter2, stop2 and step2")
                    return
                end if
                cfg%cont_stop2 = real_input(s, 'continuation', 'stop2')
                cfg%cont_step2 = real_input(s, 'continuation', 'step2')
            end if
        end associate
    end subroutine copy_continuation

    !> With a plane, samples follow from its grid (plane_points**2).
    subroutine copy_census(cfg, err)
        type(config_t), intent(inout) :: cfg
        type(error_t), allocatable, intent(out) :: err
        character(len=64) :: plane(2)
        integer :: points

        associate (s => cfg%inputs)
            plane = strings_input(s, 'census', 'plane', 2)
            if (all(plane == '')) then
                if (has_value(s, 'census', 'plane_points') .or. &
                    has_value(s, 'census', 'plane_range')) then
                    call set_error(err, "&census: plane_range and plane_points need a plane "// &
                                   "(plane = 'x<i>', 'v<j>')")
                    return
                end if
            else
                if (list_count(s, 'census', 'plane_range') /= 4) then
                    call set_error(err, "&census: a plane needs plane_range = min, max of "// &
                                   "the first coordinate, min, max of the second")
                    return
                end if
                if (.not. has_value(s, 'census', 'plane_points')) &
                    call set_input(s, 'census', 'plane_points', '100')
                points = int_input(s, 'census', 'plane_points')
                ! an out-of-range plane_points is named by validate_plane
                if (points >= 2 .and. points <= 3162) then
                    if (is_given(s, 'census', 'samples') .and. &
                        int_input(s, 'census', 'samples') /= points**2) then
                        call set_error(err, "&census: samples = "// &
                                       fmt_int(int_input(s, 'census', 'samples'))// &
                                       " with a plane must be left out or equal "// &
                                       "plane_points**2 = "//fmt_int(points**2))
                        return
                    end if
                    call set_input(s, 'census', 'samples', fmt_int(points**2))
                end if
                cfg%census_plane = plane
                cfg%census_plane_range = reals_input(s, 'census', 'plane_range')
                cfg%census_plane_points = points
            end if
            cfg%census = .true.
            cfg%census_samples = int_input(s, 'census', 'samples')
            cfg%census_seed = int_input(s, 'census', 'seed')
            cfg%census_x_amp = real_input(s, 'census', 'x_amp')
            cfg%census_v_amp = real_input(s, 'census', 'v_amp')
            cfg%census_tolerance = real_input(s, 'census', 'tolerance')
            cfg%census_mirror = lower(trim(adjustl(string_input(s, 'census', 'mirror'))))
            cfg%census_exponents = int_input(s, 'census', 'exponents')
        end associate
    end subroutine copy_census

    !> The configuration actually used, every key of every group, as a namelist input that
    !> reads back to the same configuration (reals to full precision, lists in full; &sweep,
    !> &continuation and &census only when there is one).
    function config_summary(cfg) result(text)
        type(config_t), intent(in) :: cfg
        character(len=:), allocatable :: text

        text = echo_inputs(cfg%inputs, pack(group_names, [.true., .true., .true., .true., &
                                                           .true., cfg%sweep, &
                                                           cfg%continuation, cfg%census]))
    end function config_summary

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
