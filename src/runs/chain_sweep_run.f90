!> Running a sweep (docs/model.md section 8): its branches as the tasks of chain_task_farm
!> (a task's units are the branch's points, in order), and the whole sweep from its checkpoint
!> to its file. Along a continuation each point starts from the final state of the one before;
!> every point's numbers are the same whatever the number of threads or ranks.
module chain_sweep_run
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_engine, only: chain_t, chain_init
    use chain_state, only: chain_state_t
    use chain_config, only: config_t, check_size
    use chain_record, only: memory_sink_t, record_result_t, record_cycles
    use chain_sim, only: start_chain, continuation_start
    use chain_output, only: output_t, output_begin, output_end, output_abort
    use chain_files, only: remove_file
    use chain_monitor, only: monitor_t, stage_points
    use chain_task_farm, only: task_runner_t, task_output_t, run_tasks
    use chain_checkpoint, only: checkpoint_path
    use chain_sweep, only: sweep_plan_t, sweep_result_t, plan_sweep, sweep_result_init, &
                           sweep_point_config, check_sweep, write_sweep_file
    use chain_sweep_checkpoint, only: save_checkpoint, load_checkpoint, checkpoint_monitor_t
    implicit none
    private
    public :: run_sweep, sweep_summary_t, run_sweep_branches

    type :: sweep_summary_t
        integer :: n_points = 0
        integer :: points_done = 0
        integer :: points_resumed = 0      !! points taken from a checkpoint
        logical :: complete = .false.
        real(wp) :: mean_collisions = 0
    end type sweep_summary_t

    !> A sweep as the task farm runs it: task b is branch b, its unit q the branch's point q.
    type, extends(task_runner_t) :: sweep_runner_t
        type(config_t) :: cfg
        type(sweep_plan_t) :: plan
        type(sweep_result_t), pointer :: res => null()
        type(chain_state_t), pointer :: starts(:) => null()  !! (branches): where each resumes
    contains
        procedure :: units => branch_points
        procedure :: done => point_done
        procedure :: run_unit => run_point
        procedure :: store => store_point
        procedure :: progress => points_done
    end type sweep_runner_t

    !> One point's results, and where the branch's next point starts (a continuation).
    type, extends(task_output_t) :: point_output_t
        real(wp), allocatable :: x(:, :)             !! x(n, cycles): the records
        type(record_result_t) :: out
        type(chain_state_t) :: next
    end type point_output_t

contains

    !> Run the branches selected by `mine` (all when absent) with OpenMP threads into `res`,
    !> skipping the points already done (a resumed sweep); starts(b) holds where a
    !> continuation resumes. `monitor` is told every point done, the whole sweep then being
    !> consistent (for progress and checkpoints); it may ask to stop (the points running in
    !> other threads finish first). The first error by branch, if any, is returned.
    subroutine run_sweep_branches(cfg, plan, res, starts, err, mine, monitor)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(sweep_result_t), intent(inout), target :: res
        type(chain_state_t), intent(inout), target :: starts(:)
        type(error_t), allocatable, intent(out) :: err
        logical, intent(in), optional :: mine(:)
        class(monitor_t), intent(inout), optional :: monitor
        type(sweep_runner_t) :: runner

        call check_size(cfg, err)
        if (allocated(err)) return
        runner%stage = stage_points
        runner%cfg = cfg
        runner%plan = plan
        runner%res => res
        runner%starts => starts
        call run_tasks(runner, plan%n_branches, err, mine, monitor)
    end subroutine run_sweep_branches

    integer function branch_points(runner, t)
        class(sweep_runner_t), intent(in) :: runner
        integer, intent(in) :: t

        branch_points = runner%plan%points_per_branch
    end function branch_points

    !> Point q of branch b is the sweep's point (b - 1) points_per_branch + q.
    pure integer function point_index(plan, b, q)
        type(sweep_plan_t), intent(in) :: plan
        integer, intent(in) :: b, q

        point_index = (b - 1)*plan%points_per_branch + q
    end function point_index

    logical function point_done(runner, t, u)
        class(sweep_runner_t), intent(in) :: runner
        integer, intent(in) :: t, u

        point_done = runner%res%done(point_index(runner%plan, t, u))
    end function point_done

    !> Point q of branch b, from where the branch resumes, or from the input's start.
    subroutine run_point(runner, t, u, output, err)
        class(sweep_runner_t), intent(in) :: runner
        integer, intent(in) :: t, u
        class(task_output_t), allocatable, intent(out) :: output
        type(error_t), allocatable, intent(out) :: err
        type(config_t) :: point
        type(chain_t) :: chain
        type(memory_sink_t) :: sink
        type(point_output_t), allocatable :: got

        call sweep_point_config(runner%cfg, runner%plan, point_index(runner%plan, t, u), &
                                point, err)
        if (allocated(err)) return
        if (allocated(runner%starts(t)%x)) then
            call chain_init(chain, point%model, runner%starts(t), err)
        else
            ! a start from a file reads HDF5, which is not thread-safe
            !$omp critical (sweep_hdf5)
            call start_chain(point, chain, err)
            !$omp end critical (sweep_hdf5)
        end if
        if (allocated(err)) return
        allocate (got)
        call record_cycles(point%record, chain, sink, got%out, err)
        if (allocated(err)) return
        call move_alloc(sink%x, got%x)
        if (runner%cfg%sweep_mode == 'continuation') got%next = continuation_start(chain)
        call move_alloc(got, output)
    end subroutine run_point

    subroutine store_point(runner, t, u, output)
        class(sweep_runner_t), intent(inout) :: runner
        integer, intent(in) :: t, u
        class(task_output_t), intent(in) :: output
        integer :: p

        p = point_index(runner%plan, t, u)
        select type (output)
        type is (point_output_t)
            associate (res => runner%res, out => output%out)
                res%x(:, :, p) = output%x
                res%collisions(p) = out%collisions_per_cycle
                res%period(:, p) = out%periods
                if (out%has_lyapunov) then
                    res%exponents(:, p) = out%lyapunov%bits_per_cycle
                    res%stderr(:, p) = out%lyapunov%stderr_bits
                    res%stderr_block(:, p) = out%lyapunov%stderr_cycles
                    res%ky(p) = out%lyapunov%ky_dimension
                end if
                res%done(p) = .true.
            end associate
            if (runner%cfg%sweep_mode == 'continuation') runner%starts(t) = output%next
        end select
    end subroutine store_point

    subroutine points_done(runner, done, total)
        class(sweep_runner_t), intent(in) :: runner
        integer(i8), intent(out) :: done, total

        done = count(runner%res%done)
        total = runner%plan%n_points
    end subroutine points_done

    !> The whole sweep described by cfg: resumes from `file.ckpt` when one exists for the same
    !> input, checkpoints every few seconds, and writes the HDF5 file when every point is done.
    !> `monitor`, told the points done, may ask to stop: the checkpoint then keeps the finished
    !> points.
    subroutine run_sweep(cfg, summary, err, monitor)
        type(config_t), intent(in) :: cfg
        type(sweep_summary_t), intent(out) :: summary
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional, target :: monitor
        type(sweep_plan_t) :: plan
        type(sweep_result_t), target :: res
        type(chain_state_t), allocatable, target :: starts(:)
        type(output_t) :: out
        type(error_t), allocatable :: err2
        character(len=:), allocatable :: checkpoint
        type(checkpoint_monitor_t) :: watch

        plan = plan_sweep(cfg)
        call check_sweep(cfg, plan, err)
        if (allocated(err)) return
        call output_begin(out, cfg%output_file, cfg%overwrite, err)
        if (allocated(err)) return
        checkpoint = checkpoint_path(cfg)
        call sweep_result_init(res, cfg, plan)
        allocate (starts(plan%n_branches))
        call load_checkpoint(checkpoint, cfg, plan, res, starts, err)
        if (allocated(err)) then
            call output_abort(out)
            return
        end if
        summary%n_points = plan%n_points
        summary%points_resumed = count(res%done)
        if (present(monitor)) watch%outer => monitor
        watch%cfg = cfg
        watch%plan = plan
        watch%res => res
        watch%starts => starts
        watch%path = checkpoint
        call system_clock(watch%clock_last, watch%clock_rate)
        call run_sweep_branches(cfg, plan, res, starts, err, monitor=watch)
        ! a periodic checkpoint that could not be written stopped the sweep
        if (allocated(watch%err) .and. .not. allocated(err)) call move_alloc(watch%err, err)
        summary%points_done = count(res%done)
        summary%complete = all(res%done)
        ! (the partial file goes first: on a full disk its space is the checkpoint's room)
        if (.not. summary%complete .or. allocated(err)) then
            call output_abort(out)
            call save_checkpoint(checkpoint, cfg, plan, res, starts, err2)
            if (allocated(err2) .and. .not. allocated(err)) call move_alloc(err2, err)
            return
        end if
        summary%mean_collisions = sum(res%collisions)/plan%n_points
        call write_sweep_file(out, cfg, plan, res, err)
        if (.not. allocated(err)) call output_end(out, .true., err)
        if (allocated(err)) then
            ! every point is done: the checkpoint keeps them all, and the same command
            ! writes the file from it without computing anything again
            call output_abort(out)
            call save_checkpoint(checkpoint, cfg, plan, res, starts, err2)
            if (allocated(err2)) err%message = err%message//"; the checkpoint of the "// &
                                               "finished points could not be written either: "// &
                                               err2%message
            return
        end if
        call remove_file(checkpoint)
    end subroutine run_sweep

end module chain_sweep_run
