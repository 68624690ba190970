!> The file schema's entries of periodic orbits (chain_file_table): a continuation's branches
!> (/continuation) and its curve in two parameters (/curve).
!> Infrastructure, no model section.
module chain_file_table_orbits
    use chain_file_entry, only: entry_list_t, add
    implicit none
    private
    public :: entries_continuation, entries_curve

contains

    !> /continuation attributes, /continuation.
    subroutine entries_continuation(t)
        type(entry_list_t), intent(inout) :: t

        call add(t, 'continuation', '/continuation/@parameter', 'attribute', '', 'string', '', &
                 '', 'the continued parameter', 'always')
        call add(t, 'continuation', '/continuation/@phase', 'attribute', '', 'float64', 'radian', &
                 '', 'phase of the Poincare section', 'always')
        call add(t, 'continuation', '/continuation/@start', 'attribute', '', 'float64', '1', &
                 '{parameter}', 'the parameter''s start (&chain''s value)', 'always')
        call add(t, 'continuation', '/continuation/@stop', 'attribute', '', 'float64', '1', &
                 '{parameter}', 'the parameter''s bound', 'always')
        call add(t, 'continuation', '/continuation/@step', 'attribute', '', 'float64', '1', &
                 '{parameter}', 'the first step of the parameter', 'always')
        call add(t, 'continuation', '/continuation/@end_reason', 'attribute', '', 'string', '', &
                 '', 'why each branch ended, one line per branch', 'always')
        call add(t, 'continuation', '/continuation/@end_kind', 'attribute', '', 'string', '', &
                 '', 'how each branch ended, one line per branch: max_points, bound, '// &
                 'grazing, corner, section, impacts or newton', 'always')
        call add(t, 'continuation', '/continuation/point', 'dataset', 'point', 'int32', '1', '', &
                 'point index (in the order found, branch after branch)', 'always')
        call add(t, 'continuation', '/continuation/oscillator', 'dataset', 'oscillator', 'int32', &
                 '1', '', 'oscillator index', 'always')
        call add(t, 'continuation', '/continuation/multiplier', 'dataset', 'multiplier', 'int32', &
                 '1', '', 'multiplier index', 'always')
        call add(t, 'continuation', '/continuation/iterate', 'dataset', 'iterate', 'int32', '1', &
                 '', 'section crossing of the period', 'always')
        call add(t, 'continuation', '/continuation/special', 'dataset', 'special', 'int32', '1', &
                 '', 'special point index', 'always')
        call add(t, 'continuation', '/continuation/branch_index', 'dataset', 'branch_index', &
                 'int32', '1', '', 'branch index (the values of branch)', 'always')
        call add(t, 'continuation', '/continuation/values', 'dataset', 'point', 'float64', '1', &
                 '{parameter}', '{parameter} (the continued parameter) at the point', 'always')
        call add(t, 'continuation', '/continuation/x', 'dataset', 'point oscillator', 'float64', &
                 '1', 'length', &
                 'displacement from equilibrium on the section, the orbit''s state', 'always')
        call add(t, 'continuation', '/continuation/v', 'dataset', 'point oscillator', 'float64', &
                 '1', 'length/time', 'velocity on the section, the orbit''s state', 'always')
        call add(t, 'continuation', '/continuation/strobe_x', 'dataset', &
                 'point iterate oscillator', 'float64', '1', 'length', &
                 'displacement at the section crossings of one period (NaN beyond the period)', &
                 'always')
        call add(t, 'continuation', '/continuation/period', 'dataset', 'point', 'int32', '1', &
                 'drive cycles', 'period of the orbit', 'always')
        call add(t, 'continuation', '/continuation/branch', 'dataset', 'point', 'int32', '1', '', &
                 'branch index (0: the first; 1, 2, ...: branches switched to at period '// &
                 'doublings and branch points; each starts at its parent''s special point)', &
                 'always')
        call add(t, 'continuation', '/continuation/multipliers_re', 'dataset', &
                 'point multiplier', 'float64', '1', '', 'Floquet multiplier, real part', &
                 'always')
        call add(t, 'continuation', '/continuation/multipliers_im', 'dataset', &
                 'point multiplier', 'float64', '1', '', 'Floquet multiplier, imaginary part', &
                 'always')
        call add(t, 'continuation', '/continuation/stable', 'dataset', 'point', 'int32', '1', '', &
                 'stability (1: every multiplier inside the unit circle)', 'always')
        call add(t, 'continuation', '/continuation/symmetric', 'dataset', 'point', 'int32', '1', &
                 '', 'mirror symmetry (1: the orbit is its own mirror image half a drive '// &
                 'period later)', 'always')
        call add(t, 'continuation', '/continuation/min_gap', 'dataset', 'point', 'float64', '1', &
                 'length', &
                 'smallest gap at a local minimum over one period, other than a bond''s own '// &
                 'impacts (inf: none)', 'always')
        call add(t, 'continuation', '/continuation/min_impact_speed', 'dataset', 'point', &
                 'float64', '1', 'length/time', &
                 'smallest impact speed over one period (inf: no impacts)', 'always')
        call add(t, 'continuation', '/continuation/impacts_per_period', 'dataset', 'point', &
                 'int32', '1', '', 'impacts over one period', 'always')
        call add(t, 'continuation', '/continuation/residual', 'dataset', 'point', 'float64', '1', &
                 '', 'Newton''s last residual |P(z) - z| / (1 + |z|)', 'always')
        call add(t, 'continuation', '/continuation/iterations', 'dataset', 'point', 'int32', '1', &
                 '', 'Newton iterations of the point', 'always')
        call add(t, 'continuation', '/continuation/special_index', 'dataset', 'special', 'int32', &
                 '1', '', 'the point (0-based index) of the special point', 'always')
        call add(t, 'continuation', '/continuation/special_kind', 'dataset', 'special', 'string', &
                 '1', '', 'fold, period-doubling, neimark-sacker, grazing, corner, '// &
                 'section or branch-point', 'always')
        call add(t, 'continuation', '/continuation/special_value', 'dataset', 'special', &
                 'float64', '1', '{parameter}', '{parameter} at the special point', 'always')
        call add(t, 'continuation', '/continuation/parent', 'dataset', 'branch_index', 'int32', &
                 '1', '', 'the branch it was switched from (-1: none, branch 0)', 'always')
        call add(t, 'continuation', '/continuation/origin_point', 'dataset', 'branch_index', &
                 'int32', '1', '', 'the point (0-based index) of its parent where it began, '// &
                 'a special point whose orbit is its first point (-1: none)', 'always')
        call add(t, 'continuation', '/continuation/origin_kind', 'dataset', 'branch_index', &
                 'string', '1', '', 'the kind of that special point: period-doubling or '// &
                 'branch-point ('''': none)', 'always')
    end subroutine entries_continuation

    !> /curve: a continuation's curve of special points in two parameters (&continuation
    !> follow). values2's '{parameter}' stands for the second parameter, parameter2.
    subroutine entries_curve(t)
        type(entry_list_t), intent(inout) :: t
        character(len=*), parameter :: when = '&continuation follow'

        call add(t, 'continuation', '/curve/@follow', 'attribute', '', 'string', '', '', &
                 'the kind of special point followed: fold, period-doubling, grazing, '// &
                 'branch-point or neimark-sacker', when)
        call add(t, 'continuation', '/curve/@parameter', 'attribute', '', 'string', '', '', &
                 'the continued parameter (the special point''s)', when)
        call add(t, 'continuation', '/curve/@parameter2', 'attribute', '', 'string', '', '', &
                 'the second parameter of the curve', when)
        call add(t, 'continuation', '/curve/@end_reason', 'attribute', '', 'string', '', '', &
                 'why the curve ended (bound, max_points, newton: ...; or why it has no '// &
                 'points)', when)
        call add(t, 'continuation', '/curve/curve_point', 'dataset', 'curve_point', 'int32', &
                 '1', '', 'point index along the curve (0: the located special point)', when)
        call add(t, 'continuation', '/curve/oscillator', 'dataset', 'oscillator', 'int32', '1', &
                 '', 'oscillator index', when)
        call add(t, 'continuation', '/curve/multiplier', 'dataset', 'multiplier', 'int32', '1', &
                 '', 'multiplier index', when)
        call add(t, 'continuation', '/curve/codim2', 'dataset', 'codim2', 'int32', '1', '', &
                 'codimension-two point index', when)
        call add(t, 'continuation', '/curve/values', 'dataset', 'curve_point', 'float64', '1', &
                 '{parameter}', '{parameter} (the continued parameter) at the curve''s point', &
                 when)
        call add(t, 'continuation', '/curve/values2', 'dataset', 'curve_point', 'float64', '1', &
                 '{parameter}', '{parameter} (the second parameter) at the curve''s point', when)
        call add(t, 'continuation', '/curve/x', 'dataset', 'curve_point oscillator', 'float64', &
                 '1', 'length', 'displacement from equilibrium on the section, the orbit''s '// &
                 'state', when)
        call add(t, 'continuation', '/curve/v', 'dataset', 'curve_point oscillator', 'float64', &
                 '1', 'length/time', 'velocity on the section, the orbit''s state', when)
        call add(t, 'continuation', '/curve/multipliers_re', 'dataset', &
                 'curve_point multiplier', 'float64', '1', '', &
                 'Floquet multiplier, real part', when)
        call add(t, 'continuation', '/curve/multipliers_im', 'dataset', &
                 'curve_point multiplier', 'float64', '1', '', &
                 'Floquet multiplier, imaginary part', when)
        call add(t, 'continuation', '/curve/codim2_index', 'dataset', 'codim2', 'int32', '1', &
                 '', 'the curve point (0-based index) that is the codimension-two point', when)
        call add(t, 'continuation', '/curve/codim2_kind', 'dataset', 'codim2', 'string', '1', &
                 '', 'the kind of codimension-two point (fold-flip, 1:1, 1:2, cusp, ...)', when)
    end subroutine entries_curve

end module chain_file_table_orbits
