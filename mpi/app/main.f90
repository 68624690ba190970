!> impactchain-mpi: the sweep of a namelist with &sweep, its branches distributed over MPI
!> ranks (branch b on rank mod(b - 1, size)); rank 0 gathers the points and writes the one
!> HDF5 file. Every point is computed exactly as in the threaded driver, so the file is the
!> same as a serial run's. Usage: mpirun -np 4 impactchain-mpi input.nml
program impactchain_mpi
    use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
    use mpi_f08, only: MPI_Init, MPI_Finalize, MPI_Comm_rank, MPI_Comm_size, MPI_Reduce, &
                       MPI_Bcast, MPI_Allreduce, MPI_COMM_WORLD, MPI_SUM, MPI_MAX, &
                       MPI_DOUBLE_PRECISION, MPI_INTEGER, MPI_IN_PLACE
    use chain_kinds, only: wp
    use chain_error, only: error_t
    use chain_config, only: run_config_t, read_config
    use chain_sweep, only: sweep_plan_t, sweep_result_t, branch_start_state_t, plan_sweep, &
                           sweep_result_init, run_sweep_branches, write_sweep_file
    use chain_output, only: output_t, output_begin, output_end, output_abort
    implicit none
    type(run_config_t) :: cfg
    type(sweep_plan_t) :: plan
    type(sweep_result_t) :: res
    type(branch_start_state_t), allocatable :: starts(:)
    type(output_t) :: out
    type(error_t), allocatable :: err
    integer :: rank, ranks, b, failed, length
    character(len=:), allocatable :: input

    call MPI_Init()
    call MPI_Comm_rank(MPI_COMM_WORLD, rank)
    call MPI_Comm_size(MPI_COMM_WORLD, ranks)
    if (command_argument_count() /= 1) call stop_all('usage: impactchain-mpi input.nml')
    call get_command_argument(1, length=length)
    allocate (character(len=length) :: input)
    call get_command_argument(1, input)
    call read_config(input, cfg, err)
    if (allocated(err)) call stop_all(err%message)
    if (.not. cfg%sweep) call stop_all(input//': impactchain-mpi runs sweeps; add a &sweep group')
    ! rank 0 refuses an existing or unwritable output before anyone works
    failed = 0
    if (rank == 0) then
        call output_begin(out, cfg%output_file, cfg%overwrite, err)
        if (allocated(err)) failed = 1
    end if
    call MPI_Bcast(failed, 1, MPI_INTEGER, 0, MPI_COMM_WORLD)
    if (failed /= 0) call stop_all(err_text(err))
    plan = plan_sweep(cfg)
    call sweep_result_init(res, cfg, plan)
    allocate (starts(plan%n_branches))
    call run_sweep_branches(cfg, plan, res, starts, err, &
                            mine=[(modulo(b - 1, ranks) == rank, b=1, plan%n_branches)])
    failed = merge(1, 0, allocated(err))
    call MPI_Allreduce(MPI_IN_PLACE, failed, 1, MPI_INTEGER, MPI_MAX, MPI_COMM_WORLD)
    if (failed /= 0) then
        if (rank == 0) call output_abort(out)
        call stop_all(err_text(err))
    end if
    ! every point was computed on exactly one rank, zeros elsewhere: a sum gathers them
    call gather(res%x, size(res%x))
    call gather(res%collisions, size(res%collisions))
    call gather(res%exponents, size(res%exponents))
    call gather(res%stderr, size(res%stderr))
    call gather(res%ky, size(res%ky))
    call gather_int(res%period, size(res%period))
    if (rank == 0) then
        write (output_unit, '(a,i0,a,i0,a)') 'impactchain-mpi: ', plan%n_points, &
            ' points on ', ranks, ' ranks'
        call write_sweep_file(out, cfg, plan, res, err)
        if (.not. allocated(err)) call output_end(out, .true., err)
        if (allocated(err)) then
            call output_abort(out)
            write (error_unit, '(a)') 'impactchain-mpi: error: '//err%message
        else
            write (output_unit, '(a)') 'impactchain-mpi: wrote '//cfg%output_file
        end if
    end if
    call MPI_Finalize()
    if (allocated(err)) stop 1, quiet=.true.

contains

    subroutine gather(values, count)
        real(wp), intent(inout) :: values(*)
        integer, intent(in) :: count

        if (rank == 0) then
            call MPI_Reduce(MPI_IN_PLACE, values, count, MPI_DOUBLE_PRECISION, MPI_SUM, 0, &
                            MPI_COMM_WORLD)
        else
            call MPI_Reduce(values, values, count, MPI_DOUBLE_PRECISION, MPI_SUM, 0, &
                            MPI_COMM_WORLD)
        end if
    end subroutine gather

    subroutine gather_int(values, count)
        integer, intent(inout) :: values(*)
        integer, intent(in) :: count

        if (rank == 0) then
            call MPI_Reduce(MPI_IN_PLACE, values, count, MPI_INTEGER, MPI_SUM, 0, MPI_COMM_WORLD)
        else
            call MPI_Reduce(values, values, count, MPI_INTEGER, MPI_SUM, 0, MPI_COMM_WORLD)
        end if
    end subroutine gather_int

    function err_text(e) result(text)
        type(error_t), allocatable, intent(in) :: e
        character(len=:), allocatable :: text

        text = 'a rank failed'
        if (allocated(e)) text = e%message
    end function err_text

    subroutine stop_all(message)
        character(len=*), intent(in) :: message

        if (rank == 0) write (error_unit, '(a)') 'impactchain-mpi: error: '//message
        call MPI_Finalize()
        stop 1, quiet=.true.
    end subroutine stop_all

end program impactchain_mpi
