!> Every check a run makes before it starts, for any kind of run, creating nothing: what
!> `--check` runs after reading the input, and what the MPI driver runs on every rank before
!> rank 0 opens the output. The runs themselves make the same checks through the same
!> procedures (check_run_start, check_sweep, check_census, then output_begin's output_check), so
!> an input that passes here is refused by none of them before it starts.
!> Infrastructure, no model section.
module chain_preflight
    use chain_error, only: error_t
    use chain_config, only: config_t
    use chain_output, only: output_check
    use chain_sim, only: check_run_start
    use chain_sweep, only: check_sweep, plan_sweep
    use chain_census_file, only: check_census
    implicit none
    private
    public :: check_before_run

contains

    !> The checks of the run cfg describes (a continuation, a census, a sweep or a single
    !> run, as app/main.f90 tells them apart): sizes against &output max_size_mb, every point
    !> of a sweep, and the output file (an existing one without overwrite, its directory); for
    !> a single run also its initial state, or the stopped run it would continue.
    subroutine check_before_run(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err

        if (cfg%continuation) then
            call output_check(cfg%output_file, cfg%overwrite, err)
        else if (cfg%census) then
            call check_census(cfg, err)
            if (.not. allocated(err)) call output_check(cfg%output_file, cfg%overwrite, err)
        else if (cfg%sweep) then
            call check_sweep(cfg, plan_sweep(cfg), err)
            if (.not. allocated(err)) call output_check(cfg%output_file, cfg%overwrite, err)
        else
            call check_run_start(cfg, err)
        end if
    end subroutine check_before_run

end module chain_preflight
