!> What a branch is made of (docs/model.md section 12): the options of a continuation, its
!> result (the points of every branch, the special points, where each branch began and why it
!> ended), the cursor
!> the continuation moves along a branch (a point, its unit tangent and the test quantities of
!> its multipliers), the fixed setting of one branch, and how a cursor's orbit is stored as a
!> point. Following the branches: chain_branch; the corrector: chain_branch_corrector; special
!> points: chain_branch_special.
module chain_branch_points
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error
    use chain_model, only: model_t, set_model_parameter
    use chain_engine, only: chain_t, chain_positions, chain_time
    use chain_event_log, only: event_log_t, event_log_init, event_impact
    use chain_section, only: chain_at_section, advance_to_point
    use chain_orbit, only: orbit_t, orbit_options_t, orbit_pass_t, describe_orbit, interleave
    use chain_curve_mirror, only: half_pass, mirror_symmetric_chain
    implicit none
    private
    public :: branch_options_t, branch_point_t, special_point_t, branch_origin_t, branches_t
    public :: special_kinds, end_kinds
    public :: cursor_t, setting_t, cursor_from_orbit, cursor_from_pass, impacts_per_bond
    public :: store, add_special, add_branch, add_reason, mirror_image

    !> The kinds of special point, as stored.
    character(len=*), parameter :: special_kinds(7) = &
        [character(len=15) :: 'fold', 'period-doubling', 'neimark-sacker', 'grazing', 'corner', &
         'section', 'branch-point']

    !> How a branch can end, as stored (docs/model.md 12.5): its last allowed point, a bound
    !> of the parameter, a grazing, a simultaneous impact of one oscillator with both
    !> neighbours (a corner of the impact surfaces), an impact at the section, a change of the
    !> impacts where no monitor vanishes, or a failure of Newton.
    character(len=*), parameter :: end_kinds(7) = &
        [character(len=10) :: 'max_points', 'bound', 'grazing', 'corner', 'section', 'impacts', &
         'newton']

    type :: branch_options_t
        character(len=:), allocatable :: parameter !! one of chain_parameter's orbit_parameters
        real(wp) :: stop = 0      !! the far bound of the parameter
        real(wp) :: step = 0      !! first arclength step; its sign: the parameter's direction
        integer :: max_points = 200 !! per branch; 1: Newton only, no continuation
        !> levels of period-doubled branches followed (0: none; 1: the 2p branches from the
        !> first branch's period doublings; 2: also the 4p branches from those; ...)
        integer :: doublings = 0
        !> levels of branch switching at branch points (0: none; 1: the two branches crossing
        !> at each branch point of the branches above; 2: also at those located on these; ...)
        integer :: branch_points = 0
        real(wp) :: max_step = 0  !! largest |step| (0: 20 |step|)
        real(wp) :: min_step = 0  !! smallest |step| before Newton's failure ends (0: 1e-6 |step|)
        type(orbit_options_t) :: newton
    end type branch_options_t

    !> One periodic orbit on a branch.
    type :: branch_point_t
        real(wp) :: value = 0     !! the parameter
        integer :: branch = 0     !! 0 the first branch, 1, 2, ... those switched to
        type(orbit_t) :: orbit    !! state, multipliers, impacts, grazing monitors
        real(wp), allocatable :: strobe_x(:, :) !! (n, p): positions at the p section crossings
        logical :: stable = .false. !! every multiplier inside the unit circle
        !> its own mirror image half a drive period later (docs/model.md 12.3)
        logical :: symmetric = .false.
    end type branch_point_t

    type :: special_point_t
        integer :: point = 0      !! index into the points (the located orbit is a point)
        character(len=:), allocatable :: kind !! one of special_kinds
        real(wp) :: value = 0
    end type special_point_t

    !> Where a branch began (docs/model.md 12.4): the special point of its parent branch it
    !> was switched to at (its own first point is that orbit). The first branch has none.
    type :: branch_origin_t
        integer :: parent = -1 !! the parent branch (-1: none)
        integer :: point = 0   !! index into the points of the parent's special point (0: none)
        character(len=:), allocatable :: kind !! that point's kind, one of special_kinds ('': none)
    end type branch_origin_t

    !> Everything followed: the points of every branch in order, the special points, where
    !> each branch began and why each ended.
    type :: branches_t
        integer :: n_points = 0
        type(branch_point_t), allocatable :: points(:)
        integer :: n_specials = 0
        type(special_point_t), allocatable :: specials(:)
        integer :: n_branches = 0
        type(branch_origin_t), allocatable :: origins(:) !! of branch 0, 1, ... in this order
        character(len=:), allocatable :: end_reason !! of every branch, one line each
        character(len=:), allocatable :: end_kind   !! of every branch, one of end_kinds a line
        logical :: stopped = .false. !! the monitor stopped the work: the result is partial
        !> Newton's result from the guess, converged or not (converged: the first point's orbit)
        type(orbit_t) :: start
    end type branches_t

    !> Where the continuation stands: a point on the branch and its unit tangent.
    type :: cursor_t
        real(wp), allocatable :: y(:)        !! (z, mu)
        real(wp), allocatable :: tangent(:)  !! unit, (dz, dmu)
        real(wp), allocatable :: jacobian(:, :)
        type(orbit_t) :: orbit
        integer, allocatable :: impacts(:)   !! impacts per bond 0..n over one period
        real(wp) :: det_plus = 0             !! det(J + I)
        real(wp) :: det_minus = 0            !! det(J - I)
        integer :: unstable_pairs = 0        !! complex pairs outside the unit circle
    end type cursor_t

    !> Fixed things of one branch.
    type :: setting_t
        type(model_t) :: model
        real(wp) :: phase = 0
        integer :: cycles = 1
        integer :: branch = 0
        real(wp) :: low = 0, high = 0  !! the parameter's bounds
        type(branch_options_t) :: opt
    end type setting_t

contains

    !> A cursor at a converged orbit at parameter value mu (tangent not set).
    subroutine cursor_from_orbit(set, mu, orbit, c)
        type(setting_t), intent(in) :: set
        real(wp), intent(in) :: mu
        type(orbit_t), intent(in) :: orbit
        type(cursor_t), intent(out) :: c

        c%y = [interleave(orbit%x, orbit%v), mu]
        c%orbit = orbit
        c%jacobian = orbit%jacobian
        call measure(set, c)
    end subroutine cursor_from_orbit

    !> A cursor at the converged pass (c%y set), described as an orbit.
    subroutine cursor_from_pass(set, model, pass, iterations, c, err)
        type(setting_t), intent(in) :: set
        type(model_t), intent(in) :: model
        type(orbit_pass_t), intent(in) :: pass
        integer, intent(in) :: iterations
        type(cursor_t), intent(inout) :: c
        type(error_t), allocatable, intent(out) :: err

        c%orbit%converged = .true.
        c%orbit%reason = ''
        c%orbit%cycles = set%cycles
        c%orbit%phase = set%phase
        c%orbit%iterations = iterations
        c%orbit%residuals = [pass%residual]
        call describe_orbit(model, pass, c%orbit, err)
        if (allocated(err)) return
        c%jacobian = c%orbit%jacobian
        call measure(set, c)
    end subroutine cursor_from_pass

    !> The impacts per bond and the test quantities of the multipliers.
    pure subroutine measure(set, c)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(inout) :: c
        integer :: j

        associate (o => c%orbit)
            c%impacts = impacts_per_bond(set%model%n, o%event_bond, o%event_kind)
            c%det_plus = 1
            c%det_minus = 1
            c%unstable_pairs = 0
            do j = 1, size(o%multipliers_re)
                if (o%multipliers_im(j) == 0) then
                    c%det_plus = c%det_plus*(1 + o%multipliers_re(j))
                    c%det_minus = c%det_minus*(1 - o%multipliers_re(j))
                else
                    c%det_plus = c%det_plus*hypot(1 + o%multipliers_re(j), &
                                                  o%multipliers_im(j))
                    c%det_minus = c%det_minus*hypot(1 - o%multipliers_re(j), &
                                                    o%multipliers_im(j))
                    if (o%multipliers_im(j) > 0 .and. &
                        hypot(o%multipliers_re(j), o%multipliers_im(j)) > 1) &
                        c%unstable_pairs = c%unstable_pairs + 1
                end if
            end do
        end associate
    end subroutine measure

    !> Impacts per bond 0..n among events (bonds, kinds).
    pure function impacts_per_bond(n, bonds, kinds) result(counts)
        integer, intent(in) :: n, bonds(:), kinds(:)
        integer :: counts(0:n)
        integer :: j

        counts = 0
        do j = 1, size(bonds)
            if (kinds(j) == event_impact) counts(bonds(j)) = counts(bonds(j)) + 1
        end do
    end function impacts_per_bond

    !> Append the cursor's orbit as a point, with its section crossings and its stability.
    subroutine store(set, c, res, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: c
        type(branches_t), intent(inout) :: res
        type(error_t), allocatable, intent(out) :: err
        type(branch_point_t), allocatable :: grown(:)
        type(branch_point_t) :: p
        type(model_t) :: model
        type(chain_t) :: chain
        type(event_log_t) :: log
        integer :: j
        integer(i8) :: cycle

        p%value = c%y(size(c%y))
        p%branch = set%branch
        p%orbit = c%orbit
        p%stable = maxval(hypot(c%orbit%multipliers_re, c%orbit%multipliers_im)) < 1
        model = set%model
        call set_model_parameter(model, set%opt%parameter, p%value)
        allocate (p%strobe_x(model%n, set%cycles))
        p%strobe_x(:, 1) = c%orbit%x
        call mirror_symmetric(model, set%phase, c%orbit%x, c%orbit%v, p%symmetric, err)
        if (allocated(err)) return
        if (set%cycles > 1) then
            call chain_at_section(model, set%phase, c%orbit%x, c%orbit%v, chain, err)
            if (allocated(err)) return
            call event_log_init(log, .false., 0)
            do j = 2, set%cycles
                cycle = j - 1
                call advance_to_point(chain, cycle, chain_time(chain), log, err)
                if (allocated(err)) return
                p%strobe_x(:, j) = chain_positions(chain)
            end do
        end if
        if (res%n_points == size(res%points)) then
            allocate (grown(2*size(res%points)))
            grown(:res%n_points) = res%points
            call move_alloc(grown, res%points)
        end if
        res%n_points = res%n_points + 1
        res%points(res%n_points) = p
    end subroutine store

    !> The orbit through (x, v) on the section `phase` is its own mirror image (mirror_image)
    !> to 1e-7 of its size; never on a chain that is not mirror-symmetric (its spacings a(k)
    !> and a(n-k) differ).
    subroutine mirror_symmetric(model, phase, x, v, symmetric, err)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase, x(:), v(:)
        logical, intent(out) :: symmetric
        type(error_t), allocatable, intent(out) :: err
        real(wp), parameter :: within = 1.0e-7_wp
        real(wp), allocatable :: x_mirror(:), v_mirror(:)
        real(wp) :: size_of

        symmetric = .false.
        if (.not. mirror_symmetric_chain(model)) return
        call mirror_image(model, phase, x, v, x_mirror, v_mirror, err)
        if (allocated(err)) return
        size_of = 1 + max(maxval(abs(x)), maxval(abs(v)))
        symmetric = max(maxval(abs(x_mirror - x)), maxval(abs(v_mirror - v))) <= within*size_of
    end subroutine mirror_symmetric

    !> The mirror image S of the orbit through (x, v) on the section `phase` of a
    !> mirror-symmetric chain, on the same section (docs/model.md 9: x(i) -> -x(n+1-i),
    !> v(i) -> -v(n+1-i), the drive shifted by half a period): the state half a drive period
    !> after the section, from a fresh chain, mirrored (chain_curve_mirror's half map).
    subroutine mirror_image(model, phase, x, v, x_mirror, v_mirror, err)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase, x(:), v(:)
        real(wp), allocatable, intent(out) :: x_mirror(:), v_mirror(:)
        type(error_t), allocatable, intent(out) :: err
        type(orbit_pass_t) :: pass

        call half_pass(model, phase, interleave(x, v), pass, err, .false.)
        if (allocated(err)) return
        if (.not. pass%admissible) then
            call set_error(err, "mirror image: the state has a negative gap")
            return
        end if
        x_mirror = pass%image(1::2)
        v_mirror = pass%image(2::2)
    end subroutine mirror_image

    subroutine add_special(res, point, kind, value)
        type(branches_t), intent(inout) :: res
        integer, intent(in) :: point
        character(len=*), intent(in) :: kind
        real(wp), intent(in) :: value
        type(special_point_t), allocatable :: grown(:)

        if (res%n_specials == size(res%specials)) then
            allocate (grown(2*size(res%specials)))
            grown(:res%n_specials) = res%specials
            call move_alloc(grown, res%specials)
        end if
        res%n_specials = res%n_specials + 1
        res%specials(res%n_specials) = special_point_t(point, kind, value)
    end subroutine add_special

    !> Branch res%n_branches (0, 1, ...) begins: switched to at special point `special` (index
    !> into the special points) of its parent branch, or the first branch (none given).
    subroutine add_branch(res, special)
        type(branches_t), intent(inout) :: res
        integer, intent(in), optional :: special
        type(branch_origin_t), allocatable :: grown(:)
        type(branch_origin_t) :: origin

        origin%kind = ''
        if (present(special)) then
            origin%point = res%specials(special)%point
            origin%parent = res%points(origin%point)%branch
            origin%kind = res%specials(special)%kind
        end if
        if (.not. allocated(res%origins)) allocate (res%origins(4))
        if (res%n_branches == size(res%origins)) then
            allocate (grown(2*size(res%origins)))
            grown(:res%n_branches) = res%origins
            call move_alloc(grown, res%origins)
        end if
        res%n_branches = res%n_branches + 1
        res%origins(res%n_branches) = origin
    end subroutine add_branch

    !> A branch ended: its kind (one of end_kinds) and the line that says why.
    subroutine add_reason(res, kind, line)
        type(branches_t), intent(inout) :: res
        character(len=*), intent(in) :: kind, line

        if (len(res%end_reason) > 0) then
            res%end_reason = res%end_reason//new_line('a')
            res%end_kind = res%end_kind//new_line('a')
        end if
        res%end_reason = res%end_reason//line
        res%end_kind = res%end_kind//kind
    end subroutine add_reason

end module chain_branch_points
