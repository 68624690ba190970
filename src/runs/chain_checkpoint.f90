!> The checkpoint of a long run (sweep, census): the work done so far in `file.h5.ckpt`, from
!> which the same input resumes, with any driver (threads or MPI ranks). Infrastructure of
!> docs/model.md sections 8 and 13, no physics.
!>
!> One file layout, stream access: the kind's magic (8 characters; it changes with the kind's
!> layout), the length of the input text and the text, then the kind's own header (its sizes)
!> and payload (values as they are, so bit for bit). It is written under `.tmp`, checked on disk
!> for every byte, flushed (fsync) and renamed over the previous checkpoint (chain_files), so a
!> failed write is an error and leaves the previous one as it was. A third kind of run writes
!> with checkpoint_create, its own `write (ck%unit, iostat=ck%ios, iomsg=ck%msg)` statements
!> and checkpoint_commit; it reads with checkpoint_open, its reads into ck%ios, checkpoint_refuse
!> when its header is not its own and checkpoint_close.
module chain_checkpoint
    use chain_kinds, only: i8
    use chain_error, only: error_t, set_error
    use chain_config, only: config_t
    use chain_files, only: rename_file, close_checked
    implicit none
    private
    public :: checkpoint_t, checkpoint_path, checkpoint_create, checkpoint_commit
    public :: checkpoint_open, checkpoint_refuse, checkpoint_close

    !> A checkpoint being written or read.
    type :: checkpoint_t
        integer :: unit = -1
        integer :: ios = 0                       !! status of the writes or reads so far
        character(len=256) :: msg = ''           !! why, when ios /= 0 (writes)
        character(len=:), allocatable :: path    !! of the checkpoint (written as path.tmp)
        character(len=:), allocatable :: group   !! the input group its messages name
    end type checkpoint_t

contains

    !> The checkpoint of the run writing cfg%output_file (the same for every driver, so that
    !> any of them resumes any other's).
    pure function checkpoint_path(cfg) result(path)
        type(config_t), intent(in) :: cfg
        character(len=:), allocatable :: path

        path = cfg%output_file//'.ckpt'
    end function checkpoint_path

    !> Start writing the checkpoint `path` of the input `text` (group: '&sweep', ...): its
    !> temporary file, the magic and the text.
    subroutine checkpoint_create(ck, path, group, magic, text, err)
        type(checkpoint_t), intent(out) :: ck
        character(len=*), intent(in) :: path, group, magic, text
        type(error_t), allocatable, intent(out) :: err

        ck%path = path
        ck%group = group
        open (newunit=ck%unit, file=path//'.tmp', access='stream', form='unformatted', &
              status='replace', action='write', iostat=ck%ios, iomsg=ck%msg)
        if (ck%ios /= 0) then
            call cannot_write(ck, err)
            return
        end if
        write (ck%unit, iostat=ck%ios, iomsg=ck%msg) magic, len(text), text
    end subroutine checkpoint_create

    !> Finish writing: every byte on disk (a full disk can go unreported by buffered writes),
    !> then the temporary file flushed and renamed over the previous checkpoint.
    subroutine checkpoint_commit(ck, err)
        type(checkpoint_t), intent(inout) :: ck
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: written

        written = 0
        if (ck%ios == 0) inquire (unit=ck%unit, pos=written, iostat=ck%ios, iomsg=ck%msg)
        call close_checked(ck%unit, ck%path//'.tmp', written - 1, ck%ios, ck%msg)
        if (ck%ios /= 0) then
            call cannot_write(ck, err)
            return
        end if
        call rename_file(ck%path//'.tmp', ck%path, err)
    end subroutine checkpoint_commit

    subroutine cannot_write(ck, err)
        type(checkpoint_t), intent(in) :: ck
        type(error_t), allocatable, intent(out) :: err

        call set_error(err, ck%group//": cannot write the checkpoint '"//ck%path//".tmp' ("// &
                       trim(ck%msg)//")")
    end subroutine cannot_write

    !> Open the checkpoint `path` for reading, if there is one that can be read (`found`),
    !> past its magic and input text; one of another magic or another text is an error
    !> (checkpoint_refuse). The kind's header and payload follow.
    subroutine checkpoint_open(ck, path, group, magic, text, found, err)
        type(checkpoint_t), intent(out) :: ck
        character(len=*), intent(in) :: path, group, magic, text
        logical, intent(out) :: found
        type(error_t), allocatable, intent(out) :: err
        character(len=len(magic)) :: got
        character(len=:), allocatable :: got_text
        integer :: length

        ck%path = path
        ck%group = group
        inquire (file=path, exist=found)
        if (.not. found) return
        open (newunit=ck%unit, file=path, access='stream', form='unformatted', status='old', &
              action='read', iostat=ck%ios)
        found = ck%ios == 0
        if (.not. found) return
        read (ck%unit, iostat=ck%ios) got, length
        if (ck%ios == 0 .and. got == magic .and. length == len(text)) then
            allocate (character(len=length) :: got_text)
            read (ck%unit, iostat=ck%ios) got_text
            if (ck%ios == 0 .and. got_text == text) return
        end if
        call checkpoint_refuse(ck, err)
    end subroutine checkpoint_open

    !> The checkpoint is another input's (or another version's): closed, and an error.
    subroutine checkpoint_refuse(ck, err)
        type(checkpoint_t), intent(inout) :: ck
        type(error_t), allocatable, intent(out) :: err

        close (ck%unit)
        call set_error(err, ck%group//": '"//ck%path//"' is a checkpoint of another input "// &
                       "(or of another version); remove it to start afresh")
    end subroutine checkpoint_refuse

    !> Done reading: closed, and an error if a read failed.
    subroutine checkpoint_close(ck, err)
        type(checkpoint_t), intent(inout) :: ck
        type(error_t), allocatable, intent(out) :: err

        close (ck%unit)
        if (ck%ios /= 0) call set_error(err, ck%group//": the checkpoint '"//ck%path// &
                                        "' is damaged; remove it to start afresh")
    end subroutine checkpoint_close

end module chain_checkpoint
