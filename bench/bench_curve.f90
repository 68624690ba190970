!> `impactchain-bench --curve`: one point of a fold curve in two parameters (A, w) against one
!> Newton solve of a periodic orbit, at n = 8 and n = 16 (figure 10's parameters, the fold of
!> the impacting orbit followed down from A = 3), in one process, timed alternately in CPU
!> time, the best of `rounds`. A curve point costs a Newton solve of the augmented system whose
!> every iteration differences the Jacobian in each of 2n + 2 unknowns (chain_curve_system).
module bench_curve
    use, intrinsic :: iso_fortran_env, only: output_unit
    use impactchain, only: wp, error_t, config_t, model_t, orbit_t, find_orbit, &
                           branch_options_t, branches_t, follow_branches, curve_options_t, &
                           curve_t, follow_curve
    use impactchain_drivers, only: continuation_guess, fmt_int
    implicit none
    private
    public :: curve_ratio

contains

    !> The table: CPU ms per Newton solve, per curve point, and their ratio, for each chain.
    subroutine curve_ratio(configs, rounds)
        type(config_t), intent(in) :: configs(:)
        integer, intent(in) :: rounds
        type(branches_t) :: fold
        type(curve_options_t) :: opt
        real(wp) :: newton, point
        integer :: j, k

        write (output_unit, '(a)') '| fig. 10 fold, (A, w) | CPU ms per Newton solve | '// &
            'CPU ms per curve point | ratio |', '|---|---:|---:|---:|'
        do j = 1, size(configs)
            call fold_of(configs(j), fold)
            if (fold%n_specials == 0) then
                write (output_unit, '(a)') '| n = '//fmt_int(configs(j)%model%n)// &
                    ' | no fold on the branch from A = 3 | | |'
                cycle
            end if
            k = fold%specials(1)%point
            opt%follow = 'fold'
            opt%parameter = 'amplitude'
            opt%parameter2 = 'omega'
            opt%step2 = 0.002_wp
            opt%stop2 = 3
            call time_both(configs(j), fold%points(k)%orbit, fold%points(k)%value, opt, &
                           rounds, newton, point)
            write (output_unit, '(a, f0.3, a, f0.3, a, f0.1, a)') '| n = '// &
                fmt_int(configs(j)%model%n)//' | ', 1.0e3_wp*newton, ' | ', &
                1.0e3_wp*point, ' | ', point/newton, ' |'
        end do
    end subroutine curve_ratio

    !> The impacting orbit at A = 3 followed down to its first special point.
    subroutine fold_of(cfg, res)
        type(config_t), intent(in) :: cfg
        type(branches_t), intent(out) :: res
        type(config_t) :: settled
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        real(wp), allocatable :: x(:), v(:)

        settled = cfg
        settled%record%transient = 300
        call continuation_guess(settled, x, v, err)
        if (allocated(err)) error stop err%message
        opt%parameter = 'amplitude'
        opt%stop = 1
        opt%step = -0.05_wp
        call follow_branches(cfg%model, 0.0_wp, 1, x, v, opt, res, err)
        if (allocated(err)) error stop err%message
        if (res%n_specials > 0) then
            if (res%specials(1)%kind /= 'fold') res%n_specials = 0
        end if
    end subroutine fold_of

    !> Best CPU seconds of a Newton solve (from the fold orbit, at A 1e-3 above the fold) and
    !> of one curve point (the best of three points less the best of the refined start alone,
    !> over two).
    subroutine time_both(cfg, orbit, mu, opt, rounds, newton, point)
        type(config_t), intent(in) :: cfg
        type(orbit_t), intent(in) :: orbit
        real(wp), intent(in) :: mu
        type(curve_options_t), intent(inout) :: opt
        integer, intent(in) :: rounds
        real(wp), intent(out) :: newton, point
        type(orbit_t) :: solved
        type(curve_t) :: curve
        type(error_t), allocatable :: err
        real(wp) :: t0, t1, t3, start, three
        integer :: r

        newton = huge(1.0_wp)
        start = huge(1.0_wp)
        three = huge(1.0_wp)
        associate (model => cfg%model)
            do r = 1, rounds
                call cpu_time(t0)
                call find_orbit(model_at(model, mu + 1.0e-3_wp), 0.0_wp, 1, orbit%x, orbit%v, &
                                solved, err)
                call cpu_time(t1)
                if (allocated(err) .or. .not. solved%converged) error stop 'curve bench: Newton'
                newton = min(newton, t1 - t0)
                opt%max_points = 1
                call cpu_time(t0)
                call follow_curve(model_at(model, mu), 0.0_wp, 1, orbit%x, orbit%v, mu, &
                                       opt, curve, err)
                call cpu_time(t1)
                start = min(start, t1 - t0)
                opt%max_points = 3
                call follow_curve(model_at(model, mu), 0.0_wp, 1, orbit%x, orbit%v, mu, &
                                       opt, curve, err)
                call cpu_time(t3)
                three = min(three, t3 - t1)
                if (allocated(err) .or. curve%n_points < 3) error stop 'curve bench: '// &
                    'the fold curve has '//fmt_int(curve%n_points)//' points'
            end do
            point = (three - start)/2
        end associate
    end subroutine time_both

    !> The model at amplitude mu.
    function model_at(model, mu) result(out)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: mu
        type(model_t) :: out

        out = model
        out%amplitude = mu
    end function model_at

end module bench_curve
