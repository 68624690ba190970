!> The non-smooth corners of the model, each with the input that once went silently wrong:
!> the release from the right wall, impacts at rounding-level approach speed (touches),
!> inelastic cascades, and the tangent of runs with rests (directions removed by a rest are
!> counted as collapsed, never as a logarithm of rounding).
module test_corners
    use chain_kinds, only: wp, i8, pi
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use chain_error, only: error_t
    use chain_flow, only: make_flow
    use chain_state, only: contact_free, moving_state
    use chain_engine, only: chain_t, chain_init, chain_gaps_now, chain_model, chain_cycle, &
                            chain_time, chain_positions, chain_velocities, chain_contacts
    use chain_event_log, only: event_log_t, event_log_init, event_impact, event_stick, &
                            event_release, event_touch
    use chain_record, only: record_cycles, memory_sink_t, record_result_t, record_spec_t
    use chain_section, only: advance_to_point
    use chain_floquet, only: poincare_jacobian, floquet_multipliers
    use testing, only: tally_t, check, check_close
    use test_chains, only: init_chain
    implicit none
    private
    public :: run_corner_tests

contains

    subroutine run_corner_tests(t)
        type(tally_t), intent(inout) :: t

        call right_wall_release(t)
        call right_wall_stack_gap(t)
        call touch_keeps_sum_rule(t)
        call cascade_jacobian(t)
        call rest_orbit(t)
    end subroutine run_corner_tests

    !> A chain in state (x, v) at t = 0.
    subroutine new_chain(chain, damping, restitution, amplitude, omega, spacing, walls, x, v, &
                         err)
        type(chain_t), intent(out) :: chain
        real(wp), intent(in) :: damping, restitution, amplitude, omega, spacing(0:), x(:), v(:)
        logical, intent(in) :: walls
        type(error_t), allocatable, intent(out) :: err

        call init_chain(chain, make_flow(damping, amplitude, omega), restitution, spacing, &
                        walls, 1.0e-9_wp, x, v, 0_i8, 0.0_wp, err)
    end subroutine new_chain

    function record_spec(transient, cycles, lyapunov, phase) result(spec)
        integer(i8), intent(in) :: transient, cycles
        logical, intent(in) :: lyapunov
        real(wp), intent(in), optional :: phase
        type(record_spec_t) :: spec

        spec%transient = transient
        spec%cycles = cycles
        spec%record_events = .true.
        spec%lyapunov = lyapunov
        spec%vectors = 0
        spec%qr_every = 1
        if (present(phase)) spec%phase = phase
    end function record_spec

    !> One oscillator between walls 0.5 away, driven slowly (A = 1, w = 0.5) from rest: it
    !> comes to rest on the right wall. The force on it at rest on the right wall, A sin(w t) - a,
    !> turns away from the wall as sin(w t) falls through a/A: it leaves at w t = pi - asin(1/2)
    !> (mod 2 pi), the mirror image of the left-wall rule (-asin(1/2)). The strobes are those
    !> of an independent implementation of the model.
    subroutine right_wall_release(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(memory_sink_t) :: sink
        type(record_result_t) :: res
        real(wp) :: phase, worst_right, worst_left
        integer :: j, left, right

        call new_chain(chain, 0.1_wp, 0.5_wp, 1.0_wp, 0.5_wp, [0.5_wp, 0.5_wp], .true., &
                       [0.0_wp], [0.0_wp], err)
        call record_cycles(record_spec(0_i8, 6_i8, .false.), chain, sink, res, err)
        call check(t, .not. allocated(err), 'right-wall release run completes')
        if (allocated(err)) return
        call check_close(t, sink%x(1, 1), -0.42131_wp, 'right-wall release: first strobe', &
            5.0e-6_wp)
        call check_close(t, sink%x(1, 2), -0.42113_wp, 'right-wall release: second strobe', &
                         5.0e-6_wp)
        call check_close(t, sink%x(1, 3), -0.42110_wp, 'right-wall release: third strobe', &
                         5.0e-6_wp)
        left = 0
        right = 0
        worst_left = 0
        worst_right = 0
        do j = 1, sink%events%count
            if (sink%events%kind(j) /= event_release) cycle
            phase = modulo(0.5_wp*sink%events%time(j), 2*pi)
            if (sink%events%site(j) == 1) then
                right = right + 1
                worst_right = max(worst_right, abs(phase - (pi - asin(0.5_wp))))
            else
                left = left + 1
                worst_left = max(worst_left, abs(phase - (2*pi - asin(0.5_wp))))
            end if
        end do
        call check(t, right > 0, 'a release from the right wall')
        call check_close(t, worst_right, 0.0_wp, 'right-wall release at pi - asin(a/A)', 1.0e-12_wp)
        call check_close(t, worst_left, 0.0_wp, 'left-wall release at -asin(a/A)', 1.0e-12_wp)
    end subroutine right_wall_release

    !> Two oscillators resting in a stack on the right wall: the top one (nearer the middle)
    !> leaves first; a release in the wrong order closes the bond between them to a negative
    !> gap (once -0.064 at the section).
    subroutine right_wall_stack_gap(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(memory_sink_t) :: sink
        type(record_result_t) :: res
        real(wp) :: worst, gaps(0:2)
        integer :: j

        call new_chain(chain, 0.1_wp, 0.5_wp, 2.0_wp, 0.6_wp, [0.5_wp, 0.5_wp, 0.5_wp], .true., &
                       [0.1_wp, -0.1_wp], [0.3_wp, -0.2_wp], err)
        call record_cycles(record_spec(0_i8, 40_i8, .false., 3.6_wp), chain, sink, res, err)
        call check(t, .not. allocated(err), 'right-wall stack run completes')
        if (allocated(err)) return
        worst = huge(1.0_wp)
        do j = 1, size(sink%x, 2)
            gaps = [0.5_wp + sink%x(1, j), 0.5_wp + sink%x(2, j) - sink%x(1, j), &
                    0.5_wp - sink%x(2, j)]
            worst = min(worst, minval(gaps))
        end do
        call check(t, res%sticks > 0 .and. res%releases > 0, 'the stack run rests and releases')
        call check(t, worst >= -1.0e-12_wp, 'right-wall stack: no negative gap at any strobe')
    end subroutine right_wall_stack_gap

    !> Free ends, no damping: the collisions die out into grazing contacts that recur every
    !> oscillation, some at approach speeds of 1e-7 .. 1e-14. Such a contact is a touch (no
    !> impulse, no jump of the tangent), and the exponents keep the sum rule:
    !> sum = 2 ln(K) c per cycle, c the impacts per cycle (touches are not impacts).
    subroutine touch_keeps_sum_rule(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(memory_sink_t) :: sink
        type(record_result_t) :: res
        real(wp) :: total, expected
        integer :: touches, slow

        call new_chain(chain, 0.0_wp, 0.95_wp, 0.9_wp, 0.7_wp, [(0.45_wp, touches=0, 7)], &
                       .false., &
                       [0.012045030998285716_wp, -0.012466053811766603_wp, &
                        -0.073066711416925584_wp, -0.027345680921520815_wp, &
                        0.02187162690852229_wp, -0.086102099427112111_wp, &
                        0.067433828030196805_wp], &
                       [0.63728915674849584_wp, -0.82025241158108742_wp, &
                        0.54435773315862745_wp, -0.56736870932367256_wp, &
                        0.35212304681746931_wp, -0.6209995412417999_wp, &
                        0.34491556076987984_wp], err)
        call record_cycles(record_spec(200_i8, 1000_i8, .true.), chain, sink, res, err)
        call check(t, .not. allocated(err), 'grazing free chain run completes')
        if (allocated(err)) return
        touches = count(sink%events%kind(:sink%events%count) == event_touch)
        slow = count(sink%events%kind(:sink%events%count) == event_impact .and. &
                     sink%events%speed(:sink%events%count) < 1.0e-8_wp)
        call check(t, touches > 0 .and. res%impacts > 0, 'grazing free chain: touches and impacts')
        call check(t, slow == 0, 'grazing free chain: no impact slower than 1e-8')
        total = sum(res%lyapunov%bits_per_cycle)*log(2.0_wp)
        expected = 2*log(0.95_wp)*res%collisions_per_cycle
        call check_close(t, total, expected, 'grazing free chain: sum rule per cycle', 1.0e-9_wp)
    end subroutine touch_keeps_sum_rule

    !> Three free particles, fast enough for the springs not to matter while they collide,
    !> K = 0.05 (below the inelastic-collapse threshold 7 - 4 sqrt(3)): a cascade of impacts of
    !> geometrically shrinking speed, whose slowest ones are touches. The one-cycle Jacobian
    !> from saltation matrices equals central differences of the map.
    subroutine cascade_jacobian(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        real(wp), allocatable :: jac(:, :)
        real(wp) :: fd(6, 6), fd_wide(6, 6), z(6), accuracy
        integer :: j

        call new_chain(chain, 0.05_wp, 0.05_wp, 0.0_wp, 1.3_wp, [1.0_wp, 1.0_wp, 1.0_wp, 1.0_wp], &
                       .false., [0.2501_wp, 0.0_wp, -0.25_wp], [1.5_wp, 0.0_wp, -1.5_wp], err)
        call poincare_jacobian(chain, 1, jac, err)
        call check(t, .not. allocated(err), 'cascade Jacobian')
        if (allocated(err)) return
        z(1::2) = chain_positions(chain)
        z(2::2) = chain_velocities(chain)
        do j = 1, 6
            fd(:, j) = central_difference(chain, z, j, 1.0e-6_wp)
            fd_wide(:, j) = central_difference(chain, z, j, 1.0e-5_wp)
        end do
        ! the differences at two steps agree to `accuracy`: the analytic Jacobian must too
        accuracy = maxval(abs(fd - fd_wide)) + 1.0e-8_wp
        call check(t, maxval(abs(jac - fd)) <= 10*accuracy, &
                   'cascade: Jacobian equals central differences (within their accuracy)')
        call check(t, accuracy < 1.0e-4_wp, 'cascade: the differences are accurate to 1e-4')
    end subroutine cascade_jacobian

    !> Column j of the central difference of the one-cycle map of `chain` at state z.
    function central_difference(chain, z, j, h) result(column)
        type(chain_t), intent(in) :: chain
        real(wp), intent(in) :: z(:), h
        integer, intent(in) :: j
        real(wp) :: column(size(z))

        column = (mapped(chain, z, j, h) - mapped(chain, z, j, -h))/(2*h)
    end function central_difference

    function mapped(chain, z, j, h) result(image)
        type(chain_t), intent(in) :: chain
        real(wp), intent(in) :: z(:), h
        integer, intent(in) :: j
        real(wp) :: image(size(z)), moved(size(z))
        type(chain_t) :: copy
        type(error_t), allocatable :: err
        type(event_log_t) :: events

        moved = z
        moved(j) = moved(j) + h
        call chain_init(copy, chain_model(chain), moving_state(moved(1::2), moved(2::2), &
                        chain_cycle(chain), chain_time(chain)), err)
        call event_log_init(events, .false., 0)
        call advance_to_point(copy, chain_cycle(chain) + 1, chain_time(chain), events, err)
        image(1::2) = chain_positions(copy)
        image(2::2) = chain_velocities(copy)
    end function mapped

    !> A period-1 orbit with one rest per period: oscillator 1 chatters into the near left
    !> wall (0.5 away) and rests there once per cycle; oscillator 2 (right wall 3 away) meets
    !> it twice per cycle. Known answers: the one-cycle Jacobian from a section during the
    !> rest has exactly the zero rows of the resting oscillator; its nonzero multipliers are
    !> the same from any section; the spectrum has two collapsed directions (-infinity) and
    !> two exponents whose sum is log2 of the product of the nonzero multipliers.
    subroutine rest_orbit(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: events
        type(memory_sink_t) :: sink
        type(record_result_t) :: res
        real(wp), allocatable :: jac(:, :)
        real(wp) :: re(4), im(4), product_at(2), section
        integer :: info, p, collapsed
        integer, allocatable :: contact(:)
        logical :: zero_rows

        do p = 1, 2
            ! w t = 0 (oscillator 1 moving) and w t = 5 (resting)
            section = merge(0.0_wp, 5.0_wp, p == 1)/0.4_wp
            call rest_chain(chain, err)
            call event_log_init(events, .false., 0)
            call advance_to_point(chain, 300_i8, section, events, err)
            call poincare_jacobian(chain, 1, jac, err)
            call check(t, .not. allocated(err), 'rest orbit: Jacobian')
            if (allocated(err)) return
            call floquet_multipliers(jac, re, im, info)
            product_at(p) = product(hypot(re, im), mask=hypot(re, im) > 1.0e-12_wp)
            if (p == 2) then
                zero_rows = all(jac(1:2, :) == 0)
                contact = chain_contacts(chain)
                call check(t, contact(1) /= contact_free .and. zero_rows, &
                           'rest orbit: the Jacobian from a section during the rest has the '// &
                           'zero rows of the resting oscillator')
            end if
            call check(t, count(hypot(re, im) > 1.0e-12_wp) == 2, &
                       'rest orbit: two nonzero multipliers')
        end do
        call check_close(t, product_at(2), product_at(1), &
                         'rest orbit: nonzero multipliers the same from either section', &
                         rel_tol=1.0e-9_wp)
        call rest_chain(chain, err)
        call record_cycles(record_spec(300_i8, 1000_i8, .true.), chain, sink, res, err)
        call check(t, .not. allocated(err), 'rest orbit: spectrum')
        if (allocated(err)) return
        collapsed = count(.not. ieee_is_finite(res%lyapunov%bits_per_cycle))
        call check(t, collapsed == 2 .and. all(res%lyapunov%bits_per_cycle(3:4) < 0), &
                   'rest orbit: two collapsed directions, reported last as -infinity')
        call check_close(t, sum(res%lyapunov%bits_per_cycle(1:2)), log(product_at(1))/log(2.0_wp), &
                         'rest orbit: finite exponents sum to log2 |product of multipliers|', &
                         rel_tol=1.0e-9_wp)
    end subroutine rest_orbit

    subroutine rest_chain(chain, err)
        type(chain_t), intent(out) :: chain
        type(error_t), allocatable, intent(out) :: err

        call new_chain(chain, 0.1_wp, 0.5_wp, 1.0_wp, 0.4_wp, [0.5_wp, 0.5_wp, 3.0_wp], .true., &
                       [0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp], err)
    end subroutine rest_chain

end module test_corners
