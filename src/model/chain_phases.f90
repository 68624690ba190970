!> The transcendental functions of the flow at a time t (docs/model.md sections 2.2 and 2.7):
!> the decay exp(-b t) and the turn (cos, sin)(gam t) of a free oscillation, and the drive's
!> phase (cos, sin)(w t), from tables at multiples of a step and a short Taylor turn of the rest.
!>
!> Every event needs these at a new time (the propagator, the drive, the steps of the gap
!> searches), and the library's exp and sincos were a quarter of the time of a run. The step h
!> is a power of two, so t = k h + r is split exactly; the table holds the library's values at
!> k h, and the rest r (|gam r|, |b r|, |w r| <= 1/64) is turned on by Taylor polynomials
!> accurate to 1e-19. The result differs from the exact value at t by the rounding of a few
!> products (a few units in the last place, with no accumulation: every value comes from the
!> table afresh). Times outside the tables (negative, or beyond their range) go to the
!> functions themselves. Every one of them, in the tables too, is chain_portable_math's
!> (renamed exp, cos, sin here), so that the flow is the same bits on every machine. Longer Taylor polynomials (up to 0.05) turn the phase of a free oscillation on by
!> the short steps of Halley's iteration (advance_free_phase). The kernels are private so that
!> the compiler inlines them here (it never inlines a public procedure of the
!> position-independent library).
module chain_phases
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use chain_kinds, only: wp, pi
    use chain_portable_math, only: exp => portable_exp, cos => portable_cos, &
                                   sin => portable_sin
    implicit none
    private
    public :: phase_table_t, make_phase_table, free_phase, free_decay, drive_phase
    public :: advance_free_phase, phase_angle, phase_asin

    real(wp), parameter :: short_angle = 0.05_wp !! the largest argument of short_cis, short_exp
    real(wp), parameter :: table_angle = 1/32.0_wp !! the largest product of h and b, gam or w
    real(wp), parameter :: free_step = table_angle !! h of the free table (b, gam <= 1)
    integer, parameter :: max_entries = 2048     !! entries of the free table, at most
    !> atan(j / 16), j = 0..16, evaluated by the compiler, for phase_angle
    real(wp), parameter :: atan_grid(0:16) = &
        atan(real([0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16], wp)/16)
    real(wp), parameter :: half_pi = pi/2

    type :: phase_table_t
        real(wp) :: damping = 0, gam = 1, omega = 1 !! b, sqrt(1 - b**2), w
        real(wp) :: free_limit = -1  !! the free table serves 0 <= t < free_limit
        real(wp) :: drive_step = 1   !! h of the drive table (a power of two, w h <= 1/32)
        real(wp) :: inv_drive_step = 1
        real(wp) :: drive_limit = -1 !! the drive table serves 0 <= t < drive_limit
        real(wp), allocatable :: free(:, :)  !! free(3, 0:last): exp(-b t), cos(gam t),
                                             !! sin(gam t) at t = k free_step
        real(wp), allocatable :: drive(:, :) !! drive(2, 0:last): cos(w t), sin(w t) at
                                             !! t = k drive_step
    end type phase_table_t

contains

    !> Tables for damping b (gam = sqrt(1 - b**2)) and drive frequency w: the free functions up
    !> to free_max (at most 64 time units), the drive's up to drive_max.
    pure function make_phase_table(damping, gam, omega, free_max, drive_max) result(table)
        real(wp), intent(in) :: damping, gam, omega, free_max, drive_max
        type(phase_table_t) :: table
        real(wp) :: t, h
        integer :: k, last

        table%damping = damping
        table%gam = gam
        table%omega = omega
        last = min(max_entries - 1, ceiling(free_max/free_step) + 1)
        allocate (table%free(3, 0:last))
        do k = 0, last
            t = k*free_step
            table%free(:, k) = [exp(-damping*t), cos(gam*t), sin(gam*t)]
        end do
        table%free_limit = (last + 0.5_wp)*free_step
        ! the largest power of two with w h <= table_angle (exponent: exactly, on any machine)
        h = 2.0_wp**(exponent(table_angle/omega) - 1)
        do while (omega*h > table_angle)
            h = h/2
        end do
        table%drive_step = h
        table%inv_drive_step = 1/h
        last = ceiling(drive_max/h) + 1
        allocate (table%drive(2, 0:last))
        do k = 0, last
            t = k*h
            table%drive(:, k) = [cos(omega*t), sin(omega*t)]
        end do
        table%drive_limit = (last + 0.5_wp)*h
    end function make_phase_table

    !> exp(-b t), cos(gam t) and sin(gam t).
    pure subroutine free_phase(table, t, decay, cos_gt, sin_gt)
        type(phase_table_t), intent(in) :: table
        real(wp), value :: t
        real(wp), intent(out) :: decay, cos_gt, sin_gt
        real(wp) :: r, cd, sd
        integer :: k

        if (.not. (t >= 0 .and. t < table%free_limit)) then
            decay = exp(-table%damping*t)
            cos_gt = cos(table%gam*t)
            sin_gt = sin(table%gam*t)
            return
        end if
        ! the nearest entry (t >= 0: int rounds down); r is exact, since k free_step is a
        ! multiple of a power of two and t lies within free_step / 2 of it
        k = int(t*(1/free_step) + 0.5_wp)
        r = t - k*free_step
        call table_cis(table%gam*r, cd, sd)
        decay = table%free(1, k)*table_exp(-table%damping*r)
        cos_gt = table%free(2, k)
        sin_gt = table%free(3, k)
        call turn(cd, sd, cos_gt, sin_gt)
    end subroutine free_phase

    !> exp(-b t) alone.
    pure function free_decay(table, t) result(decay)
        type(phase_table_t), intent(in) :: table
        real(wp), value :: t
        real(wp) :: decay
        integer :: k

        if (table%damping == 0) then
            decay = 1
        else if (.not. (t >= 0 .and. t < table%free_limit)) then
            decay = exp(-table%damping*t)
        else
            k = int(t*(1/free_step) + 0.5_wp)
            decay = table%free(1, k)*table_exp(-table%damping*(t - k*free_step))
        end if
    end function free_decay

    !> cos(w t) and sin(w t).
    pure subroutine drive_phase(table, t, cos_wt, sin_wt)
        type(phase_table_t), intent(in) :: table
        real(wp), value :: t
        real(wp), intent(out) :: cos_wt, sin_wt
        real(wp) :: cd, sd
        integer :: k

        if (.not. (t >= 0 .and. t < table%drive_limit)) then
            cos_wt = cos(table%omega*t)
            sin_wt = sin(table%omega*t)
            return
        end if
        k = int(t*table%inv_drive_step + 0.5_wp)
        call table_cis(table%omega*(t - k*table%drive_step), cd, sd)
        cos_wt = table%drive(1, k)
        sin_wt = table%drive(2, k)
        call turn(cd, sd, cos_wt, sin_wt)
    end subroutine drive_phase

    !> exp(-b t), cos(gam t), sin(gam t) (or of any angle gam t - phi) moved on to t + h: short
    !> steps by the Taylor polynomials, others by the tables.
    pure subroutine advance_free_phase(table, h, decay, cos_gt, sin_gt)
        type(phase_table_t), intent(in) :: table
        real(wp), value :: h
        real(wp), intent(inout) :: decay, cos_gt, sin_gt
        real(wp) :: x, u, cd, sd, ed

        x = table%gam*h
        u = -table%damping*h
        if (max(abs(x), abs(u)) <= short_angle) then
            call short_cis(x, cd, sd)
            ed = short_exp(u)
        else
            call free_phase(table, h, ed, cd, sd)
        end if
        decay = decay*ed
        call turn(cd, sd, cos_gt, sin_gt)
    end subroutine advance_free_phase

    !> atan2(s, c), the angle of (c, s) in [-pi, pi], to a few units in the last place: the
    !> angle is reduced to the first octant (z = min(|c|, |s|) / max(|c|, |s|)), then to within
    !> 1/32 of a multiple j / 16 whose arctangent is tabulated, and the rest
    !> t = (z - j/16) / (1 + z j/16) is the argument of a Taylor polynomial (|t| <= 1/32,
    !> remainder below t**13 / 13); the octant is unfolded by a table and the sign of s, not by
    !> branches (which the data would mispredict half the time). A third of the library's
    !> cost, and the same bits on every machine. (0, 0) gives 0, or pi for c = -0, with the
    !> sign of s; non-finite arguments give NaN.
    pure function phase_angle(c, s) result(angle)
        real(wp), intent(in) :: c, s
        real(wp) :: angle
        real(wp), parameter :: a3 = -1/3.0_wp, a5 = 1/5.0_wp, a7 = -1/7.0_wp, a9 = 1/9.0_wp, &
                               a11 = -1/11.0_wp
        !> the angle in octant 0..3 (|s| > |c|: +1, c < 0: +2) is offset + factor * atan(z)
        real(wp), parameter :: offset(0:3) = [0.0_wp, half_pi, pi, half_pi]
        real(wp), parameter :: factor(0:3) = [1.0_wp, -1.0_wp, -1.0_wp, 1.0_wp]
        real(wp) :: ac, as, z, zj, t, t2
        integer :: j, octant

        ac = abs(c)
        as = abs(s)
        if (ac == 0 .and. as == 0) then
            angle = sign(merge(pi, 0.0_wp, sign(1.0_wp, c) < 0), s)
            return
        end if
        z = min(ac, as)/max(ac, as)
        if (.not. (z <= 1)) then
            angle = ieee_value(angle, ieee_quiet_nan)
            return
        end if
        j = int(16*z + 0.5_wp)
        zj = j/16.0_wp
        ! z - zj is exact (Sterbenz), so t carries the rounding of one product and a quotient
        t = (z - zj)/(1 + z*zj)
        t2 = t*t
        octant = merge(1, 0, as > ac) + merge(2, 0, c < 0)
        angle = offset(octant) + factor(octant)*(atan_grid(j) + &
                (t + (t*t2)*(a3 + t2*(a5 + t2*(a7 + t2*(a9 + t2*a11))))))
        angle = sign(angle, s)
    end function phase_angle

    !> asin(x) for |x| <= 1, the angle of (sqrt((1 - x)(1 + x)), x): a few units in the last
    !> place, the same bits on every machine; NaN outside.
    pure function phase_asin(x) result(angle)
        real(wp), intent(in) :: x
        real(wp) :: angle

        if (.not. (abs(x) <= 1)) then
            angle = ieee_value(angle, ieee_quiet_nan)
        else
            angle = phase_angle(sqrt((1 - x)*(1 + x)), x)
        end if
    end function phase_asin

    !> (cos, sin) of an angle turned on by the angle with cosine cd and sine sd.
    pure subroutine turn(cd, sd, cos_a, sin_a)
        real(wp), intent(in) :: cd, sd
        real(wp), intent(inout) :: cos_a, sin_a
        real(wp) :: c0

        c0 = cos_a
        cos_a = c0*cd - sin_a*sd
        sin_a = sin_a*cd + c0*sd
    end subroutine turn

    !> cos x and sin x for |x| <= table_angle / 2 by Taylor polynomials; the remainders are
    !> below x**8 / 8! and x**9 / 9!: under 1e-19 relative.
    pure subroutine table_cis(x, cd, sd)
        real(wp), intent(in) :: x
        real(wp), intent(out) :: cd, sd
        real(wp), parameter :: s3 = -1/6.0_wp, s5 = 1/120.0_wp, s7 = -1/5040.0_wp
        real(wp), parameter :: c2 = -1/2.0_wp, c4 = 1/24.0_wp, c6 = -1/720.0_wp
        real(wp) :: x2

        x2 = x*x
        sd = x + (x*x2)*(s3 + x2*(s5 + x2*s7))
        cd = 1 + x2*(c2 + x2*(c4 + x2*c6))
    end subroutine table_cis

    !> exp(u) for |u| <= table_angle / 2 by its Taylor polynomial (remainder below u**8 / 8!,
    !> under 1e-19 relative).
    pure function table_exp(u) result(ed)
        real(wp), intent(in) :: u
        real(wp) :: ed, u2
        real(wp), parameter :: e2 = 1/2.0_wp, e3 = 1/6.0_wp, e4 = 1/24.0_wp, e5 = 1/120.0_wp, &
                               e6 = 1/720.0_wp, e7 = 1/5040.0_wp

        u2 = u*u
        ed = (1 + u) + u2*((e2 + e3*u) + u2*((e4 + e5*u) + u2*(e6 + e7*u)))
    end function table_exp

    !> cos x and sin x for |x| <= short_angle by Taylor polynomials; the remainders are below
    !> x**8 / 8! (|x| <= 1e-3) or x**12 / 12!: under 1e-19 relative.
    pure subroutine short_cis(x, cd, sd)
        real(wp), intent(in) :: x
        real(wp), intent(out) :: cd, sd
        real(wp), parameter :: s3 = -1/6.0_wp, s5 = 1/120.0_wp, s7 = -1/5040.0_wp, &
                               s9 = 1/362880.0_wp
        real(wp), parameter :: c2 = -1/2.0_wp, c4 = 1/24.0_wp, c6 = -1/720.0_wp, &
                               c8 = 1/40320.0_wp, c10 = -1/3628800.0_wp
        real(wp) :: x2, x4

        x2 = x*x
        ! Estrin's scheme: pairs of terms evaluated side by side, a short dependency chain
        if (abs(x) <= 1.0e-3_wp) then
            sd = x + (x*x2)*(s3 + x2*s5)
            cd = (1 + c2*x2) + (x2*x2)*(c4 + c6*x2)
        else
            x4 = x2*x2
            sd = x + (x*x2)*((s3 + x2*s5) + x4*(s7 + x2*s9))
            cd = (1 + c2*x2) + x4*((c4 + c6*x2) + x4*(c8 + c10*x2))
        end if
    end subroutine short_cis

    !> exp(u) for |u| <= short_angle by its Taylor polynomial (remainder under 1e-19 relative).
    pure function short_exp(u) result(ed)
        real(wp), intent(in) :: u
        real(wp) :: ed, u2, u4
        real(wp), parameter :: e2 = 1/2.0_wp, e3 = 1/6.0_wp, e4 = 1/24.0_wp, e5 = 1/120.0_wp, &
                               e6 = 1/720.0_wp, e7 = 1/5040.0_wp, e8 = 1/40320.0_wp, &
                               e9 = 1/362880.0_wp

        u2 = u*u
        ! Estrin's scheme, as in short_cis
        if (abs(u) <= 1.0e-3_wp) then
            ed = (1 + u) + u2*((e2 + e3*u) + u2*((e4 + e5*u) + e6*u2))
        else
            u4 = u2*u2
            ed = ((1 + u) + u2*(e2 + e3*u)) + u4*(((e4 + e5*u) + u2*(e6 + e7*u)) + &
                                               u4*(e8 + e9*u))
        end if
    end function short_exp

end module chain_phases
