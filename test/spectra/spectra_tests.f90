!> fpm test: the suites of the spectra layer (src/spectra): Lyapunov exponents and covariant
!> vectors; each can be run alone (`fpm test -- <suite>`, see test/support/src/suites.f90); prints "N passed, M failed".
program spectra_tests
    use suites, only: suite_runner_t
    use test_lyapunov, only: run_lyapunov_tests
    use test_clv, only: run_clv_tests
    implicit none
    type(suite_runner_t) :: runner

    call runner%start()
    call runner%run('lyapunov', run_lyapunov_tests)
    call runner%run('clv', run_clv_tests)
    call runner%finish()
end program spectra_tests
