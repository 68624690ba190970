!> A continuation run (docs/model.md section 12.5): the guess from the input (the state on the
!> section after `&run transient` cycles from `&initial`), the branches chain_branch follows
!> from it, and the HDF5 group /continuation that holds them.
module chain_branch_file
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_model, only: model_parameter
    use chain_engine, only: chain_t, chain_positions, chain_velocities
    use chain_event_log, only: event_log_t, event_log_init
    use chain_section, only: section_target, advance_to_point, advance_cycles
    use chain_config, only: config_t
    use chain_sim, only: start_chain, write_run_header
    use chain_branch, only: branch_options_t, branches_t, follow_branches, special_kinds
    use chain_output, only: output_t, output_begin, output_group, output_end, output_abort, &
                            output_unset_param
    use chain_hdf5, only: h5_write, h5_write_attr, h5_write_strings
    use chain_describe, only: describe_group, index_coordinate
    use chain_monitor, only: monitor_t
    use chain_curve, only: curve_t
    use chain_curve_file, only: run_curve, write_curve
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_positive_inf
    implicit none
    private
    public :: continuation_guess, continuation_options, run_continuation
    public :: continuation_to_file, write_continuation, continuation_table_t
    public :: continuation_table, finite_or_inf

    !> /continuation's datasets (continuation_table): arrays of the file's shapes in Fortran
    !> order, n oscillators, np points, ns special points, nb branches.
    type :: continuation_table_t
        integer :: longest = 1 !! the longest period: the size of strobe_x's iterate axis
        real(wp), allocatable :: values(:)                !! (np) the continued parameter
        real(wp), allocatable :: x(:, :), v(:, :)         !! (n, np) the orbit's state
        real(wp), allocatable :: strobe_x(:, :, :)        !! (n, longest, np), NaN-padded
        integer, allocatable :: period(:), branch(:)      !! (np)
        real(wp), allocatable :: multipliers_re(:, :), multipliers_im(:, :) !! (2n, np)
        integer, allocatable :: stable(:)                 !! (np) 1 stable, 0 not
        integer, allocatable :: symmetric(:)              !! (np) 1 its own mirror image, 0 not
        real(wp), allocatable :: min_gap(:), min_impact_speed(:) !! (np) +inf: none
        integer, allocatable :: impacts(:)                !! (np) impacts per period
        real(wp), allocatable :: residual(:)              !! (np) Newton's last residual
        integer, allocatable :: iterations(:)             !! (np)
        integer, allocatable :: special_index(:)          !! (ns) the point, 0-based
        character(len=len(special_kinds)), allocatable :: special_kind(:) !! (ns)
        real(wp), allocatable :: special_value(:)         !! (ns) the parameter there
        integer, allocatable :: parent(:)                 !! (nb) -1: none (branch 0)
        integer, allocatable :: origin_point(:)           !! (nb) 0-based, -1: none
        character(len=len(special_kinds)), allocatable :: origin_kind(:) !! (nb) '': none
    end type continuation_table_t

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
        opt%branch_points = cfg%cont_branch_points
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
        type(curve_t) :: curve

        call output_begin(out, cfg%output_file, cfg%overwrite, err)
        if (allocated(err)) return
        call run_continuation(cfg, res, err, monitor)
        if (.not. (allocated(err) .or. res%stopped)) call write_continuation(out, cfg, res, err)
        if (.not. (allocated(err) .or. res%stopped) .and. len(cfg%cont_follow) > 0) then
            call run_curve(cfg, res, curve)
            call write_curve(out, cfg, curve, err)
        end if
        if (allocated(err) .or. res%stopped) then
            call output_abort(out)
            return
        end if
        call output_end(out, .true., err)
    end subroutine continuation_to_file

    !> /continuation's datasets of the branches `res` of a chain of n oscillators, as the file
    !> holds them: per point (in the order found, branch after branch) the parameter, the
    !> orbit's state and section crossings (NaN beyond its period), period, branch, multipliers,
    !> stability (1 or 0), grazing monitors (+inf: none), impacts and Newton's last residual
    !> and iterations; per special point its point (0-based), kind and parameter; per branch
    !> its parent branch, the parent's point (0-based) where it began and that point's kind.
    pure subroutine continuation_table(n, res, table)
        integer, intent(in) :: n
        type(branches_t), intent(in) :: res
        type(continuation_table_t), intent(out) :: table
        integer :: np, ns, j, p

        np = res%n_points
        ns = res%n_specials
        table%longest = 1
        if (np > 0) table%longest = maxval([(res%points(j)%orbit%cycles, j=1, np)])
        allocate (table%x(n, np), table%v(n, np), table%strobe_x(n, table%longest, np))
        allocate (table%multipliers_re(2*n, np), table%multipliers_im(2*n, np))
        allocate (table%min_gap(np), table%min_impact_speed(np), table%residual(np))
        table%strobe_x = ieee_value(1.0_wp, ieee_quiet_nan)
        do j = 1, np
            associate (o => res%points(j)%orbit)
                table%x(:, j) = o%x
                table%v(:, j) = o%v
                p = o%cycles
                table%strobe_x(:, :p, j) = res%points(j)%strobe_x
                table%multipliers_re(:, j) = o%multipliers_re
                table%multipliers_im(:, j) = o%multipliers_im
                table%min_gap(j) = finite_or_inf(o%min_gap)
                table%min_impact_speed(j) = finite_or_inf(o%min_impact_speed)
                ! (the residuals' bounds are 0:iterations from Newton, 1:1 from a corrector)
                table%residual(j) = o%residuals(ubound(o%residuals, 1))
            end associate
        end do
        associate (pts => res%points(:np), specials => res%specials(:ns))
            table%values = pts%value
            table%period = [(pts(j)%orbit%cycles, j=1, np)]
            table%branch = pts%branch
            table%stable = merge(1, 0, pts%stable)
            table%symmetric = merge(1, 0, pts%symmetric)
            table%impacts = [(pts(j)%orbit%impacts, j=1, np)]
            table%iterations = [(pts(j)%orbit%iterations, j=1, np)]
            table%special_index = specials%point - 1
            allocate (table%special_kind(ns))
            do j = 1, ns
                table%special_kind(j) = specials(j)%kind
            end do
            table%special_value = specials%value
        end associate
        associate (origins => res%origins(:res%n_branches))
            table%parent = origins%parent
            table%origin_point = origins%point - 1
            allocate (table%origin_kind(res%n_branches))
            do j = 1, res%n_branches
                table%origin_kind(j) = origins(j)%kind
            end do
        end associate
    end subroutine continuation_table

    !> The run's header (without the continued parameter, which /params cannot hold as one
    !> number) and /continuation: the datasets of continuation_table, the group's attributes
    !> (the parameter, the section's phase, the parameter's start, stop and step, why and how
    !> the branches ended) and every dataset's names, units and dimensions.
    subroutine write_continuation(out, cfg, res, err)
        type(output_t), intent(inout) :: out
        type(config_t), intent(in) :: cfg
        type(branches_t), intent(in) :: res
        type(error_t), allocatable, intent(out) :: err
        type(continuation_table_t) :: table
        integer :: n, np, ns

        n = cfg%model%n
        np = res%n_points
        ns = res%n_specials
        call continuation_table(n, res, table)
        call write_run_header(out, cfg, err)
        if (.not. allocated(err)) call output_unset_param(out, cfg%cont_parameter, err)
        if (.not. allocated(err)) call output_group(out, 'continuation', err)
        if (allocated(err)) return
        associate (f => out%file, t => table)
            call h5_write_attr(f, 'continuation', 'parameter', cfg%cont_parameter, err)
            call h5_write_attr(f, 'continuation', 'phase', cfg%record%phase, err)
            call h5_write_attr(f, 'continuation', 'start', &
                               model_parameter(cfg%model, cfg%cont_parameter), err)
            call h5_write_attr(f, 'continuation', 'stop', cfg%cont_stop, err)
            call h5_write_attr(f, 'continuation', 'step', cfg%cont_step, err)
            call h5_write_attr(f, 'continuation', 'end_reason', res%end_reason, err)
            call h5_write_attr(f, 'continuation', 'end_kind', res%end_kind, err)
            if (allocated(err)) return
            call index_coordinate(f, 'continuation/point', 0, np, err)
            call index_coordinate(f, 'continuation/oscillator', 1, n, err)
            call index_coordinate(f, 'continuation/multiplier', 1, 2*n, err)
            call index_coordinate(f, 'continuation/iterate', 1, t%longest, err)
            call index_coordinate(f, 'continuation/special', 0, ns, err)
            call index_coordinate(f, 'continuation/branch_index', 0, size(t%parent), err)
            if (allocated(err)) return
            call h5_write(f, 'continuation/values', t%values, err)
            call h5_write(f, 'continuation/x', t%x, err)
            call h5_write(f, 'continuation/v', t%v, err)
            call h5_write(f, 'continuation/strobe_x', t%strobe_x, err)
            call h5_write(f, 'continuation/period', t%period, err)
            call h5_write(f, 'continuation/branch', t%branch, err)
            call h5_write(f, 'continuation/multipliers_re', t%multipliers_re, err)
            call h5_write(f, 'continuation/multipliers_im', t%multipliers_im, err)
            call h5_write(f, 'continuation/stable', t%stable, err)
            call h5_write(f, 'continuation/symmetric', t%symmetric, err)
            call h5_write(f, 'continuation/min_gap', t%min_gap, err)
            call h5_write(f, 'continuation/min_impact_speed', t%min_impact_speed, err)
            call h5_write(f, 'continuation/impacts_per_period', t%impacts, err)
            call h5_write(f, 'continuation/residual', t%residual, err)
            call h5_write(f, 'continuation/iterations', t%iterations, err)
            call h5_write(f, 'continuation/special_index', t%special_index, err)
            call h5_write_strings(f, 'continuation/special_kind', t%special_kind, err)
            call h5_write(f, 'continuation/special_value', t%special_value, err)
            call h5_write(f, 'continuation/parent', t%parent, err)
            call h5_write(f, 'continuation/origin_point', t%origin_point, err)
            call h5_write_strings(f, 'continuation/origin_kind', t%origin_kind, err)
        end associate
        if (allocated(err)) return
        call describe_group(out%file, 'continuation', err, parameter=cfg%cont_parameter)
    end subroutine write_continuation

    !> `value`, or +inf where it stands for none (huge): the file's grazing monitors.
    pure real(wp) function finite_or_inf(value)
        real(wp), intent(in) :: value

        finite_or_inf = value
        if (value == huge(1.0_wp)) finite_or_inf = ieee_value(1.0_wp, ieee_positive_inf)
    end function finite_or_inf

end module chain_branch_file
