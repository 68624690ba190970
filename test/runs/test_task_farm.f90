!> The task farm and the checkpoint protocol of long runs (chain_task_farm, chain_checkpoint)
!> with a third kind of run of the tests' own: task t has t units, unit u stores 1000 t + u.
!> Suite `taskfarm`: every unit stored once with 1 and 2 threads, only the tasks `mine`
!> marks, the units done skipped, a stop asked by the monitor, the first error by task order
!> (not by time), and the checkpoint's round trip, refusals and damage.
module test_task_farm
    !$ use omp_lib, only: omp_set_num_threads
    use chain_kinds, only: i8
    use chain_error, only: error_t
    use chain_monitor, only: monitor_t, stage_samples
    use chain_task_farm, only: task_runner_t, task_output_t, run_tasks
    use chain_checkpoint, only: checkpoint_t, checkpoint_create, checkpoint_commit, &
                                checkpoint_open, checkpoint_refuse, checkpoint_close
    use chain_files, only: remove_file
    use testing, only: tally_t, check
    implicit none
    private
    public :: run_task_farm_tests

    integer, parameter :: n_tasks = 6

    !> The tests' kind of run: results(u, t) = 1000 t + u. Task `slow_failure` fails after
    !> `slow_seconds` of waiting, task `fast_failure` at once (0: none fails).
    type, extends(task_runner_t) :: toy_runner_t
        integer, pointer :: results(:, :) => null()  !! (n_tasks, n_tasks), 0 = not done
        integer :: slow_failure = 0, fast_failure = 0
        real :: slow_seconds = 0
    contains
        procedure :: units => toy_units
        procedure :: done => toy_done
        procedure :: run_unit => toy_run_unit
        procedure :: store => toy_store
        procedure :: progress => toy_progress
    end type toy_runner_t

    type, extends(task_output_t) :: toy_output_t
        integer :: value = 0
    end type toy_output_t

    !> Asks to stop once `limit` units are done, and records that it was told each one.
    type, extends(monitor_t) :: stop_after_t
        integer :: limit = huge(1), calls = 0
        logical :: told_right = .true.
    contains
        procedure :: keep_going => stop_after
    end type stop_after_t

contains

    subroutine run_task_farm_tests(t)
        type(tally_t), intent(inout) :: t

        call test_every_unit_once(t)
        call test_mine_done_and_stop(t)
        call test_first_error_by_task_order(t)
        call test_checkpoint_protocol(t)
    end subroutine run_task_farm_tests

    !> With 1 and 2 threads every unit of every task is stored once, with its value.
    subroutine test_every_unit_once(t)
        type(tally_t), intent(inout) :: t
        integer, target :: results(n_tasks, n_tasks)
        type(toy_runner_t) :: runner
        type(error_t), allocatable :: err
        integer :: threads

        do threads = 1, 2
            !$ call omp_set_num_threads(threads)
            results = 0
            runner%results => results
            call run_tasks(runner, n_tasks, err)
            call check(t, .not. allocated(err) .and. all(results == expected()), &
                       'task farm: every unit of every task stored once, in its place')
        end do
    end subroutine test_every_unit_once

    !> `mine` runs only the tasks it marks; units done already are skipped; a stop asked by
    !> the monitor ends the farm early, every stored unit told to the monitor with the total.
    subroutine test_mine_done_and_stop(t)
        type(tally_t), intent(inout) :: t
        integer, target :: results(n_tasks, n_tasks)
        type(toy_runner_t) :: runner
        type(stop_after_t) :: monitor
        type(error_t), allocatable :: err
        integer :: want(n_tasks, n_tasks), k

        !$ call omp_set_num_threads(2)
        results = 0
        runner%results => results
        runner%stage = stage_samples
        call run_tasks(runner, n_tasks, err, mine=[(modulo(k, 2) == 0, k=1, n_tasks)])
        want = expected()
        want(:, 1::2) = 0
        call check(t, .not. allocated(err) .and. all(results == want), &
                   'task farm: only the tasks mine marks run')
        results(1, 4) = -1  ! "done" before: must stay as it is
        call run_tasks(runner, n_tasks, err)
        want = expected()
        want(1, 4) = -1
        call check(t, .not. allocated(err) .and. all(results == want), &
                   'task farm: units done already are skipped')
        results = 0
        monitor%limit = 5
        call run_tasks(runner, n_tasks, err, monitor=monitor)
        call check(t, .not. allocated(err) .and. count(results /= 0) >= 5 .and. &
                   count(results /= 0) < count(expected() /= 0), &
                   'task farm: a stop asked by the monitor ends it early')
        call check(t, monitor%calls == count(results /= 0) .and. monitor%told_right, &
                   'task farm: the monitor is told every unit stored, with its stage and total')
    end subroutine test_mine_done_and_stop

    !> Task 1 fails after a wait, task 2 at once: with 2 threads task 2's error comes first in
    !> time, yet task 1's is returned (1 thread: task 1's too, the only one met).
    subroutine test_first_error_by_task_order(t)
        type(tally_t), intent(inout) :: t
        integer, target :: results(n_tasks, n_tasks)
        type(toy_runner_t) :: runner
        type(error_t), allocatable :: err
        integer :: threads

        do threads = 1, 2
            !$ call omp_set_num_threads(threads)
            results = 0
            runner%results => results
            runner%slow_failure = 1
            runner%slow_seconds = 0.3
            runner%fast_failure = 2
            call run_tasks(runner, n_tasks, err)
            call check(t, allocated(err), 'task farm: a failing task is an error')
            if (allocated(err)) call check(t, err%message == 'toy: task 1 failed', &
                                           'task farm: the first error by task order, '// &
                                           'not by time: '//err%message)
        end do
    end subroutine test_first_error_by_task_order

    !> A third kind's checkpoint: written and read back bit for bit; another magic, another
    !> input text and a short payload refused with their messages; no file, nothing found.
    subroutine test_checkpoint_protocol(t)
        type(tally_t), intent(inout) :: t
        type(checkpoint_t) :: ck
        type(error_t), allocatable :: err
        character(len=:), allocatable :: path
        integer :: values(5), got(5)
        logical :: found

        path = temp_prefix()//'toy.ckpt'
        values = [3, -1, huge(1), 0, 7]
        call checkpoint_create(ck, path, '&toy', 'ICTOY001', 'input text', err)
        if (.not. allocated(err)) write (ck%unit, iostat=ck%ios, iomsg=ck%msg) values
        if (.not. allocated(err)) call checkpoint_commit(ck, err)
        call check(t, .not. allocated(err), 'checkpoint: written')
        call checkpoint_open(ck, path, '&toy', 'ICTOY001', 'input text', found, err)
        call check(t, found .and. .not. allocated(err), 'checkpoint: found and ours')
        if (found .and. .not. allocated(err)) then
            read (ck%unit, iostat=ck%ios) got
            call checkpoint_close(ck, err)
            call check(t, .not. allocated(err) .and. all(got == values), &
                       'checkpoint: read back as written')
        end if
        call checkpoint_open(ck, path, '&toy', 'ICTOY002', 'input text', found, err)
        call check(t, refused(err, "&toy: '"//path//"' is a checkpoint of another input"), &
                   'checkpoint: another magic refused')
        call checkpoint_open(ck, path, '&toy', 'ICTOY001', 'input texT', found, err)
        call check(t, refused(err, "&toy: '"//path//"' is a checkpoint of another input"), &
                   'checkpoint: another input text refused')
        call checkpoint_open(ck, path, '&toy', 'ICTOY001', 'input text', found, err)
        if (found .and. .not. allocated(err)) then
            read (ck%unit, iostat=ck%ios) got, got(1)  ! one value more than written
            call checkpoint_close(ck, err)
        end if
        call check(t, refused(err, "&toy: the checkpoint '"//path//"' is damaged"), &
                   'checkpoint: a short payload is damage')
        call remove_file(path)
        call checkpoint_open(ck, path, '&toy', 'ICTOY001', 'input text', found, err)
        call check(t, .not. found .and. .not. allocated(err), 'checkpoint: none, none found')
    end subroutine test_checkpoint_protocol

    logical function refused(err, start)
        type(error_t), allocatable, intent(in) :: err
        character(len=*), intent(in) :: start

        refused = allocated(err)
        if (refused) refused = index(err%message, start) == 1
    end function refused

    pure function expected() result(want)
        integer :: want(n_tasks, n_tasks)
        integer :: u, k

        want = 0
        do k = 1, n_tasks
            do u = 1, k
                want(u, k) = 1000*k + u
            end do
        end do
    end function expected

    integer function toy_units(runner, t)
        class(toy_runner_t), intent(in) :: runner
        integer, intent(in) :: t

        toy_units = t
    end function toy_units

    logical function toy_done(runner, t, u)
        class(toy_runner_t), intent(in) :: runner
        integer, intent(in) :: t, u

        toy_done = runner%results(u, t) /= 0
    end function toy_done

    subroutine toy_run_unit(runner, t, u, output, err)
        class(toy_runner_t), intent(in) :: runner
        integer, intent(in) :: t, u
        class(task_output_t), allocatable, intent(out) :: output
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: start, now, rate

        if (t == runner%slow_failure) then
            call system_clock(start, rate)
            do
                call system_clock(now)
                if (now - start >= runner%slow_seconds*rate) exit
            end do
        end if
        if (t == runner%slow_failure .or. t == runner%fast_failure) then
            allocate (err)
            err%message = 'toy: task '//achar(iachar('0') + t)//' failed'
            return
        end if
        output = toy_output_t(1000*t + u)
    end subroutine toy_run_unit

    subroutine toy_store(runner, t, u, output)
        class(toy_runner_t), intent(inout) :: runner
        integer, intent(in) :: t, u
        class(task_output_t), intent(in) :: output

        select type (output)
        type is (toy_output_t)
            runner%results(u, t) = output%value
        end select
    end subroutine toy_store

    subroutine toy_progress(runner, done, total)
        class(toy_runner_t), intent(in) :: runner
        integer(i8), intent(out) :: done, total

        done = count(runner%results /= 0)
        total = count(expected() /= 0)
    end subroutine toy_progress

    logical function stop_after(monitor, stage, done, total) result(keep_going)
        class(stop_after_t), intent(inout) :: monitor
        integer, intent(in) :: stage
        integer(i8), intent(in) :: done, total

        monitor%calls = monitor%calls + 1
        monitor%told_right = monitor%told_right .and. stage == stage_samples .and. &
                             done == monitor%calls .and. total == count(expected() /= 0)
        keep_going = done < monitor%limit
    end function stop_after

    function temp_prefix() result(prefix)
        character(len=:), allocatable :: prefix
        character(len=512) :: dir
        character(len=24) :: stamp
        integer :: length, status
        integer(i8) :: clock

        call get_environment_variable('TMPDIR', dir, length, status)
        if (status /= 0 .or. length == 0) dir = '/tmp'
        call system_clock(clock)
        write (stamp, '(i0)') clock
        prefix = trim(dir)//'/impactchain-test-farm-'//trim(stamp)//'-'
    end function temp_prefix

end module test_task_farm
