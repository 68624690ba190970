!> SIGINT / SIGTERM as a request to stop: a run or sweep asked to stop ends at its next record
!> or point, writes what it has (marked complete = 0, or a checkpoint) and the same command
!> continues it. Used by both command lines (the simulator and the MPI sweep driver).
!> Infrastructure, no model section.
!>
!> A signal handler can only talk through a flag that outlives every call: this is the one
!> piece of module state in the project, set only by the handler and read by `interrupted`.
module chain_interrupt
    use, intrinsic :: iso_c_binding, only: c_int, c_funptr, c_funloc
    implicit none
    private
    public :: catch_interrupts, interrupted

    integer(c_int), parameter :: sigint = 2, sigterm = 15
    logical, volatile :: stop_requested = .false.

    interface
        function c_signal(signum, handler) bind(C, name='signal') result(previous)
            import :: c_int, c_funptr
            integer(c_int), value :: signum
            type(c_funptr), value :: handler
            type(c_funptr) :: previous
        end function c_signal
    end interface

contains

    !> From now on SIGINT and SIGTERM set the flag instead of ending the process.
    subroutine catch_interrupts()
        type(c_funptr) :: previous

        previous = c_signal(sigint, c_funloc(on_signal))
        previous = c_signal(sigterm, c_funloc(on_signal))
    end subroutine catch_interrupts

    !> Has a stop been requested?
    logical function interrupted()
        interrupted = stop_requested
    end function interrupted

    subroutine on_signal(signum) bind(C)
        integer(c_int), value :: signum

        if (signum > 0) stop_requested = .true.
    end subroutine on_signal

end module chain_interrupt
