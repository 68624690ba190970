!> Lyapunov spectra by QR re-orthonormalisation of a tangent frame (docs/model.md section 7) and
!> the Kaplan-Yorke dimension. (Floquet multipliers: chain_floquet.)
!>
!> The frame itself is carried by the engine (exact propagators between impacts, saltation
!> matrices at impacts); this module only turns frames into numbers. Block averages of the
!> per-step growth rates give the standard error of each exponent.
!>
!> The running estimates (the exponents after each QR step, for convergence plots) are kept
!> in a buffer of at most `running_capacity` rows, whatever the length of the run: every
!> `stride`-th step, the stride a power of two that doubles (dropping every other kept row)
!> when the buffer is full. The result adds the last step, so its last row is the final
!> estimate.
module chain_lyapunov
    use chain_kinds, only: wp, i8
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_negative_inf, ieee_is_finite
    use chain_lapack, only: qr_orthonormalise, qr_workspace_t, general_eigenvalues
    implicit none
    private
    public :: lyapunov_acc_t, lyapunov_start, lyapunov_step, lyapunov_result_t
    public :: lyapunov_result, ky_dimension, initial_frame
    public :: running_capacity, running_rows, lyapunov_pack, lyapunov_unpack

    integer, parameter :: max_blocks = 20
    !> A frame column whose QR diagonal is below this fraction of its own length, after an
    !> event with a singular tangent map, lies in the span of the columns before it: a
    !> direction the event removed (its true growth is zero), not a contraction. A genuine one
    !> would need to shrink by 1e-11 relative to the others within one QR interval.
    real(wp), parameter :: collapse_tolerance = 1.0e-11_wp
    !> Most running estimates kept (even: a full buffer halves), 4096 x k x 8 bytes.
    integer, parameter :: running_capacity = 4096
    !> Layout of lyapunov_pack's arrays; change it when the accumulator changes.
    integer(i8), parameter :: pack_layout = 2

    type :: lyapunov_acc_t
        integer :: k = 0              !! number of exponents
        integer :: collapsed = 0      !! directions removed by rests or collapses (-infinity)
        integer, allocatable :: active(:) !! exponent index of each remaining frame column
        integer :: steps = 0          !! QR steps done
        integer :: planned = 0        !! QR steps planned (sets the blocks)
        real(wp), allocatable :: total(:)        !! total(k): sum of ln|R(j,j)|
        real(wp), allocatable :: block_sum(:, :) !! block_sum(k, n_blocks)
        integer, allocatable :: block_len(:)     !! steps in each block
        integer :: stride = 1         !! steps between kept running estimates (a power of 2)
        integer :: rows = 0           !! running estimates kept: steps stride, 2 stride, ...
        real(wp), allocatable :: running(:, :)   !! running(k, <= running_capacity): total /
                                                 !! steps at steps stride, 2 stride, ...
        real(wp), allocatable :: frame(:, :)     !! the frame untransposed, for the QR
        real(wp), allocatable :: r_diag(:), growth(:) !! one QR step's
        type(qr_workspace_t) :: qr
    end type lyapunov_acc_t

    type :: lyapunov_result_t
        real(wp), allocatable :: bits_per_cycle(:)  !! descending
        real(wp), allocatable :: nats_per_time(:)
        real(wp), allocatable :: stderr_bits(:)     !! standard error from block means
        real(wp), allocatable :: running_bits(:, :) !! running(k, rows), bits per cycle
        integer, allocatable :: running_steps(:)    !! the QR step of each row
        real(wp) :: ky_dimension = 0
        real(wp) :: positive_sum = 0                !! bits per cycle
    end type lyapunov_result_t

contains

    pure subroutine lyapunov_start(acc, k, planned_steps)
        type(lyapunov_acc_t), intent(out) :: acc
        integer, intent(in) :: k, planned_steps
        integer :: n_blocks, j

        acc%k = k
        acc%planned = planned_steps
        n_blocks = max(1, min(max_blocks, planned_steps))
        allocate (acc%total(k), acc%block_sum(k, n_blocks), acc%block_len(n_blocks))
        allocate (acc%running(k, max(0, min(planned_steps, running_capacity))))
        allocate (acc%r_diag(k), acc%growth(k))
        acc%active = [(j, j=1, k)]
        acc%total = 0
        acc%block_sum = 0
        acc%block_len = 0
    end subroutine lyapunov_start

    !> The accumulator as two plain arrays (to save a stopped run and continue it bit for bit),
    !> and `lyapunov_unpack` back: these two are the one place that lists its components, so a
    !> new component is added here and nowhere else. The workspaces are not saved.
    pure subroutine lyapunov_pack(acc, ints, reals)
        type(lyapunov_acc_t), intent(in) :: acc
        integer(i8), allocatable, intent(out) :: ints(:)
        real(wp), allocatable, intent(out) :: reals(:)

        ints = [pack_layout, int(acc%k, i8), int(acc%steps, i8), int(acc%planned, i8), &
                int(acc%stride, i8), int(acc%rows, i8), int(acc%collapsed, i8), &
                int(acc%block_len, i8), int(acc%active, i8)]
        reals = [acc%total, reshape(acc%block_sum, [size(acc%block_sum)]), &
                 reshape(acc%running(:, :acc%rows), [acc%k*acc%rows])]
    end subroutine lyapunov_pack

    !> The accumulator from lyapunov_pack's arrays; info = 1 if they are not such arrays (of
    !> this layout, consistent sizes), 0 otherwise.
    pure subroutine lyapunov_unpack(ints, reals, acc, info)
        integer(i8), intent(in) :: ints(:)
        real(wp), intent(in) :: reals(:)
        type(lyapunov_acc_t), intent(out) :: acc
        integer, intent(out) :: info
        integer :: k, nb, rows, p

        info = 1
        if (size(ints) < 7) return
        if (ints(1) /= pack_layout .or. ints(2) < 1 .or. any(ints(3:4) < 0) .or. &
            ints(5) < 1 .or. ints(6) < 0 .or. ints(7) < 0 .or. ints(7) > ints(2) .or. &
            any(ints(2:7) > huge(1))) return
        k = int(ints(2))
        call lyapunov_start(acc, k, int(ints(4)))
        nb = size(acc%block_len)
        rows = int(ints(6))
        acc%collapsed = int(ints(7))
        if (size(ints) /= 7 + nb + k - acc%collapsed .or. rows > size(acc%running, 2)) return
        if (size(reals) /= k*(1 + nb + rows)) return
        if (any(ints(8 + nb:) < 1 .or. ints(8 + nb:) > k)) return
        acc%steps = int(ints(3))
        acc%stride = int(ints(5))
        acc%rows = rows
        acc%block_len = int(ints(8:7 + nb))
        acc%active = int(ints(8 + nb:))
        acc%total = reals(1:k)
        p = k
        acc%block_sum = reshape(reals(p + 1:p + k*nb), [k, nb])
        p = p + k*nb
        acc%running(:, :rows) = reshape(reals(p + 1:p + k*rows), [k, rows])
        info = 0
    end subroutine lyapunov_unpack

    !> Re-orthonormalise the frame (stored transposed, frame_t(k, m)) and accumulate. Column j
    !> may be the true one times 2**(-scale_bits) exp(-log_scale(j)).
    !> After an event with a singular tangent map (`singular`: a rest began, a cluster
    !> collapsed, or K = 0) a column that now lies in the span of the columns before it is a
    !> direction that event removed: its exponent is -infinity, and the column leaves the
    !> frame (frame_t loses that row), so that the other exponents never take the logarithm of
    !> a diagonal that is only rounding.
    subroutine lyapunov_step(acc, frame_t, info, scale_bits, log_scale, singular)
        type(lyapunov_acc_t), intent(inout) :: acc
        real(wp), allocatable, intent(inout) :: frame_t(:, :)
        integer, intent(out) :: info
        integer, intent(in), optional :: scale_bits !! the frame was scaled by 2**(-scale_bits)
        !> ln of the factor each column was scaled down by besides (the engine's
        !> re-orthonormalisations after large jumps)
        real(wp), intent(in), optional :: log_scale(:)
        logical, intent(in), optional :: singular
        real(wp), allocatable :: before(:, :), scale(:)
        real(wp) :: minus_infinity
        logical, allocatable :: gone(:)
        integer :: b, n_blocks, j, kept

        info = 0
        minus_infinity = ieee_value(1.0_wp, ieee_negative_inf)
        if (present(log_scale)) scale = log_scale
        acc%frame = transpose(frame_t)
        if (present(singular)) then
            if (singular) before = acc%frame
        end if
        do
            kept = size(acc%frame, 2)
            if (kept == 0) exit
            call qr_orthonormalise(acc%frame, acc%r_diag(:kept), acc%qr, info)
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
            acc%frame = before
            if (size(acc%active) == 0) exit
        end do
        frame_t = transpose(acc%frame)
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
        acc%total = acc%total + acc%growth
        n_blocks = size(acc%block_len)
        b = min(n_blocks, 1 + (acc%steps - 1)*n_blocks/max(1, acc%planned))
        acc%block_sum(:, b) = acc%block_sum(:, b) + acc%growth
        acc%block_len(b) = acc%block_len(b) + 1
        if (modulo(acc%steps, acc%stride) == 0) call keep_running(acc)
    end subroutine lyapunov_step

    !> Keep the running estimate of this step (a multiple of the stride); when the buffer is
    !> full, keep every other row and double the stride first.
    pure subroutine keep_running(acc)
        type(lyapunov_acc_t), intent(inout) :: acc
        integer :: half

        if (size(acc%running, 2) == 0) return
        if (acc%rows == size(acc%running, 2)) then
            half = acc%rows/2
            acc%running(:, 1:half) = acc%running(:, 2:2*half:2)
            acc%rows = half
            acc%stride = 2*acc%stride
            if (modulo(acc%steps, acc%stride) /= 0) return
        end if
        acc%rows = acc%rows + 1
        acc%running(:, acc%rows) = acc%total/acc%steps
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
    !> descending, with standard errors and the running estimates.
    pure function lyapunov_result(acc, cycles_per_step, period) result(res)
        type(lyapunov_acc_t), intent(in) :: acc
        integer, intent(in) :: cycles_per_step
        real(wp), intent(in) :: period
        type(lyapunov_result_t) :: res
        real(wp) :: nats(acc%k), err(acc%k), mean(acc%k), to_bits
        integer :: order(acc%k), j, b, nb, used

        to_bits = 1/(log(2.0_wp)*cycles_per_step)
        nats = acc%total/max(1, acc%steps)
        err = 0
        nb = count(acc%block_len > 0)
        if (nb > 1) then
            mean = 0
            do b = 1, nb
                mean = mean + acc%block_sum(:, b)/acc%block_len(b)
            end do
            mean = mean/nb
            ! no error bar for an exponent of -infinity (a run with rests on the walls)
            where (.not. ieee_is_finite(mean)) mean = 0
            do b = 1, nb
                where (ieee_is_finite(acc%block_sum(:, b))) &
                    err = err + (acc%block_sum(:, b)/acc%block_len(b) - mean)**2
            end do
            err = sqrt(err/(nb - 1)/nb)
            where (.not. ieee_is_finite(acc%total)) err = 0
        end if
        order = descending_order(nats)
        res%bits_per_cycle = nats(order)*to_bits
        res%nats_per_time = nats(order)/(cycles_per_step*period)
        res%stderr_bits = err(order)*to_bits
        ! the kept rows, and the last step (the final estimate) if it is not one of them
        used = acc%rows
        if (acc%steps > acc%rows*acc%stride) used = used + 1
        allocate (res%running_bits(acc%k, used), res%running_steps(used))
        do j = 1, acc%rows
            res%running_bits(:, j) = acc%running(order, j)*to_bits
            res%running_steps(j) = j*acc%stride
        end do
        if (used > acc%rows) then
            res%running_bits(:, used) = nats(order)*to_bits
            res%running_steps(used) = acc%steps
        end if
        res%ky_dimension = ky_dimension(res%bits_per_cycle)
        res%positive_sum = sum(res%bits_per_cycle, mask=res%bits_per_cycle > 0)
    end function lyapunov_result

    !> A generic orthonormal frame of k vectors in dimension m. Unit vectors would be a poor
    !> start: a chain that splits into independent pieces (a bond that never closes) keeps
    !> them inside one piece. Entry (i, j) depends on i and j only, so the first k vectors
    !> are the same whatever k: a frame of k vectors gives exactly the leading k exponents
    !> of the full spectrum.
    subroutine initial_frame(m, k, frame, info)
        integer, intent(in) :: m, k
        real(wp), allocatable, intent(out) :: frame(:, :)
        integer, intent(out) :: info
        real(wp) :: r_diag(k), h
        type(qr_workspace_t) :: ws
        integer :: i, j

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
