!> The exact flow of one driven, damped oscillator between impacts (docs/model.md section 2).
!>
!> x'' + 2 b x' + x = A sin(w t). The forced steady state xp = P sin(w t) + Q cos(w t) is the
!> same for every oscillator, and y = x - xp is a free damped oscillation propagated by the
!> 2x2 matrix of the paper's eq. 17. Times are always times within the current drive cycle,
!> so no sine or exponential ever sees a large argument.
module chain_flow
    use chain_kinds, only: wp, two_pi
    implicit none
    private
    public :: flow_t, make_flow, forced_response, forced_acceleration, propagator, advance_state

    type :: flow_t
        real(wp) :: damping = 0     !! b, 0 <= b < 1
        real(wp) :: amplitude = 0   !! A
        real(wp) :: omega = 1       !! w
        real(wp) :: gam = 1         !! sqrt(1 - b**2), the damped angular frequency
        real(wp) :: inv_gam = 1     !! 1 / gam
        real(wp) :: alpha = 0       !! asin(b): phase lag of the extrema of a free oscillation
        real(wp) :: period = two_pi !! T = 2 pi / w
        real(wp) :: p_sin = 0       !! P of the steady state
        real(wp) :: q_cos = 0       !! Q of the steady state
    end type flow_t

contains

    !> Precompute the constants of the flow for damping b, drive amplitude A and frequency w.
    pure function make_flow(damping, amplitude, omega) result(flow)
        real(wp), intent(in) :: damping, amplitude, omega
        type(flow_t) :: flow
        real(wp) :: d2

        flow%damping = damping
        flow%amplitude = amplitude
        flow%omega = omega
        flow%gam = sqrt(1 - damping**2)
        flow%inv_gam = 1 / flow%gam
        flow%alpha = asin(damping)
        flow%period = two_pi / omega
        d2 = (1 - omega**2)**2 + (2*damping*omega)**2
        flow%p_sin = amplitude*(1 - omega**2) / d2
        flow%q_cos = -2*damping*omega*amplitude / d2
    end function make_flow

    !> Steady-state position and velocity at time s within the drive cycle.
    elemental subroutine forced_response(flow, s, xp, vp)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: s
        real(wp), intent(out) :: xp, vp
        real(wp) :: sn, cs

        sn = sin(flow%omega*s)
        cs = cos(flow%omega*s)
        xp = flow%p_sin*sn + flow%q_cos*cs
        vp = flow%omega*(flow%p_sin*cs - flow%q_cos*sn)
    end subroutine forced_response

    !> Acceleration of a free oscillator in state (x, v) at time s within the cycle.
    elemental function forced_acceleration(flow, s, x, v) result(acc)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: s, x, v
        real(wp) :: acc

        acc = -2*flow%damping*v - x + flow%amplitude*sin(flow%omega*s)
    end function forced_acceleration

    !> The 2x2 propagator of (y, y') over a time tau (eq. 17); also propagates tangent vectors.
    pure function propagator(flow, tau) result(m)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: tau
        real(wp) :: m(2, 2)
        real(wp) :: e, cs, sn

        e = exp(-flow%damping*tau)
        cs = cos(flow%gam*tau)
        sn = sin(flow%gam*tau)*flow%inv_gam
        m(1, 1) = e*(cs + flow%damping*sn)
        m(1, 2) = e*sn
        m(2, 1) = -e*sn
        m(2, 2) = e*(cs - flow%damping*sn)
    end function propagator

    !> Move (x, v) from time s0 to s0 + tau within the cycle frame, exactly.
    pure subroutine advance_state(flow, s0, tau, x, v)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: s0, tau
        real(wp), intent(inout) :: x, v
        real(wp) :: m(2, 2), xp, vp, y, vy

        call forced_response(flow, s0, xp, vp)
        y = x - xp
        vy = v - vp
        m = propagator(flow, tau)
        call forced_response(flow, s0 + tau, xp, vp)
        x = m(1, 1)*y + m(1, 2)*vy + xp
        v = m(2, 1)*y + m(2, 2)*vy + vp
    end subroutine advance_state

end module chain_flow
