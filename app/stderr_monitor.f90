!> The command line's monitor: progress on standard error (chain_progress decides when and
!> formats; this writes) and a stop after SIGINT / SIGTERM (chain_interrupt).
!> IMPACTCHAIN_PROGRESS_AFTER (seconds) replaces the two quiet seconds before the first line:
!> with 0 a run shows its first unit of work, which lets the tests see progress whatever the
!> speed of the machine.
module stderr_monitor
    use, intrinsic :: iso_fortran_env, only: error_unit, int64
    use impactchain, only: wp, i8, monitor_t, stage_name, stage_events, stage_records
    use impactchain_drivers, only: interrupted, progress_t, progress_start, progress_update, &
                                   progress_within, stderr_is_terminal, progress_quiet_start, &
                                   seconds_from_environment
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
        if (stage == stage_events) then ! within the unit after the last count
            if (monitor%stage == 0) call start_count(stage_records)
            call progress_within(monitor%shown, done, seconds(), text)
            call show(text)
            return
        end if
        if (stage /= monitor%stage) then ! a new count (the records after the transient)
            call close_progress(monitor)
            call start_count(stage)
        end if
        call progress_update(monitor%shown, done, total, seconds(), text)
        call show(text)

    contains

        subroutine start_count(counted)
            integer, intent(in) :: counted

            monitor%stage = counted
            monitor%shown = progress_start(stage_name(counted), stderr_is_terminal(), &
                                           seconds(), monitor%after)
        end subroutine start_count

        subroutine show(line)
            character(len=*), intent(in) :: line

            if (len(line) == 0) return
            write (error_unit, '(a)', advance='no') line
            flush (error_unit)
        end subroutine show

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

        call seconds_from_environment('IMPACTCHAIN_PROGRESS_AFTER', progress_quiet_start, &
                                      after, message)
    end subroutine progress_after_from_environment

    !> Seconds since an arbitrary start.
    real(wp) function seconds()
        integer(int64) :: now, rate

        call system_clock(now, rate)
        seconds = real(now, wp)/rate
    end function seconds

end module stderr_monitor
