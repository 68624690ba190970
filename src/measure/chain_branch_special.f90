!> The special points of a branch (docs/model.md section 12.3): between two points, a fold (the
!> tangent's parameter component changes sign), a period doubling (det(J + I) does) or a
!> Neimark-Sacker point (complex multipliers leave the unit circle), each located by regula
!> falsi on the arclength and confirmed by its multiplier; and where the impacts per bond change,
!> located by bisection and named by the monitor that vanishes there: a grazing (a gap or an
!> impact speed) or a corner (two impacts of one oscillator at one instant). Each is stored as
!> a point of the branch.
module chain_branch_special
    use chain_kinds, only: wp, two_pi
    use chain_error, only: error_t, fmt_real, fmt_int
    use chain_event_log, only: event_impact
    use chain_model, only: model_t, set_model_parameter, bond_gaps
    use chain_orbit, only: orbit_t
    use chain_branch_points, only: cursor_t, setting_t, branches_t, special_kinds, store, &
                                   add_special
    use chain_branch_corrector, only: correct
    use chain_branch_graze, only: refine_grazing
    implicit none
    private
    public :: locate_specials, locate_nonsmooth, nonsmooth_reason

    !> A monitor (gap minimum, impact speed, corner, section gap) below this names the
    !> non-smooth point where the impacts change.
    real(wp), parameter :: vanishing = 1.0e-4_wp

contains

    !> Between `here` and `next` (arclength h apart): a fold where the tangent's parameter
    !> component changes sign, a period doubling where det(J + I) does, a Neimark-Sacker
    !> point where the number of complex multipliers outside the unit circle changes. Each
    !> is located and, when the located orbit confirms it (a multiplier within 1e-6 of +1,
    !> of -1, or a complex pair within 1e-6 of the unit circle: a complex pair that leaves
    !> the circle by turning real is no Neimark-Sacker point), stored as a point (in the
    !> order of arclength).
    subroutine locate_specials(set, here, h, next, res, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: here, next
        real(wp), intent(in) :: h
        type(branches_t), intent(inout) :: res
        type(error_t), allocatable, intent(out) :: err
        type(cursor_t) :: found(4)
        real(wp) :: at(4)
        logical :: seen(4)
        integer :: k, j, m, rank

        m = size(here%y) - 1
        seen(1) = here%tangent(m + 1)*next%tangent(m + 1) < 0
        seen(2) = (here%det_plus < 0) .neqv. (next%det_plus < 0)
        seen(3) = here%unstable_pairs /= next%unstable_pairs
        ! a real multiplier through +1 where the parameter does not turn: a branch point
        seen(4) = ((here%det_minus < 0) .neqv. (next%det_minus < 0)) .and. .not. seen(1)
        at = huge(1.0_wp)
        ! (the first pair to cross: pairs of a symmetric chain come twice and cross together)
        rank = min(here%unstable_pairs, next%unstable_pairs) + 1
        do k = 1, 4
            if (.not. seen(k)) cycle
            call locate(set, here, h, k, rank, found(k), at(k), err)
            if (allocated(err)) return
            seen(k) = confirmed(found(k)%orbit, k)
        end do
        do j = 1, count(seen)
            k = minloc(at, 1, mask=seen)
            call store(set, found(k), res, err)
            if (allocated(err)) return
            call add_special(res, res%n_points, special_kind_of(k), found(k)%y(m + 1))
            seen(k) = .false.
        end do
    end subroutine locate_specials

    !> The special kind of test function k (1 fold, 2 period doubling, 3 Neimark-Sacker,
    !> 4 branch point).
    pure function special_kind_of(k) result(kind)
        integer, intent(in) :: k
        character(len=:), allocatable :: kind

        if (k <= 3) then
            kind = trim(special_kinds(k))
        else
            kind = 'branch-point'
        end if
    end function special_kind_of

    !> The zero of test function `kind` (1 fold, 2 period doubling, 3 Neimark-Sacker,
    !> 4 branch point) on the
    !> branch between arclength 0 (`here`) and h, by regula falsi (Illinois) on the arclength,
    !> each trial corrected onto the branch; to 1e-11 in the parameter or a bracket of 1e-9.
    subroutine locate(set, here, h, kind, rank, found, s_found, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: here
        real(wp), intent(in) :: h
        integer, intent(in) :: kind, rank
        type(cursor_t), intent(out) :: found
        real(wp), intent(out) :: s_found
        type(error_t), allocatable, intent(out) :: err
        type(cursor_t) :: trial
        character(len=:), allocatable :: failure
        real(wp) :: s_lo, s_hi, f_lo, f_hi, s, f, mu_lo, mu_hi
        integer :: k, iterations, side, m
        logical :: ok

        m = size(here%y) - 1
        s_lo = 0
        f_lo = test_value(here, kind, rank, here%tangent)
        mu_lo = here%y(m + 1)
        s_hi = h
        call correct(set, here, h, trial, ok, iterations, failure, err)
        if (allocated(err)) return
        f_hi = test_value(trial, kind, rank, here%tangent)
        mu_hi = trial%y(m + 1)
        found = trial
        s_found = h
        side = 0
        do k = 1, 60
            if (abs(s_hi - s_lo) <= 1.0e-9_wp .or. (abs(mu_hi - mu_lo) <= 1.0e-11_wp .and. &
                                                     kind /= 1)) exit
            s = s_hi - f_hi*(s_hi - s_lo)/(f_hi - f_lo)
            if (.not. (s > min(s_lo, s_hi) .and. s < max(s_lo, s_hi))) s = (s_lo + s_hi)/2
            call correct(set, here, s, trial, ok, iterations, failure, err)
            if (allocated(err)) return
            if (.not. ok) exit
            f = test_value(trial, kind, rank, here%tangent)
            found = trial
            s_found = s
            if (f == 0) exit
            if ((f < 0) .eqv. (f_hi < 0)) then
                s_hi = s
                f_hi = f
                mu_hi = trial%y(m + 1)
                if (side == 1) f_lo = f_lo/2
                side = 1
            else
                s_lo = s
                f_lo = f
                mu_lo = trial%y(m + 1)
                if (side == -1) f_hi = f_hi/2
                side = -1
            end if
        end do
    end subroutine locate

    !> The test function `kind` at c: the tangent's parameter component (fold), det(J + I)
    !> (period doubling), or |mu| - 1 of the complex pair of rank `rank` by modulus (the first
    !> that crosses when the count outside the circle goes up from rank - 1, or down to it;
    !> -1 when c has fewer complex pairs) (Neimark-Sacker).
    pure real(wp) function test_value(c, kind, rank, reference) result(f)
        type(cursor_t), intent(in) :: c
        integer, intent(in) :: kind, rank
        real(wp), intent(in) :: reference(:)
        real(wp), allocatable :: moduli(:)
        integer :: j

        select case (kind)
        case (1)
            f = c%tangent(size(c%tangent))
            ! (correct orients every trial's tangent along the reference)
            if (dot_product(c%tangent, reference) < 0) f = -f
        case (2)
            f = c%det_plus
        case (4)
            f = c%det_minus
        case default
            associate (re => c%orbit%multipliers_re, im => c%orbit%multipliers_im)
                moduli = pack(hypot(re, im), im > 0)
            end associate
            f = -1
            if (size(moduli) < rank) return
            do j = 1, rank
                f = maxval(moduli)
                moduli(maxloc(moduli, 1)) = -1
            end do
            f = f - 1
        end select
    end function test_value

    !> The located orbit has the multiplier of special point `kind` to 1e-6.
    pure logical function confirmed(orbit, kind)
        type(orbit_t), intent(in) :: orbit
        integer, intent(in) :: kind
        real(wp), parameter :: within = 1.0e-6_wp

        associate (re => orbit%multipliers_re, im => orbit%multipliers_im)
            select case (kind)
            case (1, 4)
                confirmed = minval(hypot(re - 1, im)) < within
            case (2)
                confirmed = minval(hypot(re + 1, im)) < within
            case default
                confirmed = minval(abs(hypot(re, im) - 1), mask=im /= 0) < within
            end select
        end associate
    end function confirmed

    !> The impacts change within arclength h of `here`: bisection on the arclength for the
    !> last orbit with the impacts of `here` (a trial where the corrector fails counts as
    !> changed), to 1e-11 in the parameter, and what happens there (`kind`): a grazing when its
    !> smallest gap or impact speed is below 1e-4, else a corner when its corner monitor (the
    !> shortest time between impacts on neighbouring bonds) is, else an impact at the section
    !> when a gap of its state on the section is, else '' (no monitor vanishes).
    !> The orbit is stored as a special point of its kind, or as a plain point when `kind` is
    !> '' and `keep`; `value` is where the vanishing monitor extrapolates to zero. A grazing is
    !> refined to rounding (chain_branch_graze); `located`: the orbit stored, with its tangent.
    subroutine locate_nonsmooth(set, here, h, keep, res, kind, value, err, located)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: here
        real(wp), intent(in) :: h
        logical, intent(in) :: keep
        type(branches_t), intent(inout) :: res
        character(len=:), allocatable, intent(out) :: kind
        real(wp), intent(out) :: value
        type(error_t), allocatable, intent(out) :: err
        type(cursor_t), intent(out), optional :: located
        type(cursor_t) :: trial, last_same
        character(len=:), allocatable :: failure
        real(wp) :: s_lo, s_hi, s, mu_lo, mu_hi, corner_before, corner_last
        integer :: k, iterations, m, oscillator
        logical :: ok

        m = size(here%y) - 1
        s_lo = 0
        s_hi = h
        mu_lo = here%y(m + 1)
        mu_hi = here%y(m + 1) + h*here%tangent(m + 1)
        last_same = here
        do k = 1, 80
            if (abs(mu_hi - mu_lo) <= 1.0e-11_wp .and. abs(s_hi - s_lo) <= 1.0e-6_wp) exit
            s = (s_lo + s_hi)/2
            call correct(set, here, s, trial, ok, iterations, failure, err)
            if (allocated(err)) return
            if (ok) ok = all(trial%impacts == here%impacts)
            if (ok) then
                s_lo = s
                mu_lo = trial%y(m + 1)
                last_same = trial
            else
                s_hi = s
                mu_hi = here%y(m + 1) + s*here%tangent(m + 1)
                if (allocated(trial%y)) mu_hi = trial%y(m + 1)
            end if
        end do
        value = last_same%y(m + 1)
        call corner_monitor(set, here%orbit, here%y(m + 1), corner_before, oscillator)
        call corner_monitor(set, last_same%orbit, last_same%y(m + 1), corner_last, oscillator)
        if (min(last_same%orbit%min_gap, last_same%orbit%min_impact_speed) < vanishing) then
            kind = 'grazing'
            call refine_grazing(set, here, s_lo, s_hi, last_same, value, err)
            if (allocated(err)) return
        else if (corner_last < vanishing) then
            kind = 'corner'
            value = secant_root(here%y(m + 1), last_same%y(m + 1), corner_before, corner_last)
        else if (section_gap(set, last_same) < vanishing) then
            ! (the orbit goes on, but the map of this section jumps where an impact crosses it)
            kind = 'section'
            value = secant_root(here%y(m + 1), last_same%y(m + 1), section_gap(set, here), &
                                section_gap(set, last_same))
        else if (keep .and. grazing_beyond(set, res, here, last_same)) then
            ! (Newton gave out short of it, as the saltation matrices grow like 1/V; where
            ! the corrector merely failed, the step is halved and comes nearer instead)
            kind = 'grazing'
            value = secant_root(here%y(m + 1), last_same%y(m + 1), &
                                grazing_monitor(here%orbit, last_same%orbit), &
                                grazing_monitor(last_same%orbit, last_same%orbit))
        else
            kind = ''
            if (.not. keep) return
        end if
        call store(set, last_same, res, err)
        if (present(located)) located = last_same
        if (allocated(err) .or. len(kind) == 0) return
        call add_special(res, res%n_points, kind, value)
    end subroutine locate_nonsmooth

    !> A grazing beyond the last orbit with the old impacts, which Newton could not reach:
    !> that orbit's grazing monitor (its smaller one, the gap minimum or the impact speed) has
    !> fallen below 1/20 of the monitor's largest over the branch's points, and the secant
    !> through the point before it and it reaches zero within their distance.
    pure logical function grazing_beyond(set, res, before, last)
        type(setting_t), intent(in) :: set
        type(branches_t), intent(in) :: res
        type(cursor_t), intent(in) :: before, last
        real(wp) :: largest, g
        integer :: k, m

        m = size(last%y) - 1
        largest = 0
        do k = 1, res%n_points
            if (res%points(k)%branch /= set%branch) cycle
            g = grazing_monitor(res%points(k)%orbit, last%orbit)
            if (g < huge(1.0_wp)) largest = max(largest, g)
        end do
        g = grazing_monitor(last%orbit, last%orbit)
        grazing_beyond = g < largest/20 .and. &
                         secant_root(before%y(m + 1), last%y(m + 1), &
                                     grazing_monitor(before%orbit, last%orbit), g) /= last%y(m + 1)
    end function grazing_beyond

    !> An orbit's grazing monitor of the kind that is the smaller on `last`: its smallest
    !> impact speed or its smallest gap minimum (huge: none).
    pure real(wp) function grazing_monitor(orbit, last) result(g)
        type(orbit_t), intent(in) :: orbit, last

        if (last%min_impact_speed < last%min_gap) then
            g = orbit%min_impact_speed
        else
            g = orbit%min_gap
        end if
    end function grazing_monitor

    !> Where a monitor, g_before at mu_before and g_last at mu_last, reaches zero along their
    !> secant; mu_last itself when the secant does not apply (a monitor that did not decrease,
    !> or a root farther than the two points' distance).
    pure real(wp) function secant_root(mu_before, mu_last, g_before, g_last) result(value)
        real(wp), intent(in) :: mu_before, mu_last, g_before, g_last

        value = mu_last
        if (.not. (g_before > g_last .and. g_last >= 0 .and. g_before < huge(1.0_wp))) return
        if (abs(g_last*(mu_last - mu_before)/(g_last - g_before)) > abs(mu_last - mu_before)) &
            return
        value = mu_last - g_last*(mu_last - mu_before)/(g_last - g_before)
    end function secant_root

    !> The corner monitor of an orbit at parameter value mu: the shortest time between two
    !> impacts on neighbouring bonds (the two impacts of the oscillator between them), the
    !> period taken as a circle (huge: none). It reaches zero where an oscillator is hit by both neighbours at one
    !> instant: there the order of the two impacts swaps, and the map, whose pair impacts do not
    !> commute, is not smooth. `oscillator`: that oscillator (0: none).
    pure subroutine corner_monitor(set, orbit, mu, shortest, oscillator)
        type(setting_t), intent(in) :: set
        type(orbit_t), intent(in) :: orbit
        real(wp), intent(in) :: mu
        real(wp), intent(out) :: shortest
        integer, intent(out) :: oscillator
        integer, allocatable :: bonds(:)
        real(wp), allocatable :: times(:)
        real(wp) :: omega, period, apart
        integer :: j, k

        omega = set%model%omega
        if (set%opt%parameter == 'omega') omega = mu
        period = set%cycles*two_pi/omega
        bonds = pack(orbit%event_bond, orbit%event_kind == event_impact)
        times = pack(orbit%event_time, orbit%event_kind == event_impact)
        shortest = huge(1.0_wp)
        oscillator = 0
        do j = 1, size(bonds)
            do k = j + 1, size(bonds)
                if (abs(bonds(j) - bonds(k)) /= 1) cycle
                apart = abs(times(k) - times(j))
                apart = min(apart, period - apart)
                if (apart < shortest) then
                    shortest = apart
                    oscillator = max(bonds(j), bonds(k))
                end if
            end do
        end do
    end subroutine corner_monitor

    !> The smallest gap of c's state on the section: zero where an impact falls on the section.
    pure real(wp) function section_gap(set, c) result(gap)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: c
        type(model_t) :: model
        integer :: m

        m = size(c%y) - 1
        model = set%model
        call set_model_parameter(model, set%opt%parameter, c%y(m + 1))
        gap = minval(bond_gaps(model%spacing, model%walls, c%y(1:m:2)))
    end function section_gap

    !> Why a branch ended at the non-smooth point of kind `kind` (of locate_nonsmooth) just
    !> stored, at `value`.
    function nonsmooth_reason(set, res, kind, value) result(reason)
        type(setting_t), intent(in) :: set
        type(branches_t), intent(in) :: res
        character(len=*), intent(in) :: kind
        real(wp), intent(in) :: value
        character(len=:), allocatable :: reason
        integer :: oscillator
        real(wp) :: apart

        select case (kind)
        case ('grazing')
            reason = "grazing at "//set%opt%parameter//" = "//fmt_real(value)
            associate (o => res%points(res%n_points)%orbit)
                if (min(o%min_gap, o%min_impact_speed) >= vanishing) reason = reason// &
                    " (extrapolated: Newton gave out at the orbit with "// &
                    merge("impact speed", "gap minimum ", o%min_impact_speed < o%min_gap)// &
                    " "//fmt_real(min(o%min_gap, o%min_impact_speed))//")"
            end associate
            reason = reason//": the impacts change there, the branch ends"
        case ('corner')
            associate (p => res%points(res%n_points))
                call corner_monitor(set, p%orbit, p%value, apart, oscillator)
            end associate
            reason = "simultaneous impact (corner) at "//set%opt%parameter//" = "// &
                     fmt_real(value)//": oscillator "//fmt_int(oscillator)//" is hit by "// &
                     "both neighbours at one instant (the map jumps there) and Newton finds "// &
                     "no orbit with its impacts in another order past it, the branch ends"
        case ('section')
            reason = "an impact at the section at "//set%opt%parameter//" = "// &
                     fmt_real(value)//" (a gap of the orbit's state on the section vanishes: "// &
                     "the map of this section jumps there, a section at another phase "// &
                     "goes on), the branch ends"
        case default
            associate (o => res%points(res%n_points)%orbit)
                reason = "the impacts change at "//set%opt%parameter//" = "// &
                         fmt_real(value)//" where no monitor vanishes (smallest gap "// &
                         fmt_real(o%min_gap)//", impact speed "// &
                         fmt_real(o%min_impact_speed)//"), the branch ends"
            end associate
        end select
    end function nonsmooth_reason

end module chain_branch_special
