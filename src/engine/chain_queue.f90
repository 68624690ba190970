!> The next event time of every bond (0..n), in blocks of `block` consecutive bonds: each block
!> knows its earliest (time, bond), and an indexed 4-ary min-heap orders the blocks by it. An
!> impact reschedules two or three neighbouring bonds, nearly always in one block: the block's
!> earliest is found again by a scan of its times (a few cache lines, vectorised) and the
!> block moves in a heap of n/32 entries, which stays in the first-level cache at any n. So an
!> impact costs about the same at n = 16 and n = 16384 (a heap of the bonds themselves grew
!> with log n and missed the cache once its arrays outgrew it). A chain of at most `block`
!> bonds is one block and needs no heap. Ties are broken by the bond index (the lowest bond of
!> a block first, the lowest block first), which makes the order of events independent of how
!> the queue was filled; the engine orders the bonds due at exactly one time by its own rule
!> (`queue_ties` lists them).
!> Implements docs/model.md sections 2.4 (the event schedule) and 5.6 (ties between events).
module chain_queue
    use chain_kinds, only: wp
    implicit none
    private
    public :: queue_t, queue_init, queue_set, queue_top, queue_shift, queue_ties

    integer, parameter :: arity = 4
    integer, parameter :: block = 32 !! bonds per block: four cache lines of times

    type :: queue_t
        integer :: size = 0               !! bonds
        integer :: blocks = 0             !! blocks: bond j is in block j/block + 1
        real(wp), allocatable :: time(:)  !! time(0:size-1): event time of each bond
        integer, allocatable :: first(:)  !! first(1:blocks): the block's earliest bond
        integer, allocatable :: heap(:)   !! heap(1:blocks): blocks in heap order
        real(wp), allocatable :: key(:)   !! key(1:blocks): their earliest times, side by side
                                          !! in heap order
        integer, allocatable :: slot(:)   !! slot(1:blocks): position of each block in heap
    end type queue_t

contains

    !> A queue for bonds 0..n_bonds-1, all at time `never`.
    pure subroutine queue_init(q, n_bonds, never)
        type(queue_t), intent(out) :: q
        integer, intent(in) :: n_bonds
        real(wp), intent(in) :: never
        integer :: b

        q%size = n_bonds
        q%blocks = max(1, (n_bonds + block - 1)/block)
        allocate (q%time(0:n_bonds - 1), q%first(q%blocks), q%heap(q%blocks), &
                  q%key(q%blocks), q%slot(q%blocks))
        q%time = never
        q%key = never
        do b = 1, q%blocks
            q%first(b) = (b - 1)*block
            q%heap(b) = b
            q%slot(b) = b
        end do
    end subroutine queue_init

    !> Bond with the earliest event, and its time; `tied`: another bond is due at that time.
    pure subroutine queue_top(q, bond, time, tied)
        type(queue_t), intent(in) :: q
        integer, intent(out) :: bond
        real(wp), intent(out) :: time
        logical, intent(out), optional :: tied
        integer :: j, b, last
        logical :: equal

        if (q%blocks == 1) then
            call block_earliest(q, 1, bond, time)
        else
            b = q%heap(1)
            bond = q%first(b)
            time = q%key(1)
        end if
        if (.not. present(tied)) return
        ! the block's later bonds (its earliest is its lowest bond due then), then the other
        ! blocks: a key equals the minimum only if its parent's does, so the root's children
        b = bond/block + 1
        last = min(b*block, q%size) - 1
        equal = any(q%time(bond + 1:last) == time)
        do j = 2, min(arity + 1, q%blocks)
            if (q%key(j) == time) equal = .true.
        end do
        tied = equal
    end subroutine queue_top

    !> The bonds whose event is due at exactly the earliest time (ties[1:count]): those of the
    !> blocks whose earliest is then, which sit in the heap's top (a node's key equals the
    !> minimum only if its parent's does).
    pure subroutine queue_ties(q, ties, count)
        type(queue_t), intent(in) :: q
        integer, intent(inout) :: ties(:) !! room for every bond
        integer, intent(out) :: count
        integer :: seen, j, c, bond, b, n_blocks
        integer :: due(q%blocks)
        real(wp) :: earliest

        call queue_top(q, bond, earliest)
        n_blocks = 1
        due(1) = 1
        if (q%blocks > 1) then
            seen = 0
            ! breadth first over heap positions; due holds positions until the end
            do while (seen < n_blocks)
                seen = seen + 1
                j = due(seen)
                do c = arity*(j - 1) + 2, min(arity*j + 1, q%blocks)
                    if (q%key(c) /= earliest) cycle
                    n_blocks = n_blocks + 1
                    due(n_blocks) = c
                end do
            end do
            due(:n_blocks) = q%heap(due(:n_blocks))
        end if
        count = 0
        do j = 1, n_blocks
            b = due(j)
            do bond = (b - 1)*block, min(b*block, q%size) - 1
                if (q%time(bond) /= earliest) cycle
                count = count + 1
                ties(count) = bond
            end do
        end do
    end subroutine queue_ties

    !> Set the event time of `bond`; its block's earliest changes if the bond comes before it
    !> now, or was it; the block then moves up (earlier) or down (later) in the heap.
    pure subroutine queue_set(q, bond, time)
        type(queue_t), intent(inout) :: q
        integer, intent(in) :: bond
        real(wp), intent(in) :: time
        integer :: b, first
        real(wp) :: old, new

        q%time(bond) = time
        if (q%blocks == 1) return
        b = bond/block + 1
        old = q%key(q%slot(b))
        if (earlier(time, bond, old, q%first(b))) then
            q%first(b) = bond
            if (time /= old) call sift_up(q, b, time)
        else if (bond == q%first(b)) then
            call block_earliest(q, b, first, new)
            q%first(b) = first
            if (new /= old) call sift_down(q, b, new)
        end if
    end subroutine queue_set

    !> The earliest (time, bond) of block b: the lowest bond due at the block's minimum time,
    !> by a minimum without branches (the compiler vectorises it; a scan that branches on each
    !> new earliest mispredicts at random positions), then the first bond due then.
    pure subroutine block_earliest(q, b, bond, time)
        type(queue_t), intent(in) :: q
        integer, intent(in) :: b
        integer, intent(out) :: bond
        real(wp), intent(out) :: time
        integer :: low, high, j

        low = (b - 1)*block
        high = min(b*block, q%size) - 1
        time = q%time(low)
        do j = low + 1, high
            time = min(time, q%time(j))
        end do
        bond = findloc(q%time(low:high), time, dim=1) - 1
        if (bond < 0) bond = 0 ! (not a number: no event can be due)
        bond = low + bond
        time = q%time(bond)
    end subroutine block_earliest

    !> Subtract `dt` from every time (order is unchanged): the start of a new drive cycle.
    pure subroutine queue_shift(q, dt, never)
        type(queue_t), intent(inout) :: q
        real(wp), intent(in) :: dt, never
        where (q%time < never) q%time = q%time - dt
        where (q%key < never) q%key = q%key - dt
    end subroutine queue_shift

    !> Does (time ta, bond a) come before (tb, b)? Ties go to the lower bond index.
    pure logical function earlier(ta, a, tb, b)
        real(wp), intent(in) :: ta, tb
        integer, intent(in) :: a, b
        earlier = ta < tb .or. (ta == tb .and. a < b)
    end function earlier

    !> Move block b, now due at t, up past every later parent (the parents shift down into
    !> the hole).
    pure subroutine sift_up(q, b, t)
        type(queue_t), intent(inout) :: q
        integer, intent(in) :: b
        real(wp), value :: t
        integer :: j, p, parent

        j = q%slot(b)
        do while (j > 1)
            p = (j - 2)/arity + 1
            parent = q%heap(p)
            if (.not. earlier(t, b, q%key(p), parent)) exit
            call place(q, j, parent, q%key(p))
            j = p
        end do
        call place(q, j, b, t)
    end subroutine sift_up

    !> Move block b, now due at t, down past every earlier child (the earliest child shifts up
    !> into the hole).
    pure subroutine sift_down(q, b, t)
        type(queue_t), intent(inout) :: q
        integer, intent(in) :: b
        real(wp), value :: t
        integer :: j, c, first, last, child

        j = q%slot(b)
        do
            first = arity*(j - 1) + 2
            if (first > q%blocks) exit
            last = min(first + arity - 1, q%blocks)
            child = first
            do c = first + 1, last
                if (earlier(q%key(c), q%heap(c), q%key(child), q%heap(child))) child = c
            end do
            if (.not. earlier(q%key(child), q%heap(child), t, b)) exit
            call place(q, j, q%heap(child), q%key(child))
            j = child
        end do
        call place(q, j, b, t)
    end subroutine sift_down

    !> Put block b, due at `time`, at heap position j.
    pure subroutine place(q, j, b, time)
        type(queue_t), intent(inout) :: q
        integer, intent(in) :: j
        integer, value :: b
        real(wp), value :: time

        q%heap(j) = b
        q%key(j) = time
        q%slot(b) = j
    end subroutine place

end module chain_queue
