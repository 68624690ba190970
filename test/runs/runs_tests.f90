!> fpm test: the suites of the runs layer (src/runs): the HDF5 layer, parameter sweeps and
!> their checkpoints, censuses and the task farm. The last four set the process's OpenMP
!> thread count, so this program runs no suite whose results depend on it. Each can be run
!> alone (`fpm test -- <suite>`, see test/support/src/suites.f90); prints "N passed,
!> M failed".
program runs_tests
    use suites, only: suite_runner_t
    use test_hdf5, only: run_hdf5_tests
    use test_sweep, only: run_sweep_tests, run_checkpoint_tests
    use test_census, only: run_census_tests
    use test_task_farm, only: run_task_farm_tests
    implicit none
    type(suite_runner_t) :: runner

    call runner%start()
    call runner%run('hdf5', run_hdf5_tests)
    call runner%run('sweep', run_sweep_tests)
    call runner%run('checkpoint', run_checkpoint_tests)
    call runner%run('census', run_census_tests)
    call runner%run('taskfarm', run_task_farm_tests)
    call runner%finish()
end program runs_tests
