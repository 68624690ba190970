!> Whole datasets of reals, integers and strings, written and read at once (chain_hdf5
!> gathers the interface), and their extents. Infrastructure, no model section.
module chain_hdf5_datasets
    use, intrinsic :: iso_c_binding, only: c_null_char, c_ptr, c_loc, c_char
    use hdf5, only: hid_t, hsize_t, h5screate_f, h5screate_simple_f, h5sclose_f, &
                    h5sget_simple_extent_ndims_f, h5sget_simple_extent_dims_f, H5S_SCALAR_F, &
                    h5dcreate_f, h5dopen_f, h5dclose_f, h5dwrite_f, h5dread_f, h5dget_space_f, &
                    h5pclose_f, h5tclose_f
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int8
    use chain_hdf5_base, only: check, types_of, creation_properties, h5_id, h5_path, h5_file_t, &
                               h5_real, h5_int, h5_int8, compress_min
    use chain_hdf5_attributes, only: variable_string_type
    implicit none
    private
    public :: write_dataset, h5_write_strings, write_real_0d, write_real_1d, write_real_2d
    public :: write_real_3d, write_real_4d, write_int_0d, write_int_1d, write_int_2d, write_int_3d
    public :: write_int8_0d, write_int8_1d, write_int8_2d, write_int8_3d, read_dataset
    public :: dataset_dims, same_extent, dims_text, dataset_extent, h5_extent, extent_of_rank
    public :: read_real_0d, read_real_1d, read_int_0d, read_int_1d, read_int8_0d, read_int8_1d
    public :: read_alloc_real_1d, read_alloc_real_2d, read_alloc_int8_1d, h5_write, h5_read
    public :: h5_read_alloc

    !> A new dataset holding `values` (a scalar: a dataset without axes).
    interface h5_write
        module procedure write_real_0d, write_real_1d, write_real_2d, write_real_3d, &
            write_real_4d, write_int_0d, write_int_1d, write_int_2d, write_int_3d, &
            write_int8_0d, write_int8_1d, write_int8_2d, write_int8_3d
    end interface h5_write

    !> A dataset read into `values`, whose extents it must have (a scalar: one value).
    interface h5_read
        module procedure read_real_0d, read_real_1d, read_int_0d, read_int_1d, read_int8_0d, &
            read_int8_1d
    end interface h5_read

    !> A dataset of the rank of `values`, allocated to its extents and read.
    interface h5_read_alloc
        module procedure read_alloc_real_1d, read_alloc_real_2d, read_alloc_int8_1d
    end interface h5_read_alloc
contains

    ! ---- whole datasets -------------------------------------------------------------------


    !> A dataset of extents `dims` (none: a scalar) and element type `kind`, written whole
    !> from `buf`.
    subroutine write_dataset(file, name, kind, dims, buf, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in) :: kind
        integer(hsize_t), intent(in) :: dims(:)
        type(c_ptr), intent(in) :: buf
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: space, dset, file_type, mem_type, plist
        integer :: e

        if (allocated(err)) return
        call types_of(kind, file_type, mem_type)
        if (size(dims) == 0) then
            call h5screate_f(H5S_SCALAR_F, space, e)
            call check(e, 'h5screate_f', '/'//name, h5_path(file), err)
        else
            call h5screate_simple_f(size(dims), dims, space, e)
            call check(e, 'h5screate_simple_f', '/'//name, h5_path(file), err)
        end if
        if (allocated(err)) return
        call creation_properties(file, name, dims, size(dims) > 0 .and. &
                                 product(dims) >= int(compress_min, hsize_t), plist, err)
        if (.not. allocated(err)) then
            call h5dcreate_f(h5_id(file), name, file_type, space, dset, e, dcpl_id=plist)
            call check(e, 'h5dcreate_f', '/'//name, h5_path(file), err)
            if (.not. allocated(err)) then
                call h5dwrite_f(dset, mem_type, buf, e)
                call check(e, 'h5dwrite_f', '/'//name, h5_path(file), err)
                call h5dclose_f(dset, e)
                call check(e, 'h5dclose_f', '/'//name, h5_path(file), err)
            end if
            call h5pclose_f(plist, e)
            call check(e, 'h5pclose_f', '/'//name, h5_path(file), err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', '/'//name, h5_path(file), err)
    end subroutine write_dataset

    !> A 1-D dataset of variable-length UTF-8 strings (netCDF-4's NC_STRING), `values` with
    !> their trailing blanks removed.
    subroutine h5_write_strings(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name, values(:)
        type(error_t), allocatable, intent(inout) :: err
        type :: text_t
            character(kind=c_char), allocatable :: chars(:)
        end type text_t
        type(text_t), allocatable, target :: texts(:)
        type(c_ptr), allocatable, target :: pointers(:)
        integer(hid_t) :: string_type, space, dset
        integer(hsize_t) :: dims(1)
        integer :: e, j, k, length

        if (allocated(err)) return
        allocate (texts(size(values)), pointers(max(1, size(values))))
        do j = 1, size(values)
            length = len_trim(values(j))
            allocate (texts(j)%chars(length + 1))
            do k = 1, length
                texts(j)%chars(k) = values(j)(k:k)
            end do
            texts(j)%chars(length + 1) = c_null_char
            pointers(j) = c_loc(texts(j)%chars)
        end do
        call variable_string_type(file, '/'//name, string_type, err)
        if (allocated(err)) return
        dims = size(values)
        call h5screate_simple_f(1, dims, space, e)
        call check(e, 'h5screate_simple_f', '/'//name, h5_path(file), err)
        if (.not. allocated(err)) then
            call h5dcreate_f(h5_id(file), name, string_type, space, dset, e)
            call check(e, 'h5dcreate_f', '/'//name, h5_path(file), err)
            if (.not. allocated(err)) then
                if (size(values) > 0) then
                    call h5dwrite_f(dset, string_type, c_loc(pointers), e)
                    call check(e, 'h5dwrite_f', '/'//name, h5_path(file), err)
                end if
                call h5dclose_f(dset, e)
                call check(e, 'h5dclose_f', '/'//name, h5_path(file), err)
            end if
            call h5sclose_f(space, e)
            call check(e, 'h5sclose_f', '/'//name, h5_path(file), err)
        end if
        call h5tclose_f(string_type, e)
        call check(e, 'h5tclose_f', '/'//name, h5_path(file), err)
    end subroutine h5_write_strings

    subroutine write_real_0d(file, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        real(wp), intent(in), target :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: scalar(0)

        call write_dataset(file, name, h5_real, scalar, c_loc(value), err)
    end subroutine write_real_0d

    subroutine write_real_1d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        real(wp), intent(in), target, contiguous :: values(:)
        type(error_t), allocatable, intent(inout) :: err

        call write_dataset(file, name, h5_real, shape(values, hsize_t), c_loc(values), err)
    end subroutine write_real_1d

    subroutine write_real_2d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        real(wp), intent(in), target, contiguous :: values(:, :)
        type(error_t), allocatable, intent(inout) :: err

        call write_dataset(file, name, h5_real, shape(values, hsize_t), c_loc(values), err)
    end subroutine write_real_2d

    subroutine write_real_3d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        real(wp), intent(in), target, contiguous :: values(:, :, :)
        type(error_t), allocatable, intent(inout) :: err

        call write_dataset(file, name, h5_real, shape(values, hsize_t), c_loc(values), err)
    end subroutine write_real_3d

    subroutine write_real_4d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        real(wp), intent(in), target, contiguous :: values(:, :, :, :)
        type(error_t), allocatable, intent(inout) :: err

        call write_dataset(file, name, h5_real, shape(values, hsize_t), c_loc(values), err)
    end subroutine write_real_4d

    subroutine write_int_0d(file, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in), target :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: scalar(0)

        call write_dataset(file, name, h5_int, scalar, c_loc(value), err)
    end subroutine write_int_0d

    subroutine write_int_1d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in), target, contiguous :: values(:)
        type(error_t), allocatable, intent(inout) :: err

        call write_dataset(file, name, h5_int, shape(values, hsize_t), c_loc(values), err)
    end subroutine write_int_1d

    subroutine write_int_2d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in), target, contiguous :: values(:, :)
        type(error_t), allocatable, intent(inout) :: err

        call write_dataset(file, name, h5_int, shape(values, hsize_t), c_loc(values), err)
    end subroutine write_int_2d

    subroutine write_int_3d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in), target, contiguous :: values(:, :, :)
        type(error_t), allocatable, intent(inout) :: err

        call write_dataset(file, name, h5_int, shape(values, hsize_t), c_loc(values), err)
    end subroutine write_int_3d

    subroutine write_int8_0d(file, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(in), target :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: scalar(0)

        call write_dataset(file, name, h5_int8, scalar, c_loc(value), err)
    end subroutine write_int8_0d

    subroutine write_int8_1d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(in), target, contiguous :: values(:)
        type(error_t), allocatable, intent(inout) :: err

        call write_dataset(file, name, h5_int8, shape(values, hsize_t), c_loc(values), err)
    end subroutine write_int8_1d

    subroutine write_int8_2d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(in), target, contiguous :: values(:, :)
        type(error_t), allocatable, intent(inout) :: err

        call write_dataset(file, name, h5_int8, shape(values, hsize_t), c_loc(values), err)
    end subroutine write_int8_2d

    subroutine write_int8_3d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(in), target, contiguous :: values(:, :, :)
        type(error_t), allocatable, intent(inout) :: err

        call write_dataset(file, name, h5_int8, shape(values, hsize_t), c_loc(values), err)
    end subroutine write_int8_3d

    !> Read dataset `name` whole into `buf` (element type `kind`), after checking that its
    !> extents are `dims` (none: a scalar, or one value).
    subroutine read_dataset(file, name, kind, dims, buf, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in) :: kind
        integer(hsize_t), intent(in) :: dims(:)
        type(c_ptr), intent(in) :: buf
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: dset, file_type, mem_type
        integer(hsize_t), allocatable :: found(:)
        integer :: e
        type(c_ptr) :: target_buf ! (h5dread_f wants a definable pointer)

        if (allocated(err)) return
        call types_of(kind, file_type, mem_type)
        call h5dopen_f(h5_id(file), name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, h5_path(file), err)
        if (allocated(err)) return
        call dataset_dims(file, dset, name, found, err)
        if (.not. allocated(err)) then
            if (.not. same_extent(found, dims)) &
                call set_error(err, "hdf5: /"//name//" has shape "//dims_text(found)// &
                               ", expected "//dims_text(dims)//" (file "//h5_path(file)//")")
        end if
        if (.not. allocated(err)) then
            target_buf = buf
            call h5dread_f(dset, mem_type, target_buf, e)
            call check(e, 'h5dread_f', '/'//name, h5_path(file), err)
        end if
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, h5_path(file), err)
    end subroutine read_dataset

    !> Extents of an open dataset (Fortran order; none for a scalar).
    subroutine dataset_dims(file, dset, name, dims, err)
        type(h5_file_t), intent(in) :: file
        integer(hid_t), intent(in) :: dset
        character(len=*), intent(in) :: name
        integer(hsize_t), allocatable, intent(out) :: dims(:)
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: space
        integer(hsize_t), allocatable :: maxdims(:)
        integer :: e, rank

        allocate (dims(0))
        call h5dget_space_f(dset, space, e)
        call check(e, 'h5dget_space_f', '/'//name, h5_path(file), err)
        if (allocated(err)) return
        call h5sget_simple_extent_ndims_f(space, rank, e)
        call check(e, 'h5sget_simple_extent_ndims_f', '/'//name, h5_path(file), err)
        if (.not. allocated(err)) then
            deallocate (dims)
            allocate (dims(rank), maxdims(rank))
            ! (returns the rank on success)
            call h5sget_simple_extent_dims_f(space, dims, maxdims, e)
            call check(e, 'h5sget_simple_extent_dims_f', '/'//name, h5_path(file), err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', '/'//name, h5_path(file), err)
    end subroutine dataset_dims

    !> Do extents `found` hold what `want` asks for (none: one value, as a scalar or (1,))?
    pure logical function same_extent(found, want)
        integer(hsize_t), intent(in) :: found(:), want(:)

        if (size(want) == 0) then
            same_extent = product(found) == 1
        else
            same_extent = size(found) == size(want)
            if (same_extent) same_extent = all(found == want)
        end if
    end function same_extent

    !> Extents as h5py shows them: "(3, 16)" for a Fortran (16, 3).
    pure function dims_text(dims) result(text)
        integer(hsize_t), intent(in) :: dims(:)
        character(len=:), allocatable :: text
        integer :: j

        text = '('
        do j = size(dims), 1, -1
            text = text//fmt_int8(int(dims(j), i8))
            if (j > 1) text = text//', '
        end do
        if (size(dims) == 1) text = text//','
        text = text//')'
    end function dims_text

    !> Extents of dataset `name` (Fortran order; none for a scalar or after an error).
    subroutine dataset_extent(file, name, dims, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(hsize_t), allocatable, intent(out) :: dims(:)
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: dset
        integer :: e

        allocate (dims(0))
        if (allocated(err)) return
        call h5dopen_f(h5_id(file), name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, h5_path(file), err)
        if (allocated(err)) return
        call dataset_dims(file, dset, name, dims, err)
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, h5_path(file), err)
    end subroutine dataset_extent

    !> dataset_extent for the callers, who know no HDF5 kinds.
    subroutine h5_extent(file, name, dims, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), allocatable, intent(out) :: dims(:)
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t), allocatable :: found(:)

        call dataset_extent(file, name, found, err)
        dims = int(found, i8)
    end subroutine h5_extent

    !> Extents of dataset `name`, which must have `rank` axes (zero extents after an error).
    subroutine extent_of_rank(file, name, rank, dims, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in) :: rank
        integer(hsize_t), intent(out) :: dims(rank)
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t), allocatable :: found(:)
        character(len=*), parameter :: axes(2) = ['one axis ', 'two axes ']

        dims = 0
        call dataset_extent(file, name, found, err)
        if (allocated(err)) return
        if (size(found) /= rank) then
            call set_error(err, "hdf5: /"//name//" has shape "//dims_text(found)// &
                           ", expected "//trim(axes(rank))//" (file "//h5_path(file)//")")
            return
        end if
        dims = found
    end subroutine extent_of_rank

    subroutine read_real_0d(file, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        real(wp), intent(out), target :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: scalar(0)

        value = 0
        call read_dataset(file, name, h5_real, scalar, c_loc(value), err)
    end subroutine read_real_0d

    subroutine read_real_1d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        real(wp), intent(out), target, contiguous :: values(:)
        type(error_t), allocatable, intent(inout) :: err

        values = 0
        call read_dataset(file, name, h5_real, shape(values, hsize_t), c_loc(values), err)
    end subroutine read_real_1d

    subroutine read_int_0d(file, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(out), target :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: scalar(0)

        value = 0
        call read_dataset(file, name, h5_int, scalar, c_loc(value), err)
    end subroutine read_int_0d

    subroutine read_int_1d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(out), target, contiguous :: values(:)
        type(error_t), allocatable, intent(inout) :: err

        values = 0
        call read_dataset(file, name, h5_int, shape(values, hsize_t), c_loc(values), err)
    end subroutine read_int_1d

    subroutine read_int8_0d(file, name, value, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(out), target :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: scalar(0)

        value = 0
        call read_dataset(file, name, h5_int8, scalar, c_loc(value), err)
    end subroutine read_int8_0d

    subroutine read_int8_1d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(out), target, contiguous :: values(:)
        type(error_t), allocatable, intent(inout) :: err

        values = 0
        call read_dataset(file, name, h5_int8, shape(values, hsize_t), c_loc(values), err)
    end subroutine read_int8_1d

    subroutine read_alloc_real_1d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        real(wp), allocatable, intent(out) :: values(:)
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: dims(1)

        call extent_of_rank(file, name, 1, dims, err)
        allocate (values(dims(1)))
        call read_real_1d(file, name, values, err)
    end subroutine read_alloc_real_1d

    subroutine read_alloc_real_2d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        real(wp), allocatable, target, intent(out) :: values(:, :)
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: dims(2)

        call extent_of_rank(file, name, 2, dims, err)
        allocate (values(dims(1), dims(2)))
        values = 0
        call read_dataset(file, name, h5_real, dims, c_loc(values), err)
    end subroutine read_alloc_real_2d

    subroutine read_alloc_int8_1d(file, name, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), allocatable, intent(out) :: values(:)
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: dims(1)

        call extent_of_rank(file, name, 1, dims, err)
        allocate (values(dims(1)))
        call read_int8_1d(file, name, values, err)
    end subroutine read_alloc_int8_1d

end module chain_hdf5_datasets
