!> fpm test: every physics suite of impactchain (and its event queue); prints "N passed, M failed".
program main
    use testing, only: tally_t, report
    use test_flow, only: run_flow_tests
    use test_gaps, only: run_gap_tests
    use test_impact, only: run_impact_tests
    use test_engine, only: run_engine_tests
    use test_queue, only: run_queue_tests
    use test_lyapunov, only: run_lyapunov_tests
    use test_corners, only: run_corner_tests
    use test_invariants, only: run_invariant_tests
    implicit none
    type(tally_t) :: t, before

    call run_flow_tests(t)
    call report(t, before, 'flow')
    call run_gap_tests(t)
    call report(t, before, 'gaps')
    call run_impact_tests(t)
    call report(t, before, 'impact')
    call run_queue_tests(t)
    call report(t, before, 'queue')
    call run_engine_tests(t)
    call report(t, before, 'engine')
    call run_lyapunov_tests(t)
    call report(t, before, 'lyapunov')
    call run_corner_tests(t)
    call report(t, before, 'corners')
    call run_invariant_tests(t)
    call report(t, before, 'invariants')
    write (*, '(i0,a,i0,a)') t%passed, ' passed, ', t%failed, ' failed'
    if (t%failed > 0) error stop 1
end program main
