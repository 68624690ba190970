!> Neimark-Sacker curves in two parameters (docs/model.md section 12.6), against what cannot be
!> tuned: an asymmetric chain of two oscillators (spacings 1.3, 1.07, 0.59, K = 0.87,
!> b = 0.105, w = 1.6) whose period-1 orbit from A = 3.13 down has a Neimark-Sacker point;
!> its curve in (A, w) has a complex pair on the unit circle at every point, and the
!> Neimark-Sacker points that one-parameter runs locate at two of its points' w lie on it.
!> The names of the curve's ends (1:1 and 1:2 resonances) from the pair's last angle.
module test_curve_ns
    use chain_kinds, only: wp, i8, pi
    use chain_error, only: error_t
    use chain_model, only: model_t
    use chain_orbit, only: orbit_t
    use chain_branch, only: branch_options_t, branches_t, follow_branches
    use chain_curve, only: curve_options_t, curve_t, follow_curve
    use chain_curve_ns, only: pair_end_reason
    use chain_flow, only: make_flow
    use test_chains, only: model_of
    use test_branch, only: settle
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_curve_ns_tests

contains

    subroutine run_curve_ns_tests(t)
        type(tally_t), intent(inout) :: t

        call ns_curve(t)
        call ns_resonance(t)
        call ns_ends(t)
    end subroutine run_curve_ns_tests

    !> The Neimark-Sacker point at w = 1.6 followed up in w: a pair of modulus 1 to 1e-8 at
    !> every point; one-parameter runs at the w of its second and last points locate their
    !> Neimark-Sacker points at the curve's A to 1e-8.
    subroutine ns_curve(t)
        type(tally_t), intent(inout) :: t
        type(branches_t) :: ns
        type(curve_t) :: curve
        type(curve_options_t) :: opt
        type(error_t), allocatable :: err
        real(wp) :: worst
        integer :: k, j

        call ns_at(1.6_wp, ns, k)
        call check(t, k > 0, 'ns curve: a Neimark-Sacker point at w = 1.6')
        if (k == 0) return
        opt%follow = 'neimark-sacker'
        opt%parameter = 'amplitude'
        opt%parameter2 = 'omega'
        opt%stop2 = 1.8_wp
        opt%step2 = 0.02_wp
        opt%max_points = 10
        call follow_curve(example(ns%points(k)%value, 1.6_wp), 0.0_wp, 1, ns%points(k)%orbit%x, &
                          ns%points(k)%orbit%v, ns%points(k)%value, opt, curve, err)
        call check(t, .not. allocated(err), 'ns curve: followed')
        if (allocated(err)) then
            print '(a)', '    '//err%message
            return
        end if
        print '(a,i0,a)', '    ns curve: ', curve%n_points, ' points, '//curve%end_reason
        call check(t, curve%n_points >= 4, 'ns curve: at least four points')
        if (curve%n_points < 4) return
        worst = 0
        do j = 1, curve%n_points
            worst = max(worst, unit_pair_distance(curve%orbits(j)))
        end do
        write (*, '(a,es9.2)') '    ns curve: largest ||mu| - 1| of the nearest pair ', worst
        call check_close(t, worst, 0.0_wp, 'ns curve: a complex pair on the unit circle at '// &
                         'every point', 1.0e-8_wp)
        do j = 2, curve%n_points, curve%n_points - 2
            call ns_at(curve%values2(j), ns, k)
            call check(t, k > 0, 'ns curve: a one-parameter Neimark-Sacker point at its w')
            if (k == 0) cycle
            write (*, '(a,f15.11,a,es9.2)') '    one-parameter Neimark-Sacker at w = ', &
                curve%values2(j), ': |A - curve| = ', abs(ns%points(k)%value - curve%values(j))
            call check_close(t, ns%points(k)%value, curve%values(j), &
                             'ns curve: through the one-parameter Neimark-Sacker point', 1.0e-8_wp)
        end do
    end subroutine ns_curve

    !> The Neimark-Sacker point at K = 0.87 followed in (A, K) (K falling at the start): the
    !> curve turns and ends at a 1:1 resonance near K = 0.95, named so; its last pair lies
    !> within 0.1 of +1 and modulus 1 to 1e-8.
    subroutine ns_resonance(t)
        type(tally_t), intent(inout) :: t
        type(branches_t) :: ns
        type(curve_t) :: curve
        type(curve_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: k

        call ns_at(1.6_wp, ns, k)
        if (k == 0) return
        opt%follow = 'neimark-sacker'
        opt%parameter = 'amplitude'
        opt%parameter2 = 'restitution'
        opt%stop2 = 0.3_wp
        opt%step2 = -0.01_wp
        opt%max_points = 300
        call follow_curve(example(ns%points(k)%value, 1.6_wp), 0.0_wp, 1, ns%points(k)%orbit%x, &
                          ns%points(k)%orbit%v, ns%points(k)%value, opt, curve, err)
        call check(t, .not. allocated(err), 'ns resonance: followed')
        if (allocated(err)) return
        k = curve%n_points
        print '(a,i0,a)', '    ns curve in (A, K): ', k, ' points, '//curve%end_reason
        call check(t, index(curve%end_reason, '1:1 resonance near amplitude = ') == 1, &
                   'ns resonance: the end named a 1:1 resonance')
        associate (o => curve%orbits(k))
            call check(t, minval(hypot(o%multipliers_re - 1, o%multipliers_im), &
                                 mask=o%multipliers_im > 0) < 0.1_wp .and. &
                       unit_pair_distance(o) < 1.0e-8_wp, &
                       'ns resonance: the last pair on the unit circle near +1')
        end associate
    end subroutine ns_resonance

    !> A curve ends at a resonance when its pair turned real or its last angle is within 0.1
    !> of 0 (1:1) or pi (1:2); at another angle, Newton's failure alone is no resonance.
    subroutine ns_ends(t)
        type(tally_t), intent(inout) :: t
        character(len=*), parameter :: place = ' near amplitude = 1, omega = 2'
        character(len=:), allocatable :: reason

        reason = pair_end_reason(cmplx(cos(0.05_wp), sin(0.05_wp), wp), place, 'no convergence')
        call check(t, index(reason, '1:1 resonance near amplitude = 1, omega = 2') == 1, &
                   'ns ends: a small angle is a 1:1 resonance: '//reason)
        reason = pair_end_reason(cmplx(cos(pi - 0.05_wp), sin(pi - 0.05_wp), wp), place, &
                                 'no convergence')
        call check(t, index(reason, '1:2 resonance') == 1, &
                   'ns ends: an angle near pi is a 1:2 resonance: '//reason)
        reason = pair_end_reason(cmplx(cos(2.5_wp), sin(2.5_wp), wp), place, &
                                 'the complex pair turned real (a multiplier -0.99)')
        call check(t, index(reason, '1:2 resonance') == 1, &
                   'ns ends: a pair turned real is a resonance at any angle: '//reason)
        reason = pair_end_reason(cmplx(cos(1.0_wp), sin(1.0_wp), wp), place, 'no convergence')
        call check(t, len(reason) == 0, 'ns ends: no resonance at angle 1')
    end subroutine ns_ends

    !> ||mu| - 1| of the complex multiplier nearest the unit circle (huge: none complex).
    pure real(wp) function unit_pair_distance(orbit) result(d)
        type(orbit_t), intent(in) :: orbit

        associate (re => orbit%multipliers_re, im => orbit%multipliers_im)
            d = minval(abs(hypot(re, im) - 1), mask=im /= 0)
        end associate
    end function unit_pair_distance

    !> The example's period-1 orbit at A = 3.13, frequency w, followed down to 2; k the point
    !> of its first Neimark-Sacker point (0: none).
    subroutine ns_at(omega, res, k)
        real(wp), intent(in) :: omega
        type(branches_t), intent(out) :: res
        integer, intent(out) :: k
        type(orbit_t) :: start
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        integer :: j

        k = 0
        call settle(example(3.13_wp, omega), 300_i8, 1, start)
        opt%parameter = 'amplitude'
        opt%stop = 2
        opt%step = -0.05_wp
        opt%max_points = 60
        call follow_branches(example(3.13_wp, omega), 0.0_wp, 1, start%x, start%v, opt, res, &
                             err)
        if (allocated(err)) return
        do j = res%n_specials, 1, -1
            if (res%specials(j)%kind == 'neimark-sacker' .and. &
                res%points(res%specials(j)%point)%branch == 0) k = res%specials(j)%point
        end do
    end subroutine ns_at

    !> The asymmetric two-oscillator chain at amplitude A, frequency w.
    function example(amplitude, omega) result(model)
        real(wp), intent(in) :: amplitude, omega
        type(model_t) :: model

        model = model_of(make_flow(0.105_wp, amplitude, omega), 0.87_wp, &
                         [1.3_wp, 1.07_wp, 0.59_wp], .true., 1.0e-9_wp)
    end function example

end module test_curve_ns
