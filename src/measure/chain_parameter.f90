!> The exact derivative of the p-cycle stroboscopic map in one of the model's parameters
!> (docs/model.md section 12.2): an extra tangent column carried through the closed-form flow
!> between events and through every impact.
!>
!> Between events each oscillator moves as z(s) = zp(s) + M(s - s_a) (z_a - zp(s_a)), so the
!> column w = dz/dmu moves as w <- M w + dzp/dmu(s) - M dzp/dmu(s_a) + dM/dmu (z_a - zp(s_a)).
!> At an impact it jumps like any tangent vector (the saltation matrix S) plus the impact's own
!> dependence on the parameter: dR/dmu + (f+ - DR f-) (dh/dmu) / (grad h . f-). In omega the
!> section's time phase / w and the map's duration p 2 pi / w move too, which adds
!> f(z_end) dt_end/dw - J f(z_0) dt_0/dw.
module chain_parameter
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int
    use chain_model, only: model_t, is_model_parameter
    use chain_flow, only: flow_t, make_flow, propagator, forced_response, advance_state, &
                          acceleration_at
    use chain_impact, only: pair_reset_jacobian, wall_reset_jacobian, saltation_matrix
    use chain_engine, only: chain_t, chain_positions, chain_velocities, chain_next_event, &
                            chain_advance, chain_sync, chain_new_cycle, chain_cycle, &
                            chain_time, chain_period
    use chain_event_log, only: event_log_t, event_log_init, event_log_clear, event_impact, &
                               event_touch
    use chain_section, only: chain_at_section
    implicit none
    private
    public :: map_parameter_derivative

contains

    !> d P^p(z) / d mu at the state z = (x, v) on the section `phase` (interleaved order, as the
    !> Jacobian's rows), for parameter `parameter`; `jacobian`, the p-cycle Jacobian there, is
    !> needed for omega only. Every oscillator must move freely over the p cycles (no rest), and
    !> no oscillator may take part in two impacts of one instant (a triple contact): both are
    !> errors here.
    subroutine map_parameter_derivative(model, phase, cycles, x, v, parameter, jacobian, &
                                        derivative, err)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase
        integer, intent(in) :: cycles
        real(wp), intent(in) :: x(:), v(:)
        character(len=*), intent(in) :: parameter
        real(wp), intent(in) :: jacobian(:, :)
        real(wp), allocatable, intent(out) :: derivative(:)
        type(error_t), allocatable, intent(out) :: err
        type(chain_t) :: chain
        type(flow_t) :: flow
        type(event_log_t) :: log
        real(wp), allocatable :: xa(:), va(:), xb(:), vb(:)
        real(wp) :: s_a, s_stop, s_end, s_section, period, t0, t1
        integer :: next_bond, i
        integer(i8) :: last_cycle

        if (.not. is_model_parameter(parameter)) then
            call set_error(err, "parameter derivative: unknown parameter '"//parameter//"'")
            return
        end if
        flow = make_flow(model%damping, model%amplitude, model%omega)
        call chain_at_section(model, phase, x, v, chain, err)
        if (allocated(err)) return
        call event_log_init(log, .true., 16)
        period = chain_period(chain)
        s_section = chain_time(chain)
        last_cycle = chain_cycle(chain) + cycles
        allocate (derivative(2*model%n))
        derivative = 0
        xa = x
        va = v
        s_a = s_section
        do
            s_end = period
            if (chain_cycle(chain) == last_cycle) s_end = s_section
            call chain_next_event(chain, next_bond, s_stop)
            s_stop = min(s_stop, s_end)
            call flow_column(model, flow, parameter, real(chain_cycle(chain), wp)*period, s_a, &
                             s_stop - s_a, xa, va, derivative)
            xb = xa
            vb = va
            do i = 1, model%n
                call advance_state(flow, s_a, s_stop - s_a, xb(i), vb(i))
            end do
            call event_log_clear(log)
            call chain_advance(chain, s_stop, log, err)
            if (allocated(err)) return
            call chain_sync(chain)
            xa = chain_positions(chain)
            va = chain_velocities(chain)
            call jump_column(model, flow, parameter, log, s_stop, xb, vb, va, derivative, err)
            if (allocated(err)) return
            s_a = s_stop
            if (s_stop == s_end) then
                if (chain_cycle(chain) == last_cycle) exit
                call chain_new_cycle(chain)
                s_a = 0
            end if
        end do
        if (parameter == 'omega') then
            ! t0 = phase / w and t1 = t0 + p T both scale as 1 / w: dt/dw = -t / w
            t0 = s_section
            t1 = s_section + cycles*period
            derivative = derivative - vector_field(flow, s_section, xa, va)*t1/model%omega &
                         + matmul(jacobian, vector_field(flow, s_section, x, v))*t0/model%omega
        end if
    end subroutine map_parameter_derivative

    !> The column over a free flight of every oscillator from (x, v) at in-cycle time s0 of a
    !> cycle that began at time `cycle_start` (needed in omega: its drive sin(w t) depends on
    !> the whole time t), over a time h.
    pure subroutine flow_column(model, flow, parameter, cycle_start, s0, h, x, v, w)
        type(model_t), intent(in) :: model
        type(flow_t), intent(in) :: flow
        character(len=*), intent(in) :: parameter
        real(wp), intent(in) :: cycle_start, s0, h, x(:), v(:)
        real(wp), intent(inout) :: w(:)
        real(wp) :: m(2, 2), m_b(2, 2), drive(2), d0(2), d1(2), xp, vp, a, b
        integer :: i

        m = propagator(flow, h)
        drive = 0
        if (parameter == 'amplitude' .or. parameter == 'omega' .or. parameter == 'damping') then
            d0 = forced_derivative(flow, parameter, cycle_start, s0)
            d1 = forced_derivative(flow, parameter, cycle_start, s0 + h)
            drive = d1 - matmul(m, d0)
        end if
        if (parameter == 'damping') m_b = propagator_damping_derivative(flow, h)
        call forced_response(flow, s0, xp, vp)
        do i = 1, model%n
            a = w(2*i - 1)
            b = w(2*i)
            w(2*i - 1) = m(1, 1)*a + m(1, 2)*b + drive(1)
            w(2*i) = m(2, 1)*a + m(2, 2)*b + drive(2)
            if (parameter == 'damping') then
                w(2*i - 1:2*i) = w(2*i - 1:2*i) + matmul(m_b, [x(i) - xp, v(i) - vp])
            end if
        end do
    end subroutine flow_column

    !> The jump of the column at the impacts of one instant (in log), from the states just
    !> before (xb, vb) to the velocities just after (va).
    subroutine jump_column(model, flow, parameter, log, s, xb, vb, va, w, err)
        type(model_t), intent(in) :: model
        type(flow_t), intent(in) :: flow
        character(len=*), intent(in) :: parameter
        type(event_log_t), intent(in) :: log
        real(wp), intent(in) :: s, xb(:), vb(:), va(:)
        real(wp), intent(inout) :: w(:)
        type(error_t), allocatable, intent(out) :: err
        logical :: hit(model%n)
        real(wp) :: sin_wt
        integer :: e, bond, first, last

        hit = .false.
        sin_wt = sin(model%omega*s)
        do e = 1, log%count
            if (log%kind(e) == event_touch) cycle ! no impulse, no jump (section 5.8)
            if (log%kind(e) /= event_impact) then
                call set_error(err, "parameter derivative: an oscillator comes to rest on "// &
                               "a wall (not supported)")
                return
            end if
            bond = log%site(e)
            first = max(bond, 1)
            last = min(bond + 1, model%n)
            if (any(hit(first:last))) then
                call set_error(err, "parameter derivative: oscillator "//fmt_int(first)// &
                               " takes part in two impacts of one instant (not supported)")
                return
            end if
            hit(first:last) = .true.
            call impact_jump(model, flow, parameter, bond, sin_wt, xb(first:last), &
                             vb(first:last), va(first:last), w(2*first - 1:2*last))
        end do
    end subroutine jump_column

    !> One impact on `bond`: w <- S w + dR/dmu + (f+ - DR f-) (dh/dmu) / (grad h . f-), on the
    !> rows of the one or two oscillators it involves (x, v: their states before; va: their
    !> velocities after).
    pure subroutine impact_jump(model, flow, parameter, bond, sin_wt, x, v, va, w)
        type(model_t), intent(in) :: model
        type(flow_t), intent(in) :: flow
        character(len=*), intent(in) :: parameter
        integer, intent(in) :: bond
        real(wp), intent(in) :: sin_wt, x(:), v(:), va(:)
        real(wp), intent(inout) :: w(:)
        real(wp) :: dr(size(w), size(w)), salt(size(w), size(w))
        real(wp) :: f_minus(size(w)), f_plus(size(w)), grad_h(size(w)), reset_mu(size(w))
        real(wp) :: rate
        integer :: j, info

        do j = 1, size(x)
            f_minus(2*j - 1:2*j) = [v(j), acceleration_at(flow, sin_wt, x(j), v(j))]
            f_plus(2*j - 1:2*j) = [va(j), acceleration_at(flow, sin_wt, x(j), va(j))]
        end do
        reset_mu = 0
        if (size(x) == 2) then
            dr = pair_reset_jacobian(model%restitution)
            grad_h = [-1.0_wp, 0.0_wp, 1.0_wp, 0.0_wp]
            ! dv+/dK: each takes half the approach speed more
            if (parameter == 'restitution') reset_mu = [0.0_wp, (v(2) - v(1))/2, 0.0_wp, &
                                                        (v(1) - v(2))/2]
        else
            dr = wall_reset_jacobian(model%restitution)
            grad_h = [1.0_wp, 0.0_wp]
            if (bond > 0) grad_h = -grad_h
            if (parameter == 'restitution') reset_mu = [0.0_wp, -v(1)]
        end if
        call saltation_matrix(dr, f_minus, f_plus, grad_h, salt, info)
        w = matmul(salt, w) + reset_mu
        ! dh/dmu: every bond's rest gap is the spacing
        if (parameter == 'spacing' .and. info == 0) then
            rate = dot_product(grad_h, f_minus)
            w = w + (f_plus - matmul(dr, f_minus))/rate
        end if
    end subroutine impact_jump

    !> (dx_p/dmu, dv_p/dmu) of the forced steady state xp = P sin(w t) + Q cos(w t) at in-cycle
    !> time s of a cycle that began at time cycle_start (section 12.2).
    pure function forced_derivative(flow, parameter, cycle_start, s) result(d)
        type(flow_t), intent(in) :: flow
        character(len=*), intent(in) :: parameter
        real(wp), intent(in) :: cycle_start, s
        real(wp) :: d(2)
        real(wp) :: w, b, amp, den, den_mu, p_mu, q_mu, sn, cs, t, p, q

        w = flow%omega
        b = flow%damping
        amp = flow%amplitude
        p = flow%p_sin
        q = flow%q_cos
        den = (1 - w**2)**2 + (2*b*w)**2
        sn = sin(w*s)
        cs = cos(w*s)
        select case (parameter)
        case ('amplitude')
            p_mu = (1 - w**2)/den
            q_mu = -2*b*w/den
        case ('damping')
            den_mu = 8*b*w**2
            p_mu = -amp*(1 - w**2)*den_mu/den**2
            q_mu = -2*w*amp/den + 2*b*w*amp*den_mu/den**2
        case default ! omega
            den_mu = -4*w*(1 - w**2) + 8*b**2*w
            p_mu = -2*w*amp/den - amp*(1 - w**2)*den_mu/den**2
            q_mu = -2*b*amp/den + 2*b*w*amp*den_mu/den**2
        end select
        d(1) = p_mu*sn + q_mu*cs
        d(2) = w*(p_mu*cs - q_mu*sn)
        if (parameter == 'omega') then
            ! sin(w t) and cos(w t) move with w at fixed t = cycle_start + s
            t = cycle_start + s
            d(1) = d(1) + t*(p*cs - q*sn)
            d(2) = d(2) + (p*cs - q*sn) - w*t*(p*sn + q*cs)
        end if
    end function forced_derivative

    !> dM/db of the propagator M(h) = exp(-b h) [[c + b sn, sn], [-sn, c - b sn]], c =
    !> cos(gam h), sn = sin(gam h) / gam, gam = sqrt(1 - b**2).
    pure function propagator_damping_derivative(flow, h) result(m_b)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: h
        real(wp) :: m_b(2, 2)
        real(wp) :: b, gam, c, sg, sn, c_b, sn_b, r(2, 2), r_b(2, 2)

        b = flow%damping
        gam = flow%gam
        c = cos(gam*h)
        sg = sin(gam*h)
        sn = sg/gam
        ! dgam/db = -b / gam
        c_b = sg*h*b/gam
        sn_b = -b*(h*c - sn)/gam**2
        r = reshape([c + b*sn, -sn, sn, c - b*sn], [2, 2])
        r_b = reshape([c_b + sn + b*sn_b, -sn_b, sn_b, c_b - sn - b*sn_b], [2, 2])
        m_b = exp(-b*h)*(r_b - h*r)
    end function propagator_damping_derivative

    !> f(z) = (v, a) of every oscillator at in-cycle time s, interleaved.
    pure function vector_field(flow, s, x, v) result(f)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: s, x(:), v(:)
        real(wp) :: f(2*size(x))
        real(wp) :: sin_wt
        integer :: i

        sin_wt = sin(flow%omega*s)
        do i = 1, size(x)
            f(2*i - 1) = v(i)
            f(2*i) = acceleration_at(flow, sin_wt, x(i), v(i))
        end do
    end function vector_field

end module chain_parameter
