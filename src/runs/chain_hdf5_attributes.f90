!> Attributes of HDF5 objects (chain_hdf5 gathers the interface): scalar variable-length
!> UTF-8 strings, numbers of one value as scalars, small arrays; read back whichever string
!> type a file holds. Infrastructure, no model section.
module chain_hdf5_attributes
    use, intrinsic :: iso_c_binding, only: c_null_char, c_ptr, c_loc, c_char, c_size_t, &
                                           c_f_pointer, c_associated
    use hdf5, only: hid_t, hsize_t, size_t, h5screate_f, h5screate_simple_f, h5sclose_f, &
                    h5sget_simple_extent_npoints_f, H5S_SCALAR_F, H5P_DEFAULT_F, &
                    h5acreate_by_name_f, h5aopen_by_name_f, h5awrite_f, h5aread_f, h5aget_space_f, &
                    h5aclose_f, h5aexists_by_name_f, h5adelete_by_name_f, h5aget_type_f, &
                    h5tis_variable_str_f, h5tcopy_f, h5tset_cset_f, h5tclose_f, h5dvlen_reclaim_f, &
                    H5T_CSET_UTF8_F, H5T_STRING, H5T_NATIVE_DOUBLE, H5T_NATIVE_INTEGER, &
                    H5T_STD_I64LE, H5T_STRING_F, H5T_STD_I32LE, H5T_IEEE_F64LE, h5kind_to_type, &
                    H5_INTEGER_KIND
    use h5lt, only: h5ltget_attribute_info_f, h5ltget_attribute_string_f
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int8
    use chain_hdf5_base, only: check, h5_id, h5_path, attr_name, h5_file_t
    implicit none
    private
    public :: write_attr_raw, write_attr_string, variable_string_type, write_attr_int
    public :: write_attr_int_1d, write_attr_real, write_attr_real_1d, write_attr_int8, read_attr
    public :: read_attr_int8, read_attr_real, read_attr_string, attr_is_variable_string
    public :: read_attr_variable_string, h5_write_attr, h5_read_attr

    interface
        !> C's strlen, for the variable-length strings HDF5 returns.
        pure function c_strlen(s) bind(C, name='strlen') result(length)
            import :: c_ptr, c_size_t
            type(c_ptr), intent(in), value :: s
            integer(c_size_t) :: length
        end function c_strlen
    end interface
    !> Attribute `name` of object `obj` ('/' for the root, 'params' for /params), one value.
    interface h5_write_attr
        module procedure write_attr_string, write_attr_int, write_attr_int8, write_attr_real, &
            write_attr_int_1d, write_attr_real_1d
    end interface h5_write_attr

    interface h5_read_attr
        module procedure read_attr_string, read_attr_int8, read_attr_real
    end interface h5_read_attr
contains

    ! ---- attributes -----------------------------------------------------------------------

    !> Attribute `name` of `obj` with `dims` values (none: a scalar) of HDF5 type `file_type`,
    !> from `buf` (of memory type `mem_type`); an attribute of that name is replaced.
    subroutine write_attr_raw(file, obj, name, file_type, mem_type, dims, buf, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name
        integer(hid_t), intent(in) :: file_type, mem_type
        integer(hsize_t), intent(in) :: dims(:)
        type(c_ptr), intent(in) :: buf
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: space, attr
        integer :: e
        logical :: exists
        character(len=:), allocatable :: what

        if (allocated(err)) return
        what = attr_name(obj, name)
        call h5aexists_by_name_f(h5_id(file), obj, name, exists, e)
        call check(e, 'h5aexists_by_name_f', what, h5_path(file), err)
        if (allocated(err)) return
        if (exists) then
            call h5adelete_by_name_f(h5_id(file), obj, name, e)
            call check(e, 'h5adelete_by_name_f', what, h5_path(file), err)
            if (allocated(err)) return
        end if
        if (size(dims) == 0) then
            call h5screate_f(H5S_SCALAR_F, space, e)
        else
            call h5screate_simple_f(size(dims), dims, space, e)
        end if
        call check(e, 'h5screate_f', what, h5_path(file), err)
        if (allocated(err)) return
        call h5acreate_by_name_f(h5_id(file), obj, name, file_type, space, attr, e)
        call check(e, 'h5acreate_by_name_f', what, h5_path(file), err)
        if (.not. allocated(err)) then
            call h5awrite_f(attr, mem_type, buf, e)
            call check(e, 'h5awrite_f', what, h5_path(file), err)
            call h5aclose_f(attr, e)
            call check(e, 'h5aclose_f', what, h5_path(file), err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', what, h5_path(file), err)
    end subroutine write_attr_raw

    !> A string attribute: one variable-length UTF-8 string (netCDF-4's NC_STRING).
    subroutine write_attr_string(file, obj, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name, value
        type(error_t), allocatable, intent(inout) :: err
        character(kind=c_char), allocatable, target :: text(:)
        type(c_ptr), target :: pointer
        integer(hid_t) :: string_type
        integer(hsize_t) :: scalar(0)
        integer :: e, j

        if (allocated(err)) return
        allocate (text(len(value) + 1))
        do j = 1, len(value)
            text(j) = value(j:j)
        end do
        text(len(value) + 1) = c_null_char
        pointer = c_loc(text)
        call variable_string_type(file, attr_name(obj, name), string_type, err)
        if (allocated(err)) return
        call write_attr_raw(file, obj, name, string_type, string_type, scalar, c_loc(pointer), &
                            err)
        call h5tclose_f(string_type, e)
        call check(e, 'h5tclose_f', attr_name(obj, name), h5_path(file), err)
    end subroutine write_attr_string

    !> The HDF5 type of a variable-length UTF-8 string (to be closed by the caller).
    subroutine variable_string_type(file, what, string_type, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: what
        integer(hid_t), intent(out) :: string_type
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        ! (the Fortran layer's H5T_STRING is C's string of variable length)
        call h5tcopy_f(H5T_STRING, string_type, e)
        call check(e, 'h5tcopy_f', what, h5_path(file), err)
        if (allocated(err)) return
        call h5tset_cset_f(string_type, H5T_CSET_UTF8_F, e)
        call check(e, 'h5tset_cset_f', what, h5_path(file), err)
        if (allocated(err)) call h5tclose_f(string_type, e)
    end subroutine variable_string_type

    !> A default-integer attribute, a scalar (32-bit little-endian in the file).
    subroutine write_attr_int(file, obj, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name
        integer, intent(in), target :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: scalar(0)

        call write_attr_raw(file, obj, name, H5T_STD_I32LE, H5T_NATIVE_INTEGER, scalar, &
                            c_loc(value), err)
    end subroutine write_attr_int

    !> Default integers as one attribute (e.g. netCDF's flag_values), 32-bit little-endian.
    subroutine write_attr_int_1d(file, obj, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name
        integer, intent(in), target, contiguous :: values(:)
        type(error_t), allocatable, intent(inout) :: err

        call write_attr_raw(file, obj, name, H5T_STD_I32LE, H5T_NATIVE_INTEGER, &
                            shape(values, hsize_t), c_loc(values), err)
    end subroutine write_attr_int_1d

    !> A real attribute, a scalar (64-bit IEEE little-endian in the file).
    subroutine write_attr_real(file, obj, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name
        real(wp), intent(in), target :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: scalar(0)

        call write_attr_raw(file, obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, scalar, &
                            c_loc(value), err)
    end subroutine write_attr_real

    !> A real attribute, a list (64-bit IEEE little-endian in the file).
    subroutine write_attr_real_1d(file, obj, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name
        real(wp), intent(in), target, contiguous :: values(:)
        type(error_t), allocatable, intent(inout) :: err

        call write_attr_raw(file, obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &
                            shape(values, hsize_t), c_loc(values), err)
    end subroutine write_attr_real_1d

    !> A 64-bit integer attribute, a scalar.
    subroutine write_attr_int8(file, obj, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name
        integer(i8), intent(in), target :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: scalar(0)

        call write_attr_raw(file, obj, name, H5T_STD_I64LE, h5kind_to_type(i8, H5_INTEGER_KIND), &
                            scalar, c_loc(value), err)
    end subroutine write_attr_int8

    !> One attribute value of object `obj`, into `buf` of memory type `mem_type`; the
    !> attribute must hold exactly one value.
    subroutine read_attr(file, obj, name, mem_type, buf, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name
        integer(hid_t), intent(in) :: mem_type
        type(c_ptr), intent(in) :: buf
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: attr, space
        integer(hsize_t) :: points
        integer :: e
        character(len=:), allocatable :: what
        type(c_ptr) :: target_buf ! (h5aread_f wants a definable pointer)

        if (allocated(err)) return
        what = attr_name(obj, name)
        call h5aopen_by_name_f(h5_id(file), obj, name, attr, e)
        call check(e, 'h5aopen_by_name_f', what, h5_path(file), err)
        if (allocated(err)) return
        call h5aget_space_f(attr, space, e)
        call check(e, 'h5aget_space_f', what, h5_path(file), err)
        if (.not. allocated(err)) then
            call h5sget_simple_extent_npoints_f(space, points, e)
            call check(e, 'h5sget_simple_extent_npoints_f', what, h5_path(file), err)
            if (.not. allocated(err) .and. points /= 1) &
                call set_error(err, "hdf5: "//what//" holds "//fmt_int8(int(points, i8))// &
                               " values, expected one (file "//h5_path(file)//")")
            call h5sclose_f(space, e)
            call check(e, 'h5sclose_f', what, h5_path(file), err)
        end if
        if (.not. allocated(err)) then
            target_buf = buf
            call h5aread_f(attr, mem_type, target_buf, e)
            call check(e, 'h5aread_f', what, h5_path(file), err)
        end if
        call h5aclose_f(attr, e)
        call check(e, 'h5aclose_f', what, h5_path(file), err)
    end subroutine read_attr

    subroutine read_attr_int8(file, obj, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name
        integer(i8), intent(out), target :: value
        type(error_t), allocatable, intent(inout) :: err

        value = 0
        call read_attr(file, obj, name, h5kind_to_type(i8, H5_INTEGER_KIND), c_loc(value), err)
    end subroutine read_attr_int8

    subroutine read_attr_real(file, obj, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name
        real(wp), intent(out), target :: value
        type(error_t), allocatable, intent(inout) :: err

        value = 0
        call read_attr(file, obj, name, H5T_NATIVE_DOUBLE, c_loc(value), err)
    end subroutine read_attr_real

    !> A string attribute: variable-length (schema version 2) or fixed-length (version 1),
    !> without the terminating NUL or the blanks that the Fortran layer of HDF5 pads a
    !> fixed-length one with (trailing blanks are not kept either way).
    subroutine read_attr_string(file, obj, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name
        character(len=:), allocatable, intent(out) :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: dims(1)
        integer(size_t) :: type_size
        integer :: e, type_class, length
        character(len=:), allocatable :: what
        logical :: variable

        value = ''
        if (allocated(err)) return
        what = attr_name(obj, name)
        dims = 0
        type_class = -1
        type_size = 0
        call h5ltget_attribute_info_f(h5_id(file), obj, name, dims, type_class, type_size, e)
        call check(e, 'h5ltget_attribute_info_f', what, h5_path(file), err)
        if (allocated(err)) return
        if (type_class /= H5T_STRING_F) then
            call set_error(err, "hdf5: "//what//" is not a string (file "//h5_path(file)//")")
            return
        end if
        call attr_is_variable_string(file, obj, name, variable, err)
        if (allocated(err)) return
        if (variable) then
            call read_attr_variable_string(file, obj, name, value, err)
        else
            deallocate (value)
            allocate (character(len=int(type_size)) :: value)
            call h5ltget_attribute_string_f(h5_id(file), obj, name, value, e)
            call check(e, 'h5ltget_attribute_string_f', what, h5_path(file), err)
        end if
        if (allocated(err)) then
            value = ''
            return
        end if
        length = index(value, c_null_char) - 1
        if (length >= 0) value = value(:length)
        value = trim(value)
    end subroutine read_attr_string

    !> Is the string attribute `name` of `obj` a variable-length one?
    subroutine attr_is_variable_string(file, obj, name, variable, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name
        logical, intent(out) :: variable
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: attr, file_type
        integer :: e
        character(len=:), allocatable :: what

        variable = .false.
        what = attr_name(obj, name)
        call h5aopen_by_name_f(h5_id(file), obj, name, attr, e)
        call check(e, 'h5aopen_by_name_f', what, h5_path(file), err)
        if (allocated(err)) return
        call h5aget_type_f(attr, file_type, e)
        call check(e, 'h5aget_type_f', what, h5_path(file), err)
        if (.not. allocated(err)) then
            call h5tis_variable_str_f(file_type, variable, e)
            call check(e, 'h5tis_variable_str_f', what, h5_path(file), err)
            call h5tclose_f(file_type, e)
            call check(e, 'h5tclose_f', what, h5_path(file), err)
        end if
        call h5aclose_f(attr, e)
        call check(e, 'h5aclose_f', what, h5_path(file), err)
    end subroutine attr_is_variable_string

    !> A variable-length string attribute holding one string; HDF5's copy is freed.
    subroutine read_attr_variable_string(file, obj, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name
        character(len=:), allocatable, intent(out) :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: string_type, attr, space
        type(c_ptr), target :: pointer
        type(c_ptr) :: reclaim
        character(kind=c_char), pointer :: chars(:)
        integer :: e, j
        character(len=:), allocatable :: what

        value = ''
        what = attr_name(obj, name)
        call variable_string_type(file, what, string_type, err)
        if (allocated(err)) return
        call read_attr(file, obj, name, string_type, c_loc(pointer), err)
        if (.not. allocated(err)) then
            if (c_associated(pointer)) then
                call c_f_pointer(pointer, chars, [c_strlen(pointer)])
                deallocate (value)
                allocate (character(len=size(chars)) :: value)
                do j = 1, size(chars)
                    value(j:j) = chars(j)
                end do
                ! HDF5 allocated the string: give it back
                call h5aopen_by_name_f(h5_id(file), obj, name, attr, e)
                call check(e, 'h5aopen_by_name_f', what, h5_path(file), err)
                if (.not. allocated(err)) then
                    call h5aget_space_f(attr, space, e)
                    call check(e, 'h5aget_space_f', what, h5_path(file), err)
                    if (.not. allocated(err)) then
                        reclaim = c_loc(pointer) ! (h5dvlen_reclaim_f wants a definable one)
                        call h5dvlen_reclaim_f(string_type, space, H5P_DEFAULT_F, reclaim, e)
                        call check(e, 'h5dvlen_reclaim_f', what, h5_path(file), err)
                        call h5sclose_f(space, e)
                        call check(e, 'h5sclose_f', what, h5_path(file), err)
                    end if
                    call h5aclose_f(attr, e)
                    call check(e, 'h5aclose_f', what, h5_path(file), err)
                end if
            end if
        end if
        call h5tclose_f(string_type, e)
        call check(e, 'h5tclose_f', what, h5_path(file), err)
    end subroutine read_attr_variable_string

end module chain_hdf5_attributes
