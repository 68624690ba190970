!> An indexed 4-ary min-heap of the next event time of every bond (0..n), so that an impact
!> costs O(log n) whatever the length of the chain. Four children per node halve the depth of
!> a binary heap, and their keys share a cache line: a long chain's updates, which mostly
!> move a bond down, miss the cache half as often. Ties are broken by the bond index, which
!> makes the order of events independent of how the heap was filled; the engine orders the
!> bonds due at exactly one time by its own rule (`queue_ties` lists them).
!>
!> A short queue (up to `scan_limit` bonds) keeps no heap: an update only stores the time, and
!> the top is found by a scan of the times in bond order. An event updates two or three bonds
!> and asks for the top once, and a scan of a few cache lines costs less than keeping a heap
!> in order (the paper's n = 16: 17 bonds). Both forms give the same top, ties included.
!> Implements docs/model.md sections 2.4 (the event schedule) and 5.6 (ties between events).
module chain_queue
    use chain_kinds, only: wp
    implicit none
    private
    public :: queue_t, queue_init, queue_set, queue_top, queue_shift, queue_ties

    integer, parameter :: arity = 4
    integer, parameter :: scan_limit = 32 !! queues of up to this many bonds keep no heap

    type :: queue_t
        integer :: size = 0
        logical :: scan = .false.        !! a short queue: the top is found by a scan of time
        real(wp), allocatable :: time(:) !! time(0:n): event time of each bond
        integer, allocatable :: heap(:)  !! heap(1:size): bonds in heap order
        real(wp), allocatable :: key(:)  !! key(1:size): their times, side by side in heap
                                         !! order (long chains: no cache miss per comparison)
        integer, allocatable :: slot(:)  !! slot(0:n): position of each bond in heap
    end type queue_t

contains

    !> A queue for bonds 0..n_bonds-1, all at time `never`.
    pure subroutine queue_init(q, n_bonds, never)
        type(queue_t), intent(out) :: q
        integer, intent(in) :: n_bonds
        real(wp), intent(in) :: never
        integer :: j

        q%size = n_bonds
        q%scan = n_bonds <= scan_limit
        allocate (q%time(0:n_bonds - 1), q%heap(n_bonds), q%key(n_bonds), q%slot(0:n_bonds - 1))
        q%time = never
        q%key = never
        do j = 1, n_bonds
            q%heap(j) = j - 1
            q%slot(j - 1) = j
        end do
    end subroutine queue_init

    !> Bond with the earliest event, and its time; `tied`: another bond is due at that time.
    pure subroutine queue_top(q, bond, time, tied)
        type(queue_t), intent(in) :: q
        integer, intent(out) :: bond
        real(wp), intent(out) :: time
        logical, intent(out), optional :: tied
        integer :: j, first
        real(wp) :: earliest
        logical :: equal

        if (q%scan) then
            ! the earliest by a minimum without branches (the compiler vectorises it; a scan
            ! that branches on each new earliest mispredicts at random positions), then the
            ! first bond due then: the lowest bond wins a tie, as in the heap; a tie is
            ! another bond due then, after it
            earliest = q%time(0)
            do j = 1, q%size - 1
                earliest = min(earliest, q%time(j))
            end do
            first = findloc(q%time, earliest, dim=1) - 1
            if (first < 0) first = 0 ! (not a number: no event can be due)
            bond = first
            time = q%time(first)
            equal = any(q%time(first + 1:) == earliest)
        else
            bond = q%heap(1)
            time = q%key(1)
            ! a key equals the minimum only if its parent's does: look at the root's children
            equal = .false.
            do j = 2, min(arity + 1, q%size)
                if (q%key(j) == time) equal = .true.
            end do
        end if
        if (present(tied)) tied = equal
    end subroutine queue_top

    !> The bonds whose event is due at exactly the earliest time (ties[1:count]). Those keys
    !> sit in the heap's top: a node's key equals the minimum only if its parent's does.
    pure subroutine queue_ties(q, ties, count)
        type(queue_t), intent(in) :: q
        integer, intent(inout) :: ties(:) !! room for every bond
        integer, intent(out) :: count
        integer :: seen, j, c
        real(wp) :: first

        if (q%scan) then
            first = minval(q%time)
            count = 0
            do j = 0, q%size - 1
                if (q%time(j) /= first) cycle
                count = count + 1
                ties(count) = j
            end do
            return
        end if
        count = 1
        ties(1) = 1
        seen = 0
        ! breadth first over heap positions; ties holds positions until the end
        do while (seen < count)
            seen = seen + 1
            j = ties(seen)
            do c = arity*(j - 1) + 2, min(arity*j + 1, q%size)
                if (q%key(c) /= q%key(1)) cycle
                count = count + 1
                ties(count) = c
            end do
        end do
        ties(:count) = q%heap(ties(:count))
    end subroutine queue_ties

    !> Set the event time of `bond` and restore the heap order: an earlier time can only move
    !> the bond up, a later one only down.
    pure subroutine queue_set(q, bond, time)
        type(queue_t), intent(inout) :: q
        integer, intent(in) :: bond
        real(wp), intent(in) :: time
        real(wp) :: old

        if (q%scan) then
            q%time(bond) = time
            return
        end if
        old = q%time(bond)
        if (time == old) return
        q%time(bond) = time
        if (time < old) then
            call sift_up(q, bond)
        else
            call sift_down(q, bond)
        end if
    end subroutine queue_set

    !> Subtract `dt` from every time (order is unchanged): the start of a new drive cycle.
    pure subroutine queue_shift(q, dt, never)
        type(queue_t), intent(inout) :: q
        real(wp), intent(in) :: dt, never
        where (q%time < never) q%time = q%time - dt
        if (.not. q%scan) then
            where (q%key < never) q%key = q%key - dt
        end if
    end subroutine queue_shift

    !> Does (time ta, bond a) come before (tb, b)? Ties go to the lower bond index.
    pure logical function earlier(ta, a, tb, b)
        real(wp), intent(in) :: ta, tb
        integer, intent(in) :: a, b
        earlier = ta < tb .or. (ta == tb .and. a < b)
    end function earlier

    !> Move `bond` up past every later parent (the parents shift down into the hole).
    pure subroutine sift_up(q, bond)
        type(queue_t), intent(inout) :: q
        integer, intent(in) :: bond
        integer :: j, p, parent
        real(wp) :: t

        t = q%time(bond)
        j = q%slot(bond)
        do while (j > 1)
            p = (j - 2)/arity + 1
            parent = q%heap(p)
            if (.not. earlier(t, bond, q%key(p), parent)) exit
            call place(q, j, parent, q%key(p))
            j = p
        end do
        call place(q, j, bond, t)
    end subroutine sift_up

    !> Move `bond` down past every earlier child (the earliest child shifts up into the hole).
    pure subroutine sift_down(q, bond)
        type(queue_t), intent(inout) :: q
        integer, intent(in) :: bond
        integer :: j, c, first, last, child
        real(wp) :: t

        t = q%time(bond)
        j = q%slot(bond)
        do
            first = arity*(j - 1) + 2
            if (first > q%size) exit
            last = min(first + arity - 1, q%size)
            child = first
            do c = first + 1, last
                if (earlier(q%key(c), q%heap(c), q%key(child), q%heap(child))) child = c
            end do
            if (.not. earlier(q%key(child), q%heap(child), t, bond)) exit
            call place(q, j, q%heap(child), q%key(child))
            j = child
        end do
        call place(q, j, bond, t)
    end subroutine sift_down

    !> Put `bond`, due at `time`, at heap position j.
    pure subroutine place(q, j, bond, time)
        type(queue_t), intent(inout) :: q
        integer, intent(in) :: j
        integer, value :: bond
        real(wp), value :: time

        q%heap(j) = bond
        q%key(j) = time
        q%slot(bond) = j
    end subroutine place

end module chain_queue
