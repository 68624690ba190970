!> The HDF5 library behind one small interface (its modules chain_hdf5_base, _attributes,
!> _datasets and _chunks are the only ones with `use hdf5`): files (create,
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
    use chain_hdf5_base, only: h5_file_t, h5_real, h5_int, h5_int8, h5_create_file, &
                               h5_open_file, h5_close_file, h5_is_hdf5_file, h5_create_group, &
                               h5_exists, h5_delete, h5_delete_attr, h5_compression_available, &
                               compress_min, deflate_level
    use chain_hdf5_attributes, only: h5_write_attr, h5_read_attr
    use chain_hdf5_datasets, only: h5_write, h5_read, h5_read_alloc, h5_extent, &
                                   h5_write_strings
    use chain_hdf5_chunks, only: h5_create_growing, h5_create_appendable, h5_set_extent, &
                                 h5_write_slab, h5_read_slab, h5_create_dimension, &
                                 h5_set_scale, h5_dimensions, h5_detach_dimensions
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
end module chain_hdf5
