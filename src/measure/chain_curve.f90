!> Fold, period-doubling, grazing, branch-point and Neimark-Sacker curves in two parameters (docs/model.md
!> section 12.6): from such a special point of a one-parameter branch (chain_branch), its curve
!> in (parameter, parameter2) by pseudo-arclength continuation of the minimally augmented
!> system of chain_curve_system, with the orbit and its multipliers at each point, and the
!> codim-2 points met on the way (located between two points by chain_curve_codim2, or by
!> chain_curve_meet on a grazing curve, and stored as points of the curve).
module chain_curve
    use chain_kinds, only: wp
    use chain_error, only: error_t, set_error, fmt_int, fmt_real
    use chain_model, only: model_t, model_parameter, set_model_parameter
    use chain_orbit, only: orbit_t, orbit_options_t, describe_orbit, interleave, pass_impacts, &
                           multiplier_distance, orbit_pass_t, orbit_pass
    use chain_lapack, only: solve_linear
    use chain_curve_system, only: curve_setting_t, curve_state_t, evaluate, null_vectors, &
                                  lift_grazing_bond, grazing_aim, same_bonds, aim_at_pair, &
                                  tangent_of
    use chain_curve_ns, only: tracked_pair, pair_end_reason
    use chain_curve_meet, only: meet_grazing
    use chain_curve_mirror, only: mirror_symmetric_chain
    use chain_curve_codim2, only: codim2_tests, codim2_point_t, locate_codim2
    implicit none
    private
    public :: curve_options_t, curve_t, follow_curve, curve_kinds

    !> Newton's tolerance on |P(z) - z| (relative, as chain_orbit's) and on s.
    real(wp), parameter :: tolerance = 1.0e-11_wp

    !> The kinds of special point a curve follows.
    character(len=*), parameter :: curve_kinds(5) = [character(len=15) :: 'fold', &
                                                     'period-doubling', 'grazing', &
                                                     'branch-point', 'neimark-sacker']

    type :: curve_options_t
        character(len=:), allocatable :: follow     !! one of curve_kinds
        character(len=:), allocatable :: parameter  !! the special point's parameter
        character(len=:), allocatable :: parameter2 !! the second parameter
        real(wp) :: stop2 = 0     !! the far bound of parameter2
        real(wp) :: step2 = 0     !! arclength step; its sign: parameter2's direction at the start
        integer :: max_points = 100
    end type curve_options_t

    type :: curve_t
        character(len=:), allocatable :: kind   !! the special point followed (curve_kinds)
        integer :: n_points = 0
        real(wp), allocatable :: values(:), values2(:) !! (point)
        type(orbit_t), allocatable :: orbits(:) !! the orbit and its multipliers at each point
        integer :: n_codim2 = 0
        !> 'fold-flip', '1:1' or 'cusp' (fold) or '1:2' (doubling) on a fold or doubling curve,
        !> 'fold-grazing' or 'doubling-grazing' on a grazing curve: located between two points,
        !> confirmed by its multipliers
        character(len=16), allocatable :: codim2_kind(:)
        integer, allocatable :: codim2_index(:)  !! the curve's point that is the codim-2 point
        character(len=:), allocatable :: end_reason
    end type curve_t

contains

    !> The curve of kind opt%follow through the orbit (x, v) at parameter value mu (parameter2
    !> as in `model`): the start is refined at fixed parameter2, then followed to stop2 or
    !> max_points.
    subroutine follow_curve(model, phase, cycles, x, v, mu, opt, curve, err)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase, x(:), v(:), mu
        integer, intent(in) :: cycles
        type(curve_options_t), intent(in) :: opt
        type(curve_t), intent(out) :: curve
        type(error_t), allocatable, intent(out) :: err
        type(curve_setting_t) :: set
        type(curve_state_t) :: st
        real(wp), allocatable :: y(:), tangent(:), anchor(:)
        character(len=:), allocatable :: failure
        integer :: m

        if (.not. allocated(opt%follow)) then
            call set_error(err, "curve: no kind to follow (fold, period-doubling, grazing, "// &
                           "branch-point or neimark-sacker)")
            return
        else if (.not. any(curve_kinds == opt%follow)) then
            call set_error(err, "curve: follow = '"//opt%follow//"' is none of fold, "// &
                           "period-doubling, grazing, branch-point, neimark-sacker")
            return
        end if
        if (opt%follow == 'branch-point') then
            call check_mirror(model, cycles, err)
            if (allocated(err)) return
        end if
        curve%kind = opt%follow
        allocate (curve%values(opt%max_points), curve%values2(opt%max_points), &
                  curve%orbits(opt%max_points), curve%codim2_kind(opt%max_points), &
                  curve%codim2_index(opt%max_points))
        set%model = model
        set%phase = phase
        set%cycles = cycles
        set%parameter = opt%parameter
        set%parameter2 = opt%parameter2
        set%kind = opt%follow
        set%shift = merge(-1.0_wp, 1.0_wp, opt%follow == 'fold')
        m = 2*size(x)
        y = [interleave(x, v), mu, model_parameter(model, opt%parameter2)]
        if (opt%follow == 'grazing') then
            call lift_grazing_bond(set, y, err)
            if (allocated(err)) return
        else if (opt%follow == 'neimark-sacker') then
            call aim_at_pair(set, y, err)
            if (allocated(err)) return
        else
            ! (a start the map cannot pass keeps unit bordering vectors; Newton then says why)
            set = set_with_nulls(set, y)
        end if
        ! the start: parameter2 held (the last row), then the tangent with parameter2 rising
        anchor = [spread(0.0_wp, 1, m + 1), 1.0_wp]
        call newton(set, [y], anchor, y, st, failure, err)
        if (allocated(err)) return
        if (len(failure) > 0) then
            call set_error(err, opt%follow//" curve: the start does not converge: "//failure)
            return
        end if
        call tangent_of(st, anchor, tangent, failure)
        if (len(failure) > 0) then
            call set_error(err, opt%follow//" curve: "//failure)
            return
        end if
        if (tangent(m + 2)*opt%step2 < 0) tangent = -tangent
        call keep(set, y, st, curve, err)
        if (allocated(err)) return
        call walk(set, opt, y, st, tangent, curve, err)
    end subroutine follow_curve

    !> Steps of |step2| along the tangent (halved up to four times when Newton fails) to stop2
    !> or max_points; the bordering vectors follow the null vectors.
    subroutine walk(set, opt, y, st, tangent, curve, err)
        type(curve_setting_t), intent(inout) :: set
        type(curve_options_t), intent(in) :: opt
        real(wp), intent(inout) :: y(:), tangent(:)
        type(curve_state_t), intent(inout) :: st
        type(curve_t), intent(inout) :: curve
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: next(:), fresh(:), previous(:), before(:), tests(:)
        integer, allocatable :: bonds(:)
        character(len=:), allocatable :: failure
        real(wp) :: h
        integer :: m, halvings
        complex(wp) :: pair
        logical :: complex_pair

        m = size(y) - 2
        curve%end_reason = 'max_points'
        if (has_codim2_tests(set)) then
            call codim2_tests(set, y, st, tests, err)
            if (allocated(err)) return
        end if
        do while (curve%n_points < opt%max_points)
            h = abs(opt%step2)
            bonds = pass_impacts(st%pass)
            do halvings = 0, 4
                call newton(set, y + h*tangent, tangent, next, st, failure, err)
                if (allocated(err)) return
                ! (a curve keeps its orbit's impacts: another sequence is another family's)
                if (len(failure) == 0) then
                    if (.not. same_bonds(pass_impacts(st%pass), bonds)) &
                        failure = "the orbit's impacts changed"
                end if
                if (len(failure) == 0) exit
                h = h/2
            end do
            if (len(failure) > 0) then
                curve%end_reason = end_reason(set, curve, failure)
                return
            end if
            if ((next(m + 2) - opt%stop2)*(y(m + 2) - opt%stop2) <= 0) then
                curve%end_reason = 'bound'
                return
            end if
            previous = y
            y = next
            if (set%kind == 'neimark-sacker') then
                call tracked_pair(st%pass%jacobian, set%pair, pair, complex_pair)
                set%pair = pair
            else if (set%kind /= 'grazing') then
                set%b = st%v/norm2(st%v)
                set%c = st%w/norm2(st%w)
            end if
            call tangent_of(st, tangent, fresh, failure)
            before = tangent
            tangent = fresh
            if (len(failure) > 0) then
                curve%end_reason = 'newton: '//failure
                return
            end if
            call keep(set, y, st, curve, err)
            if (allocated(err)) return
            if (set%kind == 'grazing') then
                call meetings(set, opt, previous, y, curve, err)
            else if (has_codim2_tests(set)) then
                call codim2_points(set, opt, previous, before, y, st, tests, curve, err)
            end if
            if (allocated(err)) return
        end do
    end subroutine walk

    !> On a grazing curve, between its last two points (at `previous` and y): where the sign of
    !> det(J - I) or det(J + I) changes, a fold or period-doubling curve meets it; the meeting
    !> is located (chain_curve_meet), confirmed by its orbit (a multiplier +1 or -1 to 1e-8, its
    !> gap within 1e-10 of zero) and stored as a point of the curve before the last one.
    subroutine meetings(set, opt, previous, y, curve, err)
        type(curve_setting_t), intent(in) :: set
        type(curve_options_t), intent(in) :: opt
        real(wp), intent(in) :: previous(:), y(:)
        type(curve_t), intent(inout) :: curve
        type(error_t), allocatable, intent(out) :: err
        character(len=*), parameter :: kinds(2) = [character(len=16) :: 'fold-grazing', &
                                                   'doubling-grazing']
        real(wp), parameter :: shifts(2) = [-1.0_wp, 1.0_wp] !! J + shift I singular
        type(curve_setting_t) :: other
        type(curve_state_t) :: st
        real(wp), allocatable :: meeting(:)
        logical :: met
        integer :: k, j

        k = curve%n_points
        do j = 1, 2
            if (k < 2 .or. k >= opt%max_points) return
            if (flip_sign(curve%orbits(k - 1), -shifts(j)) == &
                flip_sign(curve%orbits(k), -shifts(j))) cycle
            other = set
            other%kind = merge('fold           ', 'period-doubling', j == 1)
            other%shift = shifts(j)
            other = set_with_nulls(other, y)
            call meet_grazing(other, y, 1.5_wp*norm2(y - previous), tolerance, meeting, st, &
                              met, err)
            if (allocated(err)) return
            if (.not. met) cycle
            call keep_before_last(set, meeting, st, curve, err)
            if (allocated(err)) return
            if (multiplier_distance(curve%orbits(k), -shifts(j)) <= 1.0e-8_wp .and. &
                abs(curve%orbits(k)%min_gap) <= 1.0e-10_wp) then
                curve%n_codim2 = curve%n_codim2 + 1
                curve%codim2_kind(curve%n_codim2) = kinds(j)
                curve%codim2_index(curve%n_codim2) = k
            end if
            k = k + 1
        end do
    end subroutine meetings

    !> Fold and doubling curves have codim-2 tests (chain_curve_codim2); on a branch-point
    !> curve det(J - I) vanishes all along, and a Neimark-Sacker curve's codim-2 points are its
    !> ends, which walk names.
    pure logical function has_codim2_tests(set)
        type(curve_setting_t), intent(in) :: set

        has_codim2_tests = set%kind == 'fold' .or. set%kind == 'period-doubling'
    end function has_codim2_tests

    !> On a fold or doubling curve, between its last two points (`previous`, tangent `before`,
    !> tests `tests`; y, state st): the zero of each codim-2 test that changes sign, located
    !> (chain_curve_codim2) and, when its multipliers confirm it, stored as a point of the
    !> curve before the last one. On return `tests` are y's.
    subroutine codim2_points(set, opt, previous, before, y, st, tests, curve, err)
        type(curve_setting_t), intent(in) :: set
        type(curve_options_t), intent(in) :: opt
        real(wp), intent(in) :: previous(:), before(:), y(:)
        type(curve_state_t), intent(in) :: st
        real(wp), allocatable, intent(inout) :: tests(:)
        type(curve_t), intent(inout) :: curve
        type(error_t), allocatable, intent(out) :: err
        type(codim2_point_t) :: point
        real(wp), allocatable :: fresh(:)
        integer :: which

        call codim2_tests(set, y, st, fresh, err)
        if (allocated(err)) return
        do which = 1, size(fresh)
            if (sign(1.0_wp, tests(which)) == sign(1.0_wp, fresh(which))) cycle
            if (curve%n_points >= opt%max_points) exit
            call locate_codim2(set, newton, which, previous, before, tests(which), y, &
                               fresh(which), point, err)
            if (allocated(err)) return
            if (.not. point%confirmed) cycle
            call keep_before_last(set, point%y, point%st, curve, err)
            if (allocated(err)) return
            curve%n_codim2 = curve%n_codim2 + 1
            curve%codim2_kind(curve%n_codim2) = point%kind
            curve%codim2_index(curve%n_codim2) = curve%n_points - 1
        end do
        tests = fresh
    end subroutine codim2_points

    !> Stores the point y (state st) as the curve's point before its last one.
    subroutine keep_before_last(set, y, st, curve, err)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:)
        type(curve_state_t), intent(in) :: st
        type(curve_t), intent(inout) :: curve
        type(error_t), allocatable, intent(out) :: err
        type(orbit_t) :: last
        real(wp) :: last_values(2)
        integer :: k

        k = curve%n_points
        last = curve%orbits(k)
        last_values = [curve%values(k), curve%values2(k)]
        curve%n_points = k - 1
        curve%orbits(k) = orbit_t()
        call keep(set, y, st, curve, err)
        if (allocated(err)) return
        curve%orbits(k + 1) = last
        curve%values(k + 1) = last_values(1)
        curve%values2(k + 1) = last_values(2)
        curve%n_points = k + 1
    end subroutine keep_before_last

    !> Why the curve ends where no step from its last point succeeds: a grazing when the
    !> smallest impact speed or smallest gap of the last orbit is below 1/20 of its largest
    !> on the curve and still falling (where it vanishes, by the line through the last two
    !> orbits, in the reason), else Newton's failure. (Newton gives out before the speed
    !> reaches zero: the saltation matrices grow like 1/speed.)
    function end_reason(set, curve, failure) result(reason)
        type(curve_setting_t), intent(in) :: set
        type(curve_t), intent(in) :: curve
        character(len=*), intent(in) :: failure
        character(len=:), allocatable :: reason
        character(len=*), parameter :: what(2) = [character(len=27) :: &
                                                  "an impact's speed vanishes", "a gap closes"]
        real(wp) :: before(2), last(2), largest(2), t
        integer :: k, j

        k = curve%n_points
        if (set%kind == 'neimark-sacker' .and. k > 0) then
            reason = pair_end_reason(set%pair, ' near '//set%parameter//' = '// &
                                     fmt_real(curve%values(k))//', '//set%parameter2// &
                                     ' = '//fmt_real(curve%values2(k)), failure)
            if (len(reason) > 0) return
        end if
        reason = 'newton: '//failure
        if (k < 2) return
        before = [curve%orbits(k - 1)%min_impact_speed, curve%orbits(k - 1)%min_gap]
        last = [curve%orbits(k)%min_impact_speed, curve%orbits(k)%min_gap]
        largest = [maxval(curve%orbits(:k)%min_impact_speed, &
                          mask=curve%orbits(:k)%min_impact_speed < huge(1.0_wp)), &
                   maxval(curve%orbits(:k)%min_gap, mask=curve%orbits(:k)%min_gap < huge(1.0_wp))]
        do j = 1, 2
            if (.not. (last(j) < before(j) .and. last(j) < largest(j)/20)) cycle
            ! (the zero of the line through the two, as a fraction t of their distance past k)
            t = last(j)/(before(j) - last(j))
            reason = 'grazing: '//trim(what(j))//' near '//set%parameter//' = '// &
                     fmt_real(curve%values(k) + t*(curve%values(k) - curve%values(k - 1)))// &
                     ', '//set%parameter2//' = '// &
                     fmt_real(curve%values2(k) + t*(curve%values2(k) - curve%values2(k - 1)))// &
                     ' (extrapolated; then '//failure//')'
            return
        end do
    end function end_reason

    !> Newton on (P(z) - z, s, anchor . (y - guess)) = 0 from the guess.
    subroutine newton(set, guess, anchor, y, st, failure, err)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: guess(:), anchor(:)
        real(wp), allocatable, intent(out) :: y(:)
        type(curve_state_t), intent(out) :: st
        character(len=:), allocatable, intent(out) :: failure
        type(error_t), allocatable, intent(out) :: err
        integer, parameter :: max_iterations = 30
        real(wp), allocatable :: a(:, :), rhs(:, :)
        real(wp) :: s_tolerance
        integer :: m, iteration, info

        m = size(guess) - 2
        y = guess
        ! (a grazing orbit's gap within grazing_aim / 2 of its aim stays positive: the orbit
        ! stored has the curve's impacts and no other)
        s_tolerance = merge(grazing_aim/2, tolerance, set%kind == 'grazing')
        do iteration = 0, max_iterations
            call evaluate(set, y, st, err, .true.)
            if (allocated(err)) return
            failure = st%failure
            if (len(failure) > 0) return
            ! (on the residual, not the step: figure 10's symmetric chain has a second
            ! multiplier near +1 at its fold, so z is determined only to ~1e-7 along that
            ! direction while the residual reaches rounding)
            if (st%pass%residual <= tolerance .and. abs(st%s) <= s_tolerance .and. &
                iteration > 0) return
            if (iteration == max_iterations) exit
            if (allocated(a)) deallocate (a)
            allocate (a(m + 2, m + 2))
            a(:m + 1, :) = st%rows
            a(m + 2, :) = anchor
            rhs = reshape([-st%residual, -dot_product(anchor, y - guess)], [m + 2, 1])
            call solve_linear(a, rhs, info)
            if (info > 0) then
                failure = "singular Newton matrix of the curve"
                return
            end if
            y = y + rhs(:, 1)
        end do
        failure = "no convergence in "//fmt_int(max_iterations)//" iterations"
    end subroutine newton

    !> The setting with bordering vectors from the null vectors of J + shift I at y.
    function set_with_nulls(set, y) result(out)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:)
        type(curve_setting_t) :: out
        type(curve_state_t) :: st
        type(error_t), allocatable :: err

        out = set
        out%b = spread(1.0_wp, 1, size(y) - 2)
        out%c = out%b
        call evaluate(out, y, st, err, .false.)
        if (allocated(err) .or. .not. allocated(st%pass%jacobian)) return
        call null_vectors(st%pass%jacobian, out%shift, out%c, out%b)
    end function set_with_nulls

    !> Stores the point y (the converged state st): its orbit and multipliers.
    subroutine keep(set, y, st, curve, err)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:)
        type(curve_state_t), intent(in) :: st
        type(curve_t), intent(inout) :: curve
        type(error_t), allocatable, intent(out) :: err
        type(orbit_pass_t) :: full
        integer :: m, k

        m = size(y) - 2
        k = curve%n_points + 1
        curve%orbits(k)%converged = .true.
        curve%orbits(k)%reason = ''
        curve%orbits(k)%cycles = set%cycles
        curve%orbits(k)%phase = set%phase
        if (set%kind == 'branch-point') then
            ! (Newton's pass is the half map's: the orbit is described by the whole period's)
            call orbit_pass(model_at(set, y), set%phase, set%cycles, y(:m), full, err)
            if (allocated(err)) return
            curve%orbits(k)%residuals = [full%residual]
            call describe_orbit(model_at(set, y), full, curve%orbits(k), err)
        else
            curve%orbits(k)%residuals = [st%pass%residual]
            call describe_orbit(model_at(set, y), st%pass, curve%orbits(k), err)
        end if
        if (allocated(err)) return
        curve%n_points = k
        curve%values(k) = y(m + 1)
        curve%values2(k) = y(m + 2)
    end subroutine keep

    !> The sign of the other curve's test, det(J - shift I) up to sign: the product of
    !> 1 - shift mu over the real multipliers (a complex pair contributes a square > 0).
    pure integer function flip_sign(orbit, shift)
        type(orbit_t), intent(in) :: orbit
        real(wp), intent(in) :: shift
        real(wp) :: product_
        integer :: j

        product_ = 1
        do j = 1, size(orbit%multipliers_re)
            if (orbit%multipliers_im(j) == 0) product_ = product_*(1 - shift*orbit%multipliers_re(j))
        end do
        flip_sign = merge(1, -1, product_ >= 0)
    end function flip_sign

    !> A branch-point curve is the pitchfork of the mirror symmetry: a mirror-symmetric chain
    !> and a period-1 orbit (the half map is half a drive period).
    subroutine check_mirror(model, cycles, err)
        type(model_t), intent(in) :: model
        integer, intent(in) :: cycles
        type(error_t), allocatable, intent(out) :: err

        if (.not. mirror_symmetric_chain(model)) then
            call set_error(err, "branch-point curve: the chain is not mirror-symmetric "// &
                           "(spacing a(k) /= a(n-k)); only the mirror's pitchfork is followed")
        else if (cycles /= 1) then
            call set_error(err, "branch-point curve: period = "//fmt_int(cycles)// &
                           " (only period 1 is followed)")
        end if
    end subroutine check_mirror

    !> The model at y's two parameters.
    function model_at(set, y) result(model)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:)
        type(model_t) :: model

        model = set%model
        call set_model_parameter(model, set%parameter, y(size(y) - 1))
        call set_model_parameter(model, set%parameter2, y(size(y)))
    end function model_at

end module chain_curve
