!> The grazing curve in two parameters (docs/model.md section 12.6), against the closed form:
!> figure 10's forced response (every oscillator alike, no impact) touches both walls where
!> its amplitude A / D(w) reaches the spacing a, so the curve is A = a D(w),
!> D(w) = sqrt((1 - w**2)**2 + (2 b w)**2), to 1e-10 at every point, from w = 1.9 down through
!> the resonance; every point's orbit is the forced response there and its smallest gap 0.
!> The grazing of an orbit with impacts: figure 10's family with the two wall impacts, from
!> rest upwards, grazes again (a gap of the next bonds); its curve passes through the grazings
!> that one-parameter runs locate at two of its points' w. The same chain with its left wall
!> farther (a = 1.05: no mirror symmetry, so no multiplier is doubled): the grazing curve of
!> its one-impact family meets a fold curve, located on it where its orbit has a multiplier
!> +1 and a gap 0, and the one-parameter run from rest at that w grazes there too.
module test_curve_graze
    use chain_kinds, only: wp
    use chain_error, only: error_t
    use chain_model, only: model_t
    use chain_orbit, only: multiplier_distance
    use chain_flow, only: flow_t, make_flow, forced_response
    use chain_curve, only: curve_options_t, curve_t, follow_curve
    use chain_branch, only: branch_options_t, branches_t, follow_branches
    use test_chains, only: fig10_model
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: grazing_curve, impacting_grazing_curve, fold_meets_grazing

contains

    !> From the forced response at 0.999 of the grazing amplitude (the start is refined at
    !> w = 1.9), the curve down in w to 0.6.
    subroutine grazing_curve(t)
        type(tally_t), intent(inout) :: t
        type(model_t) :: model
        type(curve_options_t) :: opt
        type(curve_t) :: curve, again
        type(error_t), allocatable :: err
        real(wp) :: a_start, xp, vp, xp0, vp0, worst_a, worst_orbit, worst_gap
        integer :: j

        model = fig10_model(1.0_wp)
        a_start = 0.999_wp*closed_form(model, model%omega)
        call forced_response(make_flow(model%damping, a_start, model%omega), 0.0_wp, xp, vp)
        xp0 = xp
        vp0 = vp
        model = fig10_model(a_start)
        opt%follow = 'grazing'
        opt%parameter = 'amplitude'
        opt%parameter2 = 'omega'
        opt%stop2 = 0.6_wp
        opt%step2 = -0.25_wp
        opt%max_points = 60
        call follow_curve(model, 0.0_wp, 1, spread(xp, 1, model%n), spread(vp, 1, model%n), &
                          a_start, opt, curve, err)
        call check(t, .not. allocated(err), 'grazing curve: followed')
        if (allocated(err)) then
            print '(a)', '    '//err%message
            return
        end if
        print '(a,i0,a,f6.3,a,f6.3)', '    grazing curve: ', curve%n_points, &
            ' points, '//curve%end_reason//', w from ', curve%values2(1), ' to ', &
            curve%values2(max(1, curve%n_points))
        call check(t, curve%end_reason == 'bound' .and. curve%n_points >= 20, &
                   'grazing curve: from w = 1.9 to the bound 0.6')
        worst_a = 0
        worst_orbit = 0
        worst_gap = 0
        do j = 1, curve%n_points
            worst_a = max(worst_a, abs(curve%values(j) - closed_form(model, curve%values2(j))))
            call forced_response(make_flow(model%damping, curve%values(j), curve%values2(j)), &
                                 0.0_wp, xp, vp)
            worst_orbit = max(worst_orbit, maxval(abs(curve%orbits(j)%x - xp)), &
                              maxval(abs(curve%orbits(j)%v - vp)))
            worst_gap = max(worst_gap, abs(curve%orbits(j)%min_gap))
        end do
        write (*, '(a,es9.2,a,es9.2,a,es9.2)') '    |A - a D(w)| <= ', worst_a, &
            ', |orbit - forced response| <= ', worst_orbit, ', |smallest gap| <= ', worst_gap
        call check_close(t, worst_a, 0.0_wp, 'grazing curve: A = a D(w) at every point', &
                         1.0e-10_wp)
        call check_close(t, worst_orbit, 0.0_wp, &
                         'grazing curve: the forced response at every point', 1.0e-10_wp)
        call check_close(t, worst_gap, 0.0_wp, 'grazing curve: a gap touching zero', &
                         1.0e-10_wp)
        call check(t, all(curve%orbits(:curve%n_points)%impacts == 0), &
                   'grazing curve: no impact at any point')
        ! the same points from spacings stored 1-based, as the command line stores them
        opt%max_points = 3
        call follow_curve(one_based(model), 0.0_wp, 1, spread(xp0, 1, model%n), &
                          spread(vp0, 1, model%n), a_start, opt, again, err)
        call check(t, .not. allocated(err) .and. again%n_points == 3, &
                   'grazing curve: followed from 1-based spacings')
        if (allocated(err) .or. again%n_points /= 3) return
        call check(t, all(again%values(:3) == curve%values(:3)) .and. &
                   all(again%values2(:3) == curve%values2(:3)), &
                   "grazing curve: the same points whatever the spacings' lower bound")
    end subroutine grazing_curve

    !> The model with its spacings stored 1-based (bond k's rest gap spacing(k + 1)).
    pure function one_based(model) result(shifted)
        type(model_t), intent(in) :: model
        type(model_t) :: shifted

        shifted = model
        deallocate (shifted%spacing)
        allocate (shifted%spacing(model%n + 1), source=model%spacing)
    end function one_based

    !> From figure 10's second grazing at w = 1.9 (its two-impact family's), the curve up in w.
    subroutine impacting_grazing_curve(t)
        type(tally_t), intent(inout) :: t
        type(branches_t) :: res
        type(curve_options_t) :: opt
        type(curve_t) :: curve
        type(error_t), allocatable :: err
        integer :: k, j

        call second_grazing(1.9_wp, res, k)
        call check(t, k > 0, 'impacting grazing curve: a second grazing at w = 1.9')
        if (k == 0) return
        print '(a,i0,a,f15.11)', '    second grazing: ', res%points(k)%orbit%impacts, &
            ' impacts per cycle, A = ', res%points(k)%value
        opt%follow = 'grazing'
        opt%parameter = 'amplitude'
        opt%parameter2 = 'omega'
        opt%stop2 = 1.95_wp
        opt%step2 = 0.02_wp
        opt%max_points = 6
        call follow_curve(fig10_model(res%points(k)%value), 0.0_wp, 1, res%points(k)%orbit%x, &
                          res%points(k)%orbit%v, res%points(k)%value, opt, curve, err)
        call check(t, .not. allocated(err), 'impacting grazing curve: followed')
        if (allocated(err)) then
            print '(a)', '    '//err%message
            return
        end if
        print '(a,i0,a)', '    impacting grazing curve: ', curve%n_points, &
            ' points, '//curve%end_reason
        call check(t, curve%n_points >= 4, 'impacting grazing curve: at least four points')
        if (curve%n_points < 4) return
        call check(t, all(curve%orbits(:curve%n_points)%impacts == &
                          res%points(k)%orbit%impacts), &
                   'impacting grazing curve: the impacts of the grazing orbit at every point')
        do j = 2, curve%n_points, curve%n_points - 2
            call second_grazing(curve%values2(j), res, k)
            call check(t, k > 0, 'impacting grazing curve: a one-parameter grazing at its w')
            if (k == 0) cycle
            write (*, '(a,f15.11,a,es9.2)') '    one-parameter grazing at w = ', &
                curve%values2(j), ': |A - curve| = ', abs(res%points(k)%value - curve%values(j))
            call check_close(t, res%points(k)%value, curve%values(j), &
                             'impacting grazing curve: through the one-parameter grazing', &
                             1.0e-9_wp)
        end do
    end subroutine impacting_grazing_curve

    !> The asymmetric chain's second grazing at w = 1.9 followed up in w: one fold-grazing
    !> point, confirmed, and found again by a one-parameter run at its w.
    subroutine fold_meets_grazing(t)
        type(tally_t), intent(inout) :: t
        type(branches_t) :: res
        type(curve_options_t) :: opt
        type(curve_t) :: curve
        type(error_t), allocatable :: err
        real(wp) :: unit_distance
        integer :: k, j

        call second_grazing(1.9_wp, res, k, 1.05_wp)
        call check(t, k > 0, 'fold meets grazing: a second grazing at w = 1.9')
        if (k == 0) return
        opt%follow = 'grazing'
        opt%parameter = 'amplitude'
        opt%parameter2 = 'omega'
        opt%stop2 = 2.0_wp
        opt%step2 = 0.05_wp
        opt%max_points = 14
        call follow_curve(asymmetric(res%points(k)%value), 0.0_wp, 1, res%points(k)%orbit%x, &
                          res%points(k)%orbit%v, res%points(k)%value, opt, curve, err)
        call check(t, .not. allocated(err), 'fold meets grazing: followed')
        if (allocated(err)) return
        print '(a,i0,a,i0,a)', '    grazing curve of the asymmetric chain: ', curve%n_points, &
            ' points, '//curve%end_reason//', ', curve%n_codim2, ' codim-2 points'
        call check(t, curve%n_codim2 == 1, 'fold meets grazing: one codim-2 point')
        if (curve%n_codim2 /= 1) return
        j = curve%codim2_index(1)
        unit_distance = multiplier_distance(curve%orbits(j), 1.0_wp)
        write (*, '(a,a,a,f15.11,a,f15.11,a,es9.2,a,es9.2)') '    ', &
            trim(curve%codim2_kind(1)), ' at A = ', curve%values(j), ', w = ', &
            curve%values2(j), ': |multiplier - 1| = ', unit_distance, ', gap ', &
            curve%orbits(j)%min_gap
        call check(t, curve%codim2_kind(1) == 'fold-grazing', 'fold meets grazing: its kind')
        call check_close(t, unit_distance, 0.0_wp, 'fold meets grazing: a multiplier +1', &
                         1.0e-8_wp)
        call check_close(t, curve%orbits(j)%min_gap, 0.0_wp, 'fold meets grazing: gap 0', &
                         1.0e-10_wp)
        call check(t, (curve%values2(j) - curve%values2(j - 1))* &
                   (curve%values2(j + 1) - curve%values2(j)) > 0, &
                   'fold meets grazing: between its neighbours on the curve')
        call second_grazing(curve%values2(j), res, k, 1.05_wp)
        call check(t, k > 0, 'fold meets grazing: a one-parameter grazing at its w')
        if (k == 0) return
        write (*, '(a,es9.2,a,es9.2)') '    one-parameter run there: |A - curve| = ', &
            abs(res%points(k)%value - curve%values(j)), ', |multiplier - 1| = ', &
            multiplier_distance(res%points(k)%orbit, 1.0_wp)
        call check_close(t, res%points(k)%value, curve%values(j), &
                         'fold meets grazing: the one-parameter grazing there', 1.0e-9_wp)
    end subroutine fold_meets_grazing

    !> Figure 10's chain with its left wall at 1.05.
    function asymmetric(amplitude) result(model)
        real(wp), intent(in) :: amplitude
        type(model_t) :: model

        model = fig10_model(amplitude)
        model%spacing(lbound(model%spacing, 1)) = 1.05_wp
    end function asymmetric

    !> Figure 10's chain at frequency w (its left wall at `left`, 1 when absent) followed from
    !> rest upwards in A; k the point of its second grazing (0: none).
    subroutine second_grazing(omega, res, k, left)
        real(wp), intent(in) :: omega
        type(branches_t), intent(out) :: res
        integer, intent(out) :: k
        real(wp), intent(in), optional :: left
        type(branch_options_t) :: opt
        type(model_t) :: model
        type(error_t), allocatable :: err
        integer :: j, found

        k = 0
        model = fig10_model(1.0_wp)
        if (present(left)) model%spacing(lbound(model%spacing, 1)) = left
        model%omega = omega
        opt%parameter = 'amplitude'
        opt%stop = 3
        opt%step = 0.1_wp
        opt%max_points = 200
        call follow_branches(model, 0.0_wp, 1, [(0.0_wp, j=1, 8)], [(0.0_wp, j=1, 8)], opt, &
                             res, err)
        if (allocated(err)) return
        found = 0
        do j = 1, res%n_specials
            if (res%specials(j)%kind /= 'grazing') cycle
            found = found + 1
            if (found == 2) then
                k = res%specials(j)%point
                return
            end if
        end do
    end subroutine second_grazing

    !> The amplitude at which figure 10's forced response at frequency w touches the walls.
    pure real(wp) function closed_form(model, omega)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: omega

        closed_form = model%spacing(0)*sqrt((1 - omega**2)**2 + (2*model%damping*omega)**2)
    end function closed_form

end module test_curve_graze
