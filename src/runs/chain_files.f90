!> Plain files on disk, written safely: a file is written under a temporary name, checked on
!> disk for every byte written (a full disk can go unreported by buffered writes), and only
!> then renamed over its final name (atomic on one file system). Used for the sweep
!> checkpoint and for the copy a stopped run is continued into. Also whether a file can be
!> made in a directory, asked before any run starts.
!> Infrastructure, no model section.
module chain_files
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char, c_size_t, c_long, &
                                           c_ptr, c_associated
    use, intrinsic :: iso_fortran_env, only: byte => int8
    use chain_kinds, only: i8
    use chain_error, only: error_t, set_error, fmt_int8
    implicit none
    private
    public :: rename_file, remove_file, copy_file, close_checked
    public :: directory_of, is_directory, can_write_in, is_symlink, same_file
    public :: lock_file, is_locked, unlock_file, sync_file, sync_directory_of

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

        ! open(2) is variadic; its third argument (the mode) is an int, which the x86-64 and
        ! aarch64 calling conventions pass as they pass a fixed argument
        function c_open(path, flags, mode) bind(C, name='open') result(fd)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int), value :: flags, mode
            integer(c_int) :: fd
        end function c_open

        function c_close(fd) bind(C, name='close') result(status)
            import :: c_int
            integer(c_int), value :: fd
            integer(c_int) :: status
        end function c_close

        function c_flock(fd, operation) bind(C, name='flock') result(status)
            import :: c_int
            integer(c_int), value :: fd, operation
            integer(c_int) :: status
        end function c_flock

        function c_fsync(fd) bind(C, name='fsync') result(status)
            import :: c_int
            integer(c_int), value :: fd
            integer(c_int) :: status
        end function c_fsync

        function c_readlink(path, buf, size) bind(C, name='readlink') result(n)
            import :: c_char, c_size_t, c_long
            character(kind=c_char), intent(in) :: path(*)
            character(kind=c_char), intent(out) :: buf(*)
            integer(c_size_t), value :: size
            integer(c_long) :: n
        end function c_readlink

        function c_realpath(path, resolved) bind(C, name='realpath') result(p)
            import :: c_char, c_ptr
            character(kind=c_char), intent(in) :: path(*)
            character(kind=c_char), intent(out) :: resolved(*)
            type(c_ptr) :: p
        end function c_realpath
    end interface

    !> Linux's open(2) flags (asm-generic/fcntl.h: x86-64, aarch64, riscv) and flock(2)
    !> operations.
    integer(c_int), parameter :: o_rdonly = 0, o_rdwr = 2, o_creat = 64, o_nofollow = 131072, &
                                 o_cloexec = 524288, o_directory = 65536
    integer(c_int), parameter :: lock_ex = 2, lock_nb = 4

contains

    !> Take the exclusive lock that says "a run is writing this file": `path` (created empty
    !> when missing, never truncated, never followed if a symbolic link) is opened and locked
    !> with flock(2); `fd` holds the lock until unlock_file (or the process's end, however it
    !> ends: a killed run leaves no stale lock). Another process holding it is an error that
    !> says so, and nothing is touched.
    subroutine lock_file(path, fd, err)
        character(len=*), intent(in) :: path
        integer, intent(out) :: fd
        type(error_t), allocatable, intent(out) :: err
        integer(c_int) :: f

        fd = -1
        f = c_open(path//c_null_char, ior(ior(o_rdwr, o_creat), ior(o_nofollow, o_cloexec)), &
                   int(o'666', c_int))
        if (f < 0) then
            call set_error(err, "output: cannot create '"//path//"' (missing directory, no "// &
                           "permission to write there, or a symbolic link)")
            return
        end if
        if (c_flock(f, ior(lock_ex, lock_nb)) /= 0) then
            f = c_close(f)
            call set_error(err, "output: another run is writing '"//path//"' (it holds "// &
                           "the file's lock); wait for it to end, or choose another file")
            return
        end if
        fd = f
    end subroutine lock_file

    !> Does another process hold lock_file's lock on the existing file `path`? (Asked without
    !> creating anything; a file that cannot be opened is not locked.)
    logical function is_locked(path)
        character(len=*), intent(in) :: path
        integer(c_int) :: f, status

        is_locked = .false.
        f = c_open(path//c_null_char, ior(o_rdonly, ior(o_nofollow, o_cloexec)), 0_c_int)
        if (f < 0) return
        is_locked = c_flock(f, ior(lock_ex, lock_nb)) /= 0
        status = c_close(f) ! (closing drops a lock just taken)
    end function is_locked

    !> Release lock_file's lock (fd < 0: none held).
    subroutine unlock_file(fd)
        integer, intent(inout) :: fd
        integer(c_int) :: status

        if (fd >= 0) status = c_close(int(fd, c_int))
        fd = -1
    end subroutine unlock_file

    !> `path` is a symbolic link (dangling or not).
    logical function is_symlink(path)
        character(len=*), intent(in) :: path
        character(kind=c_char) :: buf(1)

        is_symlink = c_readlink(path//c_null_char, buf, 1_c_size_t) >= 0
    end function is_symlink

    !> Are `a` and `b` names of one existing file (after links, `.` and `..`)?
    logical function same_file(a, b)
        character(len=*), intent(in) :: a, b
        integer, parameter :: path_max = 4096
        character(kind=c_char) :: ra(path_max), rb(path_max)

        same_file = .false.
        if (.not. c_associated(c_realpath(a//c_null_char, ra))) return
        if (.not. c_associated(c_realpath(b//c_null_char, rb))) return
        if (text_length(ra) /= text_length(rb)) return
        same_file = all(ra(:text_length(ra)) == rb(:text_length(rb)))
    contains
        pure integer function text_length(c)
            character(kind=c_char), intent(in) :: c(:)
            text_length = findloc(c, c_null_char, 1) - 1
        end function text_length
    end function same_file

    !> Flush the file `path` to the disk (fsync(2)); false if it cannot be done.
    logical function sync_file(path)
        character(len=*), intent(in) :: path
        integer(c_int) :: f, status

        sync_file = .false.
        f = c_open(path//c_null_char, ior(o_rdonly, o_cloexec), 0_c_int)
        if (f < 0) return
        sync_file = c_fsync(f) == 0
        status = c_close(f)
    end function sync_file

    !> Flush the directory holding `path` (its entries: a rename into it) to the disk.
    logical function sync_directory_of(path)
        character(len=*), intent(in) :: path
        integer(c_int) :: f, status

        sync_directory_of = .false.
        f = c_open(directory_of(path)//c_null_char, ior(ior(o_rdonly, o_directory), &
                   o_cloexec), 0_c_int)
        if (f < 0) return
        sync_directory_of = c_fsync(f) == 0
        status = c_close(f)
    end function sync_directory_of

    !> Move a finished file to its final name (atomic on one file system), durably: the file
    !> is on the disk before it takes the name (fsync), and the name after (fsync of its
    !> directory), so that a power cut or a crash of the machine cannot leave a finished name
    !> on a file whose contents were never written.
    subroutine rename_file(from, to, err)
        character(len=*), intent(in) :: from, to
        type(error_t), allocatable, intent(out) :: err

        if (.not. sync_file(from)) then
            call set_error(err, "output: cannot flush '"//from//"' to the disk")
        else if (c_rename(from//c_null_char, to//c_null_char) /= 0) then
            call set_error(err, "output: cannot rename '"//from//"' to '"//to//"'")
        else if (.not. sync_directory_of(to)) then
            call set_error(err, "output: cannot flush the directory of '"//to//"' to the disk")
        end if
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
