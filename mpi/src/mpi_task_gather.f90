!> The one gather of impactchain-mpi: the tasks of a run (a sweep's branches, a census's
!> samples) are dealt round robin, task t to rank modulo(t - 1, ranks); after a round every
!> rank sends the records of its tasks (each nr reals and ni 64-bit integers, in the layout its
!> kind of run packs: chain_sweep_checkpoint's pack_branch, chain_census_checkpoint's
!> pack_sample) and rank 0 receives them all. Values travel as they are (no arithmetic), so
!> bit for bit. A third kind of run packs its tasks' records in the same way.
module mpi_task_gather
    use mpi_f08, only: MPI_Comm_rank, MPI_Comm_size, MPI_Gatherv, MPI_COMM_WORLD, &
                       MPI_DOUBLE_PRECISION, MPI_INTEGER8
    use impactchain, only: wp, i8
    implicit none
    private
    public :: owns_task, owned_tasks, gather_records, record_slot

contains

    !> Task t runs on rank `rank` of `ranks`.
    pure logical function owns_task(t, rank, ranks)
        integer, intent(in) :: t, rank, ranks

        owns_task = modulo(t - 1, ranks) == rank
    end function owns_task

    !> Tasks of n_tasks that rank r runs.
    pure integer function owned_tasks(n_tasks, r, ranks)
        integer, intent(in) :: n_tasks, r, ranks

        owned_tasks = (n_tasks - r + ranks - 1)/ranks
    end function owned_tasks

    !> Where task t's record is in gather_records' buffers (0-based): after every task of the
    !> ranks before its own, in increasing order within its rank.
    pure integer function record_slot(t, n_tasks, ranks)
        integer, intent(in) :: t, n_tasks, ranks
        integer :: r

        record_slot = (t - 1)/ranks
        do r = 0, modulo(t - 1, ranks) - 1
            record_slot = record_slot + owned_tasks(n_tasks, r, ranks)
        end do
    end function record_slot

    !> Every rank sends rsend, isend: the records of its tasks in increasing order; rank 0
    !> receives every task's, task t's at slot s = record_slot(t, ...): rrecv(s nr + 1:(s + 1)
    !> nr), irecv(s ni + 1:(s + 1) ni). (Other ranks get buffers of one element.)
    subroutine gather_records(n_tasks, nr, ni, rsend, isend, rrecv, irecv)
        integer, intent(in) :: n_tasks, nr, ni
        real(wp), intent(in) :: rsend(:)
        integer(i8), intent(in) :: isend(:)
        real(wp), allocatable, intent(out) :: rrecv(:)
        integer(i8), allocatable, intent(out) :: irecv(:)
        integer, allocatable :: rcounts(:), icounts(:), rdispl(:), idispl(:)
        integer :: rank, ranks, r

        call MPI_Comm_rank(MPI_COMM_WORLD, rank)
        call MPI_Comm_size(MPI_COMM_WORLD, ranks)
        allocate (rcounts(0:ranks - 1), icounts(0:ranks - 1), rdispl(0:ranks - 1))
        allocate (idispl(0:ranks - 1))
        rcounts = [(owned_tasks(n_tasks, r, ranks)*nr, r=0, ranks - 1)]
        icounts = [(owned_tasks(n_tasks, r, ranks)*ni, r=0, ranks - 1)]
        rdispl(0) = 0
        idispl(0) = 0
        do r = 1, ranks - 1
            rdispl(r) = rdispl(r - 1) + rcounts(r - 1)
            idispl(r) = idispl(r - 1) + icounts(r - 1)
        end do
        if (rank == 0) then
            allocate (rrecv(sum(rcounts)), irecv(sum(icounts)))
        else
            allocate (rrecv(1), irecv(1))
        end if
        call MPI_Gatherv(rsend, rcounts(rank), MPI_DOUBLE_PRECISION, rrecv, rcounts, rdispl, &
                         MPI_DOUBLE_PRECISION, 0, MPI_COMM_WORLD)
        call MPI_Gatherv(isend, icounts(rank), MPI_INTEGER8, irecv, icounts, idispl, &
                         MPI_INTEGER8, 0, MPI_COMM_WORLD)
    end subroutine gather_records

end module mpi_task_gather
