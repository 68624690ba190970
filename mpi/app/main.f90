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
!> Usage: mpirun -np 4 impactchain-mpi [options] input.nml, with the options of impactchain
!> (--set, -o, --overwrite, --check, --quiet).
program impactchain_mpi
    use, intrinsic :: iso_fortran_env, only: error_unit, output_unit, int64
    use mpi_f08, only: MPI_Init_thread, MPI_Finalize, MPI_Comm_rank, MPI_Comm_size, MPI_Bcast, &
                       MPI_Allreduce, MPI_Gatherv, MPI_COMM_WORLD, MPI_MAX, &
                       MPI_DOUBLE_PRECISION, MPI_INTEGER, MPI_INTEGER8, MPI_IN_PLACE, &
                       MPI_THREAD_FUNNELED
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
                                   cli_schema
    implicit none
    type(config_t) :: cfg
    type(sweep_plan_t) :: plan
    type(sweep_result_t) :: res
    type(chain_state_t), allocatable :: starts(:)
    type(census_result_t) :: census
    type(output_t) :: out
    type(error_t), allocatable :: err
    integer :: rank, ranks, provided, failed, left, stopping, resumed
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
        call catch_interrupts()
        call system_clock(clock_start, clock_rate)
        do
            call census_round()
            if (left == 0) exit
            if (stopping /= 0) call stop_interrupted('census', 'samples', size(census%done))
        end do
        call finish_census()
    else
        call start_sweep()
        call catch_interrupts()
        call system_clock(clock_start, clock_rate)
        do
            call run_round()
            if (left == 0) exit
            if (stopping /= 0) call stop_interrupted('sweep', 'points', plan%n_points)
        end do
        call finish_sweep()
    end if
    call MPI_Finalize()
    if (failed /= 0) call exit_now(1)

contains

    !> Read the input (every rank): a sweep or a census.
    subroutine read_input()
        character(len=*), parameter :: usage = 'usage: impactchain-mpi [options] input.nml '// &
                                               '(the options of impactchain --help)'

        cli = parse_command_line()
        select case (cli%action)
        case (cli_help, cli_version)
            if (rank == 0 .and. cli%action == cli_help) write (output_unit, '(a)') usage
            if (rank == 0 .and. cli%action == cli_version) &
                write (output_unit, '(a)', advance='no') 'impactchain-mpi '//code_version// &
                                                          new_line('a')//provenance_text()
            call MPI_Finalize()
            stop
        case (cli_usage)
            call stop_all(usage, usage_error)
        case (cli_schema)
            call stop_all("--schema: the schema is the same for both programs; run "// &
                          "impactchain --schema", usage_error)
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

    !> Check the sweep, refuse an existing output (rank 0) and load the checkpoint
    !> (every rank, so that every rank can own any branch).
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
        mine = [(modulo(b - 1, ranks) == rank, b=1, plan%n_branches)]
        if (rank == 0 .and. plan%n_branches < ranks .and. .not. quiet) &
            write (error_unit, '(a,i0,a,i0,a)') 'impactchain-mpi: note: ', plan%n_branches, &
            ' branches for ', ranks, ' ranks, so some ranks stay idle (a continuation along '// &
            'one parameter is one branch: add parameter2 or use mode = ''independent'')'
    end subroutine start_sweep

    !> One round: every rank works on its branches until the round ends, rank 0 gathers the
    !> results, and (unless every point is done) writes the checkpoint. Sets `left` (points
    !> not done) and `stopping` (a signal reached some rank).
    subroutine run_round()
        type(signal_monitor_t) :: round ! ends the round after round_seconds, or on a signal

        call system_clock(clock_round)
        round%deadline = clock_round + int(round_seconds*clock_rate, int64)
        call run_sweep_branches(cfg, plan, res, starts, err, mine=mine, monitor=round)
        call agree_or_stop(err)
        call collect_on_root()
        left = count(.not. res%done)
        call MPI_Bcast(left, 1, MPI_INTEGER, 0, MPI_COMM_WORLD)
        if (left == 0) return
        stopping = merge(1, 0, interrupted())
        call MPI_Allreduce(MPI_IN_PLACE, stopping, 1, MPI_INTEGER, MPI_MAX, MPI_COMM_WORLD)
        ! a checkpoint that cannot be written stops every rank (the previous one stays)
        if (rank == 0) call save_checkpoint(checkpoint, cfg, plan, res, starts, err)
        call agree_or_stop(err)
        if (rank == 0) call report_progress()
    end subroutine run_round

    !> After a signal: the checkpoint is written; say how to resume and exit with status 3.
    subroutine stop_interrupted(what, units, total)
        character(len=*), intent(in) :: what, units
        integer, intent(in) :: total

        if (rank == 0) then
            call output_abort(out)
            write (error_unit, '(a,i0,a,i0,a)') 'impactchain-mpi: the '//what//' was '// &
                'stopped after ', total - left, ' of ', total, ' '//units//'; run the '// &
                'same command again to resume from '//checkpoint
        end if
        call MPI_Finalize()
        call exit_now(3)
    end subroutine stop_interrupted

    !> Rank 0 writes the one HDF5 file and deletes the checkpoint; every rank learns whether
    !> that failed (`failed`).
    subroutine finish_sweep()
        type(error_t), allocatable :: err2

        if (rank == 0) then
            call write_sweep_file(out, cfg, plan, res, err)
            if (.not. allocated(err)) call output_end(out, .true., err)
            if (allocated(err)) then
                ! every point is done: the checkpoint keeps them for the same command
                call output_abort(out)
                call save_checkpoint(checkpoint, cfg, plan, res, starts, err2)
                if (allocated(err2)) err%message = err%message//"; the checkpoint of the "// &
                    "finished points could not be written either: "//err2%message
                write (error_unit, '(a)') 'impactchain-mpi: error: '//err%message
            else
                call remove_file(checkpoint)
                write (output_unit, '(a)') 'impactchain-mpi: wrote '//cfg%output_file
                write (output_unit, '(a,i0,a,i0,a,i0,a)') '  sweep points ', plan%n_points, &
                    ' on ', ranks, ' ranks (resumed from a checkpoint: ', resumed, ')'
            end if
        end if
        failed = merge(1, 0, allocated(err))
        call MPI_Bcast(failed, 1, MPI_INTEGER, 0, MPI_COMM_WORLD)
    end subroutine finish_sweep

    !> Rank 0 receives every rank's branches: their points (results and done flags) and the
    !> states they resume from, in the layout of chain_sweep's pack_branch (the checkpoint's).
    !> Values travel as they are (no arithmetic), so bit for bit.
    subroutine collect_on_root()
        real(wp), allocatable :: rsend(:), rrecv(:)
        integer(i8), allocatable :: isend(:), irecv(:)
        integer :: nr, ni, r, c, owned(0:ranks - 1), rcounts(0:ranks - 1), icounts(0:ranks - 1)
        integer :: rdispl(0:ranks - 1), idispl(0:ranks - 1), ro, io, b

        call branch_record_sizes(cfg, plan, nr, ni)
        owned = 0
        do b = 1, plan%n_branches
            owned(modulo(b - 1, ranks)) = owned(modulo(b - 1, ranks)) + 1
        end do
        rcounts = owned*nr
        icounts = owned*ni
        rdispl(0) = 0
        idispl(0) = 0
        do r = 1, ranks - 1
            rdispl(r) = rdispl(r - 1) + rcounts(r - 1)
            idispl(r) = idispl(r - 1) + icounts(r - 1)
        end do
        allocate (rsend(rcounts(rank)), isend(icounts(rank)))
        c = 0
        do b = 1, plan%n_branches
            if (.not. mine(b)) cycle
            call pack_branch(cfg, plan, res, starts, b, rsend(c*nr + 1:(c + 1)*nr), &
                             isend(c*ni + 1:(c + 1)*ni))
            c = c + 1
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
        if (rank /= 0) return
        ! rank r's branches arrive in increasing order from displacement r
        do r = 0, ranks - 1
            ro = rdispl(r)
            io = idispl(r)
            do b = r + 1, plan%n_branches, ranks
                call unpack_branch(cfg, plan, b, rrecv(ro + 1:ro + nr), irecv(io + 1:io + ni), &
                                   res, starts)
                ro = ro + nr
                io = io + ni
            end do
        end do
    end subroutine collect_on_root

    !> Points done / total, rate and time left (rank 0, stderr; at most once a round).
    subroutine report_progress()
        integer(int64) :: now
        real(wp) :: elapsed, rate
        integer :: done

        if (quiet) return
        call system_clock(now)
        elapsed = real(now - clock_start, wp)/clock_rate
        done = plan%n_points - left
        rate = (done - resumed)/max(elapsed, 1.0e-9_wp)
        write (error_unit, '(a,i0,a,i0,a,es9.2,a,f9.1,a)') 'impactchain-mpi: point ', done, &
            ' / ', plan%n_points, ', ', rate, ' points/s, ', left/max(rate, 1.0e-9_wp), ' s left'
    end subroutine report_progress

    ! ---- a census ------------------------------------------------------------------------

    !> Check the census, refuse an existing output (rank 0), make the starts and load the
    !> checkpoint (every rank alike).
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
        mine = [(modulo(t - 1, ranks) == rank, t=1, size(census%done))]
    end subroutine start_census

    !> One round of a census: every rank runs its samples until the round ends, rank 0
    !> gathers them and (unless every sample is done) writes the checkpoint. Sets `left`
    !> (samples not done) and `stopping`.
    subroutine census_round()
        type(signal_monitor_t) :: round

        call system_clock(clock_round)
        round%deadline = clock_round + int(round_seconds*clock_rate, int64)
        call run_census_samples(cfg, census, err, round, mine)
        call agree_or_stop(err)
        call collect_samples_on_root()
        left = count(.not. census%done)
        call MPI_Bcast(left, 1, MPI_INTEGER, 0, MPI_COMM_WORLD)
        if (left == 0) return
        stopping = merge(1, 0, interrupted())
        call MPI_Allreduce(MPI_IN_PLACE, stopping, 1, MPI_INTEGER, MPI_MAX, MPI_COMM_WORLD)
        ! a checkpoint that cannot be written stops every rank (the previous one stays)
        if (rank == 0) call save_census_checkpoint(checkpoint, cfg, census, err)
        call agree_or_stop(err)
        if (rank == 0) call report_census_progress()
    end subroutine census_round

    !> Rank 0 receives every rank's samples (done or not; a rank's own are its to report), in
    !> the layout of pack_sample. Values travel as they are, so bit for bit.
    subroutine collect_samples_on_root()
        real(wp), allocatable :: rsend(:), rrecv(:)
        integer(i8), allocatable :: isend(:), irecv(:)
        integer :: nr, ni, r, c, t, tasks, rcounts(0:ranks - 1), icounts(0:ranks - 1)
        integer :: rdispl(0:ranks - 1), idispl(0:ranks - 1), owned(0:ranks - 1)

        call sample_record_sizes(cfg%model%n, cfg%census_exponents, nr, ni)
        tasks = size(census%done)
        owned = [((tasks - r + ranks - 1)/ranks, r=0, ranks - 1)]
        rcounts = owned*nr
        icounts = owned*ni
        rdispl(0) = 0
        idispl(0) = 0
        do r = 1, ranks - 1
            rdispl(r) = rdispl(r - 1) + rcounts(r - 1)
            idispl(r) = idispl(r - 1) + icounts(r - 1)
        end do
        allocate (rsend(rcounts(rank)), isend(icounts(rank)))
        c = 0
        do t = rank + 1, tasks, ranks
            call pack_sample(census, sample_of(t), point_of(t), rsend(c*nr + 1:(c + 1)*nr), &
                             isend(c*ni + 1:(c + 1)*ni))
            c = c + 1
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
        if (rank /= 0) return
        do r = 0, ranks - 1
            c = 0
            do t = r + 1, tasks, ranks
                call unpack_sample(rrecv(rdispl(r) + c*nr + 1:rdispl(r) + (c + 1)*nr), &
                                   irecv(idispl(r) + c*ni + 1:idispl(r) + (c + 1)*ni), &
                                   sample_of(t), point_of(t), census)
                c = c + 1
            end do
        end do
    end subroutine collect_samples_on_root

    pure integer function sample_of(t)
        integer, intent(in) :: t

        sample_of = modulo(t - 1, census%n_samples) + 1
    end function sample_of

    pure integer function point_of(t)
        integer, intent(in) :: t

        point_of = (t - 1)/census%n_samples + 1
    end function point_of

    !> Rank 0 classifies every sample (in sample order, as the threaded driver), writes the
    !> one HDF5 file and deletes the checkpoint; every rank learns whether that failed.
    subroutine finish_census()
        type(error_t), allocatable :: err2

        if (rank == 0) then
            call classify_census(cfg, census, err)
            if (.not. allocated(err)) call write_census_file(out, cfg, census, err)
            if (.not. allocated(err)) call output_end(out, .true., err)
            if (allocated(err)) then
                call output_abort(out)
                call save_census_checkpoint(checkpoint, cfg, census, err2)
                if (allocated(err2)) err%message = err%message//"; the checkpoint of the "// &
                    "finished samples could not be written either: "//err2%message
                write (error_unit, '(a)') 'impactchain-mpi: error: '//err%message
            else
                call remove_file(checkpoint)
                call report_census()
            end if
        end if
        failed = merge(1, 0, allocated(err))
        call MPI_Bcast(failed, 1, MPI_INTEGER, 0, MPI_COMM_WORLD)
    end subroutine finish_census

    !> The attractors found, as the threaded driver reports them.
    subroutine report_census()
        integer :: a, p

        write (output_unit, '(a)') 'impactchain-mpi: wrote '//cfg%output_file
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

    !> Samples done / total, rate and time left (rank 0, stderr; at most once a round).
    subroutine report_census_progress()
        integer(int64) :: now
        real(wp) :: elapsed, rate
        integer :: done

        if (quiet) return
        call system_clock(now)
        elapsed = real(now - clock_start, wp)/clock_rate
        done = size(census%done) - left
        rate = (done - resumed)/max(elapsed, 1.0e-9_wp)
        write (error_unit, '(a,i0,a,i0,a,es9.2,a,f9.1,a)') 'impactchain-mpi: sample ', done, &
            ' / ', size(census%done), ', ', rate, ' samples/s, ', left/max(rate, 1.0e-9_wp), &
            ' s left'
    end subroutine report_census_progress

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
