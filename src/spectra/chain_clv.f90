!> Covariant Lyapunov vectors (docs/model.md section 14), by Ginelli's forward QR / backward
!> upper-triangular iteration: the forward pass keeps, for every strobe record j, the R factor
!> of the record-to-record map (Q_j R_j = J_j Q_(j-1)) and the frame Q_j, in scratch files
!> (chain_scratch), so that memory does not depend on the length of the run; the backward
!> pass reads them from the end, iterates C_(j-1) = R_j^-1 C_j with unit columns from a
!> generic upper triangular C at the last record, and forms the vectors V_j = Q_j C_j at every
!> record but the last `transient` (the window over which C converges). What is reported of
!> them: their own growth rates, the per-oscillator weights and inverse participation ratio of
!> each, the smallest angle between the unstable vectors and the others, and the vectors
!> themselves at the last records.
!>
!> The backward pass hands its per-record numbers out in blocks of consecutive records (last
!> block first), each at most `rows_bytes`, so that a caller can stream them to a file.
module chain_clv
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error
    use chain_lapack, only: solve_upper_triangle, upper_product
    use chain_scratch, only: scratch_records_t, scratch_open, scratch_append, scratch_next, &
                             scratch_find, scratch_close
    use chain_blocking, only: blocking_t, blocking_start, blocking_add, blocking_error
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    implicit none
    private
    public :: clv_pass_t, clv_rows_t, clv_result_t
    public :: clv_start, clv_forward, clv_backward_begin, clv_backward_rows, clv_result
    public :: clv_close, clv_scratch_bytes
    public :: fold_upper, initial_c, site_weights, unstable_angle, backward_step, vector_numbers

    !> Most bytes of one block of per-record numbers.
    integer(i8), parameter :: rows_bytes = 4_i8*1024*1024

    !> One block of the backward pass's per-record numbers: records first .. first + count - 1
    !> of the `total` records that have vectors (the run's records 1 .. total).
    type :: clv_rows_t
        integer(i8) :: first = 1
        integer :: count = 0
        integer(i8) :: total = 0
        integer(i8), allocatable :: cycle(:)          !! drive cycle of each record
        real(wp), allocatable :: ipr(:, :)            !! ipr(k, count)
        real(wp), allocatable :: site_weight(:, :, :) !! site_weight(n, m, count)
        real(wp), allocatable :: min_angle(:)         !! min_angle(count), radians
    end type clv_rows_t

    !> What the backward pass found besides its per-record numbers.
    type :: clv_result_t
        integer(i8) :: kept = 0                    !! records with vectors
        integer :: transient = 0                   !! records at the end without
        integer :: unstable = 0                    !! vectors spanning the unstable subspace
        real(wp), allocatable :: exponents(:)      !! bits per drive cycle, in vector order
        real(wp), allocatable :: stderr(:)         !! their standard errors (blocking plateau)
        integer(i8), allocatable :: stderr_block(:) !! records per block at the plateau
        real(wp), allocatable :: vectors(:, :, :)  !! vectors(2n, k, r) at the last r records
        integer(i8), allocatable :: saved_cycle(:) !! drive cycle of each of those records
    end type clv_result_t

    !> Both passes: what the forward pass keeps, and where the backward pass stands.
    type :: clv_pass_t
        integer :: n = 0, k = 0, m = 0, r = 0
        integer(i8) :: records = 0     !! strobe records of the run, N
        integer(i8) :: kept = 0        !! records with vectors, N - transient
        type(scratch_records_t) :: factors !! record j: drive cycle, R_j (r_log, packed)
        type(scratch_records_t) :: frames  !! record j <= kept: Q_j
        integer(i8) :: at = 0          !! the backward pass holds C_at
        integer :: unstable = 0
        real(wp), allocatable :: c(:, :)            !! c(k, k), upper triangular, unit columns
        real(wp), allocatable :: total(:)           !! growth of each vector (nats), kept steps
        type(blocking_t) :: blocks                  !! the growths of the kept steps, blocked
        real(wp), allocatable :: vectors(:, :, :)   !! vectors(2n, k, r)
        integer(i8), allocatable :: saved_cycle(:)
        real(wp), allocatable :: r_s(:, :), r_log(:), v(:, :) !! work
    end type clv_pass_t

contains

    !> Scratch files for a run of `records` strobe records of a chain of n oscillators with k
    !> tangent vectors, the last `transient` of which get no vectors; per-oscillator weights of
    !> the first m vectors, the vectors themselves at the last r records with vectors.
    subroutine clv_start(pass, n, k, records, transient, m, r, err)
        type(clv_pass_t), intent(out) :: pass
        integer, intent(in) :: n, k, transient, m, r
        integer(i8), intent(in) :: records
        type(error_t), allocatable, intent(out) :: err

        pass%n = n
        pass%k = k
        pass%m = m
        pass%r = r
        pass%records = records
        pass%kept = records - transient
        call scratch_open(pass%factors, factor_width(k), err)
        if (allocated(err)) return
        call scratch_open(pass%frames, 2*n*k, err)
        if (allocated(err)) return
        allocate (pass%r_s(k, k), pass%r_log(k), pass%v(2*n, k))
        ! (step_back fills only the upper triangle)
        pass%r_s = 0
    end subroutine clv_start

    !> Bytes of the scratch files of such a run (docs/model.md section 14.3).
    pure real(wp) function clv_scratch_bytes(n, k, records, transient)
        integer, intent(in) :: n, k, transient
        integer(i8), intent(in) :: records

        clv_scratch_bytes = 8*(real(records, wp)*factor_width(k) + &
                               real(records - transient, wp)*2*n*k)
    end function clv_scratch_bytes

    !> Reals per record of the factors' file: the drive cycle, r_log(k), R's upper triangle.
    pure integer function factor_width(k)
        integer, intent(in) :: k

        factor_width = 1 + k + k*(k + 1)/2
    end function factor_width

    !> Keep record j (the next one) of the forward pass: its drive cycle, the R factor of the
    !> map from the frame of record j - 1 (for j = 1, the frame at the end of the transient)
    !> to that of record j, R = r_factor diag(exp(r_log)), and the frame Q_j (2n x k).
    subroutine clv_forward(pass, j, cycle, r_factor, r_log, frame, err)
        type(clv_pass_t), intent(inout) :: pass
        integer(i8), intent(in) :: j, cycle
        real(wp), intent(in) :: r_factor(:, :), r_log(:)
        real(wp), intent(in), contiguous :: frame(:, :)
        type(error_t), allocatable, intent(out) :: err
        integer :: i, p, at

        if (j /= pass%factors%count + 1) then
            call set_error(err, "clv: forward records out of order")
            return
        end if
        call scratch_next(pass%factors, at, err)
        if (allocated(err)) return
        associate (record => pass%factors%buffer(:, at))
            record(1) = real(cycle, wp)
            record(2:pass%k + 1) = r_log
            p = pass%k + 1
            do i = 1, pass%k
                record(p + 1:p + i) = r_factor(1:i, i)
                p = p + i
            end do
        end associate
        if (j > pass%kept) return
        call scratch_append(pass%frames, frame, err)
    end subroutine clv_forward

    !> Start the backward pass at the last record, with the first `unstable` vectors taken to
    !> span the unstable subspace (min_angle).
    subroutine clv_backward_begin(pass, unstable, err)
        type(clv_pass_t), intent(inout) :: pass
        integer, intent(in) :: unstable
        type(error_t), allocatable, intent(out) :: err

        if (pass%factors%count /= pass%records) then
            call set_error(err, "clv: the backward pass needs every record of the forward pass")
            return
        end if
        pass%unstable = unstable
        pass%c = initial_c(pass%k)
        pass%at = pass%records
        allocate (pass%total(pass%k))
        pass%total = 0
        call blocking_start(pass%blocks, pass%k, pass%kept)
        allocate (pass%vectors(2*pass%n, pass%k, pass%r), pass%saved_cycle(pass%r))
    end subroutine clv_backward_begin

    !> The next block of per-record numbers, going backwards (count = 0: the pass is done).
    !> The records without vectors at the end are passed through first.
    subroutine clv_backward_rows(pass, rows, err)
        type(clv_pass_t), intent(inout) :: pass
        type(clv_rows_t), intent(out) :: rows
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: hi, lo, j, cycle
        integer :: per_block

        rows%total = pass%kept
        do while (pass%at > pass%kept)
            call step_back(pass, cycle, err)
            if (allocated(err)) return
        end do
        if (pass%at == 0) return
        per_block = int(max(1_i8, rows_bytes/(8_i8*(pass%k + pass%m*pass%n + 2))))
        hi = pass%at
        lo = max(1_i8, hi - per_block + 1)
        rows%first = lo
        rows%count = int(hi - lo + 1)
        allocate (rows%cycle(rows%count), rows%ipr(pass%k, rows%count), &
                  rows%site_weight(pass%n, pass%m, rows%count), rows%min_angle(rows%count))
        do j = hi, lo, -1
            call vectors_at(pass, rows, int(j - lo) + 1, err)
            if (allocated(err)) return
            call step_back(pass, cycle, err)
            if (allocated(err)) return
            rows%cycle(j - lo + 1) = cycle
            if (j > pass%kept - pass%r) pass%saved_cycle(j - (pass%kept - pass%r)) = cycle
        end do
    end subroutine clv_backward_rows

    !> The vectors V_j = Q_j C_j of record j = pass%at, and their numbers into row i.
    subroutine vectors_at(pass, rows, i, err)
        type(clv_pass_t), intent(inout) :: pass
        type(clv_rows_t), intent(inout) :: rows
        integer, intent(in) :: i
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: s
        integer :: at

        call scratch_find(pass%frames, pass%at, at, err)
        if (allocated(err)) return
        call upper_product(pass%frames%buffer(:, at), pass%c, pass%v)
        call vector_numbers(pass%v, rows%ipr(:, i), rows%site_weight(:, :, i))
        rows%min_angle(i) = unstable_angle(pass%c, pass%unstable)
        s = pass%at - (pass%kept - pass%r)
        if (s >= 1) pass%vectors(:, :, s) = pass%v
    end subroutine vectors_at

    !> C_(at-1) from C_at by R_at, the growth of each vector over that step added when record
    !> `at` has vectors; `cycle` is record at's drive cycle.
    subroutine step_back(pass, cycle, err)
        type(clv_pass_t), intent(inout) :: pass
        integer(i8), intent(out) :: cycle
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: growth(pass%k)
        integer :: i, p, at

        call scratch_find(pass%factors, pass%at, at, err)
        if (allocated(err)) return
        associate (record => pass%factors%buffer(:, at))
            cycle = nint(record(1), i8)
            pass%r_log = record(2:pass%k + 1)
            p = pass%k + 1
            do i = 1, pass%k
                pass%r_s(1:i, i) = record(p + 1:p + i)
                p = p + i
            end do
        end associate
        call backward_step(pass%r_s, pass%r_log, pass%c, growth)
        if (pass%at <= pass%kept) then
            pass%total = pass%total + growth
            call blocking_add(pass%blocks, growth)
        end if
        pass%at = pass%at - 1
    end subroutine step_back

    !> One backward step: c := R^-1 c with unit columns, for R = r_s diag(exp(r_log)) upper
    !> triangular; `growth` gets ln of the factor by which the forward map stretches each
    !> vector (minus ln of its column's length before normalisation).
    subroutine backward_step(r_s, r_log, c, growth)
        real(wp), intent(in) :: r_s(:, :), r_log(:)
        real(wp), intent(inout), contiguous :: c(:, :)
        real(wp), intent(out) :: growth(:)
        real(wp) :: low, length(size(c, 2)), scale(size(c, 1))
        integer :: j

        call solve_upper_triangle(r_s, c)
        ! R^-1 = exp(-low) diag(exp(-(r_log - low))) r_s^-1, each factor <= 1
        low = minval(r_log)
        scale = exp(low - r_log)
        do j = 1, size(c, 2)
            c(1:j, j) = c(1:j, j)*scale(1:j)
        end do
        call triangle_squares(c, length)
        do j = 1, size(c, 2)
            length(j) = sqrt(length(j))
            c(1:j, j) = c(1:j, j)/length(j)
            growth(j) = low - log(length(j))
        end do
    end subroutine backward_step

    !> The exponents, their standard errors (by blocking the per-record growths, at the block
    !> size where the error levels off) and the saved vectors, once the backward pass is done.
    pure function clv_result(pass) result(res)
        type(clv_pass_t), intent(in) :: pass
        type(clv_result_t) :: res
        real(wp) :: err(pass%k)

        res%kept = pass%kept
        res%transient = int(pass%records - pass%kept)
        res%unstable = pass%unstable
        res%exponents = pass%total/max(1_i8, pass%kept)/log(2.0_wp)
        allocate (res%stderr_block(pass%k))
        call blocking_error(pass%blocks, err, res%stderr_block)
        res%stderr = err/log(2.0_wp)
        res%vectors = pass%vectors
        res%saved_cycle = pass%saved_cycle
    end function clv_result

    !> Close (and delete) the scratch files.
    subroutine clv_close(pass)
        type(clv_pass_t), intent(inout) :: pass

        call scratch_close(pass%factors)
        call scratch_close(pass%frames)
    end subroutine clv_close

    !> P := R P for upper triangular R (only its upper triangle is read) and P = p
    !> diag(exp(p_log)): p gets unit columns again, their lengths go to p_log. (The product of
    !> the R factors of the engine's re-orthonormalisations between two QR steps.)
    pure subroutine fold_upper(r, p, p_log)
        real(wp), intent(in) :: r(:, :)
        real(wp), intent(inout) :: p(:, :), p_log(:)
        real(wp) :: column(size(p, 1)), length
        integer :: j, l

        do j = 1, size(p, 2)
            column = 0
            do l = 1, j
                column(1:l) = column(1:l) + r(1:l, l)*p(l, j)
            end do
            length = norm2(column(1:j))
            p(1:j, j) = column(1:j)/length
            p_log(j) = p_log(j) + log(length)
        end do
    end subroutine fold_upper

    !> A generic upper triangular k x k matrix with unit columns, where the backward pass
    !> starts: entries depend on (i, j) only, so the first columns are the same whatever k.
    pure function initial_c(k) result(c)
        integer, intent(in) :: k
        real(wp), allocatable :: c(:, :)
        real(wp) :: h
        integer :: i, j

        allocate (c(k, k))
        c = 0
        do j = 1, k
            do i = 1, j - 1
                h = sin(39.3468_wp*i + 11.135_wp*j)*43758.5453_wp
                c(i, j) = h - floor(h) - 0.5_wp
            end do
            c(j, j) = 1
            c(1:j, j) = c(1:j, j)/norm2(c(1:j, j))
        end do
    end function initial_c

    !> Per-oscillator weight of a tangent vector v(2n) (rows x(1), v(1), x(2), ...):
    !> w_i = x_i**2 + v_i**2, normalised to sum 1.
    pure function site_weights(v) result(w)
        real(wp), intent(in) :: v(:)
        real(wp) :: w(size(v)/2)
        integer :: i

        do i = 1, size(w)
            w(i) = v(2*i - 1)**2 + v(2*i)**2
        end do
        w = w/sum(w)
    end function site_weights

    !> The smallest angle (radians) between the span of the first u vectors and each of the
    !> others, for vectors V = Q C with Q orthonormal and C upper triangular: the span of the
    !> first u is that of Q's first u columns, so the angle of vector s is
    !> atan2(|C(u+1:s, s)|, |C(1:u, s)|). NaN when u = 0 or u = k (no such pair).
    pure real(wp) function unstable_angle(c, u) result(angle)
        real(wp), intent(in) :: c(:, :)
        integer, intent(in) :: u
        real(wp) :: inside(size(c, 2) - u), outside(size(c, 2) - u)
        integer :: s

        angle = ieee_value(1.0_wp, ieee_quiet_nan)
        if (u < 1 .or. u >= size(c, 2)) return
        call column_squares(c(1:u, u + 1:), inside)
        call triangle_squares(c(u + 1:, u + 1:), outside)
        angle = huge(1.0_wp)
        ! (scalar atan2: the vector one of glibc's libmvec, which gfortran calls in a
        ! vectorised loop, rounds differently)
        !GCC$ novector
        do s = 1, size(c, 2) - u
            angle = min(angle, atan2(sqrt(outside(s)), sqrt(inside(s))))
        end do
    end function unstable_angle

    !> The numbers of the vectors v(2n, k) (rows x(1), v(1), x(2), ...): each column
    !> normalised, its inverse participation ratio ipr(k) (the sum of its squared site
    !> weights) and the site weights of the first size(weight, 2) columns, weight(n, :).
    pure subroutine vector_numbers(v, ipr, weight)
        real(wp), intent(inout) :: v(:, :)
        real(wp), intent(out) :: ipr(:), weight(:, :)
        real(wp) :: length(size(v, 2)), w(size(v, 1)/2, size(v, 2)), total(size(v, 2))
        integer :: l, i

        call column_squares(v, length)
        do l = 1, size(v, 2)
            v(:, l) = v(:, l)/sqrt(length(l))
            do i = 1, size(w, 1)
                w(i, l) = v(2*i - 1, l)**2 + v(2*i, l)**2
            end do
        end do
        call column_sums(w, total)
        do l = 1, size(v, 2)
            w(:, l) = w(:, l)/total(l)
        end do
        call column_squares(w, ipr)
        weight = w(:, :size(weight, 2))
    end subroutine vector_numbers

    ! The column sums below are those of SUM, each in row order from zero, so bit for bit the
    ! same, but four columns at a time: four independent chains of additions, which the
    ! processor overlaps, where one column's chain makes each addition wait for the last.

    !> s(l) = sum(a(:, l)**2) for every column l.
    pure subroutine column_squares(a, s)
        real(wp), intent(in) :: a(:, :)
        real(wp), intent(out) :: s(:)
        real(wp) :: s1, s2, s3, s4
        integer :: i, l

        do l = 1, size(a, 2) - 3, 4
            s1 = 0
            s2 = 0
            s3 = 0
            s4 = 0
            do i = 1, size(a, 1)
                s1 = s1 + a(i, l)**2
                s2 = s2 + a(i, l + 1)**2
                s3 = s3 + a(i, l + 2)**2
                s4 = s4 + a(i, l + 3)**2
            end do
            s(l:l + 3) = [s1, s2, s3, s4]
        end do
        do l = size(a, 2) - modulo(size(a, 2), 4) + 1, size(a, 2)
            s(l) = sum(a(:, l)**2)
        end do
    end subroutine column_squares

    !> s(l) = sum(a(:, l)) for every column l.
    pure subroutine column_sums(a, s)
        real(wp), intent(in) :: a(:, :)
        real(wp), intent(out) :: s(:)
        real(wp) :: s1, s2, s3, s4
        integer :: i, l

        do l = 1, size(a, 2) - 3, 4
            s1 = 0
            s2 = 0
            s3 = 0
            s4 = 0
            do i = 1, size(a, 1)
                s1 = s1 + a(i, l)
                s2 = s2 + a(i, l + 1)
                s3 = s3 + a(i, l + 2)
                s4 = s4 + a(i, l + 3)
            end do
            s(l:l + 3) = [s1, s2, s3, s4]
        end do
        do l = size(a, 2) - modulo(size(a, 2), 4) + 1, size(a, 2)
            s(l) = sum(a(:, l))
        end do
    end subroutine column_sums

    !> s(l) = sum(a(1:l, l)**2) for every column l of the upper triangle of a.
    pure subroutine triangle_squares(a, s)
        real(wp), intent(in) :: a(:, :)
        real(wp), intent(out) :: s(:)
        real(wp) :: s1, s2, s3, s4
        integer :: i, l

        do l = 1, size(a, 2) - 3, 4
            s1 = 0
            s2 = 0
            s3 = 0
            s4 = 0
            do i = 1, l
                s1 = s1 + a(i, l)**2
                s2 = s2 + a(i, l + 1)**2
                s3 = s3 + a(i, l + 2)**2
                s4 = s4 + a(i, l + 3)**2
            end do
            s2 = s2 + a(l + 1, l + 1)**2
            s3 = s3 + a(l + 1, l + 2)**2
            s4 = s4 + a(l + 1, l + 3)**2
            s3 = s3 + a(l + 2, l + 2)**2
            s4 = s4 + a(l + 2, l + 3)**2
            s4 = s4 + a(l + 3, l + 3)**2
            s(l:l + 3) = [s1, s2, s3, s4]
        end do
        do l = size(a, 2) - modulo(size(a, 2), 4) + 1, size(a, 2)
            s(l) = sum(a(1:l, l)**2)
        end do
    end subroutine triangle_squares

end module chain_clv
