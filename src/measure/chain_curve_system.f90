!> The minimally augmented systems of a curve of special points in two parameters
!> (docs/model.md section 12.6): unknowns y = (z, mu1, mu2), equations P(z) - z = 0 and one
!> test s = 0.
!> - Fold or period doubling (Govaerts 2000): s from the bordered system
!>   [[J + shift I, b], [c^T, 0]] (w, s) = (0, 1) (shift -1 at a fold, +1 at a period
!>   doubling), regular at a simple one; its row s_y = -v^T J_y w (v from the transposed
!>   system) with J_y by central differences of exact Jacobians.
!> - Branch point of the mirror symmetry: the period doubling of the half map Q
!>   (chain_curve_mirror) in place of the map, P(z) - z replaced by Q(z) - z; its parameter
!>   columns by central differences of Q.
!> - Grazing: s = the smallest minimum of the grazing bond's gap over the orbit (chain_orbit's
!>   gap monitor), less grazing_aim. The bond's contact is lifted out of reach while Newton
!>   works (its spacing raised by `lift`, the gap lowered by as much): the orbit is continued
!>   smoothly across the grazing, as the orbit with the old impacts (the penetrating
!>   continuation), so Newton may step to either side; the points kept lie on the side where
!>   the gap is positive, as real orbits. Its row by central differences.
!> - Neimark-Sacker: s = |mu|^2 - 1 of the tracked complex pair (chain_curve_ns). Its row by
!>   central differences.
!> The orbit rows of Newton's matrix are exact, [J - I, P_mu1, P_mu2]; the residual is exact,
!> only the test's row is approximate.
module chain_curve_system
    use chain_kinds, only: wp
    use chain_error, only: error_t, set_error, fmt_int
    use chain_model, only: model_t, set_model_parameter, bond_gaps
    use chain_orbit, only: orbit_pass_t, orbit_pass, pass_refusal, pass_impacts, &
                           orbit_gap_minimum
    use chain_parameter, only: map_parameter_derivative
    use chain_curve_mirror, only: half_pass, half_parameter_column
    use chain_lapack, only: solve_linear
    use chain_curve_ns, only: pair_test, unit_circle_pair
    implicit none
    private
    public :: curve_setting_t, curve_state_t, evaluate, border, null_vectors
    public :: lift_grazing_bond, grazing_aim, same_bonds, gap_and_row, tangent_of, aim_at_pair

    !> The gap a grazing curve aims at (Newton stops within grazing_aim / 2 of it): just above
    !> zero, so that the orbit kept has no new impact of a speed the engine resolves. The
    !> parameters sit aim / |dg/dmu| from the grazing, far below 1e-10.
    real(wp), parameter :: grazing_aim = 1.0e-12_wp

    !> What stays fixed along one curve.
    type :: curve_setting_t
        type(model_t) :: model
        real(wp) :: phase = 0
        integer :: cycles = 1
        character(len=:), allocatable :: parameter, parameter2
        !> fold, period-doubling, grazing, branch-point or neimark-sacker
        character(len=:), allocatable :: kind
        !> the test matrix J + shift I: -1 fold, +1 period doubling (and of DQ at a branch point)
        real(wp) :: shift = -1
        real(wp), allocatable :: b(:), c(:) !! the bordering vectors (unit, near the null vectors)
        integer :: grazing_bond = -1 !! grazing: the bond whose gap touches zero (-1: none)
        !> grazing: the bonds lifted, the grazing bond and those whose gaps touch zero with it
        !> (a mirror pair)
        integer, allocatable :: lifted(:)
        real(wp) :: lift = 0 !! grazing: added to the lifted bonds' spacings while Newton works
        integer, allocatable :: bonds(:) !! grazing: the bonds of the orbit's impacts, in time order
        complex(wp) :: pair = 0 !! neimark-sacker: the tracked multiplier at the last point
    end type curve_setting_t

    !> The system at one y: the residual (P(z) - z, s), Newton's m + 1 rows, and the
    !> bordered system's solutions w (right) and v (left).
    type :: curve_state_t
        type(orbit_pass_t) :: pass
        real(wp), allocatable :: residual(:)
        real(wp), allocatable :: rows(:, :)
        real(wp), allocatable :: w(:), v(:)
        real(wp) :: s = 0
        logical :: ok = .false.
        character(len=:), allocatable :: failure
    end type curve_state_t

contains

    !> The system at y; with `rows`, also Newton's matrix. ok = .false. with `failure` when the
    !> orbit cannot be passed (a negative gap, a rest) or the bordered matrix is singular.
    subroutine evaluate(set, y, st, err, rows)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:)
        type(curve_state_t), intent(out) :: st
        type(error_t), allocatable, intent(out) :: err
        logical, intent(in) :: rows
        real(wp), allocatable :: p1(:), p2(:), d_s(:)
        type(model_t) :: model
        integer :: m, i

        m = size(y) - 2
        st%failure = ''
        if (set%kind == 'grazing') then
            call gap_at(set, y, st%pass, model, st%s, st%failure, err)
        else if (set%kind == 'neimark-sacker') then
            call pass_at(set, y, st%pass, model, st%failure, err)
            if (allocated(err) .or. len(st%failure) > 0) return
            call pair_test(st%pass%jacobian, set%pair, st%s, st%failure)
        else
            call pass_at(set, y, st%pass, model, st%failure, err)
            if (allocated(err) .or. len(st%failure) > 0) return
            call border(st%pass%jacobian, set%shift, set%b, set%c, st%w, st%v, st%s, &
                        st%failure)
        end if
        if (allocated(err) .or. len(st%failure) > 0) return
        st%residual = [st%pass%image - st%pass%z, st%s]
        st%ok = .true.
        if (.not. rows) return
        if (set%kind == 'branch-point') then
            call half_parameter_column(model, set%phase, y(:m), set%parameter, p1, st%failure, &
                                       err)
            if (.not. allocated(err)) call half_parameter_column(model, set%phase, y(:m), &
                                                                 set%parameter2, p2, &
                                                                 st%failure, err)
        else
            call map_parameter_derivative(model, set%phase, set%cycles, y(1:m:2), y(2:m:2), &
                                          set%parameter, st%pass%jacobian, p1, err)
            if (.not. allocated(err)) &
                call map_parameter_derivative(model, set%phase, set%cycles, y(1:m:2), &
                                              y(2:m:2), set%parameter2, st%pass%jacobian, p2, &
                                              err)
        end if
        if (allocated(err)) return
        if (len(st%failure) > 0) then
            st%ok = .false.
            return
        end if
        if (set%kind == 'grazing' .or. set%kind == 'neimark-sacker') then
            call difference_row(set, y, d_s, st%failure, err)
        else
            call s_gradient(set, y, st%w, st%v, d_s, st%failure, err)
        end if
        if (allocated(err) .or. len(st%failure) > 0) then
            st%ok = .false.
            return
        end if
        allocate (st%rows(m + 1, m + 2))
        st%rows(:m, :m) = st%pass%jacobian
        do i = 1, m
            st%rows(i, i) = st%rows(i, i) - 1
        end do
        st%rows(:m, m + 1) = p1
        st%rows(:m, m + 2) = p2
        st%rows(m + 1, :) = d_s
    end subroutine evaluate

    !> One pass of the map at y (both parameters set; on a branch-point curve the half map),
    !> and the model it used.
    subroutine pass_at(set, y, pass, model, failure, err)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:)
        type(orbit_pass_t), intent(out) :: pass
        type(model_t), intent(out) :: model
        character(len=:), allocatable, intent(inout) :: failure
        type(error_t), allocatable, intent(out) :: err
        character(len=:), allocatable :: refusal

        model = lifted_model(set, y)
        if (set%kind == 'branch-point') then
            call half_pass(model, set%phase, y(:size(y) - 2), pass, err, .true.)
        else
            call orbit_pass(model, set%phase, set%cycles, y(:size(y) - 2), pass, err)
        end if
        if (allocated(err)) return
        refusal = pass_refusal(pass)
        if (len(refusal) > 0) failure = refusal
    end subroutine pass_at

    !> The model at y's two parameters, the lifted bonds' spacings raised by the lift.
    function lifted_model(set, y) result(model)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:)
        type(model_t) :: model
        integer, allocatable :: at(:)

        model = set%model
        call set_model_parameter(model, set%parameter, y(size(y) - 1))
        call set_model_parameter(model, set%parameter2, y(size(y)))
        if (allocated(set%lifted)) then
            ! (bond k's spacing, whatever the array's lower bound)
            at = lbound(model%spacing, 1) + set%lifted
            model%spacing(at) = model%spacing(at) + set%lift
        end if
    end function lifted_model

    !> A grazing curve's setting from its start y: the bond of the smallest gap minimum and
    !> those whose minima equal it to 1e-9 (a mirror pair grazes as one), none with an impact of
    !> its own on the orbit; their lift (four times the largest a gap can swing by, so that
    !> none closes) and the orbit's impacts, which the curve keeps.
    subroutine lift_grazing_bond(set, y, err)
        type(curve_setting_t), intent(inout) :: set
        real(wp), intent(in) :: y(:)
        type(error_t), allocatable, intent(out) :: err
        type(orbit_pass_t) :: pass
        type(model_t) :: model
        character(len=:), allocatable :: failure
        real(wp) :: gap, time, other, spacing
        integer :: m, k, j, bond

        m = size(y) - 2
        failure = ''
        set%grazing_bond = -1
        if (allocated(set%lifted)) deallocate (set%lifted)
        call pass_at(set, y, pass, model, failure, err)
        if (allocated(err)) return
        if (len(failure) > 0) then
            call set_error(err, "grazing curve: the start cannot be passed: "//failure)
            return
        end if
        call orbit_gap_minimum(model, set%phase, set%cycles, y(1:m:2), y(2:m:2), gap, k, &
                               time, err)
        if (allocated(err)) return
        if (k < 0) then
            call set_error(err, "grazing curve: no gap of the start has a local minimum")
            return
        end if
        spacing = model%spacing(lbound(model%spacing, 1) + k)
        set%lifted = [k]
        do j = 0, model%n
            if (j == k) cycle
            call orbit_gap_minimum(model, set%phase, set%cycles, y(1:m:2), y(2:m:2), other, &
                                   bond, time, err, only=j)
            if (allocated(err)) return
            if (abs(other - gap) <= 1.0e-9_wp*(1 + spacing)) set%lifted = [set%lifted, j]
        end do
        if (any([(any(pass_impacts(pass) == set%lifted(j)), j=1, size(set%lifted))])) then
            call set_error(err, "grazing curve: a grazing bond has impacts of its own on the "// &
                           "orbit (not supported)")
            return
        end if
        set%bonds = pass_impacts(pass)
        set%grazing_bond = k
        set%lift = 4*(1 + spacing + maxval(abs(y(1:m:2))) + &
                      maxval(abs(y(2:m:2)))/model%omega)
    end subroutine lift_grazing_bond

    !> The grazing test at y with the pass there (pass_at, for Newton's orbit rows).
    subroutine gap_at(set, y, pass, model, gap, failure, err)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:)
        type(orbit_pass_t), intent(out) :: pass
        type(model_t), intent(out) :: model
        real(wp), intent(out) :: gap
        character(len=:), allocatable, intent(inout) :: failure
        type(error_t), allocatable, intent(out) :: err

        gap = huge(1.0_wp)
        call pass_at(set, y, pass, model, failure, err)
        if (allocated(err) .or. len(failure) > 0) return
        call gap_of(set, y, gap, failure, err)
    end subroutine gap_at

    !> The grazing test at y: the smallest minimum of the lifted bond's gap over the orbit,
    !> less grazing_aim; refused when the orbit's impacts are not the curve's (another bond
    !> grazed, or the lifted one closed) or a gap is negative. One run of the chain, without
    !> the Jacobian a pass carries.
    subroutine gap_of(set, y, gap, failure, err)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:)
        real(wp), intent(out) :: gap
        character(len=:), allocatable, intent(inout) :: failure
        type(error_t), allocatable, intent(out) :: err
        type(model_t) :: model
        integer, allocatable :: impacts(:)
        real(wp) :: time
        integer :: m, bond

        gap = huge(1.0_wp)
        m = size(y) - 2
        model = lifted_model(set, y)
        if (any(bond_gaps(model%spacing, model%walls, y(1:m:2)) < 0)) then
            failure = "a negative gap"
            return
        end if
        call orbit_gap_minimum(model, set%phase, set%cycles, y(1:m:2), y(2:m:2), gap, bond, &
                               time, err, only=set%grazing_bond, impacts=impacts)
        if (allocated(err)) return
        if (.not. same_bonds(impacts, set%bonds)) then
            failure = "the orbit's impacts changed (another bond grazed)"
            return
        end if
        gap = gap - set%lift - grazing_aim
    end subroutine gap_of

    !> The grazing test at y and its row (as on a grazing curve), for a setting of any kind
    !> whose grazing bond is lifted (lift_grazing_bond).
    subroutine gap_and_row(set, y, gap, row, failure, err)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:)
        real(wp), intent(out) :: gap
        real(wp), allocatable, intent(out) :: row(:)
        character(len=:), allocatable, intent(inout) :: failure
        type(error_t), allocatable, intent(out) :: err

        call gap_of(set, y, gap, failure, err)
        if (allocated(err) .or. len(failure) > 0) return
        call difference_row(set, y, row, failure, err)
    end subroutine gap_and_row

    !> Are two sequences of impact bonds the same?
    pure logical function same_bonds(a, b)
        integer, intent(in) :: a(:), b(:)

        same_bonds = size(a) == size(b)
        if (same_bonds) same_bonds = all(a == b)
    end function same_bonds

    !> A Neimark-Sacker curve's setting from its start y: the pair tracked is the complex
    !> multiplier nearest the unit circle there.
    subroutine aim_at_pair(set, y, err)
        type(curve_setting_t), intent(inout) :: set
        real(wp), intent(in) :: y(:)
        type(error_t), allocatable, intent(out) :: err
        type(orbit_pass_t) :: pass
        type(model_t) :: model
        character(len=:), allocatable :: failure

        failure = ''
        call pass_at(set, y, pass, model, failure, err)
        if (allocated(err)) return
        if (len(failure) == 0) call unit_circle_pair(pass%jacobian, set%pair, failure)
        if (len(failure) > 0) call set_error(err, "neimark-sacker curve: the start: "//failure)
    end subroutine aim_at_pair

    !> The scalar test at y: a Neimark-Sacker curve's pair_test, else the lifted bond's gap_of
    !> (a grazing curve's, or that of a fold or doubling curve meeting one: gap_and_row).
    subroutine scalar_test(set, y, s, failure, err)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:)
        real(wp), intent(out) :: s
        character(len=:), allocatable, intent(inout) :: failure
        type(error_t), allocatable, intent(out) :: err
        type(orbit_pass_t) :: pass
        type(model_t) :: model

        if (set%kind /= 'neimark-sacker') then
            call gap_of(set, y, s, failure, err)
            return
        end if
        s = huge(1.0_wp)
        call pass_at(set, y, pass, model, failure, err)
        if (allocated(err) .or. len(failure) > 0) return
        call pair_test(pass%jacobian, set%pair, s, failure)
    end subroutine scalar_test

    !> The scalar test's row by central differences (a relative step 1e-6: the gap minimum
    !> and the pair's modulus are smooth in y, the error of order step**2).
    subroutine difference_row(set, y, d_g, failure, err)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:)
        real(wp), allocatable, intent(out) :: d_g(:)
        character(len=:), allocatable, intent(inout) :: failure
        type(error_t), allocatable, intent(out) :: err
        real(wp), parameter :: relative = 1.0e-6_wp
        real(wp), allocatable :: e(:)
        real(wp) :: h, plus, minus
        integer :: k

        allocate (d_g(size(y)), e(size(y)))
        do k = 1, size(y)
            h = relative*(1 + abs(y(k)))
            e = 0
            e(k) = h
            call scalar_test(set, y + e, plus, failure, err)
            if (allocated(err) .or. len(failure) > 0) return
            call scalar_test(set, y - e, minus, failure, err)
            if (allocated(err) .or. len(failure) > 0) return
            d_g(k) = (plus - minus)/(2*h)
        end do
    end subroutine difference_row

    !> s_y = -v^T J_y w, J_y by central differences of exact Jacobians (a relative step 1e-6:
    !> the Jacobians are exact to rounding, the difference's error is of order step**2).
    subroutine s_gradient(set, y, w, v, d_s, failure, err)
        type(curve_setting_t), intent(in) :: set
        real(wp), intent(in) :: y(:), w(:), v(:)
        real(wp), allocatable, intent(out) :: d_s(:)
        character(len=:), allocatable, intent(inout) :: failure
        type(error_t), allocatable, intent(out) :: err
        real(wp), parameter :: relative = 1.0e-6_wp
        type(orbit_pass_t) :: plus, minus
        type(model_t) :: model
        real(wp), allocatable :: e(:)
        real(wp) :: h
        integer :: k

        allocate (d_s(size(y)), e(size(y)))
        do k = 1, size(y)
            h = relative*(1 + abs(y(k)))
            e = 0
            e(k) = h
            call pass_at(set, y + e, plus, model, failure, err)
            if (allocated(err) .or. len(failure) > 0) return
            call pass_at(set, y - e, minus, model, failure, err)
            if (allocated(err) .or. len(failure) > 0) return
            d_s(k) = -dot_product(v, matmul(plus%jacobian - minus%jacobian, w))/(2*h)
        end do
    end subroutine s_gradient

    !> [[J + shift I, b], [c^T, 0]] (w, s) = (0, 1) and its transpose (v, s) = (0, 1).
    subroutine border(jacobian, shift, b, c, w, v, s, failure)
        real(wp), intent(in) :: jacobian(:, :), shift, b(:), c(:)
        real(wp), allocatable, intent(out) :: w(:), v(:)
        real(wp), intent(out) :: s
        character(len=:), allocatable, intent(inout) :: failure
        real(wp), allocatable :: a(:, :), rhs(:, :)
        integer :: m, i, info

        m = size(b)
        allocate (a(m + 1, m + 1), rhs(m + 1, 2))
        a(:m, :m) = jacobian
        do i = 1, m
            a(i, i) = a(i, i) + shift
        end do
        a(:m, m + 1) = b
        a(m + 1, :m) = c
        a(m + 1, m + 1) = 0
        rhs = 0
        rhs(m + 1, 1) = 1
        call solve_linear(a, rhs(:, 1:1), info)
        if (info == 0) then
            a(:m, :m) = transpose(jacobian)
            do i = 1, m
                a(i, i) = a(i, i) + shift
            end do
            a(:m, m + 1) = c
            a(m + 1, :m) = b
            a(m + 1, m + 1) = 0
            rhs(m + 1, 2) = 1
            call solve_linear(a, rhs(:, 2:2), info)
        end if
        if (info > 0) then
            failure = "singular bordered matrix of the test function"
            return
        end if
        w = rhs(:m, 1)
        v = rhs(:m, 2)
        s = rhs(m + 1, 1)
    end subroutine border

    !> Unit approximations of the right and left null vectors of J + shift I near a fold or
    !> period doubling, by two steps of inverse iteration each.
    subroutine null_vectors(jacobian, shift, right, left)
        real(wp), intent(in) :: jacobian(:, :), shift
        real(wp), allocatable, intent(out) :: right(:), left(:)
        real(wp), allocatable :: a(:, :), at(:, :), x(:, :)
        integer :: m, i, step, info

        m = size(jacobian, 1)
        a = jacobian
        do i = 1, m
            a(i, i) = a(i, i) + shift
        end do
        at = transpose(a)
        allocate (x(m, 2))
        x = 1
        do step = 1, 2
            block
                real(wp), allocatable :: lu(:, :)
                lu = a
                call solve_linear(lu, x(:, 1:1), info)
                if (info > 0) exit
                lu = at
                call solve_linear(lu, x(:, 2:2), info)
                if (info > 0) exit
            end block
            x(:, 1) = x(:, 1)/norm2(x(:, 1))
            x(:, 2) = x(:, 2)/norm2(x(:, 2))
        end do
        if (info > 0) then
            ! exactly singular: any unit vectors border it regularly once Newton moves
            x = 1/sqrt(real(m, wp))
        end if
        right = x(:, 1)
        left = x(:, 2)
    end subroutine null_vectors

    !> The unit tangent of the curve at st: rows t = 0, direction . t = 1.
    subroutine tangent_of(st, direction, tangent, failure)
        type(curve_state_t), intent(in) :: st
        real(wp), intent(in) :: direction(:)
        real(wp), allocatable, intent(out) :: tangent(:)
        character(len=:), allocatable, intent(out) :: failure
        real(wp), allocatable :: a(:, :), rhs(:, :)
        integer :: n, info

        failure = ''
        n = size(direction)
        allocate (a(n, n), rhs(n, 1))
        a(:n - 1, :) = st%rows
        a(n, :) = direction
        rhs = 0
        rhs(n, 1) = 1
        call solve_linear(a, rhs, info)
        if (info > 0) then
            failure = "singular tangent system of the curve"
            return
        end if
        tangent = rhs(:, 1)/norm2(rhs(:, 1))
        if (dot_product(tangent, direction) < 0) tangent = -tangent
    end subroutine tangent_of

end module chain_curve_system
