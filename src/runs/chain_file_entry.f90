!> One entry of the file schema (chain_file_table, whose header says what each field holds)
!> and the one way a table grows, shared by the modules that hold the table's groups.
!> Infrastructure, no model section.
module chain_file_entry
    implicit none
    private
    public :: output_entry_t, add

    type :: output_entry_t
        character(len=:), allocatable :: file, path, kind, dims, dtype, units, model_units, &
                                         long_name, when
    end type output_entry_t

contains

    subroutine add(t, file, path, kind, dims, dtype, units, model_units, long_name, when)
        type(output_entry_t), allocatable, intent(inout) :: t(:)
        character(len=*), intent(in) :: file, path, kind, dims, dtype, units, model_units, &
                                        long_name, when

        t = [t, output_entry_t(file, path, kind, dims, dtype, units, model_units, long_name, &
                               when)]
    end subroutine add

end module chain_file_entry
