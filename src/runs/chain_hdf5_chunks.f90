!> Chunked datasets that grow or shrink along their last axis, hyperslab transfers, and the
!> dimensions netCDF-4 reads: HDF5 dimension scales (chain_hdf5 gathers the interface).
!> Infrastructure, no model section.
module chain_hdf5_chunks
    use, intrinsic :: iso_c_binding, only: c_ptr, c_loc
    use hdf5, only: hid_t, hsize_t, h5screate_simple_f, h5sclose_f, h5sselect_hyperslab_f, &
                    H5S_UNLIMITED_F, H5S_SELECT_SET_F, h5dcreate_f, h5dopen_f, h5dclose_f, &
                    h5dwrite_f, h5dread_f, h5dset_extent_f, h5dget_space_f, h5pcreate_f, &
                    h5pset_chunk_f, h5pclose_f, H5P_DATASET_CREATE_F, H5T_IEEE_F32BE
    use h5ds, only: h5dsset_scale_f, h5dsattach_scale_f, h5dsdetach_scale_f
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int8
    use chain_hdf5_base, only: check, types_of, set_filters, h5_id, h5_path, h5_file_t, h5_real, &
                               h5_int, h5_int8, chunk_elements, not_a_variable
    use chain_hdf5_datasets, only: dataset_extent
    implicit none
    private
    public :: h5_create_growing, h5_create_appendable, create_chunked, h5_set_extent
    public :: write_slab_real_1d, write_slab_real_2d, write_slab_real_3d, write_slab_int_1d
    public :: write_slab_int8_1d, read_slab_real_2d, transfer_slab, h5_create_dimension
    public :: h5_set_scale, h5_dimensions, h5_detach_dimensions, attach_dimensions, base_name
    public :: h5_write_slab, h5_read_slab

    !> `values` written at `offset` into a dataset, first grown to hold them when `grow`.
    interface h5_write_slab
        module procedure write_slab_real_1d, write_slab_real_2d, write_slab_real_3d, &
            write_slab_int_1d, write_slab_int8_1d
    end interface h5_write_slab

    !> `values` read from a dataset at `offset`.
    interface h5_read_slab
        module procedure read_slab_real_2d
    end interface h5_read_slab
contains

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
        call check(e, 'h5screate_simple_f', '/'//name, h5_path(file), err)
        if (allocated(err)) return
        call h5pcreate_f(H5P_DATASET_CREATE_F, plist, e)
        call check(e, 'h5pcreate_f', '/'//name, h5_path(file), err)
        if (.not. allocated(err)) then
            call h5pset_chunk_f(plist, size(dims), chunk, e)
            call check(e, 'h5pset_chunk_f', '/'//name, h5_path(file), err)
            call set_filters(file, name, plist, err)
            if (.not. allocated(err)) then
                call h5dcreate_f(h5_id(file), name, file_type, space, dset, e, dcpl_id=plist)
                call check(e, 'h5dcreate_f', '/'//name, h5_path(file), err)
                if (.not. allocated(err)) then
                    call h5dclose_f(dset, e)
                    call check(e, 'h5dclose_f', '/'//name, h5_path(file), err)
                end if
            end if
            call h5pclose_f(plist, e)
            call check(e, 'h5pclose_f', '/'//name, h5_path(file), err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', '/'//name, h5_path(file), err)
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
        call h5dopen_f(h5_id(file), name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, h5_path(file), err)
        if (allocated(err)) return
        call h5dset_extent_f(dset, int(dims, hsize_t), e)
        call check(e, 'h5dset_extent_f', '/'//name, h5_path(file), err)
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, h5_path(file), err)
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
        call h5dopen_f(h5_id(file), name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, h5_path(file), err)
        if (allocated(err)) return
        if (grow) then
            call h5dset_extent_f(dset, offset + block, e)
            call check(e, 'h5dset_extent_f', '/'//name, h5_path(file), err)
        end if
        if (.not. allocated(err)) then
            call h5dget_space_f(dset, fspace, e)
            call check(e, 'h5dget_space_f', '/'//name, h5_path(file), err)
            if (.not. allocated(err)) then
                call h5sselect_hyperslab_f(fspace, H5S_SELECT_SET_F, offset, block, e)
                call check(e, 'h5sselect_hyperslab_f', '/'//name, h5_path(file), err)
                if (.not. allocated(err)) then
                    call h5screate_simple_f(size(block), block, mspace, e)
                    call check(e, 'h5screate_simple_f', '/'//name, h5_path(file), err)
                    if (.not. allocated(err)) then
                        if (writing) then
                            call h5dwrite_f(dset, mem_type, buf, e, mem_space_id=mspace, &
                                            file_space_id=fspace)
                            call check(e, 'h5dwrite_f', '/'//name, h5_path(file), err)
                        else
                            target_buf = buf
                            call h5dread_f(dset, mem_type, target_buf, e, &
                                           mem_space_id=mspace, file_space_id=fspace)
                            call check(e, 'h5dread_f', '/'//name, h5_path(file), err)
                        end if
                        call h5sclose_f(mspace, e)
                        call check(e, 'h5sclose_f', '/'//name, h5_path(file), err)
                    end if
                end if
                call h5sclose_f(fspace, e)
                call check(e, 'h5sclose_f', '/'//name, h5_path(file), err)
            end if
        end if
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, h5_path(file), err)
    end subroutine transfer_slab

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
        call check(e, 'h5screate_simple_f', '/'//name, h5_path(file), err)
        if (allocated(err)) return
        call h5pcreate_f(H5P_DATASET_CREATE_F, plist, e)
        call check(e, 'h5pcreate_f', '/'//name, h5_path(file), err)
        if (.not. allocated(err)) then
            if (growing) then
                call h5pset_chunk_f(plist, 1, [int(chunk_elements, hsize_t)], e)
                call check(e, 'h5pset_chunk_f', '/'//name, h5_path(file), err)
            end if
            if (.not. allocated(err)) then
                ! (netCDF's type for it: never written, never read)
                call h5dcreate_f(h5_id(file), name, H5T_IEEE_F32BE, space, dset, e, dcpl_id=plist)
                call check(e, 'h5dcreate_f', '/'//name, h5_path(file), err)
                if (.not. allocated(err)) then
                    write (length, '(i10)') extent
                    call h5dsset_scale_f(dset, e, not_a_variable//length)
                    call check(e, 'h5dsset_scale_f', '/'//name, h5_path(file), err)
                    call h5dclose_f(dset, e)
                    call check(e, 'h5dclose_f', '/'//name, h5_path(file), err)
                end if
            end if
            call h5pclose_f(plist, e)
            call check(e, 'h5pclose_f', '/'//name, h5_path(file), err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', '/'//name, h5_path(file), err)
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
        call h5dopen_f(h5_id(file), name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, h5_path(file), err)
        if (allocated(err)) return
        call h5dsset_scale_f(dset, e, base_name(name))
        call check(e, 'h5dsset_scale_f', '/'//name, h5_path(file), err)
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, h5_path(file), err)
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
        call h5dopen_f(h5_id(file), name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, h5_path(file), err)
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
            call h5dopen_f(h5_id(file), scale_name, scale, e)
            call check(e, 'h5dopen_f', '/'//scale_name, h5_path(file), err)
            if (allocated(err)) exit
            ! the index counts axes in C's order (h5py's), from 1: the first one named is 1
            if (attach) then
                call h5dsattach_scale_f(dset, scale, axis, e)
                call check(e, 'h5dsattach_scale_f', '/'//name//' (dimension '// &
                           dims(first:last)//')', h5_path(file), err)
            else
                call h5dsdetach_scale_f(dset, scale, axis, e)
                call check(e, 'h5dsdetach_scale_f', '/'//name//' (dimension '// &
                           dims(first:last)//')', h5_path(file), err)
            end if
            call h5dclose_f(scale, e)
            call check(e, 'h5dclose_f', '/'//scale_name, h5_path(file), err)
            if (allocated(err)) exit
        end do
        if (.not. allocated(err) .and. axis /= size(extents)) &
            call set_error(err, "hdf5: /"//name//" has "//fmt_int8(int(size(extents), i8))// &
                           " axes, named as '"//dims//"' (file "//h5_path(file)//")")
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, h5_path(file), err)
    end subroutine attach_dimensions

    !> The last component of an HDF5 path.
    pure function base_name(name) result(base)
        character(len=*), intent(in) :: name
        character(len=:), allocatable :: base

        base = name(index(name, '/', back=.true.) + 1:)
    end function base_name

end module chain_hdf5_chunks
