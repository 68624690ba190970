!> exp, cos, sin and hypot from +, -, *, / and sqrt alone, which IEEE 754 rounds the same
!> way on every machine: the elementary functions that decide a trajectory (docs/model.md
!> section 2.7; the arctangent and asin are chain_phases' phase_angle and phase_asin). The C
!> library picks its versions of exp, sin, cos and asin by CPU (glibc's FMA and AVX2 ones where the CPU has them); they differ from the baseline
!> versions in the last bit now and then, and a chaotic run magnifies one such bit into a
!> different trajectory within a few hundred cycles. With these, a trajectory is the same bits
!> on every x86-64 machine, whatever its CPU or C library (the build uses no fused
!> multiply-add). Accuracy: within 1 unit in the last place (exp, cos, sin: tested against
!> quadruple precision), 2 for hypot; no faster than the library, so they
!> serve the tables and the rare times outside them, not the event loop's inner steps.
!> Infrastructure: uses chain_kinds only.
module chain_portable_math
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_positive_inf, ieee_quiet_nan
    use chain_kinds, only: wp, pi
    implicit none
    private
    public :: portable_exp, portable_cos, portable_sin, portable_hypot
    public :: portable_reduction_limit

    real(wp), parameter :: half_pi = pi/2
    ! ln 2 split so that k ln2_hi is exact for |k| < 2**20 (fdlibm's constants)
    real(wp), parameter :: ln2_hi = 6.93147180369123816490e-01_wp
    real(wp), parameter :: ln2_lo = 1.90821492927058770002e-10_wp
    real(wp), parameter :: inv_ln2 = 1.44269504088896338700e+00_wp
    ! pi / 2 in three parts of 33 bits each, so that k pio2_1, k pio2_2 and k pio2_3 are
    ! exact for |k| < 2**20, and the rest pio2_3t (fdlibm's constants): pi / 2 to 1e-48
    real(wp), parameter :: inv_pio2 = 6.36619772367581382433e-01_wp
    real(wp), parameter :: pio2_1 = 1.57079632673412561417e+00_wp
    real(wp), parameter :: pio2_2 = 6.07710050630396597660e-11_wp
    real(wp), parameter :: pio2_3 = 2.02226624871116645580e-21_wp
    real(wp), parameter :: pio2_3t = 8.47842766036889956997e-32_wp
    !> the largest |x| that cos and sin reduce by the three parts of pi / 2 (2**19 pi / 2):
    !> beyond it they are refused by a NaN (no time of the model comes near)
    real(wp), parameter :: portable_reduction_limit = 2.0_wp**19*half_pi

contains

    !> exp(x) to within 1 unit in the last place: x = k ln 2 + r, |r| <= ln 2 / 2, and
    !> exp(r) - 1 by its Taylor polynomial of degree 13 (remainder below 5e-18).
    elemental function portable_exp(x) result(y)
        real(wp), intent(in) :: x
        real(wp) :: y, r, z
        integer :: k
        real(wp), parameter :: c2 = 1/2.0_wp, c3 = 1/6.0_wp, c4 = 1/24.0_wp, &
            c5 = 1/120.0_wp, c6 = 1/720.0_wp, c7 = 1/5040.0_wp, c8 = 1/40320.0_wp, &
            c9 = 1/362880.0_wp, c10 = 1/3628800.0_wp, c11 = 1/39916800.0_wp, &
            c12 = 1/479001600.0_wp, c13 = 1/6227020800.0_wp

        if (x /= x) then
            y = x
            return
        else if (x > 709.78_wp) then
            y = ieee_value(y, ieee_positive_inf)
            return
        else if (x < -745.2_wp) then
            y = 0
            return
        end if
        k = nint(x*inv_ln2)
        r = (x - k*ln2_hi) - k*ln2_lo
        z = r*r
        ! exp(r) - 1 = r + r**2 (1/2 + r/6 + ...), then 1 added last: its rounding is the
        ! only one of the size of a unit of the result
        y = 1 + (r + z*(c2 + r*(c3 + r*(c4 + r*(c5 + r*(c6 + r*(c7 + r*(c8 + r*(c9 + &
                r*(c10 + r*(c11 + r*(c12 + r*c13))))))))))))
        y = scale(y, k)
    end function portable_exp

    !> cos(x), to within 1 unit in the last place for |x| <= portable_reduction_limit.
    elemental function portable_cos(x) result(y)
        real(wp), intent(in) :: x
        real(wp) :: y, r, r_lo
        integer :: quadrant

        call reduce(x, r, r_lo, quadrant)
        y = cos_in_quadrant(r, r_lo, quadrant)
    end function portable_cos

    !> sin(x), to within 1 unit in the last place for |x| <= portable_reduction_limit:
    !> sin(x) = cos(x - pi/2), one quadrant back.
    elemental function portable_sin(x) result(y)
        real(wp), intent(in) :: x
        real(wp) :: y, r, r_lo
        integer :: quadrant

        call reduce(x, r, r_lo, quadrant)
        y = cos_in_quadrant(r, r_lo, modulo(quadrant - 1, 4))
    end function portable_sin

    !> cos(quadrant pi/2 + r + r_lo) from the kernels.
    elemental function cos_in_quadrant(r, r_lo, quadrant) result(y)
        real(wp), intent(in) :: r, r_lo
        integer, intent(in) :: quadrant
        real(wp) :: y

        select case (quadrant)
        case (0)
            y = kernel_cos(r, r_lo)
        case (1)
            y = -kernel_sin(r, r_lo)
        case (2)
            y = -kernel_cos(r, r_lo)
        case default
            y = kernel_sin(r, r_lo)
        end select
    end function cos_in_quadrant

    !> sqrt(a**2 + b**2) without overflow or underflow of the squares.
    elemental function portable_hypot(a, b) result(y)
        real(wp), intent(in) :: a, b
        real(wp) :: y, big, small

        big = max(abs(a), abs(b))
        small = min(abs(a), abs(b))
        if (big == 0 .or. big > huge(big)) then
            y = big
        else
            y = big*sqrt(1 + (small/big)**2)
        end if
    end function portable_hypot

    !> x = k pi/2 + r + r_lo with |r| <= pi/4 (a little more after rounding), quadrant =
    !> k mod 4, r + r_lo to about 1e-32 beyond r's own size: k pio2_1, k pio2_2 and k pio2_3
    !> are exact (k < 2**20), x - k pio2_1 is exact, and the subtraction of k pio2_2 keeps its
    !> rounding error (Knuth's two-sum) in r_lo with the last parts; so r keeps its accuracy
    !> even where x lies close to a multiple of pi / 2 and r is small. Beyond
    !> portable_reduction_limit or non-finite: r = NaN.
    elemental subroutine reduce(x, r, r_lo, quadrant)
        real(wp), intent(in) :: x
        real(wp), intent(out) :: r, r_lo
        integer, intent(out) :: quadrant
        real(wp) :: k, a, b, bb

        if (.not. (abs(x) <= portable_reduction_limit)) then
            r = ieee_value(r, ieee_quiet_nan)
            r_lo = 0
            quadrant = 0
            return
        end if
        k = anint(x*inv_pio2)
        a = x - k*pio2_1
        b = -k*pio2_2
        r = a + b
        bb = r - a
        r_lo = ((a - (r - bb)) + (b - bb)) - (k*pio2_3 + k*pio2_3t)
        a = r
        r = a + r_lo
        r_lo = r_lo - (r - a)
        quadrant = modulo(int(k), 4)
    end subroutine reduce

    !> sin(r + r_lo) for |r| <= pi/4, |r_lo| <= ulp(r): r + r**3 (-1/6 + ...), Taylor to
    !> degree 21 (remainder below 1e-22 relative), plus r_lo cos(r).
    elemental function kernel_sin(r, r_lo) result(y)
        real(wp), intent(in) :: r, r_lo
        real(wp) :: y, z
        real(wp), parameter :: s3 = -1/6.0_wp, s5 = 1/120.0_wp, s7 = -1/5040.0_wp, &
            s9 = 1/362880.0_wp, s11 = -1/39916800.0_wp, s13 = 1/6227020800.0_wp, &
            s15 = -1/1307674368000.0_wp, s17 = 1/355687428096000.0_wp, &
            s19 = -1/121645100408832000.0_wp, s21 = 1/51090942171709440000.0_wp

        z = r*r
        y = r + ((r*z)*(s3 + z*(s5 + z*(s7 + z*(s9 + z*(s11 + z*(s13 + z*(s15 + z*(s17 + &
                z*(s19 + z*s21))))))))) + r_lo*(1 - 0.5_wp*z))
    end function kernel_sin

    !> cos(r + r_lo) for |r| <= pi/4, |r_lo| <= ulp(r): 1 - r**2/2 + r**4 (1/24 - ...), Taylor
    !> to degree 20, less r_lo sin(r); 1 - r**2/2 is formed with its rounding error carried
    !> (fdlibm's way), which keeps the result within a unit in the last place where r**2/2
    !> is near 1/2.
    elemental function kernel_cos(r, r_lo) result(y)
        real(wp), intent(in) :: r, r_lo
        real(wp) :: y, z, hz, w
        real(wp), parameter :: c4 = 1/24.0_wp, c6 = -1/720.0_wp, c8 = 1/40320.0_wp, &
            c10 = -1/3628800.0_wp, c12 = 1/479001600.0_wp, c14 = -1/87178291200.0_wp, &
            c16 = 1/20922789888000.0_wp, c18 = -1/6402373705728000.0_wp, &
            c20 = 1/2432902008176640000.0_wp

        z = r*r
        hz = 0.5_wp*z
        w = 1 - hz
        y = w + (((1 - w) - hz) + ((z*z)*(c4 + z*(c6 + z*(c8 + z*(c10 + z*(c12 + z*(c14 + &
                z*(c16 + z*(c18 + z*c20)))))))) - r*r_lo))
    end function kernel_cos

end module chain_portable_math
