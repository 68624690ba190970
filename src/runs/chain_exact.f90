!> Values as namelist text that reads back to the same value: reals in the fewest significant
!> digits that do (2.2, 0.05, 1e-09), lists of them, logicals, strings. Used by the echo of the
!> configuration and by the input schema's JSON. Infrastructure, no model section.
module chain_exact
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use chain_kinds, only: wp
    use chain_error, only: fmt_int
    implicit none
    private
    public :: exact, exact_list, fmt_logical, namelist_string

    !> es30.(d - 1)e4 for d significant digits (at least 2 written).
    character(len=*), parameter :: digit_formats(17) = [character(len=11) :: &
        '(es30.1e4)', '(es30.1e4)', '(es30.2e4)', '(es30.3e4)', '(es30.4e4)', '(es30.5e4)', &
        '(es30.6e4)', '(es30.7e4)', '(es30.8e4)', '(es30.9e4)', '(es30.10e4)', &
        '(es30.11e4)', '(es30.12e4)', '(es30.13e4)', '(es30.14e4)', '(es30.15e4)', &
        '(es30.16e4)']

contains

    !> A real in the fewest significant digits that read back to the same value: positional
    !> for 1e-4 <= |x| < 1e15 (2.2, 0.05, 1000.0), else with an exponent (1e-09).
    pure function exact(x) result(text)
        real(wp), intent(in) :: x
        character(len=:), allocatable :: text
        character(len=40) :: buf
        character(len=:), allocatable :: digits
        real(wp) :: back
        integer :: d, ios, e, point

        if (x == 0 .or. .not. ieee_is_finite(x)) then
            write (buf, '(g0)') x
            text = trim(adjustl(buf))
            if (x == 0) text = merge('-0.0', ' 0.0', sign(1.0_wp, x) < 0)
            text = trim(adjustl(text))
            return
        end if
        do d = 1, 17
            write (buf, digit_formats(d)) x
            read (buf, *, iostat=ios) back
            if (ios == 0 .and. back == x) exit
        end do
        buf = adjustl(buf)
        e = index(buf, 'E')
        read (buf(e + 1:), *) point
        digits = buf(:e - 1)
        if (abs(x) >= 1.0e-4_wp .and. abs(x) < 1.0e15_wp) then
            text = positional(digits, point)
        else
            text = trim(strip_zeros(digits))//'e'//fmt_int(point)
        end if
    end function exact

    !> "d.ddd" (with sign) times 10**point, written without an exponent: 2.2, 0.05, 1000.0.
    pure function positional(mantissa, point) result(text)
        character(len=*), intent(in) :: mantissa
        integer, intent(in) :: point
        character(len=:), allocatable :: text, m, sign_text

        sign_text = ''
        m = mantissa
        if (m(1:1) == '-') then
            sign_text = '-'
            m = m(2:)
        end if
        m = m(1:1)//m(3:)
        do while (len(m) > 1 .and. m(len(m):len(m)) == '0')
            m = m(:len(m) - 1)
        end do
        if (point < 0) then
            text = sign_text//'0.'//repeat('0', -point - 1)//m
        else if (len(m) <= point + 1) then
            text = sign_text//m//repeat('0', point + 1 - len(m))//'.0'
        else
            text = sign_text//m(:point + 1)//'.'//m(point + 2:)
        end if
    end function positional

    !> "d.dd000" -> "d.dd" (at least one digit after the point).
    pure function strip_zeros(mantissa) result(text)
        character(len=*), intent(in) :: mantissa
        character(len=:), allocatable :: text

        text = trim(mantissa)
        do while (text(len(text):len(text)) == '0' .and. text(len(text) - 1:len(text) - 1) /= '.')
            text = text(:len(text) - 1)
        end do
    end function strip_zeros

    !> The values as a namelist list, "v1, v2, ...". Built in a buffer that doubles, so that a
    !> list of 10^5 values costs linear time, not a copy of the text per value.
    pure function exact_list(values) result(text)
        real(wp), intent(in) :: values(:)
        character(len=:), allocatable :: text, buffer, piece
        integer :: i, used

        allocate (character(len=max(64, 24*size(values))) :: buffer)
        used = 0
        do i = 1, size(values)
            piece = exact(values(i))
            if (i > 1) piece = ', '//piece
            if (used + len(piece) > len(buffer)) buffer = buffer//repeat(' ', len(buffer))
            buffer(used + 1:used + len(piece)) = piece
            used = used + len(piece)
        end do
        text = buffer(:used)
    end function exact_list

    pure function fmt_logical(flag) result(text)
        logical, intent(in) :: flag
        character(len=:), allocatable :: text

        text = merge('.true. ', '.false.', flag)
        text = trim(text)
    end function fmt_logical

    !> A namelist string: it's -> 'it''s'.
    pure function namelist_string(raw) result(text)
        character(len=*), intent(in) :: raw
        character(len=:), allocatable :: text
        integer :: j

        text = "'"
        do j = 1, len(raw)
            text = text//raw(j:j)
            if (raw(j:j) == "'") text = text//"'"
        end do
        text = text//"'"
    end function namelist_string

end module chain_exact
