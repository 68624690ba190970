!> docs/model.md section 2: the closed-form flow against the analytic steady state, the semigroup
!> property, the determinant, and an independent power-series integration of the ODE; the
!> flow's tables of exp, cos and sin (section 2.7) against the library at every kind of time,
!> and the portable exp, cos, sin and hypot that build them against quadruple precision.
module test_flow
    use, intrinsic :: iso_fortran_env, only: qp => real128
    use chain_kinds, only: wp, two_pi
    use chain_portable_math, only: portable_exp, portable_cos, portable_sin, portable_hypot, &
                                   portable_reduction_limit
    use chain_flow, only: flow_t, make_flow, forced_response, propagator, advance_state
    use chain_phases, only: free_phase, free_decay, drive_phase, advance_free_phase, phase_angle
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_flow_tests

contains

    subroutine run_flow_tests(t)
        type(tally_t), intent(inout) :: t
        type(flow_t) :: flow
        real(wp) :: m(2, 2), x, v, xp, vp, x2, v2, xs, vs, tau
        integer :: j

        flow = make_flow(0.05_wp, 1.7_wp, 1.5_wp)
        do j = 1, 5
            tau = 0.37_wp*j
            m = propagator(flow, tau)
            call check_close(t, m(1, 1)*m(2, 2) - m(1, 2)*m(2, 1), exp(-2*0.05_wp*tau), &
                             'propagator determinant is exp(-2 b tau)', rel_tol=1.0e-14_wp)
        end do

        ! the steady state is carried exactly onto itself over many cycles
        call forced_response(flow, 0.3_wp, x, v)
        call advance_state(flow, 0.3_wp, 7.9_wp, x, v)
        call forced_response(flow, 0.3_wp + 7.9_wp, xp, vp)
        call check_close(t, x, xp, 'steady state stays on the linear response (x)', 1.0e-14_wp)
        call check_close(t, v, vp, 'steady state stays on the linear response (v)', 1.0e-14_wp)

        ! the steady state solves the ODE: xp'' + 2b xp' + xp = A sin(w t)
        call forced_response(flow, 0.8_wp, xp, vp)
        call check_close(t, -flow%omega**2*xp + 2*flow%damping*vp + xp, &
                         flow%amplitude*sin(flow%omega*0.8_wp), &
                         'P, Q solve the forced equation', 1.0e-14_wp)

        ! semigroup: one step equals two steps
        x = 0.4_wp; v = -1.1_wp
        x2 = x; v2 = v
        call advance_state(flow, 0.2_wp, 2.5_wp, x, v)
        call advance_state(flow, 0.2_wp, 1.1_wp, x2, v2)
        call advance_state(flow, 1.3_wp, 1.4_wp, x2, v2)
        call check_close(t, x, x2, 'two steps equal one step (x)', 1.0e-14_wp)
        call check_close(t, v, v2, 'two steps equal one step (v)', 1.0e-14_wp)

        ! against an independent power-series (Taylor) integration of the ODE
        do j = 1, 4
            flow = make_flow(0.02_wp*j, 0.5_wp*j, 0.4_wp + 0.45_wp*j)
            x = 0.3_wp - 0.2_wp*j; v = 0.7_wp*j - 1
            xs = x; vs = v
            call advance_state(flow, 0.1_wp*j, 6.0_wp, x, v)
            call taylor_integrate(flow, 0.1_wp*j, 6.0_wp, xs, vs)
            call check_close(t, x, xs, 'closed form equals series integration (x)', &
                             rel_tol=1.0e-12_wp, abs_tol=1.0e-13_wp)
            call check_close(t, v, vs, 'closed form equals series integration (v)', &
                             rel_tol=1.0e-12_wp, abs_tol=1.0e-13_wp)
        end do
        call check_phase_tables(t)
        call check_phase_angle(t)
        call check_portable_math(t)
    end subroutine run_flow_tests

    !> exp, cos and sin of chain_portable_math within 1 unit in the last place of the value
    !> (quadruple precision's value rounded to double is the reference), hypot within 2, over
    !> the ranges the model uses and beyond: exp on [-745, 709], cos and sin up to the
    !> reduction limit, with points near multiples of pi/2; their special values.
    subroutine check_portable_math(t)
        type(tally_t), intent(inout) :: t
        real(wp) :: x, y, u, worst_exp, worst_cos, worst_sin, worst_hypot
        real(qp), parameter :: half_pi_q = 2*atan(1.0_qp)
        integer :: k

        worst_exp = 0
        worst_cos = 0
        worst_sin = 0
        worst_hypot = 0
        do k = 0, 200000
            u = sin(12.9898_wp*k)*43758.5453_wp
            u = u - floor(u)
            x = merge(-745 + 1454*u, 40*u - 20, mod(k, 2) == 0)
            worst_exp = max(worst_exp, ulps(portable_exp(x), exp(real(x, qp))))
            x = merge(portable_reduction_limit*(2*u - 1), 64*(2*u - 1), mod(k, 3) == 0)
            if (mod(k, 7) == 0) x = real(nint(x/1.5707963267948966_wp)*half_pi_q + &
                                         1.0e-9_qp*u, wp) ! near a multiple of pi/2
            worst_cos = max(worst_cos, ulps(portable_cos(x), cos(real(x, qp))))
            worst_sin = max(worst_sin, ulps(portable_sin(x), sin(real(x, qp))))
            y = merge(1.0e-200_wp, 3.0e200_wp, mod(k, 2) == 0)*(u - 0.3_wp)
            worst_hypot = max(worst_hypot, ulps(portable_hypot(x*y, y), &
                                                sqrt(real(x*y, qp)**2 + real(y, qp)**2)))
        end do
        call check(t, worst_exp <= 1, 'portable exp is within 1 ulp of the exact value')
        call check(t, worst_cos <= 1, 'portable cos is within 1 ulp of the exact value')
        call check(t, worst_sin <= 1, 'portable sin is within 1 ulp of the exact value')
        call check(t, worst_hypot <= 2, 'portable hypot is within 2 ulp of the exact value')
        if (max(worst_exp, worst_cos, worst_sin) > 1 .or. worst_hypot > 2) &
            print '(a, 4f8.3)', '    worst ulps (exp, cos, sin, hypot): ', worst_exp, &
                worst_cos, worst_sin, worst_hypot
        call check(t, portable_exp(0.0_wp) == 1 .and. portable_exp(-800.0_wp) == 0 .and. &
                   portable_exp(-1.0e-300_wp) == 1, &
                   'portable exp: exp(0) = 1, exp(-1e-300) = 1, underflow to 0')
        call check(t, portable_cos(0.0_wp) == 1 .and. portable_sin(0.0_wp) == 0, &
                   'portable cos(0) = 1, sin(0) = 0')
        x = 2*portable_reduction_limit
        call check(t, portable_sin(x) /= portable_sin(x), &
                   'portable sin beyond its reduction limit is NaN, not a wrong number')
    end subroutine check_portable_math

    !> |value - exact| in units in the last place of the exact value rounded to double.
    elemental function ulps(value, exact) result(n)
        real(wp), intent(in) :: value
        real(qp), intent(in) :: exact
        real(wp) :: n

        n = real(abs(real(value, qp) - exact)/spacing(abs(real(exact, wp))), wp)
    end function ulps

    !> phase_angle(c, s) is the library's atan2(s, c) to a few ulp of the angle, in every
    !> octant and at every scale, on the axes and diagonals, and gives acos(q) as the angle
    !> of (q, sqrt((1 - q) (1 + q))) to a few ulp.
    subroutine check_phase_angle(t)
        type(tally_t), intent(inout) :: t
        real(wp), parameter :: eps = epsilon(1.0_wp)
        real(wp) :: c, s, u, v, want, err_atan, err_acos, q
        integer :: k

        err_atan = 0
        err_acos = 0
        do k = 0, 200000
            u = sin(12.9898_wp*k + 1.3_wp)*43758.5453_wp
            u = u - floor(u)
            v = sin(78.233_wp*k + 0.7_wp)*24634.6345_wp
            v = v - floor(v)
            c = cos(7*u)*10.0_wp**(6*v - 3)
            s = sin(7*u)*10.0_wp**(6*v - 3)
            select case (mod(k, 7))
            case (0)
                s = 0             ! on an axis
            case (1)
                c = merge(s, -s, v < 0.5_wp) ! on a diagonal
            case (2)
                s = s*1.0e-12_wp  ! next to an axis
            end select
            want = atan2(s, c)
            err_atan = max(err_atan, abs(phase_angle(c, s) - want)/max(abs(want), tiny(1.0_wp)))
            q = 2*u - 1
            if (mod(k, 5) == 0) q = sign(1 - 10.0_wp**(-16*v), q) ! near +-1
            err_acos = max(err_acos, abs(phase_angle(q, sqrt((1 - q)*(1 + q))) - acos(q)) &
                           /max(acos(q), tiny(1.0_wp)))
        end do
        call check(t, err_atan <= 4*eps, "phase_angle is the library's atan2 to a few ulp")
        call check(t, err_acos <= 4*eps, "phase_angle of (q, sqrt(1 - q**2)) is acos(q) to a "// &
                   'few ulp')
        if (err_atan > 4*eps .or. err_acos > 4*eps) &
            print '(a, 2es10.2)', '    angle errors / eps: ', err_atan/eps, err_acos/eps
    end subroutine check_phase_angle

    !> The tables and their Taylor turns agree with the library's exp, cos and sin to a few
    !> units in the last place of the argument and of the value, at times inside the tables,
    !> on their grid, and beyond (where the library answers), for weak and strong damping and
    !> slow and fast drives; and a Halley-sized turn agrees with a fresh evaluation.
    subroutine check_phase_tables(t)
        type(tally_t), intent(inout) :: t
        real(wp), parameter :: dampings(4) = [0.0_wp, 0.05_wp, 0.5_wp, 0.99_wp]
        real(wp), parameter :: omegas(3) = [0.1_wp, 1.5_wp, 7.0_wp]
        real(wp), parameter :: eps = epsilon(1.0_wp)
        type(flow_t) :: flow
        real(wp) :: tau, u, e, c, s, err_free, err_drive, err_turn, b, gam, w, e2, c2, s2, h
        integer :: i, j, k

        err_free = 0
        err_drive = 0
        err_turn = 0
        do i = 1, size(dampings)
            do j = 1, size(omegas)
                flow = make_flow(dampings(i), 1.0_wp, omegas(j))
                b = flow%damping
                gam = flow%gam
                w = flow%omega
                do k = 0, 40000
                    ! up to 70 time units, beyond the free table (64) and the drive's (2 T)
                    u = sin(12.9898_wp*k + 78.233_wp*i + 3.7_wp*j)*43758.5453_wp
                    u = u - floor(u)
                    ! now and then a point of the grid
                    tau = merge(mod(k, 2240)/32.0_wp, 70*u, mod(k, 5) == 0)
                    call free_phase(flow%phases, tau, e, c, s)
                    err_free = max(err_free, abs(e - exp(-b*tau))/(exp(-b*tau)*(1 + b*tau)), &
                                   abs(c - cos(gam*tau))/(1 + gam*tau), &
                                   abs(s - sin(gam*tau))/(1 + gam*tau), &
                                   abs(free_decay(flow%phases, tau) - e)/e)
                    call drive_phase(flow%phases, tau, c, s)
                    err_drive = max(err_drive, abs(c - cos(w*tau))/(1 + w*tau), &
                                    abs(s - sin(w*tau))/(1 + w*tau))
                    ! a step of Halley's iteration, forward or back, short or long
                    h = (u - 0.5_wp)*merge(1.0e-4_wp, 0.2_wp, mod(k, 2) == 0)
                    call free_phase(flow%phases, tau, e, c, s)
                    call advance_free_phase(flow%phases, h, e, c, s)
                    call free_phase(flow%phases, tau + h, e2, c2, s2)
                    err_turn = max(err_turn, abs(e - e2)/(e2*(1 + b*tau)), &
                                   abs(c - c2)/(1 + gam*tau), abs(s - s2)/(1 + gam*tau))
                end do
            end do
        end do
        call check(t, err_free <= 4*eps, 'tables: exp(-b t), cos(gam t), sin(gam t) are the '// &
                   "library's to a few ulp of the argument")
        call check(t, err_drive <= 4*eps, "tables: cos(w t), sin(w t) are the library's to a "// &
                   'few ulp of the argument')
        call check(t, err_turn <= 8*eps, 'tables: a turn by a Halley step equals a fresh '// &
                   'evaluation to a few ulp')
        if (err_free > 4*eps .or. err_drive > 4*eps .or. err_turn > 8*eps) &
            print '(a, 3es10.2)', '    table errors / eps: ', err_free/eps, err_drive/eps, &
            err_turn/eps
    end subroutine check_phase_tables

    !> Integrate x'' + 2b x' + x = A sin(w t) by power series of order 30, steps of 0.05.
    subroutine taylor_integrate(flow, s0, duration, x, v)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: s0, duration
        real(wp), intent(inout) :: x, v
        integer, parameter :: order = 30, steps = 120
        real(wp) :: d(0:order + 2), h, s, total, fact
        integer :: k, step

        h = duration/steps
        s = s0
        do step = 1, steps
            d(0) = x
            d(1) = v
            do k = 0, order
                ! k-th derivative of the drive: A w^k sin(w s + k pi/2)
                d(k + 2) = -2*flow%damping*d(k + 1) - d(k) + &
                           flow%amplitude*flow%omega**k*sin(flow%omega*s + k*two_pi/4)
            end do
            x = 0
            v = 0
            fact = 1
            do k = 0, order
                if (k > 0) fact = fact*h/k
                x = x + d(k)*fact
                v = v + d(k + 1)*fact
            end do
            s = s + h
        end do
        total = s
    end subroutine taylor_integrate

end module test_flow
