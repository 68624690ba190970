!> Collision times (docs/model.md section 2.4): the first zero found by `next_gap_zero` equals the
!> one found by a brute-force fine scan of the gap function, on random and on contrived
!> near-grazing gaps, and no zero is ever missed.
module test_gaps
    use chain_kinds, only: wp, pi, two_pi
    use chain_flow, only: flow_t, make_flow
    use chain_gaps, only: gap_t, gap_search_t, next_gap_zero, gap_value, search_root, &
                          search_horizon, search_none
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_gap_tests

    real(wp), parameter :: scan_length = 40.0_wp

contains

    subroutine run_gap_tests(t)
        type(tally_t), intent(inout) :: t
        type(flow_t) :: flow
        type(gap_t) :: gap
        real(wp) :: s0, r(6)
        integer :: j, mismatches, roots, nones
        integer :: seed_size
        integer, allocatable :: seed(:)

        call random_seed(size=seed_size)
        allocate (seed(seed_size))
        seed = 20261122
        call random_seed(put=seed)
        mismatches = 0
        roots = 0
        nones = 0
        do j = 1, 300
            call random_number(r)
            flow = make_flow(0.2_wp*r(1), 3*r(2), 0.5_wp + 2*r(3))
            s0 = flow%period*r(4)
            select case (modulo(j, 3))
            case (0)
                gap = gap_t(1.0_wp, 3*(r(5) - 0.5_wp), 3*(r(6) - 0.5_wp), 0.0_wp)
            case (1)
                gap = gap_t(1.0_wp, 2*(r(5) - 0.5_wp), 2*(r(6) - 0.5_wp), 1.0_wp)
            case default
                gap = gap_t(1.0_wp, 2*(r(5) - 0.5_wp), 2*(r(6) - 0.5_wp), -1.0_wp)
            end select
            call compare_with_scan(flow, gap, s0, mismatches, roots, nones)
        end do
        call check(t, mismatches == 0, 'first zero equals the brute-force scan on 300 random gaps')
        call check(t, roots > 50 .and. nones > 20, 'random gaps include closing and open ones')

        call grazing_pairs(t)
        call grazing_walls(t)
    end subroutine run_gap_tests

    !> Search (following horizons like the engine does) and compare with a scan.
    subroutine compare_with_scan(flow, gap, s0, mismatches, roots, nones)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        real(wp), intent(in) :: s0
        integer, intent(inout) :: mismatches, roots, nones
        real(wp) :: found, truth, g0, g1

        call gap_value(flow, gap, s0, 0.0_wp, g0, g1)
        if (g0 <= 0) return
        found = search_following(flow, gap, s0)
        truth = scan_first_zero(flow, gap, s0, 2.0e-3_wp)
        if (truth < scan_length) roots = roots + 1
        if (truth >= scan_length) nones = nones + 1
        if (truth >= scan_length .and. found >= scan_length) return
        if (abs(found - truth) > 1.0e-12_wp*max(1.0_wp, truth)) then
            mismatches = mismatches + 1
            write (*, '(a,2es24.16,a,4es12.4)') '  mismatch: found/scan ', found, truth, &
                ' gap ', gap%offset, gap%y, gap%vy, gap%beta
        end if
    end subroutine compare_with_scan

    !> The engine's use of the search: follow horizons until a zero or nothing.
    function search_following(flow, gap, s0) result(tau)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        real(wp), intent(in) :: s0
        real(wp) :: tau, g, g1
        type(gap_search_t) :: res
        type(gap_t) :: moved

        tau = 0
        moved = gap
        do
            res = next_gap_zero(flow, moved, s0 + tau, flow%period)
            if (res%status == search_root) then
                tau = tau + res%tau
                return
            else if (res%status == search_none) then
                tau = huge(1.0_wp)
                return
            end if
            tau = tau + res%tau
            if (tau > scan_length) return
            ! restart the search from the horizon with the gap's free part moved there
            call free_part_at(flow, gap, tau, moved)
            g = 0; g1 = 0
        end do
    end function search_following

    subroutine free_part_at(flow, gap, tau, moved)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        real(wp), intent(in) :: tau
        type(gap_t), intent(out) :: moved
        type(gap_t) :: free
        real(wp) :: g, g1

        free = gap_t(0.0_wp, gap%y, gap%vy, 0.0_wp)
        call gap_value(flow, free, 0.0_wp, tau, g, g1)
        moved = gap_t(gap%offset, g, g1, gap%beta)
    end subroutine free_part_at

    !> First zero closing from above on a grid of step dt, refined by bisection.
    function scan_first_zero(flow, gap, s0, dt) result(tau)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        real(wp), intent(in) :: s0, dt
        real(wp) :: tau, a, b, ga, gb, gm, g1, m
        integer :: k, it

        call gap_value(flow, gap, s0, 0.0_wp, ga, g1)
        if (ga <= 1.0e-14_wp .and. g1 < 0) then
            tau = 0
            return
        end if
        a = 0
        do k = 1, nint(scan_length/dt)
            b = k*dt
            call gap_value(flow, gap, s0, b, gb, g1)
            if (gb <= 0 .and. ga > 0) then
                do it = 1, 200
                    m = 0.5_wp*(a + b)
                    call gap_value(flow, gap, s0, m, gm, g1)
                    if (gm > 0) then
                        a = m
                    else
                        b = m
                    end if
                    if (b - a < 1.0e-15_wp) exit
                end do
                tau = a
                return
            end if
            a = b
            ga = gb
        end do
        tau = huge(1.0_wp)
    end function scan_first_zero

    !> Pair gaps whose first minimum dips below zero by 1e-9 (must be found) or stays above
    !> by 1e-9 (must not be), in many phases.
    subroutine grazing_pairs(t)
        type(tally_t), intent(inout) :: t
        type(flow_t) :: flow
        type(gap_t) :: gap
        type(gap_search_t) :: res
        real(wp) :: phi, amp, tau_min, delta, g, g1, truth
        integer :: j, k, bad

        flow = make_flow(0.05_wp, 1.0_wp, 1.5_wp)
        bad = 0
        do j = 1, 40
            phi = two_pi*j/41.0_wp
            tau_min = modulo(pi - asin(flow%damping) + phi, two_pi)/flow%gam
            do k = -1, 1, 2
                delta = k*1.0e-9_wp
                ! y = amp exp(-b tau) cos(gam tau - phi), minimum -amp gam exp(-b tau_min)
                amp = (1 + delta)*exp(flow%damping*tau_min)/flow%gam
                gap = gap_t(1.0_wp, amp*cos(phi), amp*(flow%gam*sin(phi) - &
                            flow%damping*cos(phi)), 0.0_wp)
                res = next_gap_zero(flow, gap, 0.0_wp, flow%period)
                if (k < 0 .and. res%status /= search_none) bad = bad + 1
                if (k > 0) then
                    if (res%status /= search_root) then
                        bad = bad + 1
                        cycle
                    end if
                    call gap_value(flow, gap, 0.0_wp, res%tau, g, g1)
                    truth = scan_near(flow, gap, tau_min)
                    if (abs(g) > 1.0e-14_wp .or. abs(res%tau - truth) > 1.0e-9_wp) bad = bad + 1
                end if
            end do
        end do
        call check(t, bad == 0, 'near-grazing pair gaps (minimum -1e-9 found, +1e-9 not)')
    end subroutine grazing_pairs

    !> A wall gap grazing zero: the drive alone brings x to -a + 1e-9 or -a - 1e-9.
    subroutine grazing_walls(t)
        type(tally_t), intent(inout) :: t
        type(flow_t) :: flow
        type(gap_t) :: gap
        real(wp) :: rp, found, truth
        integer :: j, k, bad

        bad = 0
        do j = 1, 20
            do k = -1, 1, 2
                flow = make_flow(0.05_wp, 1.0_wp + 0.05_wp*j, 1.3_wp)
                rp = hypot(flow%p_sin, flow%q_cos)
                ! steady state only (y = 0): gap = c + xp, minimum c - rp
                gap = gap_t(rp*(1 - k*1.0e-9_wp), 0.0_wp, 0.0_wp, 1.0_wp)
                found = search_following(flow, gap, 0.1_wp*j)
                if (k < 0) then
                    if (found < scan_length) bad = bad + 1
                    cycle
                end if
                ! closed form: xp = rp sin(w s + psi) first reaches -c where
                ! w s + psi = pi + asin(c/rp)
                truth = modulo(pi + asin(gap%offset/rp) - atan2(flow%q_cos, flow%p_sin) &
                               - flow%omega*0.1_wp*j, two_pi)/flow%omega
                if (abs(found - truth) > 1.0e-8_wp) bad = bad + 1
            end do
        end do
        call check(t, bad == 0, 'near-grazing wall gaps (dip of 1e-9 found, clearance not)')
    end subroutine grazing_walls

    !> First zero near tau_min by a very fine scan (for near-grazing cases).
    function scan_near(flow, gap, tau_min) result(tau)
        type(flow_t), intent(in) :: flow
        type(gap_t), intent(in) :: gap
        real(wp), intent(in) :: tau_min
        real(wp) :: tau, a, b, g, g1, m
        integer :: k, it

        a = max(0.0_wp, tau_min - 1.0e-3_wp)
        do k = 1, 20000
            b = a + 1.0e-7_wp
            call gap_value(flow, gap, 0.0_wp, b, g, g1)
            if (g <= 0) then
                do it = 1, 100
                    m = 0.5_wp*(a + b)
                    call gap_value(flow, gap, 0.0_wp, m, g, g1)
                    if (g > 0) then
                        a = m
                    else
                        b = m
                    end if
                end do
                tau = a
                return
            end if
            a = b
        end do
        tau = huge(1.0_wp)
    end function scan_near

end module test_gaps
