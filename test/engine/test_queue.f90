!> The event queue against a brute-force minimum: after every update of a random bond, with
!> ties in time, the top is the earliest (time, bond) pair and the ties are the bonds due
!> then, for queue sizes of one block (no tree), either side of one and two blocks, and enough
!> blocks for a tree of several levels, full or padded with empty leaves.
module test_queue
    use chain_kinds, only: wp
    use chain_queue, only: queue_t, queue_init, queue_set, queue_top, queue_shift, queue_ties
    use testing, only: tally_t, check
    implicit none
    private
    public :: run_queue_tests

contains

    subroutine run_queue_tests(t)
        type(tally_t), intent(inout) :: t
        integer :: n_bonds

        ! chain_queue's blocks hold 32 bonds: one block (no tree), and either side of the
        ! second and third block's start
        do n_bonds = 1, 40
            call random_updates(t, n_bonds, 400)
        end do
        do n_bonds = 62, 66
            call random_updates(t, n_bonds, 2000)
        end do
        ! trees of 32 blocks (five levels, full), 33 (six levels, 31 empty leaves: a chain of
        ! 1024) and 157 (eight levels), the last block part full
        call random_updates(t, 1000, 20000)
        call random_updates(t, 1025, 20000)
        call random_updates(t, 5001, 20000)
    end subroutine run_queue_tests

    subroutine random_updates(t, n_bonds, updates)
        type(tally_t), intent(inout) :: t
        integer, intent(in) :: n_bonds, updates
        real(wp), parameter :: never = huge(1.0_wp)
        type(queue_t) :: q
        real(wp) :: times(0:n_bonds - 1), top_time, h
        integer :: u, bond, top_bond, want, wrong, n_ties, ties(n_bonds)
        logical :: tied, listed(0:n_bonds - 1)
        character(len=12) :: label

        call queue_init(q, n_bonds, never)
        times = never
        wrong = 0
        do u = 1, updates
            h = sin(12.9898_wp*u + 4.1_wp*n_bonds)*43758.5453_wp
            h = h - floor(h)
            bond = min(n_bonds - 1, int(h*n_bonds))
            ! coarse times make ties common; now and then a bond leaves the schedule
            times(bond) = merge(never, real(int(100*abs(sin(7.3_wp*u))), wp), mod(u, 17) == 0)
            call queue_set(q, bond, times(bond))
            if (mod(u, 101) == 0) then
                call queue_shift(q, 3.0_wp, never)
                where (times < never) times = times - 3
            end if
            call queue_top(q, top_bond, top_time, tied)
            want = minloc(times, dim=1) - 1   ! the first (lowest bond) of the earliest
            if (top_bond /= want .or. top_time /= times(want)) wrong = wrong + 1
            ! the bonds due at the earliest time: whether there are several, and which
            if (tied .neqv. count(times == times(want)) > 1) wrong = wrong + 1
            call queue_ties(q, ties, n_ties)
            listed = .false.
            listed(ties(:n_ties)) = .true.
            if (count(listed) /= n_ties .or. any(listed .neqv. times == times(want))) &
                wrong = wrong + 1
        end do
        write (label, '(i0)') n_bonds
        call check(t, wrong == 0, 'queue of '//trim(label)//' bonds: top is the earliest '// &
                   '(time, bond) after every update, and the ties are the bonds due then')
    end subroutine random_updates

end module test_queue
