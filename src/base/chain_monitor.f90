!> Watching a long computation from outside: after each unit of work (a transient cycle, a
!> strobe record, a sweep point, a census sample) the library tells a monitor how far it is,
!> and the monitor may ask it to stop. The command line shows progress and stops on a signal,
!> the Python layer shares a flag with the interpreter (Ctrl-C, progress bars), the MPI driver
!> ends its rounds.
!> Infrastructure, no model section.
!>
!> A monitor is an object, not a procedure argument: a procedure that needs the caller's
!> variables would be an internal procedure, and passing one needs a trampoline on an
!> executable stack, which a Python extension must not require.
module chain_monitor
    use, intrinsic :: iso_fortran_env, only: int64
    use chain_kinds, only: i8
    use chain_interrupt, only: interrupted
    use chain_error, only: error_t
    implicit none
    private
    public :: monitor_t, signal_monitor_t, saving_monitor_t, checkpoint_every
    public :: stage_transient, stage_records, stage_points, stage_samples, stage_backward
    public :: stage_events, events_per_poll
    public :: stage_name

    integer, parameter :: stage_transient = 1 !! drive cycles of the transient (nothing recorded)
    integer, parameter :: stage_records = 2   !! strobe records of a run
    integer, parameter :: stage_points = 3    !! finished points of a sweep
    integer, parameter :: stage_samples = 4   !! finished samples of a census (all its points)
    integer, parameter :: stage_backward = 5  !! records of the covariant vectors' backward pass
    !> events within one stretch of a drive cycle (no total: told every events_per_poll
    !> events, so that a cycle holding millions still shows progress and stops when asked)
    integer, parameter :: stage_events = 6
    integer, parameter :: events_per_poll = 4096

    type, abstract :: monitor_t
    contains
        procedure(keep_going_i), deferred :: keep_going
    end type monitor_t

    abstract interface
        !> `done` of `total` units of `stage` are finished; .false. asks the work to stop
        !> there (what a stop means is the caller's: see record_cycles, run_sweep).
        logical function keep_going_i(monitor, stage, done, total)
            import :: monitor_t, i8
            class(monitor_t), intent(inout) :: monitor
            integer, intent(in) :: stage
            integer(i8), intent(in) :: done, total
        end function keep_going_i
    end interface

    !> Keeps going until SIGINT / SIGTERM (once chain_interrupt catches them) and, when
    !> `deadline` is set, until the system clock passes it (in system_clock counts).
    type, extends(monitor_t) :: signal_monitor_t
        integer(int64) :: deadline = huge(1_int64)
    contains
        procedure :: keep_going => signal_keep_going
    end type signal_monitor_t

    !> Seconds between the checkpoints of a long computation (sweeps, censuses).
    integer, parameter :: checkpoint_every = 10

    !> Passes everything on to the caller's monitor (`outer`, if any) and saves the work done
    !> every `checkpoint_every` seconds (`save`, which the computation defines: what it saves
    !> and where). It is told where the work is consistent (a sweep's or census's critical
    !> section). A save that fails stops the work with that error (`err`).
    type, abstract, extends(monitor_t) :: saving_monitor_t
        class(monitor_t), pointer :: outer => null()
        integer(i8) :: clock_last = 0, clock_rate = 1  !! system_clock counts
        type(error_t), allocatable :: err              !! a save that failed
    contains
        procedure :: keep_going => saving_keep_going
        procedure(save_i), deferred :: save
    end type saving_monitor_t

    abstract interface
        !> Save the work done so far; a failure is set in monitor%err.
        subroutine save_i(monitor)
            import :: saving_monitor_t
            class(saving_monitor_t), intent(inout) :: monitor
        end subroutine save_i
    end interface

contains

    !> The caller's answer; and a save when checkpoint_every seconds have passed since the
    !> last (none after a failed one).
    logical function saving_keep_going(monitor, stage, done, total) result(keep_going)
        class(saving_monitor_t), intent(inout) :: monitor
        integer, intent(in) :: stage
        integer(i8), intent(in) :: done, total
        integer(i8) :: now

        keep_going = .true.
        if (associated(monitor%outer)) keep_going = monitor%outer%keep_going(stage, done, total)
        call system_clock(now)
        if (now - monitor%clock_last < checkpoint_every*monitor%clock_rate .or. &
            allocated(monitor%err)) return
        call monitor%save()
        monitor%clock_last = now
        if (allocated(monitor%err)) keep_going = .false.
    end function saving_keep_going

    !> (Whatever the stage and the count.)
    logical function signal_keep_going(monitor, stage, done, total) result(keep_going)
        class(signal_monitor_t), intent(inout) :: monitor
        integer, intent(in) :: stage
        integer(i8), intent(in) :: done, total
        integer(int64) :: now

        keep_going = .not. interrupted()
        if (.not. keep_going .or. monitor%deadline == huge(1_int64)) return
        call system_clock(now)
        keep_going = now < monitor%deadline
    end function signal_keep_going

    !> What a stage counts, for progress lines: 'transient cycle', 'cycle', 'point', 'sample',
    !> 'record (backward pass)'.
    pure function stage_name(stage) result(name)
        integer, intent(in) :: stage
        character(len=:), allocatable :: name

        select case (stage)
        case (stage_transient)
            name = 'transient cycle'
        case (stage_records)
            name = 'cycle'
        case (stage_samples)
            name = 'sample'
        case (stage_backward)
            name = 'record (backward pass)'
        case (stage_events)
            name = 'event'
        case default
            name = 'point'
        end select
    end function stage_name

end module chain_monitor
