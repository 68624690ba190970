!> The branch-point curve of the mirror symmetry in two parameters (docs/model.md section
!> 12.6), against what cannot be tuned: the chain of 12's pitchfork (A = 5.0040468 at
!> w = 2.3) followed in (A, w). At every point the orbit is its own mirror image (by the
!> branch code's mirror_image, half a period of the plain engine) to 1e-10, J has a real
!> multiplier within 1e-8 of +1, and its eigenvector is odd (the mirror, by differences,
!> turns it into minus itself); one-parameter runs at two of the curve's w locate their
!> branch points on the curve to 1e-8 in A. A chain that is not mirror-symmetric is refused.
module test_curve_branch_point
    use chain_kinds, only: wp
    use chain_error, only: error_t
    use chain_model, only: model_t, set_model_parameter
    use chain_orbit, only: orbit_t, multiplier_distance, find_orbit
    use chain_branch, only: branch_options_t, branches_t, follow_branches
    use chain_branch_points, only: mirror_image, branch_point_t
    use chain_branch_switch, only: real_eigenvector
    use chain_curve, only: curve_options_t, curve_t, follow_curve
    use test_branch, only: chain12_orbit
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_curve_branch_point_tests

contains

    subroutine run_curve_branch_point_tests(t)
        type(tally_t), intent(inout) :: t
        type(model_t) :: model
        type(orbit_t) :: start
        type(branches_t) :: res
        type(curve_t) :: curve
        integer :: k, j

        call chain12_orbit(model, start)
        call check(t, start%converged, 'branch-point curve: the 22-impact orbit at A = 5')
        if (.not. start%converged) return
        call branch_point_of(model, start%x, start%v, 5.0_wp, 5.01_wp, res, k)
        call check(t, k > 0, 'branch-point curve: the branch point at w = 2.3')
        if (k == 0) return
        call curve_from(model, res, k, curve, t)
        call check(t, curve%n_points >= 4, 'branch-point curve: at least four points')
        if (curve%n_points < 4) return
        do j = 1, curve%n_points
            call check_point(t, model, curve, j)
        end do
        do j = 2, curve%n_points, curve%n_points - 2
            call compare_with_branch(t, model, curve, j)
        end do
        call asymmetric_refused(t, model, res%points(k))
    end subroutine run_curve_branch_point_tests

    !> The chain of 12's branch from the orbit (x, v) at A = from up to A = to, and the point
    !> k of its first branch point (0: none).
    subroutine branch_point_of(model, x, v, from, to, res, k)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: x(:), v(:), from, to
        type(branches_t), intent(out) :: res
        integer, intent(out) :: k
        type(model_t) :: at
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: j

        k = 0
        at = model
        call set_model_parameter(at, 'amplitude', from)
        opt%parameter = 'amplitude'
        opt%stop = to
        opt%step = 0.001_wp
        call follow_branches(at, 0.0_wp, 1, x, v, opt, res, err)
        if (allocated(err)) return
        do j = res%n_specials, 1, -1
            if (res%specials(j)%kind == 'branch-point') k = res%specials(j)%point
        end do
    end subroutine branch_point_of

    !> The curve from the branch point (point k of res) up in w, steps 0.002, five points.
    subroutine curve_from(model, res, k, curve, t)
        type(model_t), intent(in) :: model
        type(branches_t), intent(in) :: res
        integer, intent(in) :: k
        type(curve_t), intent(out) :: curve
        type(tally_t), intent(inout) :: t
        type(curve_options_t) :: opt
        type(model_t) :: at
        type(error_t), allocatable :: err

        opt%follow = 'branch-point'
        opt%parameter = 'amplitude'
        opt%parameter2 = 'omega'
        opt%stop2 = 2.4_wp
        opt%step2 = 0.002_wp
        opt%max_points = 5
        at = model
        call set_model_parameter(at, 'amplitude', res%points(k)%value)
        call follow_curve(at, 0.0_wp, 1, res%points(k)%orbit%x, res%points(k)%orbit%v, &
                          res%points(k)%value, opt, curve, err)
        call check(t, .not. allocated(err), 'branch-point curve: followed')
        if (allocated(err)) then
            print '(a)', '    '//err%message
            return
        end if
        print '(a,i0,a)', '    branch-point curve: ', curve%n_points, ' points, '// &
            curve%end_reason
    end subroutine curve_from

    !> Point j: its own mirror image to 1e-10, a real multiplier +1 to 1e-8 whose eigenvector
    !> e is odd: (S(z + h e) - S(z - h e)) / 2h = -e to 1e-6 (S the mirror image, its
    !> derivative by central differences, h = 1e-5).
    subroutine check_point(t, model, curve, j)
        type(tally_t), intent(inout) :: t
        type(model_t), intent(in) :: model
        type(curve_t), intent(in) :: curve
        integer, intent(in) :: j
        real(wp), parameter :: h = 1.0e-5_wp
        type(model_t) :: at
        type(error_t), allocatable :: err
        real(wp), allocatable :: e(:), xm(:), vm(:), xp(:), vp(:), xn(:), vn(:)
        real(wp) :: scale, mirrored, oddness
        integer :: n

        at = model
        call set_model_parameter(at, 'amplitude', curve%values(j))
        call set_model_parameter(at, 'omega', curve%values2(j))
        associate (o => curve%orbits(j))
            n = size(o%x)
            call mirror_image(at, 0.0_wp, o%x, o%v, xm, vm, err)
            if (.not. allocated(err)) call real_eigenvector(o%jacobian, 1.0_wp, e, err)
            if (.not. allocated(err)) call mirror_image(at, 0.0_wp, o%x + h*e(1::2), &
                                                        o%v + h*e(2::2), xp, vp, err)
            if (.not. allocated(err)) call mirror_image(at, 0.0_wp, o%x - h*e(1::2), &
                                                        o%v - h*e(2::2), xn, vn, err)
            call check(t, .not. allocated(err), 'branch-point curve: mirror images')
            if (allocated(err)) return
            scale = 1 + max(maxval(abs(o%x)), maxval(abs(o%v)))
            mirrored = max(maxval(abs(xm - o%x)), maxval(abs(vm - o%v)))/scale
            oddness = max(maxval(abs((xp - xn)/(2*h) + e(1::2))), &
                          maxval(abs((vp - vn)/(2*h) + e(2::2))))/maxval(abs(e))
            write (*, '(a,f15.11,a,f15.11,3(a,es9.2))') '    A = ', curve%values(j), &
                ', w = ', curve%values2(j), ': |S z - z| = ', mirrored, &
                ', |rho - 1| = ', multiplier_distance(o, 1.0_wp), ', |DS e + e| = ', oddness
            call check_close(t, mirrored, 0.0_wp, 'branch-point curve: a symmetric orbit', &
                             1.0e-10_wp)
            call check_close(t, multiplier_distance(o, 1.0_wp), 0.0_wp, &
                             'branch-point curve: a multiplier +1', 1.0e-8_wp)
            call check_close(t, oddness, 0.0_wp, 'branch-point curve: its eigenvector is odd', &
                             1.0e-6_wp)
        end associate
    end subroutine check_point

    !> The one-parameter branch point at the w of the curve's point j, from the curve's orbit
    !> there (Newton at A - 0.002), equals the curve's A to 1e-8.
    subroutine compare_with_branch(t, model, curve, j)
        type(tally_t), intent(inout) :: t
        type(model_t), intent(in) :: model
        type(curve_t), intent(in) :: curve
        integer, intent(in) :: j
        type(model_t) :: at
        type(orbit_t) :: start
        type(branches_t) :: res
        type(error_t), allocatable :: err
        real(wp) :: below
        integer :: k

        below = curve%values(j) - 0.002_wp
        at = model
        call set_model_parameter(at, 'omega', curve%values2(j))
        call set_model_parameter(at, 'amplitude', below)
        call find_orbit(at, 0.0_wp, 1, curve%orbits(j)%x, curve%orbits(j)%v, start, err)
        call check(t, .not. allocated(err) .and. start%converged, &
                   'branch-point curve: the symmetric orbit below it at its w')
        if (allocated(err) .or. .not. start%converged) return
        call branch_point_of(at, start%x, start%v, below, curve%values(j) + 0.003_wp, res, k)
        call check(t, k > 0, 'branch-point curve: a one-parameter branch point at its w')
        if (k == 0) return
        write (*, '(a,f15.11,a,es9.2)') '    one-parameter branch point at w = ', &
            curve%values2(j), ': |A - curve| = ', abs(res%points(k)%value - curve%values(j))
        call check_close(t, res%points(k)%value, curve%values(j), &
                         'branch-point curve: through the one-parameter branch point', 1.0e-8_wp)
    end subroutine compare_with_branch

    !> The same start on the chain with its left wall moved (not mirror-symmetric): refused,
    !> the error naming the symmetry.
    subroutine asymmetric_refused(t, model, p)
        type(tally_t), intent(inout) :: t
        type(model_t), intent(in) :: model
        type(branch_point_t), intent(in) :: p
        type(curve_options_t) :: opt
        type(curve_t) :: curve
        type(model_t) :: at
        type(error_t), allocatable :: err

        opt%follow = 'branch-point'
        opt%parameter = 'amplitude'
        opt%parameter2 = 'omega'
        opt%stop2 = 2.4_wp
        opt%step2 = 0.002_wp
        at = model
        at%spacing(lbound(at%spacing, 1)) = 1.05_wp
        call follow_curve(at, 0.0_wp, 1, p%orbit%x, p%orbit%v, p%value, opt, curve, err)
        call check(t, allocated(err), 'branch-point curve: an asymmetric chain refused')
        if (allocated(err)) call check(t, index(err%message, 'not mirror-symmetric') > 0, &
                                       'branch-point curve: the refusal says why')
    end subroutine asymmetric_refused

end module test_curve_branch_point
