!> impactchain-mpi: the sweep of a namelist with &sweep, its branches distributed over MPI
!> ranks (branch b on rank mod(b - 1, ranks); inside a rank, OpenMP threads as in the serial
!> driver). Every point is computed exactly as in the threaded driver, so the file is the same
!> as a serial run's, whatever the number of ranks and threads.
!>
!> A namelist with &census (at one point or along a &sweep) is an attractor census instead:
!> its samples are distributed over the ranks (task t = sample s of point p, t = s + samples
!> (p - 1), on rank mod(t - 1, ranks)); rank 0 gathers them and, when all are done,
!> classifies them in sample order as the threaded driver does, so the /census group is the
!> same bit for bit. Rounds, checkpoints (the census checkpoint of the threaded driver),
!> signals and resumption as for a sweep.
!>
!> The ranks work in rounds of `checkpoint_every` seconds (IMPACTCHAIN_CHECKPOINT_SECONDS
!> overrides it): after each round the finished points and, for continuation branches, the
!> state each branch resumes from are gathered on rank 0, which writes `file.h5.ckpt`, the
!> same checkpoint as the threaded driver's. SIGINT / SIGTERM end the round early, write the
!> checkpoint and exit with status 3; running the same command again (with any number of ranks,
!> or the threaded driver) resumes without redoing finished points. When every point is done,
!> rank 0 writes the one HDF5 file and deletes the checkpoint.
!>
!> Either kind is a list of tasks (a sweep's branches, a census's samples) run by one loop of
!> rounds (run_round) and gathered by one gather (mpi_task_gather); what differs is their
!> start, their records and their file.
!>
!> Usage: mpirun -np 4 impactchain-mpi [options] input.nml, with the options of impactchain
!> (--set, -o, --overwrite, --check, --quiet).
program impactchain_mpi
    use, intrinsic :: iso_fortran_env, only: error_unit, output_unit, int64
    use mpi_f08, only: MPI_Init_thread, MPI_Finalize, MPI_Comm_rank, MPI_Comm_size, MPI_Bcast, &
                       MPI_Allreduce, MPI_COMM_WORLD, MPI_MAX, MPI_INTEGER, MPI_IN_PLACE, &
                       MPI_THREAD_FUNNELED
    use mpi_task_gather, only: owns_task, owned_tasks, gather_records, record_slot
    use impactchain, only: census_result_t, check_before_run, kind_names
    use impactchain_drivers, only: census_starts, run_census_samples, classify_census, &
                                   write_census_file, save_census_checkpoint, &
                                   load_census_checkpoint, sample_record_sizes, pack_sample, &
                                   unpack_sample
    use impactchain_drivers, only: exit_now, seconds_from_environment
    use impactchain, only: wp, i8, error_t, config_t, read_config, chain_state_t, code_version, &
                           provenance_text, config_summary, signal_monitor_t
    use impactchain_drivers, only: sweep_plan_t, sweep_result_t, plan_sweep, sweep_result_init, &
                                   checkpoint_path, run_sweep_branches, write_sweep_file, &
                                   save_checkpoint, load_checkpoint, remove_file, &
                                   checkpoint_every, branch_record_sizes, pack_branch, &
                                   unpack_branch, output_t, output_begin, output_end, &
                                   output_abort, catch_interrupts, interrupted, cli_t, &
                                   parse_command_line, cli_run, cli_help, cli_version, cli_usage, &
                                   cli_schema, schema_json
    implicit none
    type(config_t) :: cfg
    type(sweep_plan_t) :: plan
    type(sweep_result_t) :: res
    type(chain_state_t), allocatable :: starts(:)
    type(census_result_t) :: census
    type(output_t) :: out
    type(error_t), allocatable :: err
    integer :: rank, ranks, provided, failed, left, stopping, resumed
    integer :: n_tasks       !! a sweep's branches, or a census's samples (all its points)
    integer :: total         !! of the units counted (`unit`): a sweep's points, or n_tasks
    character(len=:), allocatable :: what, unit  !! 'sweep', 'point' or 'census', 'sample'
    !> exit code of a mistake in the command line itself (an unknown option, no input)
    integer, parameter :: usage_error = 2
    type(cli_t) :: cli
    logical :: quiet
    logical, allocatable :: mine(:)
    character(len=:), allocatable :: input, checkpoint
    real(wp) :: round_seconds
    integer(int64) :: clock_start, clock_round, clock_rate

    call MPI_Init_thread(MPI_THREAD_FUNNELED, provided)
    call MPI_Comm_rank(MPI_COMM_WORLD, rank)
    call MPI_Comm_size(MPI_COMM_WORLD, ranks)
    call read_input()
    if (cfg%census) then
        call start_census()
    else
        call start_sweep()
    end if
    call catch_interrupts()
    call system_clock(clock_start, clock_rate)
    do
        call run_round()
        if (left == 0) exit
        if (stopping /= 0) call stop_interrupted()
    end do
    call finish()
    call MPI_Finalize()
    if (failed /= 0) call exit_now(1)

contains

    !> Read the input (every rank): a sweep or a census.
    subroutine read_input()
        character(len=*), parameter :: usage = 'usage: impactchain-mpi [options] input.nml '// &
                                               '(the options of impactchain --help)'

        cli = parse_command_line()
        select case (cli%action)
        case (cli_help, cli_version, cli_schema)
            if (rank == 0 .and. cli%action == cli_help) write (output_unit, '(a)') usage
            if (rank == 0 .and. cli%action == cli_schema) write (output_unit, '(a)') schema_json()
            if (rank == 0 .and. cli%action == cli_version) &
                write (output_unit, '(a)', advance='no') 'impactchain-mpi '//code_version// &
                                                          new_line('a')//provenance_text()
            call MPI_Finalize()
            stop
        case (cli_usage)
            call stop_all(usage, usage_error)
        case (cli_run)
        case default
            call stop_all(cli%message, usage_error)
        end select
        input = cli%input
        quiet = cli%quiet
        call read_config(input, cfg, err, cli%overrides)
        if (allocated(err)) call stop_all(err%message)
        if (.not. (cfg%sweep .or. cfg%census)) &
            call stop_all(input//': impactchain-mpi runs sweeps and censuses; add a &sweep '// &
                          'or a &census group')
        round_seconds = round_length()
    end subroutine read_input

    !> With --check, print the resolved input (rank 0) and end; else rank 0 opens the output,
    !> refusing an existing file, and every rank stops if it could not.
    subroutine check_only_or_open_output()
        if (cli%check) then
            if (rank == 0) write (output_unit, '(a)', advance='no') config_summary(cfg)
            call MPI_Finalize()
            stop
        end if
        failed = 0
        if (rank == 0) then
            call output_begin(out, cfg%output_file, cfg%overwrite, err)
            if (allocated(err)) failed = 1
        end if
        call MPI_Bcast(failed, 1, MPI_INTEGER, 0, MPI_COMM_WORLD)
        if (failed /= 0) call stop_all(err_text(err))
    end subroutine check_only_or_open_output

    ! ---- a sweep ---------------------------------------------------------------------------

    !> Check the sweep, refuse an existing output (rank 0) and load the checkpoint
    !> (every rank, so that every rank can own any branch). Its tasks are its branches.
    subroutine start_sweep()
        integer :: b

        plan = plan_sweep(cfg)
        ! the threaded driver's checks (sizes, every point, the output), every rank alike,
        ! before anything is allocated or created
        call check_before_run(cfg, err)
        call stop_if_any_failed(err)
        call check_only_or_open_output()
        call sweep_result_init(res, cfg, plan)
        allocate (starts(plan%n_branches))
        checkpoint = checkpoint_path(cfg)
        call load_checkpoint(checkpoint, cfg, plan, res, starts, err)
        call agree_or_stop(err)
        resumed = count(res%done)
        n_tasks = plan%n_branches
        mine = [(owns_task(b, rank, ranks), b=1, n_tasks)]
        what = 'sweep'
        unit = 'point'
        total = plan%n_points
        if (rank == 0 .and. plan%n_branches < ranks .and. .not. quiet) &
            write (error_unit, '(a,i0,a,i0,a)') 'impactchain-mpi: note: ', plan%n_branches, &
            ' branches for ', ranks, ' ranks, so some ranks stay idle (a continuation along '// &
            'one parameter is one branch: add parameter2 or use mode = ''independent'')'
    end subroutine start_sweep

    !> Rank 0 receives every rank's branches: their points (results and done flags) and the
    !> states they resume from, in the layout of pack_branch (the checkpoint's).
    subroutine collect_branches()
        real(wp), allocatable :: rsend(:), rrecv(:)
        integer(i8), allocatable :: isend(:), irecv(:)
        integer :: nr, ni, c, b, s

        call branch_record_sizes(cfg, plan, nr, ni)
        allocate (rsend(owned_tasks(n_tasks, rank, ranks)*nr))
        allocate (isend(owned_tasks(n_tasks, rank, ranks)*ni))
        c = 0
        do b = rank + 1, n_tasks, ranks
            call pack_branch(cfg, plan, res, starts, b, rsend(c*nr + 1:(c + 1)*nr), &
                             isend(c*ni + 1:(c + 1)*ni))
            c = c + 1
        end do
        call gather_records(n_tasks, nr, ni, rsend, isend, rrecv, irecv)
        if (rank /= 0) return
        do b = 1, n_tasks
            s = record_slot(b, n_tasks, ranks)
            call unpack_branch(cfg, plan, b, rrecv(s*nr + 1:(s + 1)*nr), &
                               irecv(s*ni + 1:(s + 1)*ni), res, starts)
        end do
    end subroutine collect_branches

    ! ---- a census ------------------------------------------------------------------------

    !> Check the census, refuse an existing output (rank 0), make the starts and load the
    !> checkpoint (every rank alike). Its tasks are its samples (task order: sample s of point
    !> p is task s + samples (p - 1)).
    subroutine start_census()
        integer :: t

        call check_before_run(cfg, err)
        call stop_if_any_failed(err)
        call check_only_or_open_output()
        call census_starts(census, cfg, err)
        call agree_or_stop(err)
        checkpoint = checkpoint_path(cfg)
        call load_census_checkpoint(checkpoint, cfg, census, err)
        call agree_or_stop(err)
        resumed = count(census%done)
        census%resumed = resumed
        n_tasks = size(census%done)
        mine = [(owns_task(t, rank, ranks), t=1, n_tasks)]
        what = 'census'
        unit = 'sample'
        total = n_tasks
    end subroutine start_census

    !> Rank 0 receives every rank's samples (done or not; a rank's own are its to report), in
    !> the layout of pack_sample.
    subroutine collect_samples()
        real(wp), allocatable :: rsend(:), rrecv(:)
        integer(i8), allocatable :: isend(:), irecv(:)
        integer :: nr, ni, c, t, s

        call sample_record_sizes(cfg%model%n, cfg%census_exponents, nr, ni)
        allocate (rsend(owned_tasks(n_tasks, rank, ranks)*nr))
        allocate (isend(owned_tasks(n_tasks, rank, ranks)*ni))
        c = 0
        do t = rank + 1, n_tasks, ranks
            call pack_sample(census, sample_of(t), point_of(t), rsend(c*nr + 1:(c + 1)*nr), &
                             isend(c*ni + 1:(c + 1)*ni))
            c = c + 1
        end do
        call gather_records(n_tasks, nr, ni, rsend, isend, rrecv, irecv)
        if (rank /= 0) return
        do t = 1, n_tasks
            s = record_slot(t, n_tasks, ranks)
            call unpack_sample(rrecv(s*nr + 1:(s + 1)*nr), irecv(s*ni + 1:(s + 1)*ni), &
                               sample_of(t), point_of(t), census)
        end do
    end subroutine collect_samples

    pure integer function sample_of(t)
        integer, intent(in) :: t

        sample_of = modulo(t - 1, census%n_samples) + 1
    end function sample_of

    pure integer function point_of(t)
        integer, intent(in) :: t

        point_of = (t - 1)/census%n_samples + 1
    end function point_of

    !> The attractors found, as the threaded driver reports them.
    subroutine report_census()
        integer :: a, p

        write (output_unit, '(a,i0,a,i0,a,i0,a,i0,a,i0,a)') '  samples ', census%n_samples, &
            ' at ', census%n_points, ' point(s) on ', ranks, &
            ' ranks (resumed from a checkpoint: ', resumed, '), attractors ', &
            census%n_attractors, ''
        do a = 1, census%n_attractors
            associate (t => census%attractors(a))
                p = t%point
                write (output_unit, '(a,i0,a,i0,3a,i0,a,f0.4,a,f0.4)') '  attractor ', a - 1, &
                    ' (point ', p - 1, '): ', trim(kind_names(t%kind)), ', period ', &
                    t%period, ', fraction ', census%fraction(a, p), ' +- ', &
                    census%fraction_stderr(a, p)
            end associate
        end do
    end subroutine report_census

    ! ---- the rounds, either kind -----------------------------------------------------------

    !> One round: every rank works on its tasks until the round ends, rank 0 gathers the
    !> results, and (unless every task is done) writes the checkpoint. Sets `left` (points or
    !> samples not done) and `stopping` (a signal reached some rank).
    subroutine run_round()
        type(signal_monitor_t) :: round ! ends the round after round_seconds, or on a signal

        call system_clock(clock_round)
        round%deadline = clock_round + int(round_seconds*clock_rate, int64)
        if (cfg%census) then
            call run_census_samples(cfg, census, err, round, mine)
            call agree_or_stop(err)
            call collect_samples()
            left = count(.not. census%done)
        else
            call run_sweep_branches(cfg, plan, res, starts, err, mine=mine, monitor=round)
            call agree_or_stop(err)
            call collect_branches()
            left = count(.not. res%done)
        end if
        call MPI_Bcast(left, 1, MPI_INTEGER, 0, MPI_COMM_WORLD)
        if (left == 0) return
        stopping = merge(1, 0, interrupted())
        call MPI_Allreduce(MPI_IN_PLACE, stopping, 1, MPI_INTEGER, MPI_MAX, MPI_COMM_WORLD)
        ! a checkpoint that cannot be written stops every rank (the previous one stays)
        if (rank == 0) call save_progress(err)
        call agree_or_stop(err)
        if (rank == 0) call report_progress()
    end subroutine run_round

    !> Rank 0 writes the checkpoint of the work gathered.
    subroutine save_progress(e)
        type(error_t), allocatable, intent(out) :: e

        if (cfg%census) then
            call save_census_checkpoint(checkpoint, cfg, census, e)
        else
            call save_checkpoint(checkpoint, cfg, plan, res, starts, e)
        end if
    end subroutine save_progress

    !> After a signal: the checkpoint is written; say how to resume and exit with status 3.
    subroutine stop_interrupted()
        if (rank == 0) then
            call output_abort(out)
            write (error_unit, '(a,i0,a,i0,a)') 'impactchain-mpi: the '//what//' was '// &
                'stopped after ', total - left, ' of ', total, ' '//unit//'s; run the '// &
                'same command again to resume from '//checkpoint
        end if
        call MPI_Finalize()
        call exit_now(3)
    end subroutine stop_interrupted

    !> Rank 0 (a census: classifies every sample, in sample order as the threaded driver)
    !> writes the one HDF5 file and deletes the checkpoint; every rank learns whether that
    !> failed (`failed`).
    subroutine finish()
        type(error_t), allocatable :: err2

        if (rank == 0) then
            if (cfg%census) then
                call classify_census(cfg, census, err)
                if (.not. allocated(err)) call write_census_file(out, cfg, census, err)
            else
                call write_sweep_file(out, cfg, plan, res, err)
            end if
            if (.not. allocated(err)) call output_end(out, .true., err)
            if (allocated(err)) then
                ! every task is done: the checkpoint keeps them for the same command
                call output_abort(out)
                call save_progress(err2)
                if (allocated(err2)) err%message = err%message//"; the checkpoint of the "// &
                    "finished "//unit//"s could not be written either: "//err2%message
                write (error_unit, '(a)') 'impactchain-mpi: error: '//err%message
            else
                call remove_file(checkpoint)
                write (output_unit, '(a)') 'impactchain-mpi: wrote '//cfg%output_file
                if (cfg%census) then
                    call report_census()
                else
                    write (output_unit, '(a,i0,a,i0,a,i0,a)') '  sweep points ', total, &
                        ' on ', ranks, ' ranks (resumed from a checkpoint: ', resumed, ')'
                end if
            end if
        end if
        failed = merge(1, 0, allocated(err))
        call MPI_Bcast(failed, 1, MPI_INTEGER, 0, MPI_COMM_WORLD)
    end subroutine finish

    !> Points or samples done / total, rate and time left (rank 0, stderr; at most once a
    !> round).
    subroutine report_progress()
        integer(int64) :: now
        real(wp) :: elapsed, rate
        integer :: done

        if (quiet) return
        call system_clock(now)
        elapsed = real(now - clock_start, wp)/clock_rate
        done = total - left
        rate = (done - resumed)/max(elapsed, 1.0e-9_wp)
        write (error_unit, '(a,i0,a,i0,a,es9.2,a,f9.1,a)') 'impactchain-mpi: '//unit//' ', &
            done, ' / ', total, ', ', rate, ' '//unit//'s/s, ', left/max(rate, 1.0e-9_wp), &
            ' s left'
    end subroutine report_progress

    ! ---- shared ----------------------------------------------------------------------------

    !> Seconds per round: checkpoint_every, or IMPACTCHAIN_CHECKPOINT_SECONDS when set (0: as
    !> short as a round can usefully be, a hundredth of a second).
    real(wp) function round_length() result(seconds)
        character(len=:), allocatable :: message

        call seconds_from_environment('IMPACTCHAIN_CHECKPOINT_SECONDS', real(checkpoint_every, &
                                      wp), seconds, message)
        if (allocated(message)) call stop_all(message)
        seconds = max(seconds, 0.01_wp)
    end function round_length

    !> All ranks learn whether any failed; a failing rank prints its own message.
    subroutine agree_or_stop(e)
        type(error_t), allocatable, intent(in) :: e

        failed = merge(1, 0, allocated(e))
        if (allocated(e)) write (error_unit, '(a,i0,a)') 'impactchain-mpi: error (rank ', rank, &
            '): '//e%message
        call MPI_Allreduce(MPI_IN_PLACE, failed, 1, MPI_INTEGER, MPI_MAX, MPI_COMM_WORLD)
        if (failed == 0) return
        if (rank == 0) call output_abort(out)
        call MPI_Finalize()
        call exit_now(1)
    end subroutine agree_or_stop

    !> The checks before a run, made on every rank: all go on, or all stop (a check of the
    !> output's directory can fail on one node only). Rank 0's message is the one line; a
    !> rank that failed alone says which it is.
    subroutine stop_if_any_failed(e)
        type(error_t), allocatable, intent(in) :: e
        integer :: any_failed, root_failed

        any_failed = merge(1, 0, allocated(e))
        call MPI_Allreduce(MPI_IN_PLACE, any_failed, 1, MPI_INTEGER, MPI_MAX, MPI_COMM_WORLD)
        if (any_failed == 0) return
        root_failed = merge(1, 0, allocated(e))
        call MPI_Bcast(root_failed, 1, MPI_INTEGER, 0, MPI_COMM_WORLD)
        if (rank == 0 .and. allocated(e)) write (error_unit, '(a)') 'impactchain-mpi: error: '// &
            e%message
        if (root_failed == 0 .and. allocated(e)) write (error_unit, '(a,i0,a)') &
            'impactchain-mpi: error (rank ', rank, '): '//e%message
        call MPI_Finalize()
        call exit_now(1)
    end subroutine stop_if_any_failed

    function err_text(e) result(text)
        type(error_t), allocatable, intent(in) :: e
        character(len=:), allocatable :: text

        text = 'a rank failed'
        if (allocated(e)) text = e%message
    end function err_text

    !> Every rank calls this with the same message (errors every rank meets alike).
    !> Report `message` (rank 0) and end every rank with exit 1, or 2 for a mistake in the
    !> command line itself (`usage_error`).
    subroutine stop_all(message, code)
        character(len=*), intent(in) :: message
        integer, intent(in), optional :: code

        if (rank == 0) write (error_unit, '(a)') 'impactchain-mpi: error: '//message
        call MPI_Finalize()
        if (present(code)) then
            if (code == usage_error) call exit_now(2)
        end if
        call exit_now(1)
    end subroutine stop_all

end program impactchain_mpi
