!> The predictor-corrector of pseudo-arclength continuation (docs/model.md section 12.1): from a
!> point on a branch, the point at arclength h along its tangent by Newton on the bordered
!> system [[J - I, P_mu], [t]] with the exact Jacobian and parameter derivative of the map
!> (chain_orbit, chain_parameter), and the unit tangent there.
module chain_branch_corrector
    use chain_kinds, only: wp
    use chain_error, only: error_t, set_error, fmt_int, fmt_real
    use chain_model, only: model_t, set_model_parameter
    use chain_orbit, only: orbit_t, orbit_pass_t, orbit_pass, pass_refusal
    use chain_parameter, only: map_parameter_derivative
    use chain_lapack, only: solve_linear
    use chain_branch_points, only: cursor_t, setting_t, cursor_from_pass, cursor_from_orbit, &
                                   impacts_per_bond
    implicit none
    private
    public :: correct, tangent_at, cursor_ahead

contains

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
            failure = pass_refusal(pass)
            if (len(failure) == 0 .and. pass%residual/4 > previous .and. iterations >= 2) &
                failure = "Newton diverges (residual "//fmt_real(pass%residual)//")"
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
        next%y = y
        call cursor_from_pass(set, model, pass, iterations, next, err)
        if (allocated(err)) return
        call tangent_at(set, next, here%tangent, err)
        if (allocated(err)) then
            ! (the orbit has no tangent, at a simultaneous impact or a singular bordered
            ! matrix: this trial fails, not the run)
            failure = err%message
            deallocate (err)
            return
        end if
        ok = .true.
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

    !> The cursor of an orbit found at mu, its tangent oriented to `ahead` in the parameter:
    !> ok = .false. when it has none (the family is not continued from there).
    subroutine cursor_ahead(set, orbit, mu, ahead, found, ok, err)
        type(setting_t), intent(in) :: set
        type(orbit_t), intent(in) :: orbit
        real(wp), intent(in) :: mu, ahead
        type(cursor_t), intent(out) :: found
        logical, intent(out) :: ok
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: direction(:)

        call cursor_from_orbit(set, mu, orbit, found)
        allocate (direction(size(found%y)))
        direction = 0
        direction(size(found%y)) = ahead
        call tangent_at(set, found, direction, err)
        ok = .not. allocated(err)
        if (allocated(err)) deallocate (err)
    end subroutine cursor_ahead

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

end module chain_branch_corrector
