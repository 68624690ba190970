!> The public API of impactchain: what a program or a library built on it calls. Reading and
!> validating a configuration; single runs to a file, or record by record into a sink of one's
!> own; the chain itself as an opaque `chain_t` (started from a configuration, run to a point
!> or through recorded cycles, restarted under other parameters, read: its clock, state,
!> contacts and counters; its state travels as a `chain_state_t`); the Poincare-map Jacobian
!> of a state; periodic orbits (Newton shooting) and their branches (continuation); sweeps
!> and attractor censuses to a file; monitors (progress and stopping); errors; provenance.
!> What the programs of this project need beyond it (the command line, checkpoints, the MPI
!> driver's packing, progress lines) comes from `impactchain_drivers`. It implements nothing
!> itself: each module it re-exports names its section of docs/model.md.
module impactchain
    use chain_kinds, only: wp, i8, pi, two_pi
    use chain_error, only: error_t
    use chain_model, only: model_t
    use chain_config, only: config_t, read_config, validate_config, config_summary, &
                            lyapunov_vectors
    use chain_state, only: chain_state_t, event_counts_t
    use chain_engine, only: chain_t, chain_size, chain_cycle, chain_time, chain_start, &
                            chain_period, chain_positions, chain_velocities, chain_copy_state, &
                            chain_contacts, chain_counts
    use chain_event_log, only: event_log_t
    use chain_record, only: record_spec_t, record_result_t, record_cycles, record_sink_t, &
                            memory_sink_t
    use chain_clv, only: clv_result_t, clv_rows_t
    use chain_monitor, only: monitor_t, signal_monitor_t, stage_transient, stage_records, &
                             stage_points, stage_samples, stage_events, stage_backward, &
                             stage_name
    use chain_section, only: advance_to_point
    use chain_floquet, only: poincare_jacobian
    use chain_orbit, only: orbit_t, orbit_options_t, find_orbit, orbit_gap_minimum, impact_bonds
    use chain_curve, only: curve_options_t, curve_t, follow_curve
    use chain_branch, only: branch_options_t, branch_point_t, special_point_t, branches_t, &
                            branch_origin_t, follow_branches
    use chain_branch_file, only: run_continuation, continuation_to_file
    use chain_sim, only: simulate_to_file, start_chain, initial_state, restart_chain, &
                         chain_on_section
    use chain_sweep_run, only: run_sweep, sweep_summary_t
    use chain_attractor, only: attractor_t, kind_names
    use chain_census, only: census_result_t
    use chain_census_file, only: census_to_file
    use chain_preflight, only: check_before_run
    use chain_provenance, only: provenance, provenance_item_t, provenance_text
    use chain_output, only: code_version
    implicit none
    private
    public :: wp, i8, pi, two_pi, error_t, config_t, read_config, validate_config
    public :: config_summary, check_before_run, model_t, record_spec_t, lyapunov_vectors
    public :: simulate_to_file, record_result_t, record_cycles, record_sink_t, memory_sink_t
    public :: clv_result_t, clv_rows_t, chain_t, chain_state_t, event_counts_t, event_log_t
    public :: start_chain, initial_state, restart_chain, chain_on_section, chain_size
    public :: chain_cycle, chain_time, chain_start, chain_period, chain_positions
    public :: chain_velocities, chain_copy_state, chain_contacts, chain_counts
    public :: advance_to_point, poincare_jacobian, monitor_t, signal_monitor_t
    public :: stage_transient, stage_records, stage_points, stage_samples, stage_events
    public :: stage_backward, stage_name, orbit_t, orbit_options_t, find_orbit
    public :: orbit_gap_minimum, impact_bonds, branch_options_t, branch_point_t
    public :: special_point_t, branch_origin_t, branches_t, follow_branches, run_continuation
    public :: curve_options_t, curve_t, follow_curve
    public :: continuation_to_file, run_sweep, sweep_summary_t, census_to_file
    public :: census_result_t, attractor_t, kind_names, code_version, provenance
    public :: provenance_item_t, provenance_text

end module impactchain
