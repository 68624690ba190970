!> The public API of impactchain in one module: what the command line (app/), the MPI sweep
!> driver (mpi/), the Python layer (f2py/) and the benchmark (bench/) use. Configuration,
!> runs and their results, sweeps (including the pieces a distributed driver needs), the
!> Poincare-map Jacobian of a state, periodic orbits (Newton shooting) and their branches
!> (continuation), attractor censuses, the shared command
!> line, interrupt flag and monitors.
!> A chain is an opaque `chain_t`: it is started from a configuration, run to a point or through
!> recorded cycles, restarted under other parameters, and read (its clock, state, contacts
!> and counters); its state travels as a `chain_state_t`. The engine's own procedures (flow,
!> gap searches, impact laws, the event loop, the schedule) stay behind it; the tests reach
!> them through their own modules. It implements nothing itself: each module it re-exports
!> names its section of docs/model.md.
module impactchain
    use chain_kinds, only: wp, i8, pi, two_pi
    use chain_error, only: error_t, set_error
    use chain_model, only: model_t
    use chain_config, only: config_t, read_config, validate_config, fmt_real, fmt_int, &
                            lyapunov_vectors, set_boundary, config_summary, check_size
    use chain_state, only: chain_state_t, event_counts_t
    use chain_engine, only: chain_t, chain_size, chain_cycle, chain_time, chain_start, &
                            chain_period, chain_positions, chain_velocities, chain_copy_state, &
                            chain_contacts, chain_counts
    use chain_event_log, only: event_log_t
    use chain_record, only: record_sink_t, memory_sink_t, record_result_t, record_cycles, &
                            record_spec_t
    use chain_clv, only: clv_rows_t, clv_result_t
    use chain_monitor, only: monitor_t, signal_monitor_t, stage_transient, stage_records, &
                             stage_points, stage_samples, stage_events, stage_name
    use chain_section, only: advance_to_point
    use chain_floquet, only: poincare_jacobian
    use chain_orbit, only: orbit_t, orbit_options_t, find_orbit, orbit_gap_minimum, impact_bonds
    use chain_branch, only: branch_options_t, branch_point_t, special_point_t, branches_t, &
                            follow_branches
    use chain_branch_file, only: continuation_guess, continuation_options, run_continuation, &
                                 continuation_to_file, write_continuation, &
                                 continuation_table_t, continuation_table, finite_or_inf
    use chain_sim, only: simulate_to_file, check_run, start_chain, initial_state, &
                         chain_on_section, restart_chain
    use chain_sweep, only: run_sweep, sweep_summary_t, plan_sweep, sweep_plan_t, &
                           sweep_result_t, sweep_result_init, &
                           sweep_point_config, run_sweep_branches, write_sweep_file, &
                           save_checkpoint, load_checkpoint, remove_file, checkpoint_every, &
                           validate_sweep_points, checkpoint_path, branch_record_sizes, &
                           pack_branch, unpack_branch, check_sweep, check_sweep_size
    use chain_attractor, only: attractor_t, kind_names
    use chain_census, only: census_result_t, census_result_init, census_points, &
                            census_point_config, sample_start, run_sample, run_census_samples, &
                            classify_census, save_census_checkpoint, load_census_checkpoint, &
                            census_starts, sample_record_sizes, pack_sample, unpack_sample, &
                            ensemble_statistics
    use chain_census_file, only: census_to_file, write_census_file, check_census, &
                                 check_census_size
    use chain_preflight, only: check_before_run
    use chain_provenance, only: provenance_item_t, provenance, provenance_text
    use chain_output, only: code_version, output_t, output_check, output_begin, output_end, &
                            output_abort
    use chain_cli, only: cli_t, parse_command_line, cli_run, cli_help, cli_version, cli_usage, &
                         exit_now, seconds_from_environment, &
                         cli_error
    use chain_interrupt, only: catch_interrupts, interrupted
    use chain_progress, only: progress_t, progress_start, progress_update, progress_within, &
                              stderr_is_terminal, progress_quiet_start
    implicit none
    private
    public :: wp, i8, pi, two_pi, error_t, set_error
    public :: config_t, read_config, validate_config, fmt_real, fmt_int, check_size
    public :: lyapunov_vectors, model_t, set_boundary, config_summary
    public :: chain_t, chain_state_t, event_counts_t, event_log_t
    public :: chain_size, chain_cycle, chain_time, chain_start, chain_period, chain_positions
    public :: chain_velocities, chain_copy_state, chain_contacts, chain_counts
    public :: record_sink_t, memory_sink_t, record_result_t, record_cycles
    public :: monitor_t, signal_monitor_t, stage_transient, stage_records, stage_points
    public :: stage_samples, stage_events
    public :: stage_name
    public :: record_spec_t, clv_rows_t, clv_result_t
    public :: advance_to_point, poincare_jacobian, simulate_to_file, start_chain, initial_state
    public :: check_run, check_before_run
    public :: chain_on_section, restart_chain
    public :: orbit_t, orbit_options_t, find_orbit, orbit_gap_minimum, impact_bonds
    public :: branch_options_t, branch_point_t, special_point_t, branches_t, follow_branches
    public :: continuation_guess, continuation_options, run_continuation
    public :: continuation_to_file, write_continuation, continuation_table_t
    public :: continuation_table, finite_or_inf
    public :: run_sweep, sweep_summary_t, plan_sweep, sweep_plan_t, sweep_result_t
    public :: sweep_result_init, sweep_point_config, run_sweep_branches
    public :: write_sweep_file, save_checkpoint, load_checkpoint, remove_file, checkpoint_every
    public :: validate_sweep_points, checkpoint_path, branch_record_sizes, pack_branch
    public :: unpack_branch, check_sweep, check_sweep_size
    public :: attractor_t, kind_names, census_result_t, census_result_init, census_points
    public :: census_point_config, sample_start, run_sample, run_census_samples
    public :: classify_census, save_census_checkpoint, load_census_checkpoint
    public :: census_to_file, write_census_file, check_census_size, census_starts
    public :: check_census
    public :: sample_record_sizes, pack_sample, unpack_sample, ensemble_statistics
    public :: code_version, output_t, output_check, output_begin, output_end, output_abort
    public :: provenance_item_t, provenance, provenance_text
    public :: cli_t, parse_command_line, cli_run, cli_help, cli_version, cli_usage, cli_error
    public :: exit_now, seconds_from_environment
    public :: catch_interrupts, interrupted
    public :: progress_t, progress_start, progress_update, progress_within, stderr_is_terminal
    public :: progress_quiet_start

end module impactchain
