!> The HDF5 library behind one small interface, the only module with `use hdf5`: files (create,
!> open, close), groups and links, attributes, whole datasets of reals and integers, chunked
!> datasets that grow or shrink along their last axis, and hyperslab transfers. It knows
!> nothing of impactchain's file layout (chain_output, chain_sweep say what goes where).
!>
!> What it writes is readable as netCDF-4 (README "Output"): string attributes are scalar,
!> variable-length UTF-8; numeric attributes of one value are scalars; the axes of a dataset
!> are dimension scales (h5_set_scale, h5_create_dimension, h5_dimensions), a dimension
!> without coordinate values carrying the NAME netCDF gives such a dimension; chunked
!> datasets and whole datasets of at least `compress_min` elements are stored with the
!> shuffle and deflate filters when the HDF5 library can encode deflate (else uncompressed).
!>
!> A file is an `h5_file_t`: its HDF5 id (kept private here) and its path, which every error
!> message names. Element types are `h5_real` (real(wp), the native double in the file),
!> `h5_int` (default integer, the native integer) and `h5_int8` (integer(i8), 64-bit
!> little-endian). Fortran arrays x(n, m) appear in h5py as (m, n).
!>
!> Errors: every procedure takes `err` intent(inout), does nothing when it is already set, and
!> sets it on a failure; so a sequence of calls needs one test at its end, and the first
!> failure is the one reported. Every HDF5 status code goes through one funnel, `check`, which
!> turns a failure into "hdf5: <call> failed on <object> (file <path>)". Every id opened is
!> closed on the way out, after a failure too (`h5_close_file` closes even then).
!> Infrastructure, no model section.
module chain_hdf5
    use, intrinsic :: iso_c_binding, only: c_null_char, c_ptr, c_loc, c_char, c_size_t, &
                                           c_f_pointer, c_associated, c_int, c_bool
    use hdf5, only: hid_t, hsize_t, size_t, h5open_f, h5eset_auto_f, &
                    h5fcreate_f, h5fopen_f, h5fclose_f, h5fis_hdf5_f, &
                    H5F_ACC_TRUNC_F, H5F_ACC_RDWR_F, H5F_ACC_RDONLY_F, &
                    h5lexists_f, h5ldelete_f, h5gcreate_f, h5gclose_f, &
                    h5screate_f, h5screate_simple_f, h5sclose_f, h5sselect_hyperslab_f, &
                    h5sget_simple_extent_ndims_f, h5sget_simple_extent_dims_f, &
                    h5sget_simple_extent_npoints_f, H5S_SCALAR_F, H5S_UNLIMITED_F, &
                    H5S_SELECT_SET_F, h5dcreate_f, h5dopen_f, h5dclose_f, h5dwrite_f, &
                    h5dread_f, h5dset_extent_f, h5dget_space_f, &
                    h5pcreate_f, h5pset_chunk_f, h5pclose_f, H5P_DATASET_CREATE_F, H5P_FILE_ACCESS_F, &
                    h5pset_shuffle_f, h5pset_deflate_f, H5P_DEFAULT_F, &
                    h5zfilter_avail_f, h5zget_filter_info_f, H5Z_FILTER_DEFLATE_F, &
                    H5Z_FILTER_ENCODE_ENABLED_F, &
                    h5acreate_by_name_f, h5aopen_by_name_f, h5awrite_f, h5aread_f, &
                    h5aget_space_f, h5aclose_f, h5aexists_by_name_f, h5adelete_by_name_f, &
                    h5aget_type_f, h5tget_class_f, h5tis_variable_str_f, h5tcopy_f, &
                    h5tset_cset_f, h5tclose_f, h5dvlen_reclaim_f, &
                    H5T_CSET_UTF8_F, H5T_STRING, &
                    H5T_NATIVE_DOUBLE, H5T_NATIVE_INTEGER, H5T_STD_I64LE, H5T_STRING_F, &
                    H5T_STD_I32LE, H5T_IEEE_F64LE, H5T_IEEE_F32BE, &
                    h5kind_to_type, H5_INTEGER_KIND
    use h5lt, only: h5ltget_attribute_info_f, h5ltget_attribute_string_f
    use h5ds, only: h5dsset_scale_f, h5dsattach_scale_f, h5dsdetach_scale_f
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int8
    implicit none
    private
    public :: h5_file_t, h5_real, h5_int, h5_int8
    public :: h5_create_file, h5_open_file, h5_close_file, h5_is_hdf5_file
    public :: h5_create_group, h5_exists, h5_delete, h5_delete_attr
    public :: h5_write_attr, h5_read_attr
    public :: h5_write, h5_read, h5_read_alloc, h5_extent, h5_write_strings
    public :: h5_create_growing, h5_create_appendable, h5_set_extent
    public :: h5_write_slab, h5_read_slab
    public :: h5_create_dimension, h5_set_scale, h5_dimensions, h5_detach_dimensions
    public :: h5_compression_available, compress_min, deflate_level

    !> An HDF5 file, open (id >= 0) or not.
    type :: h5_file_t
        private
        integer(hid_t) :: id = -1
        character(len=:), allocatable :: path  !! the name in messages
    end type h5_file_t

    !> Element types of datasets created empty (h5_create_growing, h5_create_appendable).
    integer, parameter :: h5_real = 1   !! real(wp), stored as the native double
    integer, parameter :: h5_int = 2    !! default integer, stored as the native integer
    integer, parameter :: h5_int8 = 3   !! integer(i8), stored as 64-bit little-endian

    !> Whole datasets of at least this many elements are chunked and compressed (smaller ones
    !> are stored as they are: a few kilobytes gain nothing from it).
    integer(i8), parameter :: compress_min = 4096
    !> The deflate level (1 fastest .. 9 smallest). On a run's records and events (chaotic
    !> reals, halved by shuffle + deflate) level 4 saves 1.5 % more than 1 and takes half as
    !> long again to write them (README "Output").
    integer, parameter :: deflate_level = 1
    !> Elements per chunk at most (512 KiB of reals), so that a chunk fits HDF5's default
    !> chunk cache of 1 MiB.
    integer(i8), parameter :: chunk_elements = 65536
    !> The NAME netCDF-4 gives a dimension that has no coordinate values (followed by its
    !> length, as netCDF writes it).
    character(len=*), parameter :: not_a_variable = &
        'This is a netCDF dimension but not a netCDF variable.'

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

    !> `values` written at `offset` into a dataset, first grown to hold them when `grow`.
    interface h5_write_slab
        module procedure write_slab_real_1d, write_slab_real_2d, write_slab_real_3d, &
            write_slab_int_1d, write_slab_int8_1d
    end interface h5_write_slab

    !> `values` read from a dataset at `offset`.
    interface h5_read_slab
        module procedure read_slab_real_2d
    end interface h5_read_slab

    interface
        !> HDF5 1.10.7's switch of its own file locks (no Fortran binding before 1.14)
        function c_h5pset_file_locking(fapl, use_locking, ignore_disabled) &
            bind(C, name='H5Pset_file_locking') result(status)
            import :: hid_t, c_bool, c_int
            integer(hid_t), value :: fapl
            logical(c_bool), value :: use_locking, ignore_disabled
            integer(c_int) :: status
        end function c_h5pset_file_locking
    end interface

contains

    ! ---- the funnel, the library, files ---------------------------------------------------

    !> The funnel for every HDF5 status code. A negative `status` becomes an error naming the
    !> call, the object (`/group/dataset`, or an attribute of one) and the file; an error that
    !> is already set is kept, because it is the first failure, the one to report.
    subroutine check(status, call_name, object, file, err)
        integer, intent(in) :: status
        character(len=*), intent(in) :: call_name, object, file
        type(error_t), allocatable, intent(inout) :: err

        if (status >= 0 .or. allocated(err)) return
        call set_error(err, "hdf5: "//call_name//" failed on "//object//" (file "//file//")")
    end subroutine check

    !> The HDF5 library, initialised (its H5T_* constants are set by h5open_f) and told to
    !> return errors to us rather than print them. `path` is the file about to be used.
    subroutine open_library(path, err)
        character(len=*), intent(in) :: path
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        if (allocated(err)) return
        call h5open_f(e)
        call check(e, 'h5open_f', 'the HDF5 library', path, err)
        if (allocated(err)) return
        call h5eset_auto_f(0, e)
        call check(e, 'h5eset_auto_f', 'the HDF5 library', path, err)
    end subroutine open_library

    !> A new, empty file at `path` (an existing one is replaced).
    subroutine h5_create_file(file, path, err)
        type(h5_file_t), intent(out) :: file
        character(len=*), intent(in) :: path
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        integer(hid_t) :: fapl

        file%path = path
        call open_library(path, err)
        if (allocated(err)) return
        call unlocked_access(path, fapl, err)
        if (allocated(err)) return
        call h5fcreate_f(path, H5F_ACC_TRUNC_F, file%id, e, access_prp=fapl)
        call check(e, 'h5fcreate_f', '/', path, err)
        call h5pclose_f(fapl, e)
        if (allocated(err)) file%id = -1
    end subroutine h5_create_file

    !> File access without HDF5's own lock: a file written is created or opened by the
    !> program only under its own lock (chain_files' lock_file, taken before anything is
    !> truncated), which HDF5's lock, taken on another descriptor of the same file, would
    !> collide with.
    subroutine unlocked_access(path, fapl, err)
        character(len=*), intent(in) :: path
        integer(hid_t), intent(out) :: fapl
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        call h5pcreate_f(H5P_FILE_ACCESS_F, fapl, e)
        call check(e, 'h5pcreate_f', 'file access', path, err)
        if (allocated(err)) return
        e = c_h5pset_file_locking(fapl, .false._c_bool, .true._c_bool)
        call check(e, 'H5Pset_file_locking', 'file access', path, err)
        if (allocated(err)) call h5pclose_f(fapl, e)
    end subroutine unlocked_access

    !> An existing file, opened for reading, or for reading and writing when `writable`.
    subroutine h5_open_file(file, path, writable, err)
        type(h5_file_t), intent(out) :: file
        character(len=*), intent(in) :: path
        logical, intent(in) :: writable
        type(error_t), allocatable, intent(inout) :: err
        integer :: e, e2

        integer(hid_t) :: fapl

        file%path = path
        call open_library(path, err)
        if (allocated(err)) return
        if (writable) then
            call unlocked_access(path, fapl, err)
            if (allocated(err)) return
            call h5fopen_f(path, H5F_ACC_RDWR_F, file%id, e, access_prp=fapl)
            call h5pclose_f(fapl, e2)
        else
            call h5fopen_f(path, H5F_ACC_RDONLY_F, file%id, e)
        end if
        call check(e, 'h5fopen_f', '/', path, err)
        if (allocated(err)) file%id = -1
    end subroutine h5_open_file

    !> Close the file if it is open; an earlier error is kept, and the file is closed anyway.
    subroutine h5_close_file(file, err)
        type(h5_file_t), intent(inout) :: file
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        if (file%id < 0) return
        call h5fclose_f(file%id, e)
        call check(e, 'h5fclose_f', '/', file%path, err)
        file%id = -1
    end subroutine h5_close_file

    !> Is the existing file at `path` an HDF5 file?
    subroutine h5_is_hdf5_file(path, is_hdf5, err)
        character(len=*), intent(in) :: path
        logical, intent(out) :: is_hdf5
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        is_hdf5 = .false.
        call open_library(path, err)
        if (allocated(err)) return
        call h5fis_hdf5_f(path, is_hdf5, e)
        call check(e, 'h5fis_hdf5_f', '/', path, err)
    end subroutine h5_is_hdf5_file

    ! ---- groups and links -----------------------------------------------------------------

    !> Create group `name` unless it exists.
    subroutine h5_create_group(file, name, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: g
        integer :: e
        logical :: exists

        call h5_exists(file, name, exists, err)
        if (allocated(err) .or. exists) return
        call h5gcreate_f(file%id, name, g, e)
        call check(e, 'h5gcreate_f', '/'//name, file%path, err)
        if (allocated(err)) return
        call h5gclose_f(g, e)
        call check(e, 'h5gclose_f', '/'//name, file%path, err)
    end subroutine h5_create_group

    !> Is there a group or dataset `name`? (.false. after an error)
    subroutine h5_exists(file, name, exists, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        logical, intent(out) :: exists
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        exists = .false.
        if (allocated(err)) return
        call h5lexists_f(file%id, name, exists, e)
        call check(e, 'h5lexists_f', '/'//name, file%path, err)
        if (allocated(err)) exists = .false.
    end subroutine h5_exists

    !> Remove the group or dataset `name` from the file's tree.
    subroutine h5_delete(file, name, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        if (allocated(err)) return
        call h5ldelete_f(file%id, name, e)
        call check(e, 'h5ldelete_f', '/'//name, file%path, err)
    end subroutine h5_delete

    !> Remove attribute `name` of object `obj`.
    subroutine h5_delete_attr(file, obj, name, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: obj, name
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        if (allocated(err)) return
        call h5adelete_by_name_f(file%id, obj, name, e)
        call check(e, 'h5adelete_by_name_f', attr_name(obj, name), file%path, err)
    end subroutine h5_delete_attr

    ! ---- attributes -----------------------------------------------------------------------

    !> "/" for the root, "/params" for 'params'.
    pure function object_name(obj) result(name)
        character(len=*), intent(in) :: obj
        character(len=:), allocatable :: name

        if (obj == '/') then
            name = '/'
        else
            name = '/'//obj
        end if
    end function object_name

    !> An attribute as error messages name it.
    pure function attr_name(obj, name) result(what)
        character(len=*), intent(in) :: obj, name
        character(len=:), allocatable :: what

        what = "attribute '"//name//"' of "//object_name(obj)
    end function attr_name

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
        call h5aexists_by_name_f(file%id, obj, name, exists, e)
        call check(e, 'h5aexists_by_name_f', what, file%path, err)
        if (allocated(err)) return
        if (exists) then
            call h5adelete_by_name_f(file%id, obj, name, e)
            call check(e, 'h5adelete_by_name_f', what, file%path, err)
            if (allocated(err)) return
        end if
        if (size(dims) == 0) then
            call h5screate_f(H5S_SCALAR_F, space, e)
        else
            call h5screate_simple_f(size(dims), dims, space, e)
        end if
        call check(e, 'h5screate_f', what, file%path, err)
        if (allocated(err)) return
        call h5acreate_by_name_f(file%id, obj, name, file_type, space, attr, e)
        call check(e, 'h5acreate_by_name_f', what, file%path, err)
        if (.not. allocated(err)) then
            call h5awrite_f(attr, mem_type, buf, e)
            call check(e, 'h5awrite_f', what, file%path, err)
            call h5aclose_f(attr, e)
            call check(e, 'h5aclose_f', what, file%path, err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', what, file%path, err)
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
        call check(e, 'h5tclose_f', attr_name(obj, name), file%path, err)
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
        call check(e, 'h5tcopy_f', what, file%path, err)
        if (allocated(err)) return
        call h5tset_cset_f(string_type, H5T_CSET_UTF8_F, e)
        call check(e, 'h5tset_cset_f', what, file%path, err)
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
        call h5aopen_by_name_f(file%id, obj, name, attr, e)
        call check(e, 'h5aopen_by_name_f', what, file%path, err)
        if (allocated(err)) return
        call h5aget_space_f(attr, space, e)
        call check(e, 'h5aget_space_f', what, file%path, err)
        if (.not. allocated(err)) then
            call h5sget_simple_extent_npoints_f(space, points, e)
            call check(e, 'h5sget_simple_extent_npoints_f', what, file%path, err)
            if (.not. allocated(err) .and. points /= 1) &
                call set_error(err, "hdf5: "//what//" holds "//fmt_int8(int(points, i8))// &
                               " values, expected one (file "//file%path//")")
            call h5sclose_f(space, e)
            call check(e, 'h5sclose_f', what, file%path, err)
        end if
        if (.not. allocated(err)) then
            target_buf = buf
            call h5aread_f(attr, mem_type, target_buf, e)
            call check(e, 'h5aread_f', what, file%path, err)
        end if
        call h5aclose_f(attr, e)
        call check(e, 'h5aclose_f', what, file%path, err)
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
        call h5ltget_attribute_info_f(file%id, obj, name, dims, type_class, type_size, e)
        call check(e, 'h5ltget_attribute_info_f', what, file%path, err)
        if (allocated(err)) return
        if (type_class /= H5T_STRING_F) then
            call set_error(err, "hdf5: "//what//" is not a string (file "//file%path//")")
            return
        end if
        call attr_is_variable_string(file, obj, name, variable, err)
        if (allocated(err)) return
        if (variable) then
            call read_attr_variable_string(file, obj, name, value, err)
        else
            deallocate (value)
            allocate (character(len=int(type_size)) :: value)
            call h5ltget_attribute_string_f(file%id, obj, name, value, e)
            call check(e, 'h5ltget_attribute_string_f', what, file%path, err)
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
        call h5aopen_by_name_f(file%id, obj, name, attr, e)
        call check(e, 'h5aopen_by_name_f', what, file%path, err)
        if (allocated(err)) return
        call h5aget_type_f(attr, file_type, e)
        call check(e, 'h5aget_type_f', what, file%path, err)
        if (.not. allocated(err)) then
            call h5tis_variable_str_f(file_type, variable, e)
            call check(e, 'h5tis_variable_str_f', what, file%path, err)
            call h5tclose_f(file_type, e)
            call check(e, 'h5tclose_f', what, file%path, err)
        end if
        call h5aclose_f(attr, e)
        call check(e, 'h5aclose_f', what, file%path, err)
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
                call h5aopen_by_name_f(file%id, obj, name, attr, e)
                call check(e, 'h5aopen_by_name_f', what, file%path, err)
                if (.not. allocated(err)) then
                    call h5aget_space_f(attr, space, e)
                    call check(e, 'h5aget_space_f', what, file%path, err)
                    if (.not. allocated(err)) then
                        reclaim = c_loc(pointer) ! (h5dvlen_reclaim_f wants a definable one)
                        call h5dvlen_reclaim_f(string_type, space, H5P_DEFAULT_F, reclaim, e)
                        call check(e, 'h5dvlen_reclaim_f', what, file%path, err)
                        call h5sclose_f(space, e)
                        call check(e, 'h5sclose_f', what, file%path, err)
                    end if
                    call h5aclose_f(attr, e)
                    call check(e, 'h5aclose_f', what, file%path, err)
                end if
            end if
        end if
        call h5tclose_f(string_type, e)
        call check(e, 'h5tclose_f', what, file%path, err)
    end subroutine read_attr_variable_string

    ! ---- whole datasets -------------------------------------------------------------------

    !> The HDF5 types of an element type code: in the file and in memory.
    subroutine types_of(kind, file_type, mem_type)
        integer, intent(in) :: kind
        integer(hid_t), intent(out) :: file_type, mem_type

        select case (kind)
        case (h5_real)
            file_type = H5T_NATIVE_DOUBLE
            mem_type = H5T_NATIVE_DOUBLE
        case (h5_int)
            file_type = H5T_NATIVE_INTEGER
            mem_type = H5T_NATIVE_INTEGER
        case default ! h5_int8
            file_type = H5T_STD_I64LE
            mem_type = h5kind_to_type(i8, H5_INTEGER_KIND)
        end select
    end subroutine types_of

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
            call check(e, 'h5screate_f', '/'//name, file%path, err)
        else
            call h5screate_simple_f(size(dims), dims, space, e)
            call check(e, 'h5screate_simple_f', '/'//name, file%path, err)
        end if
        if (allocated(err)) return
        call creation_properties(file, name, dims, size(dims) > 0 .and. &
                                 product(dims) >= int(compress_min, hsize_t), plist, err)
        if (.not. allocated(err)) then
            call h5dcreate_f(file%id, name, file_type, space, dset, e, dcpl_id=plist)
            call check(e, 'h5dcreate_f', '/'//name, file%path, err)
            if (.not. allocated(err)) then
                call h5dwrite_f(dset, mem_type, buf, e)
                call check(e, 'h5dwrite_f', '/'//name, file%path, err)
                call h5dclose_f(dset, e)
                call check(e, 'h5dclose_f', '/'//name, file%path, err)
            end if
            call h5pclose_f(plist, e)
            call check(e, 'h5pclose_f', '/'//name, file%path, err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', '/'//name, file%path, err)
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
        call check(e, 'h5screate_simple_f', '/'//name, file%path, err)
        if (.not. allocated(err)) then
            call h5dcreate_f(file%id, name, string_type, space, dset, e)
            call check(e, 'h5dcreate_f', '/'//name, file%path, err)
            if (.not. allocated(err)) then
                if (size(values) > 0) then
                    call h5dwrite_f(dset, string_type, c_loc(pointers), e)
                    call check(e, 'h5dwrite_f', '/'//name, file%path, err)
                end if
                call h5dclose_f(dset, e)
                call check(e, 'h5dclose_f', '/'//name, file%path, err)
            end if
            call h5sclose_f(space, e)
            call check(e, 'h5sclose_f', '/'//name, file%path, err)
        end if
        call h5tclose_f(string_type, e)
        call check(e, 'h5tclose_f', '/'//name, file%path, err)
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
        call h5dopen_f(file%id, name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, file%path, err)
        if (allocated(err)) return
        call dataset_dims(file, dset, name, found, err)
        if (.not. allocated(err)) then
            if (.not. same_extent(found, dims)) &
                call set_error(err, "hdf5: /"//name//" has shape "//dims_text(found)// &
                               ", expected "//dims_text(dims)//" (file "//file%path//")")
        end if
        if (.not. allocated(err)) then
            target_buf = buf
            call h5dread_f(dset, mem_type, target_buf, e)
            call check(e, 'h5dread_f', '/'//name, file%path, err)
        end if
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, file%path, err)
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
        call check(e, 'h5dget_space_f', '/'//name, file%path, err)
        if (allocated(err)) return
        call h5sget_simple_extent_ndims_f(space, rank, e)
        call check(e, 'h5sget_simple_extent_ndims_f', '/'//name, file%path, err)
        if (.not. allocated(err)) then
            deallocate (dims)
            allocate (dims(rank), maxdims(rank))
            ! (returns the rank on success)
            call h5sget_simple_extent_dims_f(space, dims, maxdims, e)
            call check(e, 'h5sget_simple_extent_dims_f', '/'//name, file%path, err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', '/'//name, file%path, err)
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
        call h5dopen_f(file%id, name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, file%path, err)
        if (allocated(err)) return
        call dataset_dims(file, dset, name, dims, err)
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, file%path, err)
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
                           ", expected "//trim(axes(rank))//" (file "//file%path//")")
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

    ! ---- chunked datasets and hyperslabs --------------------------------------------------

    !> A chunked dataset of extents `dims` and element type `kind` whose last axis can grow
    !> (or shrink); a chunk holds whole columns, up to chunk_elements.
    subroutine h5_create_growing(file, name, kind, dims, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in) :: kind
        integer(i8), intent(in) :: dims(:)
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: extents(size(dims)), chunk(size(dims)), maxdims(size(dims))
        integer(hsize_t) :: column
        integer :: last

        last = size(dims)
        extents = int(dims, hsize_t)
        chunk = extents
        column = max(1_hsize_t, product(extents(:last - 1)))
        chunk(last) = max(1_hsize_t, min(extents(last), int(chunk_elements, hsize_t)/column))
        maxdims = extents
        maxdims(last) = H5S_UNLIMITED_F
        call create_chunked(file, name, kind, extents, maxdims, chunk, err)
    end subroutine h5_create_growing

    !> An empty 1-D dataset of element type `kind`, in chunks of `chunk` elements, that grows
    !> as values are appended.
    subroutine h5_create_appendable(file, name, kind, chunk, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in) :: kind
        integer(i8), intent(in) :: chunk
        type(error_t), allocatable, intent(inout) :: err

        call create_chunked(file, name, kind, [0_hsize_t], [H5S_UNLIMITED_F], &
                            [int(chunk, hsize_t)], err)
    end subroutine h5_create_appendable

    subroutine create_chunked(file, name, kind, dims, maxdims, chunk, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer, intent(in) :: kind
        integer(hsize_t), intent(in) :: dims(:), maxdims(:), chunk(:)
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: space, dset, plist, file_type, mem_type
        integer :: e

        if (allocated(err)) return
        call types_of(kind, file_type, mem_type)
        call h5screate_simple_f(size(dims), dims, space, e, maxdims=maxdims)
        call check(e, 'h5screate_simple_f', '/'//name, file%path, err)
        if (allocated(err)) return
        call h5pcreate_f(H5P_DATASET_CREATE_F, plist, e)
        call check(e, 'h5pcreate_f', '/'//name, file%path, err)
        if (.not. allocated(err)) then
            call h5pset_chunk_f(plist, size(dims), chunk, e)
            call check(e, 'h5pset_chunk_f', '/'//name, file%path, err)
            call set_filters(file, name, plist, err)
            if (.not. allocated(err)) then
                call h5dcreate_f(file%id, name, file_type, space, dset, e, dcpl_id=plist)
                call check(e, 'h5dcreate_f', '/'//name, file%path, err)
                if (.not. allocated(err)) then
                    call h5dclose_f(dset, e)
                    call check(e, 'h5dclose_f', '/'//name, file%path, err)
                end if
            end if
            call h5pclose_f(plist, e)
            call check(e, 'h5pclose_f', '/'//name, file%path, err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', '/'//name, file%path, err)
    end subroutine create_chunked

    !> Change the extents of a chunked dataset.
    subroutine h5_set_extent(file, name, dims, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(in) :: dims(:)
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: dset
        integer :: e

        if (allocated(err)) return
        call h5dopen_f(file%id, name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, file%path, err)
        if (allocated(err)) return
        call h5dset_extent_f(dset, int(dims, hsize_t), e)
        call check(e, 'h5dset_extent_f', '/'//name, file%path, err)
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, file%path, err)
    end subroutine h5_set_extent

    subroutine write_slab_real_1d(file, name, offset, values, grow, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(in) :: offset(1)
        real(wp), intent(in), target, contiguous :: values(:)
        logical, intent(in) :: grow
        type(error_t), allocatable, intent(inout) :: err

        call transfer_slab(file, name, int(offset, hsize_t), shape(values, hsize_t), h5_real, &
                           c_loc(values), .true., grow, err)
    end subroutine write_slab_real_1d

    subroutine write_slab_real_2d(file, name, offset, values, grow, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(in) :: offset(2)
        real(wp), intent(in), target, contiguous :: values(:, :)
        logical, intent(in) :: grow
        type(error_t), allocatable, intent(inout) :: err

        call transfer_slab(file, name, int(offset, hsize_t), shape(values, hsize_t), h5_real, &
                           c_loc(values), .true., grow, err)
    end subroutine write_slab_real_2d

    subroutine write_slab_real_3d(file, name, offset, values, grow, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(in) :: offset(3)
        real(wp), intent(in), target, contiguous :: values(:, :, :)
        logical, intent(in) :: grow
        type(error_t), allocatable, intent(inout) :: err

        call transfer_slab(file, name, int(offset, hsize_t), shape(values, hsize_t), h5_real, &
                           c_loc(values), .true., grow, err)
    end subroutine write_slab_real_3d

    subroutine write_slab_int_1d(file, name, offset, values, grow, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(in) :: offset(1)
        integer, intent(in), target, contiguous :: values(:)
        logical, intent(in) :: grow
        type(error_t), allocatable, intent(inout) :: err

        call transfer_slab(file, name, int(offset, hsize_t), shape(values, hsize_t), h5_int, &
                           c_loc(values), .true., grow, err)
    end subroutine write_slab_int_1d

    subroutine write_slab_int8_1d(file, name, offset, values, grow, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(in) :: offset(1)
        integer(i8), intent(in), target, contiguous :: values(:)
        logical, intent(in) :: grow
        type(error_t), allocatable, intent(inout) :: err

        call transfer_slab(file, name, int(offset, hsize_t), shape(values, hsize_t), h5_int8, &
                           c_loc(values), .true., grow, err)
    end subroutine write_slab_int8_1d

    subroutine read_slab_real_2d(file, name, offset, values, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(in) :: offset(2)
        real(wp), intent(out), target, contiguous :: values(:, :)
        type(error_t), allocatable, intent(inout) :: err

        values = 0
        call transfer_slab(file, name, int(offset, hsize_t), shape(values, hsize_t), h5_real, &
                           c_loc(values), .false., .false., err)
    end subroutine read_slab_real_2d

    !> Move `buf` (element type `kind`) between memory and the hyperslab offset/block of
    !> dataset `name`: write it (`writing`), first growing the dataset to hold it when
    !> `grow`, or read it.
    subroutine transfer_slab(file, name, offset, block, kind, buf, writing, grow, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(hsize_t), intent(in) :: offset(:), block(:)
        integer, intent(in) :: kind
        type(c_ptr), intent(in) :: buf
        logical, intent(in) :: writing, grow
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: dset, fspace, mspace, file_type, mem_type
        integer :: e
        type(c_ptr) :: target_buf ! (h5dread_f wants a definable pointer)

        if (allocated(err)) return
        call types_of(kind, file_type, mem_type)
        call h5dopen_f(file%id, name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, file%path, err)
        if (allocated(err)) return
        if (grow) then
            call h5dset_extent_f(dset, offset + block, e)
            call check(e, 'h5dset_extent_f', '/'//name, file%path, err)
        end if
        if (.not. allocated(err)) then
            call h5dget_space_f(dset, fspace, e)
            call check(e, 'h5dget_space_f', '/'//name, file%path, err)
            if (.not. allocated(err)) then
                call h5sselect_hyperslab_f(fspace, H5S_SELECT_SET_F, offset, block, e)
                call check(e, 'h5sselect_hyperslab_f', '/'//name, file%path, err)
                if (.not. allocated(err)) then
                    call h5screate_simple_f(size(block), block, mspace, e)
                    call check(e, 'h5screate_simple_f', '/'//name, file%path, err)
                    if (.not. allocated(err)) then
                        if (writing) then
                            call h5dwrite_f(dset, mem_type, buf, e, mem_space_id=mspace, &
                                            file_space_id=fspace)
                            call check(e, 'h5dwrite_f', '/'//name, file%path, err)
                        else
                            target_buf = buf
                            call h5dread_f(dset, mem_type, target_buf, e, &
                                           mem_space_id=mspace, file_space_id=fspace)
                            call check(e, 'h5dread_f', '/'//name, file%path, err)
                        end if
                        call h5sclose_f(mspace, e)
                        call check(e, 'h5sclose_f', '/'//name, file%path, err)
                    end if
                end if
                call h5sclose_f(fspace, e)
                call check(e, 'h5sclose_f', '/'//name, file%path, err)
            end if
        end if
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, file%path, err)
    end subroutine transfer_slab

    ! ---- compression ----------------------------------------------------------------------

    !> Can this HDF5 library write deflate-compressed datasets? (Its deflate filter may be
    !> absent, or able to decode only.)
    logical function h5_compression_available() result(available)
        integer :: e, config

        call h5zfilter_avail_f(H5Z_FILTER_DEFLATE_F, available, e)
        if (e < 0) available = .false.
        if (.not. available) return
        call h5zget_filter_info_f(H5Z_FILTER_DEFLATE_F, config, e)
        available = e >= 0 .and. iand(config, H5Z_FILTER_ENCODE_ENABLED_F) /= 0
    end function h5_compression_available

    !> The shuffle and deflate filters on dataset creation properties `plist` (which set a
    !> chunk shape), when the library can encode deflate.
    subroutine set_filters(file, name, plist, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(hid_t), intent(in) :: plist
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        if (allocated(err) .or. .not. h5_compression_available()) return
        ! byte planes of the reals grouped first: deflate finds their repeated exponents
        call h5pset_shuffle_f(plist, e)
        call check(e, 'h5pset_shuffle_f', '/'//name, file%path, err)
        call h5pset_deflate_f(plist, deflate_level, e)
        call check(e, 'h5pset_deflate_f', '/'//name, file%path, err)
    end subroutine set_filters

    !> Creation properties of a whole dataset of extents `dims`: the default ones, or, when
    !> `compressed`, chunks of up to chunk_elements (whole columns first) with set_filters.
    !> The caller closes `plist`.
    subroutine creation_properties(file, name, dims, compressed, plist, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(hsize_t), intent(in) :: dims(:)
        logical, intent(in) :: compressed
        integer(hid_t), intent(out) :: plist
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: chunk(size(dims))
        integer :: e, axis

        call h5pcreate_f(H5P_DATASET_CREATE_F, plist, e)
        call check(e, 'h5pcreate_f', '/'//name, file%path, err)
        if (allocated(err) .or. .not. compressed) return
        do axis = 1, size(dims)
            chunk(axis) = max(1_hsize_t, min(dims(axis), int(chunk_elements, hsize_t) &
                                             /max(1_hsize_t, product(chunk(:axis - 1)))))
        end do
        call h5pset_chunk_f(plist, size(dims), chunk, e)
        call check(e, 'h5pset_chunk_f', '/'//name, file%path, err)
        call set_filters(file, name, plist, err)
    end subroutine creation_properties

    ! ---- dimensions (HDF5 dimension scales, as netCDF-4 reads them) ------------------------

    !> A dimension of `extent` values without coordinate values: dataset `name` (its last path
    !> component is the dimension's name) made a dimension scale under the NAME netCDF-4
    !> gives such a dimension; no values are written, so it takes no space. A `growing` one
    !> is unlimited (chunked), and follows its datasets with h5_set_extent.
    subroutine h5_create_dimension(file, name, extent, growing, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(i8), intent(in) :: extent
        logical, intent(in) :: growing
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: space, dset, plist
        integer(hsize_t) :: dims(1), maxdims(1)
        integer :: e
        character(len=10) :: length

        if (allocated(err)) return
        dims = int(extent, hsize_t)
        maxdims = dims
        if (growing) maxdims = H5S_UNLIMITED_F
        call h5screate_simple_f(1, dims, space, e, maxdims=maxdims)
        call check(e, 'h5screate_simple_f', '/'//name, file%path, err)
        if (allocated(err)) return
        call h5pcreate_f(H5P_DATASET_CREATE_F, plist, e)
        call check(e, 'h5pcreate_f', '/'//name, file%path, err)
        if (.not. allocated(err)) then
            if (growing) then
                call h5pset_chunk_f(plist, 1, [int(chunk_elements, hsize_t)], e)
                call check(e, 'h5pset_chunk_f', '/'//name, file%path, err)
            end if
            if (.not. allocated(err)) then
                ! (netCDF's type for it: never written, never read)
                call h5dcreate_f(file%id, name, H5T_IEEE_F32BE, space, dset, e, dcpl_id=plist)
                call check(e, 'h5dcreate_f', '/'//name, file%path, err)
                if (.not. allocated(err)) then
                    write (length, '(i10)') extent
                    call h5dsset_scale_f(dset, e, not_a_variable//length)
                    call check(e, 'h5dsset_scale_f', '/'//name, file%path, err)
                    call h5dclose_f(dset, e)
                    call check(e, 'h5dclose_f', '/'//name, file%path, err)
                end if
            end if
            call h5pclose_f(plist, e)
            call check(e, 'h5pclose_f', '/'//name, file%path, err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', '/'//name, file%path, err)
    end subroutine h5_create_dimension

    !> Make the 1-D dataset `name` a coordinate variable: the dimension scale of the dimension
    !> of the same name (its last path component), holding that dimension's coordinates.
    subroutine h5_set_scale(file, name, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: dset
        integer :: e

        if (allocated(err)) return
        call h5dopen_f(file%id, name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, file%path, err)
        if (allocated(err)) return
        call h5dsset_scale_f(dset, e, base_name(name))
        call check(e, 'h5dsset_scale_f', '/'//name, file%path, err)
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, file%path, err)
    end subroutine h5_set_scale

    !> Name the axes of dataset `name`: `dims` lists its dimensions blank-separated in h5py's
    !> order (slowest first, as netCDF's CDL writes x(cycle, oscillator)), each a dimension
    !> scale in the dataset's own group; they are attached to the axes they name.
    subroutine h5_dimensions(file, name, dims, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name, dims
        type(error_t), allocatable, intent(inout) :: err

        call attach_dimensions(file, name, dims, .true., err)
    end subroutine h5_dimensions

    !> Undo h5_dimensions (before the dataset is deleted, so that no dimension scale keeps a
    !> reference to a dataset that is gone).
    subroutine h5_detach_dimensions(file, name, dims, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name, dims
        type(error_t), allocatable, intent(inout) :: err

        call attach_dimensions(file, name, dims, .false., err)
    end subroutine h5_detach_dimensions

    subroutine attach_dimensions(file, name, dims, attach, err)
        type(h5_file_t), intent(in) :: file
        character(len=*), intent(in) :: name, dims
        logical, intent(in) :: attach
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: dset, scale
        integer(hsize_t), allocatable :: extents(:)
        character(len=:), allocatable :: group, scale_name
        integer :: e, axis, first, last

        if (allocated(err)) return
        group = name(:index(name, '/', back=.true.))
        call dataset_extent(file, name, extents, err)
        if (allocated(err)) return
        call h5dopen_f(file%id, name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, file%path, err)
        if (allocated(err)) return
        axis = 0
        last = 0
        do
            first = verify(dims(last + 1:), ' ')
            if (first == 0) exit
            first = last + first
            last = index(dims(first:)//' ', ' ') + first - 2
            axis = axis + 1
            scale_name = group//dims(first:last)
            if (axis > size(extents)) exit
            call h5dopen_f(file%id, scale_name, scale, e)
            call check(e, 'h5dopen_f', '/'//scale_name, file%path, err)
            if (allocated(err)) exit
            ! the index counts axes in C's order (h5py's), from 1: the first one named is 1
            if (attach) then
                call h5dsattach_scale_f(dset, scale, axis, e)
                call check(e, 'h5dsattach_scale_f', '/'//name//' (dimension '// &
                           dims(first:last)//')', file%path, err)
            else
                call h5dsdetach_scale_f(dset, scale, axis, e)
                call check(e, 'h5dsdetach_scale_f', '/'//name//' (dimension '// &
                           dims(first:last)//')', file%path, err)
            end if
            call h5dclose_f(scale, e)
            call check(e, 'h5dclose_f', '/'//scale_name, file%path, err)
            if (allocated(err)) exit
        end do
        if (.not. allocated(err) .and. axis /= size(extents)) &
            call set_error(err, "hdf5: /"//name//" has "//fmt_int8(int(size(extents), i8))// &
                           " axes, named as '"//dims//"' (file "//file%path//")")
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, file%path, err)
    end subroutine attach_dimensions

    !> The last component of an HDF5 path.
    pure function base_name(name) result(base)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: base

        base = name(index(name, '/', back=.true.) + 1:)
    end function base_name

end module chain_hdf5
