!> chain_hdf5 round trips, as netCDF-4 readers depend on them: variable-length UTF-8 string
!> attributes (replaced in place), scalar attributes and datasets, datasets large enough to be
!> chunked and compressed read back bit for bit, and dimensions attached by name (a wrong
!> number of names is an error naming the dataset).
module test_hdf5
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_files, only: remove_file
    use chain_hdf5, only: h5_file_t, h5_create_file, h5_open_file, h5_close_file, &
                          h5_create_group, h5_write_attr, h5_read_attr, h5_write, h5_read, &
                          h5_read_alloc, h5_create_dimension, h5_set_scale, h5_dimensions, &
                          compress_min
    use testing, only: tally_t, check
    implicit none
    private
    public :: run_hdf5_tests

    character(len=*), parameter :: path = 'build/test_hdf5_roundtrip.h5'

contains

    subroutine run_hdf5_tests(t)
        type(tally_t), intent(inout) :: t
        type(h5_file_t) :: f
        type(error_t), allocatable :: err, wrong
        character(len=:), allocatable :: text
        character(len=*), parameter :: utf8 = 'd'//achar(195)//achar(169)//'placement'
        real(wp), allocatable :: big(:), back(:)
        real(wp) :: scalar, value
        integer(i8) :: count
        integer :: j, int_value

        big = [(sin(0.1_wp*j)*1.0e3_wp, j=1, int(compress_min) + 7)]
        call h5_create_file(f, path, err)
        call h5_create_group(f, 'g', err)
        call h5_write_attr(f, '/', 'text', 'first', err)
        call h5_write_attr(f, '/', 'text', utf8//' '//repeat('x', 300), err)
        call h5_write_attr(f, 'g', 'n', 7, err)
        call h5_write_attr(f, 'g', 'big', 1000000000000_i8, err)
        call h5_write_attr(f, 'g', 'a', 1.7_wp, err)
        call h5_write(f, 'g/scalar', 0.25_wp, err)
        call h5_write(f, 'g/count', 3, err)
        call h5_write(f, 'g/big', big, err)
        call h5_create_dimension(f, 'g/dim', size(big, kind=i8), .false., err)
        call h5_dimensions(f, 'g/big', 'dim', err)
        call h5_write(f, 'g/axis', [(j, j=1, 4)], err)
        call h5_set_scale(f, 'g/axis', err)
        call check(t, .not. allocated(err), 'hdf5: writing ('//message(err)//')')
        call h5_dimensions(f, 'g/scalar', 'axis', wrong)
        call check(t, allocated(wrong), 'hdf5: a dimension name too many is an error')
        if (allocated(wrong)) call check(t, index(wrong%message, '/g/scalar') > 0, &
                                         'hdf5: the error names the dataset')
        call h5_close_file(f, err)

        call h5_open_file(f, path, writable=.false., err=err)
        call h5_read_attr(f, '/', 'text', text, err)
        call check(t, text == utf8//' '//repeat('x', 300), &
                   'hdf5: a UTF-8 string attribute, replaced, reads back')
        call h5_read_attr(f, 'g', 'big', count, err)
        call check(t, count == 1000000000000_i8, 'hdf5: a 64-bit scalar attribute')
        call h5_read_attr(f, 'g', 'n', count, err)
        call check(t, count == 7, 'hdf5: a default-integer scalar attribute')
        call h5_read_attr(f, 'g', 'a', value, err)
        call check(t, value == 1.7_wp, 'hdf5: a real scalar attribute')
        call h5_read(f, 'g/scalar', scalar, err)
        call check(t, scalar == 0.25_wp, 'hdf5: a scalar dataset')
        call h5_read(f, 'g/count', int_value, err)
        call check(t, int_value == 3, 'hdf5: a scalar integer dataset')
        call h5_read_alloc(f, 'g/big', back, err)
        call check(t, size(back) == size(big), 'hdf5: a compressed dataset keeps its extent')
        if (size(back) == size(big)) call check(t, all(back == big), &
                                                'hdf5: a compressed dataset reads back bitwise')
        call check(t, .not. allocated(err), 'hdf5: reading ('//message(err)//')')
        call h5_close_file(f, err)
        call remove_file(path)
    end subroutine run_hdf5_tests

    function message(err) result(text)
        type(error_t), allocatable, intent(in) :: err
        character(len=:), allocatable :: text

        text = 'no error'
        if (allocated(err)) text = err%message
    end function message

end module test_hdf5
