!> The test of a Neimark-Sacker curve in two parameters (docs/model.md section 12.6):
!> s = |mu|^2 - 1 for the multiplier mu of the complex pair that leaves the unit circle. The
!> pair is tracked from point to point: at each y, mu is the multiplier of J nearest the
!> pair's last position (the aim), so that another pair, or the other member of a mirror
!> pair, never takes its place between two points. The curve ends where the pair turns real:
!> at +1 (a 1:1 resonance, where the curve meets a fold curve) or at -1 (a 1:2 resonance,
!> where it meets a period-doubling curve).
module chain_curve_ns
    use chain_kinds, only: wp, pi
    use chain_error, only: fmt_real
    use chain_lapack, only: general_eigenvalues
    implicit none
    private
    public :: pair_test, tracked_pair, unit_circle_pair, pair_end_reason

    !> A last point's pair within this angle (radians) of the real axis is at its end: the
    !> curve's step cannot resolve the square-root turn of the pair into two real multipliers.
    real(wp), parameter :: near_real = 0.1_wp

contains

    !> The multiplier of `jacobian` nearest `aim` (with its sign of imaginary part as aim's),
    !> and whether it is one of a complex pair.
    subroutine tracked_pair(jacobian, aim, mu, complex_pair)
        real(wp), intent(in) :: jacobian(:, :)
        complex(wp), intent(in) :: aim
        complex(wp), intent(out) :: mu
        logical, intent(out) :: complex_pair
        complex(wp), allocatable :: multipliers(:)

        multipliers = multipliers_of(jacobian)
        mu = multipliers(minloc(abs(multipliers - aim), 1))
        complex_pair = aimag(mu) /= 0
    end subroutine tracked_pair

    !> The test s = |mu|^2 - 1 of the tracked pair; `failure` when the multiplier nearest
    !> the aim is real (the pair turned real between the last point and this y).
    subroutine pair_test(jacobian, aim, s, failure)
        real(wp), intent(in) :: jacobian(:, :)
        complex(wp), intent(in) :: aim
        real(wp), intent(out) :: s
        character(len=:), allocatable, intent(inout) :: failure
        complex(wp) :: mu
        logical :: complex_pair

        call tracked_pair(jacobian, aim, mu, complex_pair)
        s = abs(mu)**2 - 1
        if (.not. complex_pair) failure = "the complex pair turned real (a multiplier "// &
                                          fmt_real(real(mu, wp))//")"
    end subroutine pair_test

    !> The start's pair: the multiplier with positive imaginary part nearest the unit circle;
    !> `failure` when no multiplier is complex.
    subroutine unit_circle_pair(jacobian, mu, failure)
        real(wp), intent(in) :: jacobian(:, :)
        complex(wp), intent(out) :: mu
        character(len=:), allocatable, intent(inout) :: failure
        complex(wp), allocatable :: multipliers(:)

        multipliers = multipliers_of(jacobian)
        multipliers = pack(multipliers, aimag(multipliers) > 0)
        mu = 0
        if (size(multipliers) == 0) then
            failure = "no complex multipliers"
            return
        end if
        mu = multipliers(minloc(abs(abs(multipliers) - 1), 1))
    end subroutine unit_circle_pair

    !> Why a Neimark-Sacker curve ends where no step from its last point (pair `pair`, at
    !> `place`) succeeds, Newton's `failure` given: a 1:1 or 1:2 resonance when the pair
    !> turned real or lies within near_real of the real axis; else ''.
    function pair_end_reason(pair, place, failure) result(reason)
        complex(wp), intent(in) :: pair
        character(len=*), intent(in) :: place, failure
        character(len=:), allocatable :: reason
        real(wp) :: angle

        reason = ''
        angle = abs(atan2(aimag(pair), real(pair, wp)))
        if (index(failure, 'turned real') == 0 .and. angle >= near_real .and. &
            angle <= pi - near_real) return
        if (angle < pi/2) then
            reason = '1:1 resonance'//place//': the pair turns real at +1'
        else
            reason = '1:2 resonance'//place//': the pair turns real at -1'
        end if
        reason = reason//' (its angle '//fmt_real(angle)//' at the last point; then '// &
                 failure//')'
    end function pair_end_reason

    !> The eigenvalues of `jacobian` (the multipliers).
    function multipliers_of(jacobian) result(multipliers)
        real(wp), intent(in) :: jacobian(:, :)
        complex(wp), allocatable :: multipliers(:)
        real(wp), allocatable :: a(:, :), re(:), im(:)
        integer :: m, info

        m = size(jacobian, 1)
        a = jacobian
        allocate (re(m), im(m))
        call general_eigenvalues(a, re, im, info)
        if (info /= 0) then
            ! (dgeev did not converge: no multiplier is near any aim)
            re = huge(1.0_wp)
            im = 0
        end if
        multipliers = cmplx(re, im, wp)
    end function multipliers_of

end module chain_curve_ns
