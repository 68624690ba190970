!> The machine's own yardsticks for the impactchain benchmark (`bench/bench.f90`): what one
!> `sin` + `cos` + `exp` of varying arguments costs (the transcendental functions the engine
!> evaluates per oscillator move: cos and sin of gam tau and exp(-b tau), docs/model.md
!> section 2.2) and the single-core `dgemm` rate of the BLAS the program is linked against
!> (the rate the QR of a tangent frame could reach at best). `bench/run_bench.py` states its
!> targets as ratios to these, measured in the same run, so that they hold on another CPU.
module bench_yardsticks
    use, intrinsic :: iso_fortran_env, only: int64
    use impactchain, only: wp
    use bench_kit, only: wall_seconds
    use chain_lapack, only: qr_orthonormalise, qr_workspace_t
    implicit none
    private
    public :: transcendental_ns, dgemm_gflops, qr_seconds

    interface
        subroutine dgemm(transa, transb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc)
            import :: wp
            implicit none
            character(len=1), intent(in) :: transa, transb
            integer, intent(in) :: m, n, k, lda, ldb, ldc
            real(wp), intent(in) :: alpha, beta
            real(wp), intent(in) :: a(lda, *), b(ldb, *)
            real(wp), intent(inout) :: c(ldc, *)
        end subroutine dgemm
    end interface

contains

    !> Nanoseconds per `sin(y) + cos(y) + exp(-b y)` on a different y each time, best of `reps`
    !> blocks of >= min_time after a warm-up; `checksum` is the sum of every result, so that
    !> no call can be dropped (the caller must use it). The arguments stay in [0, 8 pi), where
    !> the engine's phases gam tau lie; each term is added in order (no -ffast-math: the sum is
    !> not reassociated, so the calls are neither hoisted nor vectorised).
    subroutine transcendental_ns(min_time, reps, ns, checksum)
        real(wp), intent(in) :: min_time
        integer, intent(in) :: reps
        real(wp), intent(out) :: ns, checksum
        integer, parameter :: block = 100000
        real(wp), parameter :: step = 8*acos(-1.0_wp)/block, damping = 0.05_wp
        real(wp) :: t0, seconds, y
        integer(int64) :: calls
        integer :: r, i

        checksum = 0
        ns = huge(1.0_wp)
        do r = 0, reps
            calls = 0
            t0 = wall_seconds()
            do
                do i = 1, block
                    y = step*i + 1.0e-3_wp*r
                    checksum = checksum + sin(y)
                    checksum = checksum + cos(y)
                    checksum = checksum + exp(-damping*y)
                end do
                calls = calls + block
                seconds = wall_seconds() - t0
                if (seconds >= merge(0.2_wp, 1.0_wp, r == 0)*min_time) exit
            end do
            if (r > 0) ns = min(ns, 1.0e9_wp*seconds/real(calls, wp))
        end do
    end subroutine transcendental_ns

    !> GFLOP/s of `dgemm` on square n x n matrices (2 n^3 flops per call), best of `reps`
    !> blocks of >= min_time after a warm-up call; `checksum` is the trace of the product.
    subroutine dgemm_gflops(n, min_time, reps, gflops, checksum)
        integer, intent(in) :: n, reps
        real(wp), intent(in) :: min_time
        real(wp), intent(out) :: gflops, checksum
        real(wp), allocatable :: a(:, :), b(:, :), c(:, :)
        real(wp) :: t0, seconds
        integer :: r, i, j, calls

        allocate (a(n, n), b(n, n), c(n, n))
        do j = 1, n
            do i = 1, n
                a(i, j) = 1.0_wp/(i + j)
                b(i, j) = real(mod(i*j, 7) - 3, wp)/n
            end do
        end do
        c = 0
        call dgemm('N', 'N', n, n, n, 1.0_wp, a, n, b, n, 0.0_wp, c, n)
        gflops = 0
        do r = 1, reps
            calls = 0
            t0 = wall_seconds()
            do
                call dgemm('N', 'N', n, n, n, 1.0_wp, a, n, b, n, 0.0_wp, c, n)
                calls = calls + 1
                seconds = wall_seconds() - t0
                if (seconds >= min_time) exit
            end do
            gflops = max(gflops, 2.0e-9_wp*real(n, wp)**3*calls/seconds)
        end do
        checksum = sum([(c(i, i), i=1, n)])
    end subroutine dgemm_gflops

    !> Seconds per QR factorisation of an n x n frame with its Q formed, through the library's
    !> own qr_orthonormalise (dgeqrf, then Q; what a full Lyapunov spectrum does every QR
    !> step), best of `reps` blocks of >= min_time after a warm-up; `checksum` sums R's
    !> diagonal. numpy.linalg.qr (dgeqrf + dorgqr) is the comparison (bench/run_bench.py).
    subroutine qr_seconds(n, min_time, reps, seconds, checksum)
        integer, intent(in) :: n, reps
        real(wp), intent(in) :: min_time
        real(wp), intent(out) :: seconds, checksum
        real(wp), allocatable :: a(:, :), frame(:, :), r_diag(:)
        type(qr_workspace_t) :: ws
        real(wp) :: t0, elapsed
        integer :: r, i, j, calls, info

        allocate (a(n, n), r_diag(n))
        do j = 1, n
            do i = 1, n
                a(i, j) = 1.0_wp/(i + j) + merge(1.0_wp, 0.0_wp, i == j) + &
                          real(mod(i*j, 7) - 3, wp)/n
            end do
        end do
        frame = a
        call qr_orthonormalise(frame, r_diag, ws, info)
        seconds = huge(1.0_wp)
        checksum = 0
        do r = 1, reps
            calls = 0
            t0 = wall_seconds()
            do
                frame = a
                call qr_orthonormalise(frame, r_diag, ws, info)
                checksum = checksum + sum(r_diag) + info
                calls = calls + 1
                elapsed = wall_seconds() - t0
                if (elapsed >= min_time) exit
            end do
            seconds = min(seconds, elapsed/calls)
        end do
    end subroutine qr_seconds

end module bench_yardsticks
