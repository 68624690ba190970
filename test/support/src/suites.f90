!> Named test suites, run one at a time or all together. fpm hands the same arguments to every
!> test program, so `fpm test -- <suite> [<suite> ...]` reaches each of them:
!>
!>     fpm test                      every suite of every program
!>     fpm test -- lyapunov sweep    only the named suites, in each program that has them
!>     fpm test -- --list            the suites and the program of each, nothing run
!>
!> Each program checks the names against `suite_names`, the one list of the suites of every
!> program: a name that belongs to another program is no error, and a program none of whose
!> suites is named runs nothing and says so in its last line. An unknown name is an error that
!> lists the valid ones (exit 2). The last line of a run is "N passed, M failed"; any failed
!> check makes the exit status 1.
!> (Infrastructure of the tests: no section of docs/model.md.)
module suites
    use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
    use testing, only: tally_t
    implicit none
    private
    public :: suite_runner_t, suite_names

    !> Every suite of every test program (at most 10 characters each). A new suite is added
    !> here and run by its program with `runner%run(name, ...)`, which refuses a name missing
    !> from this list.
    character(len=*), parameter :: suite_names(*) = [character(len=10) :: &
        'flow', 'gaps', 'impact', &                            ! test/model/model_tests.f90
        'queue', 'engine', 'corners', 'invariants', &          ! test/engine/engine_tests.f90
        'lyapunov', 'clv', &                                   ! test/spectra/spectra_tests.f90
        'orbit', 'branch', 'switch', 'buddux', 'graze', 'curve', & ! test/measure/measure_tests.f90
        'corner', 'bpcurve', 'nscurve', 'codim2', &            ! test/measure/measure_tests.f90
        'hdf5', 'sweep', 'checkpoint', 'census', 'taskfarm'] ! test/runs/runs_tests.f90

    abstract interface
        !> The checks of one suite, added to the tally.
        subroutine suite_checks(t)
            import :: tally_t
            type(tally_t), intent(inout) :: t
        end subroutine suite_checks
    end interface

    !> The suites asked for on the command line, and the tally of those run so far.
    type :: suite_runner_t
        private
        character(len=:), allocatable :: program !! this program's name, for its messages
        character(len=:), allocatable :: own !! this program's suites, as they are met
        logical :: listing = .false. !! --list: name the suites, run none
        logical :: named(size(suite_names)) = .true. !! every suite when none is named
        integer :: ran = 0
        type(tally_t) :: t
    contains
        procedure :: start
        procedure :: run
        procedure :: finish
    end type suite_runner_t

contains

    !> Read the command line: suite names and `--list`. Stops with exit status 2 at an
    !> unknown argument.
    subroutine start(self)
        class(suite_runner_t), intent(out) :: self
        character(len=:), allocatable :: arg
        integer :: i, k

        arg = argument(0)
        self%program = arg(index(arg, '/', back=.true.) + 1:)
        self%own = ''
        if (command_argument_count() == 0) return
        self%named = .false.
        do i = 1, command_argument_count()
            arg = argument(i)
            if (arg == '--list') then
                self%listing = .true.
                cycle
            end if
            k = findloc(suite_names, arg, 1)
            if (k == 0) then
                write (error_unit, '(a)') self%program//": unknown test suite '"//arg// &
                    "'; the suites are:"//joined(suite_names)//" (or --list to see where "// &
                    "each one is)"
                stop 2, quiet=.true.
            end if
            self%named(k) = .true.
        end do
    end subroutine start

    !> Run the suite `name` if it was asked for and print its count of checks; with --list,
    !> print its name and this program's instead.
    subroutine run(self, name, checks)
        class(suite_runner_t), intent(inout) :: self
        character(len=*), intent(in) :: name
        procedure(suite_checks) :: checks
        type(tally_t) :: before
        integer :: k

        k = findloc(suite_names, name, 1)
        if (k == 0) then
            write (error_unit, '(a)') self%program//": suite '"//name// &
                "' is missing from suite_names in test/support/src/suites.f90"
            stop 2, quiet=.true.
        end if
        self%own = self%own//' '//name
        if (self%listing) then
            write (output_unit, '(a)') suite_names(k)//'  '//self%program
            return
        end if
        if (.not. self%named(k)) return
        before = self%t
        call checks(self%t)
        self%ran = self%ran + 1
        write (output_unit, '(a,i0,a,i0,a)') '  '//name//' checks: ', &
            self%t%passed - before%passed, ' passed, ', self%t%failed - before%failed, ' failed'
    end subroutine run

    !> The last line: "N passed, M failed" (exit status 1 if M > 0), also when none of this
    !> program's suites was named; nothing with --list.
    subroutine finish(self)
        class(suite_runner_t), intent(in) :: self

        if (self%listing) return
        if (self%ran == 0) then
            write (output_unit, '(a)') '0 passed, 0 failed: none of the named suites is in '// &
                self%program//' (its suites:'//self%own//')'
            return
        end if
        write (output_unit, '(i0,a,i0,a)') self%t%passed, ' passed, ', self%t%failed, ' failed'
        if (self%t%failed > 0) error stop 1
    end subroutine finish

    function argument(i) result(arg)
        integer, intent(in) :: i
        character(len=:), allocatable :: arg
        integer :: length

        call get_command_argument(i, length=length)
        allocate (character(len=length) :: arg)
        if (length > 0) call get_command_argument(i, arg)
    end function argument

    pure function joined(names) result(text)
        character(len=*), intent(in) :: names(:)
        character(len=:), allocatable :: text
        integer :: i

        text = ''
        do i = 1, size(names)
            text = text//' '//trim(names(i))
        end do
    end function joined

end module suites
