!> The command line's monitor: progress on standard error (chain_progress decides when and
!> formats; this writes) and a stop after SIGINT / SIGTERM (chain_interrupt).
!> IMPACTCHAIN_PROGRESS_AFTER (seconds) replaces the two quiet seconds before the first line:
!> with 0 a run shows its first unit of work, which lets the tests see progress whatever the
!> speed of the machine.
module stderr_monitor
    use, intrinsic :: iso_fortran_env, only: error_unit, int64
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_overflow, &
                                             ieee_get_halting_mode, ieee_set_halting_mode, &
                                             ieee_set_flag
    use impactchain, only: wp, i8, monitor_t, interrupted, progress_t, progress_start, &
                           progress_update, stderr_is_terminal, stage_name, &
                           progress_quiet_start
    implicit none
    private
    public :: stderr_monitor_t, close_progress, progress_after_from_environment

    type, extends(monitor_t) :: stderr_monitor_t
        logical :: quiet = .false.     !! no progress, only the signal check
        integer :: stage = 0           !! what the line counts now (chain_monitor's stages)
        real(wp) :: after = progress_quiet_start !! seconds before the first line
        type(progress_t) :: shown
    contains
        procedure :: keep_going => stderr_keep_going
    end type stderr_monitor_t

contains

    logical function stderr_keep_going(monitor, stage, done, total) result(keep_going)
        class(stderr_monitor_t), intent(inout) :: monitor
        integer, intent(in) :: stage
        integer(i8), intent(in) :: done, total
        character(len=:), allocatable :: text

        keep_going = .not. interrupted()
        if (monitor%quiet) return
        if (stage /= monitor%stage) then ! a new count (the records after the transient)
            call close_progress(monitor)
            monitor%stage = stage
            monitor%shown = progress_start(stage_name(stage), stderr_is_terminal(), seconds(), &
                                           monitor%after)
        end if
        call progress_update(monitor%shown, done, total, seconds(), text)
        if (len(text) == 0) return
        write (error_unit, '(a)', advance='no') text
        flush (error_unit)
    end function stderr_keep_going

    !> A progress line left open on a terminal gets its newline before anything else is said.
    subroutine close_progress(monitor)
        type(stderr_monitor_t), intent(inout) :: monitor

        if (monitor%shown%line_open) write (error_unit, '(a)') ''
        monitor%shown%line_open = .false.
    end subroutine close_progress

    !> The seconds before the first progress line: IMPACTCHAIN_PROGRESS_AFTER when set, else
    !> the library's default. `message` is allocated when the variable is not a number of
    !> seconds in [0, 1e6].
    subroutine progress_after_from_environment(after, message)
        real(wp), intent(out) :: after
        character(len=:), allocatable, intent(out) :: message
        character(len=64) :: text
        integer :: length, status, ios
        logical :: halting

        after = progress_quiet_start
        call get_environment_variable('IMPACTCHAIN_PROGRESS_AFTER', text, length, status)
        if (status == 1 .or. length == 0) return
        ! a number beyond double precision (1e400) reads as an overflow, which the
        ! runtime-checked build would trap: read without halting, and refuse what is not finite
        call ieee_get_halting_mode(ieee_overflow, halting)
        call ieee_set_halting_mode(ieee_overflow, .false.)
        read (text, *, iostat=ios) after
        call ieee_set_flag(ieee_overflow, .false.)
        call ieee_set_halting_mode(ieee_overflow, halting)
        if (status == 0 .and. ios == 0) then
            ! (a NaN compared would trap there too)
            if (ieee_is_finite(after)) then
                if (after >= 0 .and. after <= 1.0e6_wp) return
            end if
        end if
        message = 'IMPACTCHAIN_PROGRESS_AFTER = '//trim(text)// &
                  ' is not a number of seconds in [0, 1e6]'
    end subroutine progress_after_from_environment

    !> Seconds since an arbitrary start.
    real(wp) function seconds()
        integer(int64) :: now, rate

        call system_clock(now, rate)
        seconds = real(now, wp)/rate
    end function seconds

end module stderr_monitor
