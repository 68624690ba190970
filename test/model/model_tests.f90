!> fpm test: the suites of the model layer (src/model): the flow between impacts, the gaps,
!> the impact law; each can be run alone (`fpm test -- <suite>`, see
!> test/support/src/suites.f90); prints "N passed, M failed".
program model_tests
    use suites, only: suite_runner_t
    use test_flow, only: run_flow_tests
    use test_gaps, only: run_gap_tests
    use test_impact, only: run_impact_tests
    implicit none
    type(suite_runner_t) :: runner

    call runner%start()
    call runner%run('flow', run_flow_tests)
    call runner%run('gaps', run_gap_tests)
    call runner%run('impact', run_impact_tests)
    call runner%finish()
end program model_tests
