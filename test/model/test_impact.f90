!> docs/model.md sections 3-4: collision laws and saltation matrices (general formula against the
!> closed forms).
module test_impact
    use chain_kinds, only: wp
    use chain_impact, only: pair_impact, wall_impact, pair_reset_jacobian, wall_reset_jacobian, &
                            saltation_matrix, pair_saltation_closed_form, &
                            wall_saltation_closed_form
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_impact_tests

contains

    subroutine run_impact_tests(t)
        type(tally_t), intent(inout) :: t
        real(wp) :: k, vl, vr, vl0, vr0, a, u, xl, xr, accl, accr, amp, b, s
        real(wp) :: sal(4, 4), closed(4, 4), f_minus(4), f_plus(4), sw(2, 2), cw(2, 2)
        integer :: info, j

        do j = 0, 4
            k = 0.25_wp*j
            vl0 = 1.3_wp
            vr0 = -0.4_wp
            vl = vl0
            vr = vr0
            call pair_impact(k, vl, vr)
            call check_close(t, vl + vr, vl0 + vr0, 'pair impact keeps momentum', 1.0e-15_wp)
            call check_close(t, vr - vl, k*(vl0 - vr0), 'pair impact: relative velocity * -K', &
                             1.0e-15_wp)
            vl = -0.8_wp
            call wall_impact(k, vl)
            call check_close(t, vl, 0.8_wp*k, 'wall impact: v+ = -K v-', 1.0e-15_wp)
        end do

        ! general saltation formula equals the closed form of docs/model.md 4.4 (pair)
        k = 0.7_wp
        a = 1.3_wp
        b = 0.05_wp
        amp = 1.7_wp
        s = 0.4_wp
        xl = 0.2_wp
        xr = xl - a
        vl = 0.9_wp
        vr = -0.3_wp
        u = vl - vr
        accl = -2*b*vl - xl + amp*sin(s)
        accr = -2*b*vr - xr + amp*sin(s)
        f_minus = [vl, accl, vr, accr]
        call pair_impact(k, vl, vr)
        f_plus = [vl, -2*b*vl - xl + amp*sin(s), vr, -2*b*vr - xr + amp*sin(s)]
        call saltation_matrix(pair_reset_jacobian(k), f_minus, f_plus, &
                              [-1.0_wp, 0.0_wp, 1.0_wp, 0.0_wp], sal, info)
        closed = pair_saltation_closed_form(k, u, a)
        call check(t, info == 0 .and. maxval(abs(sal - closed)) < 1.0e-14_wp, &
                   'pair saltation: general formula equals closed form')
        call check_close(t, det4(sal), k**2, 'pair saltation determinant is K**2', 1.0e-14_wp)

        ! wall (left: h = a + x, grad = (1, 0))
        vl = -0.6_wp
        xl = -a
        accl = -2*b*vl - xl + amp*sin(s)
        call saltation_matrix(wall_reset_jacobian(k), [vl, accl], &
                              [-k*vl, -2*b*(-k*vl) - xl + amp*sin(s)], [1.0_wp, 0.0_wp], sw, info)
        cw = wall_saltation_closed_form(k, accl, -2*b*(-k*vl) - xl + amp*sin(s), vl)
        call check(t, info == 0 .and. maxval(abs(sw - cw)) < 1.0e-14_wp, &
                   'wall saltation: general formula equals closed form')
        call check_close(t, sw(1, 1)*sw(2, 2) - sw(1, 2)*sw(2, 1), k**2, &
                         'wall saltation determinant is K**2', 1.0e-14_wp)
    end subroutine run_impact_tests

    pure function det4(m) result(d)
        real(wp), intent(in) :: m(4, 4)
        real(wp) :: d, a(4, 4), f
        integer :: i, j, p

        a = m
        d = 1
        do j = 1, 4
            p = maxloc(abs(a(j:, j)), 1) + j - 1
            if (p /= j) then
                a([j, p], :) = a([p, j], :)
                d = -d
            end if
            d = d*a(j, j)
            do i = j + 1, 4
                f = a(i, j)/a(j, j)
                a(i, :) = a(i, :) - f*a(j, :)
            end do
        end do
    end function det4

end module test_impact
