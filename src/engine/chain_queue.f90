!> The next event time of every bond (0..n), in blocks of `block` consecutive bonds: each block
!> knows its earliest (time, bond), and a tournament tree over the blocks holds the earliest of
!> each pair of subtrees, up to the root, the earliest of all. An impact reschedules two or
!> three neighbouring bonds, nearly always in one block: the block's earliest is found again by
!> a scan of its times (a few cache lines, vectorised) and the path from its leaf to the root is
!> replayed, one comparison with the sibling per level. The number of levels is fixed by the
!> number of blocks (the leaves are padded to a power of two) and each level keeps the earlier
!> of two entries by selection, not by a branch, so an update costs the same at every event.
!> (The 4-ary heap of blocks this replaces moved the top block, rescheduled at nearly every
!> impact, down through about four levels, choosing among four children by comparisons whose
!> outcome was random: that grew with n.) A chain of at most `block` bonds is one block and
!> needs no tree. Ties are broken by the bond index (the lowest bond of a block first, the
!> lowest block first), which makes the order of events independent of how the queue was
!> filled; the engine orders the bonds due at exactly one time by its own rule (`queue_ties`
!> lists them).
!> Implements docs/model.md sections 2.4 (the event schedule) and 5.6 (ties between events).
module chain_queue
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_positive_inf
    use chain_kinds, only: wp
    implicit none
    private
    public :: queue_t, queue_init, queue_set, queue_top, queue_shift, queue_ties

    integer, parameter :: block = 32 !! bonds per block: four cache lines of times

    !> The tree is stored as an array: node 1 is the root, node j has children 2j and 2j + 1,
    !> and block b is leaf `leaves + b - 1`. Each node holds the block whose (earliest time,
    !> block) is the earliest of the leaves below it, and whether another block below is due
    !> at that time too (so the top knows it is tied without a walk), in one integer, 2 block
    !> + tie: one load per node, and half the cache lines of two arrays (the replay took 2.8
    !> first-level misses per impact at n = 16384 with two, 1.5 with one). The leaves past the
    !> last block stand for blocks due at +infinity with numbers past the last: a block of
    !> bonds, due no later and left of them, always comes before them (a tie goes to the left).
    type :: queue_t
        integer :: size = 0               !! bonds
        integer :: blocks = 0             !! blocks: bond j is in block j/block + 1
        integer :: leaves = 1             !! leaves of the tree: blocks, rounded up to 2**levels
        integer :: levels = 0             !! levels above the leaves
        real(wp), allocatable :: time(:)  !! time(0:size-1): event time of each bond
        integer, allocatable :: first(:)  !! first(1:blocks): the block's earliest bond
        real(wp), allocatable :: key(:)   !! key(1:leaves): the block's earliest time
        integer, allocatable :: node(:)   !! node(1:2*leaves-1): 2 w + t, w the earliest block
                                          !! below, t = 1 if another is due then, else 0
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
        do while (q%leaves < q%blocks)
            q%leaves = 2*q%leaves
            q%levels = q%levels + 1
        end do
        allocate (q%time(0:n_bonds - 1), q%first(q%blocks), q%key(q%leaves), &
                  q%node(2*q%leaves - 1))
        q%time = never
        q%key(:q%blocks) = never
        q%key(q%blocks + 1:) = ieee_value(never, ieee_positive_inf)
        do b = 1, q%blocks
            q%first(b) = (b - 1)*block
        end do
        do b = 1, q%leaves
            q%node(q%leaves + b - 1) = 2*b
        end do
        call settle(q)
    end subroutine queue_init

    !> Bond with the earliest event, and its time; `tied`: another bond is due at that time.
    pure subroutine queue_top(q, bond, time, tied)
        type(queue_t), intent(in) :: q
        integer, intent(out) :: bond
        real(wp), intent(out) :: time
        logical, intent(out), optional :: tied
        integer :: b, last

        if (q%blocks == 1) then
            call block_earliest(q, 1, bond, time)
        else
            b = ishft(q%node(1), -1)
            bond = q%first(b)
            time = q%key(b)
        end if
        if (.not. present(tied)) return
        ! the block's later bonds (its earliest is its lowest bond due then), or another block
        b = bond/block + 1
        last = min(b*block, q%size) - 1
        tied = any(q%time(bond + 1:last) == time) .or. btest(q%node(1), 0)
    end subroutine queue_top

    !> The bonds whose event is due at exactly the earliest time (ties[1:count], in increasing
    !> order): those of the blocks whose earliest is then, found from the root down through the
    !> nodes whose key is the minimum (a node's key is the minimum only if its parent's is).
    pure subroutine queue_ties(q, ties, count)
        type(queue_t), intent(in) :: q
        integer, intent(inout) :: ties(:) !! room for every bond
        integer, intent(out) :: count
        integer :: bond, b, j, depth
        integer :: pending(q%levels + 1) !! depth first, at most one right child per level
        real(wp) :: earliest

        call queue_top(q, bond, earliest)
        count = 0
        if (q%blocks == 1) then
            call add_due(q, 1, earliest, ties, count)
            return
        end if
        depth = 1
        pending(1) = 1
        do while (depth > 0)
            j = pending(depth)
            depth = depth - 1
            if (j >= q%leaves) then
                b = j - q%leaves + 1
                if (b <= q%blocks) call add_due(q, b, earliest, ties, count)
                cycle
            end if
            ! the right child first onto the stack, so the left, lower blocks come out first
            if (q%key(ishft(q%node(2*j + 1), -1)) == earliest) then
                depth = depth + 1
                pending(depth) = 2*j + 1
            end if
            if (q%key(ishft(q%node(2*j), -1)) == earliest) then
                depth = depth + 1
                pending(depth) = 2*j
            end if
        end do
    end subroutine queue_ties

    !> Append the bonds of block b due at `time` to ties[1:count].
    pure subroutine add_due(q, b, time, ties, count)
        type(queue_t), intent(in) :: q
        integer, intent(in) :: b
        real(wp), intent(in) :: time
        integer, intent(inout) :: ties(:), count
        integer :: bond

        do bond = (b - 1)*block, min(b*block, q%size) - 1
            if (q%time(bond) /= time) cycle
            count = count + 1
            ties(count) = bond
        end do
    end subroutine add_due

    !> Set the event time of `bond`; its block's earliest changes if the bond comes before it
    !> now, or was it; the block's path to the root is then replayed.
    pure subroutine queue_set(q, bond, time)
        type(queue_t), intent(inout) :: q
        integer, intent(in) :: bond
        real(wp), intent(in) :: time
        integer :: b, first
        real(wp) :: old, new

        q%time(bond) = time
        if (q%blocks == 1) return
        b = bond/block + 1
        old = q%key(b)
        if (earlier(time, bond, old, q%first(b))) then
            q%first(b) = bond
            if (time /= old) call replay(q, b, time)
        else if (bond == q%first(b)) then
            call block_earliest(q, b, first, new)
            q%first(b) = first
            if (new /= old) call replay(q, b, new)
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

    !> Subtract `dt` from every time: the start of a new drive cycle. The order is unchanged,
    !> but two times apart by less than the rounding of the difference may now be equal, so
    !> the tree is settled again (one pass over its inner nodes, fewer than n/16, per cycle).
    pure subroutine queue_shift(q, dt, never)
        type(queue_t), intent(inout) :: q
        real(wp), intent(in) :: dt, never
        where (q%time < never) q%time = q%time - dt
        where (q%key < never) q%key = q%key - dt
        if (q%blocks > 1) call settle(q)
    end subroutine queue_shift

    !> Every inner node from its children, from the leaves up: the earlier (a tie to the
    !> left, lower blocks), and whether another block below is due at its time.
    pure subroutine settle(q)
        type(queue_t), intent(inout) :: q
        integer :: j, left, right
        real(wp) :: k_left, k_right

        do j = q%leaves - 1, 1, -1
            left = q%node(2*j)
            right = q%node(2*j + 1)
            k_left = q%key(ishft(left, -1))
            k_right = q%key(ishft(right, -1))
            q%node(j) = merge(right, left, k_right < k_left)
            if (k_left == k_right) q%node(j) = ior(q%node(j), 1)
        end do
    end subroutine settle

    !> Does (time ta, bond a) come before (tb, b)? Ties go to the lower bond index.
    pure logical function earlier(ta, a, tb, b)
        real(wp), intent(in) :: ta, tb
        integer, intent(in) :: a, b
        earlier = ta < tb .or. (ta == tb .and. a < b)
    end function earlier

    !> Block b is now due at t: from its leaf up, each node on the path takes the earlier of
    !> the block coming up and its sibling's, and is tied if their times are equal or the
    !> earlier was tied below. The path is `levels` long whatever the times, and each node is
    !> chosen by a mask, not by a branch (gfortran compiles `merge` to one): the comparisons'
    !> outcomes, which are random, steer no jump, so the loop is always predicted. A tie goes
    !> to the left, lower, blocks: the sibling wins it when the path comes from the right
    !> (j odd).
    pure subroutine replay(q, b, t)
        type(queue_t), intent(inout) :: q
        integer, intent(in) :: b
        real(wp), intent(in) :: t
        integer :: j, level, up, sibling, equal, mask
        real(wp) :: k, ks

        q%key(b) = t
        j = q%leaves + b - 1
        k = t
        up = 2*b ! the entry coming up (a leaf is one block: no tie)
        do level = 1, q%levels
            sibling = q%node(ieor(j, 1))
            ks = q%key(ishft(sibling, -1))
            equal = merge(1, 0, ks == k)
            ! all ones if the sibling's block comes first, else zero
            mask = -ior(merge(1, 0, ks < k), iand(iand(j, 1), equal))
            k = min(ks, k) ! (only compared: the times kept are the blocks')
            up = ior(ior(iand(sibling, mask), iand(up, not(mask))), equal)
            j = ishft(j, -1)
            q%node(j) = up
        end do
    end subroutine replay

end module chain_queue
