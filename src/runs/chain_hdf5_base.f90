!> The HDF5 library behind one funnel (chain_hdf5 gathers the interface): the file type, the
!> status check every HDF5 call goes through, files (create, open, close), groups and links,
!> element types and compression. Only the chain_hdf5 modules use it and `use hdf5`.
!> Infrastructure, no model section.
module chain_hdf5_base
    use, intrinsic :: iso_c_binding, only: c_int, c_bool
    use hdf5, only: hid_t, hsize_t, h5open_f, h5eset_auto_f, h5fcreate_f, h5fopen_f, h5fclose_f, &
                    h5fis_hdf5_f, H5F_ACC_TRUNC_F, H5F_ACC_RDWR_F, H5F_ACC_RDONLY_F, h5lexists_f, &
                    h5ldelete_f, h5gcreate_f, h5gclose_f, h5pcreate_f, h5pset_chunk_f, h5pclose_f, &
                    H5P_DATASET_CREATE_F, H5P_FILE_ACCESS_F, h5pset_shuffle_f, h5pset_deflate_f, &
                    h5zfilter_avail_f, h5zget_filter_info_f, H5Z_FILTER_DEFLATE_F, &
                    H5Z_FILTER_ENCODE_ENABLED_F, h5adelete_by_name_f, H5T_NATIVE_DOUBLE, &
                    H5T_NATIVE_INTEGER, H5T_STD_I64LE, h5kind_to_type, H5_INTEGER_KIND
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error
    implicit none
    private
    public :: h5_file_t, h5_real, h5_int, h5_int8, compress_min, deflate_level, chunk_elements
    public :: not_a_variable, check, open_library, h5_create_file, unlocked_access, h5_open_file
    public :: h5_close_file, h5_is_hdf5_file, h5_create_group, h5_exists, h5_delete
    public :: h5_delete_attr, types_of, h5_compression_available, set_filters, creation_properties
    public :: h5_id, h5_path, object_name, attr_name

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

    !> The HDF5 id of `file` (for the other chain_hdf5 modules).
    pure integer(hid_t) function h5_id(file)
        type(h5_file_t), intent(in) :: file
        h5_id = file%id
    end function h5_id

    !> The name of `file` in messages.
    pure function h5_path(file) result(path)
        type(h5_file_t), intent(in) :: file
        character(len=:), allocatable :: path
        path = file%path
    end function h5_path

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

end module chain_hdf5_base
