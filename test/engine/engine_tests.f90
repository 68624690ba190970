!> fpm test: the suites of the engine layer (src/engine): the event queue, the event-driven
!> chain, its corners and the invariants of every run; each can be run alone
!> (`fpm test -- <suite>`, see test/support/src/suites.f90); prints "N passed, M failed".
program engine_tests
    use suites, only: suite_runner_t
    use test_queue, only: run_queue_tests
    use test_engine, only: run_engine_tests
    use test_corners, only: run_corner_tests
    use test_invariants, only: run_invariant_tests
    implicit none
    type(suite_runner_t) :: runner

    call runner%start()
    call runner%run('queue', run_queue_tests)
    call runner%run('engine', run_engine_tests)
    call runner%run('corners', run_corner_tests)
    call runner%run('invariants', run_invariant_tests)
    call runner%finish()
end program engine_tests
