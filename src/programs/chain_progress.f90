!> When and how a long run shows its progress: one line that updates in place on a terminal
!> (at most four times a second), and on a log file or pipe a line at every tenth of the work
!> or every minute, whichever comes first. Nothing is shown in a run's first two seconds (a
!> program may choose another delay: progress_quiet_start is the default). The library only
!> decides and formats; the programs write. Infrastructure, no model section.
module chain_progress
    use, intrinsic :: iso_c_binding, only: c_int
    use chain_kinds, only: wp, i8
    use chain_error, only: fmt_int8
    implicit none
    private
    public :: progress_t, progress_start, progress_update, progress_within, stderr_is_terminal
    public :: progress_quiet_start

    real(wp), parameter :: progress_quiet_start = 2 !! seconds before anything is shown
    real(wp), parameter :: terminal_every = 0.25_wp
    real(wp), parameter :: log_every = 60

    type :: progress_t
        logical :: terminal = .false.        !! update one line in place
        character(len=:), allocatable :: label !! what is counted: 'cycle', 'point'
        real(wp) :: start = 0, last = -huge(1.0_wp) !! seconds: start, last line shown
        real(wp) :: quiet_start = progress_quiet_start !! seconds before anything is shown
        integer(i8) :: done_at_start = -1    !! work already done when the count started
        integer :: tenths_shown = 0          !! (log) tenths of the work reported
        logical :: line_open = .false.       !! (terminal) a line without its newline
        integer(i8) :: done = 0, total = 0   !! the last update's count
        real(wp) :: done_time = 0            !! seconds: when it came
    end type progress_t

    interface
        function c_isatty(fd) bind(C, name='isatty') result(yes)
            import :: c_int
            integer(c_int), value :: fd
            integer(c_int) :: yes
        end function c_isatty
    end interface

contains

    !> Is standard error a terminal?
    logical function stderr_is_terminal()
        stderr_is_terminal = c_isatty(2_c_int) == 1
    end function stderr_is_terminal

    !> A count starting at `now`; nothing is shown before `quiet_start` seconds have passed
    !> (default progress_quiet_start; with 0 the first update is shown, then as usual).
    pure function progress_start(label, terminal, now, quiet_start) result(p)
        character(len=*), intent(in) :: label
        logical, intent(in) :: terminal
        real(wp), intent(in) :: now !! seconds on any clock
        real(wp), intent(in), optional :: quiet_start
        type(progress_t) :: p

        p%label = label
        p%terminal = terminal
        p%start = now
        p%done_time = now
        if (present(quiet_start)) p%quiet_start = quiet_start
    end function progress_start

    !> After `done` of `total` at time `now`: `text` is what to write now ('' for nothing);
    !> on a terminal it starts with a carriage return and has no newline (`p%line_open`), and
    !> the last update (done == total) ends with one.
    pure subroutine progress_update(p, done, total, now, text)
        type(progress_t), intent(inout) :: p
        integer(i8), intent(in) :: done, total
        real(wp), intent(in) :: now
        character(len=:), allocatable, intent(out) :: text
        real(wp) :: elapsed
        integer :: tenths
        logical :: show

        text = ''
        if (p%done_at_start < 0) p%done_at_start = done - 1
        p%done = done
        p%total = total
        p%done_time = now
        elapsed = now - p%start
        if (elapsed < p%quiet_start) return
        tenths = int((10*done)/max(total, 1_i8))
        if (p%terminal) then
            show = now - p%last >= terminal_every .or. done == total
        else
            show = tenths > p%tenths_shown .or. now - p%last >= log_every .or. done == total
        end if
        if (.not. show) return
        p%last = now
        p%tenths_shown = tenths
        text = progress_text(p, done, total, elapsed)
        if (p%terminal) then
            text = achar(13)//text
            p%line_open = done < total
            if (done == total) text = text//new_line('a')
        else
            text = text//new_line('a')
        end if
    end subroutine progress_update

    !> Within the unit of work after the last update, which is taking long (a drive cycle of
    !> millions of events): `events` done in it so far, at time `now`. Shown like updates
    !> (on a terminal at most four times a second; on a log file or pipe the first at once,
    !> then at most once a minute), so that even a unit of minutes shows it is moving.
    pure subroutine progress_within(p, events, now, text)
        type(progress_t), intent(inout) :: p
        integer(i8), intent(in) :: events
        real(wp), intent(in) :: now
        character(len=:), allocatable, intent(out) :: text
        character(len=:), allocatable :: unit

        text = ''
        if (now - p%start < p%quiet_start) return
        if (p%terminal .and. now - p%last < terminal_every) return
        if (.not. p%terminal .and. now - p%last < log_every .and. p%last > p%start) return
        p%last = now
        if (p%total > 0) then
            unit = p%label//' '//fmt_int8(p%done + 1)//' / '//fmt_int8(p%total)
        else
            unit = 'the first '//p%label
        end if
        text = 'impactchain: '//unit//' under way, '//formatted('(es9.2)', real(events, wp))// &
               ' events so far ('//formatted('(es9.2)', events/max(now - p%done_time, &
                                                                  1.0e-9_wp))//' events/s)'
        if (p%terminal) then
            text = achar(13)//text//'    '
            p%line_open = .true.
        else
            text = text//new_line('a')
        end if
    end subroutine progress_within

    pure function progress_text(p, done, total, elapsed) result(text)
        type(progress_t), intent(in) :: p
        integer(i8), intent(in) :: done, total
        real(wp), intent(in) :: elapsed
        character(len=:), allocatable :: text
        real(wp) :: rate

        rate = (done - p%done_at_start)/max(elapsed, 1.0e-9_wp)
        text = 'impactchain: '//p%label//' '//fmt_int8(done)//' / '//fmt_int8(total)//' ('// &
               formatted('(f0.1)', 100*real(done, wp)/max(total, 1_i8))//' %), '// &
               formatted('(es9.2)', rate)//' '//p%label//'s/s, '// &
               formatted('(f0.1)', (total - done)/max(rate, 1.0e-9_wp))//' s left'
        if (p%terminal) text = text//'    ' ! blanks over the end of a longer last line
    end function progress_text

    !> `value` in `format`, without blanks around.
    pure function formatted(format, value) result(text)
        character(len=*), intent(in) :: format
        real(wp), intent(in) :: value
        character(len=:), allocatable :: text
        character(len=40) :: buf

        write (buf, format) value
        text = trim(adjustl(buf))
        if (text(1:1) == '.') text = '0'//text
    end function formatted

end module chain_progress
