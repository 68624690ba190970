!> A continuation run (docs/model.md section 12.5): the guess from the input (the state on the
!> section after `&run transient` cycles from `&initial`), the branches chain_branch follows
!> from it, and the HDF5 group /continuation that holds them.
module chain_branch_file
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_model, only: model_parameter, parameter_units
    use chain_engine, only: chain_t, chain_positions, chain_velocities
    use chain_event_log, only: event_log_t, event_log_init
    use chain_section, only: section_target, advance_to_point, advance_cycles
    use chain_config, only: config_t
    use chain_sim, only: start_chain, write_run_header
    use chain_branch, only: branch_options_t, branches_t, follow_branches
    use chain_output, only: output_t, output_begin, output_group, output_end, output_abort, &
                            output_describe, output_index, output_unset_param
    use chain_hdf5, only: h5_write, h5_write_attr, h5_write_strings
    use chain_monitor, only: monitor_t
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_positive_inf
    implicit none
    private
    public :: continuation_guess, continuation_options, run_continuation
    public :: continuation_to_file, write_continuation, finite_or_inf

contains

    !> The guess for the first orbit: the state on the section (&run phase) after &run
    !> transient cycles from &initial. `monitor` is told the transient's cycles and may stop
    !> it there (`stopped`; x and v are then not set).
    subroutine continuation_guess(cfg, x, v, err, monitor, stopped)
        type(config_t), intent(in) :: cfg
        real(wp), allocatable, intent(out) :: x(:), v(:)
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        logical, intent(out), optional :: stopped
        type(chain_t) :: chain
        type(event_log_t) :: log
        integer(i8) :: cycle
        real(wp) :: s
        logical :: halted

        if (present(stopped)) stopped = .false.
        call start_chain(cfg, chain, err)
        if (allocated(err)) return
        call event_log_init(log, .false., 0)
        call section_target(chain, cfg%record%transient, cfg%record%phase, 0_i8, cycle, s)
        call advance_cycles(chain, cycle, log, err, monitor=monitor, stopped=halted)
        if (present(stopped)) stopped = halted
        if (allocated(err) .or. halted) return
        call advance_to_point(chain, cycle, s, log, err)
        if (allocated(err)) return
        x = chain_positions(chain)
        v = chain_velocities(chain)
    end subroutine continuation_guess

    !> The options of &continuation.
    pure function continuation_options(cfg) result(opt)
        type(config_t), intent(in) :: cfg
        type(branch_options_t) :: opt

        opt%parameter = cfg%cont_parameter
        opt%stop = cfg%cont_stop
        opt%step = cfg%cont_step
        opt%max_points = cfg%cont_max_points
        opt%doublings = cfg%cont_doublings
    end function continuation_options

    !> The branches the input asks for, from its guess. `monitor` is told the transient's
    !> cycles, then the points found, and may stop the work (res%stopped).
    subroutine run_continuation(cfg, res, err, monitor)
        type(config_t), intent(in) :: cfg
        type(branches_t), intent(out) :: res
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        real(wp), allocatable :: x(:), v(:)

        call continuation_guess(cfg, x, v, err, monitor, res%stopped)
        if (allocated(err) .or. res%stopped) return
        call follow_branches(cfg%model, cfg%record%phase, cfg%cont_period, x, v, &
                             continuation_options(cfg), res, err, monitor)
    end subroutine run_continuation

    !> The whole continuation run, written to cfg%output_file (nothing when it is stopped or
    !> fails: the file appears whole or not at all).
    subroutine continuation_to_file(cfg, res, err, monitor)
        type(config_t), intent(in) :: cfg
        type(branches_t), intent(out) :: res
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: monitor
        type(output_t) :: out

        call output_begin(out, cfg%output_file, cfg%overwrite, err)
        if (allocated(err)) return
        call run_continuation(cfg, res, err, monitor)
        if (.not. (allocated(err) .or. res%stopped)) call write_continuation(out, cfg, res, err)
        if (allocated(err) .or. res%stopped) then
            call output_abort(out)
            return
        end if
        call output_end(out, .true., err)
    end subroutine continuation_to_file

    !> The run's header (without the continued parameter, which /params cannot hold as one
    !> number) and /continuation: per point (in the order found, branch after branch) the
    !> parameter, the orbit's state and section crossings, period, branch, multipliers,
    !> stability, grazing monitors, impacts and Newton's last residual; the special points.
    subroutine write_continuation(out, cfg, res, err)
        type(output_t), intent(inout) :: out
        type(config_t), intent(in) :: cfg
        type(branches_t), intent(in) :: res
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: x(:, :), v(:, :), strobe(:, :, :), re(:, :), im(:, :)
        real(wp), allocatable :: min_gap(:), min_speed(:), residual(:)
        character(len=15), allocatable :: kinds(:)
        integer :: n, np, ns, longest, j, p

        n = cfg%model%n
        np = res%n_points
        ns = res%n_specials
        longest = 1
        if (np > 0) longest = maxval([(res%points(j)%orbit%cycles, j=1, np)])
        allocate (x(n, np), v(n, np), strobe(n, longest, np), re(2*n, np), im(2*n, np))
        allocate (min_gap(np), min_speed(np), residual(np))
        strobe = ieee_value(1.0_wp, ieee_quiet_nan)
        allocate (kinds(ns))
        do j = 1, ns
            kinds(j) = res%specials(j)%kind
        end do
        do j = 1, np
            associate (o => res%points(j)%orbit)
                x(:, j) = o%x
                v(:, j) = o%v
                p = o%cycles
                strobe(:, :p, j) = res%points(j)%strobe_x
                re(:, j) = o%multipliers_re
                im(:, j) = o%multipliers_im
                min_gap(j) = finite_or_inf(o%min_gap)
                min_speed(j) = finite_or_inf(o%min_impact_speed)
                residual(j) = o%residuals(ubound(o%residuals, 1))
            end associate
        end do
        call write_run_header(out, cfg, err)
        if (.not. allocated(err)) call output_unset_param(out, cfg%cont_parameter, err)
        if (.not. allocated(err)) call output_group(out, 'continuation', err)
        if (allocated(err)) return
        associate (f => out%file, pts => res%points(:np))
            call h5_write_attr(f, 'continuation', 'parameter', cfg%cont_parameter, err)
            call h5_write_attr(f, 'continuation', 'phase', cfg%record%phase, err)
            call h5_write_attr(f, 'continuation', 'start', &
                               model_parameter(cfg%model, cfg%cont_parameter), err)
            call h5_write_attr(f, 'continuation', 'stop', cfg%cont_stop, err)
            call h5_write_attr(f, 'continuation', 'step', cfg%cont_step, err)
            call h5_write_attr(f, 'continuation', 'end_reason', res%end_reason, err)
            if (allocated(err)) return
            call output_index(out, 'continuation/point', 0, np, 'point index (in the '// &
                              'order found, branch after branch)', err)
            if (.not. allocated(err)) call output_index(out, 'continuation/oscillator', 1, n, &
                                                        'oscillator index', err)
            if (.not. allocated(err)) call output_index(out, 'continuation/multiplier', 1, &
                                                        2*n, 'multiplier index', err)
            if (.not. allocated(err)) call output_index(out, 'continuation/iterate', 1, &
                                                        longest, 'section crossing of '// &
                                                        'the period', err)
            if (.not. allocated(err)) call output_index(out, 'continuation/special', 0, ns, &
                                                        'special point index', err)
            if (allocated(err)) return
            call h5_write(f, 'continuation/values', [(pts(j)%value, j=1, np)], '1', err)
            call h5_write(f, 'continuation/x', x, '1', err)
            call h5_write(f, 'continuation/v', v, '1', err)
            call h5_write(f, 'continuation/strobe_x', strobe, '1', err)
            call h5_write(f, 'continuation/period', [(pts(j)%orbit%cycles, j=1, np)], '1', err)
            call h5_write(f, 'continuation/branch', [(pts(j)%branch, j=1, np)], '1', err)
            call h5_write(f, 'continuation/multipliers_re', re, '1', err)
            call h5_write(f, 'continuation/multipliers_im', im, '1', err)
            call h5_write(f, 'continuation/stable', [(merge(1, 0, pts(j)%stable), j=1, np)], &
                          '1', err)
            call h5_write(f, 'continuation/min_gap', min_gap, '1', err)
            call h5_write(f, 'continuation/min_impact_speed', min_speed, '1', err)
            call h5_write(f, 'continuation/impacts_per_period', &
                          [(pts(j)%orbit%impacts, j=1, np)], '1', err)
            call h5_write(f, 'continuation/residual', residual, '1', err)
            call h5_write(f, 'continuation/iterations', [(pts(j)%orbit%iterations, j=1, np)], &
                          '1', err)
            call h5_write(f, 'continuation/special_index', &
                          [(res%specials(j)%point - 1, j=1, ns)], '1', err)
            call h5_write_strings(f, 'continuation/special_kind', kinds, '1', err)
            call h5_write(f, 'continuation/special_value', [(res%specials(j)%value, j=1, ns)], &
                          '1', err)
        end associate
        if (allocated(err)) return
        call describe_all(out, cfg%cont_parameter, err)
    end subroutine write_continuation

    !> The long names, units and dimensions of /continuation's datasets.
    subroutine describe_all(out, parameter, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: parameter
        type(error_t), allocatable, intent(inout) :: err
        character(len=:), allocatable :: unit

        unit = parameter_units(parameter)
        call describe('values', parameter//' (the continued parameter) at the point', unit, &
                      'point')
        call describe('x', "displacement from equilibrium on the section, the orbit's "// &
                      "state", 'length', 'point oscillator')
        call describe('v', "velocity on the section, the orbit's state", 'length/time', &
                      'point oscillator')
        call describe('strobe_x', 'displacement at the section crossings of one period '// &
                      '(NaN beyond the period)', 'length', 'point iterate oscillator')
        call describe('period', 'period of the orbit', 'drive cycles', 'point')
        call describe('branch', 'branch index (0: the first; 1, 2, ...: branches switched '// &
                      'to at period doublings)', '', 'point')
        call describe('multipliers_re', 'Floquet multiplier, real part', '', &
                      'point multiplier')
        call describe('multipliers_im', 'Floquet multiplier, imaginary part', '', &
                      'point multiplier')
        call describe('stable', 'stability (1: every multiplier inside the unit circle)', '', &
                      'point')
        call describe('min_gap', 'smallest gap at a local minimum over one period, other '// &
                      "than a bond's own impacts (inf: none)", 'length', 'point')
        call describe('min_impact_speed', 'smallest impact speed over one period (inf: no '// &
                      'impacts)', 'length/time', 'point')
        call describe('impacts_per_period', 'impacts over one period', '', 'point')
        call describe('residual', "Newton's last residual |P(z) - z| / (1 + |z|)", '', &
                      'point')
        call describe('iterations', 'Newton iterations of the point', '', 'point')
        call describe('special_index', 'the point (0-based index) of the special point', '', &
                      'special')
        call describe('special_kind', 'fold, period-doubling, neimark-sacker or grazing', &
                      '', 'special')
        call describe('special_value', parameter//' at the special point', unit, 'special')
    contains
        subroutine describe(name, long_name, model_units, dims)
            character(len=*), intent(in) :: name, long_name, model_units, dims

            if (.not. allocated(err)) call output_describe(out, 'continuation/'//name, &
                                                           long_name, model_units, dims, err)
        end subroutine describe
    end subroutine describe_all

    !> `value`, or +inf where it stands for none (huge).
    pure real(wp) function finite_or_inf(value)
        real(wp), intent(in) :: value

        finite_or_inf = value
        if (value == huge(1.0_wp)) finite_or_inf = ieee_value(1.0_wp, ieee_positive_inf)
    end function finite_or_inf

end module chain_branch_file
