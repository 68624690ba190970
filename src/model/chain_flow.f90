!> The exact flow of one driven, damped oscillator between impacts (docs/model.md section 2).
!>
!> x'' + 2 b x' + x = A sin(w t). The forced steady state xp = P sin(w t) + Q cos(w t) is the
!> same for every oscillator (section 2.1), and y = x - xp is a free damped oscillation
!> propagated by the 2x2 matrix of the paper's eq. 17 (section 2.2). Times are always times
!> within the current drive cycle, so no sine or exponential ever sees a large argument.
!>
!> This module is the one place of these formulas. Besides the forms that start from a time,
!> it has forms that start from the sines, cosines and exponentials a caller already holds:
!> the engine computes one propagator per event time, and chain_gaps turns its phases by
!> Taylor polynomials from one search step to the next. The sines, cosines and exponentials
!> of a time come from the flow's tables (chain_phases, section 2.7).
module chain_flow
    use chain_kinds, only: wp, two_pi
    use chain_phases, only: phase_table_t, make_phase_table, free_phase, drive_phase, phase_asin
    implicit none
    private
    public :: flow_t, make_flow, forced_response, forced_response_at, acceleration_at
    public :: propagator, propagator_pair, motion_at, advance_state

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
        real(wp) :: forced_amp = 0  !! sqrt(P**2 + Q**2), the amplitude of the steady state
        !> exp(-b t), (cos, sin)(gam t) and (cos, sin)(w t): the free functions up to two turns
        !> of the free oscillation and a drive period, the drive up to two periods (the reach of
        !> the propagators and of the gap searches)
        type(phase_table_t) :: phases
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
        flow%alpha = phase_asin(damping)
        flow%period = two_pi / omega
        d2 = (1 - omega**2)**2 + (2*damping*omega)**2
        flow%p_sin = amplitude*(1 - omega**2) / d2
        flow%q_cos = -2*damping*omega*amplitude / d2
        flow%forced_amp = sqrt(flow%p_sin**2 + flow%q_cos**2)
        flow%phases = make_phase_table(damping, flow%gam, omega, &
                                       max(2*two_pi*flow%inv_gam, flow%period), 2*flow%period)
    end function make_flow

    !> Steady-state position and velocity at time s within the drive cycle.
    elemental subroutine forced_response(flow, s, xp, vp)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: s
        real(wp), intent(out) :: xp, vp
        real(wp) :: cos_wt, sin_wt

        call drive_phase(flow%phases, s, cos_wt, sin_wt)
        call forced_terms(flow, sin_wt, cos_wt, xp, vp)
    end subroutine forced_response

    !> Steady-state position and velocity where the drive phase w t has sine sin_wt and
    !> cosine cos_wt.
    pure subroutine forced_response_at(flow, sin_wt, cos_wt, xp, vp)
        type(flow_t), intent(in) :: flow
        real(wp), value :: sin_wt, cos_wt
        real(wp), intent(out) :: xp, vp

        call forced_terms(flow, sin_wt, cos_wt, xp, vp)
    end subroutine forced_response_at

    !> Acceleration of a moving oscillator in state (x, v) where the drive phase has sine
    !> sin_wt (section 1.1).
    pure function acceleration_at(flow, sin_wt, x, v) result(acc)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: sin_wt, x, v
        real(wp) :: acc

        acc = -2*flow%damping*v - x + flow%amplitude*sin_wt
    end function acceleration_at

    !> The 2x2 propagator of (y, y') over a time tau (eq. 17); also propagates tangent vectors.
    pure function propagator(flow, tau) result(m)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: tau
        real(wp) :: m(2, 2), m_inv(2, 2)

        call propagator_pair(flow, tau, m, m_inv)
    end function propagator

    !> The propagator over tau and its inverse, from one exponential (det M = exp(-2 b tau)).
    pure subroutine propagator_pair(flow, tau, m, m_inv)
        type(flow_t), intent(in) :: flow
        real(wp), value :: tau
        real(wp), intent(out) :: m(2, 2), m_inv(2, 2)
        real(wp) :: e, cos_gt, sin_gt, inv_det, r(2, 2)

        call free_phase(flow%phases, tau, e, cos_gt, sin_gt)
        call rotation_terms(flow, cos_gt, sin_gt, r)
        m = e*r
        inv_det = 1/(e*e)
        m_inv(1, 1) = m(2, 2)*inv_det
        m_inv(2, 1) = -m(2, 1)*inv_det
        m_inv(1, 2) = -m(1, 2)*inv_det
        m_inv(2, 2) = m(1, 1)*inv_det
    end subroutine propagator_pair

    !> Both parts of the motion a time tau after the free part was (y0, vy0): the free part
    !> (y, vy), carried by the propagator with its decay `decay` = exp(-b tau) applied last,
    !> and the forced response (xp, vp), for a caller that holds cos_gt = cos(gam tau),
    !> sin_gt = sin(gam tau) and the sine and cosine of the drive phase (chain_gaps turns
    !> them by Taylor polynomials from one search step to the next). The arguments are
    !> passed by value: this is called on every step of a gap search.
    pure subroutine motion_at(flow, decay, cos_gt, sin_gt, sin_wt, cos_wt, y0, vy0, y, vy, &
                              xp, vp)
        type(flow_t), intent(in) :: flow
        real(wp), value :: decay, cos_gt, sin_gt, sin_wt, cos_wt, y0, vy0
        real(wp), intent(out) :: y, vy, xp, vp
        real(wp) :: r(2, 2)

        call rotation_terms(flow, cos_gt, sin_gt, r)
        y = decay*(r(1, 1)*y0 + r(1, 2)*vy0)
        vy = decay*(r(2, 1)*y0 + r(2, 2)*vy0)
        call forced_terms(flow, sin_wt, cos_wt, xp, vp)
    end subroutine motion_at

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

    ! The formulas themselves, private: the compiler inlines a private procedure into the
    ! others of its module, never a public one of a position-independent library.

    !> xp = P sin(w t) + Q cos(w t) and its rate (section 2.1).
    pure subroutine forced_terms(flow, sin_wt, cos_wt, xp, vp)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: sin_wt, cos_wt
        real(wp), intent(out) :: xp, vp

        xp = flow%p_sin*sin_wt + flow%q_cos*cos_wt
        vp = flow%omega*(flow%p_sin*cos_wt - flow%q_cos*sin_wt)
    end subroutine forced_terms

    !> M(tau) exp(b tau) = [[cs + b sn, sn], [-sn, cs - b sn]], cs = cos(gam tau),
    !> sn = sin(gam tau) / gam (section 2.2).
    pure subroutine rotation_terms(flow, cos_gt, sin_gt, r)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: cos_gt, sin_gt
        real(wp), intent(out) :: r(2, 2)
        real(wp) :: sn

        sn = sin_gt*flow%inv_gam
        r(1, 1) = cos_gt + flow%damping*sn
        r(1, 2) = sn
        r(2, 1) = -sn
        r(2, 2) = cos_gt - flow%damping*sn
    end subroutine rotation_terms

end module chain_flow
