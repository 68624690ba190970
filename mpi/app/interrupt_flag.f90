!> SIGINT / SIGTERM (Ctrl-C, `scancel`, a Slurm time limit) ask the MPI sweep to stop at the
!> next finished point and write its checkpoint. A signal handler can only talk through a flag
!> that outlives every call, hence module state; the same few lines as in app/main.f90 (an app
!> module is not part of the library, so it cannot be shared).
module interrupt_flag
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

    subroutine catch_interrupts()
        type(c_funptr) :: previous

        previous = c_signal(sigint, c_funloc(on_signal))
        previous = c_signal(sigterm, c_funloc(on_signal))
    end subroutine catch_interrupts

    logical function interrupted()
        interrupted = stop_requested
    end function interrupted

    subroutine on_signal(signum) bind(C)
        integer(c_int), value :: signum

        if (signum > 0) stop_requested = .true.
    end subroutine on_signal

end module interrupt_flag
