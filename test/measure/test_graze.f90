!> Through a grazing (docs/model.md section 12.5), against what cannot be tuned: figure 10's
!> chain followed up from rest in the amplitude is the forced response up to its grazing at
!> the closed form A = a sqrt((1 - w**2)**2 + (2 b w)**2), located to 1e-10 and stored once;
!> the branch goes on onto the impacting orbits (the mirror pair of wall bonds grazes
!> together: two impacts more per cycle; that family turns back at the grazing, its orbits
!> lie below it), whose first points are fixed points of the map. That family ends at its own
!> gap grazing (bonds 1 and 7), and the branch goes on through it with four impacts per cycle
!> to an impact at the section.
module test_graze
    use chain_kinds, only: wp
    use chain_error, only: error_t
    use chain_flow, only: flow_t, make_flow, forced_response
    use chain_model, only: model_t, bond_gaps
    use chain_orbit, only: orbit_t, orbit_pass_t, orbit_pass, interleave, find_orbit
    use chain_branch, only: branch_options_t, branches_t, follow_branches
    use test_chains, only: fig10_model
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_graze_tests

contains

    subroutine run_graze_tests(t)
        type(tally_t), intent(inout) :: t
        type(branches_t) :: res
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: j

        opt%parameter = 'amplitude'
        opt%stop = 3
        opt%step = 0.1_wp
        opt%max_points = 200
        call follow_branches(fig10_model(1.0_wp), 0.0_wp, 1, [(0.0_wp, j=1, 8)], &
                             [(0.0_wp, j=1, 8)], opt, res, err)
        call check(t, .not. allocated(err), 'through a grazing: followed')
        if (allocated(err)) then
            print *, err%message
            return
        end if
        print '(a)', '    '//res%end_reason
        call check(t, res%start%converged .and. res%n_points > 0, &
                   'through a grazing: the start converged')
        if (res%n_points > 0) call check(t, all(res%start%x == res%points(1)%orbit%x) .and. &
                                         all(res%start%v == res%points(1)%orbit%v) .and. &
                                         all(res%start%residuals == &
                                             res%points(1)%orbit%residuals), &
                                         'through a grazing: the start is the first point')
        call grazing_located(t, res)
        call gap_grazing_with_impacts(t, res)
    end subroutine run_graze_tests

    !> The grazing: one special point at the closed form, the forced response before it, its
    !> orbit stored once, and the impacting orbits after it.
    subroutine grazing_located(t, res)
        type(tally_t), intent(inout) :: t
        type(branches_t), intent(in) :: res
        type(model_t) :: model
        type(flow_t) :: flow
        real(wp) :: xp, vp, worst, grazing
        integer :: j, g, s

        model = fig10_model(1.0_wp)
        grazing = sqrt((1 - model%omega**2)**2 + (2*model%damping*model%omega)**2)
        s = 0
        do j = res%n_specials, 1, -1
            if (res%specials(j)%kind == 'grazing') s = j
        end do
        call check(t, s > 0, 'through a grazing: a grazing special point')
        if (s == 0) return
        g = res%specials(s)%point
        write (*, '(a,es22.14,a,es9.2,a,i0,a,i0)') '    grazing at ', res%specials(s)%value, &
            ', |A - closed form| = ', abs(res%specials(s)%value - grazing), ', point ', g, &
            ' of ', res%n_points
        call check_close(t, res%specials(s)%value, grazing, &
                         'through a grazing: at a sqrt(D2) to 1e-10', 1.0e-10_wp)
        call check_close(t, res%points(g)%value, grazing, &
                         'through a grazing: the orbit stored there, to 1e-10', 1.0e-10_wp)
        call check(t, count(abs(res%points(:res%n_points)%value - grazing) < 1.0e-8_wp) == 1, &
                   'through a grazing: its orbit stored once')
        worst = 0
        do j = 1, g - 1
            flow = make_flow(model%damping, res%points(j)%value, model%omega)
            call forced_response(flow, 0.0_wp, xp, vp)
            worst = max(worst, maxval(abs(res%points(j)%orbit%x - xp)), &
                        maxval(abs(res%points(j)%orbit%v - vp)))
        end do
        write (*, '(a,i0,a,es9.2)') '    ', g - 1, &
            ' points before it, |orbit - forced response| <= ', worst
        call check_close(t, worst, 0.0_wp, 'through a grazing: the forced response before it', &
                         1.0e-12_wp)
        call check(t, all(res%points(:g - 1)%value < grazing), &
                   'through a grazing: points below it')
        call check(t, res%n_points >= g + 3, 'through a grazing: points past it')
        if (res%n_points < g + 3) return
        call impacting_side(t, res, g, grazing)
    end subroutine grazing_located

    !> Past the grazing at point g: the impacts per cycle go up by the mirror pair (walls 0 and
    !> n graze together), every point up to the next grazing has those two, and the first
    !> three are fixed points of the map.
    subroutine impacting_side(t, res, g, grazing)
        type(tally_t), intent(inout) :: t
        type(branches_t), intent(in) :: res
        integer, intent(in) :: g
        real(wp), intent(in) :: grazing
        type(model_t) :: model
        type(orbit_pass_t) :: pass
        type(error_t), allocatable :: err
        real(wp) :: worst
        integer :: j, last

        ! (the two-impact family reaches up to the branch's next grazing)
        last = res%n_points
        do j = 1, res%n_specials
            if (res%specials(j)%kind == 'grazing' .and. res%specials(j)%point > g) &
                last = min(last, res%specials(j)%point)
        end do
        write (*, '(a,i0,a,i0,a,es9.2)') '    impacts per cycle: ', res%points(g)%orbit%impacts, &
            ' at the grazing, ', res%points(g + 1)%orbit%impacts, ' past it, at A - A_g = ', &
            res%points(g + 1)%value - grazing
        call check(t, res%points(g)%orbit%impacts == 0 .and. &
                   all(res%points(g + 1:last)%orbit%impacts == 2), &
                   'through a grazing: two impacts per cycle past it (the mirror pair)')
        ! (the impacting family turns back at the grazing: its orbits lie below it)
        call check(t, abs(res%points(g + 1)%value - grazing) < 1.0e-3_wp .and. &
                   all(res%points(g + 1:g + 3)%value < grazing), &
                   'through a grazing: the first point past it next to it, below it')
        do j = g + 1, g + 3
            write (*, '(a,es9.2,a,es9.2,a,es9.2)') '    A - A_g = ', &
                res%points(j)%value - grazing, ', impact speed ', &
                res%points(j)%orbit%min_impact_speed, ', largest |multiplier| ', &
                maxval(hypot(res%points(j)%orbit%multipliers_re, &
                             res%points(j)%orbit%multipliers_im))
        end do
        worst = 0
        do j = g + 1, g + 3
            model = fig10_model(res%points(j)%value)
            call orbit_pass(model, 0.0_wp, 1, interleave(res%points(j)%orbit%x, &
                                                         res%points(j)%orbit%v), pass, err)
            call check(t, .not. allocated(err), 'through a grazing: the map past it')
            if (allocated(err)) return
            worst = max(worst, maxval(abs(pass%image - pass%z)))
        end do
        write (*, '(a,es9.2)') '    first three points past it: |P(z) - z| <= ', worst
        call check_close(t, worst, 0.0_wp, 'through a grazing: fixed points past it', 1.0e-10_wp)
    end subroutine impacting_side

    !> The second grazing of the branch: the two-impact family's gap minimum touches zero at
    !> A = 2.4755439 (an orbit that already impacts). Located to 1e-10 against the boundary of
    !> that family found independently (bisection in A on Newton orbits at fixed A: converged,
    !> two impacts, no negative gap), stored once; past it, to the branch's end, the impacts
    !> go up by the mirror pair, the first orbits are fixed points of the map, and the orbits
    !> on both sides tend to the grazing orbit (gap_grazing_sides).
    subroutine gap_grazing_with_impacts(t, res)
        type(tally_t), intent(inout) :: t
        type(branches_t), intent(in) :: res
        real(wp) :: boundary, worst
        integer :: s, g, j

        s = 0
        do j = 1, res%n_specials
            if (res%specials(j)%kind == 'grazing' .and. &
                abs(res%specials(j)%value - 2.4755439_wp) < 1.0e-6_wp) s = j
        end do
        call check(t, s > 0, 'gap grazing with impacts: located near A = 2.4755439')
        if (s == 0) return
        g = res%specials(s)%point
        boundary = family_boundary(res%points(g - 1)%orbit, res%points(g - 1)%value, &
                                   res%specials(s)%value)
        write (*, '(a,es22.14,a,es9.2,a,i0,a,i0)') '    gap grazing at ', &
            res%specials(s)%value, ', |A - bisection| = ', &
            abs(res%specials(s)%value - boundary), ', point ', g, ' of ', res%n_points
        call check_close(t, res%specials(s)%value, boundary, &
                         'gap grazing with impacts: at the family''s boundary to 1e-10', &
                         1.0e-10_wp)
        call check(t, count(abs(res%points(:res%n_points)%value - res%specials(s)%value) &
                            < 1.0e-9_wp) == 1, 'gap grazing with impacts: its orbit stored once')
        call check(t, res%n_points >= g + 3, 'gap grazing with impacts: points past it')
        if (res%n_points < g + 3) return
        write (*, '(a,i0,a,i0,a,i0,a,i0)') '    impacts per cycle: ', &
            res%points(g - 1)%orbit%impacts, ' before, ', res%points(g)%orbit%impacts, &
            ' at it, ', res%points(g + 1)%orbit%impacts, ' past it, to point ', res%n_points
        call check(t, res%points(g - 1)%orbit%impacts == 2 .and. &
                   res%points(g)%orbit%impacts == 2 .and. &
                   all(res%points(g + 1:res%n_points)%orbit%impacts == 4), &
                   'gap grazing with impacts: the impacts go up by the mirror pair')
        worst = 0
        do j = g + 1, g + 3
            worst = max(worst, map_residual(res%points(j)%orbit%x, res%points(j)%orbit%v, &
                                            res%points(j)%value))
        end do
        write (*, '(a,es9.2)') '    first three points past it: |P(z) - z| <= ', worst
        call check_close(t, worst, 0.0_wp, 'gap grazing with impacts: fixed points past it', &
                         1.0e-10_wp)
        call gap_grazing_sides(t, res, g)
        call section_end(t, res)
    end subroutine gap_grazing_with_impacts

    !> The branch ends where an impact of its orbit reaches the section: a gap of the last
    !> orbit's section state z is zero there, and z with that impact applied (the section's
    !> other side, where figure 10's six-impact branch ends) returns to z in one period.
    subroutine section_end(t, res)
        type(tally_t), intent(inout) :: t
        type(branches_t), intent(in) :: res
        type(model_t) :: model
        type(orbit_pass_t) :: pass
        type(error_t), allocatable :: err
        real(wp), allocatable :: gaps(:), v(:)
        real(wp) :: u, back
        integer :: k

        associate (last => res%points(res%n_points))
            model = fig10_model(last%value)
            ! (gaps(1:n + 1): bonds 0..n)
            gaps = bond_gaps(model%spacing, model%walls, last%orbit%x)
            k = minloc(abs(gaps), 1) - 1
            call check(t, res%end_kind == 'section' .and. abs(gaps(k + 1)) < 1.0e-8_wp .and. &
                       k >= 1 .and. k < model%n, &
                       'gap grazing with impacts: the branch ends at an impact at the section')
            if (k < 1 .or. k >= model%n) return
            v = last%orbit%v
            u = v(k) - v(k + 1)
            v(k:k + 1) = v(k:k + 1) + [-1.0_wp, 1.0_wp]*(1 + model%restitution)*u/2
            call orbit_pass(model, 0.0_wp, 1, interleave(last%orbit%x, v), pass, err)
            back = huge(1.0_wp)
            if (.not. allocated(err)) back = maxval(abs(pass%image - &
                                                        interleave(last%orbit%x, last%orbit%v)))
            write (*, '(a,f13.10,a,i0,a,es9.2,a,es9.2)') '    ends at A = ', last%value, &
                ': bond ', k, ' gap ', gaps(k + 1), ', after its impact back in a period to ', &
                back
            call check_close(t, back, 0.0_wp, &
                             'gap grazing with impacts: the section''s other side, one orbit', &
                             1.0e-8_wp)
        end associate
    end subroutine section_end

    !> Both sides of the gap grazing at point g tend to its orbit: |z - z_g| ~ |A - A_g|^p, p
    !> measured from the two nearest points on each side (1 on both: the two-impact family is
    !> smooth up to it, and past it the new impacts' speed u ~ A_g - A moves the orbit by
    !> O(u)). The largest multiplier is continuous at the grazing from the old side and grows
    !> like 1/u past it: |multiplier| u alike at the first two points past it.
    subroutine gap_grazing_sides(t, res, g)
        type(tally_t), intent(inout) :: t
        type(branches_t), intent(in) :: res
        integer, intent(in) :: g
        real(wp) :: law(2), mult(-2:2), grow(2)
        integer :: j, side

        do side = 1, 2
            law(side) = exponent_of(res, g, 2*side - 3)
        end do
        write (*, '(a,2f7.3)') '    |z - z_g| ~ |A - A_g|^p, p before and past it: ', law
        call check(t, all(abs(law - 1) < 0.2_wp), &
                   'gap grazing with impacts: both sides tend to its orbit like |A - A_g|')
        do j = -2, 2
            mult(j) = maxval(hypot(res%points(g + j)%orbit%multipliers_re, &
                                   res%points(g + j)%orbit%multipliers_im))
        end do
        grow = mult(1:2)*res%points(g + 1:g + 2)%orbit%min_impact_speed
        write (*, '(a,5es10.3,a,2f7.4)') '    largest |multiplier| at points g-2..g+2: ', mult, &
            ', times the new speed past it: ', grow
        call check(t, abs(mult(-1) - mult(0)) < 0.1_wp*mult(0) .and. &
                   abs(grow(2)/grow(1) - 1) < 0.1_wp, &
                   'gap grazing with impacts: multipliers continuous before, like 1/u past it')
    end subroutine gap_grazing_sides

    !> p in |z - z_g| ~ |A - A_g|^p from the points g + dir and g + 2 dir (dir = +-1).
    real(wp) function exponent_of(res, g, dir) result(p)
        type(branches_t), intent(in) :: res
        integer, intent(in) :: g, dir
        real(wp) :: d(2), da(2)
        integer :: j

        do j = 1, 2
            associate (here => res%points(g + j*dir), graze => res%points(g))
                d(j) = norm2([here%orbit%x - graze%orbit%x, here%orbit%v - graze%orbit%v])
                da(j) = abs(here%value - graze%value)
            end associate
        end do
        p = log(d(2)/d(1))/log(da(2)/da(1))
    end function exponent_of

    !> Where the family of `orbit` (at a, its impacts) ends towards a_g: bisection in A, each
    !> trial Newton at fixed A from `orbit`.
    function family_boundary(orbit, a, a_g) result(boundary)
        type(orbit_t), intent(in) :: orbit
        real(wp), intent(in) :: a, a_g
        real(wp) :: boundary, inside, outside
        type(orbit_t) :: trial
        type(error_t), allocatable :: err
        integer :: k

        inside = a
        outside = a_g + (a_g - a)
        do k = 1, 80
            boundary = (inside + outside)/2
            call find_orbit(fig10_model(boundary), 0.0_wp, 1, orbit%x, orbit%v, trial, err)
            if (allocated(err)) deallocate (err)
            if (trial%converged .and. trial%impacts == orbit%impacts .and. &
                trial%min_gap >= 0) then
                inside = boundary
            else
                outside = boundary
            end if
            if (abs(outside - inside) < 1.0e-13_wp) exit
        end do
        boundary = (inside + outside)/2
    end function family_boundary

    !> |P(z) - z| of the section state (x, v) at the amplitude a.
    real(wp) function map_residual(x, v, a) result(r)
        real(wp), intent(in) :: x(:), v(:), a
        type(orbit_pass_t) :: pass
        type(error_t), allocatable :: err

        r = huge(1.0_wp)
        call orbit_pass(fig10_model(a), 0.0_wp, 1, interleave(x, v), pass, err)
        if (allocated(err)) return
        r = maxval(abs(pass%image - pass%z))
    end function map_residual

end module test_graze
