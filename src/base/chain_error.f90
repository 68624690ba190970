!> Error reporting without `stop`: library procedures return an allocated `error_t` whose
!> message reads "where: what (offending value, allowed range)"; only app/ turns it into an
!> exit code. Also the formatting of numbers inside such messages.
!> Infrastructure, no model section.
module chain_error
    use chain_kinds, only: wp, i8
    implicit none
    private
    public :: error_t, set_error, fmt_real, fmt_int, fmt_int8

    type :: error_t
        character(len=:), allocatable :: message
    end type error_t

contains

    !> Allocate `err` with `message`.
    pure subroutine set_error(err, message)
        type(error_t), allocatable, intent(out) :: err
        character(len=*), intent(in) :: message
        allocate (err)
        err%message = message
    end subroutine set_error

    !> Numbers as message text.
    pure function fmt_real(x) result(s)
        real(wp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=40) :: buf

        write (buf, '(g0.8)') x
        s = trim(adjustl(buf))
    end function fmt_real

    pure function fmt_int(i) result(s)
        integer, intent(in) :: i
        character(len=:), allocatable :: s
        character(len=24) :: buf

        write (buf, '(i0)') i
        s = trim(buf)
    end function fmt_int

    pure function fmt_int8(i) result(s)
        integer(i8), intent(in) :: i
        character(len=:), allocatable :: s
        character(len=24) :: buf

        write (buf, '(i0)') i
        s = trim(buf)
    end function fmt_int8

end module chain_error
