!> The few LAPACK routines impactchain needs, with explicit interfaces:
!> QR factorisation (Lyapunov re-orthonormalisation), the nonsymmetric eigenproblem
!> (Floquet multipliers, eigenvectors) and products and solves with upper triangular matrices
!> (covariant Lyapunov vectors).
!> The factorisations of docs/model.md sections 7.2 (QR), 7.9 (multipliers) and 14 (the
!> triangular factors of covariant vectors).
module chain_lapack
    use chain_kinds, only: wp
    implicit none
    private
    public :: qr_orthonormalise, qr_workspace_t, general_eigenvalues
    public :: solve_linear, qr_last_r, qr_copy_r, solve_upper_triangle, upper_product
    public :: general_eigenvectors, blas_one_thread, qr_orthonormalise_blocks
    public :: qr_orthonormalise_piece

    !> Triangular matrices of at most this order are solved and multiplied in plain loops.
    integer, parameter :: small_triangle = 40

    !> Arrays qr_orthonormalise needs, kept by its caller between calls of the same shape
    !> (a Lyapunov run re-orthonormalises its frame every cycle).
    type :: qr_workspace_t
        real(wp), allocatable :: r(:, :)   !! the factorisation (R and the reflectors)
        real(wp), allocatable :: tau(:)
        real(wp), allocatable :: work(:)
        real(wp), allocatable :: t(:, :)   !! dgeqrt's block reflector factors (large frames)
    end type qr_workspace_t

    interface
        subroutine dgeqrf(m, n, a, lda, tau, work, lwork, info)
            import :: wp
            implicit none
            integer, intent(in) :: m, n, lda, lwork
            real(wp), intent(inout) :: a(lda, *)
            real(wp), intent(out) :: tau(*), work(*)
            integer, intent(out) :: info
        end subroutine dgeqrf
        subroutine dgeqrt(m, n, nb, a, lda, t, ldt, work, info)
            import :: wp
            implicit none
            integer, intent(in) :: m, n, nb, lda, ldt
            real(wp), intent(inout) :: a(lda, *)
            real(wp), intent(out) :: t(ldt, *), work(*)
            integer, intent(out) :: info
        end subroutine dgeqrt
        subroutine dorgqr(m, n, k, a, lda, tau, work, lwork, info)
            import :: wp
            implicit none
            integer, intent(in) :: m, n, k, lda, lwork
            real(wp), intent(inout) :: a(lda, *)
            real(wp), intent(in) :: tau(*)
            real(wp), intent(out) :: work(*)
            integer, intent(out) :: info
        end subroutine dorgqr
        subroutine dtrsm(side, uplo, transa, diag, m, n, alpha, a, lda, b, ldb)
            import :: wp
            implicit none
            character(len=1), intent(in) :: side, uplo, transa, diag
            integer, intent(in) :: m, n, lda, ldb
            real(wp), intent(in) :: alpha, a(lda, *)
            real(wp), intent(inout) :: b(ldb, *)
        end subroutine dtrsm
        subroutine dtrmm(side, uplo, transa, diag, m, n, alpha, a, lda, b, ldb)
            import :: wp
            implicit none
            character(len=1), intent(in) :: side, uplo, transa, diag
            integer, intent(in) :: m, n, lda, ldb
            real(wp), intent(in) :: alpha, a(lda, *)
            real(wp), intent(inout) :: b(ldb, *)
        end subroutine dtrmm
        subroutine dgeev(jobvl, jobvr, n, a, lda, wr, wi, vl, ldvl, vr, ldvr, work, lwork, info)
            import :: wp
            implicit none
            character(len=1), intent(in) :: jobvl, jobvr
            integer, intent(in) :: n, lda, ldvl, ldvr, lwork
            real(wp), intent(inout) :: a(lda, *)
            real(wp), intent(out) :: wr(*), wi(*), vl(ldvl, *), vr(ldvr, *), work(*)
            integer, intent(out) :: info
        end subroutine dgeev
        !> src/base/chain_blas_runtime.c: the linked BLAS's thread count set to one
        subroutine blas_one_thread_c() bind(c, name='impactchain_blas_one_thread')
            implicit none
        end subroutine blas_one_thread_c
    end interface

contains

    !> One thread inside every call of the linked BLAS (docs/performance.md, "Which BLAS"). Done when the
    !> program is loaded, by a constructor in src/base/chain_blas_runtime.c, which this reference
    !> links into every program that uses this module; call it again only if something else
    !> (a host program) changed the BLAS's thread count, outside any parallel region.
    subroutine blas_one_thread()
        call blas_one_thread_c()
    end subroutine blas_one_thread

    !> Replace the columns of a (m x k, m >= k) by an orthonormal basis of their span (Q of
    !> a = QR) and return the diagonal of R. info /= 0 is LAPACK's.
    !>
    !> R is Householder's (dgeqrf). Q is then a R^-1, one triangular solve (dtrsm, level 3:
    !> 0.4 to 0.7 of dorgqr's instructions on BLIS from 32 x 32 to 512 x 512), when that is
    !> accurate: its columns are orthonormal to about eps cond(a), so the solve is taken only
    !> when a bound on the largest column of a (sqrt(k) times the largest entry of R: reflections
    !> keep lengths)
    !> over the smallest |R_jj| (about a lower bound of cond(a)) is below `solve_span`, and
    !> kept only when every column of the result has unit length to `unit_tolerance`.
    !> Otherwise (rows zeroed by a rest on a wall, a collapse cascade, a nearly dependent
    !> frame) Q comes from dorgqr. The growth rates do not depend on that choice: the R
    !> factors telescope, Q_T = Phi Q_0 (R_T..R_1)^-1, whatever the orthogonality of the
    !> frames in between. With `keep_singular`, a with an exactly zero R(j,j) is left as it was.
    subroutine qr_orthonormalise(a, r_diag, ws, info, keep_singular)
        ! contiguous, as every caller's frame is: without it gfortran 12 copies `a` into a
        ! temporary and back for each call below that takes it contiguous, at every step
        real(wp), intent(inout), contiguous :: a(:, :)
        real(wp), intent(out) :: r_diag(:)
        type(qr_workspace_t), intent(inout) :: ws
        integer, intent(out) :: info
        logical, intent(in), optional :: keep_singular
        real(wp), parameter :: solve_span = 1.0e6_wp, unit_tolerance = 1.0e-10_wp
        integer, parameter :: block_width = 64
        !> frames of at most this many columns are factorised here, without library calls:
        !> on vectors this short, LAPACK's and the BLAS's per-call work (dnrm2's scaling, the
        !> level-2 calls of dgeqr2, dtrsm's dispatch) cost more than the arithmetic
        integer, parameter :: small_frame = 40
        !> frames of at least this many columns are factorised by dgeqrt in blocks of
        !> `large_block` columns (recursive panels): dgeqrf's blocks of 32 make its trailing
        !> updates rank-32 products, which stream the whole frame per block (2048 x 2048 on
        !> BLIS: 1.0 s against 0.58 s)
        integer, parameter :: large_frame = 1024, large_block = 256
        real(wp) :: widest
        integer :: m, k, j

        m = size(a, 1)
        k = size(a, 2)
        if (allocated(ws%r)) then
            if (any(shape(ws%r) /= shape(a))) deallocate (ws%r, ws%tau, ws%work)
            if (allocated(ws%t) .and. .not. allocated(ws%r)) deallocate (ws%t)
        end if
        ! room for LAPACK's blocked algorithms at any usual block size, without a workspace
        ! query (which costs as much as the factorisation of a small frame); a smaller
        ! lwork would only make them block less
        if (.not. allocated(ws%r)) allocate (ws%r(m, k), ws%tau(k), &
                                             ws%work(max(block_width, large_block)*k))
        associate (r => ws%r, tau => ws%tau, work => ws%work)
            r = a
            if (k <= small_frame) then
                call householder_qr(r, tau)
                info = 0
            else if (k >= large_frame) then
                if (.not. allocated(ws%t)) allocate (ws%t(large_block, k))
                call dgeqrt(m, k, large_block, r, m, ws%t, large_block, work, info)
                if (info /= 0) return
                ! the same reflectors as dgeqrf's; their factors are the diagonals of the
                ! blocks of T, which is what dorgqr takes
                do j = 1, k
                    tau(j) = ws%t(modulo(j - 1, large_block) + 1, j)
                end do
            else
                call dgeqrf(m, k, r, m, tau, work, size(work), info)
                if (info /= 0) return
            end if
            widest = 0
            do j = 1, k
                r_diag(j) = r(j, j)
                widest = max(widest, maxval(abs(r(1:j, j))))
            end do
            widest = sqrt(real(k, wp))*widest
            if (present(keep_singular)) then
                if (keep_singular .and. any(r_diag == 0)) return
            end if
            if (minval(abs(r_diag)) > widest/solve_span) then
                if (k <= small_frame) then
                    call solve_upper_right(r, a)
                else
                    call dtrsm('R', 'U', 'N', 'N', m, k, 1.0_wp, r, m, a, m)
                end if
                if (unit_columns(a, unit_tolerance)) return
            end if
            a = r
            call dorgqr(m, k, k, a, m, tau, work, size(work), info)
        end associate
    end subroutine qr_orthonormalise

    !> qr_orthonormalise of a square frame a (2n x 2n, two rows and columns per oscillator)
    !> made of independent pieces: `joined` (n - 1) marks the bonds joined (bond i between
    !> oscillators i and i + 1), a piece is a maximal run [p, q] of oscillators joined by them,
    !> and a piece's columns 2p - 1 .. 2q are zero outside its rows 2p - 1 .. 2q and its rows
    !> zero outside its columns (a full spectrum started from unit vectors: only impacts join
    !> neighbours). Householder's reflections never mix such blocks (every reflection of a
    !> piece's column is zero outside the piece's rows), so R and Q are, entry for entry, those
    !> of the dense factorisation in exact arithmetic (docs/model.md section 7.2); each piece
    !> goes to qr_orthonormalise_piece. Cost the sum of the pieces' m^3 (m twice a piece's
    !> length). With `keep_singular`, a frame with an exactly zero R(j,j) is left as it was:
    !> the pieces are kept aside as they were until all are known to be regular.
    subroutine qr_orthonormalise_blocks(a, joined, r_diag, ws, info, keep_singular)
        real(wp), intent(inout), contiguous :: a(:, :)
        logical, intent(in) :: joined(:)
        real(wp), intent(out) :: r_diag(:)
        type(qr_workspace_t), intent(inout) :: ws
        integer, intent(out) :: info
        logical, intent(in), optional :: keep_singular
        real(wp), allocatable :: q_all(:)
        integer, allocatable :: pieces(:, :)
        logical :: keep
        integer :: k, low, high, m, used

        info = 0
        keep = .false.
        if (present(keep_singular)) keep = keep_singular
        pieces = piece_rows(joined)
        ! (with keep_singular, each piece is kept here as it was until all are known regular)
        if (keep) allocate (q_all(sum((pieces(2, :) - pieces(1, :) + 1)**2)))
        used = 0
        do k = 1, size(pieces, 2)
            low = pieces(1, k)
            high = pieces(2, k)
            m = high - low + 1
            if (keep) q_all(used + 1:used + m*m) = reshape(a(low:high, low:high), [m*m])
            used = used + m*m
            call qr_orthonormalise_piece(a, low, high, r_diag(low:high), ws, info, keep_singular)
            if (info == 0 .and. .not. (keep .and. any(r_diag(low:high) == 0))) cycle
            if (keep) call put_back(k)
            return
        end do
    contains
        !> Pieces 1 .. last as they were before their factorisation.
        subroutine put_back(last)
            integer, intent(in) :: last
            integer :: k, low, high, m, used

            used = 0
            do k = 1, last
                low = pieces(1, k)
                high = pieces(2, k)
                m = high - low + 1
                a(low:high, low:high) = reshape(q_all(used + 1:used + m*m), [m, m])
                used = used + m*m
            end do
        end subroutine put_back

        !> The first and last row of each piece, in order: a piece ends at each bond not joined.
        pure function piece_rows(joined) result(rows)
            logical, intent(in) :: joined(:)
            integer :: rows(2, count(.not. joined) + 1)
            integer :: first, last, k

            first = 1
            k = 0
            do last = 1, size(joined) + 1
                if (last <= size(joined)) then
                    if (joined(last)) cycle
                end if
                k = k + 1
                rows(:, k) = [2*first - 1, 2*last]
                first = last + 1
            end do
        end function piece_rows
    end subroutine qr_orthonormalise_blocks

    !> The piece of a block-diagonal frame a whose rows and columns are low .. high (zero
    !> outside that block, qr_orthonormalise_blocks) re-orthonormalised alone, the diagonal of
    !> its R in r_diag (high - low + 1): the frame's columns change by block-diag(I, R^-1, I),
    !> upper triangular, so the growth telescopes as for a whole factorisation. A piece of one
    !> oscillator (2 x 2) in closed form; with `keep_singular`, a singular piece is left as is.
    subroutine qr_orthonormalise_piece(a, low, high, r_diag, ws, info, keep_singular)
        real(wp), intent(inout), contiguous :: a(:, :)
        integer, intent(in) :: low, high
        real(wp), intent(out) :: r_diag(:)
        type(qr_workspace_t), intent(inout) :: ws
        integer, intent(out) :: info
        logical, intent(in), optional :: keep_singular
        real(wp), allocatable :: block(:, :)

        info = 0
        block = a(low:high, low:high)
        if (high - low == 1) then
            call closed_form_qr(block, r_diag)
            if (present(keep_singular)) then
                if (keep_singular .and. any(r_diag == 0)) return
            end if
        else
            call qr_orthonormalise(block, r_diag, ws, info, keep_singular)
            if (info /= 0) return
        end if
        a(low:high, low:high) = block
    end subroutine qr_orthonormalise_piece

    !> A 2 x 2 block b = [a b; c d] replaced by its Q, R's diagonal in r_diag: the reflector of
    !> its first column, Q = H = [a c; c -a]/beta (beta = -sign(|(a, c)|, a)), or Q = I when
    !> c = 0, as householder_qr builds it.
    pure subroutine closed_form_qr(b, r_diag)
        real(wp), intent(inout) :: b(:, :)
        real(wp), intent(out) :: r_diag(:)
        real(wp) :: beta, a11, a21, a12, a22

        a11 = b(1, 1)
        a21 = b(2, 1)
        a12 = b(1, 2)
        a22 = b(2, 2)
        if (a21 == 0) then
            b = reshape([1.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [2, 2])
            r_diag(1) = a11
            r_diag(2) = a22
        else
            if (plain_squares(abs(a21)) .and. abs(a11) < 1.0e100_wp) then
                beta = -sign(sqrt(a11**2 + a21**2), a11)
            else
                beta = -sign(hypot(a11, a21), a11)
            end if
            b(:, 1) = [a11, a21]/beta
            b(:, 2) = [a21, -a11]/beta
            r_diag(1) = beta
            r_diag(2) = (a21*a12 - a11*a22)/beta
        end if
    end subroutine closed_form_qr

    !> Can squares of numbers up to `largest` be summed without overflow or underflow that
    !> matters? (Then a length is the square root of the plain sum of squares.)
    pure logical function plain_squares(largest)
        real(wp), intent(in) :: largest

        plain_squares = largest > 1.0e-100_wp .and. largest < 1.0e100_wp
    end function plain_squares

    !> Householder QR of r (m x k, m >= k) in place, in LAPACK's storage (dgeqrf's): R in the
    !> upper triangle, the reflectors' vectors below it (first entry 1, implied) and their
    !> factors in tau, each reflector H = I - tau (1, v)(1, v)^T built as dlarfg builds it
    !> (beta = -sign(|x|, x(1)), R(j,j) = beta), so that dorgqr can form Q from it. Unblocked
    !> loops over columns, for small frames (see qr_orthonormalise).
    pure subroutine householder_qr(r, tau)
        real(wp), intent(inout), contiguous :: r(:, :)
        real(wp), intent(out) :: tau(:)
        real(wp) :: alpha, beta, xnorm, scale, squares
        integer :: m, k, j, c

        m = size(r, 1)
        k = size(r, 2)
        do j = 1, k
            alpha = r(j, j)
            xnorm = 0
            scale = 0
            if (j < m) then
                scale = maxval(abs(r(j + 1:m, j)))
                ! the plain sum of squares unless it could overflow or underflow
                if (plain_squares(scale)) then
                    squares = sum(r(j + 1:m, j)**2)
                    xnorm = sqrt(squares)
                else if (scale > 0) then
                    xnorm = norm2(r(j + 1:m, j))
                end if
            end if
            if (xnorm == 0) then
                tau(j) = 0
                cycle
            end if
            ! |(alpha, x)| by one square root of the sum of squares where nothing can overflow
            ! (IEEE 754 rounds it alike on every machine, the library's hypot need not)
            if (plain_squares(scale) .and. abs(alpha) < 1.0e100_wp) then
                beta = -sign(sqrt(alpha**2 + squares), alpha)
            else
                beta = -sign(hypot(alpha, xnorm), alpha)
            end if
            tau(j) = (beta - alpha)/beta
            r(j + 1:m, j) = r(j + 1:m, j)/(alpha - beta)
            r(j, j) = beta
            do c = j + 1, k - 7, 8
                call reflect_eight(r, j, c, tau(j))
            end do
            do c = c, k
                call reflect_one(r, j, c, tau(j))
            end do
        end do
    end subroutine householder_qr

    !> Columns c .. c + 7 of r reflected by the reflector of column j (below row j, v;
    !> factor tau): r(j:, c) -= tau (1, v) ((1, v) . r(j:, c)). The eight sums run side by
    !> side, each over the rows in order, as reflect_one's: one sum alone is a chain of
    !> additions, each waiting for the last.
    pure subroutine reflect_eight(r, j, c, tau)
        real(wp), intent(inout), contiguous :: r(:, :)
        integer, intent(in) :: j, c
        real(wp), intent(in) :: tau
        real(wp) :: s(8), v
        integer :: i, q

        s = 0
        do i = j + 1, size(r, 1)
            v = r(i, j)
            s = s + v*r(i, c:c + 7)
        end do
        s = tau*(r(j, c:c + 7) + s)
        do q = 1, 8
            r(j, c + q - 1) = r(j, c + q - 1) - s(q)
            r(j + 1:, c + q - 1) = r(j + 1:, c + q - 1) - s(q)*r(j + 1:, j)
        end do
    end subroutine reflect_eight

    !> Column c of r reflected by the reflector of column j.
    pure subroutine reflect_one(r, j, c, tau)
        real(wp), intent(inout), contiguous :: r(:, :)
        integer, intent(in) :: j, c
        real(wp), intent(in) :: tau
        real(wp) :: s
        integer :: i

        s = 0
        do i = j + 1, size(r, 1)
            s = s + r(i, j)*r(i, c)
        end do
        s = tau*(r(j, c) + s)
        r(j, c) = r(j, c) - s
        r(j + 1:, c) = r(j + 1:, c) - s*r(j + 1:, j)
    end subroutine reflect_one

    !> a := a R^-1 for the upper triangle R of r (k x k of it), column by column: dtrsm's
    !> 'R', 'U', 'N', 'N', without the library call (small frames). Each entry takes its
    !> updates from columns 1, 2, ... in turn, then its division; columns are solved in pairs
    !> (each finished column read once for both).
    pure subroutine solve_upper_right(r, a)
        real(wp), intent(in), contiguous :: r(:, :)
        real(wp), intent(inout), contiguous :: a(:, :)
        integer :: j, l, i

        do j = 1, size(a, 2) - 1, 2
            do l = 1, j - 1
                do i = 1, size(a, 1)
                    a(i, j) = a(i, j) - r(l, j)*a(i, l)
                    a(i, j + 1) = a(i, j + 1) - r(l, j + 1)*a(i, l)
                end do
            end do
            a(:, j) = a(:, j)/r(j, j)
            a(:, j + 1) = (a(:, j + 1) - r(j, j + 1)*a(:, j))/r(j + 1, j + 1)
        end do
        if (modulo(size(a, 2), 2) == 1) then
            j = size(a, 2)
            do l = 1, j - 1
                a(:, j) = a(:, j) - r(l, j)*a(:, l)
            end do
            a(:, j) = a(:, j)/r(j, j)
        end if
    end subroutine solve_upper_right

    !> Has every column of a unit length to `tolerance`? (Each sum of squares over the rows
    !> in order; four columns at a time, as independent sums.)
    pure logical function unit_columns(a, tolerance)
        real(wp), intent(in), contiguous :: a(:, :)
        real(wp), intent(in) :: tolerance
        real(wp) :: s(4)
        integer :: j, i, c

        unit_columns = .false.
        do j = 1, size(a, 2), 4
            c = min(4, size(a, 2) - j + 1)
            s = 0
            do i = 1, size(a, 1)
                s(1:c) = s(1:c) + a(i, j:j + c - 1)**2
            end do
            if (.not. all(abs(s(1:c) - 1) < 2*tolerance)) return
        end do
        unit_columns = .true.
    end function unit_columns

    !> The R factor (k x k, zeros below the diagonal) of the last qr_orthonormalise on `ws`,
    !> a frame of k columns: that frame was Q R, Q the frame it was replaced by.
    pure function qr_last_r(ws, k) result(r)
        type(qr_workspace_t), intent(in) :: ws
        integer, intent(in) :: k
        real(wp), allocatable :: r(:, :)
        integer :: j

        allocate (r(k, k))
        r = 0
        do j = 1, k
            r(1:j, j) = ws%r(1:j, j)
        end do
    end function qr_last_r

    !> The same R into the upper triangle of r (k x k; below the diagonal r is left as it
    !> is), without a temporary: a covariant run takes it at every record.
    pure subroutine qr_copy_r(ws, r)
        type(qr_workspace_t), intent(in) :: ws
        real(wp), intent(inout) :: r(:, :)
        integer :: j

        do j = 1, size(r, 2)
            r(1:j, j) = ws%r(1:j, j)
        end do
    end subroutine qr_copy_r

    !> c := R^-1 c for upper triangular R (the upper triangle of r) and c, both k x k (below
    !> the diagonal c is zero, and stays zero, of either sign). By LAPACK's dtrsm on each block
    !> of `solve_block` columns of c down to the block's last row only, as below it the block
    !> is zero (k = 128: 0.8 times the time of one solve of all of c, with the same result bit
    !> for bit on BLIS, as with reference BLAS, whose solve goes column by column), or for at
    !> most `small_triangle` columns in plain loops (on matrices this small the library's
    !> per-call work costs more than the arithmetic).
    subroutine solve_upper_triangle(r, c)
        real(wp), intent(in) :: r(:, :)
        real(wp), intent(inout), contiguous :: c(:, :)
        integer, parameter :: solve_block = 64
        integer :: j, l, k, first, last

        k = size(c, 2)
        if (k > small_triangle) then
            do first = 1, k, solve_block
                last = min(k, first + solve_block - 1)
                call dtrsm('L', 'U', 'N', 'N', last, last - first + 1, 1.0_wp, r, size(r, 1), &
                           c(:, first:), k)
            end do
            return
        end if
        ! (row l of every column in turn, from the last row: each entry gets the updates from
        ! the rows below it, last first, then its division, as in a back substitution of one
        ! column at a time, and column l of R serves every column of c at once)
        do l = k, 1, -1
            do j = l, k
                if (c(l, j) == 0) cycle
                c(l, j) = c(l, j)/r(l, l)
                c(1:l - 1, j) = c(1:l - 1, j) - c(l, j)*r(1:l - 1, l)
            end do
        end do
    end subroutine solve_upper_triangle

    !> b = a C for a (m x k) and the upper triangle C of c (k x k): by dtrmm on a copy of a,
    !> or for at most `small_triangle` columns in plain loops, each entry a(i, j) c(j, j) plus
    !> a(i, l) c(l, j) for l = 1 .. j - 1 in turn. (a is explicit-shape, so that a record of
    !> a scratch file can be passed in place.)
    subroutine upper_product(a, c, b)
        real(wp), intent(out), contiguous :: b(:, :)
        real(wp), intent(in) :: a(size(b, 1), size(b, 2)), c(:, :)
        integer :: j, l

        if (size(c, 1) > small_triangle) then
            b = a
            call dtrmm('R', 'U', 'N', 'N', size(b, 1), size(b, 2), 1.0_wp, c, size(c, 1), b, &
                       size(b, 1))
            return
        end if
        do j = 1, size(b, 2)
            b(:, j) = a(:, j)*c(j, j)
            do l = 1, j - 1
                b(:, j) = b(:, j) + a(:, l)*c(l, j)
            end do
        end do
    end subroutine upper_product

    !> Eigenvalues wr + i wi and right eigenvectors of a general square matrix (a is
    !> overwritten), in LAPACK's dgeev form: for a real eigenvalue j, vr(:, j) is its unit
    !> eigenvector; for a pair j, j + 1 (wi(j) > 0), vr(:, j) +- i vr(:, j + 1).
    subroutine general_eigenvectors(a, wr, wi, vr, info)
        real(wp), intent(inout) :: a(:, :)
        real(wp), intent(out) :: wr(:), wi(:), vr(:, :)
        integer, intent(out) :: info
        real(wp), allocatable :: work(:)
        real(wp) :: query(1), dummy(1, 1)
        integer :: n

        n = size(a, 1)
        call dgeev('N', 'V', n, a, n, wr, wi, dummy, 1, vr, n, query, -1, info)
        allocate (work(max(1, int(query(1)))))
        call dgeev('N', 'V', n, a, n, wr, wi, dummy, 1, vr, n, work, size(work), info)
    end subroutine general_eigenvectors

    !> Eigenvalues wr + i wi of a general square matrix (a is overwritten).
    subroutine general_eigenvalues(a, wr, wi, info)
        real(wp), intent(inout) :: a(:, :)
        real(wp), intent(out) :: wr(:), wi(:)
        integer, intent(out) :: info
        real(wp), allocatable :: work(:)
        real(wp) :: query(1), dummy(1, 1)
        integer :: n

        n = size(a, 1)
        call dgeev('N', 'N', n, a, n, wr, wi, dummy, 1, dummy, 1, query, -1, info)
        allocate (work(max(1, int(query(1)))))
        call dgeev('N', 'N', n, a, n, wr, wi, dummy, 1, dummy, 1, work, size(work), info)
    end subroutine general_eigenvalues

    !> Solve a x = b in place (b(n, nrhs) becomes x; a is overwritten by its LU factors) by
    !> LAPACK dgesv, partial pivoting: the Newton steps of periodic orbits (docs/model.md
    !> section 11). info > 0: U(info, info) is exactly zero, a is singular.
    subroutine solve_linear(a, b, info)
        real(wp), intent(inout) :: a(:, :), b(:, :)
        integer, intent(out) :: info
        interface
            subroutine dgesv(n, nrhs, a, lda, ipiv, b, ldb, info)
                import :: wp
                implicit none
                integer, intent(in) :: n, nrhs, lda, ldb
                real(wp), intent(inout) :: a(lda, *), b(ldb, *)
                integer, intent(out) :: ipiv(*), info
            end subroutine dgesv
        end interface
        integer, allocatable :: pivots(:)
        integer :: n

        n = size(a, 1)
        allocate (pivots(n))
        call dgesv(n, size(b, 2), a, n, pivots, b, n, info)
    end subroutine solve_linear

end module chain_lapack
