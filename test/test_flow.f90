!> docs/model.md section 2: the closed-form flow against the analytic steady state, the semigroup
!> property, the determinant, and an independent power-series integration of the ODE.
module test_flow
    use chain_kinds, only: wp, two_pi
    use chain_flow, only: flow_t, make_flow, forced_response, propagator, advance_state
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
    end subroutine run_flow_tests

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
