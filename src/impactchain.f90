!> The public API of impactchain in one module.
!> It implements nothing itself: each module it re-exports names its section of docs/model.md.
module impactchain
    use chain_kinds, only: wp, i8, pi, two_pi
    use chain_error, only: error_t, set_error
    use chain_flow, only: flow_t, make_flow, forced_response, propagator, advance_state
    use chain_gaps, only: gap_t, gap_search_t, next_gap_zero, gap_value, search_none, &
                          search_root, search_horizon
    use chain_impact, only: pair_impact, wall_impact, saltation_matrix
    use chain_engine, only: chain_t, chain_init, chain_advance, chain_sync, chain_new_cycle, &
                            chain_set_tangent, chain_gaps_now
    use chain_events, only: event_log_t, event_log_init
    use chain_lyapunov, only: ky_dimension, floquet_multipliers
    use chain_period, only: detect_period
    use chain_config, only: run_config_t, read_config, validate_config
    use chain_run, only: record_sink_t, memory_sink_t, run_result_t, record_run, &
                         progress_callback, poincare_jacobian, advance_to_point, section_target
    use chain_sim, only: run_simulation, start_chain, initial_state
    use chain_sweep, only: run_sweep, sweep_summary_t, plan_sweep, sweep_plan_t
    use chain_output, only: code_version
    use chain_cli, only: cli_t, parse_command_line, cli_run, cli_help, cli_version, cli_usage, &
                         cli_error
    use chain_interrupt, only: catch_interrupts, interrupted
    implicit none
    private
    public :: wp, i8, pi, two_pi, error_t, set_error
    public :: flow_t, make_flow, forced_response, propagator, advance_state
    public :: gap_t, gap_search_t, next_gap_zero, gap_value, search_none, search_root
    public :: search_horizon, pair_impact, wall_impact, saltation_matrix
    public :: chain_t, chain_init, chain_advance, chain_sync, chain_new_cycle
    public :: chain_set_tangent, chain_gaps_now, event_log_t, event_log_init
    public :: ky_dimension, floquet_multipliers, detect_period
    public :: run_config_t, read_config, validate_config
    public :: record_sink_t, memory_sink_t, run_result_t, record_run, progress_callback
    public :: poincare_jacobian, advance_to_point, section_target
    public :: run_simulation, start_chain, initial_state
    public :: run_sweep, sweep_summary_t, plan_sweep, sweep_plan_t
    public :: code_version, cli_t, parse_command_line, cli_run, cli_help, cli_version
    public :: cli_usage, cli_error, catch_interrupts, interrupted

end module impactchain
