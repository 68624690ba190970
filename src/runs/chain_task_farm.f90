!> The task farm of long runs (sweeps, censuses): tasks 1..n run in parallel on OpenMP threads,
!> each a short sequence of units (a sweep's branch: its points in order; a census's task: one
!> sample), and every finished unit is handed back to the shared results one thread at a time,
!> where the caller's monitor is told the progress and may ask to stop. A stop lets the units
!> running in other threads finish. An error stops the farm too; the error returned is that of
!> the lowest task that failed, so the message does not depend on the threads' timing.
!> Infrastructure of docs/model.md sections 8 and 13, no physics.
!>
!> A kind of run plugs in by extending task_runner_t (pointers to its configuration and
!> results) and task_output_t (what one unit computes), and defining the five bindings:
!> `units` (of a task), `done` (a unit already done, e.g. resumed from a checkpoint),
!> `run_unit` (the work, in its thread, reading only what no other thread writes), `store`
!> (its output into the shared results) and `progress` (units done and in all, for the
!> monitor); then `call run_tasks(runner, n_tasks, err, mine, monitor)`. Its checkpoint uses
!> chain_checkpoint, its MPI records one plain array of reals and one of integers per task.
module chain_task_farm
    use chain_kinds, only: i8
    use chain_error, only: error_t, set_error
    use chain_monitor, only: monitor_t
    implicit none
    private
    public :: task_runner_t, task_output_t, run_tasks

    !> What one unit computes in its thread, handed to `store` (a kind of run extends it).
    type, abstract :: task_output_t
    end type task_output_t

    !> A kind of run as the farm sees it (see the header).
    type, abstract :: task_runner_t
        integer :: stage = 0  !! chain_monitor's stage of a unit (stage_points, ...)
    contains
        procedure(units_i), deferred :: units
        procedure(done_i), deferred :: done
        procedure(run_unit_i), deferred :: run_unit
        procedure(store_i), deferred :: store
        procedure(progress_i), deferred :: progress
    end type task_runner_t

    abstract interface
        !> Units of task t, run in order.
        integer function units_i(runner, t)
            import :: task_runner_t
            class(task_runner_t), intent(in) :: runner
            integer, intent(in) :: t
        end function units_i

        !> Unit u of task t is done already (it is skipped).
        logical function done_i(runner, t, u)
            import :: task_runner_t
            class(task_runner_t), intent(in) :: runner
            integer, intent(in) :: t, u
        end function done_i

        !> Unit u of task t, computed in its thread into `output`.
        subroutine run_unit_i(runner, t, u, output, err)
            import :: task_runner_t, task_output_t, error_t
            class(task_runner_t), intent(in) :: runner
            integer, intent(in) :: t, u
            class(task_output_t), allocatable, intent(out) :: output
            type(error_t), allocatable, intent(out) :: err
        end subroutine run_unit_i

        !> Unit u of task t's output into the shared results (one thread at a time).
        subroutine store_i(runner, t, u, output)
            import :: task_runner_t, task_output_t
            class(task_runner_t), intent(inout) :: runner
            integer, intent(in) :: t, u
            class(task_output_t), intent(in) :: output
        end subroutine store_i

        !> Units done and in all (one thread at a time, the results consistent).
        subroutine progress_i(runner, done, total)
            import :: task_runner_t, i8
            class(task_runner_t), intent(in) :: runner
            integer(i8), intent(out) :: done, total
        end subroutine progress_i
    end interface

contains

    !> Run tasks 1..n_tasks, those `mine` marks (the share of one MPI rank; all when absent),
    !> with OpenMP threads. `monitor` is told after each stored unit; the first error by task
    !> order, if any, is returned after all threads stop.
    subroutine run_tasks(runner, n_tasks, err, mine, monitor)
        class(task_runner_t), intent(inout) :: runner
        integer, intent(in) :: n_tasks
        type(error_t), allocatable, intent(out) :: err
        logical, intent(in), optional :: mine(:)
        class(monitor_t), intent(inout), optional :: monitor
        type(error_t), allocatable :: task_err
        character(len=:), allocatable :: first_message
        logical :: stop_now
        integer :: t, first_task

        stop_now = .false.
        first_task = huge(1)
        !$omp parallel do schedule(dynamic) private(task_err) &
        !$omp shared(stop_now, first_task, first_message)
        do t = 1, n_tasks
            if (present(mine)) then
                if (.not. mine(t)) cycle
            end if
            call run_task(runner, t, stop_now, task_err, monitor)
            if (allocated(task_err)) then
                !$omp critical (task_farm)
                if (t < first_task) then
                    first_task = t
                    first_message = task_err%message
                end if
                !$omp atomic write
                stop_now = .true.
                !$omp end critical (task_farm)
            end if
        end do
        !$omp end parallel do
        if (allocated(first_message)) call set_error(err, first_message)
    end subroutine run_tasks

    !> Task t's units in order, skipping those done, until it ends, fails or a stop is asked.
    subroutine run_task(runner, t, stop_now, err, monitor)
        class(task_runner_t), intent(inout) :: runner
        integer, intent(in) :: t
        logical, intent(inout) :: stop_now
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        class(task_output_t), allocatable :: output
        integer(i8) :: done, total
        integer :: u
        logical :: stopping

        do u = 1, runner%units(t)
            if (runner%done(t, u)) cycle
            !$omp atomic read
            stopping = stop_now
            if (stopping) return
            call runner%run_unit(t, u, output, err)
            if (allocated(err)) return
            !$omp critical (task_farm)
            call runner%store(t, u, output)
            if (present(monitor)) then
                call runner%progress(done, total)
                if (.not. monitor%keep_going(runner%stage, done, total)) then
                    !$omp atomic write
                    stop_now = .true.
                end if
            end if
            !$omp end critical (task_farm)
        end do
    end subroutine run_task

end module chain_task_farm
