!> fpm test: the suites of the measure layer (src/measure): periodic orbits, Floquet
!> multipliers and their branches; each can be run alone (`fpm test -- <suite>`, see
!> test/support/src/suites.f90); prints "N passed, M failed".
program measure_tests
    use suites, only: suite_runner_t
    use test_orbit, only: run_orbit_tests
    use test_branch, only: run_branch_tests
    use test_branch_switch, only: run_switch_tests
    use test_budd_dux, only: run_budd_dux_tests
    use test_graze, only: run_graze_tests
    use test_branch_corner, only: run_branch_corner_tests
    use test_curve, only: run_curve_tests
    use test_curve_branch_point, only: run_curve_branch_point_tests
    use test_curve_ns, only: run_curve_ns_tests
    use test_curve_codim2, only: run_curve_codim2_tests
    implicit none
    type(suite_runner_t) :: runner

    call runner%start()
    call runner%run('orbit', run_orbit_tests)
    call runner%run('branch', run_branch_tests)
    call runner%run('switch', run_switch_tests)
    call runner%run('buddux', run_budd_dux_tests)
    call runner%run('graze', run_graze_tests)
    call runner%run('corner', run_branch_corner_tests)
    call runner%run('curve', run_curve_tests)
    call runner%run('bpcurve', run_curve_branch_point_tests)
    call runner%run('nscurve', run_curve_ns_tests)
    call runner%run('codim2', run_curve_codim2_tests)
    call runner%finish()
end program measure_tests
