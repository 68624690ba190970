!> Through a grazing (docs/model.md section 12.5): where a branch's impacts change because a
!> gap minimum touches zero or an impact's speed vanishes, the grazing is located on the branch
!> to rounding, and the family is continued on the other side, with one impact more or fewer
!> (two for a mirror pair grazing together).
!>
!> Location: the grazing monitor of the orbits with the old impacts (the gap minimum g(t*),
!> g'(t*) = 0 with t* from the closed-form flow, or the impact speed V) is a smooth function of
!> the arclength s along the branch (a periodic orbit's new impact has V proportional to
!> mu - mu_g: its kick moves the next approach's gap minimum by O(V)), so its zero is found by
!> secant steps in s, each trial corrected onto the branch: the solution of G(z, mu) = 0,
!> g(t*) = 0, g'(t*) = 0 reduced to the branch. The parameter there is the secant root
!> through the last two orbits.
!>
!> The other side: the orbit with the changed impacts at a small distance in the parameter,
!> by Newton from the grazing orbit moved along the old branch's tangent, on the side where it
!> exists (the non-impacting family's penetrating continuation is not followed). Its impact
!> speed there is V1 ~ sqrt(distance); the arclength steps start at V1's scale and grow as
!> Newton allows, so near the grazing the step is a step in V.
module chain_branch_graze
    use chain_kinds, only: wp, i8, two_pi
    use chain_error, only: error_t
    use chain_engine, only: chain_t, chain_set_tangent, chain_tangent_frame, chain_time, &
                            chain_cycle, chain_period
    use chain_event_log, only: event_log_t, event_log_init
    use chain_section, only: chain_at_section, advance_to_point
    use chain_model, only: model_t, set_model_parameter
    use chain_lapack, only: solve_linear
    use chain_orbit, only: orbit_t, find_orbit
    use chain_branch_points, only: cursor_t, setting_t, cursor_from_orbit
    use chain_branch_corrector, only: correct, cursor_ahead
    implicit none
    private
    public :: refine_grazing, pass_grazing, grazing_from_gap, orbit_at

contains

    !> Refine the grazing between arclength s_lo (the orbit `lo`, old impacts) and s_hi
    !> (changed impacts or no orbit) from `here`: secant steps in s on lo's vanishing monitor,
    !> bisection when a step lands on the other side. `lo` becomes the last orbit with the old
    !> impacts, `value` the parameter where the monitor is zero.
    subroutine refine_grazing(set, here, s_lo, s_hi, lo, value, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: here
        real(wp), intent(in) :: s_lo, s_hi
        type(cursor_t), intent(inout) :: lo
        real(wp), intent(out) :: value
        type(error_t), allocatable, intent(out) :: err
        integer, parameter :: max_trials = 60
        real(wp), parameter :: done = 1.0e-13_wp
        type(cursor_t) :: trial, before
        character(len=:), allocatable :: failure
        real(wp) :: a, b, s_before, s, f_lo, f_before
        integer :: k, iterations, m
        logical :: by_speed, ok

        m = size(here%y) - 1
        by_speed = lo%orbit%min_impact_speed < lo%orbit%min_gap
        a = s_lo
        b = s_hi
        before = here
        s_before = 0
        do k = 1, max_trials
            f_lo = monitor(lo, by_speed)
            f_before = monitor(before, by_speed)
            if (f_lo <= done .or. b - a <= done*max(1.0_wp, abs(b))) exit
            s = (a + b)/2
            if (f_before > f_lo) s = a - f_lo*(a - s_before)/(f_lo - f_before)
            ! (a secant step that does not shrink the bracket well is a bisection)
            if (.not. (s > a .and. s < b)) s = (a + b)/2
            call correct(set, here, s, trial, ok, iterations, failure, err)
            if (allocated(err)) return
            if (ok) ok = all(trial%impacts == here%impacts)
            if (ok) ok = monitor(trial, by_speed) < f_lo
            if (ok) then
                before = lo
                s_before = a
                lo = trial
                a = s
            else
                b = s
            end if
        end do
        value = root(before, lo, by_speed)
    end subroutine refine_grazing

    !> The grazing monitor: the gap minimum, or the smallest impact speed.
    pure real(wp) function monitor(c, by_speed)
        type(cursor_t), intent(in) :: c
        logical, intent(in) :: by_speed

        if (by_speed) then
            monitor = c%orbit%min_impact_speed
        else
            monitor = c%orbit%min_gap
        end if
    end function monitor

    !> Where the monitor reaches zero, by the secant through two orbits in the parameter (g
    !> and V are both smooth in it there); the last orbit's parameter when the secant does
    !> not apply.
    pure real(wp) function root(before, last, by_speed) result(value)
        type(cursor_t), intent(in) :: before, last
        logical, intent(in) :: by_speed
        real(wp) :: g0, g1, mu0, mu1
        integer :: m

        m = size(last%y) - 1
        mu0 = before%y(m + 1)
        mu1 = last%y(m + 1)
        g0 = monitor(before, by_speed)
        g1 = monitor(last, by_speed)
        value = mu1
        if (.not. (g0 > g1 .and. g1 >= 0 .and. g0 < huge(1.0_wp) .and. mu0 /= mu1)) return
        value = mu1 - g1*(mu1 - mu0)/(g1 - g0)
    end function root

    !> From the grazing orbit `g` at the parameter value mu_g (its tangent that of the old
    !> branch; `before` the branch's point before it), the first orbit of the family on the
    !> other side, with other impacts than `g`; `found` gets its tangent, oriented away from
    !> the grazing; ok = .false. when Newton finds none. Where a gap touched zero, Newton
    !> starts from the first-order orbit with the new impact of speed v_new (new_impact_orbit:
    !> its kick carried by the orbit's flow and impacts), then sqrt(10) and 10 times v_new:
    !> its free gap minimum is zero only to first order in V, the new impact's depth is
    !> V**2/(2 g''), and an iterate that misses the impact lacks its 1/V in the Jacobian
    !> (figure 10's two-impact family at its gap grazing needs 3.2e-3). Where an impact's
    !> speed vanished, from g's state at mu_g + delta, then mu_g - delta (the side ahead
    !> first).
    subroutine pass_grazing(set, g, before, mu_g, symmetric, delta, v_new, found, ok, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: g, before
        real(wp), intent(in) :: mu_g, delta, v_new
        logical, intent(in) :: symmetric
        type(cursor_t), intent(out) :: found
        logical, intent(out) :: ok
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: z(:)
        real(wp) :: ahead, mu
        integer :: m, side, try

        ok = .false.
        m = size(g%y) - 1
        if (g%orbit%min_gap < g%orbit%min_impact_speed) then
            do try = 0, 2
                call new_impact_orbit(set, g, before, mu_g, symmetric, v_new*sqrt(10.0_wp)**try, &
                                      z, mu, ok, err)
                if (ok) call newton_other_side(set, g, z, mu, sign(1.0_wp, mu - mu_g), found, &
                                               ok, err)
                if (ok .or. allocated(err)) return
            end do
            return
        end if
        ahead = sign(1.0_wp, mu_g - before%y(m + 1))
        do side = 1, 2
            mu = mu_g + ahead*delta
            if (mu >= set%low .and. mu <= set%high) then
                call newton_other_side(set, g, g%y(:m), mu, ahead, found, ok, err)
                if (ok .or. allocated(err)) return
            end if
            ahead = -ahead
        end do
    end subroutine pass_grazing

    !> The grazing located again from the side where the impact is gone (`found`, past an
    !> impact whose speed vanished at about mu_g): that family is smooth up to it, so the
    !> secant on its gap minimum in the parameter, Newton at each trial, converges to
    !> rounding where Newton on the impacting side (its Jacobian growing like 1/V) cannot.
    !> ok: `graze` is its orbit there, at `value`.
    subroutine grazing_from_gap(set, found, mu_g, graze, value, ok, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: found
        real(wp), intent(in) :: mu_g
        type(cursor_t), intent(out) :: graze
        real(wp), intent(out) :: value
        logical, intent(out) :: ok
        type(error_t), allocatable, intent(out) :: err
        type(cursor_t) :: trial, last
        real(wp) :: mu(2), gap(2), next
        integer :: k, m

        ok = .false.
        m = size(found%y) - 1
        last = found
        mu = [2*found%y(m + 1) - mu_g, found%y(m + 1)]
        call orbit_at(set, found, mu(1), trial, ok, err)
        if (.not. ok) return
        gap = [trial%orbit%min_gap, found%orbit%min_gap]
        if (gap(1) < gap(2)) then
            ! (mu_g was short of the grazing, found lies on the near side: the trial is nearer)
            mu = mu([2, 1])
            gap = gap([2, 1])
            last = trial
        end if
        do k = 1, 30
            if (gap(2) <= 1.0e-14_wp .or. .not. gap(1) > gap(2)) exit
            next = mu(2) - gap(2)*(mu(2) - mu(1))/(gap(2) - gap(1))
            call orbit_at(set, found, next, trial, ok, err)
            if (allocated(err)) return
            if (.not. ok) exit
            if (.not. trial%orbit%min_gap < gap(2)) exit
            mu = [mu(2), next]
            gap = [gap(2), trial%orbit%min_gap]
            last = trial
        end do
        ok = gap(1) > gap(2) .and. gap(2) < 1.0e-10_wp
        graze = last
        value = mu(2) - gap(2)*(mu(2) - mu(1))/(gap(2) - gap(1))
    end subroutine grazing_from_gap

    !> The orbit of c's family at the parameter value mu, by Newton from c's state: ok when
    !> it converges with c's impacts and no touch of its own.
    subroutine orbit_at(set, c, mu, found, ok, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: c
        real(wp), intent(in) :: mu
        type(cursor_t), intent(out) :: found
        logical, intent(out) :: ok
        type(error_t), allocatable, intent(out) :: err
        type(model_t) :: model
        type(orbit_t) :: orbit

        ok = .false.
        model = set%model
        call set_model_parameter(model, set%opt%parameter, mu)
        call find_orbit(model, set%phase, set%cycles, c%orbit%x, c%orbit%v, orbit, err, &
                        set%opt%newton)
        if (allocated(err) .or. .not. orbit%converged) return
        call cursor_from_orbit(set, mu, orbit, found)
        ok = all(found%impacts == c%impacts) .and. orbit%min_gap >= 0
    end subroutine orbit_at

    !> Newton from z at mu: ok when it converges to an orbit with other impacts than g's,
    !> which has a tangent (oriented to `ahead` in the parameter).
    subroutine newton_other_side(set, g, z, mu, ahead, found, ok, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: g
        real(wp), intent(in) :: z(:), mu, ahead
        type(cursor_t), intent(out) :: found
        logical, intent(out) :: ok
        type(error_t), allocatable, intent(out) :: err
        type(model_t) :: model
        type(orbit_t) :: orbit

        ok = .false.
        model = set%model
        call set_model_parameter(model, set%opt%parameter, mu)
        call find_orbit(model, set%phase, set%cycles, z(1::2), z(2::2), orbit, err, &
                        set%opt%newton)
        if (allocated(err) .or. .not. orbit%converged) return
        call cursor_from_orbit(set, mu, orbit, found)
        if (all(found%impacts == g%impacts)) return
        call cursor_ahead(set, orbit, mu, ahead, found, ok, err)
    end subroutine newton_other_side

    !> The impacting orbit near a grazing where a gap touches zero, to first order in the new
    !> impact's speed V (Nordmark's discontinuity map): the impact kicks the velocities of its
    !> bond at the grazing time t*, the kick carried to the section by the flow (with the
    !> orbit's own impacts after t*), and the orbit moves by V w, (I - J) w = that kick; the
    !> parameter moves so that the gap minimum stays zero to first order: mu - mu_g = a V,
    !> a = -(dg/dz . w)/(dg/dmu along the branch). A mirror-symmetric orbit's mirror bond is
    !> kicked half a period later (both graze).
    subroutine new_impact_orbit(set, g, before, mu_g, symmetric, v_new, z, mu, ok, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: g, before
        real(wp), intent(in) :: mu_g, v_new
        logical, intent(in) :: symmetric
        real(wp), allocatable, intent(out) :: z(:)
        real(wp), intent(out) :: mu
        logical, intent(out) :: ok
        type(error_t), allocatable, intent(out) :: err
        type(model_t) :: model
        real(wp), allocatable :: kick(:), gap_row(:), a(:, :), b(:, :)
        real(wp) :: period, t_star, slope, rate
        integer :: m, n, i, info, k
        logical :: pair

        ok = .false.
        m = size(g%y) - 1
        n = m/2
        model = set%model
        call set_model_parameter(model, set%opt%parameter, g%y(m + 1))
        period = set%cycles*two_pi/model%omega
        t_star = g%orbit%min_gap_time
        k = g%orbit%min_gap_bond
        pair = symmetric .and. k /= n - k
        allocate (kick(m), gap_row(m))
        kick = 0
        gap_row = 0
        call add_kick(set, model, g, k, t_star, kick, gap_row, ok, err)
        if (pair .and. ok) call add_kick(set, model, g, n - k, modulo(t_star + period/2, period), &
                                         kick, gap_row, ok, err)
        if (.not. ok) return
        ok = .false.
        a = -g%jacobian
        do i = 1, m
            a(i, i) = a(i, i) + 1
        end do
        b = reshape(kick, [m, 1])
        call solve_linear(a, b, info)
        if (info > 0) return
        slope = (g%orbit%min_gap - before%orbit%min_gap)/(g%y(m + 1) - before%y(m + 1))
        if (.not. (abs(slope) > 0 .and. abs(slope) < huge(1.0_wp))) return
        ! the gap at its minimum moves by gap_row . w per unit V (both bonds alike)
        rate = dot_product(gap_row, b(:, 1))
        if (pair) rate = rate/2
        mu = mu_g - v_new*rate/slope
        z = g%y(:m) + v_new*b(:, 1) + (mu - g%y(m + 1))*g%tangent(:m)/g%tangent(m + 1)
        ok = mu >= set%low .and. mu <= set%high .and. abs(g%tangent(m + 1)) > 0
    end subroutine new_impact_orbit

    !> An impact of unit approach speed on bond k at time t since the section of g's orbit:
    !> its velocity jump ((1 + r) to a wall oscillator, (1 + r)/2 each to a pair) carried to
    !> the period's end, J A^-1 jump with A the Jacobian from the section to t (the orbit's
    !> impacts before t included), added to `kick`; the bond's gap at t as a row on the
    !> section's state (its rows of A), added to `gap_row`. ok: A is regular.
    subroutine add_kick(set, model, g, k, t, kick, gap_row, ok, err)
        type(setting_t), intent(in) :: set
        type(model_t), intent(in) :: model
        type(cursor_t), intent(in) :: g
        integer, intent(in) :: k
        real(wp), intent(in) :: t
        real(wp), intent(inout) :: kick(:), gap_row(:)
        logical, intent(out) :: ok
        type(error_t), allocatable, intent(out) :: err
        type(chain_t) :: chain
        type(event_log_t) :: log
        real(wp), allocatable :: a(:, :), b(:, :)
        real(wp) :: s, jump, side(2)
        integer :: m, n, j, i, info, who(2)

        ok = .false.
        m = size(kick)
        n = m/2
        call chain_at_section(model, set%phase, g%orbit%x, g%orbit%v, chain, err)
        if (allocated(err)) return
        allocate (a(m, m), b(m, 1))
        a = 0
        do i = 1, m
            a(i, i) = 1
        end do
        call chain_set_tangent(chain, a)
        call event_log_init(log, .false., 0)
        s = chain_time(chain) + t
        call advance_to_point(chain, chain_cycle(chain) + int(s/chain_period(chain), i8), &
                              modulo(s, chain_period(chain)), log, err)
        if (allocated(err)) return
        a = chain_tangent_frame(chain)
        b = 0
        who = [k, k + 1]
        side = [-1.0_wp, 1.0_wp]
        jump = (1 + model%restitution)/2
        if (k == 0 .or. k == n) jump = 1 + model%restitution
        do j = 1, 2
            i = who(j)
            if (i < 1 .or. i > n) cycle
            b(2*i, 1) = side(j)*jump
            gap_row = gap_row + side(j)*a(2*i - 1, :)
        end do
        call solve_linear(a, b, info)
        if (info /= 0) return
        kick = kick + matmul(g%jacobian, b(:, 1))
        ok = .true.
    end subroutine add_kick

end module chain_branch_graze
