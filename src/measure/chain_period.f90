!> Period of an oscillator's strobe record: the smallest p <= max_period with
!> |x(j+p) - x(j)| within tol*(1 + |x(j)|) and |v(j+p) - v(j)| within tol*(1 + |v(j)|) over the
!> whole record, or 0
!> (aperiodic or of period beyond max_period). This is the paper's "period-1, period-2,
!> high period, chaotic" classification made explicit.
!> Implements docs/model.md section 6.3.
module chain_period
    use chain_kinds, only: wp
    implicit none
    private
    public :: detect_period

contains

    pure function detect_period(x, v, max_period, tol) result(period)
        real(wp), intent(in) :: x(:), v(:) !! strobe record of one oscillator
        integer, intent(in) :: max_period
        real(wp), intent(in) :: tol
        integer :: period, p, m

        m = size(x)
        period = 0
        do p = 1, min(max_period, m/2)
            if (all(abs(x(p + 1:m) - x(1:m - p)) <= tol*(1 + abs(x(1:m - p)))) .and. &
                all(abs(v(p + 1:m) - v(1:m - p)) <= tol*(1 + abs(v(1:m - p))))) then
                period = p
                return
            end if
        end do
    end function detect_period

end module chain_period
