!> The command line both programs share:
!>   [--quiet] [--set group.key=value]... [-o file.h5] [--overwrite] [--check] input.nml
!> plus `--help` and `--version`. `--set` (repeatable), `-o` and `--overwrite` become
!> overrides of the input's text (chain_namelist), applied in the order given; `--check`
!> validates the input and prints it resolved, running nothing. Returns what was asked for;
!> the programs print and exit (library code never stops). Infrastructure, no model section.
module chain_cli
    implicit none
    private
    public :: cli_t, parse_command_line, parse_arguments
    public :: cli_run, cli_help, cli_version, cli_usage, cli_error

    integer, parameter :: cli_run = 0     !! run the input file
    integer, parameter :: cli_help = 1    !! print the usage and exit 0
    integer, parameter :: cli_version = 2 !! print the version and exit 0
    integer, parameter :: cli_usage = 3   !! no input given: print the usage, exit 2
    integer, parameter :: cli_error = 4   !! print `message` and exit 1
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
