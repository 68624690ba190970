!> The next zero of a gap function (docs/model.md sections 2.3-2.4, 5.1): when does a bond close?
!>
!> Every gap the chain can have is g(tau) = c + y(tau) + beta*xp(s0 + tau), with y a free
!> damped oscillation and beta in {-1, 0, 1} the multiple of the forced response:
!>   - a pair of free oscillators: beta = 0 (the drive cancels), y = y(k+1) - y(k);
!>   - a wall, or a pair whose other oscillator rests on a wall: beta = +-1.
!> For beta = 0 the extrema of y are known in closed form, so the first minimum that reaches
!> -c brackets the first zero on a monotone branch, refined by safeguarded Newton.
!> For beta /= 0 we advance conservatively: a Taylor polynomial with a bound on the next
!> derivative (|y^(m)| <= R exp(-b tau), |xp^(m)| <= w^m Rp) gives a step that cannot jump over
!> a zero, and converges quadratically onto transversal zeros. No sign-change sampling.
module chain_gaps
    use chain_kinds, only: wp, pi, two_pi
    use chain_flow, only: flow_t, forced_response, forced_response_at, propagator, motion_at
    use chain_phases, only: free_phase, free_decay, drive_phase, advance_free_phase, phase_angle
    implicit none
    private
    public :: gap_t, gap_search_t, next_gap_zero, gap_value, resolvable_speed, surely_resolvable
    public :: earliest_closing
    public :: search_none, search_root, search_horizon, time_tolerance, max_steps

    integer, parameter :: search_none = 0    !! the gap never closes
    integer, parameter :: search_root = 1    !! the gap closes at tau
    integer, parameter :: search_horizon = 2 !! no zero before tau = horizon; search again there
    real(wp), parameter :: time_tolerance = 1.0e-13_wp !! accuracy of a located zero
    integer, parameter :: max_steps = 200000 !! steps of one search (its limit: info = 1)
    integer, parameter :: lazy_steps = 2      !! steps of a forced search before it defers

    type :: gap_t
        real(wp) :: offset = 0 !! c: constant part of the gap (a sum of spacings)
        real(wp) :: y = 0      !! free damped part at tau = 0
        real(wp) :: vy = 0     !! its rate at tau = 0
        real(wp) :: beta = 0   !! multiple of the forced response in the gap
    end type gap_t

    type :: gap_search_t
        integer :: status = search_none
        real(wp) :: tau = huge(1.0_wp)  !! time of the zero (or of the horizon) after s0
        integer :: info = 0             !! 0 fine; 1 the step limit was hit (report it)
    end type gap_search_t

contains

    !> Gap value and rate at time s0 + tau.
    pure subroutine gap_value(flow, gap, s0, tau, g, g1)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        real(wp), intent(in) :: s0, tau
        real(wp), intent(out) :: g, g1
        real(wp) :: m(2, 2), xp, vp

        m = propagator(flow, tau)
        g = gap%offset + m(1, 1)*gap%y + m(1, 2)*gap%vy
        g1 = m(2, 1)*gap%y + m(2, 2)*gap%vy
        if (gap%beta /= 0) then
            call forced_response(flow, s0 + tau, xp, vp)
            g = g + gap%beta*xp
            g1 = g1 + gap%beta*vp
        end if
    end subroutine gap_value

    !> First zero of the gap after s0 at which the gap is closing (or touching), up to horizon.
    pure function next_gap_zero(flow, gap, s0, horizon) result(res)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        real(wp), intent(in) :: s0      !! time within the cycle at tau = 0
        real(wp), intent(in) :: horizon !! forced gaps are searched up to tau = horizon
        type(gap_search_t) :: res

        if (gap%beta == 0) then
            res = free_gap_zero(flow, gap)
        else
            res = forced_gap_zero(flow, gap, s0, horizon)
        end if
    end function next_gap_zero

    !> Zero of c + y(tau) with y a free damped oscillation: closed-form bracket, then Halley
    !> (halley_zero). y = amp exp(-b tau) cos(theta), theta = gam tau - phi.
    pure function free_gap_zero(flow, gap) result(res)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        type(gap_search_t) :: res
        real(wp) :: ss, amp, tau_min, e
        logical :: touching

        call amplitude_phase(flow, gap%y, gap%vy, amp, ss)
        res%status = search_none
        res%tau = huge(1.0_wp)
        if (gap%offset - amp > 0) return
        touching = gap%offset + gap%y <= noise(gap%offset, amp)
        if (touching .and. gap%vy < 0) then
            res%status = search_root
            res%tau = 0
            return
        end if
        tau_min = first_minimum(flow, gap%y, ss, touching)
        e = free_decay(flow%phases, tau_min)
        if (gap%offset - amp*flow%gam*e > 0) return
        res%status = search_root
        res%tau = halley_zero(flow, gap%offset, gap%y, ss, amp, tau_min, e)
    end function free_gap_zero

    !> The first minimum of y = amp exp(-b tau) cos(theta), with amp cos(phi) = cc and
    !> amp sin(phi) = ss, from now on: theta = pi - alpha (mod 2 pi), value
    !> -amp gam exp(-b tau); each minimum is shallower than the one before. In contact and not
    !> closing (`touching`), the minimum we sit at is not a new impact: the next one.
    pure function first_minimum(flow, cc, ss, touching) result(tau_min)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: cc, ss
        logical, intent(in) :: touching
        real(wp) :: tau_min

        tau_min = wrap_angle(pi - flow%alpha + phase_angle(cc, ss))*flow%inv_gam
        if (touching .and. tau_min < 0.5_wp*pi*flow%inv_gam) &
            tau_min = tau_min + two_pi*flow%inv_gam
    end function first_minimum

    !> modulo(x, two_pi) for -two_pi < x < 2 two_pi, bit for bit, without its call to fmod
    !> (fmod is exact there, and so are these sums by Sterbenz's lemma, except x + two_pi
    !> for x < 0, which is what modulo computes too).
    pure function wrap_angle(x) result(wrapped)
        real(wp), intent(in) :: x
        real(wp) :: wrapped

        wrapped = x
        if (wrapped < 0) then
            wrapped = wrapped + two_pi
        else if (wrapped >= two_pi) then
            wrapped = wrapped - two_pi
        end if
    end function wrap_angle

    !> The zero of c + y(tau) on the decreasing branch of y before its minimum at tau_min
    !> (where exp(-b tau_min) = e and c + y < 0), by Halley's method safeguarded by bisection.
    !> The iteration carries exp(-b tau), cos(theta) and sin(theta) along and updates them by
    !> the step (angle addition), so a search costs one atan2 and one acos (and look-ups in the
    !> flow's tables), whatever the steps.
    pure function halley_zero(flow, offset, cc, ss, amp, tau_min, e) result(root)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: offset, cc, ss, amp, tau_min, e
        real(wp) :: root
        real(wp) :: b, gam, lo, hi, tau, g, g1, g2, denom, step, q, decay, cos_th, sin_th
        integer :: it
        logical :: halley

        b = flow%damping
        gam = flow%gam
        lo = max(0.0_wp, tau_min - pi*flow%inv_gam)
        hi = tau_min
        ! first guess: the zero of the same (decreasing) branch with the decay frozen at
        ! tau_min, theta = acos(q); it lies at or after the true zero, whose |cos| is smaller
        q = max(-1.0_wp, -offset/(amp*e))
        cos_th = q
        sin_th = sqrt(max(0.0_wp, (1 - q)*(1 + q)))
        ! theta = acos(q), as the angle of (cos_th, sin_th)
        step = (pi - flow%alpha - phase_angle(cos_th, sin_th))*flow%inv_gam
        tau = tau_min - step
        decay = free_decay(flow%phases, tau)
        if (tau < lo .or. tau > hi) then
            tau = min(hi, max(lo, tau))
            call phase_at(flow, cc, ss, amp, tau, decay, cos_th, sin_th)
        end if
        do it = 1, 100
            g = offset + amp*decay*cos_th
            g1 = -amp*decay*(b*cos_th + gam*sin_th)
            g2 = -2*b*g1 - (g - offset)
            if (g > 0) then
                lo = tau
            else
                hi = tau
            end if
            if (hi - lo <= time_tolerance) then
                root = lo
                return
            end if
            ! Halley's step (cubic convergence; g'' comes free from the oscillator equation)
            denom = 2*g1**2 - g*g2
            step = huge(1.0_wp)
            if (denom /= 0) step = -2*g*g1/denom
            ! on the zero to within rounding (a step that would not even change tau)
            if (abs(step) <= 0.25_wp*time_tolerance) then
                root = min(hi, max(lo, tau))
                return
            end if
            halley = tau + step > lo .and. tau + step < hi
            if (halley) then
                ! cubic convergence on a transversal zero: after a Halley step this small the
                ! error is below 1e-15 (no need to evaluate there); near grazing (small slope)
                ! iterate to the tolerance instead
                if (abs(step) <= 1.0e-5_wp .and. abs(g1) >= 1.0e-3_wp*amp) then
                    root = min(hi, max(lo, tau + step))
                    return
                end if
                call advance_free_phase(flow%phases, step, decay, cos_th, sin_th)
                tau = tau + step
            else
                ! bisection: a fresh evaluation, no accumulated rotations
                step = 0.5_wp*(lo + hi) - tau
                tau = tau + step
                call phase_at(flow, cc, ss, amp, tau, decay, cos_th, sin_th)
                if (abs(step) <= 0.25_wp*time_tolerance) then
                    root = min(hi, max(lo, tau))
                    return
                end if
            end if
        end do
        root = lo
    end function halley_zero

    !> exp(-b t), cos(theta), sin(theta) at time t, from scratch (theta = gam t - phi,
    !> amp cos(phi) = cc, amp sin(phi) = ss).
    pure subroutine phase_at(flow, cc, ss, amp, t, decay, cos_th, sin_th)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: cc, ss, amp, t
        real(wp), intent(out) :: decay, cos_th, sin_th
        real(wp) :: cg, sg

        call free_phase(flow%phases, t, decay, cg, sg)
        cos_th = (cg*cc + sg*ss)/amp
        sin_th = (sg*cc - cg*ss)/amp
    end subroutine phase_at

    !> Zero of c + y(tau) + beta xp(s0 + tau) by Taylor-bounded conservative advancement.
    pure function forced_gap_zero(flow, gap, s0, horizon) result(res)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        real(wp), intent(in) :: s0, horizon
        type(gap_search_t) :: res
        real(wp) :: b, w, ry0, rp, tau, e, ry, g, g1, g2, g3, m2, m4, h, tol
        real(wp) :: cg, sg, cw, sw, y, vy, ay, jy, xp, vp
        integer :: it

        b = flow%damping
        w = flow%omega
        ry0 = free_amplitude(flow, gap)
        rp = abs(gap%beta)*flow%forced_amp
        tol = noise(gap%offset, ry0 + rp)
        tau = 0
        h = 0
        do it = 1, max_steps
            ! every step from the tables afresh: no rounding carried from step to step (the
            ! first is at the start, where the free part is the gap's own)
            if (it == 1) then
                e = 1
                y = gap%y
                vy = gap%vy
                call drive_phase(flow%phases, s0, cw, sw)
                call forced_response_at(flow, sw, cw, xp, vp)
            else
                call free_phase(flow%phases, tau, e, cg, sg)
                call drive_phase(flow%phases, s0 + tau, cw, sw)
                call motion_at(flow, e, cg, sg, sw, cw, gap%y, gap%vy, y, vy, xp, vp)
            end if
            ry = ry0*e
            if (gap%offset - ry - rp > 0) then
                res%status = search_none
                res%tau = huge(1.0_wp)
                return
            end if
            ay = -2*b*vy - y
            jy = -2*b*ay - vy
            g = gap%offset + y + gap%beta*xp
            g1 = vy + gap%beta*vp
            g2 = ay - gap%beta*w**2*xp
            g3 = jy - gap%beta*w**2*vp
            m2 = ry + w**2*rp
            m4 = ry + w**4*rp
            if (g <= tol) then
                if (g1 < 0) exit
                ! in contact and not closing: g, g1 >= 0 only help, so bound by the rest
                h = max(quadratic_step(max(g, 0.0_wp), g1, m2), quartic_step(g2, g3, m4, tol))
                if (h <= 0) exit
            else
                h = quadratic_step(g, g1, m2)
                if (g1 < 0 .and. h <= time_tolerance) exit
            end if
            if (tau + h >= horizon) then
                res%status = search_horizon
                res%tau = horizon
                return
            end if
            tau = tau + h
            ! far from contact, stop here and let the queue come back: a neighbour's impact
            ! may overwrite the prediction first (about a quarter of them on the paper's
            ! default chain), and the steps a longer search spends on those cost about what
            ! resuming the others costs (docs/performance.md)
            if (it >= lazy_steps .and. g > 0.25_wp*gap%offset) then
                res%status = search_horizon
                res%tau = tau
                return
            end if
        end do
        res%status = search_root
        res%tau = tau
        if (it > max_steps) res%info = 1
    end function forced_gap_zero

    !> Largest h with g + g1 h - m h**2/2 >= 0 on [0, h] (g >= 0, m > 0).
    pure function quadratic_step(g, g1, m) result(h)
        real(wp), intent(in) :: g, g1, m
        real(wp) :: h, disc

        disc = sqrt(g1**2 + 2*m*g)
        if (g1 >= 0) then
            h = (g1 + disc)/m
        else if (disc - g1 > 0) then
            h = 2*g/(disc - g1)
        else
            h = 0
        end if
    end function quadratic_step

    !> Largest h with g2/2 + g3 h/6 - m h**2/24 >= 0 on [0, h]; zero if the gap curls inwards.
    pure function quartic_step(g2, g3, m, tol) result(h)
        real(wp), intent(in) :: g2, g3, m, tol
        real(wp) :: h, g2c

        g2c = g2
        if (abs(g2c) <= tol) g2c = 0
        h = 0
        if (g2c < 0) return
        if (g2c == 0 .and. g3 <= 0) return
        h = (g3/6 + sqrt((g3/6)**2 + m*g2c/12))*12/m
    end function quartic_step

    !> The slowest approach a gap search can resolve. A gap that closes at speed u with
    !> curvature g'' (its second derivative at contact) turns round u**2 / (2 |g''|) beyond
    !> zero: an impact slower than sqrt(2 |g''| noise) is one whose very existence is decided by
    !> the rounding of the gap, and whose saltation matrix (terms of size 1/u) describes
    !> perturbations smaller than that rounding. The engine's touch and stick rules use it.
    pure function resolvable_speed(flow, gap, curvature) result(u_min)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        real(wp), intent(in) :: curvature !! g'' at contact
        real(wp) :: u_min

        u_min = sqrt(2*abs(curvature)*noise(gap%offset, gap_amplitude(flow, gap)))
    end function resolvable_speed

    !> Is an approach at speed u > 0 surely not below resolvable_speed? A bound without its two
    !> square roots (r <= |y| + |q|, and a factor 2 over the rounding of either form): nearly
    !> every impact is far faster than the rounding level, and only a doubtful one needs
    !> resolvable_speed itself.
    pure logical function surely_resolvable(flow, gap, curvature, u)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        real(wp), intent(in) :: curvature, u
        real(wp) :: q

        q = (gap%vy + flow%damping*gap%y)*flow%inv_gam
        surely_resolvable = u > 0 .and. u*u > 4*abs(curvature)*noise(gap%offset, abs(gap%y) + &
                                                      abs(q) + abs(gap%beta)*flow%forced_amp)
    end function surely_resolvable

    !> Size of the moving terms of a gap: its free oscillation and its share of the drive (the
    !> amplitude that sets the rounding level of the gap in every search).
    pure function gap_amplitude(flow, gap) result(amp)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        real(wp) :: amp

        amp = free_amplitude(flow, gap) + abs(gap%beta)*flow%forced_amp
    end function gap_amplitude

    !> Rounding level of a gap built from terms of size `offset` and `amplitude`.
    pure function noise(offset, amplitude) result(tol)
        real(wp), intent(in) :: offset, amplitude
        real(wp) :: tol

        tol = 64*epsilon(1.0_wp)*(abs(offset) + amplitude)
    end function noise

    !> For an opening free pair gap (beta = 0, y' > 0): a time before which it cannot close.
    !> The gap's curvature is bounded by the amplitude r of its free oscillation, so
    !> g(tau) >= g(0) + y' tau - r tau**2 / 2 >= g(0) up to tau = 2 y' / r.
    pure function earliest_closing(flow, gap) result(tau)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        real(wp) :: tau

        tau = 2*gap%vy/free_amplitude(flow, gap)
    end function earliest_closing

    !> The amplitude-phase form y(tau) = r exp(-b tau) cos(gam tau - phi) of the free part of
    !> a gap (docs/model.md section 2.2): r, and q = r sin(phi) (r cos(phi) is y(0)).
    pure subroutine amplitude_phase(flow, y, vy, r, q)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: y, vy
        real(wp), intent(out) :: r, q

        q = (vy + flow%damping*y)*flow%inv_gam
        r = sqrt(y**2 + q**2)
    end subroutine amplitude_phase

    !> r of amplitude_phase for the free part of a gap.
    pure function free_amplitude(flow, gap) result(r)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        real(wp) :: r, q

        call amplitude_phase(flow, gap%y, gap%vy, r, q)
    end function free_amplitude

end module chain_gaps
