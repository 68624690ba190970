!> The tangent frame the engine carries (docs/model.md sections 4.7 and 7): its start, the
!> jumps of its rows at impacts (saltation matrices), rows moved between the coordinates of the
!> epoch and of now, the frame kept finite, its re-orthonormalisation after large jumps, while
!> it aligns, and at every QR step of a Lyapunov spectrum, and the frame as a Jacobian.
!>
!> The frame is stored as its columns, tangent(2n, n_vectors), the layout LAPACK factorises:
!> a QR step works on it in place, with no transposed copies (a jump touches a few rows of
!> every column instead, which costs little next to a factorisation). Rows of moving
!> oscillators are referred back to the epoch, like their free parts; rows hit at the current
!> instant are kept in the coordinates of now until the instant ends.
submodule(chain_engine) chain_engine_tangent
    use chain_error, only: set_error, fmt_int
    use chain_lapack, only: qr_orthonormalise, qr_orthonormalise_blocks, qr_orthonormalise_piece, &
                            qr_last_r, qr_copy_r
    use chain_lyapunov, only: lyapunov_step
    use chain_clv, only: fold_upper
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_negative_inf
    use chain_state, only: contact_free
    implicit none

    !> A saltation matrix with an entry above this re-orthonormalises a Lyapunov frame at once.
    real(wp), parameter :: large_jump = 64
    !> ... and so does a run of jumps that shrank the frame's volume by more than e**(-18)
    !> (a piece's alone, when the frame knows its pieces: the others are untouched).
    real(wp), parameter :: small_volume = -18
    !> ... and so does a frame entry above this (the frame was orthonormal: entries <= 1).
    real(wp), parameter :: large_growth = 1024

contains

    !> With `orthonormalise_jumps`, re-orthonormalised after every large jump (Lyapunov
    !> spectra).
    module procedure chain_set_tangent
        integer :: i

        chain%orthonormalise_jumps = .false.
        if (present(orthonormalise_jumps)) chain%orthonormalise_jumps = orthonormalise_jumps
        chain%keep_r_factors = .false.
        if (present(keep_r_factors)) chain%keep_r_factors = keep_r_factors
        if (allocated(chain%r_product)) deallocate (chain%r_product, chain%r_product_log)
        if (chain%keep_r_factors) then
            allocate (chain%r_product(size(frame, 2), size(frame, 2)), &
                      chain%r_product_log(size(frame, 2)))
            call reset_r_product(chain)
        end if
        chain%tangent_log = [(0.0_wp, i=1, size(frame, 2))]
        chain%jumps_volume = [(0.0_wp, i=1, size(frame, 2))]
        chain%n_vectors = 0
        call chain_sync(chain)
        chain%n_vectors = size(frame, 2)
        chain%rank_losses = 0
        chain%n_touched = 0
        chain%row_stamp = -1
        chain%tangent = frame
        call find_joined(chain)
        call forget_resting_rows(chain)
    end procedure chain_set_tangent

    !> For a square frame without kept R factors, the bonds its pattern crosses (none for unit
    !> vectors, all for a generic frame; a frame restored from a saved run gets the pieces its
    !> run had, to exact zeros). Cut i, between oscillators i and i + 1, is crossed iff a
    !> column left of it (<= 2i) has a nonzero row below it (> 2i) or a column right of it one
    !> above it: a running maximum of the columns' last nonzero rows from the left, a running
    !> minimum of their first from the right, O(n^2) in all.
    pure subroutine find_joined(chain)
        type(chain_t), intent(inout) :: chain
        integer :: first_row(2*chain%n), last_row(2*chain%n)
        integer :: n, i, j, reach, low(2*chain%n + 1)

        if (allocated(chain%joined)) deallocate (chain%joined)
        n = chain%n
        if (chain%n_vectors /= 2*n .or. chain%keep_r_factors) return
        allocate (chain%joined(n - 1))
        do j = 1, 2*n
            ! (a zero column crosses no cut)
            first_row(j) = findloc(chain%tangent(:, j) /= 0, .true., dim=1)
            if (first_row(j) == 0) first_row(j) = 2*n + 1
            last_row(j) = findloc(chain%tangent(:, j) /= 0, .true., dim=1, back=.true.)
        end do
        low(2*n + 1) = 2*n + 1
        do j = 2*n, 1, -1
            low(j) = min(low(j + 1), first_row(j))
        end do
        reach = 0
        do i = 1, n - 1
            reach = max(reach, last_row(2*i - 1), last_row(2*i))
            chain%joined(i) = reach > 2*i .or. low(2*i + 1) <= 2*i
        end do
    end subroutine find_joined

    !> Oscillators first..last joined by one jump (a pair impact, a cluster).
    pure subroutine join(chain, first, last)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: first, last

        if (allocated(chain%joined) .and. last > first) chain%joined(first:last - 1) = .true.
    end subroutine join

    !> The columns that can be nonzero in oscillator i's rows: its piece's, 2a - 1 .. 2b for
    !> the piece [a, b], when the frame knows its pieces; else all of them.
    pure subroutine piece_columns(chain, i, low, high)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: i
        integer, intent(out) :: low, high
        integer :: a, b

        if (.not. allocated(chain%joined)) then
            low = 1
            high = chain%n_vectors
            return
        end if
        a = i
        do while (a > 1)
            if (.not. chain%joined(a - 1)) exit
            a = a - 1
        end do
        b = i
        do while (b < chain%n)
            if (.not. chain%joined(b)) exit
            b = b + 1
        end do
        low = 2*a - 1
        high = 2*b
    end subroutine piece_columns

    !> Re-orthonormalise the frame (Q in place, the diagonal of R in r_diag): piece by piece
    !> when the frame knows its pieces, else the whole frame.
    subroutine factorise_frame(chain, r_diag, info, keep_singular)
        type(chain_t), intent(inout) :: chain
        real(wp), intent(out) :: r_diag(:)
        integer, intent(out) :: info
        logical, intent(in), optional :: keep_singular

        if (allocated(chain%joined)) then
            call qr_orthonormalise_blocks(chain%tangent, chain%joined, r_diag, chain%qr, info, &
                                          keep_singular)
        else
            call qr_orthonormalise(chain%tangent, r_diag, chain%qr, info, keep_singular)
        end if
    end subroutine factorise_frame

    module procedure chain_vectors
        chain_vectors = chain%n_vectors
    end procedure chain_vectors

    module procedure chain_tangent_frame
        frame = chain%tangent
        if (chain%tangent_scale_bits > 0) then
            where (frame /= 0 .and. exponent(frame) + chain%tangent_scale_bits < &
                   maxexponent(1.0_wp))
                frame = scale(frame, chain%tangent_scale_bits)
            elsewhere (frame /= 0)
                frame = sign(huge(1.0_wp), frame)
            end where
        end if
    end procedure chain_tangent_frame

    !> The growth the engine kept (power-of-two scaling, re-orthonormalisations after large
    !> jumps) is added, directions removed by singular jumps are dropped (chain_lyapunov's
    !> lyapunov_step), and the engine's bookkeeping starts afresh.
    !> The R of the interval is the step's own times the product of those of the
    !> re-orthonormalisations in between (and the power-of-two scaling): the frame was
    !> J Q P^-1 2**-bits = Q' R', so J Q = Q' (R' P 2**bits).
    module procedure chain_qr_step
        integer :: info, i, k

        k = size(chain%tangent, 2)
        call lyapunov_step(acc, chain%tangent, info, chain%tangent_scale_bits, &
                           chain%tangent_log, chain%rank_losses > 0, cycles, chain%joined)
        if (present(r_factor)) then
            r_factor = 0
            r_log = 0
            if (chain%keep_r_factors .and. info == 0 .and. size(chain%tangent, 2) == k) then
                r_log = chain%r_product_log + chain%tangent_scale_bits*log(2.0_wp)
                if (chain%r_folded) then
                    r_factor = chain%r_product
                    call fold_upper(qr_last_r(acc%qr, k), r_factor, r_log)
                else
                    ! (P = I: the step's own R, as it is)
                    call qr_copy_r(acc%qr, r_factor)
                end if
            end if
        end if
        ! (the step may have dropped collapsed directions: the frame is no longer square)
        chain%n_vectors = size(chain%tangent, 2)
        if (chain%n_vectors /= k .and. allocated(chain%joined)) deallocate (chain%joined)
        chain%tangent_log = [(0.0_wp, i=1, chain%n_vectors)]
        call restart_bookkeeping(chain)
        if (info /= 0) call set_error(err, "lyapunov: QR factorisation failed (LAPACK info "// &
                                      fmt_int(info)//")")
    end procedure chain_qr_step

    !> A frame that starts in generic directions meets the shears of slow impacts (|S| ~ 1/u)
    !> across all its columns, and the smallest diagonals of R lose digits; once it has turned
    !> towards the leading directions they meet mostly the first. Rows of resting oscillators
    !> stay zero. A change of columns needs no sync: the state is not touched.
    module procedure chain_reorthonormalise
        real(wp) :: r_diag(chain%n_vectors)
        integer :: info, j

        call factorise_frame(chain, r_diag, info)
        if (info /= 0) then
            call set_error(err, "lyapunov: QR factorisation failed while aligning the "// &
                           "frame (LAPACK info "//fmt_int(info)//")")
            return
        end if
        if (present(growth)) then
            growth = ieee_value(1.0_wp, ieee_negative_inf)
            do j = 1, chain%n_vectors
                if (r_diag(j) /= 0) growth(j) = log(abs(r_diag(j))) + chain%tangent_log(j) + &
                                                chain%tangent_scale_bits*log(2.0_wp)
            end do
        end if
        call forget_resting_rows(chain)
        chain%tangent_log = 0
        call restart_bookkeeping(chain)
    end procedure chain_reorthonormalise

    module procedure chain_rank_lost
        chain_rank_lost = chain%rank_losses > 0
    end procedure chain_rank_lost

    !> The frame has just been orthonormalised (and tangent_log cleared): no scaling, no
    !> singular jump since, no shrinking of its volume.
    pure subroutine restart_bookkeeping(chain)
        type(chain_t), intent(inout) :: chain
        integer :: j

        chain%tangent_scale_bits = 0
        chain%rank_losses = 0
        chain%jumps_volume = [(0.0_wp, j=1, chain%n_vectors)]
        ! (P = I still unless a re-orthonormalisation came since the last reset)
        if (chain%keep_r_factors .and. chain%r_folded) call reset_r_product(chain)
    end subroutine restart_bookkeeping

    !> No re-orthonormalisation since the frame was orthonormal: P = I.
    pure subroutine reset_r_product(chain)
        type(chain_t), intent(inout) :: chain
        integer :: j

        chain%r_product = 0
        do j = 1, size(chain%r_product, 2)
            chain%r_product(j, j) = 1
        end do
        chain%r_product_log = 0
        chain%r_folded = .false.
    end subroutine reset_r_product

    !> The first impact of an instant takes M^-1 S M on rows still in the coordinates of the
    !> epoch: one pass over them instead of three (to now, S, back when the instant ends), if
    !> S is moderate: forming M^-1 S M spreads rounding of size eps |S| into every entry,
    !> while S applied in the coordinates of now keeps it in the direction S amplifies (a slow
    !> impact before a rest has |S| ~ 1/u). Those, and any later impact of the same instant (a
    !> triple contact, a collapse cascade), move their rows to now.
    module procedure jump_rows
        real(wp), parameter :: moderate_jump = 16
        real(wp) :: in_epoch(4, 4), largest  ! (fixed size: automatic arrays are allocated)
        real(wp) :: s_max
        integer :: last, j, p, ns, low, high

        ns = size(s, 1)
        last = i + ns/2 - 1
        ! (joined first: the jump's rows are then nonzero only in the merged piece's columns)
        call join(chain, i, last)
        call piece_columns(chain, i, low, high)
        s_max = maxval(abs(s))
        if (chain%same_instant == 0 .and. s_max <= moderate_jump .and. &
            all(chain%row_stamp(i:last) /= chain%instant)) then
            if (ns == 2) then
                call apply_jump(chain, 2*i - 1, conjugated(s, chain%m, chain%m_inv), low, high, &
                                largest)
            else
                do p = 1, ns, 2
                    do j = 1, ns, 2
                        in_epoch(j:j + 1, p:p + 1) = conjugated(s(j:j + 1, p:p + 1), chain%m, &
                                                                chain%m_inv)
                    end do
                end do
                call apply_jump(chain, 2*i - 1, in_epoch, low, high, largest)
            end if
        else
            do j = i, last
                call rows_to_now(chain, j)
            end do
            call apply_jump(chain, 2*i - 1, s, low, high, largest)
        end if
        call keep_tangent_finite(chain, largest)
        ! (not while a direction removed by a rest waits for the QR step to find it: a
        ! factorisation here would turn it into a unit vector)
        ! (nor after many strongly inelastic impacts: each shrinks the frame's volume by K**2,
        ! and a frame shrunk by 1e-8 within one interval keeps its smallest directions poorly;
        ! a piece's columns meet no other rows, so the volume that matters is the piece's)
        chain%jumps_volume(low) = chain%jumps_volume(low) + chain%impact_volume
        ! (nor while the frame grows fast: once an entry passes large_growth, its leading
        ! direction outgrows the others by about as much, and their digits go)
        if (chain%orthonormalise_jumps .and. chain%rank_losses == 0) then
            if (s_max > large_jump .or. sum(chain%jumps_volume(low:high)) < small_volume .or. &
                largest > large_growth) call orthonormalise_tangent(chain, low, high)
        end if
    contains
        ! (internal, so that it is inlined: no procedure of a submodule is)
        !> M^-1 B M for 2x2 blocks (written out: a section of s passed to fixed-shape dummies
        !> would be copied into an allocated temporary).
        pure function conjugated(b, m, m_inv) result(c)
            real(wp), intent(in) :: b(:, :), m(2, 2), m_inv(2, 2)
            real(wp) :: c(2, 2), bm(2, 2)
            integer :: j

            do j = 1, 2
                bm(:, j) = b(:, 1)*m(1, j) + b(:, 2)*m(2, j)
            end do
            do j = 1, 2
                c(:, j) = m_inv(:, 1)*bm(1, j) + m_inv(:, 2)*bm(2, j)
            end do
        end function conjugated
    end procedure jump_rows

    !> (After propagators_now.) Rows already moved to now at this instant stay. Afterwards every row
    !> is in the coordinates of now.
    module procedure move_tangent_epoch
        logical :: moves(chain%n)
        integer, allocatable :: rows(:)
        integer :: i, j, first, last, q, q_end

        if (chain%n_vectors > 0) then
            moves = chain%row_stamp /= chain%instant .and. chain%contact == contact_free
            rows = pack([(i, i=1, chain%n)], moves)
            if (allocated(chain%joined)) then
                ! piece by piece, its columns times its moving rows (rows(q:q_end)): the
                ! only nonzero entries of those rows
                q = 1
                first = 1
                do while (first <= chain%n)
                    last = first
                    do while (last < chain%n)
                        if (.not. chain%joined(last)) exit
                        last = last + 1
                    end do
                    q_end = q - 1
                    do while (q_end < size(rows))
                        if (rows(q_end + 1) > last) exit
                        q_end = q_end + 1
                    end do
                    if (q_end >= q) then
                        do j = 2*first - 1, 2*last
                            call move_rows(chain%tangent, rows(q:q_end), j, chain%m)
                        end do
                    end if
                    q = q_end + 1
                    first = last + 1
                end do
            else
                ! column by column: each column is read and written once, in order
                do j = 1, chain%n_vectors
                    call move_rows(chain%tangent, rows, j, chain%m)
                end do
            end if
        end if
        chain%n_touched = 0
    end procedure move_tangent_epoch

    !> Rows of the oscillators `rows` of column j moved by the 2 x 2 map m.
    pure subroutine move_rows(t, rows, j, m)
        real(wp), contiguous, intent(inout) :: t(:, :)
        integer, intent(in) :: rows(:), j
        real(wp), intent(in) :: m(2, 2)
        real(wp) :: a, b
        integer :: q, i

        do q = 1, size(rows)
            i = rows(q)
            a = t(2*i - 1, j)
            b = t(2*i, j)
            t(2*i - 1, j) = m(1, 1)*a + m(1, 2)*b
            t(2*i, j) = m(2, 1)*a + m(2, 2)*b
        end do
    end subroutine move_rows

    !> (M^-1 of that instant.)
    module procedure rows_back_to_epoch
        real(wp) :: largest
        integer :: j, i, low, high

        do j = 1, chain%n_touched
            i = chain%touched(j)
            call piece_columns(chain, i, low, high)
            call jump_two_rows(chain%tangent, 2*i - 1, chain%m_inv, low, high, largest)
        end do
        chain%n_touched = 0
    end procedure rows_back_to_epoch

    !> (The tangent map of a rest is singular: the QR step looks for the lost direction.)
    module procedure forget_rows
        chain%tangent(2*i - 1:2*i, :) = 0
        chain%rank_losses = chain%rank_losses + 1
    end procedure forget_rows

    !> A resting oscillator's state does not depend on where it came from: its rows are zero.
    pure subroutine forget_resting_rows(chain)
        type(chain_t), intent(inout) :: chain
        integer :: i

        do i = 1, chain%n
            if (chain%contact(i) /= contact_free) call forget_rows(chain, i)
        end do
    end subroutine forget_resting_rows

    !> The velocity rows of the cluster are replaced by their mean (zero if it stopped), with
    !> no saltation term: a singular map.
    module procedure average_rows
        real(wp), allocatable :: rows(:)
        integer :: i, m, low, high

        m = last - first + 1
        if (m > 1 .or. stopped) chain%rank_losses = chain%rank_losses + 1
        call join(chain, first, last)
        ! (the merged piece's columns: the rows are zero in the others)
        call piece_columns(chain, first, low, high)
        allocate (rows(low:high))
        rows = 0
        do i = first, last
            rows = rows + chain%tangent(2*i, low:high)
        end do
        ! a cluster stopped by a wall has v = 0 whatever the perturbation
        if (stopped) rows = 0
        do i = first, last
            chain%tangent(2*i, low:high) = rows/m
        end do
    end procedure average_rows

    !> The tangent rows of oscillator i in the coordinates of now, for an impact (after
    !> propagators_now); they go back to the epoch when the instant ends.
    pure subroutine rows_to_now(chain, i)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: i
        real(wp) :: largest
        integer :: low, high

        if (chain%row_stamp(i) == chain%instant) return
        call piece_columns(chain, i, low, high)
        call jump_two_rows(chain%tangent, 2*i - 1, chain%m, low, high, largest)
        chain%row_stamp(i) = chain%instant
        chain%n_touched = chain%n_touched + 1
        chain%touched(chain%n_touched) = i
    end subroutine rows_to_now

    !> Re-orthonormalise the frame now, keeping ln |R(j,j)| in tangent_log: the piece of
    !> columns (and rows) low .. high alone when the frame knows its pieces and carries no
    !> power-of-two scale (which is the whole frame's), else the whole frame. Any upper
    !> triangular change of the columns commutes with the rows' own coordinates (epoch or
    !> now), so the frame need not be synced first.
    subroutine orthonormalise_tangent(chain, low, high)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: low, high
        integer :: info, j

        if (.not. allocated(chain%r_diag)) allocate (chain%r_diag(chain%n_vectors))
        if (size(chain%r_diag) /= chain%n_vectors) then
            deallocate (chain%r_diag)
            allocate (chain%r_diag(chain%n_vectors))
        end if
        ! a zero diagonal (a direction lost exactly) is left to the QR step to report: the
        ! frame is then left as it was
        if (allocated(chain%joined) .and. chain%tangent_scale_bits == 0) then
            associate (r_diag => chain%r_diag(low:high))
                call qr_orthonormalise_piece(chain%tangent, low, high, r_diag, chain%qr, info, &
                                             keep_singular=.true.)
                if (info /= 0 .or. any(r_diag == 0)) return
                chain%jumps_volume(low:high) = 0
                chain%tangent_log(low:high) = chain%tangent_log(low:high) + log(abs(r_diag))
            end associate
            return
        end if
        call factorise_frame(chain, chain%r_diag, info, keep_singular=.true.)
        if (info /= 0 .or. any(chain%r_diag == 0)) return
        chain%jumps_volume = 0
        do j = 1, chain%n_vectors
            chain%tangent_log(j) = chain%tangent_log(j) + log(abs(chain%r_diag(j)))
        end do
        if (chain%keep_r_factors) then
            call fold_upper(qr_last_r(chain%qr, chain%n_vectors), chain%r_product, &
                            chain%r_product_log)
            chain%r_folded = .true.
        end if
    end subroutine orthonormalise_tangent

    !> Impacts at nearly zero approach speed (the last steps of an inelastic collapse) have
    !> saltation matrices of size 1/u, and a cascade of them can overflow the frame within one
    !> QR interval. The whole frame is then scaled by a power of two (exact), and the factor is
    !> kept in tangent_scale_bits for the next QR step to add back. The threshold leaves room
    !> for rows checked in the coordinates of now to be moved back to the epoch (|M^-1| up to
    !> about 2**93 before the epoch is moved) and then hit once more.
    pure subroutine keep_tangent_finite(chain, largest)
        type(chain_t), intent(inout) :: chain
        real(wp), intent(in) :: largest  !! of the rows just changed
        integer, parameter :: bits = 512

        if (largest < 2.0_wp**800) return
        chain%tangent = scale(chain%tangent, -bits)
        chain%tangent_scale_bits = chain%tangent_scale_bits + bits
    end subroutine keep_tangent_finite

    !> Replace the tangent rows first, first + 1, ... (one oscillator, s 2x2, or a neighbour
    !> pair, s 4x4) by S times them in columns low..high (the others are zero in those rows);
    !> `largest` is the largest magnitude written (jump_two_rows, jump_four_rows; the whole
    !> frame is passed, as a section of its rows would be copied).
    pure subroutine apply_jump(chain, first, s, low, high, largest)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: first, low, high
        real(wp), intent(in) :: s(:, :)
        real(wp), intent(out) :: largest

        if (size(s, 1) == 2) then
            call jump_two_rows(chain%tangent, first, s, low, high, largest)
        else
            call jump_four_rows(chain%tangent, first, s, low, high, largest)
        end if
    end subroutine apply_jump

    pure subroutine jump_two_rows(t, first, s, low, high, largest)
        real(wp), contiguous, intent(inout) :: t(:, :)
        integer, intent(in) :: first, low, high
        real(wp), intent(in) :: s(2, 2)
        real(wp), intent(out) :: largest
        real(wp) :: a, b
        integer :: j

        largest = 0
        do j = low, high
            a = t(first, j)
            b = t(first + 1, j)
            t(first, j) = s(1, 1)*a + s(1, 2)*b
            t(first + 1, j) = s(2, 1)*a + s(2, 2)*b
            largest = max(largest, abs(t(first, j)), abs(t(first + 1, j)))
        end do
    end subroutine jump_two_rows

    pure subroutine jump_four_rows(t, first, s, low, high, largest)
        real(wp), contiguous, intent(inout) :: t(:, :)
        integer, intent(in) :: first, low, high
        real(wp), intent(in) :: s(4, 4)
        real(wp), intent(out) :: largest
        real(wp) :: a, b, c, d
        integer :: j

        largest = 0
        do j = low, high
            a = t(first, j)
            b = t(first + 1, j)
            c = t(first + 2, j)
            d = t(first + 3, j)
            t(first, j) = s(1, 1)*a + s(1, 2)*b + s(1, 3)*c + s(1, 4)*d
            t(first + 1, j) = s(2, 1)*a + s(2, 2)*b + s(2, 3)*c + s(2, 4)*d
            t(first + 2, j) = s(3, 1)*a + s(3, 2)*b + s(3, 3)*c + s(3, 4)*d
            t(first + 3, j) = s(4, 1)*a + s(4, 2)*b + s(4, 3)*c + s(4, 4)*d
            largest = max(largest, abs(t(first, j)), abs(t(first + 1, j)), &
                          abs(t(first + 2, j)), abs(t(first + 3, j)))
        end do
    end subroutine jump_four_rows

end submodule chain_engine_tangent
