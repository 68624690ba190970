!> A run's output file (docs/output.md), one module for its users: its start, header, records
!> and end (chain_run_file), its spectra (chain_run_file_spectra), a run stopped early, its
!> continuation and a start from a file (chain_run_file_resume). It implements nothing.
!> Infrastructure, no model section: it writes the records of docs/model.md sections 6-7.
module chain_output
    use chain_run_file, only: output_t, output_check, output_begin, output_header, &
                              output_strobe_write, output_events_append, output_final, &
                              output_stats, output_periods, output_end, output_abort, &
                              output_group, output_unset_param, schema_version, code_version, &
                              output_truncate_strobe
    use chain_run_file_spectra, only: output_lyapunov, output_windows_write, &
                                      output_truncate_windows, output_clv_rows, output_clv, &
                                      output_jacobian
    use chain_run_file_resume, only: resume_data_t, output_resume, read_resume, output_inspect, &
                                     output_continue, output_checkpoint, read_final_state, &
                                     file_absent, file_continuable, file_other_input, file_other
    implicit none
    private
    public :: output_t, output_check, output_begin, output_header, output_strobe_write
    public :: output_events_append
    public :: output_final, output_stats, output_periods, output_lyapunov, output_jacobian
    public :: output_clv_rows, output_clv, output_windows_write, output_truncate_windows
    public :: output_end, output_abort, read_final_state, output_group
    public :: schema_version, code_version, output_truncate_strobe
    public :: resume_data_t, output_resume, read_resume, output_inspect, output_continue
    public :: output_checkpoint
    public :: file_absent, file_continuable, file_other_input, file_other
    public :: output_unset_param
end module chain_output
