!> The file schema as one table: every dataset, coordinate, dimension and attribute that the
!> four kinds of file hold (a run's; a sweep's, a continuation's and a census's, which begin
!> with a run's header), with its dimensions, type, units, reduced unit and long name, and
!> when a file holds it (docs/output.md). The writers take every name, unit and long name
!> from here, through chain_file_schema; so do `impactchain --schema` and the Python package.
!>
!> An entry's fields, all text:
!> - `file`: 'run', 'sweep', 'continuation' or 'census'; the header (when = 'header': the
!>   root's attributes, /params, /initial) is listed once, as the run's.
!> - `path`: '/group/name', or '/group/@name' for an attribute of the group ('/@name': root).
!> - `kind`: 'dataset', 'attribute' or 'dimension' (a netCDF dimension without values).
!> - `dims`: netCDF dimension names, blank-separated, h5py's order ('': a scalar; a coordinate
!>   variable names its own). `name?` is present only in a 2-D sweep; `a|b` is either one
!>   (the axis a sweep's omega runs along).
!> - `dtype`: 'float64', 'int32', 'int64', 'string' ('' for a dimension).
!> - `units`: the UDUNITS unit ('1' for the model's reduced units; '' for text).
!> - `model_units`: the reduced unit (docs/model.md section 1.5), '' if none; '{parameter}'
!>   is the unit of the swept or continued parameter, whose name '{parameter}' stands for in
!>   a long name.
!> - `when`: 'always', 'header', or in words the input that makes a file hold it.
!> Infrastructure, no model section.
module chain_file_table
    use chain_inputs, only: input_keys, find_input
    use chain_file_entry, only: output_entry_t, entry_list_t, add, entries_of
    use chain_file_table_orbits, only: entries_continuation, entries_curve
    implicit none
    private
    public :: output_entry_t, output_table

contains

    !> Every entry, group by group in the order a run's file is written.
    function output_table() result(t)
        type(output_entry_t), allocatable :: t(:)
        type(entry_list_t) :: list

        call entries_root_params(list)
        call entries_initial_strobe_events_final(list)
        call entries_stats_lyapunov_finite_time(list)
        call entries_clv_floquet(list)
        call entries_resume(list)
        call entries_sweep(list)
        call entries_continuation(list)
        call entries_curve(list)
        call entries_census_attributes(list)
        call entries_census(list)
        t = entries_of(list)
    end function output_table

    !> The reduced unit of an input key as a file states it (model_units): the input table's,
    !> its one home; none for a pure number.
    pure function key_units(group, name) result(units)
        character(len=*), intent(in) :: group, name
        character(len=:), allocatable :: units

        units = trim(input_keys(find_input(group, name))%units)
        if (units == '1') units = ''
    end function key_units

    !> /, /params attributes, /params.
    subroutine entries_root_params(t)
        type(entry_list_t), intent(inout) :: t

        call add(t, 'run', '/@schema_version', 'attribute', '', 'int32', '1', '', &
                 'version of the file''s layout', 'header')
        call add(t, 'run', '/@code_version', 'attribute', '', 'string', '', '', &
                 'version of impactchain that wrote the file', 'header')
        call add(t, 'run', '/@compiler', 'attribute', '', 'string', '', '', &
                 'compiler that built the library', 'header')
        call add(t, 'run', '/@compiler_options', 'attribute', '', 'string', '', '', &
                 'the library''s compiler flags', 'header')
        call add(t, 'run', '/@blas', 'attribute', '', 'string', '', '', &
                 'the BLAS''s name, version and build', 'header')
        call add(t, 'run', '/@blas_kernel', 'attribute', '', 'string', '', '', &
                 'the BLAS kernels selected on this CPU at run time', 'header')
        call add(t, 'run', '/@cpu_model', 'attribute', '', 'string', '', '', &
                 'the CPU (/proc/cpuinfo)', 'header')
        call add(t, 'run', '/@input_namelist', 'attribute', '', 'string', '', '', &
                 'the input text', 'header')
        call add(t, 'run', '/@resolved_namelist', 'attribute', '', 'string', '', '', &
                 'every key of the input as used', 'header')
        call add(t, 'run', '/@complete', 'attribute', '', 'int32', '1', '', &
                 '1: the run finished, 0: it stopped early', 'header')
        call add(t, 'run', '/params/@n', 'attribute', '', 'int32', '1', '', &
                 'number of oscillators', 'header')
        call add(t, 'run', '/params/@damping', 'attribute', '', 'float64', '1', &
                 key_units('chain', 'damping'), &
                 'damping ratio b', 'header')
        call add(t, 'run', '/params/@restitution', 'attribute', '', 'float64', '1', &
                 key_units('chain', 'restitution'), &
                 'coefficient of restitution', 'header')
        call add(t, 'run', '/params/@amplitude', 'attribute', '', 'float64', '1', &
                 key_units('chain', 'amplitude'), &
                 'drive amplitude A', 'header')
        call add(t, 'run', '/params/@omega', 'attribute', '', 'float64', '1', &
                 key_units('chain', 'omega'), &
                 'drive frequency w', 'header')
        call add(t, 'run', '/params/@boundary', 'attribute', '', 'string', '', '', &
                 '''fixed'' (walls at both ends) or ''free''', 'header')
        call add(t, 'run', '/params/@drive_period', 'attribute', '', 'float64', '1', 'time', &
                 'drive period 2 pi / omega', 'header')
        call add(t, 'run', '/params/@phase', 'attribute', '', 'float64', 'radian', '', &
                 'phase of the Poincare section, w t mod 2 pi', 'header')
        call add(t, 'run', '/params/@transient', 'attribute', '', 'int64', '1', &
                 key_units('run', 'transient'), &
                 'drive cycles before the records', 'header')
        call add(t, 'run', '/params/@cycles', 'attribute', '', 'int64', '1', &
                 key_units('run', 'cycles'), &
                 'drive cycles recorded (planned)', 'header')
        call add(t, 'run', '/params/bond', 'dataset', 'bond', 'int32', '1', '', &
                 'bond index: bond k joins oscillators k and k+1 (0: the left wall, n: the '// &
                 'right wall)', 'header')
        call add(t, 'run', '/params/spacing', 'dataset', 'bond', 'float64', '1', &
                 key_units('chain', 'spacing'), &
                 'spacing of the bond (the gap at rest)', 'header')
    end subroutine entries_root_params

    !> /initial, /strobe, /events, /final.
    subroutine entries_initial_strobe_events_final(t)
        type(entry_list_t), intent(inout) :: t

        call add(t, 'run', '/initial/oscillator', 'dataset', 'oscillator', 'int32', '1', '', &
                 'oscillator index', 'header')
        call add(t, 'run', '/initial/x', 'dataset', 'oscillator', 'float64', '1', 'length', &
                 'displacement from equilibrium at t = 0', 'header')
        call add(t, 'run', '/initial/v', 'dataset', 'oscillator', 'float64', '1', 'length/time', &
                 'velocity at t = 0', 'header')
        call add(t, 'run', '/strobe/oscillator', 'dataset', 'oscillator', 'int32', '1', '', &
                 'oscillator index', 'always')
        call add(t, 'run', '/strobe/cycle', 'dataset', 'cycle', 'int64', '1', 'drive cycles', &
                 'drive cycle of the record (from the start, transient included)', 'always')
        call add(t, 'run', '/strobe/x', 'dataset', 'cycle oscillator', 'float64', '1', 'length', &
                 'displacement from equilibrium at the section', 'always')
        call add(t, 'run', '/strobe/v', 'dataset', 'cycle oscillator', 'float64', '1', &
                 'length/time', 'velocity at the section', 'always')
        call add(t, 'run', '/strobe/period', 'dataset', 'oscillator', 'int32', '1', &
                 'drive cycles', &
                 'period of the oscillator''s strobe record (0: none found, aperiodic)', &
                 'a finished run')
        call add(t, 'run', '/events/event', 'dimension', 'event', '', '', '', 'events recorded', &
                 '&run record_events')
        call add(t, 'run', '/events/time', 'dataset', 'event', 'float64', '1', 'time', &
                 'time of the event from the start of the run', '&run record_events')
        call add(t, 'run', '/events/site', 'dataset', 'event', 'int32', '1', '', &
                 'bond of the event: bond k joins oscillators k and k+1 (0: the left wall, '// &
                 'n: the right wall)', '&run record_events')
        call add(t, 'run', '/events/speed', 'dataset', 'event', 'float64', '1', 'length/time', &
                 'approach speed', '&run record_events')
        call add(t, 'run', '/events/kind', 'dataset', 'event', 'int32', '1', '', 'kind of event', &
                 '&run record_events')
        call add(t, 'run', '/final/oscillator', 'dataset', 'oscillator', 'int32', '1', '', &
                 'oscillator index', 'always')
        call add(t, 'run', '/final/bond', 'dataset', 'bond', 'int32', '1', '', &
                 'bond index: bond k joins oscillators k and k+1 (0: the left wall, n: the '// &
                 'right wall)', 'always')
        call add(t, 'run', '/final/x', 'dataset', 'oscillator', 'float64', '1', 'length', &
                 'displacement from equilibrium at the end', 'always')
        call add(t, 'run', '/final/v', 'dataset', 'oscillator', 'float64', '1', 'length/time', &
                 'velocity at the end', 'always')
        call add(t, 'run', '/final/phase', 'dataset', '', 'float64', 'radian', '', &
                 'drive phase at the end', 'always')
        call add(t, 'run', '/final/time_in_cycle', 'dataset', '', 'float64', '1', 'time', &
                 'time since the start of the drive cycle at the end', 'always')
        call add(t, 'run', '/final/contact', 'dataset', 'oscillator', 'int32', '1', '', &
                 'resting contact of the oscillator with a wall', 'always')
        call add(t, 'run', '/final/event_time', 'dataset', 'bond', 'float64', '1', 'time', &
                 'time within the drive cycle of the next event scheduled at the bond', 'always')
        call add(t, 'run', '/final/event_action', 'dataset', 'bond', 'int32', '1', '', &
                 'next event scheduled at the bond', 'always')
        call add(t, 'run', '/final/cycle', 'dataset', '', 'int64', '1', 'drive cycles', &
                 'drive cycle at the end', 'always')
    end subroutine entries_initial_strobe_events_final

    !> /stats, /lyapunov and /finite_time, their attributes first.
    subroutine entries_stats_lyapunov_finite_time(t)
        type(entry_list_t), intent(inout) :: t

        call add(t, 'run', '/stats/@collisions_per_cycle', 'attribute', '', 'float64', '1', &
                 'impacts per drive cycle', &
                 'collisions per drive cycle over the recorded cycles', 'always')
        call add(t, 'run', '/stats/@impacts', 'attribute', '', 'int64', '1', 'impacts', &
                 'impacts in the recorded cycles', 'always')
        call add(t, 'run', '/stats/@sticks', 'attribute', '', 'int64', '1', '', &
                 'rests on a wall begun in the recorded cycles', 'always')
        call add(t, 'run', '/stats/@releases', 'attribute', '', 'int64', '1', '', &
                 'releases from a wall in the recorded cycles', 'always')
        call add(t, 'run', '/stats/@touches', 'attribute', '', 'int64', '1', '', &
                 'touches without impulse in the recorded cycles (not impacts)', 'always')
        call add(t, 'run', '/stats/bond', 'dataset', 'bond', 'int32', '1', '', &
                 'bond index: bond k joins oscillators k and k+1 (0: the left wall, n: the '// &
                 'right wall)', 'always')
        call add(t, 'run', '/stats/site_counts', 'dataset', 'bond', 'int64', '1', 'impacts', &
                 'impacts at the bond in the recorded cycles', 'always')
        call add(t, 'run', '/stats/cycles_done', 'dataset', '', 'int64', '1', 'drive cycles', &
                 'strobe records done', 'always')
        call add(t, 'run', '/lyapunov/@ky_dimension', 'attribute', '', 'float64', '1', '', &
                 'Kaplan-Yorke dimension', '&lyapunov enabled')
        call add(t, 'run', '/lyapunov/@positive_sum', 'attribute', '', 'float64', 'bit', &
                 'bits per drive cycle', 'sum of the positive Lyapunov exponents', &
                 '&lyapunov enabled')
        call add(t, 'run', '/lyapunov/@collisions_per_cycle', 'attribute', '', 'float64', '1', &
                 'impacts per drive cycle', 'collisions per drive cycle (the c of the sum rule)', &
                 '&lyapunov enabled')
        call add(t, 'run', '/lyapunov/exponent', 'dataset', 'exponent', 'int32', '1', '', &
                 'exponent index (descending order)', '&lyapunov enabled')
        call add(t, 'run', '/lyapunov/qr_step', 'dimension', 'qr_step', '', '', '', &
                 'QR steps of the running estimates', '&lyapunov enabled')
        call add(t, 'run', '/lyapunov/exponents', 'dataset', 'exponent', 'float64', 'bit', &
                 'bits per drive cycle', 'Lyapunov exponent', '&lyapunov enabled')
        call add(t, 'run', '/lyapunov/exponents_per_time', 'dataset', 'exponent', 'float64', '1', &
                 'nats per unit time', 'Lyapunov exponent', '&lyapunov enabled')
        call add(t, 'run', '/lyapunov/stderr', 'dataset', 'exponent', 'float64', 'bit', &
                 'bits per drive cycle', &
                 'standard error of the Lyapunov exponent (blocking, where it levels off '// &
                 'with the block size)', '&lyapunov enabled')
        call add(t, 'run', '/lyapunov/stderr_block', 'dataset', 'exponent', 'int64', '1', &
                 'drive cycles', 'drive cycles per block at which stderr was read', &
                 '&lyapunov enabled')
        call add(t, 'run', '/lyapunov/running_cycle', 'dataset', 'qr_step', 'int64', '1', &
                 'drive cycles', 'drive cycle of the running estimate', '&lyapunov enabled')
        call add(t, 'run', '/lyapunov/running', 'dataset', 'qr_step exponent', 'float64', 'bit', &
                 'bits per drive cycle', &
                 'running estimate of the Lyapunov exponent after a QR step', '&lyapunov enabled')
        call add(t, 'run', '/finite_time/@window', 'attribute', '', 'int32', '1', 'drive cycles', &
                 'recorded cycles per window', '&lyapunov window > 0')
        call add(t, 'run', '/finite_time/cycle', 'dataset', 'cycle', 'int64', '1', &
                 'drive cycles', 'drive cycle at the end of the window', '&lyapunov window > 0')
        call add(t, 'run', '/finite_time/exponent', 'dataset', 'exponent', 'int32', '1', '', &
                 'exponent index (column of the tangent frame: the order of '// &
                 '/lyapunov/exponents unless two exponents cross)', '&lyapunov window > 0')
        call add(t, 'run', '/finite_time/exponents', 'dataset', 'cycle exponent', 'float64', '1', &
                 'bits per drive cycle', &
                 'finite-time Lyapunov exponent over the window (growth of the frame column '// &
                 'per cycle)', '&lyapunov window > 0')
    end subroutine entries_stats_lyapunov_finite_time

    !> /clv and /floquet, their attributes first.
    subroutine entries_clv_floquet(t)
        type(entry_list_t), intent(inout) :: t

        call add(t, 'run', '/clv/@clv_transient', 'attribute', '', 'int32', '1', 'drive cycles', &
                 'backward steps without vectors at the end', '&lyapunov covariant')
        call add(t, 'run', '/clv/@unstable', 'attribute', '', 'int32', '1', '', &
                 'vectors spanning the unstable subspace (positive exponents)', &
                 '&lyapunov covariant')
        call add(t, 'run', '/clv/cycle', 'dataset', 'cycle', 'int64', '1', 'drive cycles', &
                 'drive cycle of the record (as /strobe/cycle)', '&lyapunov covariant')
        call add(t, 'run', '/clv/vector', 'dataset', 'vector', 'int32', '1', '', &
                 'covariant vector index (the columns of the QR frame: descending exponents)', &
                 '&lyapunov covariant')
        call add(t, 'run', '/clv/oscillator', 'dataset', 'oscillator', 'int32', '1', '', &
                 'oscillator index', '&lyapunov covariant')
        call add(t, 'run', '/clv/ipr', 'dataset', 'cycle vector', 'float64', '1', '', &
                 'inverse participation ratio of the vector''s per-oscillator weight (1/n: '// &
                 'spread evenly, 1: one oscillator)', '&lyapunov covariant')
        call add(t, 'run', '/clv/min_angle', 'dataset', 'cycle', 'float64', 'radian', '', &
                 'smallest angle between the span of the unstable vectors and any other '// &
                 'vector (NaN: no such pair)', '&lyapunov covariant')
        call add(t, 'run', '/clv/leading_vector', 'dataset', 'leading_vector', 'int32', '1', '', &
                 'index of the vectors whose site weights are stored (the first clv_store)', &
                 '&lyapunov clv_store > 0')
        call add(t, 'run', '/clv/site_weight', 'dataset', 'cycle leading_vector oscillator', &
                 'float64', '1', '', &
                 'weight of the oscillator in the vector, x**2 + v**2 of its components '// &
                 '(summing to 1)', '&lyapunov clv_store > 0')
        call add(t, 'run', '/clv/exponents', 'dataset', 'vector', 'float64', 'bit', &
                 'bits per drive cycle', 'growth rate of the covariant vector', &
                 '&lyapunov covariant')
        call add(t, 'run', '/clv/stderr', 'dataset', 'vector', 'float64', 'bit', &
                 'bits per drive cycle', &
                 'standard error of the growth rate (blocking, where it levels off with the '// &
                 'block size)', '&lyapunov covariant')
        call add(t, 'run', '/clv/stderr_block', 'dataset', 'vector', 'int64', '1', &
                 'drive cycles', 'records per block at which stderr was read off', &
                 '&lyapunov covariant')
        call add(t, 'run', '/clv/component', 'dataset', 'component', 'int32', '1', '', &
                 'state component: 2i - 1 is x(i), 2i is v(i)', '&lyapunov clv_save > 0')
        call add(t, 'run', '/clv/saved_cycle', 'dataset', 'saved_cycle', 'int64', '1', &
                 'drive cycles', 'drive cycle of the record whose vectors are stored', &
                 '&lyapunov clv_save > 0')
        call add(t, 'run', '/clv/vectors', 'dataset', 'saved_cycle vector component', 'float64', &
                 '1', '', &
                 'covariant Lyapunov vector (unit length; components x(1), v(1), x(2), ...)', &
                 '&lyapunov clv_save > 0')
        call add(t, 'run', '/floquet/@cycles', 'attribute', '', 'int32', '1', 'drive cycles', &
                 'drive cycles the Jacobian spans', '&lyapunov jacobian')
        call add(t, 'run', '/floquet/row', 'dimension', 'row', '', '', '', &
                 'rows of the Jacobian', '&lyapunov jacobian')
        call add(t, 'run', '/floquet/column', 'dimension', 'column', '', '', '', &
                 'columns of the Jacobian', '&lyapunov jacobian')
        call add(t, 'run', '/floquet/multiplier', 'dimension', 'multiplier', '', '', '', &
                 'Floquet multipliers', '&lyapunov jacobian')
        call add(t, 'run', '/floquet/jacobian', 'dataset', 'row column', 'float64', '1', '', &
                 'Jacobian of the Poincare map over the cycles; rows and columns ordered '// &
                 'x(1), v(1), x(2), ...', '&lyapunov jacobian')
        call add(t, 'run', '/floquet/multipliers_re', 'dataset', 'multiplier', 'float64', '1', &
                 '', 'real part of the Floquet multiplier', '&lyapunov jacobian')
        call add(t, 'run', '/floquet/multipliers_im', 'dataset', 'multiplier', 'float64', '1', &
                 '', 'imaginary part of the Floquet multiplier', '&lyapunov jacobian')
    end subroutine entries_clv_floquet

    !> /resume.
    subroutine entries_resume(t)
        type(entry_list_t), intent(inout) :: t

        call add(t, 'run', '/resume/start_cycle', 'dataset', '', 'int64', '1', 'drive cycles', &
                 'drive cycle of the run''s start', 'a run stopped early')
        call add(t, 'run', '/resume/start_time_in_cycle', 'dataset', '', 'float64', '1', 'time', &
                 'time within the drive cycle of the run''s start', 'a run stopped early')
        call add(t, 'run', '/resume/last_event', 'dataset', '', 'float64', '1', 'time', &
                 'time within the drive cycle of the last impact', 'a run stopped early')
        call add(t, 'run', '/resume/same_instant', 'dataset', '', 'int32', '1', '', &
                 'impacts at the time of last_event', 'a run stopped early')
        call add(t, 'run', '/resume/state', 'dimension', 'state', '', '', '', &
                 'components of the state', 'a run stopped early, &lyapunov enabled')
        call add(t, 'run', '/resume/vector', 'dimension', 'vector', '', '', '', &
                 'tangent vectors', 'a run stopped early, &lyapunov enabled')
        call add(t, 'run', '/resume/packed_int', 'dimension', 'packed_int', '', '', '', &
                 'the packed integers of the Lyapunov accumulator', &
                 'a run stopped early, &lyapunov enabled')
        call add(t, 'run', '/resume/packed_real', 'dimension', 'packed_real', '', '', '', &
                 'the packed reals of the Lyapunov accumulator', &
                 'a run stopped early, &lyapunov enabled')
        call add(t, 'run', '/resume/tangent', 'dataset', 'state vector', 'float64', '1', '', &
                 'tangent vectors (times 2**-tangent_scale_bits)', &
                 'a run stopped early, &lyapunov enabled')
        call add(t, 'run', '/resume/tangent_scale_bits', 'dataset', '', 'int32', '1', '', &
                 'binary scale of the tangent vectors', 'a run stopped early, &lyapunov enabled')
        call add(t, 'run', '/resume/tangent_log', 'dataset', 'vector', 'float64', '1', 'nats', &
                 'growth of the tangent vector kept by the engine', &
                 'a run stopped early, &lyapunov enabled')
        call add(t, 'run', '/resume/rank_losses', 'dataset', '', 'int64', '1', '', &
                 'singular tangent maps since the last QR step', &
                 'a run stopped early, &lyapunov enabled')
        call add(t, 'run', '/resume/jumps_volume', 'dataset', 'vector', 'float64', '1', 'nats', &
                 'ln |det| of the jumps since the vector''s piece was orthonormal (on its '// &
                 'first vector)', &
                 'a run stopped early, &lyapunov enabled')
        call add(t, 'run', '/resume/lyapunov_int', 'dataset', 'packed_int', 'int64', '1', '', &
                 'the Lyapunov accumulator''s integers (packed)', &
                 'a run stopped early, &lyapunov enabled')
        call add(t, 'run', '/resume/lyapunov_real', 'dataset', 'packed_real', 'float64', '1', &
                 'nats', 'the Lyapunov accumulator''s reals (packed)', &
                 'a run stopped early, &lyapunov enabled')
    end subroutine entries_resume

    !> /sweep attributes, /sweep.
    subroutine entries_sweep(t)
        type(entry_list_t), intent(inout) :: t

        call add(t, 'sweep', '/sweep/@parameter', 'attribute', '', 'string', '', '', &
                 'the swept parameter', 'always')
        call add(t, 'sweep', '/sweep/@parameter2', 'attribute', '', 'string', '', '', &
                 'the second swept parameter ('''' in a 1-D sweep)', 'always')
        call add(t, 'sweep', '/sweep/@mode', 'attribute', '', 'string', '', '', &
                 '''continuation'' (each point starts from the last state of the one '// &
                 'before) or ''independent'' (every point from the initial state)', 'always')
        call add(t, 'sweep', '/sweep/point', 'dataset', 'point', 'float64', '1', '{parameter}', &
                 '{parameter} (the swept parameter) at the point', 'always')
        call add(t, 'sweep', '/sweep/point2', 'dataset', 'point2', 'float64', '1', '{parameter}', &
                 '{parameter} (the swept parameter) at the point', 'a 2-D sweep')
        call add(t, 'sweep', '/sweep/record', 'dimension', 'record', '', '', '', &
                 'records of each point', 'always')
        call add(t, 'sweep', '/sweep/oscillator', 'dataset', 'oscillator', 'int32', '1', '', &
                 'oscillator index', 'always')
        call add(t, 'sweep', '/sweep/x', 'dataset', 'point point2? record oscillator', 'float64', &
                 '1', 'length', &
                 'displacement from equilibrium at the section, the records of the point', &
                 'always')
        call add(t, 'sweep', '/sweep/collisions_per_cycle', 'dataset', 'point point2?', &
                 'float64', '1', 'impacts per drive cycle', 'collisions per drive cycle', &
                 'always')
        call add(t, 'sweep', '/sweep/period', 'dataset', 'point point2? oscillator', 'int32', &
                 '1', 'drive cycles', &
                 'period of the oscillator''s strobe record (0: none found, aperiodic)', 'always')
        call add(t, 'sweep', '/sweep/drive_period', 'dataset', 'point|point2', 'float64', '1', &
                 'time', 'drive period 2 pi / omega', 'an omega sweep')
        call add(t, 'sweep', '/sweep/exponent', 'dataset', 'exponent', 'int32', '1', '', &
                 'exponent index (descending order)', '&lyapunov enabled')
        call add(t, 'sweep', '/sweep/exponents', 'dataset', 'point point2? exponent', 'float64', &
                 'bit', 'bits per drive cycle', 'Lyapunov exponent', '&lyapunov enabled')
        call add(t, 'sweep', '/sweep/stderr', 'dataset', 'point point2? exponent', 'float64', &
                 'bit', 'bits per drive cycle', &
                 'standard error of the Lyapunov exponent (blocking, where it levels off '// &
                 'with the block size)', '&lyapunov enabled')
        call add(t, 'sweep', '/sweep/stderr_block', 'dataset', 'point point2? exponent', 'int64', &
                 '1', 'drive cycles', 'drive cycles per block at which stderr was read', &
                 '&lyapunov enabled')
        call add(t, 'sweep', '/sweep/ky_dimension', 'dataset', 'point point2?', 'float64', '1', &
                 '', 'Kaplan-Yorke dimension', '&lyapunov enabled')
    end subroutine entries_sweep

    !> /census attributes.
    subroutine entries_census_attributes(t)
        type(entry_list_t), intent(inout) :: t

        call add(t, 'census', '/census/@samples', 'attribute', '', 'int32', '1', '', &
                 'samples per point', 'always')
        call add(t, 'census', '/census/@seed', 'attribute', '', 'int32', '1', '', &
                 'seed of the samples'' random starts', 'always')
        call add(t, 'census', '/census/@x_amp', 'attribute', '', 'float64', '1', 'length', &
                 'half-width of the random starts'' displacements', 'always')
        call add(t, 'census', '/census/@v_amp', 'attribute', '', 'float64', '1', 'length/time', &
                 'half-width of the random starts'' velocities', 'always')
        call add(t, 'census', '/census/@tolerance', 'attribute', '', 'float64', '1', '', &
                 'tolerance of two states on one attractor', 'always')
        call add(t, 'census', '/census/@mirror', 'attribute', '', 'string', '', '', &
                 'how mirror images count (''merge'' or ''separate'')', 'always')
        call add(t, 'census', '/census/@parameter', 'attribute', '', 'string', '', '', &
                 'the swept parameter ('''' at one point)', 'always')
        call add(t, 'census', '/census/@site_distance_limit', 'attribute', '', 'float64', '1', &
                 '', 'largest distance of two impact-site distributions on one attractor', &
                 'always')
        call add(t, 'census', '/census/@chaos_sigmas', 'attribute', '', 'float64', '1', '', &
                 'standard errors by which lambda1 must exceed 0 to be chaotic', 'always')
        call add(t, 'census', '/census/@rule', 'attribute', '', 'string', '', '', &
                 'the classification in words', 'always')
        call add(t, 'census', '/census/@plane', 'attribute', '', 'string', '', '', &
                 'the two coordinates of the plane, blank-separated', '&census plane')
        call add(t, 'census', '/census/@plane_range', 'attribute', '', 'float64', '1', '', &
                 'lo1, hi1, lo2, hi2 of the plane', '&census plane')
        call add(t, 'census', '/census/@plane_points', 'attribute', '', 'int32', '1', '', &
                 'points per side of the plane', '&census plane')
    end subroutine entries_census_attributes

    !> /census.
    subroutine entries_census(t)
        type(entry_list_t), intent(inout) :: t

        call add(t, 'census', '/census/point', 'dataset', 'point', 'float64', '1', '{parameter}', &
                 '{parameter} (the swept parameter) at the point', 'a census over a sweep')
        call add(t, 'census', '/census/point', 'dataset', 'point', 'int32', '1', '', &
                 'point index (a census at one parameter point)', 'a census at one point')
        call add(t, 'census', '/census/sample', 'dataset', 'sample', 'int32', '1', '', &
                 'sample index (the stream of its random start)', 'always')
        call add(t, 'census', '/census/oscillator', 'dataset', 'oscillator', 'int32', '1', '', &
                 'oscillator index', 'always')
        call add(t, 'census', '/census/attractor', 'dataset', 'attractor', 'int32', '1', '', &
                 'attractor id', 'always')
        call add(t, 'census', '/census/bond', 'dataset', 'bond', 'int32', '1', '', &
                 'bond index: bond k joins oscillators k and k+1 (0: the left wall, n: the '// &
                 'right wall)', 'always')
        call add(t, 'census', '/census/exponent', 'dataset', 'exponent', 'int32', '1', '', &
                 'exponent index (descending order)', 'always')
        call add(t, 'census', '/census/x0', 'dataset', 'point sample oscillator', 'float64', '1', &
                 'length', 'displacement at t = 0, the sample''s start', 'always')
        call add(t, 'census', '/census/v0', 'dataset', 'point sample oscillator', 'float64', '1', &
                 'length/time', 'velocity at t = 0, the sample''s start', 'always')
        call add(t, 'census', '/census/sample_attractor', 'dataset', 'point sample', 'int32', &
                 '1', '', 'the attractor the sample reached (its id)', 'always')
        call add(t, 'census', '/census/mirrored', 'dataset', 'point sample', 'int32', '1', '', &
                 '1: the sample reached the attractor''s mirror image (mirror = ''merge''), '// &
                 '0: the attractor itself', 'always')
        call add(t, 'census', '/census/lambda1', 'dataset', 'point sample', 'float64', 'bit', &
                 'bits per drive cycle', &
                 'the sample''s largest Lyapunov exponent over its records', 'always')
        call add(t, 'census', '/census/attractor_period', 'dataset', 'attractor oscillator', &
                 'int32', '1', 'drive cycles', &
                 'period of each oscillator''s strobe record on the attractor (0: none '// &
                 'found, aperiodic)', 'always')
        call add(t, 'census', '/census/attractor_lambda1', 'dataset', 'attractor', 'float64', &
                 'bit', 'bits per drive cycle', &
                 'largest Lyapunov exponent of the attractor''s representative (its first '// &
                 'sample)', 'always')
        call add(t, 'census', '/census/attractor_lambda1_stderr', 'dataset', 'attractor', &
                 'float64', 'bit', 'bits per drive cycle', &
                 'standard error of attractor_lambda1 (block averages)', 'always')
        call add(t, 'census', '/census/attractor_x', 'dataset', 'attractor oscillator', &
                 'float64', '1', 'length', &
                 'displacement of the representative at its last record, on the section: a '// &
                 'state the attractor''s runs can start from', 'always')
        call add(t, 'census', '/census/attractor_v', 'dataset', 'attractor oscillator', &
                 'float64', '1', 'length/time', &
                 'velocity of the representative at its last record', 'always')
        call add(t, 'census', '/census/attractor_point', 'dataset', 'attractor', 'int32', '1', &
                 '', 'the point (0-based index) where the attractor was found', 'always')
        call add(t, 'census', '/census/attractor_sample', 'dataset', 'attractor', 'int32', '1', &
                 '', 'its representative: the first sample (1-based) that reached it', 'always')
        call add(t, 'census', '/census/attractor_kind', 'dataset', 'attractor', 'string', '1', &
                 '', 'periodic, chaotic or aperiodic-nonchaotic', 'always')
        call add(t, 'census', '/census/attractor_sites', 'dataset', 'attractor bond', 'float64', &
                 '1', '', &
                 'fraction of the representative''s impacts on each bond over its records', &
                 'always')
        call add(t, 'census', '/census/fraction', 'dataset', 'point attractor', 'float64', '1', &
                 '', &
                 'fraction of the point''s samples that reached the attractor (its basin '// &
                 'fraction)', 'always')
        call add(t, 'census', '/census/fraction_stderr', 'dataset', 'point attractor', 'float64', &
                 '1', '', 'binomial standard error of fraction, sqrt(f (1 - f) / samples)', &
                 'always')
        call add(t, 'census', '/census/sample_exponents', 'dataset', 'point sample exponent', &
                 'float64', 'bit', 'bits per drive cycle', &
                 'the sample''s leading Lyapunov exponents over its records (&census '// &
                 'exponents; the first is lambda1)', 'always')
        call add(t, 'census', '/census/sample_exponents_stderr', 'dataset', &
                 'point sample exponent', 'float64', 'bit', 'bits per drive cycle', &
                 'standard error of sample_exponents (block averages along the sample''s own '// &
                 'run)', 'always')
        call add(t, 'census', '/census/attractor_exponents', 'dataset', 'attractor exponent', &
                 'float64', 'bit', 'bits per drive cycle', &
                 'mean of sample_exponents over the attractor''s samples (mirror images '// &
                 'included)', 'always')
        call add(t, 'census', '/census/attractor_exponents_spread', 'dataset', &
                 'attractor exponent', 'float64', 'bit', 'bits per drive cycle', &
                 'standard deviation of sample_exponents between the attractor''s samples (n '// &
                 '- 1 in the denominator; 0 for one sample): the spread between trajectories', &
                 'always')
    end subroutine entries_census
end module chain_file_table
