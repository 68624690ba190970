!> The undamped single impact oscillator against Budd and Dux (1994) (docs/model.md 12.4):
!> x'' + x = A sin(w t), one wall at x = sigma (bond 1, spacing sigma) and the other far
!> (bond 0, spacing 1000). Its (1,1) orbits, one impact of speed V per drive period, satisfy
!>
!>     (sigma + c V/2)**2 + ((1 - r) V/(2 w))**2 = gamma**2,
!>     gamma = 1/(1 - w**2),   c = (1 + r) sin(2 pi/w)/(1 - cos(2 pi/w)),
!>
!> at A = 1, and turn at the fold sigma_s = |gamma| sqrt(1 + (c w/(1 - r))**2). The model
!> continues A, not one wall's spacing (a continuation in `spacing` moves every bond), so the
!> branch is followed in A at a fixed wall sigma0: by the scaling symmetry of 1.5 the orbit
!> at A is the one at A = 1 with the wall at sigma0/A and the speed V/A. Checked: every point
!> on the closed form's curve, its fold where the form says and named a fold (on this chain,
!> not mirror-symmetric, a multiplier through +1 with a turn is no branch point), and the
!> product of the multipliers r**2 per impact (b = 0: no decay between impacts).
module test_budd_dux
    use chain_kinds, only: wp, two_pi
    use chain_error, only: error_t
    use chain_flow, only: make_flow
    use chain_model, only: model_t
    use chain_branch, only: branch_options_t, branches_t, follow_branches
    use test_chains, only: model_of
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_budd_dux_tests

    real(wp), parameter :: w = 1.5_wp, r = 0.8_wp, sigma0 = 5.0_wp

contains

    subroutine run_budd_dux_tests(t)
        type(tally_t), intent(inout) :: t
        type(model_t) :: model
        type(branches_t) :: res
        type(branch_options_t) :: opt
        type(error_t), allocatable :: err
        real(wp) :: x0(1), v0(1)

        model = model_of(make_flow(0.0_wp, 1.0_wp, w), r, [1000.0_wp, sigma0], .true., &
                         1.0e-9_wp)
        call closed_form_state(sigma0, x0(1), v0(1))
        opt%parameter = 'amplitude'
        opt%stop = 0.7_wp
        opt%step = -0.01_wp
        opt%max_points = 400
        call follow_branches(model, 0.0_wp, 1, x0, v0, opt, res, err)
        call check(t, .not. allocated(err), 'Budd-Dux: a result, not an error')
        if (allocated(err)) return
        print '(a)', '    '//res%end_reason
        call check(t, res%n_points > 10 .and. all(res%points(:res%n_points)%orbit%impacts == 1), &
                   'Budd-Dux: a branch of (1,1) orbits, one impact per period')
        if (res%n_points == 0) return
        call on_the_curve(t, res)
        call fold_where_the_form_says(t, res)
    end subroutine run_budd_dux_tests

    pure real(wp) function c_s()
        c_s = (1 + r)*sin(two_pi/w)/(1 - cos(two_pi/w))
    end function c_s

    pure real(wp) function gamma_w()
        gamma_w = 1/(1 - w**2)
    end function gamma_w

    !> The state on the section (drive phase 0) of the (1,1) orbit at A = 1 with the wall at
    !> sigma, its larger root V: between impacts x = gamma cos(w s + phi) + C cos s + D sin s,
    !> s the time since the impact, x(0) = sigma, x'(0) = -r V, the drive cos(w s + phi) the
    !> model's sin(w t) at t = s + (phi + pi/2)/w.
    subroutine closed_form_state(sigma, x, v)
        real(wp), intent(in) :: sigma
        real(wp), intent(out) :: x, v
        real(wp) :: k, qa, qb, qc, speed, phi, c, d, s, period

        k = (1 - r)/(2*w)
        qa = c_s()**2/4 + k**2
        qb = sigma*c_s()
        qc = sigma**2 - gamma_w()**2
        speed = (-qb + sqrt(qb**2 - 4*qa*qc))/(2*qa)
        phi = atan2(-(1 - r)*speed/(2*w*gamma_w()), (sigma + c_s()*speed/2)/gamma_w())
        c = sigma - gamma_w()*cos(phi)
        d = gamma_w()*w*sin(phi) - r*speed
        period = two_pi/w
        s = modulo(-(phi + two_pi/4)/w, period)
        x = gamma_w()*cos(w*s + phi) + c*cos(s) + d*sin(s)
        v = -gamma_w()*w*sin(w*s + phi) - c*sin(s) + d*cos(s)
    end subroutine closed_form_state

    !> Every point (sigma, V) = (sigma0, V)/A against the curve F = 0 of the closed form, by its
    !> distance |F|/|grad F| (well conditioned also at the fold, where V(sigma) is not)
    !> relative to 1 + max(sigma, V), as Newton's residual is relative to the orbit's size, to
    !> 1e-10; and the product of its multipliers r**2 to 1e-10.
    subroutine on_the_curve(t, res)
        type(tally_t), intent(inout) :: t
        type(branches_t), intent(in) :: res
        real(wp) :: sigma, speed, f, grad(2), dist, worst, product_error, k
        complex(wp) :: product
        integer :: i

        k = (1 - r)/(2*w)
        worst = 0
        product_error = 0
        do i = 1, res%n_points
            associate (p => res%points(i))
                sigma = sigma0/p%value
                speed = p%orbit%min_impact_speed/p%value
                f = (sigma + c_s()*speed/2)**2 + (k*speed)**2 - gamma_w()**2
                grad = [2*(sigma + c_s()*speed/2), c_s()*(sigma + c_s()*speed/2) + 2*k**2*speed]
                dist = abs(f)/norm2(grad)/(1 + max(sigma, speed))
                worst = max(worst, dist)
                product = product_of(p%orbit%multipliers_re, p%orbit%multipliers_im)
                product_error = max(product_error, abs(product - r**2))
            end associate
        end do
        write (*, '(a,i0,a,es9.2,a,es9.2)') '    ', res%n_points, &
            ' points: largest relative distance from the closed form ', worst, &
            ', |product of multipliers - r**2| ', product_error
        call check_close(t, worst, 0.0_wp, 'Budd-Dux: every (sigma, V) on the closed form', &
                         1.0e-10_wp)
        call check_close(t, product_error, 0.0_wp, &
                         'Budd-Dux: the multipliers multiply to r**2 (one impact)', 1.0e-10_wp)
    end subroutine on_the_curve

    pure complex(wp) function product_of(re, im) result(product)
        real(wp), intent(in) :: re(:), im(:)
        integer :: j

        product = 1
        do j = 1, size(re)
            product = product*cmplx(re(j), im(j), wp)
        end do
    end function product_of

    !> One fold, at sigma0/A = sigma_s to 1e-9, and no branch point.
    subroutine fold_where_the_form_says(t, res)
        type(tally_t), intent(inout) :: t
        type(branches_t), intent(in) :: res
        real(wp) :: sigma_s
        integer :: i, folds, branch_points, s

        folds = 0
        branch_points = 0
        s = 0
        do i = 1, res%n_specials
            if (res%specials(i)%kind == 'fold') then
                folds = folds + 1
                s = i
            end if
            if (res%specials(i)%kind == 'branch-point') branch_points = branch_points + 1
        end do
        call check(t, folds == 1 .and. branch_points == 0, &
                   'Budd-Dux: one fold, stored as a fold, no branch point')
        if (s == 0) return
        sigma_s = abs(gamma_w())*sqrt(1 + (c_s()*w/(1 - r))**2)
        write (*, '(a,f16.12,a,f16.12)') '    fold at sigma = ', &
            sigma0/res%specials(s)%value, ', closed form ', sigma_s
        call check_close(t, sigma0/res%specials(s)%value, sigma_s, &
                         'Budd-Dux: the fold at sigma_s', 1.0e-9_wp)
    end subroutine fold_where_the_form_says

end module test_budd_dux
