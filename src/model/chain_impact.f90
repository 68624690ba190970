!> Instantaneous impacts (docs/model.md section 3) and the jump of the tangent map across them
!> (section 4): S = DR + (f+ - DR f-) grad(h)^T / (grad(h) . f-).
!>
!> The engine uses the general formula with the vector fields it actually has before and after
!> (a resting oscillator has f = 0), so sticking needs no special matrix; the closed forms of
!> docs/model.md sections 4.3-4.4 are kept here to test it against.
module chain_impact
    use chain_kinds, only: wp
    implicit none
    private
    public :: pair_impact, wall_impact, pair_reset_jacobian, wall_reset_jacobian
    public :: saltation_matrix, pair_saltation_closed_form, wall_saltation_closed_form

contains

    !> Velocities after an impact of two equal masses (restitution k): momentum kept,
    !> relative velocity reversed and scaled by k.
    pure subroutine pair_impact(k, v_left, v_right)
        real(wp), intent(in) :: k
        real(wp), intent(inout) :: v_left, v_right
        real(wp) :: q, vl, vr

        q = 0.5_wp*(1 + k) ! the share of the approach speed each oscillator takes
        vl = v_left
        vr = v_right
        v_left = (1 - q)*vl + q*vr
        v_right = q*vl + (1 - q)*vr
    end subroutine pair_impact

    !> Velocity after hitting a wall: v+ = -k v-.
    elemental subroutine wall_impact(k, v)
        real(wp), intent(in) :: k
        real(wp), intent(inout) :: v

        v = -k*v
    end subroutine wall_impact

    !> DR of the pair reset in the order (x(k), v(k), x(k+1), v(k+1)).
    pure function pair_reset_jacobian(k) result(dr)
        real(wp), intent(in) :: k
        real(wp) :: dr(4, 4), q

        q = 0.5_wp*(1 + k)
        dr = 0
        dr(1, 1) = 1
        dr(3, 3) = 1
        dr(2, 2) = 1 - q
        dr(2, 4) = q
        dr(4, 2) = q
        dr(4, 4) = 1 - q
    end function pair_reset_jacobian

    !> DR of the wall reset in the order (x, v).
    pure function wall_reset_jacobian(k) result(dr)
        real(wp), intent(in) :: k
        real(wp) :: dr(2, 2)

        dr = reshape([1.0_wp, 0.0_wp, 0.0_wp, -k], [2, 2])
    end function wall_reset_jacobian

    !> The saltation matrix for reset Jacobian dr, vector fields f_minus / f_plus just before
    !> and after, and the gradient of the event surface. info = 1 when the flow is tangent to
    !> the surface (grazing), where S does not exist.
    pure subroutine saltation_matrix(dr, f_minus, f_plus, grad_h, salt, info)
        real(wp), intent(in) :: dr(:, :), f_minus(:), f_plus(:), grad_h(:)
        real(wp), intent(out) :: salt(size(dr, 1), size(dr, 2))
        integer, intent(out) :: info
        real(wp) :: rate, w(4)  ! (fixed size: an automatic array would be allocated)
        integer :: j, m

        rate = dot_product(grad_h, f_minus)
        info = 0
        if (rate == 0) then
            info = 1
            salt = dr
            return
        end if
        ! f+ - DR f-, column by column (matmul of assumed-shape arrays would allocate)
        m = size(f_minus)
        w(1:m) = f_plus
        do j = 1, m
            w(1:m) = w(1:m) - dr(:, j)*f_minus(j)
        end do
        w(1:m) = w(1:m)/rate
        do j = 1, size(grad_h)
            salt(:, j) = dr(:, j) + w(1:m)*grad_h(j)
        end do
    end subroutine saltation_matrix

    !> docs/model.md section 4.4, pair on a bond of spacing a with approach speed u > 0.
    pure function pair_saltation_closed_form(k, u, a) result(salt)
        real(wp), intent(in) :: k, u, a
        real(wp) :: salt(4, 4), col(4), row(4), q
        integer :: j

        q = 0.5_wp*(1 + k)
        col = q*[-1.0_wp, -a/u, 1.0_wp, a/u]
        row = [1.0_wp, 0.0_wp, -1.0_wp, 0.0_wp]
        salt = pair_reset_jacobian(k)
        do j = 1, 4
            salt(:, j) = salt(:, j) + col*row(j)
        end do
    end function pair_saltation_closed_form

    !> docs/model.md section 4.3, wall: [[-K, 0], [(K acc- + acc+)/v-, -K]].
    pure function wall_saltation_closed_form(k, acc_minus, acc_plus, v_minus) result(salt)
        real(wp), intent(in) :: k, acc_minus, acc_plus, v_minus
        real(wp) :: salt(2, 2)

        salt = reshape([-k, (k*acc_minus + acc_plus)/v_minus, 0.0_wp, -k], [2, 2])
    end function wall_saltation_closed_form

end module chain_impact
