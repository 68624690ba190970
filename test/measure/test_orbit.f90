!> Periodic orbits by Newton shooting (docs/model.md section 11), against what cannot be tuned:
!> the linear response of a chain without impacts (section 2.1); quadratic convergence onto a
!> stable and an unstable impacting orbit of figure 10's chain; the multipliers against the
!> eigenvalues of central differences of the map; an unstable orbit re-run by the ordinary
!> simulator, and a perturbation along its leading eigenvector growing by the leading
!> multiplier; the product of the multipliers (section 7.9); the smallest gap against dense
!> sampling; and Newton's failures reported as results.
module test_orbit
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_flow, only: flow_t, make_flow, forced_response
    use chain_model, only: model_t
    use chain_engine, only: chain_t, chain_model, chain_positions, chain_velocities, &
                            chain_gaps_now, chain_period
    use chain_event_log, only: event_log_t, event_log_init, event_impact
    use chain_section, only: advance_to_point, chain_at_section
    use chain_floquet, only: floquet_multipliers
    use chain_lapack, only: solve_linear
    use chain_orbit, only: orbit_t, orbit_options_t, find_orbit, interleave
    use test_chains, only: make_chain
    use test_chains, only: model_of, fig10_model
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_orbit_tests

contains

    subroutine run_orbit_tests(t)
        type(tally_t), intent(inout) :: t
        type(orbit_t) :: stable, unstable, saddle

        call linear_response(t)
        ! figure 10's chain (n = 8, w = 1.9, b = 0.05, K = 0.5): a stable period-1 orbit at
        ! A = 3 from 5 cycles after rest; at A = 2.2 the attractor is not periodic and an
        ! unstable period-1 orbit (a complex pair of multipliers outside the unit circle) is
        ! found from a state on it after 2000 cycles or more
        call converge(t, fig10_model(3.0_wp), 5_i8, 'stable fig. 10 A = 3', stable)
        call check(t, maxval(hypot(stable%multipliers_re, stable%multipliers_im)) < 1, &
                   'stable fig. 10 A = 3: multipliers inside the unit circle')
        call converge(t, fig10_model(2.2_wp), 2000_i8, 'unstable fig. 10 A = 2.2', unstable)
        call check(t, maxval(hypot(unstable%multipliers_re, unstable%multipliers_im)) > 1.1_wp, &
                   'unstable fig. 10 A = 2.2: a multiplier outside the unit circle')
        ! figure 2's chain (n = 15, w = 1.5, b = 0.05, K = 0.7) at A = 2.22: a saddle (a real
        ! multiplier 4.5) found from a state after 3000 cycles or more of its aperiodic attractor
        call converge(t, fig2(2.22_wp), 3000_i8, 'saddle fig. 2 A = 2.22', saddle, .true.)
        call check(t, real_saddle(saddle), 'saddle fig. 2 A = 2.22: a real multiplier > 1')
        call multipliers_by_differences(t, fig10_model(3.0_wp), stable, 'stable fig. 10')
        call multipliers_by_differences(t, fig10_model(2.2_wp), unstable, 'unstable fig. 10')
        call multipliers_by_differences(t, fig2(2.22_wp), saddle, 'saddle fig. 2')
        call returns_and_grows(t, fig10_model(2.2_wp), unstable, 'unstable fig. 10')
        call returns_and_grows(t, fig2(2.22_wp), saddle, 'saddle fig. 2')
        call multiplier_product(t, fig10_model(3.0_wp), stable, 'stable fig. 10')
        call multiplier_product(t, fig10_model(2.2_wp), unstable, 'unstable fig. 10')
        call multiplier_product(t, fig2(2.22_wp), saddle, 'saddle fig. 2')
        call gap_by_sampling(t, fig10_model(3.0_wp), stable, 'stable fig. 10')
        call gap_by_sampling(t, fig10_model(2.2_wp), unstable, 'unstable fig. 10')
        call failures(t)
    end subroutine run_orbit_tests

    !> Figure 2's chain at amplitude A (a = 1, fixed walls).
    function fig2(amplitude) result(model)
        real(wp), intent(in) :: amplitude
        type(model_t) :: model
        integer :: i

        model = model_of(make_flow(0.05_wp, amplitude, 1.5_wp), 0.7_wp, [(1.0_wp, i=0, 15)], &
                         .true., 1.0e-9_wp)
    end function fig2

    !> No impacts: the period-1 orbit is the forced response, x = xp, v = vp at the section
    !> (section 2.1), and every multiplier has modulus exp(-b T) (the map is affine). Newton
    !> needs one step; a section inside the cycle checks where the phase enters.
    subroutine linear_response(t)
        type(tally_t), intent(inout) :: t
        type(model_t) :: model
        type(flow_t) :: flow
        type(orbit_t) :: orbit
        type(error_t), allocatable :: err
        real(wp) :: xp, vp, phase, x(4), v(4)
        integer :: i

        flow = make_flow(0.05_wp, 1.0_wp, 1.9_wp)
        model = model_of(flow, 0.5_wp, [(1.0_wp, i=0, 4)], .true., 1.0e-9_wp)
        phase = 1.0_wp
        call forced_response(flow, phase/flow%omega, xp, vp)
        x = xp + [0.1_wp, -0.05_wp, 0.02_wp, 0.1_wp]
        v = vp + [0.0_wp, 0.1_wp, -0.1_wp, 0.05_wp]
        call find_orbit(model, phase, 1, x, v, orbit, err)
        call check(t, .not. allocated(err) .and. orbit%converged .and. orbit%impacts == 0 .and. &
                   orbit%iterations <= 2, 'linear response: converged without impacts')
        if (.not. orbit%converged) return
        call check_close(t, maxval(abs(orbit%x - xp)) + maxval(abs(orbit%v - vp)), 0.0_wp, &
                         'linear response: the orbit is (xp, vp) at the section', 1.0e-12_wp)
        call check_close(t, maxval(abs(hypot(orbit%multipliers_re, orbit%multipliers_im) - &
                                       exp(-flow%damping*flow%period))), 0.0_wp, &
                         'linear response: every multiplier of modulus exp(-b T)', 1.0e-12_wp)
        ! pair gaps stay at their spacing (every oscillator on xp); a wall gap dips to 1 - |xp|
        call check(t, orbit%min_gap_bond == 0 .or. orbit%min_gap_bond == 4, &
                   'linear response: the smallest gap is a wall gap')
        call check_close(t, orbit%min_gap, 1 - flow%forced_amp, &
                         'linear response: smallest gap 1 - A / sqrt(D2)', 1.0e-12_wp)
    end subroutine linear_response

    !> Newton from the state `transient` cycles after a start at rest, or, when it does not
    !> converge from there, from the states 10, 20, ... cycles later (at most 40 tries: which
    !> state of an aperiodic attractor comes close enough to an unstable orbit depends on the
    !> trajectory, and so on its rounding): converged to the tolerance, quadratically at the
    !> end. Linear convergence would make r(k) / r(k-1)**2 grow without bound; 100 bounds the
    !> map's curvature in these units. Steps that end at the rounding floor (1e-14) are not
    !> judged.
    subroutine converge(t, model, transient, label, orbit, saddle)
        type(tally_t), intent(inout) :: t
        type(model_t), intent(in) :: model
        integer(i8), intent(in) :: transient
        character(len=*), intent(in) :: label
        type(orbit_t), intent(out) :: orbit
        !> only an orbit with a real multiplier outside the unit circle will do
        logical, intent(in), optional :: saddle
        integer, parameter :: tries = 100
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: events
        real(wp) :: scale
        integer :: k, quadratic, try
        logical :: ok

        call make_chain(chain, model%n, model%amplitude, model%omega, model%damping, &
                        model%restitution, .true., 0.0_wp, 0.0_wp, err)
        call event_log_init(events, .false., 0)
        do try = 1, tries
            call advance_to_point(chain, transient + 10*(try - 1), 0.0_wp, events, err)
            if (allocated(err)) exit
            call find_orbit(model, 0.0_wp, 1, chain_positions(chain), chain_velocities(chain), &
                            orbit, err)
            if (allocated(err)) exit
            if (.not. orbit%converged) cycle
            if (.not. present(saddle)) exit
            if (.not. saddle .or. real_saddle(orbit)) exit
        end do
        if (orbit%converged) write (*, '(a,i0,a)') '    '//label//': found from the state ', &
            transient + 10*(try - 1), ' cycles after the start'
        call check(t, .not. allocated(err) .and. orbit%converged, label//': Newton converged')
        if (.not. orbit%converged) return
        write (*, '(a,*(es9.2))') '    '//label//': residuals', orbit%residuals
        scale = 1 + max(maxval(abs(orbit%x)), maxval(abs(orbit%v)))
        call check(t, orbit%residuals(orbit%iterations) <= 1.0e-11_wp, &
                   label//': residual <= 1e-11 (1 + |z|)')
        ok = .true.
        quadratic = 0
        do k = 1, orbit%iterations
            associate (r => orbit%residuals(k), before => orbit%residuals(k - 1))
                if (before > 1.0e-2_wp .or. r < 1.0e-14_wp) cycle
                quadratic = quadratic + 1
                ok = ok .and. r <= 100*before**2
            end associate
        end do
        call check(t, ok .and. quadratic >= 2, label//': quadratic convergence (at least two '// &
                   'steps with r(k) <= 100 r(k-1)**2)')
    end subroutine converge

    !> Has the orbit a real multiplier outside the unit circle?
    pure logical function real_saddle(orbit)
        type(orbit_t), intent(in) :: orbit

        real_saddle = .false.
        if (allocated(orbit%multipliers_re)) real_saddle = &
            any(orbit%multipliers_im == 0 .and. abs(orbit%multipliers_re) > 1)
    end function real_saddle

    !> The multipliers are the eigenvalues of the central differences of the map (h = 1e-7),
    !> matched one to one; the perturbed runs keep the orbit's impact sequence.
    subroutine multipliers_by_differences(t, model, orbit, label)
        type(tally_t), intent(inout) :: t
        type(model_t), intent(in) :: model
        type(orbit_t), intent(in) :: orbit
        character(len=*), intent(in) :: label
        real(wp), parameter :: h = 1.0e-7_wp
        real(wp), allocatable :: z(:), fd(:, :), re(:), im(:), plus(:), minus(:)
        complex(wp), allocatable :: want(:), got(:)
        real(wp) :: worst
        integer :: j, m, info, k
        logical :: same

        if (.not. orbit%converged) return
        m = 2*model%n
        z = interleave(orbit%x, orbit%v)
        allocate (fd(m, m), re(m), im(m))
        same = .true.
        do j = 1, m
            z(j) = z(j) + h
            call map_of(model, orbit, z, plus, same)
            z(j) = z(j) - 2*h
            call map_of(model, orbit, z, minus, same)
            z(j) = z(j) + h
            fd(:, j) = (plus - minus)/(2*h)
        end do
        call check(t, same, label//': the perturbed runs keep the impact sequence')
        call floquet_multipliers(fd, re, im, info)
        got = cmplx(orbit%multipliers_re, orbit%multipliers_im, wp)
        want = cmplx(re, im, wp)
        worst = 0
        do j = 1, m
            k = minloc(abs(want - got(j)), 1)
            worst = max(worst, abs(want(k) - got(j)))
            want(k) = huge(1.0_wp)
        end do
        write (*, '(a,es9.2)') '    '//label//': |multiplier - eigenvalue of differences| <= ', &
            worst
        call check_close(t, worst, 0.0_wp, label//': multipliers = eigenvalues of central '// &
                         'differences', 1.0e-6_wp)
    end subroutine multipliers_by_differences

    !> The orbit, re-run for p cycles by the ordinary simulator (no tangent), returns to
    !> itself; a perturbation of 1e-8 along the eigenvector of the largest real multiplier
    !> (inverse iteration) grows by that multiplier per period, over four periods.
    subroutine returns_and_grows(t, model, orbit, label)
        type(tally_t), intent(inout) :: t
        type(model_t), intent(in) :: model
        type(orbit_t), intent(in) :: orbit
        character(len=*), intent(in) :: label
        real(wp), parameter :: eps = 1.0e-8_wp
        real(wp), allocatable :: z(:), image(:), w(:), a(:, :), b(:, :), moved(:)
        real(wp) :: mu, worst
        integer :: m, i, k, it, info
        logical :: same

        if (.not. orbit%converged) return
        m = 2*model%n
        z = interleave(orbit%x, orbit%v)
        same = .true.
        call map_of(model, orbit, z, image, same)
        call check_close(t, maxval(abs(image - z)), 0.0_wp, label//': the ordinary '// &
                         'simulator returns to the orbit after p cycles', 1.0e-9_wp)
        mu = 0
        do i = 1, m
            if (orbit%multipliers_im(i) == 0 .and. abs(orbit%multipliers_re(i)) > abs(mu)) &
                mu = orbit%multipliers_re(i)
        end do
        if (abs(mu) <= 1) return
        w = [(1.0_wp/i, i=1, m)]
        do it = 1, 3
            a = orbit%jacobian
            do i = 1, m
                a(i, i) = a(i, i) - mu*(1 + 1.0e-12_wp)
            end do
            b = reshape(w, [m, 1])
            call solve_linear(a, b, info)
            w = b(:, 1)/norm2(b(:, 1))
        end do
        moved = z + eps*w
        worst = 0
        do k = 1, 4
            call map_of(model, orbit, moved, image, same)
            worst = max(worst, abs(norm2(image - z)/(eps*abs(mu)**k) - 1))
            ! the deviation keeps the eigenvector's direction (sign flips for mu < 0)
            worst = max(worst, maxval(abs((image - z)/(eps*mu**k) - w)))
            moved = image
        end do
        write (*, '(a,f9.5,a,es9.2)') '    '//label//': leading multiplier ', mu, &
            ', largest relative deviation from its growth over 4 periods ', worst
        call check(t, same .and. worst < 0.02_wp, label//': a perturbation along the '// &
                   'leading eigenvector grows by the leading multiplier per period (2 %)')
    end subroutine returns_and_grows

    !> prod mu = exp(-2 b n p T) K**(2 c), c the impacts per period (section 7.9).
    subroutine multiplier_product(t, model, orbit, label)
        type(tally_t), intent(inout) :: t
        type(model_t), intent(in) :: model
        type(orbit_t), intent(in) :: orbit
        character(len=*), intent(in) :: label
        type(flow_t) :: flow
        real(wp) :: expected

        if (.not. orbit%converged) return
        flow = make_flow(model%damping, model%amplitude, model%omega)
        expected = -2*model%damping*model%n*orbit%cycles*flow%period + &
                   2*orbit%impacts*log(model%restitution)
        write (*, '(a,es9.2)') '    '//label//': ln prod |mu|, relative deviation ', &
            abs(sum(log(hypot(orbit%multipliers_re, orbit%multipliers_im)))/expected - 1)
        call check_close(t, sum(log(hypot(orbit%multipliers_re, orbit%multipliers_im))), &
                         expected, label//': product of the multipliers = exp(-2 b n p T) '// &
                         'K**(2 c)', rel_tol=1.0e-10_wp)
    end subroutine multiplier_product

    !> The smallest gap against dense sampling (20000 points per cycle): the smallest of the
    !> sampled local minima of every bond's gap, leaving out those next to the bond's own
    !> impacts. Sampling can only miss the exact minimum from above, by at most about
    !> max|g''| dt**2 / 8 (2e-8 here).
    subroutine gap_by_sampling(t, model, orbit, label)
        type(tally_t), intent(inout) :: t
        type(model_t), intent(in) :: model
        type(orbit_t), intent(in) :: orbit
        character(len=*), intent(in) :: label
        integer, parameter :: per_cycle = 20000
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: events
        real(wp), allocatable :: g(:, :), times(:)
        real(wp) :: period, s0, dt, best, near
        integer :: j, k, e, n_samples, best_bond
        logical :: near_own

        if (.not. orbit%converged) return
        call chain_at_section(model, orbit%phase, orbit%x, orbit%v, chain, err)
        period = chain_period(chain)
        s0 = orbit%phase/model%omega
        n_samples = per_cycle*orbit%cycles
        dt = orbit%cycles*period/n_samples
        allocate (g(0:model%n, 0:n_samples - 1), times(0:n_samples - 1))
        times = [(j*dt, j=0, n_samples - 1)]
        call event_log_init(events, .true., 64)
        do j = 0, n_samples - 1
            if (j > 0) call advance_to_point(chain, int(floor((s0 + times(j))/period), i8), &
                                             modulo(s0 + times(j), period), events, err)
            g(:, j) = chain_gaps_now(chain)
        end do
        best = huge(1.0_wp)
        best_bond = -1
        do k = 0, model%n
            do j = 0, n_samples - 1
                if (g(k, j) > g(k, modulo(j - 1, n_samples)) .or. &
                    g(k, j) > g(k, modulo(j + 1, n_samples))) cycle
                near_own = .false.
                do e = 1, events%count
                    near = abs(events%time(e) - times(j))
                    near = min(near, n_samples*dt - near)
                    if (events%site(e) == k .and. events%kind(e) == event_impact .and. &
                        near <= dt) near_own = .true.
                end do
                if (.not. near_own .and. g(k, j) < best) then
                    best = g(k, j)
                    best_bond = k
                end if
            end do
        end do
        write (*, '(a,es23.15,a,es23.15)') '    '//label//': smallest gap ', orbit%min_gap, &
            ', sampled ', best
        call check(t, best_bond == orbit%min_gap_bond .and. best >= orbit%min_gap - 1.0e-12_wp &
                   .and. best - orbit%min_gap < 1.0e-7_wp, label//': smallest gap (and its '// &
                   'bond) equals dense sampling')
    end subroutine gap_by_sampling

    !> Newton that cannot succeed returns a result with a reason, not an error: too few
    !> iterations; a period-3 shooting from a far-away guess stopped after three; and an orbit
    !> that rests on a wall every cycle.
    subroutine failures(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: events
        type(orbit_t) :: orbit
        type(orbit_options_t) :: options
        type(model_t) :: model
        integer :: i

        call make_chain(chain, 8, 3.0_wp, 1.9_wp, 0.05_wp, 0.5_wp, .true., 0.0_wp, 0.0_wp, err)
        call event_log_init(events, .false., 0)
        call advance_to_point(chain, 5_i8, 0.0_wp, events, err)
        options%max_iterations = 2
        call find_orbit(fig10_model(3.0_wp), 0.0_wp, 1, chain_positions(chain), &
                        chain_velocities(chain), orbit, err, options)
        call check(t, .not. allocated(err) .and. .not. orbit%converged .and. &
                   orbit%reason == 'did not converge in 2 iterations' .and. &
                   size(orbit%residuals) == 3, 'failure: did not converge in 2 iterations')
        options%max_iterations = 3
        call find_orbit(fig10_model(3.0_wp), 0.0_wp, 3, [(0.4_wp*(-1)**i, i=1, 8)], &
                        [(0.3_wp*i, i=1, 8)], orbit, err, options)
        call check(t, .not. allocated(err) .and. .not. orbit%converged .and. &
                   len(orbit%reason) > 0 .and. orbit%iterations <= 3, &
                   'failure: period 3 from far away, at most 3 iterations: '//orbit%reason)
        ! test_corners' chain that rests on the left wall once per cycle
        model = model_of(make_flow(0.1_wp, 1.0_wp, 0.4_wp), 0.5_wp, [0.5_wp, 0.5_wp, 3.0_wp], &
                         .true., 1.0e-9_wp)
        call find_orbit(model, 0.0_wp, 1, [0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp], orbit, err)
        call check(t, .not. allocated(err) .and. .not. orbit%converged .and. &
                   index(orbit%reason, 'sticks on a wall') > 0, &
                   'failure: an orbit with a rest: '//orbit%reason)
        call find_orbit(fig10_model(3.0_wp), 0.0_wp, 1, [(2.0_wp, i=1, 8)], [(0.0_wp, i=1, 8)], &
                        orbit, err)
        call check(t, allocated(err), 'an overlapping guess is an error')
    end subroutine failures

    !> The p-cycle map by the ordinary simulator (no tangent) from z on the orbit's section;
    !> `same` turns false if the impact sequence is not the orbit's.
    subroutine map_of(model, orbit, z, image, same)
        type(model_t), intent(in) :: model
        type(orbit_t), intent(in) :: orbit
        real(wp), intent(in) :: z(:)
        real(wp), allocatable, intent(out) :: image(:)
        logical, intent(inout) :: same
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: events

        call chain_at_section(model, orbit%phase, z(1::2), z(2::2), chain, err)
        call event_log_init(events, .true., 64)
        call advance_to_point(chain, int(orbit%cycles, i8), orbit%phase/model%omega, events, err)
        image = interleave(chain_positions(chain), chain_velocities(chain))
        if (events%count /= size(orbit%event_bond)) then
            same = .false.
        else if (any(events%site(:events%count) /= orbit%event_bond)) then
            same = .false.
        end if
    end subroutine map_of

end module test_orbit
