!> Branch switching (docs/model.md section 12.4): the real eigenvector of the
!> Jacobian J for a multiplier -1 (a period doubling) or +1 (a branch point), and the start
!> cursors of the two asymmetric branches born at a branch point of a mirror-symmetric branch.
!> The branches themselves are followed by chain_branch.
module chain_branch_switch
    use chain_kinds, only: wp
    use chain_error, only: error_t, set_error
    use chain_lapack, only: solve_linear
    use chain_branch_points, only: setting_t, cursor_t, branch_point_t, cursor_from_orbit
    implicit none
    private
    public :: real_eigenvector, branch_point_starts

contains

    !> The unit eigenvector of J for its real eigenvalue nearest rho (-1 or +1), by inverse
    !> iteration on J - rho I shifted 1e-12 further out (nearly singular at the special point).
    subroutine real_eigenvector(jacobian, rho, e, err)
        real(wp), intent(in) :: jacobian(:, :)
        real(wp), intent(in) :: rho
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
                a(i, i) = a(i, i) - rho - sign(1.0e-12_wp, rho)
            end do
            call solve_linear(a, b, info)
            if (info > 0) exit
            b = b/norm2(b(:, 1))
        end do
        if (.not. all(abs(b) < huge(1.0_wp))) then
            call set_error(err, "continuation: no eigenvector for the multiplier "// &
                           merge('-1', '+1', rho < 0))
            return
        end if
        e = b(:, 1)
    end subroutine real_eigenvector

    !> The first points of the two branches that cross the branch at its branch point `bp`
    !> (a multiplier +1, no fold): the orbit itself, with the tangents (e, 0) and (-e, 0),
    !> e the null vector of J - I. On a mirror-symmetric branch that null vector is odd under
    !> the mirror S (the even directions carry the symmetric branch itself, whose tangent has
    !> a parameter component), and the two branches are the asymmetric pair, each other's
    !> mirror images; the parameter moves at second order along them (a pitchfork).
    subroutine branch_point_starts(set, bp, starts, err)
        type(setting_t), intent(in) :: set
        type(branch_point_t), intent(in) :: bp
        type(cursor_t), intent(out) :: starts(2)
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: e(:)
        integer :: side

        call real_eigenvector(bp%orbit%jacobian, 1.0_wp, e, err)
        if (allocated(err)) return
        do side = 1, 2
            call cursor_from_orbit(set, bp%value, bp%orbit, starts(side))
            starts(side)%tangent = [merge(e, -e, side == 1), 0.0_wp]
        end do
    end subroutine branch_point_starts

end module chain_branch_switch
