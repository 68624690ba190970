!> Plain files on disk, written safely: a file is written under a temporary name, checked on
!> disk for every byte written (a full disk can go unreported by buffered writes), and only
!> then renamed over its final name (atomic on one file system). Used for the sweep
!> checkpoint and for the copy a stopped run is continued into. Also whether a file can be
!> made in a directory, asked before any run starts.
!> Infrastructure, no model section.
module chain_files
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char
    use, intrinsic :: iso_fortran_env, only: byte => int8
    use chain_kinds, only: i8
    use chain_error, only: error_t, set_error, fmt_int8
    implicit none
    private
    public :: rename_file, remove_file, copy_file, close_checked
    public :: directory_of, is_directory, can_write_in

    integer(c_int), parameter :: f_ok = 0, w_ok = 2, x_ok = 1 !! POSIX access() modes

    interface
        function c_rename(old, new) bind(C, name='rename') result(status)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: old(*), new(*)
            integer(c_int) :: status
        end function c_rename

        function c_access(path, mode) bind(C, name='access') result(status)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int), value :: mode
            integer(c_int) :: status
        end function c_access
    end interface

contains

    !> Move a finished file to its final name (atomic on one file system).
    subroutine rename_file(from, to, err)
        character(len=*), intent(in) :: from, to
        type(error_t), allocatable, intent(out) :: err

        if (c_rename(from//c_null_char, to//c_null_char) /= 0) &
            call set_error(err, "output: cannot rename '"//from//"' to '"//to//"'")
    end subroutine rename_file

    !> The directory a file named `path` is (or would be) in: '.' for a bare name.
    pure function directory_of(path) result(dir)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: dir
        integer :: slash

        slash = index(path, '/', back=.true.)
        if (slash == 0) then
            dir = '.'
        else if (slash == 1) then
            dir = '/'
        else
            dir = path(:slash - 1)
        end if
    end function directory_of

    !> `dir` exists and is a directory (its entry '.' does; a plain file has none).
    logical function is_directory(dir)
        character(len=*), intent(in) :: dir

        is_directory = c_access(dir//'/.'//c_null_char, f_ok) == 0
    end function is_directory

    !> New files can be made in the directory `dir` (write and search permission).
    logical function can_write_in(dir)
        character(len=*), intent(in) :: dir

        can_write_in = c_access(dir//'/.'//c_null_char, ior(w_ok, x_ok)) == 0
    end function can_write_in

    !> Delete a file if it exists.
    subroutine remove_file(path)
        character(len=*), intent(in) :: path
        integer :: u, ios

        open (newunit=u, file=path, status='old', iostat=ios)
        if (ios == 0) close (u, status='delete')
    end subroutine remove_file

    !> Close unit u, just written to `path`, and check that the file on disk holds the
    !> `expected` bytes. `ios` and `msg` come in with the status of the writes and go out
    !> with that of the whole file: nonzero, with `msg` saying why, if a write, the close or
    !> the check failed, and the file is then deleted.
    subroutine close_checked(u, path, expected, ios, msg)
        integer, intent(in) :: u
        character(len=*), intent(in) :: path
        integer(i8), intent(in) :: expected
        integer, intent(inout) :: ios
        character(len=*), intent(inout) :: msg
        integer(i8) :: on_disk

        if (ios == 0) then
            close (u, iostat=ios, iomsg=msg)
        else
            close (u)
        end if
        on_disk = -1
        if (ios == 0) inquire (file=path, size=on_disk, iostat=ios, iomsg=msg)
        if (ios == 0 .and. on_disk /= expected) then
            ios = 1
            msg = fmt_int8(expected)//" bytes written, "//fmt_int8(on_disk)// &
                  " on disk: is the disk full?"
        end if
        if (ios /= 0) call remove_file(path)
    end subroutine close_checked

    !> A byte-for-byte copy of a file (the new one checked for its full size).
    subroutine copy_file(from, to, err)
        character(len=*), intent(in) :: from, to
        type(error_t), allocatable, intent(out) :: err
        integer, parameter :: chunk = 4*1024*1024
        integer(byte), allocatable :: buf(:)
        integer(i8) :: total, done
        character(len=256) :: msg
        integer :: ui, uo, ios, m

        msg = ''
        open (newunit=ui, file=from, access='stream', form='unformatted', status='old', &
              action='read', iostat=ios, iomsg=msg)
        if (ios /= 0) then
            call set_error(err, "output: cannot read '"//from//"' ("//trim(msg)//")")
            return
        end if
        inquire (unit=ui, size=total)
        open (newunit=uo, file=to, access='stream', form='unformatted', status='replace', &
              action='write', iostat=ios, iomsg=msg)
        if (ios /= 0) then
            close (ui)
            call set_error(err, "output: cannot create '"//to//"' ("//trim(msg)//")")
            return
        end if
        allocate (buf(chunk))
        done = 0
        do while (done < total .and. ios == 0)
            m = int(min(int(chunk, i8), total - done))
            read (ui, iostat=ios, iomsg=msg) buf(:m)
            if (ios == 0) write (uo, iostat=ios, iomsg=msg) buf(:m)
            done = done + m
        end do
        close (ui)
        call close_checked(uo, to, total, ios, msg)
        if (ios /= 0) call set_error(err, "output: cannot copy '"//from//"' to '"//to// &
                                     "' ("//trim(msg)//")")
    end subroutine copy_file

end module chain_files
