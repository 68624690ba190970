!> Standard errors of the mean of a correlated series by blocking (Flyvbjerg and Petersen,
!> J. Chem. Phys. 91, 461, 1989), read off where they stop growing with the block size
!> (docs/model.md sections 7.4 and 14.2): the growth rates of the QR frame's columns and of
!> covariant vectors.
!>
!> Consecutive values are averaged in pairs, the pairs' means in pairs again, and so on: level
!> l holds the means of blocks of 2**l values, and the naive standard error of the mean from
!> the blocks of level l, se(l), changes with l while the blocks are shorter than the series'
!> correlation time and then stays level (a plateau) within its own uncertainty
!> se(l) / sqrt(2 (M(l) - 1)), M(l) the blocks of the level. Only sums are kept per level (and
!> the one unpaired mean waiting for its partner), so memory is O(log N) per series whatever
!> its length N; every series is shifted by its first value, so that the sums of squares do
!> not cancel a large mean.
module chain_blocking
    use chain_kinds, only: wp, i8
    implicit none
    private
    public :: blocking_t, blocking_start, blocking_add, blocking_error, min_blocks
    public :: blocking_pack, blocking_unpack

    !> Levels with fewer blocks than this are not used (their errors scatter by more than 18 %).
    integer, parameter :: min_blocks = 16

    !> m series of at most `capacity` values, blocked side by side.
    type :: blocking_t
        integer(i8), allocatable :: count(:)        !! count(0:L): complete blocks per level
        real(wp), allocatable :: shift(:)           !! shift(m): each series' first value
        real(wp), allocatable :: total(:, :)        !! total(m, 0:L): sum of the block means
        real(wp), allocatable :: squares(:, :)      !! squares(m, 0:L): sum of their squares
        real(wp), allocatable :: waiting(:, :)      !! waiting(m, 0:L): an unpaired mean
    end type blocking_t

contains

    !> Room for m series of up to `capacity` values each.
    pure subroutine blocking_start(b, m, capacity)
        type(blocking_t), intent(out) :: b
        integer, intent(in) :: m
        integer(i8), intent(in) :: capacity
        integer :: levels

        levels = 0
        do while (2_i8**(levels + 1) <= capacity)
            levels = levels + 1
        end do
        allocate (b%count(0:levels), b%shift(m), b%total(m, 0:levels), b%squares(m, 0:levels), &
                  b%waiting(m, 0:levels))
        b%count = 0
        b%shift = 0
        b%total = 0
        b%squares = 0
        b%waiting = 0
    end subroutine blocking_start

    !> The next value of each series.
    pure subroutine blocking_add(b, x)
        type(blocking_t), intent(inout) :: b
        real(wp), intent(in) :: x(:)
        real(wp) :: mean(size(x))
        integer :: l

        if (b%count(0) == 0) b%shift = x
        mean = x - b%shift
        do l = 0, ubound(b%count, 1)
            b%count(l) = b%count(l) + 1
            b%total(:, l) = b%total(:, l) + mean
            b%squares(:, l) = b%squares(:, l) + mean**2
            ! the first of a pair waits; the second makes the pair's mean one level up
            if (modulo(b%count(l), 2_i8) == 1) then
                b%waiting(:, l) = mean
                return
            end if
            mean = (b%waiting(:, l) + mean)/2
        end do
    end subroutine blocking_add

    !> Standard error of the mean of each series at its plateau: at the smallest level l
    !> (of at least min_blocks blocks) from which every larger level's error differs from
    !> se(l) by at most twice their combined uncertainty; `block` gets 2**l, the values per
    !> block used. (se(l) grows with l for positively correlated values; it falls for values
    !> that anticorrelate, as the growths of a vector from record to record do when part of
    !> them is a difference of consecutive terms, which telescopes in the mean.)
    !> With fewer than 2 min_blocks values: the naive error of the single values (block 1).
    pure subroutine blocking_error(b, err, block)
        type(blocking_t), intent(in) :: b
        real(wp), intent(out) :: err(:)
        integer(i8), intent(out) :: block(:)
        real(wp) :: se(0:ubound(b%count, 1)), spread(0:ubound(b%count, 1))
        integer :: i, l, top, at

        top = 0
        do l = 1, ubound(b%count, 1)
            if (b%count(l) >= min_blocks) top = l
        end do
        do i = 1, size(err)
            do l = 0, top
                se(l) = level_error(b, i, l)
                spread(l) = se(l)/sqrt(2*real(max(2_i8, b%count(l)) - 1, wp))
            end do
            at = top
            do l = 0, top
                if (all(abs(se(l + 1:top) - se(l)) <= &
                        2*sqrt(spread(l)**2 + spread(l + 1:top)**2))) then
                    at = l
                    exit
                end if
            end do
            err(i) = se(at)
            block(i) = 2_i8**at
        end do
    end subroutine blocking_error

    !> The blocks as plain arrays, appended to `ints` and `reals` (to save a stopped run), and
    !> `blocking_unpack` back into blocks started for the same m and capacity.
    pure subroutine blocking_pack(b, ints, reals)
        type(blocking_t), intent(in) :: b
        integer(i8), allocatable, intent(inout) :: ints(:)
        real(wp), allocatable, intent(inout) :: reals(:)

        ints = [ints, b%count]
        reals = [reals, b%shift, reshape(b%total, [size(b%total)]), &
                 reshape(b%squares, [size(b%squares)]), reshape(b%waiting, [size(b%waiting)])]
    end subroutine blocking_pack

    !> Blocks `b` (from blocking_start) filled from ints(ip + 1:) and reals(rp + 1:), the
    !> positions moved past what was read; info = 1 if the arrays are too short or a count is
    !> negative, 0 otherwise.
    pure subroutine blocking_unpack(ints, reals, ip, rp, b, info)
        integer(i8), intent(in) :: ints(:)
        real(wp), intent(in) :: reals(:)
        integer, intent(inout) :: ip, rp
        type(blocking_t), intent(inout) :: b
        integer, intent(out) :: info
        integer :: levels, m, nl

        info = 1
        levels = size(b%count)
        m = size(b%shift)
        nl = m*levels
        if (size(ints) < ip + levels .or. size(reals) < rp + m + 3*nl) return
        if (any(ints(ip + 1:ip + levels) < 0)) return
        b%count = ints(ip + 1:ip + levels)
        ip = ip + levels
        b%shift = reals(rp + 1:rp + m)
        b%total = reshape(reals(rp + m + 1:rp + m + nl), shape(b%total))
        b%squares = reshape(reals(rp + m + nl + 1:rp + m + 2*nl), shape(b%squares))
        b%waiting = reshape(reals(rp + m + 2*nl + 1:rp + m + 3*nl), shape(b%waiting))
        rp = rp + m + 3*nl
        info = 0
    end subroutine blocking_unpack

    !> The naive standard error of the mean of series i from the block means of level l.
    pure real(wp) function level_error(b, i, l) result(se)
        type(blocking_t), intent(in) :: b
        integer, intent(in) :: i, l
        real(wp) :: mean, variance
        integer(i8) :: m

        se = 0
        m = b%count(l)
        if (m < 2) return
        mean = b%total(i, l)/m
        variance = max(0.0_wp, (b%squares(i, l) - m*mean**2)/(m - 1))
        se = sqrt(variance/m)
    end function level_error

end module chain_blocking
