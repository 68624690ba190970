!> fpm test: every physics suite of impactchain (and its event queue), each of which can be run
!> alone (`fpm test -- <suite>`, see test/suites.f90); prints "N passed, M failed".
program main
    use suites, only: suite_runner_t
    use test_flow, only: run_flow_tests
    use test_gaps, only: run_gap_tests
    use test_impact, only: run_impact_tests
    use test_engine, only: run_engine_tests
    use test_queue, only: run_queue_tests
    use test_lyapunov, only: run_lyapunov_tests
    use test_corners, only: run_corner_tests
    use test_invariants, only: run_invariant_tests
    use test_hdf5, only: run_hdf5_tests
    use test_orbit, only: run_orbit_tests
    use test_branch, only: run_branch_tests
    use test_clv, only: run_clv_tests
    implicit none
    type(suite_runner_t) :: runner

    call runner%start()
    call runner%run('flow', run_flow_tests)
    call runner%run('gaps', run_gap_tests)
    call runner%run('impact', run_impact_tests)
    call runner%run('queue', run_queue_tests)
    call runner%run('engine', run_engine_tests)
    call runner%run('lyapunov', run_lyapunov_tests)
    call runner%run('corners', run_corner_tests)
    call runner%run('invariants', run_invariant_tests)
    call runner%run('hdf5', run_hdf5_tests)
    call runner%run('orbit', run_orbit_tests)
    call runner%run('branch', run_branch_tests)
    call runner%run('clv', run_clv_tests)
    call runner%finish()
end program main
