!> A minimal test harness: a tally of passed and failed checks, and checks that print both
!> values on failure. A check passes when |got - want| <= max(abs_tol, rel_tol*|want|).
module testing
    use, intrinsic :: iso_fortran_env, only: output_unit
    use chain_kinds, only: wp
    implicit none
    private
    public :: tally_t, check, check_close

    type :: tally_t
        integer :: passed = 0
        integer :: failed = 0
    end type tally_t

contains

    subroutine check(t, condition, message)
        type(tally_t), intent(inout) :: t
        logical, intent(in) :: condition
        character(len=*), intent(in) :: message

        if (condition) then
            t%passed = t%passed + 1
        else
            t%failed = t%failed + 1
            write (output_unit, '(a)') 'FAIL: '//message
        end if
    end subroutine check

    subroutine check_close(t, got, want, message, abs_tol, rel_tol)
        type(tally_t), intent(inout) :: t
        real(wp), intent(in) :: got, want
        character(len=*), intent(in) :: message
        real(wp), intent(in), optional :: abs_tol, rel_tol
        real(wp) :: tol

        tol = 0
        if (present(abs_tol)) tol = abs_tol
        if (present(rel_tol)) tol = max(tol, rel_tol*abs(want))
        if (abs(got - want) <= tol) then
            t%passed = t%passed + 1
        else
            t%failed = t%failed + 1
            write (output_unit, '(a,es24.16,a,es24.16,a,es10.2,a,es10.2)') 'FAIL: '//message// &
                ': got ', got, ' want ', want, ' diff ', abs(got - want), ' tol ', tol
        end if
    end subroutine check_close

end module testing
