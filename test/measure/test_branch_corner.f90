!> Through a corner (docs/model.md section 12.3): the unstable 22-impact period-1 orbit of a
!> chain of 12 (b = 0.02, K = 0.85, w = 2.3, a = 1, walls; Newton from rest after 500 cycles at
!> A = 5), continued down, meets a corner near A = 4.8296, where oscillator 4 (and its mirror
!> image 9) is hit by both neighbours at one instant. The corner is located and stored, and the
!> branch goes on along the orbits with the impacts in the other order. Checked against what
!> the branch did not compute: Newton from the far end of the new family lands on its first
!> point, and the new family exists on the corner's old side too (a jump, not a continuation).
module test_branch_corner
    use chain_kinds, only: wp
    use chain_error, only: error_t
    use chain_model, only: model_t, set_model_parameter
    use chain_orbit, only: orbit_t, find_orbit, impact_bonds
    use chain_branch, only: branch_options_t, branches_t, follow_branches
    use test_branch, only: chain12_orbit
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_branch_corner_tests

contains

    subroutine run_branch_corner_tests(t)
        type(tally_t), intent(inout) :: t
        type(model_t) :: model
        type(orbit_t) :: start
        type(branches_t) :: res
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: c

        call chain12_orbit(model, start)
        call check(t, start%converged .and. start%impacts == 22, &
                   'corner: the unstable 22-impact orbit at A = 5')
        if (.not. start%converged) return
        opt%parameter = 'amplitude'
        opt%stop = 4.8_wp
        opt%step = -0.01_wp
        call follow_branches(model, 0.0_wp, 1, start%x, start%v, opt, res, err)
        call check(t, .not. allocated(err), 'corner: a result, not an error')
        if (allocated(err)) return
        print '(a)', '    '//res%end_reason
        call check(t, res%n_specials == 1, 'corner: one special point')
        if (res%n_specials /= 1) return
        c = res%specials(1)%point
        call check(t, res%specials(1)%kind == 'corner' .and. c >= 8 .and. &
                   abs(res%specials(1)%value - 4.8295554_wp) < 1.0e-6_wp, &
                   'corner: located at A = 4.8295554, the points before it kept')
        call corner_orbit(t, res%points(c)%orbit)
        call check(t, res%end_kind == 'bound' .and. res%n_points > c + 1, &
                   'corner: the branch goes on past it to the bound')
        if (res%n_points <= c + 1) return
        call new_family(t, model, res, c)
    end subroutine run_branch_corner_tests

    !> The orbit stored at the corner: two impacts on neighbouring bonds within 1e-6 in time,
    !> and neither grazing monitor near zero.
    subroutine corner_orbit(t, o)
        type(tally_t), intent(inout) :: t
        type(orbit_t), intent(in) :: o
        real(wp), allocatable :: times(:)
        integer, allocatable :: bonds(:)
        real(wp) :: apart
        integer :: j, k

        call check(t, o%min_gap > 0.1_wp .and. o%min_impact_speed > 0.1_wp, &
                   'corner: no grazing there')
        bonds = impact_bonds(o)
        times = pack(o%event_time, o%event_kind == 0)
        apart = huge(1.0_wp)
        do j = 1, size(bonds)
            do k = j + 1, size(bonds)
                if (abs(bonds(j) - bonds(k)) == 1) apart = min(apart, times(k) - times(j))
            end do
        end do
        call check(t, apart < 1.0e-6_wp, 'corner: two impacts of one oscillator at once')
    end subroutine corner_orbit

    !> The points past the corner (c): the same 22 impacts in another order than the corner
    !> orbit's, all alike, the first within 2e-6 of the corner in A and a finite distance from
    !> its orbit (the map jumps there). Newton at the first point's A from the last point's
    !> state finds the first point (one family); Newton 1e-3 above the corner from the first
    !> point finds an orbit with its order (the family also lives on the old side).
    subroutine new_family(t, model, res, c)
        type(tally_t), intent(inout) :: t
        type(model_t), intent(in) :: model
        type(branches_t), intent(in) :: res
        integer, intent(in) :: c
        type(model_t) :: at
        type(orbit_t) :: again
        type(error_t), allocatable :: err
        integer, allocatable :: old(:), new(:)
        real(wp) :: distance
        integer :: k
        logical :: alike

        old = impact_bonds(res%points(c)%orbit)
        associate (first => res%points(c + 1))
            new = impact_bonds(first%orbit)
            call check(t, size(new) == 22 .and. any(new /= old), &
                       'corner: past it, the 22 impacts in another order')
            call check(t, first%value < res%specials(1)%value .and. &
                       res%specials(1)%value - first%value < 2.0e-6_wp, &
                       'corner: the first orbit past it within 2e-6 in A')
            distance = norm2([first%orbit%x - res%points(c)%orbit%x, &
                              first%orbit%v - res%points(c)%orbit%v])
            print '(a, es10.3, a, 2f9.5)', '    the orbit jumps by ', distance, &
                ' at the corner; largest |multiplier| before and after: ', &
                maxval(hypot(res%points(c)%orbit%multipliers_re, &
                             res%points(c)%orbit%multipliers_im)), &
                maxval(hypot(first%orbit%multipliers_re, first%orbit%multipliers_im))
            call check(t, distance > 1.0e-3_wp, 'corner: the map jumps there (a new family)')
            alike = .true.
            do k = c + 2, res%n_points
                alike = alike .and. all(impact_bonds(res%points(k)%orbit) == new)
            end do
            call check(t, alike, 'corner: every orbit past it has the new order')
            at = model
            call set_model_parameter(at, 'amplitude', first%value)
            associate (last => res%points(res%n_points)%orbit)
                call find_orbit(at, 0.0_wp, 1, last%x, last%v, again, err)
            end associate
            call check(t, .not. allocated(err) .and. again%converged, &
                       'corner: Newton from the far end converges')
            if (.not. again%converged) return
            call check_close(t, max(maxval(abs(again%x - first%orbit%x)), &
                                    maxval(abs(again%v - first%orbit%v))), 0.0_wp, &
                             'corner: the far end''s family passes through the first orbit', &
                             1.0e-8_wp)
            call set_model_parameter(at, 'amplitude', res%specials(1)%value + 1.0e-3_wp)
            call find_orbit(at, 0.0_wp, 1, first%orbit%x, first%orbit%v, again, err)
            call check(t, .not. allocated(err) .and. again%converged, &
                       'corner: the new family above the corner, by Newton')
            if (.not. again%converged) return
            call check(t, all(impact_bonds(again) == new), &
                       'corner: above it, the new family keeps its order')
        end associate
    end subroutine new_family

end module test_branch_corner
