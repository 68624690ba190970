!> Branch switching at a branch point (docs/model.md 12.4), against what cannot be tuned: on
!> the mirror-symmetric 22-impact branch of the chain of 12 the branch point has a multiplier
!> +1; the two branches switched to there are labelled not symmetric (their parent is), and
!> are each other's mirror images: the mirror of a point of one is, by Newton at the same
!> parameter, the orbit of the other there; each says it began at that branch point. And a
!> fold is no branch point: on figure 10's chain made asymmetric (a(0) = 1.05), a single
!> multiplier crosses +1 at its fold.
module test_branch_switch
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_model, only: model_t, set_model_parameter
    use chain_orbit, only: orbit_t, find_orbit
    use chain_branch, only: branch_options_t, branches_t, follow_branches
    use chain_branch_points, only: mirror_image
    use test_branch, only: chain12_orbit, settle, check_origins
    use test_chains, only: fig10_model
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_switch_tests

contains

    subroutine run_switch_tests(t)
        type(tally_t), intent(inout) :: t

        call crossing_branches(t)
        call simple_fold(t)
    end subroutine run_switch_tests

    !> Figure 10's chain with the left wall's spacing 1.05 (not mirror-symmetric), its
    !> eight-impact orbit from rest at A = 3 followed down: it folds with one multiplier +1
    !> (det(J - I) changes sign, the next multiplier 0.2 away), in the same step as the
    !> parameter turns: stored as a fold, not as a branch point.
    subroutine simple_fold(t)
        type(tally_t), intent(inout) :: t
        type(model_t) :: model
        type(orbit_t) :: start
        type(branches_t) :: res
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        real(wp), allocatable :: distance(:)
        integer :: i, folds, branch_points, f

        model = fig10_model(3.0_wp)
        model%spacing(0) = 1.05_wp
        call settle(model, 5_i8, 1, start)
        call check(t, start%converged .and. start%impacts == 8, &
                   'simple fold: an eight-impact orbit at A = 3, a(0) = 1.05')
        if (.not. start%converged) return
        opt%parameter = 'amplitude'
        opt%stop = 2
        opt%step = -0.05_wp
        call follow_branches(model, 0.0_wp, 1, start%x, start%v, opt, res, err)
        call check(t, .not. allocated(err), 'simple fold: followed')
        if (allocated(err)) return
        print '(a)', '    '//res%end_reason
        folds = 0
        branch_points = 0
        f = 0
        do i = 1, res%n_specials
            if (res%specials(i)%kind == 'fold') then
                folds = folds + 1
                f = res%specials(i)%point
            end if
            if (res%specials(i)%kind == 'branch-point') branch_points = branch_points + 1
        end do
        call check(t, folds == 1 .and. branch_points == 0, &
                   'simple fold: one fold, no branch point')
        call check(t, .not. any(res%points(:res%n_points)%symmetric), &
                   'simple fold: no orbit of the asymmetric chain is symmetric')
        if (f == 0) return
        associate (o => res%points(f)%orbit)
            distance = abs(cmplx(o%multipliers_re - 1, o%multipliers_im, wp))
            write (*, '(a,f15.11,a,es9.2,a,es9.2)') '    simple fold at A = ', &
                res%points(f)%value, ', |rho - 1| = ', minval(distance), ', the next ', &
                minval(distance, mask=distance > minval(distance))
            call check(t, minval(distance) < 1.0e-6_wp .and. &
                       minval(distance, mask=distance > minval(distance)) > 0.1_wp, &
                       'simple fold: one multiplier +1, the others away from it')
        end associate
    end subroutine simple_fold

    !> The chain of 12 from A = 5 up to 5.01 with branch_points = 1: its branch point, then
    !> the two branches crossing there (branches 1 and 2), each starting at the branch point's
    !> orbit.
    subroutine crossing_branches(t)
        type(tally_t), intent(inout) :: t
        type(model_t) :: model
        type(orbit_t) :: start
        type(branches_t) :: res
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        integer, allocatable :: first(:), last(:)
        integer :: i, p, b

        call chain12_orbit(model, start)
        call check(t, start%converged, 'branch point: the 22-impact orbit at A = 5')
        if (.not. start%converged) return
        opt%parameter = 'amplitude'
        opt%stop = 5.01_wp
        opt%step = 0.001_wp
        opt%branch_points = 1
        call follow_branches(model, 0.0_wp, 1, start%x, start%v, opt, res, err)
        call check(t, .not. allocated(err), 'switching: a result, not an error')
        if (allocated(err)) return
        print '(a)', '    '//res%end_reason
        p = 0
        do i = 1, res%n_specials
            if (res%specials(i)%kind == 'branch-point' .and. p == 0) p = res%specials(i)%point
        end do
        call check(t, p > 0, 'switching: the branch point found')
        if (p == 0) return
        call check_origins(t, res, 'switching')
        call check(t, res%n_branches == 3, 'switching: three branches')
        if (res%n_branches == 3) call check(t, all(res%origins(2:3)%parent == 0) .and. &
                                            all(res%origins(2:3)%point == p) .and. &
                                            res%origins(2)%kind == 'branch-point' .and. &
                                            res%origins(3)%kind == 'branch-point', &
                                            'switching: branches 1 and 2 began at branch 0''s '// &
                                            'branch point')
        associate (o => res%points(p)%orbit)
            write (*, '(a,f15.11,a,es9.2)') '    branch point at A = ', res%points(p)%value, &
                ', |multiplier - 1| = ', minval(abs(cmplx(o%multipliers_re - 1, &
                                                          o%multipliers_im, wp)))
            call check(t, minval(abs(cmplx(o%multipliers_re - 1, o%multipliers_im, wp))) < &
                       1.0e-8_wp, 'switching: the branch point has a multiplier 1 to 1e-8')
        end associate
        allocate (first(2), last(2))
        do b = 1, 2
            first(b) = findloc(res%points(:res%n_points)%branch, b, 1)
            last(b) = findloc(res%points(:res%n_points)%branch, b, 1, back=.true.)
        end do
        call check(t, all(first > 0) .and. all(last - first >= 2) .and. &
                   maxval(res%points(:res%n_points)%branch) == 2, &
                   'switching: two branches switched to, 1 and 2, with points')
        if (.not. (all(first > 0) .and. all(last - first >= 2))) return
        write (*, '(a,2f15.11)') '    branches 1 and 2 end at A = ', res%points(last)%value
        call check(t, res%points(p)%symmetric .and. all(res%points(:p)%symmetric), &
                   'switching: the parent branch is symmetric up to its branch point')
        call check(t, all([(res%points(first(b))%value == res%points(p)%value .and. &
                            all(res%points(first(b))%orbit%x == res%points(p)%orbit%x), &
                            b=1, 2)]), &
                   'switching: each branch starts at the branch point''s orbit')
        call check(t, .not. any(res%points(first(1) + 1:last(1))%symmetric) .and. &
                   .not. any(res%points(first(2) + 1:last(2))%symmetric), &
                   'switching: the orbits of the switched branches are not symmetric')
        call check(t, any(abs(res%points(first(1) + 1:last(1))%value - &
                              res%points(p)%value) > 1.0e-6_wp), &
                   'switching: the branch moves off the branch point')
        do i = first(1) + 1, last(1)
            call mirror_of_the_other(t, model, res, i, first(2), last(2))
        end do
    end subroutine crossing_branches

    !> The mirror image of point i (of branch 1) against the orbit of branch 2 at the same
    !> parameter, by Newton from branch 2's point nearest in the parameter. Both are fixed
    !> points of the map to Newton's tolerance 1e-11 (relative), so they agree to about
    !> 1e-11 / min |rho - 1|, J - I being nearly singular near the branch point: to 1e-8, or
    !> that where min |rho - 1| < 1e-3.
    subroutine mirror_of_the_other(t, model, res, i, first, last)
        type(tally_t), intent(inout) :: t
        type(model_t), intent(in) :: model
        type(branches_t), intent(in) :: res
        integer, intent(in) :: i, first, last
        type(model_t) :: at
        type(orbit_t) :: other
        type(error_t), allocatable :: err
        real(wp), allocatable :: x_mirror(:), v_mirror(:)
        real(wp) :: apart, mirrored, scale, closest
        integer :: j

        at = model
        call set_model_parameter(at, 'amplitude', res%points(i)%value)
        associate (x => res%points(i)%orbit%x, v => res%points(i)%orbit%v)
            call mirror_image(at, 0.0_wp, x, v, x_mirror, v_mirror, err)
            call check(t, .not. allocated(err), 'switching: the mirror image')
            if (allocated(err)) return
            j = first - 1 + minloc(abs(res%points(first:last)%value - res%points(i)%value), 1)
            call find_orbit(at, 0.0_wp, 1, res%points(j)%orbit%x, res%points(j)%orbit%v, &
                            other, err)
            call check(t, .not. allocated(err) .and. other%converged, &
                       'switching: Newton on branch 2 at the same A')
            if (allocated(err) .or. .not. other%converged) return
            scale = 1 + max(maxval(abs(x)), maxval(abs(v)))
            apart = max(maxval(abs(x_mirror - other%x)), maxval(abs(v_mirror - other%v)))/scale
            mirrored = max(maxval(abs(x_mirror - x)), maxval(abs(v_mirror - v)))/scale
        end associate
        closest = minval(abs(cmplx(other%multipliers_re - 1, other%multipliers_im, wp)))
        write (*, '(a,f15.11,3(a,es9.2))') '    A = ', res%points(i)%value, &
            ': |S z1 - z2| / (1 + |z1|) = ', apart, ', |S z1 - z1| / (1 + |z1|) = ', mirrored, &
            ', min |rho - 1| = ', closest
        call check_close(t, apart, 0.0_wp, 'switching: S of branch 1 = branch 2 at the same A', &
                         max(1.0e-8_wp, 1.0e-11_wp/closest))
        call check(t, mirrored > 1.0e3_wp*1.0e-8_wp, &
                   'switching: and not branch 1 itself (the two branches differ)')
    end subroutine mirror_of_the_other

end module test_branch_switch
