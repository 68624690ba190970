!> Lyapunov spectra by QR re-orthonormalisation of a tangent frame (docs/model.md section 7) and
!> the Kaplan-Yorke dimension. (Floquet multipliers: chain_floquet.)
!>
!> The frame itself is carried by the engine (exact propagators between impacts, saltation
!> matrices at impacts); this module only turns frames into numbers. The standard error of
!> each exponent comes from blocking its growth per cycle (chain_blocking), read where it
!> levels off with the block size; finite-time exponents, over windows of a chosen number of
!> cycles, come out one window at a time (docs/model.md sections 7.4 and 7.10).
!>
!> QR steps come every `qr_every` cycles, or, with qr_every = 0, at an adaptive interval: the
!> frame is re-orthonormalised before the growths of its columns since the last step are
!> predicted (from the growth rates of the last step and of the whole run) to span more than
!> `condition_bound`. Every average is weighted by cycles, not by steps.
!>
!> The running estimates (the exponents after each QR step, for convergence plots) are kept
!> in a buffer of at most `running_capacity` rows, whatever the length of the run: every
!> `stride`-th step, the stride a power of two that doubles (dropping every other kept row)
!> when the buffer is full. The result adds the last step, so its last row is the final
!> estimate.
module chain_lyapunov
    use chain_kinds, only: wp, i8
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_negative_inf, ieee_is_finite
    use chain_lapack, only: qr_orthonormalise, qr_orthonormalise_blocks, qr_workspace_t, &
                            general_eigenvalues
    use chain_blocking, only: blocking_t, blocking_start, blocking_add, blocking_error, &
                              blocking_pack, blocking_unpack
    implicit none
    private
    public :: lyapunov_acc_t, lyapunov_start, lyapunov_step, lyapunov_result_t
    public :: lyapunov_result, ky_dimension, initial_frame, lyapunov_due, adaptive_interval
    public :: longest_interval, lyapunov_unit
    public :: running_capacity, running_rows, lyapunov_pack, lyapunov_unpack

    !> The standard error's blocking starts from units of cycles, at least this many per run.
    integer, parameter :: min_units = 40
    !> A frame column whose QR diagonal is below this fraction of its own length, after an
    !> event with a singular tangent map, lies in the span of the columns before it: a
    !> direction the event removed (its true growth is zero), not a contraction. A genuine one
    !> would need to shrink by 1e-11 relative to the others within one QR interval.
    real(wp), parameter :: collapse_tolerance = 1.0e-11_wp
    !> Most running estimates kept (even: a full buffer halves), 4096 x k x 8 bytes.
    integer, parameter :: running_capacity = 4096
    !> Layout of lyapunov_pack's arrays; change it when the accumulator changes.
    integer(i8), parameter :: pack_layout = 4
    !> Adaptive QR steps keep the frame's condition (the spread of its columns' growths since
    !> it was orthonormal) below this: the smallest columns then keep about 16 - log10(bound)
    !> significant digits, and QR steps spaced by it give the exponents of a step every cycle
    !> to 1e-10 bits per cycle (test_lyapunov's adaptive_matches_every_cycle).
    real(wp), parameter :: condition_bound = 1.0e8_wp
    !> ... and never wait more than this many cycles (nor more than a unit of the standard
    !> error's blocking, lyapunov_unit).
    integer, parameter :: longest_interval = 64

    type :: lyapunov_acc_t
        integer :: k = 0              !! number of exponents
        integer :: collapsed = 0      !! directions removed by rests or collapses (-infinity)
        integer, allocatable :: active(:) !! exponent index of each remaining frame column
        integer :: steps = 0          !! QR steps done
        integer(i8) :: cycles = 0     !! drive cycles the steps cover
        integer(i8) :: planned = 0    !! drive cycles planned (sets the units)
        integer :: qr_every = 1       !! cycles per step, 0: adaptive
        integer :: interval = 1       !! cycles from the last step to the next
        integer :: longest = 1        !! longest adaptive interval
        real(wp), allocatable :: total(:)        !! total(k): sum of ln|R(j,j)|
        integer :: unit = 1           !! cycles per value of the standard error's blocking
        real(wp), allocatable :: unit_sum(:)     !! unit_sum(k): growth in the current unit
        type(blocking_t) :: blocks    !! each unit's growth per cycle, blocked
        integer :: window = 0         !! cycles per finite-time exponent, 0: none
        integer(i8) :: windows = 0    !! windows completed
        real(wp), allocatable :: window_sum(:)   !! window_sum(k): growth in the current window
        real(wp), allocatable :: window_last(:)  !! the last complete window's growth per
                                                 !! cycle (nats), by exponent index
        integer :: stride = 1         !! steps between kept running estimates (a power of 2)
        integer :: rows = 0           !! running estimates kept: steps stride, 2 stride, ...
        real(wp), allocatable :: running(:, :)   !! running(k, <= running_capacity): total /
                                                 !! cycles at steps stride, 2 stride, ...
        integer(i8), allocatable :: running_cycles(:) !! the cycles each row covers
        real(wp), allocatable :: r_diag(:), growth(:) !! one QR step's
        type(qr_workspace_t) :: qr
    end type lyapunov_acc_t

    type :: lyapunov_result_t
        real(wp), allocatable :: bits_per_cycle(:)  !! descending
        real(wp), allocatable :: nats_per_time(:)
        real(wp), allocatable :: stderr_bits(:)     !! standard error (blocking plateau)
        integer(i8), allocatable :: stderr_cycles(:) !! cycles per block at the plateau
        real(wp), allocatable :: running_bits(:, :) !! running(k, rows), bits per cycle
        integer(i8), allocatable :: running_cycles(:) !! cycles averaged at each row
        real(wp) :: ky_dimension = 0
        real(wp) :: positive_sum = 0                !! bits per cycle
    end type lyapunov_result_t

contains

    !> An empty accumulator of k exponents for a run of `cycles` drive cycles with a QR step
    !> every `qr_every` cycles (default 1; 0: adaptive), and finite-time exponents over
    !> windows of `window` cycles (default 0: none; with qr_every > 1 a multiple of it).
    pure subroutine lyapunov_start(acc, k, cycles, qr_every, window)
        type(lyapunov_acc_t), intent(out) :: acc
        integer, intent(in) :: k
        integer(i8), intent(in) :: cycles
        integer, intent(in), optional :: qr_every, window
        integer(i8) :: most_steps
        integer :: j

        acc%k = k
        if (present(qr_every)) acc%qr_every = qr_every
        if (present(window)) acc%window = window
        acc%interval = max(1, acc%qr_every)
        acc%planned = (cycles/acc%interval)*acc%interval
        most_steps = acc%planned/acc%interval
        acc%unit = lyapunov_unit(acc%planned, acc%qr_every)
        acc%longest = acc%unit
        call blocking_start(acc%blocks, k, max(1_i8, acc%planned/acc%unit))
        allocate (acc%total(k), acc%unit_sum(k), acc%window_sum(k), acc%window_last(k))
        allocate (acc%running(k, max(0_i8, min(most_steps, int(running_capacity, i8)))))
        allocate (acc%running_cycles(size(acc%running, 2)))
        allocate (acc%r_diag(k), acc%growth(k))
        acc%active = [(j, j=1, k)]
        acc%total = 0
        acc%unit_sum = 0
        acc%window_sum = 0
        acc%window_last = 0
    end subroutine lyapunov_start

    !> Cycles per value of the standard error's blocking in a run of `planned` cycles with
    !> QR steps every `qr_every` cycles (0: adaptive): qr_every itself when above 1 (each step
    !> one value); otherwise the largest power of two within min(longest_interval, planned /
    !> min_units), so that a step every cycle and adaptive steps (which never cross a unit)
    !> give the same units, and units and their doublings stay whole powers of two.
    pure integer function lyapunov_unit(planned, qr_every) result(unit)
        integer(i8), intent(in) :: planned
        integer, intent(in) :: qr_every
        integer(i8) :: most

        if (qr_every > 1) then
            unit = qr_every
            return
        end if
        most = max(1_i8, min(int(longest_interval, i8), planned/min_units))
        unit = 1
        do while (2*unit <= most)
            unit = 2*unit
        end do
    end function lyapunov_unit

    !> The accumulator as two plain arrays (to save a stopped run and continue it bit for bit),
    !> and `lyapunov_unpack` back: these two are the one place that lists its components, so a
    !> new component is added here and nowhere else. The workspaces are not saved.
    pure subroutine lyapunov_pack(acc, ints, reals)
        type(lyapunov_acc_t), intent(in) :: acc
        integer(i8), allocatable, intent(out) :: ints(:)
        real(wp), allocatable, intent(out) :: reals(:)

        ints = [pack_layout, int(acc%k, i8), int(acc%steps, i8), acc%planned, &
                int(acc%stride, i8), int(acc%rows, i8), int(acc%collapsed, i8), &
                acc%cycles, int(acc%qr_every, i8), int(acc%interval, i8), &
                int(acc%window, i8), acc%windows]
        reals = [acc%total, acc%unit_sum, acc%window_sum, acc%window_last]
        call blocking_pack(acc%blocks, ints, reals)
        ints = [ints, acc%running_cycles(:acc%rows), int(acc%active, i8)]
        reals = [reals, reshape(acc%running(:, :acc%rows), [acc%k*acc%rows])]
    end subroutine lyapunov_pack

    !> The accumulator from lyapunov_pack's arrays; info = 1 if they are not such arrays (of
    !> this layout, consistent sizes), 0 otherwise.
    pure subroutine lyapunov_unpack(ints, reals, acc, info)
        integer(i8), intent(in) :: ints(:)
        real(wp), intent(in) :: reals(:)
        type(lyapunov_acc_t), intent(out) :: acc
        integer, intent(out) :: info
        integer, parameter :: head = 12
        integer :: k, rows, ip, rp, status

        info = 1
        if (size(ints) < head) return
        if (ints(1) /= pack_layout .or. ints(2) < 1 .or. any(ints(3:4) < 0) .or. &
            ints(5) < 1 .or. ints(6) < 0 .or. ints(7) < 0 .or. ints(7) > ints(2) .or. &
            ints(8) < 0 .or. ints(9) < 0 .or. ints(10) < 1 .or. any(ints(11:12) < 0) .or. &
            any(ints([2, 3, 5, 6, 7, 9, 10, 11]) > huge(1))) return
        k = int(ints(2))
        call lyapunov_start(acc, k, ints(4), int(ints(9)), int(ints(11)))
        if (acc%planned /= ints(4)) return
        rows = int(ints(6))
        acc%collapsed = int(ints(7))
        if (size(reals) < 4*k) return
        ! (the windows done fit the cycles done; adaptive steps wait at most a unit)
        if (acc%window > 0) then
            if (ints(12) > ints(8)/acc%window) return
            if (acc%qr_every > 1 .and. modulo(acc%window, max(1, acc%qr_every)) /= 0) return
        else if (ints(12) /= 0) then
            return
        end if
        if (acc%qr_every == 0 .and. ints(10) > acc%longest) return
        ip = head
        rp = 4*k
        call blocking_unpack(ints, reals, ip, rp, acc%blocks, status)
        if (status /= 0) return
        if (size(ints) /= ip + rows + k - acc%collapsed .or. &
            rows > size(acc%running, 2)) return
        if (size(reals) /= rp + k*rows) return
        if (any(ints(ip + rows + 1:) < 1 .or. ints(ip + rows + 1:) > k)) return
        acc%steps = int(ints(3))
        acc%stride = int(ints(5))
        acc%rows = rows
        acc%cycles = ints(8)
        acc%interval = int(ints(10))
        acc%windows = ints(12)
        acc%total = reals(1:k)
        acc%unit_sum = reals(k + 1:2*k)
        acc%window_sum = reals(2*k + 1:3*k)
        acc%window_last = reals(3*k + 1:4*k)
        acc%running_cycles(:rows) = ints(ip + 1:ip + rows)
        acc%active = int(ints(ip + rows + 1:))
        acc%running(:, :rows) = reshape(reals(rp + 1:rp + k*rows), [k, rows])
        info = 0
    end subroutine lyapunov_unpack

    !> Re-orthonormalise the frame (frame(m, k), its columns the vectors) and accumulate the
    !> growth of an interval of `cycles` drive cycles (default 1). Column j may be the true one
    !> times 2**(-scale_bits) exp(-log_scale(j)).
    !> After an event with a singular tangent map (`singular`: a rest began, a cluster
    !> collapsed, or K = 0) a column that now lies in the span of the columns before it is a
    !> direction that event removed: its exponent is -infinity, and the column leaves the
    !> frame, so that the other exponents never take the logarithm of a diagonal that is only
    !> rounding. With adaptive steps, the interval to the next step is set here. A step that
    !> ends a window of finite-time exponents counts it in acc%windows, its exponents in
    !> acc%window_last.
    subroutine lyapunov_step(acc, frame, info, scale_bits, log_scale, singular, cycles, joined)
        type(lyapunov_acc_t), intent(inout) :: acc
        real(wp), allocatable, intent(inout) :: frame(:, :)
        integer, intent(out) :: info
        integer, intent(in), optional :: scale_bits !! the frame was scaled by 2**(-scale_bits)
        !> ln of the factor each column was scaled down by besides (the engine's
        !> re-orthonormalisations after large jumps)
        real(wp), intent(in), optional :: log_scale(:)
        logical, intent(in), optional :: singular
        integer, intent(in), optional :: cycles
        !> a square frame's joined bonds, its pieces (chain_lapack's qr_orthonormalise_blocks)
        logical, intent(in), optional :: joined(:)
        real(wp), allocatable :: before(:, :), scale(:)
        real(wp) :: minus_infinity
        logical, allocatable :: gone(:)
        integer :: j, kept, span

        info = 0
        span = 1
        if (present(cycles)) span = cycles
        minus_infinity = ieee_value(1.0_wp, ieee_negative_inf)
        if (present(log_scale)) scale = log_scale
        if (present(singular)) then
            if (singular) before = frame
        end if
        do
            kept = size(frame, 2)
            if (kept == 0) exit
            if (present(joined) .and. kept == size(frame, 1)) then
                call qr_orthonormalise_blocks(frame, joined, acc%r_diag(:kept), acc%qr, info)
            else
                call qr_orthonormalise(frame, acc%r_diag(:kept), acc%qr, info)
            end if
            if (info /= 0) return
            if (.not. allocated(before)) exit
            gone = [(abs(acc%r_diag(j)) <= collapse_tolerance*norm2(before(:, j)), j=1, kept)]
            if (.not. any(gone)) exit
            ! drop the removed directions and factorise the others afresh
            acc%total(pack(acc%active, gone)) = minus_infinity
            if (allocated(scale)) scale = pack(scale, .not. gone)
            acc%collapsed = acc%collapsed + count(gone)
            acc%active = pack(acc%active, .not. gone)
            before = before(:, pack([(j, j=1, kept)], .not. gone))
            frame = before
            if (size(acc%active) == 0) exit
        end do
        ! a rest that zeroes every row leaves exact zeros: that growth is -infinity too, set
        ! without a floating-point exception (log(0) traps under -ffpe-trap=zero)
        acc%growth = minus_infinity
        do j = 1, size(acc%active)
            if (acc%r_diag(j) /= 0) then
                acc%growth(acc%active(j)) = log(abs(acc%r_diag(j)))
                if (present(scale_bits)) acc%growth(acc%active(j)) = &
                    acc%growth(acc%active(j)) + scale_bits*log(2.0_wp)
                if (allocated(scale)) acc%growth(acc%active(j)) = &
                    acc%growth(acc%active(j)) + scale(j)
            end if
        end do
        acc%steps = acc%steps + 1
        acc%cycles = acc%cycles + span
        acc%total = acc%total + acc%growth
        ! (a collapsed direction has no error bar: its growth counts as 0 there)
        where (ieee_is_finite(acc%growth)) acc%unit_sum = acc%unit_sum + acc%growth
        if (modulo(acc%cycles, int(acc%unit, i8)) == 0) then
            call blocking_add(acc%blocks, acc%unit_sum/acc%unit)
            acc%unit_sum = 0
        end if
        if (acc%window > 0) then
            acc%window_sum = acc%window_sum + acc%growth
            if (modulo(acc%cycles, int(acc%window, i8)) == 0) then
                acc%windows = acc%windows + 1
                acc%window_last = acc%window_sum/acc%window
                acc%window_sum = 0
            end if
        end if
        if (modulo(acc%steps, acc%stride) == 0) call keep_running(acc)
        if (acc%qr_every == 0) then
            ! a step never crosses into the next unit or window: each then holds the same
            ! cycles as with a step every cycle, and its growth is theirs (the R factors
            ! telescope)
            acc%interval = min(adaptive_interval(acc%growth/span, acc%longest), &
                               adaptive_interval(acc%total/acc%cycles, acc%longest), &
                               cycles_to_boundary(acc%cycles, acc%unit))
            if (acc%window > 0) acc%interval = min(acc%interval, &
                                                   cycles_to_boundary(acc%cycles, acc%window))
        end if
    end subroutine lyapunov_step

    !> Cycles from `cycles` to the next multiple of `every` (every, when on one).
    pure integer function cycles_to_boundary(cycles, every) result(left)
        integer(i8), intent(in) :: cycles
        integer, intent(in) :: every

        left = every - int(modulo(cycles, int(every, i8)))
    end function cycles_to_boundary

    !> Cycles until the spread of growths of columns growing at `rates` (ln per cycle; values
    !> that are not finite, collapsed directions, are left out) reaches condition_bound:
    !> at least 1, at most `longest`.
    pure integer function adaptive_interval(rates, longest) result(interval)
        real(wp), intent(in) :: rates(:)
        integer, intent(in) :: longest
        real(wp) :: spread

        interval = longest
        if (count(ieee_is_finite(rates)) < 2) return
        spread = maxval(rates, mask=ieee_is_finite(rates)) - &
                 minval(rates, mask=ieee_is_finite(rates))
        if (spread*longest > log(condition_bound)) &
            interval = max(1, int(log(condition_bound)/spread))
    end function adaptive_interval

    !> Is a QR step due after `done` recorded cycles? Every qr_every cycles, or once the
    !> adaptive interval has passed; with adaptive steps also at the last record (`last`),
    !> so that every cycle is averaged.
    pure logical function lyapunov_due(acc, done, last)
        type(lyapunov_acc_t), intent(in) :: acc
        integer(i8), intent(in) :: done
        logical, intent(in) :: last

        lyapunov_due = done - acc%cycles >= acc%interval .or. (acc%qr_every == 0 .and. last)
    end function lyapunov_due

    !> Keep the running estimate of this step (a multiple of the stride); when the buffer is
    !> full, keep every other row and double the stride first.
    pure subroutine keep_running(acc)
        type(lyapunov_acc_t), intent(inout) :: acc
        integer :: half

        if (size(acc%running, 2) == 0) return
        if (acc%rows == size(acc%running, 2)) then
            half = acc%rows/2
            acc%running(:, 1:half) = acc%running(:, 2:2*half:2)
            acc%running_cycles(1:half) = acc%running_cycles(2:2*half:2)
            acc%rows = half
            acc%stride = 2*acc%stride
            if (modulo(acc%steps, acc%stride) /= 0) return
        end if
        acc%rows = acc%rows + 1
        acc%running(:, acc%rows) = acc%total/acc%cycles
        acc%running_cycles(acc%rows) = acc%cycles
    end subroutine keep_running

    !> Rows of running estimates in the result of a run of `steps` QR steps: the multiples of
    !> the final stride (the least power of two d with steps / d <= running_capacity), and the
    !> last step when it is not one of them.
    pure integer function running_rows(steps)
        integer(i8), intent(in) :: steps
        integer(i8) :: d

        d = 1
        do while (steps/d > running_capacity)
            d = 2*d
        end do
        running_rows = int(steps/d) + merge(0, 1, modulo(steps, d) == 0)
    end function running_rows

    !> Exponents in the paper's units (bits per drive cycle) and per unit time, sorted
    !> descending, with standard errors (and the cycles per block they were read at) and the
    !> running estimates; every mean is over cycles.
    pure function lyapunov_result(acc, period) result(res)
        type(lyapunov_acc_t), intent(in) :: acc
        real(wp), intent(in) :: period
        type(lyapunov_result_t) :: res
        real(wp) :: nats(acc%k), err(acc%k), to_bits
        integer(i8) :: block(acc%k)
        integer :: order(acc%k), j, used

        to_bits = 1/log(2.0_wp)
        nats = acc%total/max(1_i8, acc%cycles)
        call blocking_error(acc%blocks, err, block)
        ! no error bar for an exponent of -infinity (a run with rests on the walls)
        where (.not. ieee_is_finite(acc%total))
            err = 0
            block = 1
        end where
        order = descending_order(nats)
        res%bits_per_cycle = nats(order)*to_bits
        res%nats_per_time = nats(order)/period
        res%stderr_bits = err(order)*to_bits
        res%stderr_cycles = block(order)*acc%unit
        ! the kept rows, and the last step (the final estimate) if it is not one of them
        used = acc%rows
        if (acc%steps > acc%rows*acc%stride) used = used + 1
        allocate (res%running_bits(acc%k, used), res%running_cycles(used))
        do j = 1, acc%rows
            res%running_bits(:, j) = acc%running(order, j)*to_bits
            res%running_cycles(j) = acc%running_cycles(j)
        end do
        if (used > acc%rows) then
            res%running_bits(:, used) = nats(order)*to_bits
            res%running_cycles(used) = acc%cycles
        end if
        res%ky_dimension = ky_dimension(res%bits_per_cycle)
        res%positive_sum = sum(res%bits_per_cycle, mask=res%bits_per_cycle > 0)
    end function lyapunov_result

    !> A generic orthonormal frame of k vectors in dimension m. Unit vectors would be a poor
    !> start: a chain that splits into independent pieces (a bond that never closes) keeps
    !> them inside one piece. Entry (i, j) depends on i and j only, so the first k vectors
    !> are the same whatever k: a frame of k vectors gives exactly the leading k exponents
    !> of the full spectrum. With `unit` and k = m, the unit vectors instead: the full
    !> spectrum's frame, whose blocks its QR steps exploit (docs/model.md section 7.1).
    subroutine initial_frame(m, k, frame, info, unit)
        integer, intent(in) :: m, k
        real(wp), allocatable, intent(out) :: frame(:, :)
        integer, intent(out) :: info
        logical, intent(in), optional :: unit
        real(wp) :: r_diag(k), h
        type(qr_workspace_t) :: ws
        integer :: i, j

        if (present(unit)) then
            if (unit .and. k == m) then
                allocate (frame(m, m), source=0.0_wp)
                do j = 1, m
                    frame(j, j) = 1
                end do
                info = 0
                return
            end if
        end if
        allocate (frame(m, k))
        do j = 1, k
            do i = 1, m
                h = sin(12.9898_wp*i + 78.233_wp*j)*43758.5453_wp
                frame(i, j) = h - floor(h) - 0.5_wp
            end do
        end do
        call qr_orthonormalise(frame, r_diag, ws, info)
    end subroutine initial_frame

    !> Kaplan-Yorke dimension of a spectrum sorted descending: j + S(j)/|l(j+1)| with j the
    !> largest index whose partial sum S(j) >= 0 (0 if l(1) < 0; k if every partial sum >= 0).
    pure function ky_dimension(exponents) result(dim)
        real(wp), intent(in) :: exponents(:)
        real(wp) :: dim, partial
        integer :: j

        partial = 0
        dim = 0
        do j = 1, size(exponents)
            if (partial + exponents(j) < 0) then
                dim = (j - 1) + partial/abs(exponents(j))
                return
            end if
            partial = partial + exponents(j)
        end do
        dim = size(exponents)
    end function ky_dimension

    !> Indices that sort `values` descending (insertion sort: spectra are short).
    pure function descending_order(values) result(order)
        real(wp), intent(in) :: values(:)
        integer :: order(size(values)), i, j, t

        order = [(i, i=1, size(values))]
        do i = 2, size(values)
            t = order(i)
            j = i - 1
            do while (j >= 1)
                if (values(order(j)) >= values(t)) exit
                order(j + 1) = order(j)
                j = j - 1
            end do
            order(j + 1) = t
        end do
    end function descending_order

end module chain_lyapunov
