!> Periodic orbits of the stroboscopic map (docs/model.md section 11): Newton shooting for a
!> fixed point of P^p, the map over p drive cycles from the section (drive phase `phase`) to
!> itself, with the exact Jacobian of the tangent dynamics; and what is reported of an orbit:
!> its Floquet multipliers, its events over one period, and two grazing monitors (the
!> smallest impact speed, the smallest gap at a local minimum away from the bond's own
!> contacts).
!>
!> A state z is interleaved, z = (x(1), v(1), ..., x(n), v(n)), as the rows and columns of the
!> Jacobian (section 4). A failure of Newton is a result (converged = .false. and a reason),
!> never an error; errors are bad arguments and failures of the engine or of LAPACK.
module chain_orbit
    use chain_kinds, only: wp, i8, two_pi
    use chain_error, only: error_t, set_error, fmt_int
    use chain_model, only: model_t, bond_gaps
    use chain_flow, only: flow_t, make_flow, propagator, forced_response
    use chain_engine, only: chain_t, chain_positions, chain_velocities, chain_next_event, &
                            chain_advance, chain_sync, chain_new_cycle, chain_cycle, chain_time, &
                            chain_period
    use chain_event_log, only: event_log_t, event_log_init, event_log_clear, event_impact, &
                               event_stick
    use chain_section, only: chain_at_section
    use chain_floquet, only: advance_with_jacobian, floquet_multipliers, pass_end
    use chain_lapack, only: solve_linear
    implicit none
    private
    public :: orbit_t, orbit_options_t, find_orbit, orbit_gap_minimum, interleave
    public :: multiplier_distance
    public :: orbit_pass_t, orbit_pass, pass_refusal, describe_orbit, impact_bonds, pass_impacts

    !> How Newton is run.
    type :: orbit_options_t
        !> stop when |P^p(z) - z|_inf <= tolerance (1 + |z|_inf)
        real(wp) :: tolerance = 1.0e-11_wp
        integer :: max_iterations = 40 !! Newton steps
        integer :: max_halvings = 12   !! halvings of a step whose residual does not decrease
    end type orbit_options_t

    !> A periodic orbit (or Newton's last iterate, when it did not converge).
    type :: orbit_t
        logical :: converged = .false.
        !> why Newton stopped without converging ('' when it converged)
        character(len=:), allocatable :: reason
        integer :: cycles = 1               !! p: drive cycles per period
        real(wp) :: phase = 0               !! drive phase of the section
        integer :: iterations = 0           !! Newton steps taken
        !> residuals(0:iterations): |P^p(z) - z|_inf / (1 + |z|_inf) of each iterate
        real(wp), allocatable :: residuals(:)
        real(wp), allocatable :: x(:), v(:) !! x(n), v(n): the last iterate, on the section
        real(wp), allocatable :: jacobian(:, :) !! (2n, 2n): of P^p there, interleaved order
        !> (2n): the Floquet multipliers, eigenvalues of the Jacobian (set when converged)
        real(wp), allocatable :: multipliers_re(:), multipliers_im(:)
        integer :: impacts = 0              !! c: impacts per period
        !> The events of one period in time order: impacts and touches (section 5.8)
        integer, allocatable :: event_bond(:), event_kind(:)
        real(wp), allocatable :: event_time(:)  !! since the section
        real(wp), allocatable :: event_speed(:) !! approach speed
        real(wp) :: min_impact_speed = huge(1.0_wp) !! over the impacts (huge: none)
        !> The smallest gap at a local minimum, other than the bond's own impacts (huge:
        !> none), its bond and its time since the section (set when converged)
        real(wp) :: min_gap = huge(1.0_wp)
        integer :: min_gap_bond = -1
        real(wp) :: min_gap_time = 0
    end type orbit_t

    !> One pass of p cycles from a state z.
    type :: orbit_pass_t
        logical :: admissible = .false. !! z has no negative gap (else nothing else is set)
        logical :: rests = .false.      !! an oscillator came to rest during the pass
        logical :: collapse = .false.   !! the cluster rule acted (an impact of speed 0)
        real(wp), allocatable :: z(:), image(:) !! z and P^p(z)
        real(wp), allocatable :: jacobian(:, :)
        real(wp) :: residual = huge(1.0_wp)
        type(event_log_t) :: log
    end type orbit_pass_t

contains

    !> Newton shooting for a period-p orbit of the map on the section `phase` (drive phase,
    !> [0, 2 pi)), from the guess (x, v). Newton on F(z) = P^p(z) - z with DF = J - I, J the
    !> exact p-cycle Jacobian; a step whose residual does not decrease is halved.
    subroutine find_orbit(model, phase, cycles, x, v, orbit, err, options)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase
        integer, intent(in) :: cycles
        real(wp), intent(in) :: x(:), v(:)
        type(orbit_t), intent(out) :: orbit
        type(error_t), allocatable, intent(out) :: err
        type(orbit_options_t), intent(in), optional :: options
        type(orbit_options_t) :: opt
        type(orbit_pass_t) :: now, trial
        real(wp), allocatable :: a(:, :), step(:, :), history(:)
        real(wp) :: lambda
        integer :: m, i, halvings, info

        if (present(options)) opt = options
        call check_arguments(model, phase, cycles, x, v, opt, err)
        if (allocated(err)) return
        m = 2*model%n
        orbit%cycles = cycles
        orbit%phase = phase
        orbit%reason = ''
        call orbit_pass(model, phase, cycles, interleave(x, v), now, err)
        if (allocated(err)) return
        if (.not. now%admissible) then
            call set_error(err, "orbit: the starting guess has a negative gap (oscillators "// &
                           "overlap a neighbour or a wall)")
            return
        end if
        allocate (history(0:opt%max_iterations))
        history(0) = now%residual
        do
            if (now%rests) then
                orbit%reason = "the orbit sticks on a wall (rest): not supported"
                exit
            end if
            if (now%collapse) then
                orbit%reason = "the cluster rule acts on the orbit (inelastic collapse): "// &
                               "not supported"
                exit
            end if
            if (now%residual <= opt%tolerance) then
                orbit%converged = .true.
                exit
            end if
            if (orbit%iterations == opt%max_iterations) then
                orbit%reason = "did not converge in "//fmt_int(opt%max_iterations)// &
                               " iterations"
                exit
            end if
            a = now%jacobian
            do i = 1, m
                a(i, i) = a(i, i) - 1
            end do
            step = reshape(now%z - now%image, [m, 1])
            call solve_linear(a, step, info)
            if (info > 0) then
                orbit%reason = "singular Jacobian (a multiplier at +1: fold?)"
                exit
            end if
            lambda = 1
            do halvings = 0, opt%max_halvings
                call orbit_pass(model, phase, cycles, now%z + lambda*step(:, 1), trial, err)
                if (allocated(err)) return
                if (trial%admissible .and. trial%residual < now%residual) exit
                lambda = lambda/2
            end do
            if (halvings > opt%max_halvings) then
                orbit%reason = "no decrease of the residual along the Newton step (halved "// &
                               fmt_int(opt%max_halvings)//" times): a non-smooth map "// &
                               "(grazing) or the rounding floor"
                exit
            end if
            now = trial
            orbit%iterations = orbit%iterations + 1
            history(orbit%iterations) = now%residual
        end do
        allocate (orbit%residuals(0:orbit%iterations))
        orbit%residuals = history(0:orbit%iterations)
        call describe_orbit(model, now, orbit, err)
    end subroutine find_orbit

    !> Refuse arguments no orbit can have.
    subroutine check_arguments(model, phase, cycles, x, v, opt, err)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase
        integer, intent(in) :: cycles
        real(wp), intent(in) :: x(:), v(:)
        type(orbit_options_t), intent(in) :: opt
        type(error_t), allocatable, intent(out) :: err

        if (size(x) /= model%n .or. size(v) /= model%n) then
            call set_error(err, "orbit: the guess has "//fmt_int(size(x))//" positions and "// &
                           fmt_int(size(v))//" velocities for a chain of n = "// &
                           fmt_int(model%n))
        else if (.not. (phase >= 0 .and. phase < two_pi)) then
            call set_error(err, "orbit: the section's drive phase is outside [0, 2 pi)")
        else if (cycles < 1) then
            call set_error(err, "orbit: cycles = "//fmt_int(cycles)//" is not >= 1")
        else if (.not. opt%tolerance > 0 .or. opt%max_iterations < 0 .or. &
                 opt%max_halvings < 0) then
            call set_error(err, "orbit: the options need tolerance > 0, max_iterations >= 0 "// &
                           "and max_halvings >= 0")
        end if
    end subroutine check_arguments

    !> The p-cycle map and its Jacobian at z, and the events on the way: one pass of a fresh
    !> chain on the section with the identity frame.
    subroutine orbit_pass(model, phase, cycles, z, pass, err)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase, z(:)
        integer, intent(in) :: cycles
        type(orbit_pass_t), intent(out) :: pass
        type(error_t), allocatable, intent(out) :: err
        type(chain_t) :: chain

        pass%z = z
        pass%admissible = .not. any(bond_gaps(model%spacing, model%walls, z(1::2)) < 0)
        if (.not. pass%admissible) return
        call chain_at_section(model, phase, z(1::2), z(2::2), chain, err)
        if (allocated(err)) return
        call event_log_init(pass%log, .true., 64)
        call advance_with_jacobian(chain, cycles, pass%log, pass%jacobian, err)
        if (allocated(err)) return
        pass%image = interleave(chain_positions(chain), chain_velocities(chain))
        call pass_end(chain, pass%log, pass%rests, pass%collapse)
        pass%residual = maxval(abs(pass%image - z))/(1 + maxval(abs(z)))
    end subroutine orbit_pass

    !> Why a continuation's Newton cannot use this pass (a negative gap, a rest, the cluster
    !> rule), or '' when it can.
    pure function pass_refusal(pass) result(refusal)
        type(orbit_pass_t), intent(in) :: pass
        character(len=:), allocatable :: refusal

        if (.not. pass%admissible) then
            refusal = "a negative gap"
        else if (pass%rests) then
            refusal = "the orbit sticks on a wall (rest): not supported"
        else if (pass%collapse) then
            refusal = "the cluster rule acts on the orbit: not supported"
        else
            refusal = ''
        end if
    end function pass_refusal

    !> The orbit's state, Jacobian, events and, when converged, multipliers and gap monitor.
    subroutine describe_orbit(model, pass, orbit, err)
        type(model_t), intent(in) :: model
        type(orbit_pass_t), intent(in) :: pass
        type(orbit_t), intent(inout) :: orbit
        type(error_t), allocatable, intent(out) :: err
        logical, allocatable :: impact(:)
        integer :: info

        orbit%x = pass%z(1::2)
        orbit%v = pass%z(2::2)
        orbit%jacobian = pass%jacobian
        associate (log => pass%log)
            orbit%event_bond = log%site(:log%count)
            orbit%event_kind = log%kind(:log%count)
            orbit%event_time = log%time(:log%count)
            orbit%event_speed = log%speed(:log%count)
        end associate
        impact = counts_as_impact(orbit%event_kind, orbit%event_speed)
        orbit%impacts = count(impact)
        if (orbit%impacts > 0) orbit%min_impact_speed = minval(orbit%event_speed, mask=impact)
        if (.not. orbit%converged) return
        allocate (orbit%multipliers_re(2*model%n), orbit%multipliers_im(2*model%n))
        call floquet_multipliers(orbit%jacobian, orbit%multipliers_re, orbit%multipliers_im, &
                                 info)
        if (info /= 0) then
            call set_error(err, "orbit: the eigenvalue solver (LAPACK dgeev) failed")
            return
        end if
        call orbit_gap_minimum(model, orbit%phase, orbit%cycles, orbit%x, orbit%v, &
                               orbit%min_gap, orbit%min_gap_bond, orbit%min_gap_time, err)
    end subroutine describe_orbit

    !> What counts as an impact among an orbit's events (section 5.8): an ordinary impact, or
    !> one that ends chatter at a nonzero speed.
    elemental logical function counts_as_impact(kind, speed)
        integer, intent(in) :: kind
        real(wp), intent(in) :: speed

        counts_as_impact = kind == event_impact .or. (kind == event_stick .and. speed > 0)
    end function counts_as_impact

    !> The bonds of the orbit's impacts over one period, in time order (orbit%impacts of them).
    pure function impact_bonds(orbit) result(bonds)
        type(orbit_t), intent(in) :: orbit
        integer, allocatable :: bonds(:)

        bonds = pack(orbit%event_bond, counts_as_impact(orbit%event_kind, orbit%event_speed))
    end function impact_bonds

    !> The distance from `target` of the orbit's multiplier nearest to it.
    pure real(wp) function multiplier_distance(orbit, target)
        type(orbit_t), intent(in) :: orbit
        real(wp), intent(in) :: target

        multiplier_distance = minval(abs(cmplx(orbit%multipliers_re - target, &
                                               orbit%multipliers_im, wp)))
    end function multiplier_distance

    !> The bonds of a pass's impacts in time order (what counts as one as in impact_bonds).
    pure function pass_impacts(pass) result(bonds)
        type(orbit_pass_t), intent(in) :: pass
        integer, allocatable :: bonds(:)

        associate (log => pass%log)
            bonds = pack(log%site(:log%count), counts_as_impact(log%kind(:log%count), &
                                                                log%speed(:log%count)))
        end associate
    end function pass_impacts

    ! ------------------------------------------------------------------ the gap monitor

    !> The smallest gap over p cycles from (x, v) on the section, at the local minima of every
    !> bond's gap other than the instants of that bond's own impacts (where it is zero): zero
    !> where a new impact is about to appear. Between events each gap is the closed form of
    !> docs/model.md 2.3; its minima inside an interval are the zeros of its rate where the
    !> rate rises through zero, found by subdivision with bounds on the second and third
    !> derivatives (so none is missed) and bisection; at an event instant the gap has a
    !> local minimum when its rate is <= 0 just before and >= 0 just after. `bond` is -1 and
    !> `gap` huge when no gap has a local minimum (no bond closes, free ends with n = 1).
    !> (x, v) is meant to lie on a period-p orbit: the state after the p cycles stands for the
    !> start, so that a minimum at the section is seen. The chain must not rest on a wall
    !> (unsupported: the gaps would not be those of interval_minima). With `only`, bond `only`
    !> alone is looked at (a grazing curve follows one bond: the smallest of two equal gaps,
    !> a mirror pair's, has no derivative). `impacts`: the bonds of the impacts on the way, in
    !> time order (as pass_impacts has them).
    subroutine orbit_gap_minimum(model, phase, cycles, x, v, gap, bond, time, err, only, impacts)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase
        integer, intent(in) :: cycles
        real(wp), intent(in) :: x(:), v(:)
        real(wp), intent(out) :: gap, time
        integer, intent(out) :: bond
        type(error_t), allocatable, intent(out) :: err
        integer, intent(in), optional :: only
        integer, allocatable, intent(out), optional :: impacts(:)
        type(chain_t) :: chain
        type(flow_t) :: flow
        type(event_log_t) :: log
        real(wp), allocatable :: xa(:), va(:), xb(:), vb(:)
        real(wp) :: rate_before(0:model%n), rate_after(0:model%n), values(0:model%n)
        logical :: own(0:model%n), watched(0:model%n)
        real(wp) :: s_a, s_stop, s_end, s_section, elapsed, period
        integer :: k, e, next_bond
        integer(i8) :: last_cycle

        gap = huge(1.0_wp)
        bond = -1
        time = 0
        watched = .true.
        if (present(impacts)) allocate (impacts(0))
        if (present(only)) watched = [(k == only, k=0, model%n)]
        flow = make_flow(model%damping, model%amplitude, model%omega)
        call chain_at_section(model, phase, x, v, chain, err)
        if (allocated(err)) return
        call event_log_init(log, .true., 16)
        period = chain_period(chain)
        s_section = chain_time(chain)
        last_cycle = chain_cycle(chain) + cycles
        xa = x
        va = v
        s_a = s_section
        elapsed = 0
        do
            s_end = period
            if (chain_cycle(chain) == last_cycle) s_end = s_section
            call chain_next_event(chain, next_bond, s_stop)
            s_stop = min(s_stop, s_end)
            call interval_minima(model, flow, s_a, s_stop - s_a, xa, va, elapsed, watched, gap, &
                                 bond, time)
            ! the state just before the events at s_stop, and just after them
            call flow_state(flow, s_a, s_stop - s_a, xa, va, xb, vb)
            call event_log_clear(log)
            call chain_advance(chain, s_stop, log, err)
            if (allocated(err)) return
            call chain_sync(chain)
            xa = chain_positions(chain)
            va = chain_velocities(chain)
            elapsed = elapsed + (s_stop - s_a)
            own = .false.
            do e = 1, log%count
                if (log%kind(e) == event_impact .or. log%kind(e) == event_stick) &
                    own(log%site(e)) = .true.
                if (present(impacts)) then
                    if (counts_as_impact(log%kind(e), log%speed(e))) &
                        impacts = [impacts, log%site(e)]
                end if
            end do
            rate_before = gap_rates(model, vb)
            rate_after = gap_rates(model, va)
            values = bond_gaps(model%spacing, model%walls, xa)
            do k = 0, model%n
                if (own(k) .or. .not. watched(k) .or. abs(values(k)) == huge(1.0_wp)) cycle
                if (rate_before(k) <= 0 .and. rate_after(k) >= 0 .and. values(k) < gap) then
                    gap = values(k)
                    bond = k
                    time = elapsed
                end if
            end do
            s_a = s_stop
            if (s_stop == s_end) then
                if (chain_cycle(chain) == last_cycle) exit
                call chain_new_cycle(chain)
                s_a = 0
            end if
        end do
        ! the end of the period is its start: a minimum found there is at time 0
        if (time >= cycles*period - 1.0e-12_wp*period) time = 0
    end subroutine orbit_gap_minimum

    !> Local minima of every watched gap inside (0, h) from the state (x, v) at in-cycle time
    !> s0 (every oscillator moving): the smallest below `gap` replaces it, with its bond and
    !> time `elapsed` + tau.
    subroutine interval_minima(model, flow, s0, h, x, v, elapsed, watched, gap, bond, time)
        type(model_t), intent(in) :: model
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: s0, h, x(:), v(:), elapsed
        logical, intent(in) :: watched(0:)
        real(wp), intent(inout) :: gap, time
        integer, intent(inout) :: bond
        real(wp) :: xp, vp, c, y, vy, beta, tau, g, bond_spacing(0:model%n)
        integer :: k, n, first, last
        logical :: found

        if (.not. h > 0) return
        n = model%n
        bond_spacing = model%spacing
        call forced_response(flow, s0, xp, vp)
        first = merge(0, 1, model%walls)
        last = merge(n, n - 1, model%walls)
        do k = first, last
            if (.not. watched(k)) cycle
            call free_gap(bond_spacing, k, x - xp, v - vp, c, y, vy, beta)
            call gap_minimum(flow, c, y, vy, beta, s0, h, found, tau, g)
            if (found .and. g < gap) then
                gap = g
                bond = k
                time = elapsed + tau
            end if
        end do
    end subroutine interval_minima

    !> Bond k's gap as c + y(tau) + beta xp(s0 + tau) (section 2.3) from the free parts
    !> (x - xp, v - vp) of the moving oscillators.
    pure subroutine free_gap(spacing, k, y_osc, vy_osc, c, y, vy, beta)
        real(wp), intent(in) :: spacing(0:) !! a(0:n)
        integer, intent(in) :: k
        real(wp), intent(in) :: y_osc(:), vy_osc(:)
        real(wp), intent(out) :: c, y, vy, beta
        integer :: n

        n = size(y_osc)
        c = spacing(k)
        if (k == 0) then
            y = y_osc(1)
            vy = vy_osc(1)
            beta = 1
        else if (k == n) then
            y = -y_osc(n)
            vy = -vy_osc(n)
            beta = -1
        else
            y = y_osc(k + 1) - y_osc(k)
            vy = vy_osc(k + 1) - vy_osc(k)
            beta = 0
        end if
    end subroutine free_gap

    !> The smallest local minimum of g(tau) = c + y(tau) + beta xp(s0 + tau) inside (0, h),
    !> if any. The m-th derivative of a free oscillation of amplitude r (section 2.2) is at
    !> most r (|-b + i gam| = 1), and of xp at most w**m |xp|, so |g''| <= d2 and
    !> |g'''| <= d3 below. A piece [t0, t0 + l] holds no zero of g' if |g'(t0)| > l d2, and at
    !> most one (g' monotone) if |g''(t0)| > l d3; other pieces are halved. A minimum is where
    !> a monotone g' rises through zero, refined by bisection.
    pure subroutine gap_minimum(flow, c, y, vy, beta, s0, h, found, tau, g)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: c, y, vy, beta, s0, h
        logical, intent(out) :: found
        real(wp), intent(out) :: tau, g
        integer, parameter :: max_pieces = 4096
        real(wp) :: r, d2, d3, lo(max_pieces), hi(max_pieces), t0, t1, l, g0, g1, g2, gb
        real(wp) :: ta, tb, tm, shortest
        integer :: top

        found = .false.
        tau = 0
        g = huge(1.0_wp)
        r = sqrt(y**2 + ((vy + flow%damping*y)*flow%inv_gam)**2)
        d2 = r + abs(beta)*flow%omega**2*flow%forced_amp
        d3 = r + abs(beta)*flow%omega**3*flow%forced_amp
        ! a constant gap (two oscillators moving alike) has no minimum to report
        if (d2 == 0) return
        shortest = 1.0e-12_wp*h
        top = 1
        lo(1) = 0
        hi(1) = h
        do while (top > 0)
            t0 = lo(top)
            t1 = hi(top)
            top = top - 1
            l = t1 - t0
            call gap_terms(flow, c, y, vy, beta, s0, t0, g0, g1, g2)
            if (abs(g1) > l*d2) cycle
            if (abs(g2) <= l*d3 .and. l > shortest .and. top + 2 <= max_pieces) then
                tm = t0 + l/2
                top = top + 2
                lo(top - 1) = tm
                hi(top - 1) = t1
                lo(top) = t0
                hi(top) = tm
                cycle
            end if
            ! g' monotone on [t0, t1]: a minimum if it rises through zero
            if (.not. g1 < 0) cycle
            call gap_terms(flow, c, y, vy, beta, s0, t1, gb, g1, g2)
            if (.not. g1 > 0) cycle
            ta = t0
            tb = t1
            do while (tb - ta > 4*spacing(max(tb, 1.0_wp)))
                tm = ta + (tb - ta)/2
                call gap_terms(flow, c, y, vy, beta, s0, tm, gb, g1, g2)
                if (g1 < 0) then
                    ta = tm
                else
                    tb = tm
                end if
            end do
            tm = ta + (tb - ta)/2
            call gap_terms(flow, c, y, vy, beta, s0, tm, gb, g1, g2)
            if (gb < g) then
                found = .true.
                g = gb
                tau = tm
            end if
        end do
    end subroutine gap_minimum

    !> The gap c + y(tau) + beta xp(s0 + tau) and its first two derivatives (y'' = -2 b y' - y,
    !> xp'' = -w**2 xp).
    pure subroutine gap_terms(flow, c, y, vy, beta, s0, tau, g, g1, g2)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: c, y, vy, beta, s0, tau
        real(wp), intent(out) :: g, g1, g2
        real(wp) :: m(2, 2), yt, vyt, xp, vp

        m = propagator(flow, tau)
        yt = m(1, 1)*y + m(1, 2)*vy
        vyt = m(2, 1)*y + m(2, 2)*vy
        g = c + yt
        g1 = vyt
        g2 = -2*flow%damping*vyt - yt
        if (beta /= 0) then
            call forced_response(flow, s0 + tau, xp, vp)
            g = g + beta*xp
            g1 = g1 + beta*vp
            g2 = g2 - beta*flow%omega**2*xp
        end if
    end subroutine gap_terms

    !> Every oscillator moved freely from (x, v) at in-cycle time s0 over a time h.
    pure subroutine flow_state(flow, s0, h, x, v, x_after, v_after)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: s0, h, x(:), v(:)
        real(wp), allocatable, intent(out) :: x_after(:), v_after(:)
        real(wp) :: m(2, 2), xp0, vp0, xp1, vp1

        m = propagator(flow, h)
        call forced_response(flow, s0, xp0, vp0)
        call forced_response(flow, s0 + h, xp1, vp1)
        x_after = xp1 + m(1, 1)*(x - xp0) + m(1, 2)*(v - vp0)
        v_after = vp1 + m(2, 1)*(x - xp0) + m(2, 2)*(v - vp0)
    end subroutine flow_state

    ! ------------------------------------------------------------------------- helpers

    !> The rates of the gaps of bonds 0..n at velocities v (0 for the ends of a free chain).
    pure function gap_rates(model, v) result(rates)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: v(:)
        real(wp), allocatable :: rates(:)
        integer :: n

        n = model%n
        allocate (rates(0:n))
        rates(1:n - 1) = v(2:n) - v(1:n - 1)
        rates(0) = 0
        rates(n) = 0
        if (model%walls) then
            rates(0) = v(1)
            rates(n) = -v(n)
        end if
    end function gap_rates

    !> z = (x(1), v(1), ..., x(n), v(n)): the state in the order of the Jacobian's rows.
    pure function interleave(x, v) result(z)
        real(wp), intent(in) :: x(:), v(:)
        real(wp), allocatable :: z(:)

        allocate (z(2*size(x)))
        z(1::2) = x
        z(2::2) = v
    end function interleave

end module chain_orbit
