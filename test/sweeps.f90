!> fpm test: the parameter-sweep, census and task-farm suites (test/test_sweep.f90,
!> test/test_census.f90, test/test_task_farm.f90),
!> in a program of their own, as they set the process's OpenMP thread count; each can be run
!> alone (`fpm test -- <suite>`, see test/suites.f90); prints "N passed, M failed".
program sweeps
    use suites, only: suite_runner_t
    use test_sweep, only: run_sweep_tests, run_checkpoint_tests
    use test_census, only: run_census_tests
    use test_task_farm, only: run_task_farm_tests
    implicit none
    type(suite_runner_t) :: runner

    call runner%start()
    call runner%run('sweep', run_sweep_tests)
    call runner%run('checkpoint', run_checkpoint_tests)
    call runner%run('census', run_census_tests)
    call runner%run('taskfarm', run_task_farm_tests)
    call runner%finish()
end program sweeps
