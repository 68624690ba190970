!> The few LAPACK routines impactchain needs, with explicit interfaces and workspace queries:
!> QR factorisation (Lyapunov re-orthonormalisation) and the nonsymmetric eigenproblem
!> (Floquet multipliers). BLAS dtrsm forms Q from R when that is safe (see below).
module chain_lapack
    use chain_kinds, only: wp
    implicit none
    private
    public :: qr_orthonormalise, general_eigenvalues

    interface
        subroutine dgeqrf(m, n, a, lda, tau, work, lwork, info)
            import :: wp
            implicit none
            integer, intent(in) :: m, n, lda, lwork
            real(wp), intent(inout) :: a(lda, *)
            real(wp), intent(out) :: tau(*), work(*)
            integer, intent(out) :: info
        end subroutine dgeqrf
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
        subroutine dgeev(jobvl, jobvr, n, a, lda, wr, wi, vl, ldvl, vr, ldvr, work, lwork, info)
            import :: wp
            implicit none
            character(len=1), intent(in) :: jobvl, jobvr
            integer, intent(in) :: n, lda, ldvl, ldvr, lwork
            real(wp), intent(inout) :: a(lda, *)
            real(wp), intent(out) :: wr(*), wi(*), vl(ldvl, *), vr(ldvr, *), work(*)
            integer, intent(out) :: info
        end subroutine dgeev
    end interface

contains

    !> Replace the columns of a (m x k, m >= k) by an orthonormal basis of their span (Q of
    !> a = QR) and return the diagonal of R. info /= 0 is LAPACK's.
    !>
    !> R is Householder's (dgeqrf). Q is then a R^-1, one triangular solve, when the diagonal
    !> of R spans less than `solve_span`: its columns are orthonormal to about
    !> eps cond(R), as with the modified Gram-Schmidt of the classic Lyapunov algorithm, at a
    !> fifth of the cost of dorgqr (which dominated a 32-exponent run). The growth rates do
    !> not depend on that choice: the R factors telescope, Q_T = Phi Q_0 (R_T..R_1)^-1,
    !> whatever the orthogonality of the frames in between. A frame with a wider span
    !> (rows zeroed by a rest on a wall, a collapse cascade) gets Q from dorgqr.
    subroutine qr_orthonormalise(a, r_diag, info)
        real(wp), intent(inout) :: a(:, :)
        real(wp), intent(out) :: r_diag(:)
        integer, intent(out) :: info
        real(wp), parameter :: solve_span = 1.0e8_wp
        real(wp), allocatable :: tau(:), work(:), r(:, :)
        real(wp) :: query(1)
        integer :: m, k, j, lwork

        m = size(a, 1)
        k = size(a, 2)
        allocate (tau(k))
        call dgeqrf(m, k, a, m, tau, query, -1, info)
        lwork = max(1, int(query(1)))
        call dorgqr(m, k, k, a, m, tau, query, -1, info)
        lwork = max(lwork, int(query(1)))
        allocate (work(lwork))
        r = a
        call dgeqrf(m, k, r, m, tau, work, lwork, info)
        if (info /= 0) return
        do j = 1, k
            r_diag(j) = r(j, j)
        end do
        if (minval(abs(r_diag)) > maxval(abs(r_diag))/solve_span) then
            call dtrsm('R', 'U', 'N', 'N', m, k, 1.0_wp, r, m, a, m)
        else
            a = r
            call dorgqr(m, k, k, a, m, tau, work, lwork, info)
        end if
    end subroutine qr_orthonormalise

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

end module chain_lapack
