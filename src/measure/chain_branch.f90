!> Branches of periodic orbits followed in one parameter (docs/model.md section 12):
!> pseudo-arclength continuation of y = (z, mu), z the orbit's state on the section, with the
!> exact Jacobian [J - I, dP/dmu] (chain_floquet, chain_parameter); an adaptive step; the
!> special points between two points detected by test functions and located on the branch
!> (fold: the tangent's parameter component; period doubling: det(J + I); Neimark-Sacker: the
!> complex multipliers outside the unit circle; grazing: the impacts per bond change), and
!> branch switching at a period doubling onto the period-2p branch.
!>
!> The branch stops at the bounds of the parameter (the interval from its start to `stop`),
!> after `max_points` points, at a grazing (the map is not smooth there: the branch ends and
!> says so) or when Newton fails at the smallest step; each is a result with its reason, not
!> an error.
module chain_branch
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int, fmt_real
    use chain_model, only: model_t, model_parameter, set_model_parameter, is_model_parameter
    use chain_engine, only: chain_t, chain_positions, chain_time
    use chain_event_log, only: event_log_t, event_log_init, event_impact
    use chain_section, only: chain_at_section, advance_to_point
    use chain_orbit, only: orbit_t, orbit_options_t, find_orbit, orbit_pass_t, orbit_pass, &
                           describe_orbit, interleave
    use chain_parameter, only: map_parameter_derivative
    use chain_lapack, only: solve_linear
    use chain_monitor, only: monitor_t, stage_points
    implicit none
    private
    public :: branch_options_t, branch_point_t, special_point_t, branches_t, follow_branches
    public :: special_kinds

    !> The kinds of special point, as stored.
    character(len=*), parameter :: special_kinds(4) = &
        [character(len=15) :: 'fold', 'period-doubling', 'neimark-sacker', 'grazing']

    type :: branch_options_t
        character(len=:), allocatable :: parameter !! one of chain_parameter's orbit_parameters
        real(wp) :: stop = 0      !! the far bound of the parameter
        real(wp) :: step = 0      !! first arclength step; its sign: the parameter's direction
        integer :: max_points = 200 !! per branch; 1: Newton only, no continuation
        !> levels of period-doubled branches followed (0: none; 1: the 2p branches from the
        !> first branch's period doublings; 2: also the 4p branches from those; ...)
        integer :: doublings = 0
        real(wp) :: max_step = 0  !! largest |step| (0: 20 |step|)
        real(wp) :: min_step = 0  !! smallest |step| before Newton's failure ends (0: 1e-6 |step|)
        type(orbit_options_t) :: newton
    end type branch_options_t

    !> One periodic orbit on a branch.
    type :: branch_point_t
        real(wp) :: value = 0     !! the parameter
        integer :: branch = 0     !! 0 the first branch, 1, 2, ... those switched to
        type(orbit_t) :: orbit    !! state, multipliers, impacts, grazing monitors
        real(wp), allocatable :: strobe_x(:, :) !! (n, p): positions at the p section crossings
        logical :: stable = .false. !! every multiplier inside the unit circle
    end type branch_point_t

    type :: special_point_t
        integer :: point = 0      !! index into the points (the located orbit is a point)
        character(len=:), allocatable :: kind !! one of special_kinds
        real(wp) :: value = 0
    end type special_point_t

    !> Everything followed: the points of every branch in order, the special points, and why
    !> each branch ended.
    type :: branches_t
        integer :: n_points = 0
        type(branch_point_t), allocatable :: points(:)
        integer :: n_specials = 0
        type(special_point_t), allocatable :: specials(:)
        character(len=:), allocatable :: end_reason !! of every branch, one line each
        logical :: stopped = .false. !! the monitor stopped the work: the result is partial
        !> Newton's result from the guess, converged or not (converged: the first point's orbit)
        type(orbit_t) :: start
    end type branches_t

    !> Where the continuation stands: a point on the branch and its unit tangent.
    type :: cursor_t
        real(wp), allocatable :: y(:)        !! (z, mu)
        real(wp), allocatable :: tangent(:)  !! unit, (dz, dmu)
        real(wp), allocatable :: jacobian(:, :)
        type(orbit_t) :: orbit
        integer, allocatable :: impacts(:)   !! impacts per bond 0..n over one period
        real(wp) :: det_plus = 0             !! det(J + I)
        integer :: unstable_pairs = 0        !! complex pairs outside the unit circle
    end type cursor_t

    !> Fixed things of one branch.
    type :: setting_t
        type(model_t) :: model
        real(wp) :: phase = 0
        integer :: cycles = 1
        integer :: branch = 0
        real(wp) :: low = 0, high = 0  !! the parameter's bounds
        type(branch_options_t) :: opt
    end type setting_t

contains

    !> Follow the branch of period-`cycles` orbits through the guess (x, v) at the model's
    !> value of opt%parameter, and the period-doubled branches opt%doublings asks for.
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
        integer, allocatable :: level(:)
        integer :: depth, first, last, s
        logical :: stopped

        call check_options(model, opt, err)
        if (allocated(err)) return
        allocate (res%points(16), res%specials(4))
        res%end_reason = ''
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
            call add_reason(res, "branch 0: Newton failed at the start ("//opt%parameter// &
                            " = "//fmt_real(model_parameter(model, opt%parameter))//"): "// &
                            start%reason)
            return
        end if
        call follow_one(set, start, res, stopped, err, monitor)
        res%stopped = stopped
        if (allocated(err) .or. stopped) return
        ! level(b): how many doublings branch b is away from the first
        level = [0]
        first = 1
        do depth = 1, opt%doublings
            last = res%n_specials
            do s = first, last
                if (res%specials(s)%kind /= 'period-doubling') cycle
                if (level(res%points(res%specials(s)%point)%branch + 1) /= depth - 1) cycle
                set%branch = size(level)
                level = [level, depth]
                call switch_at_doubling(set, res, res%specials(s)%point, stopped, err, monitor)
                res%stopped = stopped
                if (allocated(err) .or. stopped) return
            end do
            first = last + 1
        end do
    end subroutine follow_branches

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
        else if (opt%parameter == 'spacing' .and. &
                 any(model%spacing /= model%spacing(1))) then
            call set_error(err, "continuation: parameter = 'spacing' needs one spacing for "// &
                           "every bond")
        end if
    end subroutine check_options

    ! --------------------------------------------------------------------- one branch

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
        integer :: m

        stopped = .false.
        m = 2*set%model%n
        call cursor_from_orbit(set, model_parameter(set%model, set%opt%parameter), start, here)
        if (set%opt%max_points == 1) then
            ! Newton only: no tangent (it need not exist, at a fold)
            call store(set, here, res, err)
            if (.not. allocated(err)) call add_reason(res, "branch 0 (period "// &
                                                      fmt_int(set%cycles)//"): max_points "// &
                                                      "= 1: the orbit only, no continuation")
            return
        end if
        ! the first tangent: the null vector of [J - I, dP/dmu] with dmu of the step's sign
        allocate (direction(m + 1))
        direction = 0
        direction(m + 1) = sign(1.0_wp, set%opt%step)
        call tangent_at(set, here, direction, err)
        if (allocated(err)) return
        call walk(set, here, res, .false., stopped, err, monitor)
    end subroutine follow_one

    !> Switch at the period doubling at point `index` onto the period-2p branch: at the
    !> doubling the 2p branch crosses the p branch (doubled) with the tangent (e, 0), e the
    !> eigenvector of J for the multiplier -1.
    subroutine switch_at_doubling(set, res, index, stopped, err, monitor)
        type(setting_t), intent(in) :: set
        type(branches_t), intent(inout) :: res
        integer, intent(in) :: index
        logical, intent(out) :: stopped
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(setting_t) :: doubled
        type(cursor_t) :: here
        type(orbit_t) :: orbit
        real(wp) :: mu
        real(wp), allocatable :: e(:)

        stopped = .false.
        doubled = set
        doubled%cycles = 2*res%points(index)%orbit%cycles
        mu = res%points(index)%value
        call set_model_parameter(doubled%model, set%opt%parameter, mu)
        call doubling_eigenvector(res%points(index)%orbit%jacobian, e, err)
        if (allocated(err)) return
        ! the doubling orbit is a (degenerate) period-2p orbit: its own first point
        call find_orbit(doubled%model, set%phase, doubled%cycles, res%points(index)%orbit%x, &
                        res%points(index)%orbit%v, orbit, err, set%opt%newton)
        if (allocated(err)) return
        if (.not. orbit%converged) then
            call add_reason(res, "branch "//fmt_int(doubled%branch)//": Newton failed on "// &
                            "the doubled orbit at "//set%opt%parameter//" = "//fmt_real(mu)// &
                            ": "//orbit%reason)
            return
        end if
        call cursor_from_orbit(doubled, mu, orbit, here)
        here%tangent = [e, 0.0_wp]
        call walk(doubled, here, res, .true., stopped, err, monitor)
    end subroutine switch_at_doubling

    !> Store `here` and step along the branch until it ends. `switched`: the first step leaves a
    !> branch crossing, where the test functions are not compared.
    subroutine walk(set, here, res, switched, stopped, err, monitor)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(inout) :: here
        type(branches_t), intent(inout) :: res
        logical, intent(in) :: switched
        logical, intent(out) :: stopped
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(cursor_t) :: next
        character(len=:), allocatable :: reason, failure
        real(wp) :: h, mu_next
        integer :: count, iterations
        logical :: ok, compare, crossed, grazed

        stopped = .false.
        call store(set, here, res, err)
        if (allocated(err)) return
        count = 1
        if (present(monitor)) then
            stopped = .not. monitor%keep_going(stage_points, int(count, i8), &
                                               int(set%opt%max_points, i8))
            if (stopped) return
        end if
        h = abs(set%opt%step)
        compare = .not. switched
        reason = ''
        do
            if (count >= set%opt%max_points) then
                reason = "max_points = "//fmt_int(set%opt%max_points)//" reached"
                exit
            end if
            call correct(set, here, h, next, ok, iterations, failure, err, crossed)
            if (allocated(err)) return
            if (.not. ok .and. crossed .and. compare) then
                ! Newton fails where the impacts change: a grazing, if the last orbit with
                ! the old impacts has a vanishing gap or impact speed
                call locate_grazing(set, here, h, res, err, grazed)
                if (allocated(err)) return
                if (grazed) then
                    reason = grazing_reason(set, res)
                    exit
                end if
            end if
            if (.not. ok) then
                h = h/2
                if (h < set%opt%min_step) then
                    reason = "Newton failed at "//set%opt%parameter//" = "// &
                             fmt_real(here%y(size(here%y)))//" (step "//fmt_real(2*h)// &
                             "): "//failure
                    exit
                end if
                cycle
            end if
            mu_next = next%y(size(next%y))
            if (compare .and. any(next%impacts /= here%impacts)) then
                call locate_grazing(set, here, h, res, err)
                if (allocated(err)) return
                reason = grazing_reason(set, res)
                exit
            end if
            if (mu_next < set%low .or. mu_next > set%high) then
                call end_at_bound(set, here, next, res, reason, err)
                exit
            end if
            if (compare) call locate_specials(set, here, h, next, res, err)
            if (allocated(err)) return
            call store(set, next, res, err)
            if (allocated(err)) return
            count = count + 1
            if (present(monitor)) then
                stopped = .not. monitor%keep_going(stage_points, int(count, i8), &
                                                   int(set%opt%max_points, i8))
                if (stopped) return
            end if
            here = next
            compare = .true.
            if (iterations <= 2) h = min(1.5_wp*h, set%opt%max_step)
            if (iterations >= 5) h = h/2
        end do
        if (allocated(err)) return
        call add_reason(res, "branch "//fmt_int(set%branch)//" (period "// &
                        fmt_int(set%cycles)//"): "//reason)
    end subroutine walk

    !> The next point past a bound of the parameter: the branch ends on the bound, with the
    !> orbit there found by Newton at the bound's value from the interpolated state.
    subroutine end_at_bound(set, here, next, res, reason, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: here, next
        type(branches_t), intent(inout) :: res
        character(len=:), allocatable, intent(out) :: reason
        type(error_t), allocatable, intent(out) :: err
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
        if (allocated(err)) return
        reason = "reached the bound "//set%opt%parameter//" = "//fmt_real(bound)
        if (.not. orbit%converged) then
            reason = reason//" (Newton failed on the bound: "//orbit%reason//")"
            return
        end if
        call cursor_from_orbit(set, bound, orbit, last)
        call store(set, last, res, err)
    end subroutine end_at_bound

    ! ------------------------------------------------------------ predictor-corrector

    !> From `here`, the point at arclength h along the tangent: Newton on
    !> (P(z; mu) - z, t . (y - y_pred)) = 0 with the bordered Jacobian [[J - I, P_mu], [t]].
    !> ok = .false. with `failure` saying why when it does not converge.
    subroutine correct(set, here, h, next, ok, iterations, failure, err, crossed)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: here
        real(wp), intent(in) :: h
        type(cursor_t), intent(out) :: next
        logical, intent(out) :: ok
        integer, intent(out) :: iterations
        character(len=:), allocatable, intent(out) :: failure
        type(error_t), allocatable, intent(out) :: err
        !> some iterate had other impacts per bond than `here`
        logical, intent(out), optional :: crossed
        integer, parameter :: max_iterations = 10
        real(wp), parameter :: floor_factor = 100
        type(orbit_pass_t) :: pass
        type(model_t) :: model
        real(wp), allocatable :: y(:), y_pred(:), a(:, :), rhs(:, :), p_mu(:)
        real(wp) :: previous
        integer :: m, info

        ok = .false.
        failure = ''
        if (present(crossed)) crossed = .false.
        m = size(here%y) - 1
        y_pred = here%y + h*here%tangent
        y = y_pred
        previous = huge(1.0_wp)
        model = set%model
        do iterations = 0, max_iterations
            call set_model_parameter(model, set%opt%parameter, y(m + 1))
            if (.not. parameter_allowed(set%opt%parameter, y(m + 1))) then
                failure = "the parameter left its physical range"
                return
            end if
            call orbit_pass(model, set%phase, set%cycles, y(:m), pass, err)
            if (allocated(err)) return
            if (present(crossed) .and. pass%admissible) then
                if (any(impacts_per_bond(set%model%n, pass%log%site(:pass%log%count), &
                                         pass%log%kind(:pass%log%count)) /= here%impacts)) &
                    crossed = .true.
            end if
            if (.not. pass%admissible) then
                failure = "a negative gap"
            else if (pass%rests) then
                failure = "the orbit sticks on a wall (rest): not supported"
            else if (pass%collapse) then
                failure = "the cluster rule acts on the orbit: not supported"
            else if (pass%residual/4 > previous .and. iterations >= 2) then
                failure = "Newton diverges (residual "//fmt_real(pass%residual)//")"
            end if
            if (len(failure) > 0) return
            if (pass%residual <= set%opt%newton%tolerance) exit
            ! the rounding floor: a full step that gained less than a factor 10 close to the
            ! tolerance (an unstable orbit's map amplifies rounding by its largest multiplier)
            if (iterations >= 2 .and. pass%residual <= floor_factor*set%opt%newton%tolerance &
                .and. pass%residual > previous/10) exit
            if (iterations == max_iterations) then
                failure = "no convergence in "//fmt_int(max_iterations)//" iterations "// &
                          "(residual "//fmt_real(pass%residual)//")"
                return
            end if
            previous = pass%residual
            call map_parameter_derivative(model, set%phase, set%cycles, y(1:m:2), y(2:m:2), &
                                          set%opt%parameter, pass%jacobian, p_mu, err)
            if (allocated(err)) then
                ! (a triple contact or a rest on the way: this trial fails, not the run)
                failure = err%message
                deallocate (err)
                return
            end if
            call bordered(pass%jacobian, p_mu, here%tangent, a)
            allocate (rhs(m + 1, 1))
            rhs(:m, 1) = pass%z - pass%image
            rhs(m + 1, 1) = -dot_product(here%tangent, y - y_pred)
            call solve_linear(a, rhs, info)
            if (info > 0) then
                failure = "singular bordered Jacobian"
                return
            end if
            y = y + rhs(:, 1)
            deallocate (rhs)
        end do
        ok = .true.
        next%y = y
        call cursor_from_pass(set, model, pass, iterations, next, err)
        if (allocated(err)) return
        call tangent_at(set, next, here%tangent, err)
    end subroutine correct

    !> [[J - I, p_mu], [t]]: the Jacobian of the corrector's equations.
    pure subroutine bordered(jacobian, p_mu, tangent, a)
        real(wp), intent(in) :: jacobian(:, :), p_mu(:), tangent(:)
        real(wp), allocatable, intent(out) :: a(:, :)
        integer :: m, i

        m = size(p_mu)
        allocate (a(m + 1, m + 1))
        a(:m, :m) = jacobian
        do i = 1, m
            a(i, i) = a(i, i) - 1
        end do
        a(:m, m + 1) = p_mu
        a(m + 1, :) = tangent
    end subroutine bordered

    !> The unit tangent at c: [[J - I, P_mu], [direction]] t = (0, 1), normalised, oriented
    !> along `direction` (the previous tangent).
    subroutine tangent_at(set, c, direction, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(inout) :: c
        real(wp), intent(in) :: direction(:)
        type(error_t), allocatable, intent(out) :: err
        type(model_t) :: model
        real(wp), allocatable :: p_mu(:), a(:, :), rhs(:, :)
        integer :: m, info

        m = size(c%y) - 1
        model = set%model
        call set_model_parameter(model, set%opt%parameter, c%y(m + 1))
        call map_parameter_derivative(model, set%phase, set%cycles, c%y(1:m:2), c%y(2:m:2), &
                                      set%opt%parameter, c%jacobian, p_mu, err)
        if (allocated(err)) return
        call bordered(c%jacobian, p_mu, direction, a)
        allocate (rhs(m + 1, 1))
        rhs = 0
        rhs(m + 1, 1) = 1
        call solve_linear(a, rhs, info)
        if (info > 0) then
            call set_error(err, "continuation: singular bordered Jacobian at "// &
                           set%opt%parameter//" = "//fmt_real(c%y(m + 1)))
            return
        end if
        c%tangent = rhs(:, 1)/norm2(rhs(:, 1))
        if (dot_product(c%tangent, direction) < 0) c%tangent = -c%tangent
    end subroutine tangent_at

    ! --------------------------------------------------------------- special points

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
        type(cursor_t) :: found(3)
        real(wp) :: at(3)
        logical :: seen(3)
        integer :: k, j, m, rank

        m = size(here%y) - 1
        seen(1) = here%tangent(m + 1)*next%tangent(m + 1) < 0
        seen(2) = (here%det_plus < 0) .neqv. (next%det_plus < 0)
        seen(3) = here%unstable_pairs /= next%unstable_pairs
        at = huge(1.0_wp)
        ! (the first pair to cross: pairs of a symmetric chain come twice and cross together)
        rank = min(here%unstable_pairs, next%unstable_pairs) + 1
        do k = 1, 3
            if (.not. seen(k)) cycle
            call locate(set, here, h, k, rank, found(k), at(k), err)
            if (allocated(err)) return
            seen(k) = confirmed(found(k)%orbit, k)
        end do
        do j = 1, count(seen)
            k = minloc(at, 1, mask=seen)
            call store(set, found(k), res, err)
            if (allocated(err)) return
            call add_special(res, res%n_points, special_kinds(k), found(k)%y(m + 1))
            seen(k) = .false.
        end do
    end subroutine locate_specials

    !> The zero of test function `kind` (1 fold, 2 period doubling, 3 Neimark-Sacker) on the
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
            case (1)
                confirmed = minval(hypot(re - 1, im)) < within
            case (2)
                confirmed = minval(hypot(re + 1, im)) < within
            case default
                confirmed = minval(abs(hypot(re, im) - 1), mask=im /= 0) < within
            end select
        end associate
    end function confirmed

    !> The impacts change within arclength h of `here`: bisection on the arclength for the
    !> last orbit with the impacts of `here` (a trial where Newton fails counts as changed),
    !> to 1e-11 in the parameter. It is stored as a grazing point, unconditionally or, with
    !> `grazed`, only when its smallest gap or impact speed is below 1e-4 (else Newton failed
    !> for another reason than a grazing and nothing is stored).
    subroutine locate_grazing(set, here, h, res, err, grazed)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: here
        real(wp), intent(in) :: h
        type(branches_t), intent(inout) :: res
        type(error_t), allocatable, intent(out) :: err
        logical, intent(out), optional :: grazed
        real(wp), parameter :: vanishing = 1.0e-4_wp
        type(cursor_t) :: trial, last_same
        character(len=:), allocatable :: failure
        real(wp) :: s_lo, s_hi, s, mu_lo, mu_hi, value
        integer :: k, iterations, m
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
        if (present(grazed)) then
            grazed = min(last_same%orbit%min_gap, last_same%orbit%min_impact_speed) < vanishing
            if (.not. grazed) return
        end if
        value = grazing_value(here, last_same)
        call store(set, last_same, res, err)
        if (.not. allocated(err)) call add_special(res, res%n_points, 'grazing', value)
    end subroutine locate_grazing

    !> Where the grazing monitor of the last orbit with the old impacts (its smallest gap or
    !> impact speed, whichever is smaller) reaches zero, by the secant through it and the
    !> branch's point before the bisection: as an impact vanishes its saltation grows as
    !> 1 / speed, and Newton stops converging before the speed is zero, so the last orbit
    !> stands some 1e-5 short of the grazing. The orbit's own parameter when the secant does
    !> not apply (a monitor that did not decrease, or a root farther than the two points'
    !> distance).
    pure real(wp) function grazing_value(before, last) result(value)
        type(cursor_t), intent(in) :: before, last
        real(wp) :: g_last, g_before, mu_last, mu_before
        integer :: m

        m = size(last%y) - 1
        mu_last = last%y(m + 1)
        mu_before = before%y(m + 1)
        value = mu_last
        if (last%orbit%min_impact_speed < last%orbit%min_gap) then
            g_last = last%orbit%min_impact_speed
            g_before = before%orbit%min_impact_speed
        else
            g_last = last%orbit%min_gap
            g_before = before%orbit%min_gap
        end if
        if (.not. (g_before > g_last .and. g_last >= 0 .and. g_before < huge(1.0_wp))) return
        if (abs(g_last*(mu_last - mu_before)/(g_last - g_before)) > abs(mu_last - mu_before)) &
            return
        value = mu_last - g_last*(mu_last - mu_before)/(g_last - g_before)
    end function grazing_value

    !> Why a branch ended at the grazing just stored.
    function grazing_reason(set, res) result(reason)
        type(setting_t), intent(in) :: set
        type(branches_t), intent(in) :: res
        character(len=:), allocatable :: reason

        reason = "grazing at "//set%opt%parameter//" = "// &
                 fmt_real(res%specials(res%n_specials)%value)// &
                 ": the impacts change there, the branch ends"
    end function grazing_reason

    ! ----------------------------------------------------------------- the cursor

    !> A cursor at a converged orbit at parameter value mu (tangent not set).
    subroutine cursor_from_orbit(set, mu, orbit, c)
        type(setting_t), intent(in) :: set
        real(wp), intent(in) :: mu
        type(orbit_t), intent(in) :: orbit
        type(cursor_t), intent(out) :: c

        c%y = [interleave(orbit%x, orbit%v), mu]
        c%orbit = orbit
        c%jacobian = orbit%jacobian
        call measure(set, c)
    end subroutine cursor_from_orbit

    !> A cursor at the converged pass (c%y set), described as an orbit.
    subroutine cursor_from_pass(set, model, pass, iterations, c, err)
        type(setting_t), intent(in) :: set
        type(model_t), intent(in) :: model
        type(orbit_pass_t), intent(in) :: pass
        integer, intent(in) :: iterations
        type(cursor_t), intent(inout) :: c
        type(error_t), allocatable, intent(out) :: err

        c%orbit%converged = .true.
        c%orbit%reason = ''
        c%orbit%cycles = set%cycles
        c%orbit%phase = set%phase
        c%orbit%iterations = iterations
        c%orbit%residuals = [pass%residual]
        call describe_orbit(model, pass, c%orbit, err)
        if (allocated(err)) return
        c%jacobian = c%orbit%jacobian
        call measure(set, c)
    end subroutine cursor_from_pass

    !> The impacts per bond and the test quantities of the multipliers.
    pure subroutine measure(set, c)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(inout) :: c
        integer :: j

        associate (o => c%orbit)
            c%impacts = impacts_per_bond(set%model%n, o%event_bond, o%event_kind)
            c%det_plus = 1
            c%unstable_pairs = 0
            do j = 1, size(o%multipliers_re)
                if (o%multipliers_im(j) == 0) then
                    c%det_plus = c%det_plus*(1 + o%multipliers_re(j))
                else
                    c%det_plus = c%det_plus*hypot(1 + o%multipliers_re(j), &
                                                  o%multipliers_im(j))
                    if (o%multipliers_im(j) > 0 .and. &
                        hypot(o%multipliers_re(j), o%multipliers_im(j)) > 1) &
                        c%unstable_pairs = c%unstable_pairs + 1
                end if
            end do
        end associate
    end subroutine measure

    !> Impacts per bond 0..n among events (bonds, kinds).
    pure function impacts_per_bond(n, bonds, kinds) result(counts)
        integer, intent(in) :: n, bonds(:), kinds(:)
        integer :: counts(0:n)
        integer :: j

        counts = 0
        do j = 1, size(bonds)
            if (kinds(j) == event_impact) counts(bonds(j)) = counts(bonds(j)) + 1
        end do
    end function impacts_per_bond

    ! --------------------------------------------------------------------- results

    !> Append the cursor's orbit as a point, with its section crossings and its stability.
    subroutine store(set, c, res, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: c
        type(branches_t), intent(inout) :: res
        type(error_t), allocatable, intent(out) :: err
        type(branch_point_t), allocatable :: grown(:)
        type(branch_point_t) :: p
        type(model_t) :: model
        type(chain_t) :: chain
        type(event_log_t) :: log
        integer :: j
        integer(i8) :: cycle

        p%value = c%y(size(c%y))
        p%branch = set%branch
        p%orbit = c%orbit
        p%stable = maxval(hypot(c%orbit%multipliers_re, c%orbit%multipliers_im)) < 1
        model = set%model
        call set_model_parameter(model, set%opt%parameter, p%value)
        allocate (p%strobe_x(model%n, set%cycles))
        p%strobe_x(:, 1) = c%orbit%x
        if (set%cycles > 1) then
            call chain_at_section(model, set%phase, c%orbit%x, c%orbit%v, chain, err)
            if (allocated(err)) return
            call event_log_init(log, .false., 0)
            do j = 2, set%cycles
                cycle = j - 1
                call advance_to_point(chain, cycle, chain_time(chain), log, err)
                if (allocated(err)) return
                p%strobe_x(:, j) = chain_positions(chain)
            end do
        end if
        if (res%n_points == size(res%points)) then
            allocate (grown(2*size(res%points)))
            grown(:res%n_points) = res%points
            call move_alloc(grown, res%points)
        end if
        res%n_points = res%n_points + 1
        res%points(res%n_points) = p
    end subroutine store

    subroutine add_special(res, point, kind, value)
        type(branches_t), intent(inout) :: res
        integer, intent(in) :: point
        character(len=*), intent(in) :: kind
        real(wp), intent(in) :: value
        type(special_point_t), allocatable :: grown(:)

        if (res%n_specials == size(res%specials)) then
            allocate (grown(2*size(res%specials)))
            grown(:res%n_specials) = res%specials
            call move_alloc(grown, res%specials)
        end if
        res%n_specials = res%n_specials + 1
        res%specials(res%n_specials) = special_point_t(point, kind, value)
    end subroutine add_special

    subroutine add_reason(res, line)
        type(branches_t), intent(inout) :: res
        character(len=*), intent(in) :: line

        if (len(res%end_reason) > 0) res%end_reason = res%end_reason//new_line('a')
        res%end_reason = res%end_reason//line
    end subroutine add_reason

    !> Values a parameter can physically take (validated like the input).
    pure logical function parameter_allowed(name, value)
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: value

        select case (name)
        case ('omega', 'spacing')
            parameter_allowed = value > 0
        case ('damping')
            parameter_allowed = value >= 0 .and. value < 1
        case ('restitution')
            parameter_allowed = value >= 0 .and. value <= 1
        case default
            parameter_allowed = value >= 0
        end select
    end function parameter_allowed

    !> The unit eigenvector of J for its real eigenvalue nearest -1, by inverse iteration on
    !> J + I (nearly singular at a period doubling).
    subroutine doubling_eigenvector(jacobian, e, err)
        real(wp), intent(in) :: jacobian(:, :)
        real(wp), allocatable, intent(out) :: e(:)
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: a(:, :), b(:, :)
        integer :: m, i, k, info

        m = size(jacobian, 1)
        allocate (b(m, 1))
        b(:, 1) = [(1.0_wp + 0.1_wp*i, i=1, m)]
        do k = 1, 3
            a = jacobian
            do i = 1, m
                a(i, i) = a(i, i) + 1 + 1.0e-12_wp
            end do
            call solve_linear(a, b, info)
            if (info > 0) exit
            b = b/norm2(b(:, 1))
        end do
        if (.not. all(abs(b) < huge(1.0_wp))) then
            call set_error(err, "continuation: no eigenvector for the multiplier -1")
            return
        end if
        e = b(:, 1)
    end subroutine doubling_eigenvector

end module chain_branch
