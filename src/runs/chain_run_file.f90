!> A run's file from its start to its end (docs/output.md): the checks before it is created,
!> the `.part` file and its lock, the header every kind of file begins with (root
!> attributes, /params, /initial), the records as the run goes (/strobe, /events), /final,
!> /stats, and the rename when it ends. The names, units and long names of what it writes are
!> the file schema's (chain_describe); the spectra are chain_run_file_spectra's, a run stopped
!> early and reading a file back chain_run_file_resume's; chain_output gathers them.
!>
!> A run writes to `name.h5.part` and renames it to `name.h5` when it ends, so a file under the
!> final name is never one whose writing was cut off. Strobe records and events go to disk in
!> chunks as the run proceeds, so memory does not grow with its length. Fortran arrays x(n, m)
!> appear in h5py as (m, n).
!>
!> Schema version 2 is netCDF-4 readable: every group holds the dimensions of its datasets
!> (`oscillator`, `bond`, `cycle`, `event`, ...), as coordinate variables (an index or the
!> record's drive cycle) or as bare dimensions; every dataset has `long_name`, `units` in
!> UDUNITS' syntax (`1` for the model's reduced units, docs/model.md section 1.5) and, for
!> those, `model_units` naming the reduced unit; coded integers have `flag_values` and
!> `flag_meanings`.
!>
!> Errors come up from chain_hdf5 as "hdf5: <call> failed on <object> (file <path>)"; where a
!> procedure here knows which input a file belongs to, it says so in front ("&output: ...",
!> "&initial: ..."). The chain_hdf5 calls of a procedure follow one another untested: each
!> does nothing after a failure, so the first one is the error returned.
!> Infrastructure, no model section: it writes the records of docs/model.md sections 6-7.
module chain_run_file
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error
    use chain_files, only: lock_file, is_locked, unlock_file, is_symlink
    use chain_files, only: rename_file, remove_file, directory_of, is_directory, can_write_in
    use chain_state, only: chain_state_t
    use chain_describe, only: describe, index_coordinate, bare_dimension, flags
    use chain_provenance, only: code_version, provenance_item_t, provenance
    use chain_hdf5, only: h5_file_t, h5_real, h5_int, h5_int8, h5_create_file, &
                          h5_close_file, h5_create_group, h5_exists, h5_delete, &
                          h5_write_attr, h5_write, h5_create_growing, h5_create_appendable, &
                          h5_set_extent, h5_write_slab, h5_set_scale, h5_delete_attr
    implicit none
    private
    public :: output_t, output_check, output_begin, output_header, output_strobe_write
    public :: output_events_append, output_final, output_stats, output_periods
    public :: output_end, output_abort, output_group, output_unset_param
    public :: schema_version, code_version, output_truncate_strobe
    !> (for the other parts of a run's file)
    public :: check_part, set_strobe_records, oscillator_coordinate

    integer, parameter :: schema_version = 2
    !> Events per chunk of the /events datasets.
    integer(i8), parameter :: event_chunk = 65536

    !> A run's file being written: `file` is the `.part` file until output_end renames it.
    type :: output_t
        type(h5_file_t) :: file
        character(len=:), allocatable :: path, part_path
        integer :: n = 0
        integer(i8) :: n_events = 0
        logical :: events_created = .false.
        logical :: clv_created = .false.   !! /clv's per-record datasets exist
        integer :: lock = -1 !! the descriptor holding the `.part` file's lock (lock_file)
    end type output_t

contains

    !> What output_begin refuses, checked without creating anything (so that `--check` can
    !> ask it too): a `.part` file that another run is writing, a directory of the output's
    !> name, an existing file (unless overwrite), a directory that is missing or that cannot
    !> be written to.
    subroutine output_check(path, overwrite, err)
        character(len=*), intent(in) :: path
        logical, intent(in) :: overwrite
        type(error_t), allocatable, intent(out) :: err

        call check_part(path//'.part', err)
        if (.not. allocated(err)) call check_place(path, overwrite, err)
    end subroutine output_check

    !> output_check but for the `.part` file.
    subroutine check_place(path, overwrite, err)
        character(len=*), intent(in) :: path
        logical, intent(in) :: overwrite
        type(error_t), allocatable, intent(out) :: err
        character(len=:), allocatable :: dir
        logical :: exists

        if (is_directory(path)) then
            call set_error(err, "&output: file = '"//path//"' is a directory; give the name "// &
                           "of a file (overwrite never replaces a directory)")
            return
        end if
        inquire (file=path, exist=exists)
        exists = exists .or. is_symlink(path) ! (a dangling link is the user's too)
        if (exists .and. .not. overwrite) then
            call set_error(err, "&output: file = '"//path//"' exists; choose another name "// &
                           "or set overwrite = .true.")
            return
        end if
        dir = directory_of(path)
        if (.not. is_directory(dir)) then
            call set_error(err, "&output: cannot create '"//path//"': the directory '"//dir// &
                           "' does not exist")
        else if (.not. can_write_in(dir)) then
            call set_error(err, "&output: cannot create '"//path//"': no permission to "// &
                           "write in the directory '"//dir//"'")
        end if
    end subroutine check_place

    !> The `.part` file a run would write: refused when another run is writing it (it holds
    !> its lock), or when it is not one of ours (a directory, a symbolic link, or a file that
    !> is neither empty nor HDF5: a user's own file, which is never replaced). A `.part` left
    !> by a run that was killed (HDF5, or not yet begun) is replaced.
    subroutine check_part(part, err)
        character(len=*), intent(in) :: part
        type(error_t), allocatable, intent(out) :: err
        character(len=8), parameter :: signature = achar(137)//'HDF'//achar(13)//achar(10)// &
                                                   achar(26)//achar(10)
        character(len=8) :: head
        integer(i8) :: bytes
        integer :: u, ios
        logical :: exists

        if (is_symlink(part) .or. is_directory(part)) then
            call set_error(err, "&output: '"//part//"' (the file a run writes before its "// &
                           "end) is a symbolic link or a directory; remove it or choose "// &
                           "another file")
            return
        end if
        inquire (file=part, exist=exists)
        if (.not. exists) return
        if (is_locked(part)) then
            call set_error(err, "&output: another run is writing '"//part//"' (it holds "// &
                           "the file's lock); wait for it to end, or choose another file")
            return
        end if
        inquire (file=part, size=bytes)
        if (bytes == 0) return
        head = ''
        open (newunit=u, file=part, access='stream', form='unformatted', status='old', &
              action='read', iostat=ios)
        if (ios == 0) then
            read (u, iostat=ios) head
            close (u)
        end if
        ! (a run killed before HDF5 wrote its superblock leaves zeros where it goes)
        if (head /= signature .and. head /= repeat(achar(0), 8)) &
            call set_error(err, "&output: '"//part//"' exists and is not a file a run left "// &
                           "(not HDF5); it is never replaced: move it away or choose "// &
                           "another file")
    end subroutine check_part

    !> Refuse an existing file (unless overwrite) or an unwritable place, before any run starts;
    !> then create `path.part`.
    subroutine output_begin(out, path, overwrite, err)
        type(output_t), intent(out) :: out
        character(len=*), intent(in) :: path
        logical, intent(in) :: overwrite
        type(error_t), allocatable, intent(out) :: err

        out%path = path
        out%part_path = path//'.part'
        call output_check(path, overwrite, err)
        if (allocated(err)) return
        ! the lock first, before anything is truncated; then the checks again, as another
        ! run may have ended (and written the file) in between
        call lock_file(out%part_path, out%lock, err)
        if (allocated(err)) then
            err%message = "&"//err%message
            return
        end if
        call check_place(path, overwrite, err)
        if (.not. allocated(err)) call h5_create_file(out%file, out%part_path, err)
        if (allocated(err)) then
            call output_abort(out)
            if (index(err%message, '&output') /= 1) &
                err%message = "&output: cannot create '"//out%part_path// &
                              "' (missing directory or no permission to write there; "// &
                              err%message//")"
            return
        end if
        call output_provenance(out, err)
        if (allocated(err)) call output_abort(out)
    end subroutine output_begin

    !> Root attributes saying where the file was made (chain_provenance: code version,
    !> compiler and flags, BLAS and its kernels, CPU), written once for every kind of file.
    subroutine output_provenance(out, err)
        type(output_t), intent(inout) :: out
        type(error_t), allocatable, intent(out) :: err
        type(provenance_item_t), allocatable :: items(:)
        integer :: i

        items = provenance()
        do i = 1, size(items)
            call h5_write_attr(out%file, '/', items(i)%key, items(i)%value, err)
        end do
    end subroutine output_provenance

    !> Root attributes, /params, /initial.
    subroutine output_header(out, input_text, summary, n, spacing, damping, restitution, &
                             amplitude, omega, boundary, period, phase, transient, cycles, &
                             x0, v0, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: input_text, summary, boundary
        integer, intent(in) :: n
        real(wp), intent(in) :: damping, restitution, amplitude, omega, period, phase
        real(wp), intent(in), contiguous :: spacing(:)
        integer(i8), intent(in) :: transient, cycles
        real(wp), intent(in), contiguous :: x0(:), v0(:)
        type(error_t), allocatable, intent(out) :: err

        out%n = n
        associate (f => out%file)
            call h5_write_attr(f, '/', 'schema_version', schema_version, err)
            call h5_write_attr(f, '/', 'input_namelist', input_text, err)
            call h5_write_attr(f, '/', 'resolved_namelist', summary, err)
            call h5_write_attr(f, '/', 'complete', 0, err)
            call h5_create_group(f, 'params', err)
            call h5_write_attr(f, 'params', 'n', n, err)
            call h5_write_attr(f, 'params', 'damping', damping, err)
            call h5_write_attr(f, 'params', 'restitution', restitution, err)
            call h5_write_attr(f, 'params', 'amplitude', amplitude, err)
            call h5_write_attr(f, 'params', 'omega', omega, err)
            call h5_write_attr(f, 'params', 'boundary', boundary, err)
            call h5_write_attr(f, 'params', 'drive_period', period, err)
            call h5_write_attr(f, 'params', 'phase', phase, err)
            ! cycle counts go up to 1e12: 64-bit in the file as in memory
            call h5_write_attr(f, 'params', 'transient', transient, err)
            call h5_write_attr(f, 'params', 'cycles', cycles, err)
            call bond_coordinate(f, 'params', n, err)
            call h5_write(f, 'params/spacing', spacing, err)
            call describe(f, 'params/spacing', err)
            call h5_create_group(f, 'initial', err)
            call oscillator_coordinate(f, 'initial', n, err)
            call h5_write(f, 'initial/x', x0, err)
            call describe(f, 'initial/x', err)
            call h5_write(f, 'initial/v', v0, err)
            call describe(f, 'initial/v', err)
        end associate
    end subroutine output_header

    !> A sweep's file: /params without the parameter `name`, which differs from point to
    !> point (the sweep's coordinates hold it); without drive_period when that is omega.
    subroutine output_unset_param(out, name, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: name
        type(error_t), allocatable, intent(out) :: err

        associate (f => out%file)
            select case (name)
            case ('spacing')
                ! the variable first: its dimension then has no dataset left to refer to
                call h5_delete(f, 'params/spacing', err)
                call h5_delete(f, 'params/bond', err)
            case ('omega')
                call h5_delete_attr(f, 'params', 'omega', err)
                call h5_delete_attr(f, 'params', 'drive_period', err)
            case default
                call h5_delete_attr(f, 'params', name, err)
            end select
        end associate
    end subroutine output_unset_param

    !> `group/oscillator`: oscillators 1..n.
    subroutine oscillator_coordinate(f, group, n, err)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: group
        integer, intent(in) :: n
        type(error_t), allocatable, intent(inout) :: err

        call index_coordinate(f, group//'/oscillator', 1, n, err)
    end subroutine oscillator_coordinate

    !> `group/bond`: bonds 0..n, bond k between oscillators k and k+1 (0 and n: the walls).
    subroutine bond_coordinate(f, group, n, err)
        type(h5_file_t), intent(in) :: f
        character(len=*), intent(in) :: group
        integer, intent(in) :: n
        type(error_t), allocatable, intent(inout) :: err

        call index_coordinate(f, group//'/bond', 0, n + 1, err)
    end subroutine bond_coordinate

    !> Create a group (once).
    subroutine output_group(out, name, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: name
        type(error_t), allocatable, intent(out) :: err

        call h5_create_group(out%file, name, err)
    end subroutine output_group

    !> Write strobe records first .. first+m-1 (x, v of shape (n, m)) of n_records in all.
    subroutine output_strobe_write(out, n_records, first, x, v, cycle, err)
        type(output_t), intent(inout) :: out
        integer(i8), intent(in) :: n_records, first
        real(wp), intent(in), contiguous :: x(:, :), v(:, :)
        integer(i8), intent(in), contiguous :: cycle(:)
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: dims(2), offset(2)

        dims = [int(out%n, i8), n_records]
        offset = [0_i8, first - 1]
        associate (f => out%file)
            if (first == 1) then
                call h5_create_group(f, 'strobe', err)
                call oscillator_coordinate(f, 'strobe', out%n, err)
                call h5_create_growing(f, 'strobe/cycle', h5_int8, dims(2:2), err)
                call h5_set_scale(f, 'strobe/cycle', err)
                call describe(f, 'strobe/cycle', err)
                call h5_create_growing(f, 'strobe/x', h5_real, dims, err)
                call describe(f, 'strobe/x', err)
                call h5_create_growing(f, 'strobe/v', h5_real, dims, err)
                call describe(f, 'strobe/v', err)
            end if
            call h5_write_slab(f, 'strobe/x', offset, x, grow=.false., err=err)
            call h5_write_slab(f, 'strobe/v', offset, v, grow=.false., err=err)
            call h5_write_slab(f, 'strobe/cycle', offset(2:2), cycle, grow=.false., err=err)
        end associate
    end subroutine output_strobe_write

    !> Append events to the extendible /events datasets.
    subroutine output_events_append(out, time, site, speed, kind, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in), contiguous :: time(:), speed(:)
        integer, intent(in), contiguous :: site(:), kind(:)
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: offset(1)

        associate (f => out%file)
            if (.not. out%events_created) then
                call h5_create_group(f, 'events', err)
                call bare_dimension(f, 'events/event', 0_i8, .true., err)
                call h5_create_appendable(f, 'events/time', h5_real, event_chunk, err)
                call describe(f, 'events/time', err)
                call h5_create_appendable(f, 'events/site', h5_int, event_chunk, err)
                call describe(f, 'events/site', err)
                call h5_create_appendable(f, 'events/speed', h5_real, event_chunk, err)
                call describe(f, 'events/speed', err)
                call h5_create_appendable(f, 'events/kind', h5_int, event_chunk, err)
                call describe(f, 'events/kind', err)
                call flags(f, 'events/kind', [0, 1, 2, 3], 'impact impact_starting_a_rest '// &
                           'release touch_without_impulse', err)
                if (allocated(err)) return
                out%events_created = .true.
            end if
            if (size(time) == 0) return
            offset = [out%n_events]
            call h5_set_extent(f, 'events/event', [out%n_events + size(time)], err)
            call h5_write_slab(f, 'events/time', offset, time, grow=.true., err=err)
            call h5_write_slab(f, 'events/site', offset, site, grow=.true., err=err)
            call h5_write_slab(f, 'events/speed', offset, speed, grow=.true., err=err)
            call h5_write_slab(f, 'events/kind', offset, kind, grow=.true., err=err)
        end associate
        if (.not. allocated(err)) out%n_events = out%n_events + size(time)
    end subroutine output_events_append

    !> /final: everything needed to continue bit-for-bit.
    !> /final: the chain's state at the end (with its schedule, so that a continuation goes on
    !> bit for bit); `omega` gives the drive phase.
    subroutine output_final(out, state, omega, err)
        type(output_t), intent(inout) :: out
        type(chain_state_t), intent(in) :: state
        real(wp), intent(in) :: omega
        type(error_t), allocatable, intent(out) :: err

        associate (f => out%file)
            call h5_create_group(f, 'final', err)
            call oscillator_coordinate(f, 'final', out%n, err)
            call bond_coordinate(f, 'final', out%n, err)
            call h5_write(f, 'final/x', state%x, err)
            call describe(f, 'final/x', err)
            call h5_write(f, 'final/v', state%v, err)
            call describe(f, 'final/v', err)
            call h5_write(f, 'final/phase', state%time*omega, err)
            call describe(f, 'final/phase', err)
            call h5_write(f, 'final/time_in_cycle', state%time, err)
            call describe(f, 'final/time_in_cycle', err)
            call h5_write(f, 'final/contact', state%contact, err)
            call describe(f, 'final/contact', err)
            call flags(f, 'final/contact', [-1, 0, 1], 'resting_on_the_left_wall free '// &
                       'resting_on_the_right_wall', err)
            call h5_write(f, 'final/event_time', state%event_time, err)
            call describe(f, 'final/event_time', err)
            call h5_write(f, 'final/event_action', state%event_action, err)
            call describe(f, 'final/event_action', err)
            call flags(f, 'final/event_action', [0, 1, 2, 3], 'none impact release recheck', &
                       err)
            call h5_write(f, 'final/cycle', state%cycle, err)
            call describe(f, 'final/cycle', err)
        end associate
    end subroutine output_final

    subroutine output_stats(out, collisions_per_cycle, impacts, sticks, releases, touches, &
                            site_counts, cycles_done, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in) :: collisions_per_cycle
        integer(i8), intent(in) :: impacts, sticks, releases, touches, cycles_done
        integer(i8), intent(in), contiguous :: site_counts(:)
        type(error_t), allocatable, intent(out) :: err

        associate (f => out%file)
            call h5_create_group(f, 'stats', err)
            call h5_write_attr(f, 'stats', 'collisions_per_cycle', collisions_per_cycle, err)
            call h5_write_attr(f, 'stats', 'impacts', impacts, err)
            call h5_write_attr(f, 'stats', 'sticks', sticks, err)
            call h5_write_attr(f, 'stats', 'releases', releases, err)
            call h5_write_attr(f, 'stats', 'touches', touches, err)
            call bond_coordinate(f, 'stats', out%n, err)
            call h5_write(f, 'stats/site_counts', site_counts, err)
            call describe(f, 'stats/site_counts', err)
            ! /params/cycles is the number planned; a run stopped early did fewer
            call h5_write(f, 'stats/cycles_done', cycles_done, err)
            call describe(f, 'stats/cycles_done', err)
        end associate
    end subroutine output_stats

    subroutine output_periods(out, period, err)
        type(output_t), intent(inout) :: out
        integer, intent(in), contiguous :: period(:)
        type(error_t), allocatable, intent(out) :: err

        call h5_write(out%file, 'strobe/period', period, err)
        call describe(out%file, 'strobe/period', err)
    end subroutine output_periods

    !> A run stopped early keeps only its finished records: shrink /strobe to them.
    subroutine output_truncate_strobe(out, records_done, err)
        type(output_t), intent(inout) :: out
        integer(i8), intent(in) :: records_done
        type(error_t), allocatable, intent(out) :: err
        logical :: exists

        call h5_exists(out%file, 'strobe', exists, err)
        if (exists) call set_strobe_records(out, records_done, err)
    end subroutine output_truncate_strobe

    !> /strobe/x, v and cycle cut (or grown) to `records` records.
    subroutine set_strobe_records(out, records, err)
        type(output_t), intent(in) :: out
        integer(i8), intent(in) :: records
        type(error_t), allocatable, intent(inout) :: err

        call h5_set_extent(out%file, 'strobe/x', [int(out%n, i8), records], err)
        call h5_set_extent(out%file, 'strobe/v', [int(out%n, i8), records], err)
        call h5_set_extent(out%file, 'strobe/cycle', [records], err)
    end subroutine set_strobe_records

    !> Mark complete (or partial), close, and move `.part` to the final name.
    subroutine output_end(out, complete, err)
        type(output_t), intent(inout) :: out
        logical, intent(in) :: complete
        type(error_t), allocatable, intent(out) :: err

        call h5_write_attr(out%file, '/', 'complete', merge(1, 0, complete), err)
        call h5_close_file(out%file, err)
        if (allocated(err)) then
            call output_abort(out)
            return
        end if
        call rename_file(out%part_path, out%path, err)
        ! (a checkpoint's copy left by a run killed while it made one)
        call remove_file(out%path//'.saving')
        call unlock_file(out%lock)
    end subroutine output_end

    !> Close and delete the partial file after an error. The error that brought us here is
    !> the one reported; a failure to close the file now is part of it (the file is deleted).
    subroutine output_abort(out)
        type(output_t), intent(inout) :: out
        type(error_t), allocatable :: ignored

        call h5_close_file(out%file, ignored)
        if (allocated(out%part_path) .and. out%lock >= 0) call remove_file(out%part_path)
        call unlock_file(out%lock)
    end subroutine output_abort

end module chain_run_file
