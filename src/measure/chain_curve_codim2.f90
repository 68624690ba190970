!> Codim-2 points on fold and period-doubling curves (docs/model.md section 12.6): test
!> functions at every point of a curve; the zero of one that changes sign between two points
!> is located by a secant in arclength (every trial corrected onto the curve) and kept only
!> when the multipliers there confirm it.
module chain_curve_codim2
    use chain_kinds, only: wp
    use chain_error, only: error_t
    use chain_lapack, only: general_eigenvalues
    use chain_curve_system, only: curve_setting_t, curve_state_t, evaluate, tangent_of
    implicit none
    private
    public :: codim2_tests, codim2_point_t, locate_codim2

    !> The zero is located when |test| is below test_tolerance (the tests are of order one)
    !> or the arclength bracket below bracket_tolerance.
    real(wp), parameter :: test_tolerance = 1.0e-13_wp, bracket_tolerance = 1.0e-13_wp

    !> A fold-flip point: multipliers +1 and -1, each within this distance.
    real(wp), parameter :: flip_confirmation = 1.0e-8_wp
    !> A 1:1 (1:2) point: two multipliers within this distance of +1 (-1). A double multiplier
    !> with a Jordan block splits like the square root of a perturbation of J: with s at
    !> rounding (1e-15 relative) the pair sits about 1e-6 apart (found: 1.1e-6 in the test,
    !> 1.7e-5 before the last Newton step from |s| <= 1e-11); a tenfold margin.
    real(wp), parameter :: resonance_confirmation = 1.0e-5_wp
    !> A cusp: a multiplier +1 within flip_confirmation, and the curve's tangent (unit in
    !> (z, mu1, mu2)) with a part in the parameter plane below this: there the fold curve turns
    !> back in both parameters.
    real(wp), parameter :: cusp_confirmation = 1.0e-4_wp

    !> A codim-2 point located between two points of a curve.
    type :: codim2_point_t
        character(len=:), allocatable :: kind
        real(wp), allocatable :: y(:)          !! (z, mu1, mu2) there
        type(curve_state_t) :: st              !! the converged state there
        logical :: confirmed = .false.
    end type codim2_point_t

    abstract interface
        !> Newton onto the curve from guess, on the hyperplane anchor . (y - guess) = 0.
        subroutine corrector(set, guess, anchor, y, st, failure, err)
            import :: curve_setting_t, curve_state_t, error_t, wp
            type(curve_setting_t), intent(in) :: set
            real(wp), intent(in) :: guess(:), anchor(:)
            real(wp), allocatable, intent(out) :: y(:)
            type(curve_state_t), intent(out) :: st
            character(len=:), allocatable, intent(out) :: failure
            type(error_t), allocatable, intent(out) :: err
        end subroutine corrector
    end interface

contains

    !> The names of the tests of a curve with this shift (-1 fold, +1 period doubling), in the
    !> order of codim2_tests.
    pure function codim2_names(shift) result(names)
        real(wp), intent(in) :: shift
        character(len=16), allocatable :: names(:)

        if (shift < 0) then
            names = [character(len=16) :: 'fold-flip', '1:1', 'cusp']
        else
            names = [character(len=16) :: 'fold-flip', '1:2']
        end if
    end function codim2_names

    !> The test functions at a converged point y (state st) of a curve:
    !> - fold-flip: det(J - shift I) (the other curve's test) from the multipliers, each factor
    !>   mu - shift divided by 1 + |mu| (of order one whatever the orbit's stability);
    !> - 1:1 (fold) or 1:2 (doubling): v . w / (|v| |w|), the bordered system's left and right
    !>   null vectors of J + shift I, zero where they are orthogonal: the multiplier is double
    !>   with a Jordan block. (Their signs follow the bordering vectors, so the test is
    !>   continuous along the curve.)
    !> - cusp (fold): v . B(w, w) / (|v| |w|**2), the fold's quadratic normal-form coefficient
    !>   up to the factor |v| |w| / (v . w), of fixed sign away from 1:1.
    subroutine codim2_tests(set, y, st, tests, err)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:)
        type(curve_state_t), intent(in) :: st
        real(wp), allocatable, intent(out) :: tests(:)
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: re(:), im(:), bww(:)

        call multipliers(st%pass%jacobian, re, im)
        tests = [other_determinant(re, im, set%shift), &
                 dot_product(st%v, st%w)/(norm2(st%v)*norm2(st%w))]
        if (set%shift > 0) return
        call second_derivative(set, y, st%w, bww, err)
        if (allocated(err)) return
        tests = [tests, dot_product(st%v, bww)/(norm2(st%v)*norm2(st%w)**2)]
    end subroutine codim2_tests

    !> B(w, w), the second derivative of the map along w, as (J(z + h w) - J(z - h w)) w / (2 h):
    !> the Jacobians are exact, so the error is O(h**2) with no cancellation of function values;
    !> h = 1e-5 (1 + |z|) / |w| keeps both passes on the orbit's impacts away from a grazing.
    !> Zero when a pass fails (no test there).
    subroutine second_derivative(set, y, w, bww, err)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:), w(:)
        real(wp), allocatable, intent(out) :: bww(:)
        type(error_t), allocatable, intent(out) :: err
        type(curve_state_t) :: plus, minus
        real(wp), allocatable :: step(:)
        real(wp) :: h
        integer :: m

        m = size(w)
        h = 1.0e-5_wp*(1 + norm2(y(:m)))/norm2(w)
        step = [h*w, 0.0_wp, 0.0_wp]
        bww = spread(0.0_wp, 1, m)
        call evaluate(set, y + step, plus, err, .false.)
        if (allocated(err)) return
        call evaluate(set, y - step, minus, err, .false.)
        if (allocated(err)) return
        if (.not. (plus%ok .and. minus%ok)) return
        bww = matmul(plus%pass%jacobian - minus%pass%jacobian, w)/(2*h)
    end subroutine second_derivative

    !> prod (mu - shift)/(1 + |mu|): det(J - shift I) scaled, real (pairs give |.|^2 > 0).
    pure real(wp) function other_determinant(re, im, shift)
        real(wp), intent(in) :: re(:), im(:), shift
        complex(wp) :: product_
        integer :: j

        product_ = 1
        do j = 1, size(re)
            product_ = product_*cmplx(re(j) - shift, im(j), wp)/(1 + abs(cmplx(re(j), im(j), wp)))
        end do
        other_determinant = real(product_, wp)
    end function other_determinant

    !> The eigenvalues of J.
    subroutine multipliers(jacobian, re, im)
        real(wp), intent(in) :: jacobian(:, :)
        real(wp), allocatable, intent(out) :: re(:), im(:)
        real(wp), allocatable :: a(:, :)
        integer :: info

        a = jacobian
        allocate (re(size(a, 1)), im(size(a, 1)))
        call general_eigenvalues(a, re, im, info)
    end subroutine multipliers

    !> The zero of test `which` between y0 (tangent t0, test g0) and y1 (test g1): regula
    !> falsi (Illinois) in the arclength tau along t0, every trial y0 + tau t0 corrected onto
    !> the curve on the hyperplane normal to t0; then the multipliers' word on it.
    subroutine locate_codim2(set, correct, which, y0, t0, g0, y1, g1, point, err)
        type(curve_setting_t), intent(in) :: set
        procedure(corrector) :: correct
        integer, intent(in) :: which
        real(wp), intent(in) :: y0(:), t0(:), g0, y1(:), g1
        type(codim2_point_t), intent(out) :: point
        type(error_t), allocatable, intent(out) :: err
        integer, parameter :: max_iterations = 60
        character(len=:), allocatable :: failure
        character(len=16), allocatable :: names(:)
        real(wp), allocatable :: tests(:), y(:), tangent(:)
        real(wp) :: a, b, ga, gb, tau, g
        integer :: iteration, side

        names = codim2_names(set%shift)
        point%kind = trim(names(which))
        a = 0
        b = dot_product(y1 - y0, t0)
        ga = g0
        gb = g1
        side = 0
        do iteration = 1, max_iterations
            tau = (a*gb - b*ga)/(gb - ga)
            call correct(set, y0 + tau*t0, t0, point%y, point%st, failure, err)
            if (allocated(err)) return
            if (len(failure) > 0) return
            call codim2_tests(set, point%y, point%st, tests, err)
            if (allocated(err)) return
            g = tests(which)
            if (abs(g) <= test_tolerance .or. abs(b - a) <= bracket_tolerance) exit
            if (sign(1.0_wp, g) == sign(1.0_wp, ga)) then
                a = tau
                ga = g
                if (side == -1) gb = gb/2
                side = -1
            else
                b = tau
                gb = g
                if (side == 1) ga = ga/2
                side = 1
            end if
        end do
        ! (one more Newton step from the point found, on the same hyperplane: Newton stops at
        ! |s| <= 1e-11, and at a double multiplier J + shift I's two small singular values
        ! meet, so the pair sits sqrt(|s|) apart there; the extra step takes s to rounding)
        call correct(set, point%y, t0, y, point%st, failure, err)
        if (allocated(err)) return
        if (len(failure) > 0) return
        point%y = y
        call tangent_of(point%st, t0, tangent, failure)
        if (len(failure) > 0) return
        call confirm(point, -set%shift, tangent(size(y) - 1:))
    end subroutine locate_codim2

    !> The multipliers' word on a located point of a curve whose own multiplier is `own`:
    !> fold-flip, +1 and -1 each within flip_confirmation; 1:1 or 1:2, two multipliers within
    !> resonance_confirmation of `own`; cusp, +1 within flip_confirmation and the unit
    !> tangent's parameter part `turn` below cusp_confirmation.
    subroutine confirm(point, own, turn)
        type(codim2_point_t), intent(inout) :: point
        real(wp), intent(in) :: own, turn(:)
        real(wp), allocatable :: re(:), im(:), d_plus(:), d_minus(:), d_own(:)

        call multipliers(point%st%pass%jacobian, re, im)
        d_plus = sorted_distances(re, im, 1.0_wp)
        d_minus = sorted_distances(re, im, -1.0_wp)
        d_own = merge(d_plus, d_minus, own > 0)
        select case (point%kind)
        case ('fold-flip')
            point%confirmed = d_plus(1) <= flip_confirmation .and. &
                              d_minus(1) <= flip_confirmation
        case ('cusp')
            point%confirmed = d_plus(1) <= flip_confirmation .and. &
                              norm2(turn) <= cusp_confirmation
        case default
            point%confirmed = d_own(2) <= resonance_confirmation
        end select
    end subroutine confirm

    !> The distances of the multipliers from `target`, smallest first.
    pure function sorted_distances(re, im, target) result(d)
        real(wp), intent(in) :: re(:), im(:), target
        real(wp), allocatable :: d(:)
        real(wp) :: swap
        integer :: i, j

        d = abs(cmplx(re - target, im, wp))
        do i = 2, size(d)
            do j = i, 2, -1
                if (d(j) >= d(j - 1)) exit
                swap = d(j)
                d(j) = d(j - 1)
                d(j - 1) = swap
            end do
        end do
    end function sorted_distances

end module chain_curve_codim2
