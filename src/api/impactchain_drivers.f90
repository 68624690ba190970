!> What the programs of this project need beyond the public API (`impactchain`): the shared
!> command line and exit, the interrupt flag and progress lines (app/), the MPI driver's
!> sweep and census rounds, checkpoints, packing and file writing (mpi/), the Python layer's
!> continuation tables and argument checks, its configurations as namelist text (f2py/), and
!> the input schema (`--schema`). Not an API for other projects: these
!> names follow the drivers. It implements nothing itself.
module impactchain_drivers
    use chain_error, only: set_error, fmt_int8
    use chain_config, only: fmt_real, fmt_int, check_size, set_boundary, read_config_text
    use chain_inputs, only: input_schema_json
    use chain_exact, only: exact, exact_list, fmt_logical, namelist_string
    use chain_branch_file, only: continuation_guess, continuation_table_t, continuation_table, &
                                 finite_or_inf
    use chain_curve_file, only: curve_table_t, curve_table, run_curve
    use chain_curve, only: curve_t
    use chain_sweep, only: plan_sweep, sweep_plan_t, sweep_result_t, sweep_result_init, &
                           write_sweep_file, check_sweep
    use chain_sweep_run, only: run_sweep_branches
    use chain_sweep_checkpoint, only: save_checkpoint, load_checkpoint, branch_record_sizes, &
                                      pack_branch, unpack_branch
    use chain_checkpoint, only: checkpoint_path
    use chain_census, only: census_result_init, run_census_samples, census_starts
    use chain_census_classify, only: classify_census
    use chain_census_checkpoint, only: save_census_checkpoint, load_census_checkpoint, &
                                       sample_record_sizes, pack_sample, unpack_sample
    use chain_census_file, only: write_census_file
    use chain_files, only: remove_file
    use chain_monitor, only: checkpoint_every
    use chain_output, only: output_t, output_begin, output_end, output_abort
    use chain_cli, only: cli_t, parse_command_line, cli_run, cli_help, cli_version, cli_usage, &
                         cli_schema, schema_json, exit_now, seconds_from_environment
    use chain_file_schema, only: output_schema_json
    use chain_interrupt, only: catch_interrupts, interrupted
    use chain_progress, only: progress_t, progress_start, progress_update, progress_within, &
                              stderr_is_terminal, progress_quiet_start
    implicit none
    private
    public :: set_error, fmt_real, fmt_int, check_size, set_boundary, continuation_guess
    public :: read_config_text, input_schema_json, exact, exact_list, fmt_logical, fmt_int8
    public :: namelist_string
    public :: cli_schema
    public :: continuation_table_t, continuation_table, finite_or_inf, plan_sweep
    public :: curve_t, curve_table_t, curve_table, run_curve
    public :: sweep_plan_t, sweep_result_t, sweep_result_init, run_sweep_branches
    public :: write_sweep_file, save_checkpoint, load_checkpoint, remove_file
    public :: checkpoint_every, checkpoint_path, branch_record_sizes, pack_branch
    public :: unpack_branch, check_sweep, census_result_init, run_census_samples
    public :: classify_census, save_census_checkpoint, load_census_checkpoint
    public :: write_census_file, census_starts, sample_record_sizes, pack_sample
    public :: unpack_sample, output_t, output_begin, output_end, output_abort, cli_t
    public :: parse_command_line, cli_run, cli_help, cli_version, cli_usage, exit_now
    public :: cli_schema, schema_json, output_schema_json
    public :: seconds_from_environment, catch_interrupts, interrupted, progress_t
    public :: progress_start, progress_update, progress_within, stderr_is_terminal
    public :: progress_quiet_start

end module impactchain_drivers
