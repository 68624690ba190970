!> The description of a dataset as the file schema has it (chain_file_schema): its `units`,
!> `long_name`, `model_units` (the reduced unit, docs/model.md section 1.5) and the dimensions
!> of its axes; index coordinates; netCDF's flags. Every writer of the four kinds of file
!> describes its datasets here, so none spells a unit or a long name.
!> Infrastructure, no model section.
module chain_describe
    use chain_kinds, only: i8
    use chain_error, only: error_t, set_error
    use chain_hdf5, only: h5_file_t, h5_write, h5_write_attr, h5_set_scale, h5_dimensions, &
                          h5_create_dimension
    use chain_file_table, only: output_table
    use chain_file_schema, only: output_entry_t, output_entry, entry_dims, entry_long_name, &
                                 entry_model_units, entry_is_coordinate
    implicit none
    private
    public :: describe, describe_group, index_coordinate, bare_dimension, flags

contains

    !> Describe dataset `name` (written): `parameter` names the swept or continued parameter
    !> of its long name and unit, `axes` a sweep's axes (1 or 2), `along` the sweep axis an
    !> `a|b` dimension runs along, `when` the one of two entries of one path. Its dimensions
    !> (a coordinate variable's excepted: it is one) must exist in its group.
    subroutine describe(f, name, err, parameter, axes, along, when)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: name
        type(error_t), allocatable, intent(inout) :: err
        character(len=*), intent(in), optional :: parameter, when
        integer, intent(in), optional :: axes, along
        type(output_entry_t) :: e
        character(len=:), allocatable :: model_units

        if (allocated(err)) return
        e = output_entry(name, when)
        if (e%kind /= 'dataset') then
            call set_error(err, "file schema: no dataset '/"//name//"' in the table")
            return
        end if
        call h5_write_attr(f, name, 'units', e%units, err)
        call h5_write_attr(f, name, 'long_name', entry_long_name(e, parameter), err)
        model_units = entry_model_units(e, parameter)
        if (len(model_units) > 0) call h5_write_attr(f, name, 'model_units', model_units, err)
        if (len(e%dims) > 0 .and. .not. entry_is_coordinate(e)) &
            call h5_dimensions(f, name, entry_dims(e, axes, along), err)
    end subroutine describe

    !> Describe every dataset of `group` that the file schema says a file always holds,
    !> coordinates excepted (index_coordinate describes them).
    subroutine describe_group(f, group, err, parameter)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: group
        type(error_t), allocatable, intent(inout) :: err
        character(len=*), intent(in), optional :: parameter
        type(output_entry_t), allocatable :: t(:)
        integer :: i

        t = output_table()
        do i = 1, size(t)
            if (index(t(i)%path, '/'//group//'/') /= 1 .or. t(i)%kind /= 'dataset' .or. &
                t(i)%when /= 'always') cycle
            if (.not. entry_is_coordinate(t(i))) &
                call describe(f, t(i)%path(2:), err, parameter=parameter)
        end do
    end subroutine describe_group

    !> The coordinate variable `name` numbering its dimension first, first + 1, ...
    subroutine index_coordinate(f, name, first, count, err, when)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: name
        integer, intent(in) :: first, count
        type(error_t), allocatable, intent(inout) :: err
        character(len=*), intent(in), optional :: when
        integer :: j

        call h5_write(f, name, [(j, j=first, first + count - 1)], err)
        call describe(f, name, err, when=when)
        call h5_set_scale(f, name, err)
    end subroutine index_coordinate

    !> The dimension `name` without values, of `extent` (growing: unlimited), which the file
    !> schema must list.
    subroutine bare_dimension(f, name, extent, growing, err)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: name
        integer(i8), intent(in) :: extent
        logical, intent(in) :: growing
        type(error_t), allocatable, intent(inout) :: err
        type(output_entry_t) :: e

        if (allocated(err)) return
        e = output_entry(name)
        if (e%kind /= 'dimension') then
            call set_error(err, "file schema: no dimension '/"//name//"' in the table")
            return
        end if
        call h5_create_dimension(f, name, extent, growing, err)
    end subroutine bare_dimension

    !> Integer flags of dataset `name`: netCDF's flag_values and flag_meanings (words joined
    !> by underscores, one per value).
    subroutine flags(f, name, values, meanings, err)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: name, meanings
        integer, intent(in), contiguous :: values(:)
        type(error_t), allocatable, intent(inout) :: err

        call h5_write_attr(f, name, 'flag_values', values, err)
        call h5_write_attr(f, name, 'flag_meanings', meanings, err)
    end subroutine flags

end module chain_describe
