!> Covariant Lyapunov vectors (docs/model.md section 14) against what cannot be tuned: on a
!> stable periodic orbit with real multipliers of distinct moduli they are the eigenvectors of
!> the Poincare-map Jacobian; on a chaotic run each is covariant (the one-cycle Jacobian at a
!> record maps it onto the direction of the next record's) and grows at the rate of the QR
!> exponent of the same run; without impacts every one decays at -b T; the leading k of a
!> frame of k are the first k of the full set; and the kernels (the product of R factors, the
!> scratch files read backwards, the angle to the unstable span) by brute force.
module test_clv
    use chain_kinds, only: wp, i8
    use, intrinsic :: ieee_arithmetic, only: ieee_is_nan
    use chain_error, only: error_t
    use chain_flow, only: flow_t, make_flow
    use chain_model, only: model_t
    use chain_engine, only: chain_t, chain_model, chain_positions, chain_velocities, &
                            chain_set_tangent, chain_qr_step, chain_tangent_frame, chain_cycle
    use chain_lyapunov, only: lyapunov_acc_t, lyapunov_start, initial_frame
    use chain_record, only: record_cycles, memory_sink_t, record_result_t, record_spec_t
    use chain_section, only: chain_at_section, advance_to_point
    use chain_event_log, only: event_log_t, event_log_init
    use chain_floquet, only: poincare_jacobian
    use chain_orbit, only: orbit_t, find_orbit
    use chain_lapack, only: general_eigenvectors, qr_orthonormalise, qr_workspace_t, qr_last_r, &
                            solve_upper_triangle
    use chain_clv, only: fold_upper, initial_c, unstable_angle, site_weights, vector_numbers
    use chain_scratch, only: scratch_records_t, scratch_open, scratch_append, scratch_read, &
                             scratch_close, scratch_block
    use test_chains, only: make_chain
    use test_chains, only: model_of, flow_of
    use chain_blocking, only: blocking_t, blocking_start, blocking_add, blocking_error
    use chain_monitor, only: monitor_t, stage_backward
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_clv_tests

    !> Angles between vectors that must be parallel (the issue's bound).
    real(wp), parameter :: angle_tol = 1.0e-8_wp

    !> Notes what the backward pass tells it; with `stop_there`, asks it to stop.
    type, extends(monitor_t) :: backward_monitor_t
        logical :: stop_there = .false.
        integer :: calls = 0
        integer(i8) :: last_done = 0, last_total = 0
        logical :: rising = .true.
    contains
        procedure :: keep_going => backward_keep_going
    end type backward_monitor_t

contains

    subroutine run_clv_tests(t)
        type(tally_t), intent(inout) :: t

        call periodic_orbit(t)
        call chaotic_run(t)
        call no_impacts(t)
        call leading_vectors(t)
        call backward_progress(t)
        call interval_factor(t)
        call folded_factors(t)
        call scratch_round_trip(t)
        call angle_by_projection(t)
        call numbers_by_vector(t, 7)
        call numbers_by_vector(t, 8)
        call triangle_solve(t, 7)
        call triangle_solve(t, 100)
        call blocking_plateau(t, 0.0_wp)
        call blocking_plateau(t, 0.9_wp)
    end subroutine run_clv_tests

    !> A run of `cycles` records with k covariant vectors (0: all 2n).
    function clv_spec(transient, cycles, k, clv_transient, clv_save) result(spec)
        integer(i8), intent(in) :: transient, cycles
        integer, intent(in) :: k, clv_transient, clv_save
        type(record_spec_t) :: spec

        spec%transient = transient
        spec%cycles = cycles
        spec%record_events = .false.
        spec%lyapunov = .true.
        spec%vectors = k
        spec%covariant = .true.
        spec%clv_transient = clv_transient
        spec%clv_store = 2
        spec%clv_save = clv_save
    end function clv_spec

    !> The angle between the lines of a and b, accurate when small.
    pure real(wp) function line_angle(a, b)
        real(wp), intent(in) :: a(:), b(:)
        real(wp) :: u(size(a)), w(size(b))

        u = a/norm2(a)
        w = b/norm2(b)
        line_angle = atan2(norm2(u - dot_product(u, w)*w), abs(dot_product(u, w)))
    end function line_angle

    !> A chain of three oscillators with unequal spacings (no mirror symmetry, which would
    !> double every multiplier) has a stable period-1 orbit whose six multipliers are real, of
    !> distinct moduli (-0.775, 0.288, -0.214, -0.170, ...: consecutive ratios <= 0.8). A run
    !> sitting on it has for covariant vectors the eigenvectors of its Poincare-map Jacobian, in
    !> the order of the multipliers' moduli, and their growth rates are log2 |mu| bits per cycle.
    subroutine periodic_orbit(t)
        type(tally_t), intent(inout) :: t
        type(model_t) :: model
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(event_log_t) :: events
        type(orbit_t) :: orbit
        type(memory_sink_t) :: sink
        type(record_result_t) :: res
        real(wp), allocatable :: a(:, :), vr(:, :), wr(:), wi(:)
        real(wp) :: worst, zeros(3)
        integer :: order(6), i, j, s, info

        model = model_of(make_flow(0.05_wp, 1.25_wp, 0.9_wp), 0.5_wp, &
                         [1.0_wp, 0.8_wp, 1.15_wp, 0.95_wp], .true., 1.0e-9_wp)
        zeros = 0
        call chain_at_section(model, 0.0_wp, zeros, zeros, chain, err)
        call event_log_init(events, .false., 0)
        if (.not. allocated(err)) call advance_to_point(chain, 300_i8, 0.0_wp, events, err)
        if (.not. allocated(err)) call find_orbit(model, 0.0_wp, 1, chain_positions(chain), &
                                                  chain_velocities(chain), orbit, err)
        call check(t, .not. allocated(err) .and. orbit%converged .and. orbit%impacts > 0, &
                   'clv orbit: a period-1 orbit with impacts is found')
        if (.not. orbit%converged) return
        allocate (a(6, 6), vr(6, 6), wr(6), wi(6))
        a = orbit%jacobian
        call general_eigenvectors(a, wr, wi, vr, info)
        order = by_modulus(wr)
        call check(t, info == 0 .and. all(wi == 0) .and. abs(wr(order(1))) < 1 .and. &
                   all(abs(wr(order(2:))) < 0.8_wp*abs(wr(order(:5)))), &
                   'clv orbit: stable, six real multipliers of distinct moduli')
        ! on the orbit: the frame aligns over the transient, vectors at the last 5 records
        call chain_at_section(model, 0.0_wp, orbit%x, orbit%v, chain, err)
        sink%keep_strobe = .false.
        if (.not. allocated(err)) call record_cycles(clv_spec(200_i8, 400_i8, 0, 150, 5), chain, &
                                                     sink, res, err)
        call check(t, .not. allocated(err) .and. res%has_clv, 'clv orbit: the run has vectors')
        if (.not. res%has_clv) return
        worst = 0
        do s = 1, 5
            do i = 1, 6
                worst = max(worst, line_angle(res%clv%vectors(:, i, s), vr(:, order(i))))
            end do
        end do
        call check(t, worst <= angle_tol, 'clv orbit: every vector is the eigenvector of '// &
                   'its multiplier (angle <= 1e-8)')
        do i = 1, 6
            call check_close(t, res%clv%exponents(i), log(abs(wr(order(i))))/log(2.0_wp), &
                             'clv orbit: growth rate of vector '//digit(i)//' is log2 |mu|', &
                             1.0e-10_wp)
        end do
        call check(t, all(ieee_is_nan(sink%clv_min_angle)), &
                   'clv orbit: no unstable vector, no angle')
        do j = 1, size(sink%clv_ipr, 2)
            if (any(abs(sink%clv_ipr(:, j) - sink%clv_ipr(:, 1)) > 1.0e-8_wp)) exit
        end do
        call check(t, j > size(sink%clv_ipr, 2), 'clv orbit: the same participation at '// &
                   'every record')
    end subroutine periodic_orbit

    !> Indices sorting `values` by descending modulus.
    pure function by_modulus(values) result(order)
        real(wp), intent(in) :: values(:)
        integer :: order(size(values)), i, j, swap

        order = [(i, i=1, size(values))]
        do i = 1, size(values)
            do j = i + 1, size(values)
                if (abs(values(order(j))) > abs(values(order(i)))) then
                    swap = order(i)
                    order(i) = order(j)
                    order(j) = swap
                end if
            end do
        end do
    end function by_modulus

    pure function digit(i) result(text)
        integer, intent(in) :: i
        character(len=:), allocatable :: text
        character(len=12) :: buffer

        write (buffer, '(i0)') i
        text = trim(buffer)
    end function digit

    !> A chaotic chain (n = 4, A = 4.15, w = 1.5, K = 0.85, 0.5 bits per cycle): the vectors'
    !> growth rates equal the QR exponents of the same run within their standard errors; the
    !> one-cycle Jacobian at a record maps each vector onto the direction of the next record's
    !> (angle <= 1e-8); the unstable span and the others keep a positive angle.
    !> (That angle cannot be smaller than the rounding of the plain-product Jacobian applied
    !> to the vector, about eps times the spread of the vectors' growths over the cycle: on
    !> chains whose exponents span 10 bits per cycle it reaches 1e-7 at the slowest impacts,
    !> docs/model.md section 14.4; this chain's span 4 bits per cycle.)
    subroutine chaotic_run(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(memory_sink_t) :: sink
        type(record_result_t) :: res
        type(model_t) :: model
        type(chain_t) :: at_record
        real(wp), allocatable :: jacobian(:, :)
        real(wp) :: worst, gap, band
        integer(i8) :: first
        integer :: s, i, r, k
        integer, parameter :: saved = 20

        call make_chain(chain, 4, 4.15_wp, 1.5_wp, 0.05_wp, 0.85_wp, .true., 0.3_wp, 0.5_wp, err)
        model = chain_model(chain)
        call record_cycles(clv_spec(200_i8, 2200_i8, 0, 200, saved), chain, sink, res, err)
        call check(t, .not. allocated(err) .and. res%has_clv .and. res%sticks == 0, &
                   'clv chaotic: the run has vectors and no rests')
        if (.not. res%has_clv) return
        k = size(res%clv%exponents)
        call check(t, res%lyapunov%bits_per_cycle(1) > 0 .and. res%clv%unstable >= 1, &
                   'clv chaotic: the run is chaotic')
        worst = 0
        do i = 1, k
            gap = abs(res%clv%exponents(i) - res%lyapunov%bits_per_cycle(i))
            band = hypot(res%clv%stderr(i), res%lyapunov%stderr_bits(i))
            worst = max(worst, gap/band)
        end do
        call check(t, worst <= 1, 'clv chaotic: every growth rate within one standard error '// &
                   'of its QR exponent')
        ! the states of the saved records: records kept - saved + 1 .. kept
        first = res%clv%kept - saved + 1
        call check(t, all(sink%cycle(first:first + saved - 1) == res%clv%saved_cycle), &
                   'clv chaotic: saved vectors at the last records with vectors')
        worst = 0
        do s = 1, saved - 1
            call chain_at_section(model, 0.0_wp, sink%x(:, first + s - 1), &
                                  sink%v(:, first + s - 1), at_record, err)
            if (.not. allocated(err)) call poincare_jacobian(at_record, 1, jacobian, err)
            if (allocated(err)) exit
            do r = 1, k
                worst = max(worst, line_angle(matmul(jacobian, res%clv%vectors(:, r, s)), &
                                              res%clv%vectors(:, r, s + 1)))
            end do
        end do
        call check(t, .not. allocated(err) .and. worst <= angle_tol, 'clv chaotic: the '// &
                   'one-cycle Jacobian maps every vector onto the next record''s (angle <= 1e-8)')
        call check(t, all(sink%clv_min_angle > 0) .and. all(sink%clv_min_angle <= 2*atan(1.0_wp)), &
                   'clv chaotic: angles to the unstable span in (0, pi/2]')
        call check(t, all(sink%clv_ipr >= 0.25_wp - 1.0e-12_wp .and. sink%clv_ipr <= 1), &
                   'clv chaotic: participation ratios in [1/n, 1]')
        call check(t, all(abs(sum(sink%clv_site_weight, 1) - 1) < 1.0e-12_wp), &
                   'clv chaotic: site weights sum to 1')
    end subroutine chaotic_run

    !> Without impacts every direction decays at -b T per cycle: so does every vector.
    subroutine no_impacts(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(memory_sink_t) :: sink
        type(record_result_t) :: res
        type(flow_t) :: flow
        real(wp) :: bt

        call make_chain(chain, 3, 0.2_wp, 1.5_wp, 0.05_wp, 0.7_wp, .true., 0.2_wp, 0.1_wp, err)
        sink%keep_strobe = .false.
        call record_cycles(clv_spec(0_i8, 2200_i8, 0, 200, 1), chain, sink, res, err)
        call check(t, .not. allocated(err) .and. res%impacts == 0 .and. res%has_clv, &
                   'clv no impacts: the run has vectors and no impacts')
        if (.not. res%has_clv) return
        flow = flow_of(chain)
        bt = flow%damping*flow%period
        call check(t, maxval(abs(res%clv%exponents*log(2.0_wp) + bt)) < 1.0e-4_wp, &
                   'clv no impacts: every growth rate within 1e-4 of -b T after 2000 cycles')
    end subroutine no_impacts

    !> The k = 3 leading vectors of a frame of 3 are the first three of the full set (the
    !> leading blocks of the triangular factors are the factors of the leading columns).
    subroutine leading_vectors(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain
        type(error_t), allocatable :: err
        type(memory_sink_t) :: full_sink, sink
        type(record_result_t) :: full, res
        real(wp) :: worst
        integer :: i

        call make_chain(chain, 4, 4.15_wp, 0.9_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, 0.5_wp, err)
        call record_cycles(clv_spec(200_i8, 700_i8, 0, 200, 1), chain, full_sink, full, err)
        call make_chain(chain, 4, 4.15_wp, 0.9_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, 0.5_wp, err)
        call record_cycles(clv_spec(200_i8, 700_i8, 3, 200, 1), chain, sink, res, err)
        call check(t, .not. allocated(err) .and. full%has_clv .and. res%has_clv, &
                   'clv leading: both runs have vectors')
        if (.not. res%has_clv) return
        worst = 0
        do i = 1, 3
            worst = max(worst, line_angle(full%clv%vectors(:, i, 1), res%clv%vectors(:, i, 1)))
        end do
        call check(t, worst <= angle_tol, 'clv leading: the 3 leading vectors are the first '// &
                   '3 of all 8 (angle <= 1e-8)')
        call check(t, maxval(abs(full%clv%exponents(:3) - res%clv%exponents)) < 1.0e-10_wp, &
                   'clv leading: and grow alike')
        call check(t, maxval(abs(full_sink%clv_ipr(:3, :) - sink%clv_ipr)) < 1.0e-8_wp, &
                   'clv leading: and have the same participation at every record')
    end subroutine leading_vectors

    !> The backward pass tells a monitor the records it has done, up to all of them; asked to
    !> stop, it ends with an error and no vectors.
    subroutine backward_progress(t)
        type(tally_t), intent(inout) :: t
        type(chain_t) :: chain, copy
        type(error_t), allocatable :: err
        type(memory_sink_t) :: sink
        type(record_result_t) :: res
        type(backward_monitor_t) :: watch

        call make_chain(chain, 3, 0.2_wp, 1.5_wp, 0.05_wp, 0.7_wp, .true., 0.2_wp, 0.1_wp, err)
        copy = chain
        sink%keep_strobe = .false.
        call record_cycles(clv_spec(0_i8, 600_i8, 0, 100, 1), chain, sink, res, err, watch)
        call check(t, .not. allocated(err) .and. res%has_clv .and. watch%calls >= 1 .and. &
                   watch%rising .and. watch%last_done == 500 .and. watch%last_total == 500, &
                   'clv backward pass: the monitor is told its records, up to all 500')
        watch = backward_monitor_t(stop_there=.true.)
        call record_cycles(clv_spec(0_i8, 600_i8, 0, 100, 1), copy, sink, res, err, watch)
        call check(t, allocated(err) .and. .not. res%has_clv, &
                   'clv backward pass: a stop asked there is an error, without vectors')
        if (allocated(err)) call check(t, index(err%message, 'backward pass') > 0, &
                                       'clv backward pass: the error says where it stopped')
    end subroutine backward_progress

    logical function backward_keep_going(monitor, stage, done, total) result(keep_going)
        class(backward_monitor_t), intent(inout) :: monitor
        integer, intent(in) :: stage
        integer(i8), intent(in) :: done, total

        keep_going = .true.
        if (stage /= stage_backward) return
        monitor%calls = monitor%calls + 1
        monitor%rising = monitor%rising .and. done > monitor%last_done .and. done <= total
        monitor%last_done = done
        monitor%last_total = total
        keep_going = .not. monitor%stop_there
    end function backward_keep_going

    !> The R factor of a QR step over several cycles of a chain with many inelastic impacts
    !> (n = 16, K = 0.7: the engine re-orthonormalises the frame in between, 7.2) satisfies
    !> Q' R = J Q with J the plain product of the exact tangent maps (the Poincare-map
    !> Jacobian of those cycles), column by column to rounding; the step's own R alone does
    !> not, so the engine's factors are in it.
    subroutine interval_factor(t)
        type(tally_t), intent(inout) :: t
        integer, parameter :: k = 6, cycles = 4
        type(chain_t) :: chain, copy
        type(error_t), allocatable :: err
        type(event_log_t) :: events
        type(lyapunov_acc_t) :: acc
        real(wp), allocatable :: frame(:, :), jacobian(:, :), q(:, :), want(:, :)
        real(wp) :: r_factor(k, k), r_log(k), folded, alone
        integer :: info, j

        call make_chain(chain, 16, 1.7_wp, 1.5_wp, 0.05_wp, 0.7_wp, .true., 0.3_wp, 0.5_wp, err)
        call event_log_init(events, .false., 0)
        if (.not. allocated(err)) call advance_to_point(chain, 100_i8, 0.0_wp, events, err)
        call initial_frame(32, k, frame, info)
        copy = chain
        if (.not. allocated(err)) call poincare_jacobian(copy, cycles, jacobian, err)
        call chain_set_tangent(chain, frame, orthonormalise_jumps=.true., keep_r_factors=.true.)
        if (.not. allocated(err)) call advance_to_point(chain, chain_cycle(chain) + cycles, &
                                                        0.0_wp, events, err)
        call lyapunov_start(acc, k, int(cycles, i8), cycles)
        if (.not. allocated(err)) call chain_qr_step(chain, acc, cycles, err, r_factor, r_log)
        call check(t, .not. allocated(err), 'clv factor: the run')
        if (allocated(err)) return
        q = chain_tangent_frame(chain)
        want = matmul(jacobian, frame)
        folded = 0
        alone = 0
        do j = 1, k
            folded = max(folded, norm2(matmul(q, r_factor(:, j))*exp(r_log(j)) - want(:, j))/ &
                                 norm2(want(:, j)))
        end do
        r_factor = qr_last_r(acc%qr, k)
        do j = 1, k
            alone = max(alone, norm2(matmul(q, r_factor(:, j)) - want(:, j))/norm2(want(:, j)))
        end do
        call check(t, folded <= 1.0e-10_wp, 'clv factor: Q'' R = J Q for every column')
        call check(t, alone > 1.0e-3_wp, 'clv factor: not without the engine''s factors')
    end subroutine interval_factor

    !> fold_upper keeps the product R P exactly as P's unit columns times exp(p_log).
    subroutine folded_factors(t)
        type(tally_t), intent(inout) :: t
        integer, parameter :: k = 7
        real(wp) :: r(k, k), p(k, k), p_log(k), want(k, k), got(k, k)
        integer :: i, j

        r = 0
        p = 0
        do j = 1, k
            do i = 1, j
                r(i, j) = sin(3.1_wp*i + 1.7_wp*j)
                p(i, j) = cos(2.3_wp*i - 0.9_wp*j)
            end do
            r(j, j) = r(j, j) + 2*sign(1.0_wp, r(j, j))
            p_log(j) = 0.3_wp*j
        end do
        want = matmul(r, p*spread(exp(p_log), 1, k))
        ! (the lower triangle of r is never read)
        r(k, 1) = huge(1.0_wp)
        call fold_upper(r, p, p_log)
        got = p*spread(exp(p_log), 1, k)
        call check(t, maxval(abs(got - want)) <= 100*epsilon(1.0_wp)*maxval(abs(want)), &
                   'clv fold: R P as unit columns and their logarithms')
        call check(t, maxval(abs(norm2(p, 1) - 1)) <= 10*epsilon(1.0_wp), &
                   'clv fold: unit columns')
    end subroutine folded_factors

    !> Records spilled over several blocks come back bit for bit, read backwards and at random
    !> (the last block from the buffer, until another is read); records that fit in the
    !> buffer never reach the file.
    subroutine scratch_round_trip(t)
        type(tally_t), intent(inout) :: t
        type(scratch_records_t) :: file
        type(error_t), allocatable :: err
        integer, parameter :: width = 20000
        real(wp), allocatable :: values(:)
        integer(i8) :: j, records, bytes
        integer :: i
        logical :: same

        records = 3*scratch_block(width) + 2
        call check(t, scratch_block(width) > 1 .and. scratch_block(width) < records, &
                   'clv scratch: the test spans several blocks')
        allocate (values(width))
        call scratch_open(file, width, err)
        do j = 1, records
            if (allocated(err)) exit
            values = [(real(j, wp)*1.0e6_wp + i, i=1, width)]
            call scratch_append(file, values, err)
        end do
        same = .not. allocated(err)
        do j = records, 1, -1
            if (.not. same) exit
            call scratch_read(file, j, values, err)
            same = .not. allocated(err) .and. &
                   all(values == [(real(j, wp)*1.0e6_wp + i, i=1, width)])
        end do
        call check(t, same, 'clv scratch: records read backwards are those written')
        do i = 1, 20
            if (.not. same) exit
            j = 1 + modulo(7_i8*i*i + 3, records)
            call scratch_read(file, j, values, err)
            same = .not. allocated(err) .and. values(width) == real(j, wp)*1.0e6_wp + width
        end do
        call check(t, same, 'clv scratch: and in any order')
        call scratch_append(file, values, err)
        call check(t, allocated(err), 'clv scratch: no append after reading')
        call scratch_close(file)
        records = scratch_block(width)
        call scratch_open(file, width, err)
        do j = 1, records
            if (allocated(err)) exit
            values = [(real(j, wp)*1.0e6_wp + i, i=1, width)]
            call scratch_append(file, values, err)
        end do
        same = .not. allocated(err)
        do j = records, 1, -1
            if (.not. same) exit
            call scratch_read(file, j, values, err)
            same = .not. allocated(err) .and. values(1) == real(j, wp)*1.0e6_wp + 1
        end do
        inquire (unit=file%unit, size=bytes)
        call check(t, same .and. bytes == 0, 'clv scratch: one block read back from the '// &
                   'buffer, never written')
        call scratch_close(file)
    end subroutine scratch_round_trip

    !> The angle from C alone equals the angle between V = Q C's vectors and the span of its
    !> first u, found by projecting on an orthonormal basis of that span.
    subroutine angle_by_projection(t)
        type(tally_t), intent(inout) :: t
        integer, parameter :: m = 9, k = 6, u = 2
        type(qr_workspace_t) :: ws
        real(wp) :: q(m, k), basis(m, u), v(m, k), r_diag(k), want, proj(m)
        real(wp), allocatable :: c(:, :)
        integer :: i, j, s, info

        do j = 1, k
            do i = 1, m
                q(i, j) = sin(1.3_wp*i*j + 0.4_wp*i)
            end do
        end do
        call qr_orthonormalise(q, r_diag, ws, info)
        c = initial_c(k)
        v = matmul(q, c)
        basis = v(:, :u)
        call qr_orthonormalise(basis, r_diag(:u), ws, info)
        want = huge(1.0_wp)
        do s = u + 1, k
            proj = matmul(basis, matmul(transpose(basis), v(:, s)))
            want = min(want, atan2(norm2(v(:, s) - proj), norm2(proj)))
        end do
        call check_close(t, unstable_angle(c, u), want, 'clv angle: from C as by projection', &
                         1.0e-13_wp)
        call check(t, ieee_is_nan(unstable_angle(c, 0)) .and. ieee_is_nan(unstable_angle(c, k)), &
                   'clv angle: none without an unstable or a stable vector')
        call check_close(t, sum(site_weights(v(:, 1))), 1.0_wp, 'clv weights sum to 1', &
                         10*epsilon(1.0_wp))
    end subroutine angle_by_projection

    !> The numbers of k vectors at once (columns summed four at a time) are those of one vector
    !> at a time, bit for bit: each normalised, its site weights and their sum of squares.
    subroutine numbers_by_vector(t, k)
        type(tally_t), intent(inout) :: t
        integer, intent(in) :: k
        integer, parameter :: n = 5, m = 3
        real(wp) :: v(2*n, k), u(2*n), w(n), ipr(k), weight(n, m)
        logical :: same
        integer :: i, l

        do l = 1, k
            do i = 1, 2*n
                v(i, l) = sin(0.9_wp*i*l + 0.3_wp*l)*exp(0.1_wp*i)
            end do
        end do
        u = v(:, k)
        call vector_numbers(v, ipr, weight)
        same = all(v(:, k) == u/sqrt(sum(u**2)))
        do l = 1, k
            w = site_weights(v(:, l))
            same = same .and. ipr(l) == sum(w**2)
            if (l <= m) same = same .and. all(weight(:, l) == w)
        end do
        call check(t, same, 'clv numbers: of '//digit(k)//' vectors at once as of each alone')
    end subroutine numbers_by_vector

    !> X = R^-1 C for upper triangular R and C (k = 7: plain loops; 100: the library, by blocks
    !> of columns) is upper triangular and solves R X = C to rounding.
    subroutine triangle_solve(t, k)
        type(tally_t), intent(inout) :: t
        integer, intent(in) :: k
        real(wp) :: r(k, k), c(k, k), x(k, k), residual
        integer :: i, j

        r = 0
        c = 0
        do j = 1, k
            do i = 1, j
                r(i, j) = cos(1.7_wp*i + 0.6_wp*j)
                c(i, j) = sin(0.8_wp*i - 1.3_wp*j)
            end do
            r(j, j) = r(j, j) + 2*sign(1.0_wp, r(j, j))
        end do
        x = c
        call solve_upper_triangle(r, x)
        residual = 0
        do j = 1, k
            residual = max(residual, norm2(matmul(r, x(:, j)) - c(:, j))/norm2(c(:, j)))
        end do
        call check(t, residual <= 100*epsilon(1.0_wp) .and. &
                   all([(all(x(j + 1:, j) == 0), j=1, k)]), &
                   'clv solve: upper triangular X with R X = C, k = '//digit(k))
    end subroutine triangle_solve

    !> The standard error by blocking of the mean of an AR(1) series x(i) = phi x(i-1) + e(i)
    !> (unit Gaussian innovations, 2**16 values) is that of its closed form,
    !> 1 / ((1 - phi) sqrt(N)) for large N, to 15 % (the estimate's scatter, and for phi = 0.9
    !> the bias of blocks not much longer than the correlation time: 10 % here); for phi = 0
    !> (white noise) it is read off at blocks of at most 4 values, and for phi = 0.9
    !> (correlation time (1 + phi) / (1 - phi) = 19 values) at blocks of at least 16.
    !> Memory: one level per power of two of the length.
    subroutine blocking_plateau(t, phi)
        type(tally_t), intent(inout) :: t
        real(wp), intent(in) :: phi
        integer(i8), parameter :: values = 2_i8**16
        type(blocking_t) :: b
        real(wp) :: x(1), err(1), u1, u2, want
        integer(i8) :: i, block(1), state
        character(len=8) :: label

        write (label, '(f3.1)') phi
        call blocking_start(b, 1, values)
        state = 12345
        x = 0
        do i = 1, values
            u1 = next_uniform(state)
            u2 = next_uniform(state)
            ! (a large constant mean: the sums must not cancel it)
            x = phi*x + sqrt(-2*log(u1))*cos(8*atan(1.0_wp)*u2)
            call blocking_add(b, x + 1000)
        end do
        call blocking_error(b, err, block)
        want = 1/((1 - phi)*sqrt(real(values, wp)))
        call check_close(t, err(1), want, 'clv blocking: AR(1) phi = '//trim(label)// &
                         ', the standard error of the mean', rel_tol=0.15_wp)
        if (phi == 0) then
            call check(t, block(1) <= 4, 'clv blocking: white noise needs no blocks')
        else
            call check(t, block(1) >= 16, 'clv blocking: AR(1) phi = '//trim(label)// &
                       ', blocks longer than its correlation time')
        end if
        call check(t, size(b%count) == 17, 'clv blocking: one level per power of two')
    contains
        real(wp) function next_uniform(s)
            integer(i8), intent(inout) :: s

            s = modulo(48271_i8*s, 2147483647_i8)
            next_uniform = real(s, wp)/2147483647.0_wp
        end function next_uniform
    end subroutine blocking_plateau

end module test_clv
