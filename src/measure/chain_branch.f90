!> Branches of periodic orbits followed in one parameter (docs/model.md section 12):
!> pseudo-arclength continuation of y = (z, mu), z the orbit's state on the section, with the
!> exact Jacobian [J - I, dP/dmu] (chain_floquet, chain_parameter); an adaptive step; the
!> special points between two points detected by test functions and located on the branch
!> (fold: the tangent's parameter component; period doubling: det(J + I); Neimark-Sacker: the
!> complex multipliers outside the unit circle; grazing: the impacts per bond change), and
!> branch switching at a period doubling onto the period-2p branch and at a branch point onto
!> the two branches crossing there (chain_branch_switch).
!>
!> The branch goes through a grazing onto the family with the changed impacts
!> (chain_branch_graze) and through a corner onto the orbits with the impacts in another order
!> (chain_branch_corner). It stops at the bounds of the parameter (the interval from its start
!> to `stop`), after `max_points` points, at an impact at the section, at a grazing or corner
!> with no orbit found on its other side, or when Newton fails at the smallest step;
!> each is a result with its reason, not an error.
!>
!> Here the branches are followed: the first through the guess, step by step, to its end, and
!> those switched to. What a branch is made of: chain_branch_points (its
!> types come from here too); the corrector: chain_branch_corrector; the special points:
!> chain_branch_special.
module chain_branch
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int, fmt_real
    use chain_model, only: model_t, model_parameter, set_model_parameter, is_model_parameter
    use chain_orbit, only: orbit_t, find_orbit
    use chain_monitor, only: monitor_t, stage_points
    use chain_branch_points, only: branch_options_t, branch_point_t, special_point_t, &
                                   branch_origin_t, branches_t, special_kinds, end_kinds, &
                                   cursor_t, setting_t, cursor_from_orbit, store, add_branch, &
                                   add_reason
    use chain_branch_corrector, only: correct, tangent_at
    use chain_branch_special, only: locate_specials, locate_nonsmooth, nonsmooth_reason
    use chain_branch_switch, only: real_eigenvector, branch_point_starts
    use chain_branch_graze, only: pass_grazing, grazing_from_gap, orbit_at
    use chain_branch_corner, only: pass_corner
    implicit none
    private
    public :: branch_options_t, branch_point_t, special_point_t, branch_origin_t, branches_t
    public :: follow_branches
    public :: special_kinds, end_kinds

contains

    !> Follow the branch of period-`cycles` orbits through the guess (x, v) at the model's
    !> value of opt%parameter, the period-doubled branches opt%doublings asks for, then the
    !> branches crossing at branch points that opt%branch_points asks for.
    !> `monitor` is told the points found (of max_points per branch) and may stop the work.
    subroutine follow_branches(model, phase, cycles, x, v, opt, res, err, monitor)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase
        integer, intent(in) :: cycles
        real(wp), intent(in) :: x(:), v(:)
        type(branch_options_t), intent(in) :: opt
        type(branches_t), intent(out) :: res
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(setting_t) :: set
        type(orbit_t) :: start
        logical :: stopped

        call check_options(model, opt, err)
        if (allocated(err)) return
        allocate (res%points(16), res%specials(4))
        res%end_reason = ''
        res%end_kind = ''
        call add_branch(res)
        set%model = model
        set%phase = phase
        set%cycles = cycles
        set%opt = opt
        if (set%opt%max_step == 0) set%opt%max_step = 20*abs(opt%step)
        if (set%opt%min_step == 0) set%opt%min_step = 1.0e-6_wp*abs(opt%step)
        set%low = min(model_parameter(model, opt%parameter), opt%stop)
        set%high = max(model_parameter(model, opt%parameter), opt%stop)
        call find_orbit(model, phase, cycles, x, v, start, err, opt%newton)
        if (allocated(err)) return
        res%start = start
        if (.not. start%converged) then
            call add_reason(res, 'newton', "branch 0: Newton failed at the start ("// &
                            opt%parameter// &
                            " = "//fmt_real(model_parameter(model, opt%parameter))//"): "// &
                            start%reason)
            return
        end if
        call follow_one(set, start, res, stopped, err, monitor)
        res%stopped = stopped
        if (allocated(err) .or. stopped) return
        call switch_levels(set, res, 'period-doubling', opt%doublings, err, monitor)
        if (allocated(err) .or. res%stopped) return
        call switch_levels(set, res, 'branch-point', opt%branch_points, err, monitor)
    end subroutine follow_branches

    !> Switch at the special points of `kind` ('period-doubling': onto the period-2p branch;
    !> 'branch-point': onto the two branches crossing there), `levels` deep: level 1 at those of
    !> every branch followed so far, each further level at those on the branches of the level
    !> before. set%branch: the last branch followed, with points or not.
    subroutine switch_levels(set, res, kind, levels, err, monitor)
        type(setting_t), intent(inout) :: set
        type(branches_t), intent(inout) :: res
        character(len=*), intent(in) :: kind
        integer, intent(in) :: levels
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        integer, allocatable :: level(:)
        integer :: depth, first, last, s
        logical :: stopped

        ! level(b): how many switches branch b is away from the branches followed before
        allocate (level(set%branch + 1))
        level = 0
        first = 1
        do depth = 1, levels
            last = res%n_specials
            do s = first, last
                if (res%specials(s)%kind /= kind) cycle
                if (level(res%points(res%specials(s)%point)%branch + 1) /= depth - 1) cycle
                set%branch = size(level)
                if (kind == 'period-doubling') then
                    level = [level, depth]
                    call switch_at_doubling(set, res, s, stopped, err, monitor)
                else
                    level = [level, depth, depth]
                    call switch_at_branch_point(set, res, s, stopped, err, monitor)
                end if
                res%stopped = stopped
                if (allocated(err) .or. stopped) return
            end do
            first = last + 1
        end do
    end subroutine switch_levels

    !> Refuse options no branch can be followed with.
    subroutine check_options(model, opt, err)
        type(model_t), intent(in) :: model
        type(branch_options_t), intent(in) :: opt
        type(error_t), allocatable, intent(out) :: err

        if (.not. allocated(opt%parameter)) then
            call set_error(err, "continuation: no parameter given")
        else if (.not. is_model_parameter(opt%parameter)) then
            call set_error(err, "continuation: parameter = '"//opt%parameter//"' is not one "// &
                           "of amplitude, omega, damping, restitution, spacing")
        else if (opt%max_points < 1) then
            call set_error(err, "continuation: max_points = "//fmt_int(opt%max_points)// &
                           " is not >= 1")
        else if (opt%max_points > 1 .and. .not. (abs(opt%step) > 0)) then
            call set_error(err, "continuation: step must be nonzero (its sign is the "// &
                           "direction)")
        else if (opt%doublings < 0) then
            call set_error(err, "continuation: doublings = "//fmt_int(opt%doublings)// &
                           " is not >= 0")
        else if (opt%branch_points < 0) then
            call set_error(err, "continuation: branch_points = "//fmt_int(opt%branch_points)// &
                           " is not >= 0")
        else if (opt%parameter == 'spacing' .and. &
                 any(model%spacing /= model%spacing(1))) then
            call set_error(err, "continuation: parameter = 'spacing' needs one spacing for "// &
                           "every bond")
        end if
    end subroutine check_options

    !> Follow one branch from the converged orbit `start` at the model's parameter value.
    subroutine follow_one(set, start, res, stopped, err, monitor)
        type(setting_t), intent(in) :: set
        type(orbit_t), intent(in) :: start
        type(branches_t), intent(inout) :: res
        logical, intent(out) :: stopped
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(cursor_t) :: here
        real(wp), allocatable :: direction(:)
        character(len=:), allocatable :: failure
        integer :: m

        stopped = .false.
        m = 2*set%model%n
        call cursor_from_orbit(set, model_parameter(set%model, set%opt%parameter), start, here)
        if (set%opt%max_points == 1) then
            ! Newton only: no tangent (it need not exist, at a fold)
            call store(set, here, res, err)
            if (.not. allocated(err)) call add_reason(res, 'max_points', "branch 0 "// &
                                                      "(period "//fmt_int(set%cycles)// &
                                                      "): max_points = 1: the orbit only, "// &
                                                      "no continuation")
            return
        end if
        ! the first tangent: the null vector of [J - I, dP/dmu] with dmu of the step's sign
        allocate (direction(m + 1))
        direction = 0
        direction(m + 1) = sign(1.0_wp, set%opt%step)
        call tangent_at(set, here, direction, err)
        if (allocated(err)) then
            ! (a result, not an error: the orbit is kept and the branch ends at once)
            failure = err%message
            deallocate (err)
            call store(set, here, res, err)
            if (.not. allocated(err)) call add_reason(res, 'newton', "branch 0 (period "// &
                                                      fmt_int(set%cycles)//"): no tangent "// &
                                                      "at the start: "//failure)
            return
        end if
        call walk(set, here, res, .false., stopped, err, monitor)
    end subroutine follow_one

    !> Switch at the period doubling `special` (index into the special points) onto the
    !> period-2p branch, set%branch: at the doubling the 2p branch crosses the p branch
    !> (doubled) with the tangent (e, 0), e the eigenvector of J for the multiplier -1.
    subroutine switch_at_doubling(set, res, special, stopped, err, monitor)
        type(setting_t), intent(in) :: set
        type(branches_t), intent(inout) :: res
        integer, intent(in) :: special
        logical, intent(out) :: stopped
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(setting_t) :: doubled
        type(cursor_t) :: here
        type(orbit_t) :: orbit
        real(wp) :: mu
        real(wp), allocatable :: e(:)
        integer :: index

        stopped = .false.
        index = res%specials(special)%point
        call add_branch(res, special)
        doubled = set
        doubled%cycles = 2*res%points(index)%orbit%cycles
        mu = res%points(index)%value
        call set_model_parameter(doubled%model, set%opt%parameter, mu)
        call real_eigenvector(res%points(index)%orbit%jacobian, -1.0_wp, e, err)
        if (allocated(err)) return
        ! the doubling orbit is a (degenerate) period-2p orbit: its own first point
        call find_orbit(doubled%model, set%phase, doubled%cycles, res%points(index)%orbit%x, &
                        res%points(index)%orbit%v, orbit, err, set%opt%newton)
        if (allocated(err)) return
        if (.not. orbit%converged) then
            call add_reason(res, 'newton', "branch "//fmt_int(doubled%branch)// &
                            ": Newton failed on "// &
                            "the doubled orbit at "//set%opt%parameter//" = "//fmt_real(mu)// &
                            ": "//orbit%reason)
            return
        end if
        call cursor_from_orbit(doubled, mu, orbit, here)
        here%tangent = [e, 0.0_wp]
        call walk(doubled, here, res, .true., stopped, err, monitor)
    end subroutine switch_at_doubling

    !> Switch at the branch point `special` (index into the special points) onto the two
    !> branches that cross there (chain_branch_switch), numbered set%branch and
    !> set%branch + 1, each followed from the branch point's orbit.
    subroutine switch_at_branch_point(set, res, special, stopped, err, monitor)
        type(setting_t), intent(in) :: set
        type(branches_t), intent(inout) :: res
        integer, intent(in) :: special
        logical, intent(out) :: stopped
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(setting_t) :: crossing
        type(cursor_t) :: starts(2)
        integer :: side, index

        stopped = .false.
        index = res%specials(special)%point
        crossing = set
        crossing%cycles = res%points(index)%orbit%cycles
        call set_model_parameter(crossing%model, set%opt%parameter, res%points(index)%value)
        call branch_point_starts(crossing, res%points(index), starts, err)
        if (allocated(err)) return
        do side = 1, 2
            crossing%branch = set%branch + side - 1
            call add_branch(res, special)
            call walk(crossing, starts(side), res, .true., stopped, err, monitor)
            if (allocated(err) .or. stopped) return
        end do
    end subroutine switch_at_branch_point

    !> Store `here` and step along the branch until it ends, through the grazings and corners
    !> met on the way (go_through). `switched`: the first step leaves a branch crossing, where the test
    !> functions are not compared.
    subroutine walk(set, here, res, switched, stopped, err, monitor)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(inout) :: here
        type(branches_t), intent(inout) :: res
        logical, intent(in) :: switched
        logical, intent(out) :: stopped
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(cursor_t) :: next, located
        character(len=:), allocatable :: reason, failure, kind
        real(wp) :: h, mu_next, value
        integer :: count, iterations
        logical :: ok, compare, crossed, passed

        call store(set, here, res, err)
        if (allocated(err)) return
        count = 0
        call count_point(set, count, stopped, monitor)
        if (stopped) return
        h = abs(set%opt%step)
        compare = .not. switched
        reason = ''
        kind = ''
        do
            if (count >= set%opt%max_points) then
                kind = 'max_points'
                reason = "max_points = "//fmt_int(set%opt%max_points)//" reached"
                exit
            end if
            call correct(set, here, h, next, ok, iterations, failure, err, crossed)
            if (allocated(err)) return
            if (.not. ok .and. (crossed .or. h/2 < set%opt%min_step) .and. compare) then
                ! Newton fails where the impacts change: a grazing or a corner, if a monitor
                ! of the last orbit with the old impacts vanishes (the failing step may end at
                ! one all the same at the smallest step)
                call locate_nonsmooth(set, here, merge(h, 2*(h/2), crossed), .false., res, &
                                      kind, value, err, located)
                if (allocated(err)) return
                call go_through(set, kind, located, value, res, here, h, passed, err)
                if (passed) call count_point(set, count, stopped, monitor)
                if (allocated(err) .or. stopped) return
                if (passed) cycle
                if (len(kind) > 0) then
                    reason = nonsmooth_reason(set, res, kind, value)
                    exit
                end if
            end if
            if (.not. ok) then
                h = h/2
                if (h < set%opt%min_step) then
                    kind = 'newton'
                    reason = "Newton failed at "//set%opt%parameter//" = "// &
                             fmt_real(here%y(size(here%y)))//" (step "//fmt_real(2*h)// &
                             "): "//failure
                    exit
                end if
                cycle
            end if
            mu_next = next%y(size(next%y))
            if (compare .and. any(next%impacts /= here%impacts)) then
                call end_at_impact_change(set, here, next, h, res, kind, reason, err, located, &
                                          value)
                if (allocated(err)) return
                call go_through(set, kind, located, value, res, here, h, passed, err)
                if (passed) call count_point(set, count, stopped, monitor)
                if (allocated(err) .or. stopped) return
                if (passed) cycle
                exit
            end if
            if (mu_next < set%low .or. mu_next > set%high) then
                kind = 'bound'
                call end_at_bound(set, here, next, res, reason, err)
                exit
            end if
            if (compare) call locate_specials(set, here, h, next, res, err)
            if (allocated(err)) return
            call store(set, next, res, err)
            if (allocated(err)) return
            call count_point(set, count, stopped, monitor)
            if (stopped) return
            here = next
            compare = .true.
            if (iterations <= 2) h = min(1.5_wp*h, set%opt%max_step)
            if (iterations >= 5) h = h/2
        end do
        if (allocated(err)) return
        call add_reason(res, kind, "branch "//fmt_int(set%branch)//" (period "// &
                        fmt_int(set%cycles)//"): "//reason)
    end subroutine walk

    !> One more point stored: the monitor is told and may stop the work.
    subroutine count_point(set, count, stopped, monitor)
        type(setting_t), intent(in) :: set
        integer, intent(inout) :: count
        logical, intent(out) :: stopped
        class(monitor_t), intent(inout), optional :: monitor

        count = count + 1
        stopped = .false.
        if (present(monitor)) stopped = .not. monitor%keep_going(stage_points, int(count, i8), &
                                                                 int(set%opt%max_points, i8))
    end subroutine count_point

    !> At a grazing just stored (`kind`, the orbit `located` at `value`, `here` the point before
    !> it): the first orbit of the family on the other side (chain_branch_graze), with a new
    !> impact of speed 1e-3 (up to 1e-2) or at 1e-4 |step| from the grazing, stored, becomes `here`
    !> (`passed`); the step starts at its distance from the grazing. Where an impact's speed
    !> vanished, the grazing is stored again as located from the other side, and that first
    !> orbit found again from there (the impacting side's value is only as good as Newton
    !> with a Jacobian like 1/u, and would round differently with other BLAS kernels).
    !> At a corner: the orbit with the impacts in another order at 1e-4 |step| past it
    !> (chain_branch_corner); the step starts at its distance from the corner orbit.
    subroutine go_through(set, kind, located, value, res, here, h, passed, err)
        type(setting_t), intent(in) :: set
        character(len=*), intent(in) :: kind
        type(cursor_t), intent(in) :: located
        real(wp), intent(in) :: value
        type(branches_t), intent(inout) :: res
        type(cursor_t), intent(inout) :: here
        real(wp), intent(inout) :: h
        logical, intent(out) :: passed
        type(error_t), allocatable, intent(out) :: err
        real(wp), parameter :: v_new = 1.0e-3_wp
        type(cursor_t) :: found, graze
        real(wp) :: mu_g, delta, distance
        logical :: better

        passed = .false.
        delta = 1.0e-4_wp*abs(set%opt%step)
        if (kind == 'corner') then
            call pass_corner(set, located, here, value, delta, found, distance, passed, err)
            if (allocated(err) .or. .not. passed) return
            call store(set, found, res, err)
            if (allocated(err)) return
            h = min(max(distance, delta), abs(set%opt%step))
            here = found
            return
        end if
        if (kind /= 'grazing') return
        call pass_grazing(set, located, here, value, res%points(res%n_points)%symmetric, &
                          delta, v_new, found, passed, err)
        if (allocated(err) .or. .not. passed) return
        graze = located
        if (located%orbit%min_impact_speed < located%orbit%min_gap) then
            call grazing_from_gap(set, found, value, graze, mu_g, better, err)
            if (allocated(err)) return
            if (better) then
                res%n_points = res%n_points - 1
                call store(set, graze, res, err)
                if (allocated(err)) return
                res%specials(res%n_specials)%value = mu_g
                call first_past(set, graze, mu_g, &
                                mu_g + sign(delta, found%y(size(found%y)) - mu_g), found, err)
                if (allocated(err)) return
            else
                graze = located
            end if
        end if
        call store(set, found, res, err)
        if (allocated(err)) return
        h = min(norm2(found%y - graze%y), abs(set%opt%step))
        here = found
    end subroutine go_through

    !> The orbit of graze's family at mu, with its tangent oriented away from the grazing at
    !> mu_g (where an impact's speed falls to zero on the way up and the other family lies on
    !> the same side, the branch turns there): it replaces found when Newton finds it.
    subroutine first_past(set, graze, mu_g, mu, found, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: graze
        real(wp), intent(in) :: mu_g, mu
        type(cursor_t), intent(inout) :: found
        type(error_t), allocatable, intent(out) :: err
        type(cursor_t) :: again
        real(wp), allocatable :: away(:)
        logical :: ok

        call orbit_at(set, graze, mu, again, ok, err)
        if (allocated(err) .or. .not. ok) return
        allocate (away(size(again%y)))
        away = 0
        away(size(away)) = sign(1.0_wp, mu - mu_g)
        call tangent_at(set, again, away, err)
        if (allocated(err)) then
            ! (no tangent there: the first orbit stays as found)
            deallocate (err)
            return
        end if
        found = again
    end subroutine first_past

    !> The step from `here` to `next` changes the impacts. Past a bound they may change beyond
    !> it: the branch ends on the bound if the orbit there keeps them; else it ends at the
    !> grazing or corner located in the step ('impacts' when no monitor vanishes there).
    subroutine end_at_impact_change(set, here, next, h, res, kind, reason, err, located, value)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: here, next
        real(wp), intent(in) :: h
        type(branches_t), intent(inout) :: res
        character(len=:), allocatable, intent(out) :: kind, reason
        type(error_t), allocatable, intent(out) :: err
        type(cursor_t), intent(out) :: located !! the orbit stored there
        real(wp), intent(out) :: value         !! where its monitor vanishes
        real(wp) :: mu_next
        logical :: reached

        mu_next = next%y(size(next%y))
        reached = .false.
        if (mu_next < set%low .or. mu_next > set%high) &
            call end_at_bound(set, here, next, res, reason, err, here%impacts, reached)
        if (allocated(err)) return
        if (reached) then
            kind = 'bound'
            return
        end if
        value = mu_next
        call locate_nonsmooth(set, here, h, .true., res, kind, value, err, located)
        if (allocated(err)) return
        if (len(kind) == 0) kind = 'impacts'
        reason = nonsmooth_reason(set, res, kind, value)
    end subroutine end_at_impact_change

    !> The next point past a bound of the parameter: the branch ends on the bound, with the
    !> orbit there found by Newton at the bound's value from the interpolated state. With
    !> `impacts`, only an orbit with these impacts per bond is the branch's (`reached`; else
    !> nothing is stored).
    subroutine end_at_bound(set, here, next, res, reason, err, impacts, reached)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: here, next
        type(branches_t), intent(inout) :: res
        character(len=:), allocatable, intent(out) :: reason
        type(error_t), allocatable, intent(out) :: err
        integer, intent(in), optional :: impacts(:)
        logical, intent(out), optional :: reached
        type(model_t) :: model
        type(orbit_t) :: orbit
        type(cursor_t) :: last
        real(wp) :: bound, mu0, mu1, frac
        real(wp), allocatable :: z(:)
        integer :: m

        m = size(here%y) - 1
        mu0 = here%y(m + 1)
        mu1 = next%y(m + 1)
        bound = set%high
        if (mu1 < set%low) bound = set%low
        frac = (bound - mu0)/(mu1 - mu0)
        z = here%y(:m) + frac*(next%y(:m) - here%y(:m))
        model = set%model
        call set_model_parameter(model, set%opt%parameter, bound)
        call find_orbit(model, set%phase, set%cycles, z(1::2), z(2::2), orbit, err, &
                        set%opt%newton)
        if (present(reached)) reached = .false.
        if (allocated(err)) return
        reason = "reached the bound "//set%opt%parameter//" = "//fmt_real(bound)
        if (.not. orbit%converged) then
            reason = reason//" (Newton failed on the bound: "//orbit%reason//")"
            return
        end if
        call cursor_from_orbit(set, bound, orbit, last)
        if (present(impacts)) then
            if (any(last%impacts /= impacts)) return
        end if
        if (present(reached)) reached = .true.
        call store(set, last, res, err)
    end subroutine end_at_bound

end module chain_branch
