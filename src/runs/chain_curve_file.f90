!> A continuation's curve in two parameters (docs/model.md section 12.6): the first located
!> special point of kind &continuation follow on branch 0, followed by chain_curve in
!> (parameter, parameter2), and the HDF5 group /curve that holds it.
module chain_curve_file
    use chain_kinds, only: wp
    use chain_error, only: error_t
    use chain_model, only: model_t, set_model_parameter
    use chain_config, only: config_t
    use chain_branch, only: branches_t
    use chain_curve, only: curve_options_t, curve_t, follow_curve
    use chain_output, only: output_t, output_group
    use chain_hdf5, only: h5_write, h5_write_attr, h5_write_strings
    use chain_describe, only: describe, index_coordinate
    implicit none
    private
    public :: curve_table_t, curve_table, first_special, run_curve, write_curve

    !> /curve's datasets (curve_table): arrays of the file's shapes in Fortran order, n
    !> oscillators, np points, nc codim-2 points.
    type :: curve_table_t
        real(wp), allocatable :: values(:), values2(:)            !! (np)
        real(wp), allocatable :: x(:, :), v(:, :)                 !! (n, np)
        real(wp), allocatable :: multipliers_re(:, :), multipliers_im(:, :) !! (2n, np)
        character(len=:), allocatable :: codim2_kind(:)           !! (nc)
        integer, allocatable :: codim2_index(:)                   !! (nc) the point, 0-based
    end type curve_table_t

contains

    !> The first special point of `kind` on branch 0 of `res` (its point; 0: none).
    pure integer function first_special(res, kind) result(k)
        type(branches_t), intent(in) :: res
        character(len=*), intent(in) :: kind
        integer :: j

        k = 0
        do j = 1, res%n_specials
            associate (s => res%specials(j))
                if (s%kind == kind .and. res%points(s%point)%branch == 0) then
                    k = s%point
                    return
                end if
            end associate
        end do
    end function first_special

    !> The curve of cfg%cont_follow from the branches `res`: with no such point, or a start
    !> the curve cannot take, no points and end_reason says why (the run goes on).
    subroutine run_curve(cfg, res, curve)
        type(config_t), intent(in) :: cfg
        type(branches_t), intent(in) :: res
        type(curve_t), intent(out) :: curve
        type(curve_options_t) :: opt
        type(model_t) :: model
        type(error_t), allocatable :: err
        integer :: k

        k = first_special(res, cfg%cont_follow)
        if (k == 0) then
            curve%kind = cfg%cont_follow
            curve%end_reason = 'no '//cfg%cont_follow//' located on branch 0'
            return
        end if
        opt%follow = cfg%cont_follow
        opt%parameter = cfg%cont_parameter
        opt%parameter2 = cfg%cont_parameter2
        opt%stop2 = cfg%cont_stop2
        opt%step2 = cfg%cont_step2
        opt%max_points = cfg%cont_max_points
        model = cfg%model
        associate (p => res%points(k))
            call set_model_parameter(model, cfg%cont_parameter, p%value)
            call follow_curve(model, cfg%record%phase, p%orbit%cycles, p%orbit%x, p%orbit%v, &
                              p%value, opt, curve, err)
        end associate
        ! (follow_curve fails only where its numerics do: the file says so)
        if (allocated(err)) curve%end_reason = err%message
    end subroutine run_curve

    !> /curve's datasets of `curve`, a chain of n oscillators: per point both parameters, the
    !> orbit's state and multipliers; per codim-2 point its kind and point (0-based).
    pure subroutine curve_table(n, curve, table)
        integer, intent(in) :: n
        type(curve_t), intent(in) :: curve
        type(curve_table_t), intent(out) :: table
        integer :: np, nc, j

        np = curve%n_points
        nc = curve%n_codim2
        allocate (table%x(n, np), table%v(n, np))
        allocate (table%multipliers_re(2*n, np), table%multipliers_im(2*n, np))
        allocate (table%values(np), table%values2(np))
        do j = 1, np
            table%values(j) = curve%values(j)
            table%values2(j) = curve%values2(j)
            table%x(:, j) = curve%orbits(j)%x
            table%v(:, j) = curve%orbits(j)%v
            table%multipliers_re(:, j) = curve%orbits(j)%multipliers_re
            table%multipliers_im(:, j) = curve%orbits(j)%multipliers_im
        end do
        if (allocated(curve%codim2_kind)) then
            allocate (character(len=len(curve%codim2_kind)) :: table%codim2_kind(nc))
            table%codim2_kind = curve%codim2_kind(:nc)
            table%codim2_index = curve%codim2_index(:nc) - 1
        else
            allocate (character(len=1) :: table%codim2_kind(0))
            allocate (table%codim2_index(0))
        end if
    end subroutine curve_table

    !> /curve: the datasets of curve_table, the group's attributes (the kind followed, both
    !> parameters, why the curve ended) and every dataset's names, units and dimensions.
    subroutine write_curve(out, cfg, curve, err)
        type(output_t), intent(inout) :: out
        type(config_t), intent(in) :: cfg
        type(curve_t), intent(in) :: curve
        type(error_t), allocatable, intent(out) :: err
        character(len=*), parameter :: names(6) = [character(len=14) :: 'x', 'v', &
            'multipliers_re', 'multipliers_im', 'codim2_index', 'codim2_kind']
        type(curve_table_t) :: t
        integer :: n, j

        n = cfg%model%n
        call curve_table(n, curve, t)
        call output_group(out, 'curve', err)
        if (allocated(err)) return
        associate (f => out%file)
            call h5_write_attr(f, 'curve', 'follow', cfg%cont_follow, err)
            call h5_write_attr(f, 'curve', 'parameter', cfg%cont_parameter, err)
            call h5_write_attr(f, 'curve', 'parameter2', cfg%cont_parameter2, err)
            call h5_write_attr(f, 'curve', 'end_reason', curve%end_reason, err)
            if (allocated(err)) return
            call index_coordinate(f, 'curve/curve_point', 0, size(t%values), err)
            call index_coordinate(f, 'curve/oscillator', 1, n, err)
            call index_coordinate(f, 'curve/multiplier', 1, 2*n, err)
            call index_coordinate(f, 'curve/codim2', 0, size(t%codim2_index), err)
            if (allocated(err)) return
            call h5_write(f, 'curve/values', t%values, err)
            call h5_write(f, 'curve/values2', t%values2, err)
            call h5_write(f, 'curve/x', t%x, err)
            call h5_write(f, 'curve/v', t%v, err)
            call h5_write(f, 'curve/multipliers_re', t%multipliers_re, err)
            call h5_write(f, 'curve/multipliers_im', t%multipliers_im, err)
            call h5_write(f, 'curve/codim2_index', t%codim2_index, err)
            call h5_write_strings(f, 'curve/codim2_kind', t%codim2_kind, err)
            if (allocated(err)) return
            call describe(f, 'curve/values', err, parameter=cfg%cont_parameter)
            ! (values2's placeholder is the second parameter)
            call describe(f, 'curve/values2', err, parameter=cfg%cont_parameter2)
            do j = 1, size(names)
                call describe(f, 'curve/'//trim(names(j)), err)
            end do
        end associate
    end subroutine write_curve

end module chain_curve_file
