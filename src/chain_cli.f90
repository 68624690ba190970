!> The command line both programs share: `[--quiet] input.nml`, plus `--help` and
!> `--version`. Returns what was asked for; the programs print and exit (library code never
!> stops). Infrastructure, no model section.
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

    type :: cli_t
        integer :: action = cli_run
        character(len=:), allocatable :: input   !! the namelist file
        logical :: quiet = .false.                !! no progress lines
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
        do j = 1, size(args)
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
        end do
        if (len(cli%input) == 0) cli%action = cli_usage
    end function parse_arguments

    pure subroutine refuse(cli, message)
        type(cli_t), intent(inout) :: cli
        character(len=*), intent(in) :: message

        cli%action = cli_error
        cli%message = message
    end subroutine refuse

end module chain_cli
