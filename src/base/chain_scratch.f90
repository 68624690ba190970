!> Records of a fixed number of reals spilled to a scratch file, written in order and read
!> back in any order, so that what a long computation must keep of every step does not stay in
!> memory: the forward pass of covariant Lyapunov vectors keeps its triangular factors and
!> frames here for the backward pass (docs/model.md section 14.3).
!>
!> The file is an unformatted stream scratch file (gfortran puts it in $TMPDIR, else /tmp, and
!> deletes it when it is closed or the program ends). Records go through one buffer of whole
!> records, at most `buffer_bytes` (at least one record): appends fill it and are written to
!> the file as one block; a read loads the block of records that holds the one asked for, so
!> reading backwards costs one file read per block, not per record. The records still in the
!> buffer when reading begins (the last block) are read from there, and written to the file
!> only if another block is asked for: a file whose records fit in one buffer is never
!> written, and one read backwards never reads back the block it wrote last.
!> Infrastructure, no model section of its own.
module chain_scratch
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error
    implicit none
    private
    public :: scratch_records_t, scratch_open, scratch_append, scratch_read, scratch_close
    public :: scratch_block, scratch_next, scratch_find

    !> Most bytes the buffer of a scratch file holds (more only for a single record).
    integer(i8), parameter :: buffer_bytes = 1_i8*1024*1024

    type :: scratch_records_t
        integer :: unit = -1              !! open unit, -1 when closed
        integer :: width = 0              !! reals per record
        integer(i8) :: count = 0          !! records appended
        real(wp), allocatable :: buffer(:, :) !! buffer(width, block): whole records
        integer(i8) :: first = 1          !! the record in buffer(:, 1)
        integer :: held = 0               !! records in the buffer
        logical :: reading = .false.      !! appending is over
        logical :: unwritten = .false.    !! the records in the buffer are not in the file
    end type scratch_records_t

contains

    !> Records per block of a file of records of `width` reals.
    pure integer function scratch_block(width)
        integer, intent(in) :: width

        scratch_block = int(max(1_i8, buffer_bytes/(8_i8*max(1, width))))
    end function scratch_block

    !> An empty scratch file of records of `width` reals.
    subroutine scratch_open(file, width, err)
        type(scratch_records_t), intent(out) :: file
        integer, intent(in) :: width
        type(error_t), allocatable, intent(out) :: err
        character(len=512) :: msg
        integer :: ios

        open (newunit=file%unit, status='scratch', access='stream', form='unformatted', &
              action='readwrite', iostat=ios, iomsg=msg)
        if (ios /= 0) then
            file%unit = -1
            call set_error(err, "scratch file: cannot open one (directory $TMPDIR or /tmp): "// &
                           trim(msg))
            return
        end if
        file%width = width
        allocate (file%buffer(width, scratch_block(width)))
    end subroutine scratch_open

    !> Append one record (`width` reals, of an array of any rank) after the last. Appending
    !> after a read is an error.
    subroutine scratch_append(file, values, err)
        type(scratch_records_t), intent(inout) :: file
        real(wp), intent(in) :: values(file%width)
        type(error_t), allocatable, intent(out) :: err
        integer :: at

        call scratch_next(file, at, err)
        if (allocated(err)) return
        file%buffer(:, at) = values
    end subroutine scratch_append

    !> Record j (1 .. count) into `values` (an array of any rank, `width` reals).
    subroutine scratch_read(file, j, values, err)
        type(scratch_records_t), intent(inout) :: file
        integer(i8), intent(in) :: j
        real(wp), intent(out) :: values(file%width)
        type(error_t), allocatable, intent(out) :: err
        integer :: at

        call scratch_find(file, j, at, err)
        if (allocated(err)) return
        values = file%buffer(:, at)
    end subroutine scratch_read

    ! scratch_next and scratch_find give a record's place in the buffer, to be filled or read
    ! there without a copy, until the next call on the file.

    !> Append one record after the last, to be filled as file%buffer(:, at).
    subroutine scratch_next(file, at, err)
        type(scratch_records_t), intent(inout) :: file
        integer, intent(out) :: at
        type(error_t), allocatable, intent(out) :: err

        at = 0
        if (file%reading) then
            call set_error(err, "scratch file: a record appended after reading began")
            return
        end if
        if (file%held == size(file%buffer, 2)) then
            call write_buffer(file, err)
            if (allocated(err)) return
            file%first = file%first + file%held
            file%held = 0
        end if
        file%held = file%held + 1
        file%count = file%count + 1
        file%unwritten = .true.
        at = file%held
    end subroutine scratch_next

    !> Record j (1 .. count), to be read as file%buffer(:, at).
    subroutine scratch_find(file, j, at, err)
        type(scratch_records_t), intent(inout) :: file
        integer(i8), intent(in) :: j
        integer, intent(out) :: at
        type(error_t), allocatable, intent(out) :: err
        character(len=512) :: msg
        integer(i8) :: block
        integer :: ios

        at = 0
        if (j < 1 .or. j > file%count) then
            call set_error(err, "scratch file: no such record")
            return
        end if
        file%reading = .true.
        if (j < file%first .or. j >= file%first + file%held) then
            ! (the last block, kept since the appends, goes to the file before it is replaced)
            if (file%unwritten) then
                call write_buffer(file, err)
                if (allocated(err)) return
            end if
            block = size(file%buffer, 2)
            file%first = ((j - 1)/block)*block + 1
            file%held = int(min(block, file%count - file%first + 1))
            call read_reals(file%unit, position(file, file%first), file%buffer, &
                            file%width*file%held, ios, msg)
            if (ios /= 0) then
                file%held = 0
                call set_error(err, "scratch file: read failed: "//trim(msg))
                return
            end if
        end if
        at = int(j - file%first) + 1
    end subroutine scratch_find

    !> Close (and so delete) the file; nothing if it is not open.
    subroutine scratch_close(file)
        type(scratch_records_t), intent(inout) :: file
        integer :: ios

        if (file%unit >= 0) close (file%unit, iostat=ios)
        file%unit = -1
        if (allocated(file%buffer)) deallocate (file%buffer)
        file%held = 0
    end subroutine scratch_close

    !> The buffered records to the file, at their place (block-aligned: after those written
    !> before).
    subroutine write_buffer(file, err)
        type(scratch_records_t), intent(inout) :: file
        type(error_t), allocatable, intent(out) :: err
        character(len=512) :: msg
        integer :: ios

        if (file%held == 0) return
        call write_reals(file%unit, position(file, file%first), file%buffer, &
                         file%width*file%held, ios, msg)
        if (ios /= 0) then
            call set_error(err, "scratch file: write failed (disk full?): "//trim(msg))
            return
        end if
        file%unwritten = .false.
    end subroutine write_buffer

    ! The buffer's first m reals as one array, which the runtime library moves in one
    ! transfer: a section of the buffer goes column by column, short columns through a buffer
    ! of gfortran's own (with records of 8 KiB a section's reads took 15 % longer, its
    ! writes twice as long).

    subroutine write_reals(unit, pos, values, m, ios, msg)
        integer, intent(in) :: unit, m
        integer(i8), intent(in) :: pos
        real(wp), intent(in) :: values(m)
        integer, intent(out) :: ios
        character(len=*), intent(inout) :: msg

        write (unit, pos=pos, iostat=ios, iomsg=msg) values
    end subroutine write_reals

    subroutine read_reals(unit, pos, values, m, ios, msg)
        integer, intent(in) :: unit, m
        integer(i8), intent(in) :: pos
        real(wp), intent(out) :: values(m)
        integer, intent(out) :: ios
        character(len=*), intent(inout) :: msg

        read (unit, pos=pos, iostat=ios, iomsg=msg) values
    end subroutine read_reals

    !> The file position (bytes from 1) of record j.
    pure integer(i8) function position(file, j)
        type(scratch_records_t), intent(in) :: file
        integer(i8), intent(in) :: j

        position = (j - 1)*8_i8*file%width + 1
    end function position

end module chain_scratch
