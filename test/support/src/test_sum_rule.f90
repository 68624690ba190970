!> The Lyapunov sum rule as a check of the tests (docs/model.md section 7): shared by the
!> invariant, Lyapunov and census suites, which sit in different layers' folders.
module test_sum_rule
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use chain_kinds, only: wp, i8
    use chain_flow, only: flow_t
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: check_sum_rule, real_text

contains

    !> The sum rule: the sum of all 2n exponents in nats per cycle is -2 b n T + 2 ln(K) c,
    !> c the mean number of impacts per cycle (the flow multiplies phase-space volume by
    !> exp(-2 b n T) per cycle, every impact by K**2). Checked to 1e-9 of the larger of 1 and
    !> the expected sum: the logarithms of the QR diagonals add up to the logarithm of each
    !> cycle's determinant, exact to rounding. With K = 0 and impacts the sum is -infinity.
    subroutine check_sum_rule(t, label, n, flow, restitution, collisions_per_cycle, &
                              bits_per_cycle, sticks)
        type(tally_t), intent(inout) :: t
        character(len=*), intent(in) :: label
        integer, intent(in) :: n
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: restitution, collisions_per_cycle, bits_per_cycle(:)
        integer(i8), intent(in) :: sticks
        real(wp) :: total, expected
        logical :: infinite

        call check(t, size(bits_per_cycle) == 2*n, 'sum rule '//label//': all 2n exponents')
        if (size(bits_per_cycle) /= 2*n) return
        ! Excluded: runs with rests on a wall. A rest zeroes the resting oscillator's tangent
        ! rows (the Jacobian is singular, as the true infinite chatter sequence makes it), so
        ! the sum is -infinity whatever K; such runs are treated separately.
        if (sticks > 0) return
        infinite = .not. all(ieee_is_finite(bits_per_cycle))
        total = -huge(1.0_wp)
        if (.not. infinite) total = sum(bits_per_cycle)*log(2.0_wp)
        if (restitution == 0 .and. collisions_per_cycle > 0) then
            ! det S = K**2 = 0 at every impact: the exact sum is -infinity
            call check(t, infinite, 'sum rule '//label//': K = 0 with impacts, the sum '// &
                       'must be -infinity, got '//real_text(total)//' nats per cycle')
            return
        end if
        expected = -2*flow%damping*n*flow%period
        if (collisions_per_cycle > 0) expected = expected + &
                                                 2*log(restitution)*collisions_per_cycle
        if (infinite) then
            call check(t, .false., 'sum rule '//label//': an exponent is -infinity, want '// &
                       real_text(expected)//' nats per cycle in all')
            return
        end if
        call check_close(t, total, expected, 'sum rule '//label//' (nats per cycle)', &
                         abs_tol=1.0e-9_wp, rel_tol=1.0e-9_wp)
    end subroutine check_sum_rule

    function real_text(x) result(text)
        real(wp), intent(in) :: x
        character(len=:), allocatable :: text
        character(len=32) :: buf

        write (buf, '(es12.4)') x
        text = trim(adjustl(buf))
    end function real_text

end module test_sum_rule
