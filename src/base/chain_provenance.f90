!> Where a result was made: the code's version, the compiler and its flags, the BLAS with its
!> version and the kernels it selected on this CPU, and the CPU's model (docs/performance.md, "Which BLAS"
!> and "Output"). One table, `provenance()`: every output file carries it as root attributes
!> (chain_output's output_begin, which every writer calls), `impactchain --version` and the MPI
!> driver's print it, the bench prints it above its table and the Python package returns it
!> (`impactchain.api.provenance()`), so the four always agree.
!>
!> The BLAS and the CPU are asked at run time (src/base/chain_blas_runtime.c): the same executable
!> may run on another machine, where the BLAS selects other kernels and results that go
!> through it (Lyapunov exponents, continuation) change in their last bits.
!> Infrastructure, no model section.
module chain_provenance
    use, intrinsic :: iso_c_binding, only: c_char, c_size_t, c_null_char
    use, intrinsic :: iso_fortran_env, only: compiler_version, compiler_options
    implicit none
    private
    public :: code_version, provenance_item_t, provenance, provenance_text

    character(len=*), parameter :: code_version = '0.1.0'

    !> One fact: its root attribute's name, what it is, its value on this run.
    type :: provenance_item_t
        character(len=:), allocatable :: key
        character(len=:), allocatable :: long_name
        character(len=:), allocatable :: value
    end type provenance_item_t

    !> Room for the C side's answers (OpenBLAS's configuration line is under 100 characters).
    integer, parameter :: text_size = 512

    interface
        subroutine blas_describe(blas, blas_size, kernel, kernel_size) &
            bind(c, name='impactchain_blas_describe')
            import :: c_char, c_size_t
            implicit none
            character(kind=c_char), intent(out) :: blas(*), kernel(*)
            integer(c_size_t), value :: blas_size, kernel_size
        end subroutine blas_describe
        subroutine cpu_model(model, model_size) bind(c, name='impactchain_cpu_model')
            import :: c_char, c_size_t
            implicit none
            character(kind=c_char), intent(out) :: model(*)
            integer(c_size_t), value :: model_size
        end subroutine cpu_model
    end interface

contains

    !> The provenance of a result made now, in this process: the table every output file,
    !> --version, the bench and the Python package show.
    function provenance() result(items)
        type(provenance_item_t) :: items(6)
        character(kind=c_char) :: blas(text_size), kernel(text_size), model(text_size)

        call blas_describe(blas, int(text_size, c_size_t), kernel, int(text_size, c_size_t))
        call cpu_model(model, int(text_size, c_size_t))
        ! (item by item: gfortran 12 fails on structure constructors of these components)
        call set(items(1), 'code_version', 'impactchain version', code_version)
        call set(items(2), 'compiler', 'Fortran compiler', compiler_version())
        call set(items(3), 'compiler_options', 'its options for the library', compiler_options())
        call set(items(4), 'blas', 'BLAS and LAPACK: name, version, build', c_text(blas))
        call set(items(5), 'blas_kernel', 'the kernels the BLAS selected on this CPU', &
                 c_text(kernel))
        call set(items(6), 'cpu_model', 'CPU model (/proc/cpuinfo)', c_text(model))
    end function provenance

    !> The table as text, one `key: value` line per fact (what --version prints).
    function provenance_text() result(text)
        character(len=:), allocatable :: text
        type(provenance_item_t), allocatable :: items(:)
        integer :: i

        items = provenance()
        text = ''
        do i = 1, size(items)
            text = text//items(i)%key//': '//items(i)%value//new_line('a')
        end do
    end function provenance_text

    subroutine set(item, key, long_name, value)
        type(provenance_item_t), intent(out) :: item
        character(len=*), intent(in) :: key, long_name, value

        item%key = key
        item%long_name = long_name
        item%value = value
    end subroutine set

    !> A NUL-terminated C string as Fortran text, blanks at either end removed.
    function c_text(chars) result(text)
        character(kind=c_char), intent(in) :: chars(:)
        character(len=:), allocatable :: text
        integer :: i

        text = ''
        do i = 1, size(chars)
            if (chars(i) == c_null_char) exit
            text = text//chars(i)
        end do
        text = trim(adjustl(text))
    end function c_text
end module chain_provenance
