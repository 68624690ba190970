!> Parameter sweeps (docs/model.md section 8, chain_sweep) through the library, without the CLI.
!> Suite `sweep`: the number of points and their values, the configuration of one point,
!> identical results with 1 and 2 OpenMP threads, a continuation equal to the same steps run one
!> by one from files (`&initial kind = 'file'`). Suite `checkpoint`: a sweep stopped,
!> checkpointed and resumed equal to an uninterrupted one, and checkpoints that cannot be
!> written. The CLI, MPI and signal tests are in test/python/test_sweep.py.
module test_sweep
    use, intrinsic :: iso_fortran_env, only: output_unit
    !$ use omp_lib, only: omp_set_num_threads
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_config, only: config_t, read_config, validate_config
    use chain_sim, only: simulate_to_file
    use chain_record, only: record_result_t
    use chain_output, only: read_final_state
    use chain_state, only: chain_state_t
    use chain_model, only: model_t
    use chain_sweep, only: sweep_plan_t, sweep_result_t, plan_sweep, &
                           sweep_result_init, sweep_point_config, check_sweep_size
    use chain_sweep_run, only: run_sweep_branches, run_sweep, sweep_summary_t
    use chain_sweep_checkpoint, only: save_checkpoint, load_checkpoint, branch_record_sizes
    use chain_files, only: remove_file
    use chain_preflight, only: check_before_run
    use chain_monitor, only: monitor_t, stage_points
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_sweep_tests, run_checkpoint_tests

    !> Asks the sweep to stop once five points are done (and records what it was told).
    type, extends(monitor_t) :: stop_after_five_t
        integer :: calls = 0
        integer :: points = 0            !! of the sweep
        logical :: told_points = .true.  !! every call was about sweep points, of the right total
    contains
        procedure :: keep_going => stop_after_five
    end type stop_after_five_t

contains

    subroutine run_sweep_tests(t)
        type(tally_t), intent(inout) :: t

        call test_axes(t)
        call test_point_limit(t)
        call test_sweep_size(t)
        call test_checks_before_run(t)
        call test_point_config(t)
        call test_threads(t)
        call test_continuation_equals_files(t)
    end subroutine run_sweep_tests

    subroutine run_checkpoint_tests(t)
        type(tally_t), intent(inout) :: t

        call test_checkpoint_resume(t)
        call test_checkpoint_write_failure(t)
    end subroutine run_checkpoint_tests

    !> Points per axis from the index (never accumulated), rounding-safe at both ends.
    subroutine test_axes(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg
        type(sweep_plan_t) :: plan
        type(sweep_result_t) :: res

        ! the paper's figure 10: A from 6 down to 1 in steps of 0.001
        call config_from(cfg, "&sweep parameter = 'amplitude', start = 6.0, stop = 1.0, "// &
                         "step = -0.001 /", 'axes')
        plan = plan_sweep(cfg)
        call check(t, plan%n_points == 5001 .and. plan%n_branches == 1 .and. &
                   plan%points_per_branch == 5001, 'figure 10 axis: 5001 points, one branch')
        call sweep_result_init(res, cfg, plan)
        call check_close(t, res%values(1, 5001), 1.0_wp, 'figure 10 axis: last value', &
                         abs_tol=4*epsilon(1.0_wp))
        call check(t, res%values(1, 2501) == 6.0_wp + 2500*(-0.001_wp), &
                   'values come from the index: start + (i - 1) step')
        ! a step that does not divide the range stops before `stop`
        call config_from(cfg, "&sweep parameter = 'omega', start = 1.0, stop = 2.0, "// &
                         "step = 0.3 /", 'axes')
        plan = plan_sweep(cfg)
        call check(t, plan%n_points == 4, '1 .. 2 step 0.3: 4 points (1.0 .. 1.9)')
        call config_from(cfg, "&sweep parameter = 'omega', start = 0.1, stop = 0.7, "// &
                         "step = 0.1 /", 'axes')
        plan = plan_sweep(cfg)
        call check(t, plan%n_points == 7, '0.1 .. 0.7 step 0.1: 7 points')
        ! a grid: index i along parameter runs fastest; one branch per value of parameter2
        call config_from(cfg, "&sweep parameter = 'amplitude', start = 1.0, stop = 2.0, "// &
                         "step = 0.5, parameter2 = 'damping', start2 = 0.1, stop2 = 0.05, "// &
                         "step2 = -0.05 /", 'axes')
        plan = plan_sweep(cfg)
        call sweep_result_init(res, cfg, plan)
        call check(t, plan%n_points == 6 .and. plan%n_branches == 2 .and. plan%n_axes == 2, &
                   '2-D continuation grid: 6 points in 2 branches')
        call check(t, all(res%values(:, 4) == [1.0_wp, 0.05_wp]) .and. &
                   all(res%values(:, 3) == [2.0_wp, 0.1_wp]), '2-D grid: point order')
        call config_from(cfg, "&sweep parameter = 'amplitude', start = 1.0, stop = 2.0, "// &
                         "step = 0.5, mode = 'independent', parameter2 = 'damping', "// &
                         "start2 = 0.1, stop2 = 0.05, step2 = -0.05 /", 'axes')
        plan = plan_sweep(cfg)
        call check(t, plan%n_branches == 6, 'independent grid: a branch per point')
    end subroutine test_axes

    !> At most 1e7 points in all: along one parameter, and in a 2-D grid the product of its
    !> axes (each axis alone within the limit), refused when read, naming the keys.
    subroutine test_point_limit(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg
        type(error_t), allocatable :: err

        call config_from(cfg, "&sweep parameter = 'amplitude', start = 1.0, stop = 2.0, "// &
                         "step = 0.5, parameter2 = 'damping', start2 = 0.1, stop2 = 0.05, "// &
                         "step2 = -0.05 /", 'limit')
        cfg%sweep_step = 1.0e-4_wp           ! 10001 values
        cfg%sweep_stop2 = 0.9_wp
        cfg%sweep_step2 = 1.0e-4_wp          ! 8001 values
        call validate_config(cfg, err)
        call check(t, allocated(err), 'a 10001 x 8001 grid is refused')
        if (allocated(err)) call check(t, err%message == "&sweep: start, stop, step and "// &
                                       "start2, stop2, step2 give 10001 x 8001 = 80018001 "// &
                                       "points; a sweep has at most 1e7", err%message)
        cfg%sweep_stop2 = 0.1_wp + 999*1.0e-4_wp ! 10001 x 1000 = 10010001
        call validate_config(cfg, err)
        call check(t, allocated(err), 'a grid just above 1e7 points is refused')
        cfg%sweep_stop = 1.0_wp + 9999*1.0e-4_wp ! 10000 x 1000
        call validate_config(cfg, err)
        call check(t, .not. allocated(err), 'a grid of exactly 1e7 points is accepted')
        ! along one parameter: 1e7 steps is 1e7 + 1 points, one too many
        cfg%sweep_parameter2 = ''
        cfg%sweep_start = 0
        cfg%sweep_stop = 1
        cfg%sweep_step = 1.0e-7_wp
        call validate_config(cfg, err)
        call check(t, allocated(err), '1e7 + 1 points along one parameter are refused')
        if (allocated(err)) call check(t, err%message == "&sweep: start, stop, step give "// &
                                       "10000001 points; a sweep has at most 1e7", err%message)
        cfg%sweep_start = 1
        cfg%sweep_stop = 1.0e7_wp
        cfg%sweep_step = 1
        call validate_config(cfg, err)
        call check(t, .not. allocated(err), '1e7 points along one parameter are accepted')
    end subroutine test_point_limit

    !> check_sweep_size refuses exactly what the sweep would hold, measured on the arrays
    !> themselves: in the file /sweep's (x, collisions, periods, and with exponents their
    !> errors, blocks and ky), in memory every array of sweep_result_t plus the largest copy
    !> (a branch packed for a checkpoint; a 2-D sweep's x reordered for the file).
    subroutine test_sweep_size(t)
        type(tally_t), intent(inout) :: t
        character(len=*), parameter :: sweeps(3) = [character(len=160) :: &
            "&sweep parameter = 'amplitude', start = 1.0, stop = 2.0, step = 0.001 /", &
            "&sweep parameter = 'amplitude', start = 1.0, stop = 2.0, step = 0.001, "// &
            "mode = 'independent' /", &
            "&sweep parameter = 'amplitude', start = 1.0, stop = 2.0, step = 0.01, "// &
            "parameter2 = 'damping', start2 = 0.1, stop2 = 0.05, step2 = -0.05 /"]
        character(len=*), parameter :: lyapunov(3) = [character(len=24) :: &
            "&lyapunov vectors = 2 /", "", ""]
        type(config_t) :: cfg
        type(sweep_plan_t) :: plan
        type(sweep_result_t) :: res
        type(error_t), allocatable :: err
        real(wp) :: file_mb, memory_mb, copy
        integer :: j, nr, ni
        logical :: refused_file, memory_alone, refused_memory, accepted

        do j = 1, size(sweeps)
            call config_from(cfg, trim(lyapunov(j))//new_line('a')//trim(sweeps(j)), 'size')
            plan = plan_sweep(cfg)
            call sweep_result_init(res, cfg, plan)
            file_mb = real(bytes_real(res%x) + bytes_real(res%collisions) + &
                           bytes_int(res%period), wp)
            if (plan%k > 0) file_mb = file_mb + bytes_real(res%exponents) + &
                                      bytes_real(res%stderr) + bytes_int8(res%stderr_block) + &
                                      bytes_real(res%ky)
            file_mb = file_mb/1.0e6_wp
            call branch_record_sizes(cfg, plan, nr, ni)
            copy = 8.0_wp*(nr + ni)
            if (plan%n_axes == 2) copy = max(copy, real(bytes_real(res%x), wp))
            memory_mb = (bytes_real(res%values) + bytes_real(res%x) + &
                         bytes_real(res%collisions) + bytes_int(res%period) + &
                         bytes_real(res%exponents) + bytes_real(res%stderr) + &
                         bytes_int8(res%stderr_block) + bytes_real(res%ky) + &
                         storage_size(res%done)/8*size(res%done) + copy)/1.0e6_wp
            cfg%max_size_mb = file_mb*(1 - 1.0e-9_wp)
            call check_sweep_size(cfg, plan, err)
            refused_file = allocated(err)
            if (refused_file) refused_file = index(err%message, "&sweep: the records of "// &
                                                   "this sweep need about") == 1 .and. &
                                             index(err%message, "in the file") > 0
            cfg%max_size_mb = file_mb*(1 + 1.0e-9_wp)
            call check_sweep_size(cfg, plan, err)
            memory_alone = allocated(err)
            if (memory_alone) memory_alone = index(err%message, "MB of memory") > 0
            cfg%max_size_mb = memory_mb*(1 - 1.0e-9_wp)
            call check_sweep_size(cfg, plan, err)
            refused_memory = allocated(err)
            if (refused_memory) refused_memory = index(err%message, "&sweep: this sweep "// &
                                                       "needs about") == 1
            cfg%max_size_mb = memory_mb*(1 + 1.0e-9_wp)
            call check_sweep_size(cfg, plan, err)
            accepted = .not. allocated(err)
            call check(t, refused_file .and. memory_alone .and. refused_memory .and. accepted, &
                       'sweep size '//trim(sweeps(j))//': the file and the memory counted '// &
                       'exactly, each refused just above max_size_mb')
        end do
        ! the keys to change are named; a 2-D sweep's include the second axis
        cfg%max_size_mb = 0.01_wp
        call check_sweep_size(cfg, plan, err)
        call check(t, allocated(err), 'a 2-D sweep over max_size_mb is refused')
        if (allocated(err)) call check(t, index(err%message, "202 points x n x cycles") > 0 &
                                       .and. index(err%message, "lower the points (&sweep "// &
                                                   "start, stop, step, start2, stop2, step2)"// &
                                                   " or &run cycles") > 0, err%message)
    end subroutine test_sweep_size

    !> check_before_run refuses, creating nothing, what run_sweep refuses before it starts:
    !> a sweep over max_size_mb, an output in a missing directory, an existing output without
    !> overwrite; run_sweep refuses the same with the same message and leaves no file, and
    !> what passes the check runs.
    subroutine test_checks_before_run(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg
        type(sweep_summary_t) :: summary
        type(error_t), allocatable :: err, ran
        character(len=:), allocatable :: tmp
        logical :: left
        integer :: u

        tmp = temp_prefix()
        call config_from(cfg, "&sweep parameter = 'amplitude', start = 1.0, stop = 2.0, "// &
                         "step = 0.25 /", 'check')
        cfg%output_file = tmp//'check.h5'
        cfg%max_size_mb = 1.0e-4_wp
        call check_before_run(cfg, err)
        call run_sweep(cfg, summary, ran)
        call check(t, allocated(err) .and. allocated(ran), 'a sweep over max_size_mb is '// &
                   'refused by the check and by the run')
        if (allocated(err) .and. allocated(ran)) call check(t, err%message == ran%message &
            .and. index(err%message, '&sweep: the records of this sweep') == 1, &
            'the same message: '//err%message)
        cfg%max_size_mb = 4096
        cfg%output_file = tmp//'missing/check.h5'
        call check_before_run(cfg, err)
        call run_sweep(cfg, summary, ran)
        call check(t, allocated(err) .and. allocated(ran), 'an output in a missing '// &
                   'directory is refused by the check and by the run')
        if (allocated(err) .and. allocated(ran)) call check(t, err%message == ran%message &
            .and. index(err%message, "the directory '"//tmp//"missing' does not exist") > 0, &
            'the same message: '//err%message)
        cfg%output_file = tmp//'check.h5'
        open (newunit=u, file=cfg%output_file, status='replace', action='write')
        close (u)
        call check_before_run(cfg, err)
        call run_sweep(cfg, summary, ran)
        call check(t, allocated(err) .and. allocated(ran), 'an existing output is refused '// &
                   'by the check and by the run')
        if (allocated(err) .and. allocated(ran)) call check(t, err%message == ran%message &
            .and. index(err%message, 'exists') > 0, 'the same message: '//err%message)
        cfg%overwrite = .true.
        call check_before_run(cfg, err)
        call check(t, .not. allocated(err), 'with overwrite the check passes')
        call remove_file(cfg%output_file)
        inquire (file=tmp//'check.h5.part', exist=left)
        call check(t, .not. left, 'no .part is left by a refused sweep')
        call run_sweep(cfg, summary, ran)
        call check(t, .not. allocated(ran) .and. summary%complete, 'what passes the check runs')
        call remove_file(cfg%output_file)
    end subroutine test_checks_before_run

    pure integer(i8) function bytes_real(a)
        real(wp), intent(in) :: a(..)

        bytes_real = storage_size(1.0_wp)/8*int(size(a), i8)
    end function bytes_real

    pure integer(i8) function bytes_int(a)
        integer, intent(in) :: a(..)

        bytes_int = storage_size(1)/8*int(size(a), i8)
    end function bytes_int

    pure integer(i8) function bytes_int8(a)
        integer(i8), intent(in) :: a(..)

        bytes_int8 = storage_size(1_i8)/8*int(size(a), i8)
    end function bytes_int8

    !> One point: the parameter set (every bond for 'spacing'), checked like any input.
    subroutine test_point_config(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg, point
        type(sweep_plan_t) :: plan
        type(error_t), allocatable :: err

        call config_from(cfg, "&sweep parameter = 'spacing', start = 1.0, stop = 1.2, "// &
                         "step = 0.1 /", 'point')
        plan = plan_sweep(cfg)
        call sweep_point_config(cfg, plan, 3, point, err)
        call check(t, .not. allocated(err), 'spacing point 3 is valid')
        if (allocated(err)) return
        call check(t, size(point%model%spacing) == cfg%model%n + 1 .and. &
                   all(point%model%spacing == 1.0_wp + 2*0.1_wp), "'spacing' sets every bond")
        call check(t, .not. point%sweep .and. .not. point%record%record_events, &
                   'a point is a plain run that keeps no events')
        call config_from(cfg, "&sweep parameter = 'restitution', start = 0.9, stop = 1.1, "// &
                         "step = 0.1 /", 'point')
        plan = plan_sweep(cfg)
        call sweep_point_config(cfg, plan, 3, point, err)
        call check(t, allocated(err), 'restitution 1.1 is refused')
        if (allocated(err)) call check(t, index(err%message, 'point 3') > 0 .and. &
                                       index(err%message, 'restitution') > 0 .and. &
                                       index(err%message, '1.1') > 0, &
                                       'the error names the point, parameter and value: '// &
                                       err%message)
    end subroutine test_point_config

    !> The same grid with 1 and 2 threads, continuation and independent: equal bit for bit.
    subroutine test_threads(t)
        type(tally_t), intent(inout) :: t
        character(len=*), parameter :: modes(2) = [character(len=12) :: 'continuation', &
                                                   'independent']
        type(config_t) :: cfg
        type(sweep_result_t) :: one, two
        integer :: m

        do m = 1, 2
            call config_from(cfg, "&lyapunov vectors = 4 /"//new_line('a')// &
                             "&sweep parameter = 'amplitude', start = 1.8, stop = 2.4, "// &
                             "step = 0.2, mode = '"//trim(modes(m))//"', parameter2 = "// &
                             "'omega', start2 = 1.4, stop2 = 1.6, step2 = 0.1 /", 'threads')
            !$ call omp_set_num_threads(1)
            call whole_sweep(t, cfg, one)
            !$ call omp_set_num_threads(2)
            call whole_sweep(t, cfg, two)
            call check(t, all(one%done) .and. all(two%done), trim(modes(m))//': all done')
            call check(t, same(one, two), trim(modes(m))//': 1 and 2 threads agree bit for bit')
            call check(t, any(one%collisions > 0) .and. any(one%exponents(1, :) /= 0), &
                       trim(modes(m))//': the sweep has impacts and exponents')
        end do
    end subroutine test_threads

    !> A continuation sweep ends where the same steps, run one by one with
    !> `&initial kind = 'file'` on the previous step's output, end: same x, v, cycle, time.
    subroutine test_continuation_equals_files(t)
        type(tally_t), intent(inout) :: t
        character(len=*), parameter :: chain = "&chain n = 5, omega = 1.9, restitution = 0.5, "
        character(len=*), parameter :: run = "&run transient = 20, cycles = 10, "// &
                                             "record_events = .false. /"
        type(config_t) :: cfg, step
        type(sweep_plan_t) :: plan
        type(sweep_result_t) :: res
        type(chain_state_t), allocatable :: starts(:)
        type(record_result_t) :: summary
        type(error_t), allocatable :: err
        type(chain_state_t) :: last
        type(model_t) :: file_model
        character(len=:), allocatable :: previous, path, tmp
        integer :: j

        tmp = temp_prefix()
        call config_text(cfg, chain//"amplitude = 3.0 /"//new_line('a')//run//new_line('a')// &
                         "&sweep parameter = 'amplitude', start = 3.0, stop = 2.8, "// &
                         "step = -0.1 /", 'cont')
        plan = plan_sweep(cfg)
        call sweep_result_init(res, cfg, plan)
        allocate (starts(plan%n_branches))
        call run_sweep_branches(cfg, plan, res, starts, err)
        call check(t, .not. allocated(err) .and. all(res%done), 'continuation sweep runs')
        if (allocated(err)) return
        previous = ''
        ! each step's amplitude is the sweep's own value, printed with every digit
        do j = 1, plan%n_points
            call config_text(step, chain//"amplitude = "//real_text(res%values(1, j))//" /"// &
                             new_line('a')//run, 'step')
            if (j > 1) then
                step%initial_kind = 'file'
                step%initial_file = previous
            end if
            path = tmp//'step'//char(iachar('0') + j)//'.h5'
            step%output_file = path
            step%overwrite = .true.
            call simulate_to_file(step, summary, err)
            call check(t, .not. allocated(err), 'step run from a file')
            if (allocated(err)) return
            if (j > 1) call remove_file(previous)
            previous = path
        end do
        call read_final_state(previous, cfg%model%n, last, file_model, err)
        call remove_file(previous)
        call check(t, .not. allocated(err), 'final state of the last step')
        if (allocated(err)) return
        call check(t, all(last%x == starts(1)%x) .and. all(last%v == starts(1)%v) .and. &
                   last%cycle == starts(1)%cycle .and. last%time == starts(1)%time .and. &
                   all(last%contact == starts(1)%contact), &
                   'continuation = steps from files, bit for bit')
        call check(t, all(last%x == res%x(:, 10, 3)), 'the last record of the sweep is the final x')
        call check(t, last%cycle == 3*(20 + 10), 'the drive cycle count runs on over the steps')
    end subroutine test_continuation_equals_files

    !> Stopped after a few points, saved, loaded into a fresh result and finished: the same
    !> as an uninterrupted sweep. A checkpoint of another input is refused.
    subroutine test_checkpoint_resume(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg, other
        type(sweep_plan_t) :: plan
        type(sweep_result_t) :: whole, part, loaded
        type(chain_state_t), allocatable :: starts(:), loaded_starts(:)
        type(error_t), allocatable :: err
        character(len=:), allocatable :: path, tmp
        type(stop_after_five_t) :: monitor
        integer :: b

        tmp = temp_prefix()
        call config_from(cfg, "&lyapunov vectors = 3 /"//new_line('a')// &
                         "&sweep parameter = 'amplitude', start = 2.4, stop = 1.6, "// &
                         "step = -0.1, parameter2 = 'restitution', start2 = 0.5, "// &
                         "stop2 = 0.7, step2 = 0.1 /", 'ckpt')
        call whole_sweep(t, cfg, whole)
        plan = plan_sweep(cfg)
        call sweep_result_init(part, cfg, plan)
        allocate (starts(plan%n_branches))
        !$ call omp_set_num_threads(2)
        monitor%points = plan%n_points
        call run_sweep_branches(cfg, plan, part, starts, err, monitor=monitor)
        call check(t, .not. allocated(err) .and. count(part%done) >= 5 .and. &
                   .not. all(part%done), 'the sweep stops early when asked')
        call check(t, monitor%calls == count(part%done) .and. monitor%told_points, &
                   'the monitor is told every finished point, with the total')
        path = tmp//'sweep.ckpt'
        call save_checkpoint(path, cfg, plan, part, starts, err)
        call check(t, .not. allocated(err), 'checkpoint written')
        call sweep_result_init(loaded, cfg, plan)
        allocate (loaded_starts(plan%n_branches))
        call load_checkpoint(path, cfg, plan, loaded, loaded_starts, err)
        call check(t, .not. allocated(err), 'checkpoint read')
        if (allocated(err)) return
        call check(t, same(part, loaded) .and. all(part%done .eqv. loaded%done), &
                   'checkpoint round trip keeps the finished points bit for bit')
        do b = 1, plan%n_branches
            call check(t, allocated(loaded_starts(b)%x) .eqv. allocated(starts(b)%x), &
                       'checkpoint round trip keeps which branches resume')
            if (allocated(starts(b)%x) .and. allocated(loaded_starts(b)%x)) &
                call check(t, all(loaded_starts(b)%x == starts(b)%x) .and. &
                           all(loaded_starts(b)%v == starts(b)%v) .and. &
                           all(loaded_starts(b)%contact == starts(b)%contact) .and. &
                           loaded_starts(b)%cycle == starts(b)%cycle .and. &
                           loaded_starts(b)%time == starts(b)%time, &
                           'checkpoint round trip keeps the resume state bit for bit')
        end do
        call run_sweep_branches(cfg, plan, loaded, loaded_starts, err)
        call check(t, .not. allocated(err) .and. all(loaded%done), 'the resumed sweep finishes')
        call check(t, same(whole, loaded), 'stopped + resumed = uninterrupted, bit for bit')
        other = cfg
        other%input_text = cfg%input_text//' '
        deallocate (loaded_starts)
        allocate (loaded_starts(plan%n_branches))
        call load_checkpoint(path, other, plan, loaded, loaded_starts, err)
        call check(t, allocated(err), 'a checkpoint of another input is refused')
        call remove_file(path)
    end subroutine test_checkpoint_resume

    !> A checkpoint that cannot be written (the disk full: the temporary file is /dev/full,
    !> which takes every write and keeps nothing; a missing directory) is an error naming
    !> it, and the previous checkpoint stays as it was.
    subroutine test_checkpoint_write_failure(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg
        type(sweep_plan_t) :: plan
        type(sweep_result_t) :: res, loaded
        type(chain_state_t), allocatable :: starts(:)
        type(error_t), allocatable :: err
        character(len=:), allocatable :: path, tmp
        integer :: status

        tmp = temp_prefix()
        call config_from(cfg, "&sweep parameter = 'amplitude', start = 2.0, stop = 1.8, "// &
                         "step = -0.1 /", 'full')
        plan = plan_sweep(cfg)
        call sweep_result_init(res, cfg, plan)
        allocate (starts(plan%n_branches))
        path = tmp//'full.ckpt'
        call save_checkpoint(path, cfg, plan, res, starts, err)
        call check(t, .not. allocated(err), 'a first checkpoint is written')
        call execute_command_line('ln -s /dev/full '//path//'.tmp', exitstat=status)
        call check(t, status == 0, 'test setup: a link to /dev/full')
        res%done(1) = .true.
        call save_checkpoint(path, cfg, plan, res, starts, err)
        call check(t, allocated(err), 'a checkpoint written to a full disk is an error')
        if (allocated(err)) call check(t, index(err%message, path) > 0, &
                                       'the error names the checkpoint: '//err%message)
        call sweep_result_init(loaded, cfg, plan)
        call load_checkpoint(path, cfg, plan, loaded, starts, err)
        call check(t, .not. allocated(err) .and. .not. any(loaded%done), &
                   'the previous checkpoint is kept')
        call remove_file(path//'.tmp')
        call remove_file(path)
        call save_checkpoint(tmp//'no/such/dir/x.ckpt', cfg, plan, res, starts, err)
        call check(t, allocated(err), 'a checkpoint in a missing directory is an error')
    end subroutine test_checkpoint_write_failure

    logical function stop_after_five(monitor, stage, done, total) result(keep_going)
        class(stop_after_five_t), intent(inout) :: monitor
        integer, intent(in) :: stage
        integer(i8), intent(in) :: done, total

        monitor%calls = monitor%calls + 1
        monitor%told_points = monitor%told_points .and. stage == stage_points .and. &
                              done == monitor%calls .and. total == monitor%points
        keep_going = done < 5
    end function stop_after_five

    subroutine whole_sweep(t, cfg, res)
        type(tally_t), intent(inout) :: t
        type(config_t), intent(in) :: cfg
        type(sweep_result_t), intent(out) :: res
        type(sweep_plan_t) :: plan
        type(chain_state_t), allocatable :: starts(:)
        type(error_t), allocatable :: err

        plan = plan_sweep(cfg)
        call sweep_result_init(res, cfg, plan)
        allocate (starts(plan%n_branches))
        call run_sweep_branches(cfg, plan, res, starts, err)
        call check(t, .not. allocated(err), 'sweep runs')
    end subroutine whole_sweep

    logical function same(a, b)
        type(sweep_result_t), intent(in) :: a, b

        same = all(a%x == b%x) .and. all(a%collisions == b%collisions) .and. &
               all(a%period == b%period) .and. all(a%exponents == b%exponents) .and. &
               all(a%stderr == b%stderr) .and. all(a%ky == b%ky) .and. &
               all(a%values == b%values)
    end function same

    !> A small chaotic-enough chain with the given &sweep (and other groups) appended.
    subroutine config_from(cfg, groups, name)
        type(config_t), intent(out) :: cfg
        character(len=*), intent(in) :: groups, name

        call config_text(cfg, "&chain n = 4, amplitude = 2.0, omega = 1.5, "// &
                         "restitution = 0.7 /"//new_line('a')// &
                         "&initial kind = 'random', seed = 5, x_amp = 0.3, v_amp = 0.5 /"// &
                         new_line('a')//"&run transient = 30, cycles = 12 /"//new_line('a')// &
                         groups, name)
    end subroutine config_from

    !> The configuration of a namelist text (written to a temporary file and read back).
    subroutine config_text(cfg, text, name)
        type(config_t), intent(out) :: cfg
        character(len=*), intent(in) :: text, name
        type(error_t), allocatable :: err
        character(len=:), allocatable :: tmp
        integer :: u

        tmp = temp_prefix()
        open (newunit=u, file=tmp//name//'.nml', status='replace', action='write')
        write (u, '(a)') text
        write (u, '(a)') "&output file = '"//tmp//name//".h5' /"
        close (u)
        call read_config(tmp//name//'.nml', cfg, err)
        call remove_file(tmp//name//'.nml')
        if (allocated(err)) then
            write (output_unit, '(a)') 'test_sweep: bad test input: '//err%message
            error stop 1
        end if
    end subroutine config_text

    function real_text(x) result(text)
        real(wp), intent(in) :: x
        character(len=:), allocatable :: text
        character(len=32) :: buf

        write (buf, '(es24.17)') x
        text = trim(adjustl(buf))
    end function real_text

    !> A fresh prefix for temporary files: $TMPDIR (or /tmp)/impactchain-test-sweep-<clock>-
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
        prefix = trim(dir)//'/impactchain-test-sweep-'//trim(stamp)//'-'
    end function temp_prefix

end module test_sweep
