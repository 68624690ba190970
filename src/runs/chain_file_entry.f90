!> One entry of the file schema (chain_file_table, whose header says what each field holds)
!> and the one way a table grows, shared by the modules that hold the table's groups.
!> Infrastructure, no model section.
module chain_file_entry
    implicit none
    private
    public :: output_entry_t, entry_list_t, add, entries_of

    type :: output_entry_t
        character(len=:), allocatable :: file, path, kind, dims, dtype, units, model_units, &
                                         long_name, when
    end type output_entry_t

    !> A table while it grows: room doubled when full, so that building a table of n entries
    !> moves each entry a few times, not n times (the table is built afresh for every lookup,
    !> dozens per file written).
    type :: entry_list_t
        type(output_entry_t), allocatable :: entries(:)
        integer :: count = 0
    end type entry_list_t

contains

    subroutine add(t, file, path, kind, dims, dtype, units, model_units, long_name, when)
        type(entry_list_t), intent(inout) :: t
        character(len=*), intent(in) :: file, path, kind, dims, dtype, units, model_units, &
                                        long_name, when
        type(output_entry_t), allocatable :: room(:)

        if (.not. allocated(t%entries)) allocate (t%entries(256))
        if (t%count == size(t%entries)) then
            allocate (room(2*t%count))
            room(1:t%count) = t%entries
            call move_alloc(room, t%entries)
        end if
        t%count = t%count + 1
        t%entries(t%count) = output_entry_t(file, path, kind, dims, dtype, units, model_units, &
                                            long_name, when)
    end subroutine add

    !> The entries added, in order.
    function entries_of(t) result(entries)
        type(entry_list_t), intent(in) :: t
        type(output_entry_t), allocatable :: entries(:)

        allocate (entries(t%count))
        if (t%count > 0) entries = t%entries(1:t%count)
    end function entries_of

end module chain_file_entry
