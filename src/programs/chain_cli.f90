!> The command line both programs share:
!>   [--quiet] [--set group.key=value]... [-o file.h5] [--overwrite] [--check] input.nml
!> plus `--help`, `--version` and `--schema` (the input and output tables as JSON). `--set`
!> (repeatable), `-o` and `--overwrite` become overrides of the input's text (chain_namelist),
!> applied in the order given; `--check` validates the input and prints it resolved, running
!> nothing. Returns what was asked for;
!> the programs print and exit (library code never stops; `exit_now` is the programs' way
!> out after an error). Infrastructure, no model section.
module chain_cli
    use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
    use, intrinsic :: iso_c_binding, only: c_int
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_overflow, &
                                             ieee_get_halting_mode, ieee_set_halting_mode, &
                                             ieee_set_flag
    use chain_kinds, only: wp
    use chain_file_schema, only: output_schema_json
    use chain_inputs, only: input_schema_json
    implicit none
    private
    public :: cli_t, parse_command_line, parse_arguments, exit_now, seconds_from_environment
    public :: cli_run, cli_help, cli_version, cli_usage, cli_error, cli_schema, schema_json

    integer, parameter :: cli_run = 0     !! run the input file
    integer, parameter :: cli_help = 1    !! print the usage and exit 0
    integer, parameter :: cli_version = 2 !! print the version and exit 0
    integer, parameter :: cli_usage = 3   !! no input given: print the usage, exit 2
    integer, parameter :: cli_error = 4   !! print `message` and exit 1
    integer, parameter :: cli_schema = 5  !! print schema_json() and exit 0
    integer, parameter :: max_override = 4096 !! longest `--set` value

    type :: cli_t
        integer :: action = cli_run
        character(len=:), allocatable :: input   !! the namelist file
        logical :: quiet = .false.                !! no progress lines
        logical :: check = .false.                !! validate and print, run nothing
        !> `group.key=value` overrides of the input, in order
        character(len=max_override), allocatable :: overrides(:)
        character(len=:), allocatable :: message !! with cli_error: what is wrong
    end type cli_t

contains

    !> What `--schema` prints: the schema version, the input table and the output table
    !> (chain_file_schema), one JSON object.
    function schema_json() result(json)
        character(len=:), allocatable :: json

        json = '{"schema_version": 1,'//new_line('a')// &
               '"inputs": '//input_schema_json()//','//new_line('a')// &
               '"outputs": '//output_schema_json()//'}'
    end function schema_json

    !> For the programs only: flush what was written and end the process with `code` at once,
    !> without the exit handlers. After a failed write (a full disk) HDF5's own handler,
    !> closing the file that could not be closed, crashed (SIGSEGV, exit 139, the message
    !> lost with stderr in a file). A partial file is deleted before (output_abort).
    subroutine exit_now(code)
        integer, intent(in) :: code
        interface
            subroutine c_exit(status) bind(C, name='_exit')
                import :: c_int
                integer(c_int), value :: status
            end subroutine c_exit
        end interface

        flush (output_unit)
        flush (error_unit)
        call c_exit(int(code, c_int))
    end subroutine exit_now

    !> The environment variable `name` as a number of seconds in [0, 1e6], or `default` when
    !> it is unset or empty; `message` is allocated when it is anything else.
    subroutine seconds_from_environment(name, default, seconds, message)
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: default
        real(wp), intent(out) :: seconds
        character(len=:), allocatable, intent(out) :: message
        character(len=64) :: text
        integer :: length, status, ios
        logical :: halting

        seconds = default
        call get_environment_variable(name, text, length, status)
        if (status == 1 .or. length == 0) return
        ! a number beyond double precision (1e400) reads as an overflow, which the
        ! runtime-checked build would trap: read without halting, and refuse what is not finite
        call ieee_get_halting_mode(ieee_overflow, halting)
        call ieee_set_halting_mode(ieee_overflow, .false.)
        read (text, *, iostat=ios) seconds
        call ieee_set_flag(ieee_overflow, .false.)
        call ieee_set_halting_mode(ieee_overflow, halting)
        if (status == 0 .and. ios == 0) then
            ! (a NaN compared would trap there too)
            if (ieee_is_finite(seconds)) then
                if (seconds >= 0 .and. seconds <= 1.0e6_wp) return
            end if
        end if
        message = name//' = '//trim(text)//' is not a number of seconds in [0, 1e6]'
    end subroutine seconds_from_environment

    !> The program's own arguments.
    function parse_command_line() result(cli)
        type(cli_t) :: cli
        character(len=:), allocatable :: args(:)
        integer :: j, length, longest

        longest = 1
        do j = 1, command_argument_count()
            call get_command_argument(j, length=length)
            longest = max(longest, length)
        end do
        allocate (character(len=longest) :: args(command_argument_count()))
        do j = 1, size(args)
            call get_command_argument(j, args(j))
        end do
        cli = parse_arguments(args)
    end function parse_command_line

    !> Arguments as given (trailing blanks are padding).
    pure function parse_arguments(args) result(cli)
        character(len=*), intent(in) :: args(:)
        type(cli_t) :: cli
        integer :: j
        character(len=:), allocatable :: arg

        cli%input = ''
        allocate (cli%overrides(0))
        j = 0
        do while (j < size(args))
            j = j + 1
            arg = trim(args(j))
            select case (arg)
            case ('-q', '--quiet')
                cli%quiet = .true.
            case ('-h', '--help')
                cli%action = cli_help
                return
            case ('--version')
                cli%action = cli_version
                return
            case ('--schema')
                cli%action = cli_schema
                return
            case ('--check')
                cli%check = .true.
            case ('--overwrite')
                call add_override(cli, 'output.overwrite=.true.')
            case ('--set', '-o', '--output')
                if (j == size(args)) then
                    call refuse(cli, arg//" needs a value (see --help)")
                    return
                end if
                j = j + 1
                if (arg == '--set') then
                    call add_override(cli, trim(args(j)))
                else
                    call add_override(cli, 'output.file='//quoted(trim(args(j))))
                end if
            case default
                if (arg(1:min(1, len(arg))) == '-') then
                    call refuse(cli, "unknown option '"//arg//"' (see --help)")
                    return
                end if
                if (len(cli%input) > 0) then
                    call refuse(cli, "give one input file, not '"//cli%input//"' and '"// &
                                arg//"'")
                    return
                end if
                cli%input = arg
            end select
            if (cli%action == cli_error) return
        end do
        if (len(cli%input) == 0) cli%action = cli_usage
    end function parse_arguments

    pure subroutine add_override(cli, spec)
        type(cli_t), intent(inout) :: cli
        character(len=*), intent(in) :: spec

        if (len(spec) > max_override) then
            call refuse(cli, "--set "//spec(:40)//"...: longer than "// &
                        "4096 characters; put it in the input file")
            return
        end if
        cli%overrides = [character(len=max_override) :: cli%overrides, spec]
    end subroutine add_override

    !> A file name as a namelist string: in quotes that it does not contain.
    pure function quoted(name) result(text)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: text

        if (index(name, "'") == 0) then
            text = "'"//name//"'"
        else
            text = '"'//name//'"'
        end if
    end function quoted

    pure subroutine refuse(cli, message)
        type(cli_t), intent(inout) :: cli
        character(len=*), intent(in) :: message

        cli%action = cli_error
        cli%message = message
    end subroutine refuse

end module chain_cli
