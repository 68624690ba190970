!> The input schema: every key of every namelist group, declared once with its type, default,
!> allowed range, units and one-line help. The reader (chain_input_values), the range
!> messages, the echo of the configuration, `impactchain --schema` and the Python API's
!> defaults all come from this table; docs/model.md sections 1, 6-8 and 13 give the keys'
!> meaning. A range that names another key ("[0, 2n]") is checked by the code that knows that
!> key (chain_config_checks); `dynamic` marks it.
module chain_inputs
    use chain_kinds, only: wp, i8, two_pi
    use chain_error, only: error_t, set_error, fmt_real, fmt_int8
    use chain_exact, only: exact
    use chain_namelist, only: key_spec_t, key_integer, key_real, key_logical, key_string
    implicit none
    private
    public :: input_key_t, input_keys, input_specs, find_input, input_schema_json
    public :: check_input, outside_message, choices_listed, max_list, none
    public :: key_integer, key_real, key_logical, key_string

    !> Longest explicit list in a namelist (spacing, x0, v0); longer chains use a file start.
    integer, parameter :: max_list = 100001
    !> No bound on that side.
    real(wp), parameter :: none = huge(1.0_wp)

    type :: input_key_t
        character(len=12) :: group = ''
        character(len=16) :: name = ''
        integer :: kind = key_real
        logical :: list = .false.
        integer :: most = 1             !! the most values a list takes
        logical :: wide = .false.       !! an integer read into 64 bits
        logical :: required = .false.
        character(len=24) :: default = ''   !! namelist text of the default; '': none or depends
        character(len=40) :: default_text = '' !! the default as the docs show it
        character(len=48) :: range = ''     !! as the messages word it
        real(wp) :: low = -none, high = none
        logical :: low_open = .false., high_open = .false.
        logical :: dynamic = .false.    !! the range names another key: checked in code
        character(len=64) :: choices = '' !! blank-separated allowed strings (any case)
        character(len=16) :: units = ''
        character(len=96) :: help = ''
        logical :: echo_default = .true. !! echoed when at its default (else left out)
    end type input_key_t

    type(input_key_t), parameter :: input_keys(*) = [ &
        input_key_t('chain', 'n', key_integer, required=.true., range='[1, 10000000]', &
                    low=1, high=1.0e7_wp, units='1', help='number of oscillators'), &
        input_key_t('chain', 'spacing', key_real, list=.true., most=max_list, default='1.0', &
                    default_text='1.0 for every bond', range='> 0', low=0, low_open=.true., &
                    dynamic=.true., units='length', help='equilibrium spacing a: one value, '// &
                    'or n + 1 values, one per bond from the left wall'), &
        input_key_t('chain', 'damping', key_real, default='0.05', range='[0, 1)', low=0, &
                    high=1, high_open=.true., units='1', help='damping ratio b'), &
        input_key_t('chain', 'restitution', key_real, default='0.7', range='[0, 1]', low=0, &
                    high=1, units='1', help='coefficient of restitution K'), &
        input_key_t('chain', 'amplitude', key_real, required=.true., range='[0, 1e6]', low=0, &
                    high=1.0e6_wp, units='length', help='drive amplitude A'), &
        input_key_t('chain', 'omega', key_real, required=.true., range='[1e-3, 1e3]', &
                    low=1.0e-3_wp, high=1.0e3_wp, units='1/time', help='drive frequency w'), &
        input_key_t('chain', 'boundary', key_string, default="'fixed'", choices='fixed free', &
                    help='fixed: walls at both ends; free: no walls'), &
        input_key_t('initial', 'kind', key_string, default="'rest'", &
                    choices='rest random explicit file', help='how the chain starts'), &
        input_key_t('initial', 'seed', key_integer, default='1', units='1', &
                    help='seed of a random start'), &
        input_key_t('initial', 'x_amp', key_real, default='0.0', &
                    range='[0, half the smallest spacing)', low=0, dynamic=.true., &
                    units='length', help='a random start: largest |x|'), &
        input_key_t('initial', 'v_amp', key_real, default='0.0', range='[0, 1e6]', low=0, &
                    high=1.0e6_wp, units='length/time', help='a random start: largest |v|'), &
        input_key_t('initial', 'file', key_string, default="''", units='', &
                    help="a file start: an earlier run's file, its final state"), &
        input_key_t('initial', 'kick', key_real, default='0.0', range='[-1e6, 1e6]', &
                    low=-1.0e6_wp, high=1.0e6_wp, units='length/time', &
                    help='velocity added to oscillator 1 at t = 0 (an impulse at the left '// &
                    "end); not to a file's start"), &
        input_key_t('initial', 'x0', key_real, list=.true., most=max_list, &
                    default_text='none', units='length', &
                    help='an explicit start: n displacements'), &
        input_key_t('initial', 'v0', key_real, list=.true., most=max_list, &
                    default_text='0 for every oscillator', units='length/time', &
                    help='an explicit start: n velocities'), &
        input_key_t('run', 'transient', key_integer, wide=.true., default='0', &
                    range='[0, 1e12]', low=0, high=1.0e12_wp, units='drive cycles', &
                    help='drive cycles run before the first record'), &
        input_key_t('run', 'cycles', key_integer, wide=.true., default='200', &
                    range='[1, 1e12]', low=1, high=1.0e12_wp, units='drive cycles', &
                    help='drive cycles recorded, one strobe record each'), &
        input_key_t('run', 'phase', key_real, default='0.0', range='[0, 2 pi)', low=0, &
                    high=two_pi, high_open=.true., units='radian', &
                    help='drive phase of the Poincare section'), &
        input_key_t('run', 'record_events', key_logical, default='.true.', &
                    help='keep every collision'), &
        input_key_t('run', 'stick_speed', key_real, default='1e-9', range='(0, 1]', low=0, &
                    low_open=.true., high=1, units='length/time', &
                    help='approach speed below which chatter ends in rest'), &
        input_key_t('run', 'max_period', key_integer, default='16', range='[1, 10000]', &
                    low=1, high=1.0e4_wp, units='drive cycles', help='longest period looked for'), &
        input_key_t('run', 'period_tol', key_real, default='1e-6', range='(0, 1)', low=0, &
                    low_open=.true., high=1, high_open=.true., units='1', &
                    help='relative tolerance of the period rule'), &
        input_key_t('lyapunov', 'enabled', key_logical, default='.true.', &
                    default_text='.true. (no exponents without &lyapunov)', &
                    help='compute the Lyapunov spectrum'), &
        input_key_t('lyapunov', 'vectors', key_integer, default='0', range='[0, 2n]', low=0, &
                    dynamic=.true., units='1', help='exponents computed (0: all 2n)'), &
        input_key_t('lyapunov', 'qr_every', key_integer, default='0', range='[0, cycles]', &
                    low=0, dynamic=.true., units='drive cycles', &
                    help='cycles per QR step (0: adaptive)'), &
        input_key_t('lyapunov', 'align', key_integer, default='100', range='[0, 100000]', &
                    low=0, high=1.0e5_wp, units='drive cycles', &
                    help='transient cycles that turn the frame before averaging'), &
        input_key_t('lyapunov', 'jacobian', key_logical, default='.false.', &
                    help='the Poincare-map Jacobian at the final state'), &
        input_key_t('lyapunov', 'jacobian_cycles', key_integer, default='1', &
                    range='[1, 1000]', low=1, high=1.0e3_wp, units='drive cycles', &
                    help='drive cycles of that map'), &
        input_key_t('lyapunov', 'covariant', key_logical, default='.false.', &
                    echo_default=.false., help='covariant Lyapunov vectors'), &
        input_key_t('lyapunov', 'clv_transient', key_integer, &
                    default_text='cycles/2, in [1, 200]', range='[1, cycles - 1]', low=1, &
                    dynamic=.true., units='drive cycles', echo_default=.false., &
                    help='last records, without vectors, over which the backward pass converges'), &
        input_key_t('lyapunov', 'clv_store', key_integer, default_text='min(4, vectors)', &
                    range='[0, vectors]', low=0, dynamic=.true., units='1', &
                    echo_default=.false., help='vectors whose per-oscillator weights are kept'), &
        input_key_t('lyapunov', 'clv_save', key_integer, default='1', &
                    range='[0, cycles - clv_transient]', low=0, dynamic=.true., &
                    units='drive cycles', echo_default=.false., &
                    help='last records with vectors whose vectors are kept'), &
        input_key_t('lyapunov', 'window', key_integer, default='0', range='[0, cycles]', &
                    low=0, dynamic=.true., units='drive cycles', echo_default=.false., &
                    help='recorded cycles per finite-time exponent (0: none)'), &
        input_key_t('output', 'file', key_string, default_text="the input's name, .h5", &
                    help='the output file'), &
        input_key_t('output', 'overwrite', key_logical, default='.false.', &
                    help='replace an existing output file'), &
        input_key_t('output', 'max_size_mb', key_real, default='4096.0', range='(0, 1e9]', &
                    low=0, low_open=.true., high=1.0e9_wp, units='MB', &
                    help='largest output (and scratch, memory) a run may need'), &
        input_key_t('sweep', 'parameter', key_string, required=.true., dynamic=.true., &
                    choices='amplitude omega damping restitution spacing', &
                    help='the swept parameter of &chain'), &
        input_key_t('sweep', 'start', key_real, required=.true., help='first value'), &
        input_key_t('sweep', 'stop', key_real, required=.true., help='last value'), &
        input_key_t('sweep', 'step', key_real, required=.true., &
                    help='step from start towards stop'), &
        input_key_t('sweep', 'mode', key_string, default="'continuation'", &
                    choices='continuation independent', &
                    help='continuation: each point starts from the last state'), &
        input_key_t('sweep', 'parameter2', key_string, default="''", dynamic=.true., &
                    choices=' amplitude omega damping restitution spacing', &
                    help="a second swept parameter: a 2-D grid ('': none)"), &
        input_key_t('sweep', 'start2', key_real, default_text='none (needed with parameter2)', &
                    help='first value of parameter2'), &
        input_key_t('sweep', 'stop2', key_real, default_text='none (needed with parameter2)', &
                    help='last value of parameter2'), &
        input_key_t('sweep', 'step2', key_real, default_text='none (needed with parameter2)', &
                    help='step of parameter2'), &
        input_key_t('continuation', 'parameter', key_string, required=.true., dynamic=.true., &
                    choices='amplitude omega damping restitution spacing', &
                    help='the continued parameter of &chain (starting from its value)'), &
        input_key_t('continuation', 'stop', key_real, default_text='required unless '// &
                    'max_points = 1', help='the value the branch runs towards'), &
        input_key_t('continuation', 'step', key_real, default_text='required unless '// &
                    'max_points = 1', help='first step of the parameter'), &
        input_key_t('continuation', 'period', key_integer, default='1', range='1..10000', &
                    low=1, high=1.0e4_wp, units='drive cycles', help='period of the orbit'), &
        input_key_t('continuation', 'max_points', key_integer, default='200', &
                    range='>= 1', low=1, units='1', &
                    help='most orbits along the branch (1: Newton only)'), &
        input_key_t('continuation', 'doublings', key_integer, default='0', range='0..8', &
                    low=0, high=8, units='1', help='period doublings followed'), &
        input_key_t('continuation', 'branch_points', key_integer, default='0', range='0..4', &
                    low=0, high=4, units='1', &
                    help='levels of switching at branch points (two branches each)'), &
        input_key_t('continuation', 'follow', key_string, default="''", &
                    choices=' fold period-doubling grazing branch-point neimark-sacker', &
                    help="the first such special point of branch 0 followed in two "// &
                    "parameters, to /curve ('': none)"), &
        input_key_t('continuation', 'parameter2', key_string, default="''", dynamic=.true., &
                    choices=' amplitude omega damping restitution spacing', &
                    help="the curve's second parameter ('': none; needed with follow)"), &
        input_key_t('continuation', 'stop2', key_real, default_text='none (needed with follow)', &
                    help='the value of parameter2 the curve runs towards'), &
        input_key_t('continuation', 'step2', key_real, default_text='none (needed with follow)', &
                    help="the curve's arclength step; its sign: parameter2's first direction"), &
        input_key_t('census', 'samples', key_integer, default='100', &
                    default_text='100 (plane_points**2 with a plane)', &
                    range='[1, 10000000]', low=1, high=1.0e7_wp, units='1', &
                    help='random starts per point'), &
        input_key_t('census', 'seed', key_integer, default='1', units='1', &
                    help='seed of the starts'), &
        input_key_t('census', 'x_amp', key_real, default='0.3', &
                    range='[0, half the smallest spacing)', low=0, dynamic=.true., &
                    units='length', help='largest |x| of a start'), &
        input_key_t('census', 'v_amp', key_real, default='0.3', range='[0, 1e6]', low=0, &
                    high=1.0e6_wp, units='length/time', help='largest |v| of a start'), &
        input_key_t('census', 'tolerance', key_real, default='1e-6', range='(0, 1)', low=0, &
                    low_open=.true., high=1, high_open=.true., units='1', &
                    help='relative distance at which two attractors are one'), &
        input_key_t('census', 'mirror', key_string, default="'merge'", &
                    choices='merge separate', help='mirror images: one attractor or two'), &
        input_key_t('census', 'plane', key_string, list=.true., most=2, &
                    default_text='none', &
                    help="a plane of two start coordinates, 'x<i>' or 'v<i>'"), &
        input_key_t('census', 'plane_range', key_real, list=.true., most=4, &
                    default_text='none', units='', &
                    help='min, max of the first coordinate, then of the second'), &
        input_key_t('census', 'plane_points', key_integer, default_text='100 with a plane', &
                    range='[2, 3162]', low=2, high=3162, units='1', &
                    help='grid points along each side of the plane'), &
        input_key_t('census', 'exponents', key_integer, default='1', range='[1, 2n]', low=1, &
                    dynamic=.true., units='1', echo_default=.false., &
                    help='leading Lyapunov exponents of each sample')]

contains

    !> The checker's view of the table (chain_namelist): group, name, type, list.
    pure function input_specs() result(specs)
        type(key_spec_t) :: specs(size(input_keys))
        integer :: j

        do j = 1, size(input_keys)
            specs(j) = key_spec_t(input_keys(j)%group, input_keys(j)%name, input_keys(j)%kind, &
                                  input_keys(j)%list, input_keys(j)%wide, &
                                  merge(input_keys(j)%most, huge(1), input_keys(j)%list))
        end do
    end function input_specs

    !> Index of group.key in the table, 0 if none.
    pure integer function find_input(group, key) result(k)
        character(len=*), intent(in) :: group, key
        integer :: j

        k = 0
        do j = 1, size(input_keys)
            if (input_keys(j)%group == group .and. input_keys(j)%name == key) k = j
        end do
    end function find_input

    !> The message for a value outside its range: "&group: key = value is outside range".
    pure function outside_message(spec, value_text) result(text)
        type(input_key_t), intent(in) :: spec
        character(len=*), intent(in) :: value_text
        character(len=:), allocatable :: text, verb

        ! ("n = 0 is outside [1, 10000000]", "max_points = 0 must be >= 1")
        verb = " is outside "
        if (scan(spec%range(1:1), '<>') > 0) verb = " must be "
        text = "&"//trim(spec%group)//": "//trim(spec%name)//" = "//value_text//verb// &
               trim(spec%range)
    end function outside_message

    !> A number of key k against the table's static range (a NaN is outside every range).
    pure logical function inside(spec, x)
        type(input_key_t), intent(in) :: spec
        real(wp), intent(in) :: x

        inside = x == x .and. abs(x) <= huge(x)
        if (spec%low > -none) inside = inside .and. (x > spec%low .or. &
                                                     (x == spec%low .and. .not. spec%low_open))
        if (spec%high < none) inside = inside .and. (x < spec%high .or. &
                                                     (x == spec%high .and. .not. spec%high_open))
    end function inside

    !> Check a real value (reals as fmt_real writes them) or a 64-bit integer of group.key
    !> against the table's range; keys with a dynamic range or none pass.
    pure subroutine check_input(err, group, key, x, i)
        type(error_t), allocatable, intent(inout) :: err
        character(len=*), intent(in) :: group, key
        real(wp), intent(in), optional :: x
        integer(i8), intent(in), optional :: i
        type(input_key_t) :: spec
        integer :: k

        if (allocated(err)) return
        k = find_input(group, key)
        if (k == 0) return
        spec = input_keys(k)
        if (spec%dynamic .or. len_trim(spec%range) == 0) return
        if (present(x)) then
            if (.not. inside(spec, x)) call set_error(err, outside_message(spec, fmt_real(x)))
        else if (present(i)) then
            if (.not. inside(spec, real(i, wp))) &
                call set_error(err, outside_message(spec, fmt_int8(i)))
        end if
    end subroutine check_input

    !> The table as the JSON array of `impactchain --schema`'s "inputs" (one object a key).
    function input_schema_json() result(text)
        character(len=:), allocatable :: text
        integer :: j

        text = '['
        do j = 1, size(input_keys)
            if (j > 1) text = text//','
            text = text//new_line('a')//key_json(input_keys(j))
        end do
        text = text//new_line('a')//']'
    end function input_schema_json

    function key_json(spec) result(text)
        type(input_key_t), intent(in) :: spec
        character(len=:), allocatable :: text
        character(len=*), parameter :: type_names(4) = &
            [character(len=8) :: 'integer', 'real', 'logical', 'string']

        text = '{"group": '//quoted(spec%group)//', "name": '//quoted(spec%name)// &
               ', "type": '//quoted(type_names(spec%kind))//', "list": '// &
               json_bool(spec%list)//', "required": '// &
               json_bool(spec%required)//', "default": '// &
               default_json(spec)//', "default_text": '//quoted(default_words(spec))// &
               ', "range": '//quoted(range_words(spec))//', "min": '// &
               bound_json(spec, spec%low, -none)//', "max": '//bound_json(spec, spec%high, none)// &
               ', "choices": '//choices_json(spec%choices)//', "units": '// &
               quoted(spec%units)//', "help": '//quoted(spec%help)//'}'
    end function key_json

    pure function default_words(spec) result(text)
        type(input_key_t), intent(in) :: spec
        character(len=:), allocatable :: text

        text = trim(spec%default_text)
        if (len(text) == 0 .and. spec%required) text = 'required'
        if (len(text) == 0) text = trim(spec%default)
    end function default_words

    pure function range_words(spec) result(text)
        type(input_key_t), intent(in) :: spec
        character(len=:), allocatable :: text

        text = trim(spec%range)
        if (len(text) == 0 .and. len_trim(spec%choices) > 0) &
            text = 'one of '//choices_listed(spec%choices)
    end function range_words

    !> The default as a JSON value, from its namelist text ('fixed' -> "fixed", .true. -> true).
    pure function default_json(spec) result(text)
        type(input_key_t), intent(in) :: spec
        character(len=:), allocatable :: text

        text = trim(spec%default)
        if (len(text) == 0) then
            text = 'null'
        else if (spec%kind == key_string) then
            text = quoted(text(2:len(text) - 1))
        else if (spec%kind == key_logical) then
            text = json_bool(text == '.true.')
        end if
    end function default_json

    pure function bound_json(spec, x, unbounded) result(text)
        type(input_key_t), intent(in) :: spec
        real(wp), intent(in) :: x, unbounded
        character(len=:), allocatable :: text

        if (x == unbounded) then
            text = 'null'
        else if (spec%kind == key_integer) then
            text = fmt_int8(nint(x, i8))
        else
            text = exact(x)
        end if
    end function bound_json

    !> "a b c" -> ["a", "b", "c"] (a leading blank: '' is allowed too); null when empty.
    pure function choices_json(choices) result(text)
        character(len=*), intent(in) :: choices
        character(len=:), allocatable :: text, rest
        integer :: blank

        if (len_trim(choices) == 0) then
            text = 'null'
            return
        end if
        text = '['
        if (choices(1:1) == ' ') text = text//'""'
        rest = trim(adjustl(choices))
        do while (len(rest) > 0)
            blank = index(rest, ' ')
            if (blank == 0) blank = len(rest) + 1
            if (len(text) > 1) text = text//', '
            text = text//quoted(rest(:blank - 1))
            if (blank > len(rest)) exit
            rest = trim(adjustl(rest(blank + 1:)))
        end do
        text = text//']'
    end function choices_json

    !> "a b" -> 'a', 'b' (as the messages list them).
    pure function choices_listed(choices) result(text)
        character(len=*), intent(in) :: choices
        character(len=:), allocatable :: text
        integer :: j

        text = choices_json(choices)
        text = text(2:len(text) - 1)
        do j = 1, len(text)
            if (text(j:j) == '"') text(j:j) = "'"
        end do
    end function choices_listed

    pure function json_bool(flag) result(text)
        logical, intent(in) :: flag
        character(len=:), allocatable :: text

        text = trim(merge('true ', 'false', flag))
    end function json_bool

    !> A JSON string of the trimmed text (quotes and backslashes escaped).
    pure function quoted(raw) result(text)
        character(len=*), intent(in) :: raw
        character(len=:), allocatable :: text
        integer :: j

        text = '"'
        do j = 1, len_trim(raw)
            if (raw(j:j) == '"' .or. raw(j:j) == '\') text = text//'\'
            text = text//raw(j:j)
        end do
        text = text//'"'
    end function quoted

end module chain_inputs
