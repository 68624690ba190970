!> impactchain command line: `impactchain [options] input.nml` (see usage below). Parses
!> arguments (chain_cli),
!> runs the library, reports progress and errors, and sets the exit code. No physics here.
!> SIGINT / SIGTERM ask a running simulation to stop (chain_interrupt): at once, at its last
!> strobe record; the file is then closed cleanly and marked complete = 0, and the same command
!> continues it. Runs also save such a file every IMPACTCHAIN_CHECKPOINT_SECONDS (default 10 s)
!> and go on, so that a kill loses at most that.
program main
    use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
    use, intrinsic :: iso_c_binding, only: c_int
    use impactchain, only: error_t, config_t, read_config, simulate_to_file, record_result_t, &
                           run_sweep, sweep_summary_t, code_version, provenance_text, &
                           config_summary, check_before_run, branches_t, orbit_t, &
                           continuation_to_file, &
                           census_result_t, census_to_file, kind_names, wp
    use impactchain_drivers, only: checkpoint_path, catch_interrupts, cli_t, parse_command_line, &
                                   cli_run, cli_help, cli_version, cli_usage, exit_now, &
                                   cli_schema, schema_json, &
                                   seconds_from_environment, checkpoint_every
    use stderr_monitor, only: stderr_monitor_t, close_progress, progress_after_from_environment
    implicit none
    type(config_t) :: cfg
    type(record_result_t) :: summary
    type(sweep_summary_t) :: sweep_summary
    type(branches_t) :: branches
    type(census_result_t) :: census
    type(error_t), allocatable :: err
    type(cli_t) :: cli
    type(stderr_monitor_t) :: monitor
    character(len=:), allocatable :: message
    real(wp) :: checkpoint_seconds

    cli = parse_command_line()
    select case (cli%action)
    case (cli_help)
        call usage(output_unit)
        stop
    case (cli_version)
        ! the version, then where this executable runs: compiler, BLAS and its kernels, CPU
        write (output_unit, '(a)') 'impactchain '//code_version
        write (output_unit, '(a)', advance='no') provenance_text()
        stop
    case (cli_schema)
        write (output_unit, '(a)') schema_json()
        stop
    case (cli_usage)
        call usage(error_unit)
        stop 2, quiet=.true.
    case (cli_run)
    case default
        call fail_usage(cli%message)
    end select
    monitor%quiet = cli%quiet
    call progress_after_from_environment(monitor%after, message)
    if (allocated(message)) call fail(message)
    call seconds_from_environment('IMPACTCHAIN_CHECKPOINT_SECONDS', real(checkpoint_every, wp), &
                                  checkpoint_seconds, message)
    if (allocated(message)) call fail(message)
    call read_config(cli%input, cfg, err, cli%overrides)
    if (allocated(err)) call fail(err%message)
    if (cli%check) then
        ! the checks the run would make before it starts, so that --check passes what runs
        call check_before_run(cfg, err)
        if (allocated(err)) call fail(err%message)
        write (output_unit, '(a)', advance='no') config_summary(cfg)
        stop
    end if
    call catch_interrupts()
    if (cfg%continuation) then
        call continuation_to_file(cfg, branches, err, monitor)
        call close_progress(monitor)
        if (allocated(err)) call fail(err%message)
        if (branches%stopped) then
            write (error_unit, '(a)') 'impactchain: the continuation was stopped; nothing '// &
                'was written'
            stop 3, quiet=.true.
        end if
        call report_branches(branches, cfg%output_file, cfg%cont_max_points == 1)
    else if (cfg%census) then
        call census_to_file(cfg, census, err, monitor)
        call close_progress(monitor)
        if (allocated(err)) call fail(err%message)
        call report_census(census, cfg%output_file, checkpoint_path(cfg))
        if (.not. all(census%done)) stop 3, quiet=.true.
    else if (cfg%sweep) then
        call run_sweep(cfg, sweep_summary, err, monitor)
        call close_progress(monitor)
        if (allocated(err)) call fail(err%message)
        call report_sweep(sweep_summary, cfg%output_file, checkpoint_path(cfg))
        if (.not. sweep_summary%complete) stop 3, quiet=.true.
    else
        call simulate_to_file(cfg, summary, err, monitor, checkpoint_seconds)
        call close_progress(monitor)
        if (allocated(err)) call fail(err%message)
        call report(summary, cfg%output_file, cfg%record%covariant)
        if (.not. summary%complete) stop 3, quiet=.true.
    end if

contains

    subroutine usage(unit)
        integer, intent(in) :: unit

        write (unit, '(a)') 'usage: impactchain [options] input.nml', &
            '  Runs the impact-oscillator chain described by the namelist file and writes', &
            '  HDF5 output (see README.md for every key).', &
            '', &
            'options:', &
            '  --set group.key=value  override one key of the input (repeatable), e.g.', &
            '                         --set chain.amplitude=2.2 --set run.cycles=1000', &
            '  -o, --output file.h5   write to this file (the same as --set output.file=...)', &
            '  --overwrite            replace an existing output file', &
            '  --check                validate the input (and what the run checks before', &
            '                         it starts: sizes, the output file), print it', &
            '                         resolved, run nothing', &
            '  -q, --quiet            no progress (shown on stderr for runs over 2 s;', &
            '                         IMPACTCHAIN_PROGRESS_AFTER=seconds changes the 2 s)', &
            '  -h, --help             this text', &
            '  --version              the code version', &
            '  --schema               every input key and every dataset of the output', &
            '                         files, as JSON', &
            '', &
            'A run is saved as it goes: every 10 s (IMPACTCHAIN_CHECKPOINT_SECONDS=seconds', &
            'changes that) its file holds the records so far, marked complete = 0; after', &
            'a kill, or SIGINT / SIGTERM, the same command continues it. A sweep or census', &
            'keeps a checkpoint beside its file, and resumes from it.'
    end subroutine usage

    subroutine report(summary, output_file, covariant)
        type(record_result_t), intent(in) :: summary
        character(len=*), intent(in) :: output_file
        logical, intent(in) :: covariant

        write (output_unit, '(a)') 'impactchain: wrote '//output_file
        if (summary%cycles_continued > 0) write (output_unit, '(a,i0,a)') &
            '  continued a run stopped early after ', summary%cycles_continued, ' records'
        write (output_unit, '(a,i0,a,f0.4,a,i0,a,i0,a)') '  cycles recorded ', &
            summary%cycles_done, ', collisions per cycle ', summary%collisions_per_cycle, &
            ', sticking contacts ', summary%sticks, ', releases ', summary%releases, ''
        if (summary%has_lyapunov) write (output_unit, '(a,es12.4,a,f0.3)') &
            '  largest Lyapunov exponent ', summary%lyapunov%bits_per_cycle(1), &
            ' bits/cycle, Kaplan-Yorke dimension ', summary%lyapunov%ky_dimension
        if (summary%has_clv) write (output_unit, '(a,i0,a,i0,a)') &
            '  covariant Lyapunov vectors at ', summary%clv%kept, ' records (the last ', &
            summary%clv%transient, ' without)'
        if (.not. summary%complete .and. covariant) write (error_unit, '(a)') &
            'impactchain: the run was stopped early; the file holds the finished records '// &
            'and is marked complete = 0, without covariant vectors, which need a complete '// &
            'run: run the command again with --overwrite'
        if (.not. summary%complete .and. .not. covariant) write (error_unit, '(a)') &
            'impactchain: the run was stopped early; the file holds the finished records '// &
            'and is marked complete = 0; run the same command again to continue it'
    end subroutine report

    subroutine report_sweep(summary, output_file, checkpoint)
        type(sweep_summary_t), intent(in) :: summary
        character(len=*), intent(in) :: output_file, checkpoint

        if (summary%complete) then
            write (output_unit, '(a)') 'impactchain: wrote '//output_file
            write (output_unit, '(a,i0,a,i0,a,f0.4)') '  sweep points ', summary%n_points, &
                ' (resumed from a checkpoint: ', summary%points_resumed, &
                '), mean collisions per cycle ', summary%mean_collisions
        else
            write (error_unit, '(a,i0,a,i0,a)') 'impactchain: the sweep was stopped after ', &
                summary%points_done, ' of ', summary%n_points, ' points; run the same '// &
                'command again to resume from '//checkpoint
        end if
    end subroutine report_sweep

    !> The attractors found, each with its kind, periods and basin fraction at its point
    !> (and how many samples reached its mirror image).
    subroutine report_census(res, output_file, checkpoint)
        type(census_result_t), intent(in) :: res
        character(len=*), intent(in) :: output_file, checkpoint
        integer :: a, p

        if (.not. all(res%done)) then
            write (error_unit, '(a,i0,a,i0,a)') 'impactchain: the census was stopped after ', &
                count(res%done), ' of ', size(res%done), ' samples; run the same command '// &
                'again to resume from '//checkpoint
            return
        end if
        write (output_unit, '(a)') 'impactchain: wrote '//output_file
        write (output_unit, '(a,i0,a,i0,a,i0,a,i0,a)') '  samples ', res%n_samples, &
            ' at ', res%n_points, ' point(s) (resumed from a checkpoint: ', res%resumed, &
            '), attractors ', res%n_attractors, ''
        do a = 1, res%n_attractors
            associate (t => res%attractors(a))
                p = t%point
                write (output_unit, '(a,i0,a,i0,3a,i0,a,f0.4,a,f0.4,a,es11.3,a,i0,a)') &
                    '  attractor ', a - 1, ' (point ', p - 1, '): ', trim(kind_names(t%kind)), &
                    ', period ', t%period, ', fraction ', res%fraction(a, p), ' +- ', &
                    res%fraction_stderr(a, p), ', lambda1 ', t%lambda1, &
                    ' bits/cycle, mirror images ', count(res%attractor(:, p) == a .and. &
                                                         res%mirrored(:, p)), ''
            end associate
        end do
    end subroutine report_census

    !> Points and special points found, and why each branch ended (a Newton failure is a
    !> result: the file then says so too). `newton_only` (max_points = 1): what Newton found
    !> too, the orbit being the result.
    subroutine report_branches(res, output_file, newton_only)
        type(branches_t), intent(in) :: res
        character(len=*), intent(in) :: output_file
        logical, intent(in) :: newton_only
        integer :: j

        write (output_unit, '(a)') 'impactchain: wrote '//output_file
        write (output_unit, '(a,i0,a,i0)') '  orbits ', res%n_points, ', special points ', &
            res%n_specials
        do j = 1, res%n_specials
            write (output_unit, '(a,es22.14,a,i0,a)') '  '//res%specials(j)%kind//' at ', &
                res%specials(j)%value, ' (point ', res%specials(j)%point - 1, ')'
        end do
        if (newton_only) call report_newton(res%start)
        write (output_unit, '(a)') '  '//res%end_reason
        write (output_unit, '(a)') '  ends: '//comma_lines(res%end_kind)
    end subroutine report_branches

    !> The lines of `text` joined by ', '.
    pure function comma_lines(text) result(joined)
        character(len=*), intent(in) :: text
        character(len=:), allocatable :: joined
        integer :: j

        joined = ''
        do j = 1, len(text)
            if (text(j:j) == new_line('a')) then
                joined = joined//', '
            else
                joined = joined//text(j:j)
            end if
        end do
    end function comma_lines

    !> Newton's outcome: converged or not, its steps and last residual; for a converged orbit
    !> its stability (stable: every Floquet multiplier inside the unit circle), the largest
    !> multiplier modulus and the impacts per period.
    subroutine report_newton(orbit)
        type(orbit_t), intent(in) :: orbit
        real(wp), allocatable :: modulus(:)
        real(wp) :: residual

        residual = huge(1.0_wp)
        if (allocated(orbit%residuals)) residual = orbit%residuals(ubound(orbit%residuals, 1))
        write (output_unit, '(a,i0,a,es8.2)') '  converged: '// &
            trim(merge('yes', 'no ', orbit%converged))//', Newton steps ', orbit%iterations, &
            ', residual |P(z) - z| / (1 + |z|) = ', residual
        if (.not. orbit%converged) then
            write (output_unit, '(a)') '  stability: unknown (no orbit converged)'
            return
        end if
        modulus = hypot(orbit%multipliers_re, orbit%multipliers_im)
        write (output_unit, '(a,i0,a,i0,a,g0.6)') '  stability: '// &
            trim(merge('unstable', 'stable  ', maxval(modulus) >= 1))//', ', &
            count(modulus > 1), ' of ', size(modulus), ' Floquet multipliers outside the '// &
            'unit circle, largest modulus ', maxval(modulus)
        write (output_unit, '(a,i0,a,i0,a)') '  impacts per period: ', orbit%impacts, &
            ' (period ', orbit%cycles, ')'
    end subroutine report_newton

    subroutine fail(message)
        character(len=*), intent(in) :: message

        write (error_unit, '(a)') 'impactchain: error: '//message
        call exit_now(1)
    end subroutine fail

    !> A mistake in the command line itself (an unknown option, a missing value): exit 2.
    subroutine fail_usage(message)
        character(len=*), intent(in) :: message

        write (error_unit, '(a)') 'impactchain: error: '//message
        stop 2, quiet=.true.
    end subroutine fail_usage

end program main
