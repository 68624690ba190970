!> The layout of a run's output file (docs/output.md): which groups, datasets and attributes
!> a run writes (their names, units and long names are the file schema's: chain_describe),
!> and reading back a final state (a start from a
!> file) or what a run stopped early keeps for its continuation. The HDF5 calls are
!> chain_hdf5's; a sweep's /sweep group is chain_sweep's.
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
module chain_output
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int, fmt_int8, fmt_real
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_is_nan
    use chain_files, only: lock_file, is_locked, unlock_file, is_symlink
    use chain_files, only: rename_file, remove_file, copy_file, directory_of, is_directory, &
                           can_write_in
    use chain_model, only: model_t
    use chain_namelist, only: same_input
    use chain_state, only: chain_state_t
    use chain_describe, only: describe, index_coordinate, bare_dimension, flags
    use chain_provenance, only: code_version, provenance_item_t, provenance
    use chain_hdf5, only: h5_file_t, h5_real, h5_int, h5_int8, h5_create_file, h5_open_file, &
                          h5_close_file, h5_is_hdf5_file, h5_create_group, h5_exists, &
                          h5_delete, h5_write_attr, h5_read_attr, h5_write, h5_read, &
                          h5_read_alloc, h5_extent, h5_create_growing, h5_create_appendable, &
                          h5_set_extent, h5_write_slab, h5_read_slab, &
                          h5_set_scale, h5_dimensions, h5_detach_dimensions, h5_delete_attr
    implicit none
    private
    public :: output_t, output_check, output_begin, output_header, output_strobe_write
    public :: output_events_append
    public :: output_final, output_stats, output_periods, output_lyapunov, output_jacobian
    public :: output_clv_rows, output_clv, output_windows_write, output_truncate_windows
    public :: output_end, output_abort, read_final_state, output_group
    public :: schema_version, code_version, output_truncate_strobe
    public :: resume_data_t, output_resume, read_resume, output_inspect, output_continue
    public :: output_checkpoint
    public :: file_absent, file_continuable, file_other_input, file_other
    public :: output_unset_param

    integer, parameter :: schema_version = 2
    !> The schema versions whose /final a run can start from (&initial kind = 'file').
    integer, parameter :: readable_versions(2) = [1, 2]
    !> Events per chunk of the /events datasets.
    integer(i8), parameter :: event_chunk = 65536

    !> What output_inspect finds under an output file's name.
    integer, parameter :: file_absent = 0       !! nothing
    integer, parameter :: file_continuable = 1  !! a run stopped early, of the same input text
    integer, parameter :: file_other_input = 2  !! a run stopped early, of another input
    integer, parameter :: file_other = 3        !! anything else (a finished run, not ours)

    !> What a run stopped early keeps for its continuation besides the chain's state (whose
    !> bookkeeping and tangent frame go to /resume with it, its counters to /stats, the rest to
    !> /final): the records done, the Lyapunov accumulator (packed), and the last records
    !> read back from /strobe for the period window.
    type :: resume_data_t
        integer(i8) :: cycles_done = 0       !! records done (/stats/cycles_done)
        integer(i8), allocatable :: lyapunov_int(:) !! the accumulator (lyapunov_pack)
        real(wp), allocatable :: lyapunov_real(:)
        real(wp), allocatable :: x_last(:, :), v_last(:, :) !! (n, m): the last m records
    end type resume_data_t

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

    ! ---- a run's file, from its start to its end ------------------------------------------

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

    !> /lyapunov; `running_bits(k, rows)` are the running estimates at drive cycles
    !> `running_cycle(rows)` (a bounded selection of the QR steps: chain_lyapunov).
    subroutine output_lyapunov(out, bits, per_time, stderr_bits, stderr_cycles, running_bits, &
                               running_cycle, ky, positive_sum, collisions_per_cycle, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in), contiguous :: bits(:), per_time(:), stderr_bits(:)
        integer(i8), intent(in), contiguous :: stderr_cycles(:)
        real(wp), intent(in), contiguous :: running_bits(:, :)
        integer(i8), intent(in), contiguous :: running_cycle(:)
        real(wp), intent(in) :: ky, positive_sum, collisions_per_cycle
        type(error_t), allocatable, intent(out) :: err

        associate (f => out%file)
            call h5_create_group(f, 'lyapunov', err)
            call index_coordinate(f, 'lyapunov/exponent', 1, size(bits), err)
            call bare_dimension(f, 'lyapunov/qr_step', size(running_cycle, kind=i8), &
                                     .false., err)
            call h5_write(f, 'lyapunov/exponents', bits, err)
            call describe(f, 'lyapunov/exponents', err)
            call h5_write(f, 'lyapunov/exponents_per_time', per_time, err)
            call describe(f, 'lyapunov/exponents_per_time', err)
            call h5_write(f, 'lyapunov/stderr', stderr_bits, err)
            call describe(f, 'lyapunov/stderr', err)
            call h5_write(f, 'lyapunov/stderr_block', stderr_cycles, err)
            call describe(f, 'lyapunov/stderr_block', err)
            call h5_write(f, 'lyapunov/running_cycle', running_cycle, err)
            call describe(f, 'lyapunov/running_cycle', err)
            call h5_write(f, 'lyapunov/running', running_bits, err)
            call describe(f, 'lyapunov/running', err)
            call h5_write_attr(f, 'lyapunov/running', 'coordinates', 'running_cycle', err)
            call h5_write_attr(f, 'lyapunov', 'ky_dimension', ky, err)
            call h5_write_attr(f, 'lyapunov', 'positive_sum', positive_sum, err)
            call h5_write_attr(f, 'lyapunov', 'collisions_per_cycle', collisions_per_cycle, err)
        end associate
    end subroutine output_lyapunov

    !> /finite_time (docs/model.md section 7.10), a chunk of windows at a time: windows first ..
    !> first + m - 1 of `n_windows`, exponents(k, m) in bits per drive cycle, each window of
    !> `window` cycles ending at drive cycle cycle(m); the first window creates the group.
    !> (Its own group, not /lyapunov, which the end of a run writes whole: a run stopped
    !> early keeps its windows, and its continuation adds to them, as /strobe.)
    subroutine output_windows_write(out, n_windows, first, window, exponents, cycle, err)
        type(output_t), intent(inout) :: out
        integer(i8), intent(in) :: n_windows, first
        integer, intent(in) :: window
        real(wp), intent(in), contiguous :: exponents(:, :)
        integer(i8), intent(in), contiguous :: cycle(:)
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: k

        k = size(exponents, 1)
        associate (f => out%file)
            if (first == 1) then
                call h5_create_group(f, 'finite_time', err)
                call h5_write_attr(f, 'finite_time', 'window', window, err)
                call h5_create_growing(f, 'finite_time/cycle', h5_int8, [n_windows], err)
                call h5_set_scale(f, 'finite_time/cycle', err)
                call describe(f, 'finite_time/cycle', err)
                call index_coordinate(f, 'finite_time/exponent', 1, int(k), err)
                call h5_create_growing(f, 'finite_time/exponents', h5_real, [k, n_windows], err)
                call describe(f, 'finite_time/exponents', err)
            end if
            call h5_write_slab(f, 'finite_time/exponents', [0_i8, first - 1], exponents, &
                               grow=.false., err=err)
            call h5_write_slab(f, 'finite_time/cycle', [first - 1], cycle, grow=.false., &
                               err=err)
        end associate
    end subroutine output_windows_write

    !> A run stopped early: /finite_time cut (or, continued, grown back) to `windows`.
    subroutine output_truncate_windows(out, windows, err)
        type(output_t), intent(inout) :: out
        integer(i8), intent(in) :: windows
        type(error_t), allocatable, intent(out) :: err
        integer(i8), allocatable :: dims(:)
        logical :: exists

        call h5_exists(out%file, 'finite_time', exists, err)
        if (.not. exists .or. allocated(err)) return
        call h5_extent(out%file, 'finite_time/exponents', dims, err)
        if (allocated(err)) return
        call h5_set_extent(out%file, 'finite_time/exponents', [dims(1), windows], err)
        call h5_set_extent(out%file, 'finite_time/cycle', [windows], err)
    end subroutine output_truncate_windows

    !> /clv's per-record datasets (docs/model.md section 14.5), a block of records at a time:
    !> records first .. first + m - 1 of the `total` records with covariant vectors, in any
    !> order of blocks (the backward pass writes the last first); the first block written
    !> creates them. ipr(k, m), site_weight(n, stored, m), min_angle(m), cycle(m).
    subroutine output_clv_rows(out, first, total, cycle, ipr, site_weight, min_angle, err)
        type(output_t), intent(inout) :: out
        integer(i8), intent(in) :: first, total
        integer(i8), intent(in), contiguous :: cycle(:)
        real(wp), intent(in), contiguous :: ipr(:, :), site_weight(:, :, :), min_angle(:)
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: k, stored

        k = size(ipr, 1)
        stored = size(site_weight, 2)
        associate (f => out%file)
            if (.not. out%clv_created) then
                call h5_create_group(f, 'clv', err)
                call h5_create_growing(f, 'clv/cycle', h5_int8, [total], err)
                call h5_set_scale(f, 'clv/cycle', err)
                call describe(f, 'clv/cycle', err)
                call index_coordinate(f, 'clv/vector', 1, int(k), err)
                call oscillator_coordinate(f, 'clv', out%n, err)
                call h5_create_growing(f, 'clv/ipr', h5_real, [k, total], err)
                call describe(f, 'clv/ipr', err)
                call h5_create_growing(f, 'clv/min_angle', h5_real, [total], err)
                call describe(f, 'clv/min_angle', err)
                if (stored > 0) then
                    call index_coordinate(f, 'clv/leading_vector', 1, int(stored), err)
                    call h5_create_growing(f, 'clv/site_weight', h5_real, &
                                           [int(out%n, i8), stored, total], err)
                    call describe(f, 'clv/site_weight', err)
                end if
                if (allocated(err)) return
                out%clv_created = .true.
            end if
            call h5_write_slab(f, 'clv/cycle', [first - 1], cycle, grow=.false., err=err)
            call h5_write_slab(f, 'clv/ipr', [0_i8, first - 1], ipr, grow=.false., err=err)
            call h5_write_slab(f, 'clv/min_angle', [first - 1], min_angle, grow=.false., &
                               err=err)
            if (stored > 0) call h5_write_slab(f, 'clv/site_weight', [0_i8, 0_i8, first - 1], &
                                               site_weight, grow=.false., err=err)
        end associate
    end subroutine output_clv_rows

    !> The rest of /clv, after its per-record datasets: the vectors' growth rates, their
    !> standard errors and the records per block these were read at, the vectors at the last
    !> records (vectors(2n, k, r), at drive cycles saved_cycle(r)), and as attributes the
    !> records without vectors at the end and the number of vectors spanning the unstable
    !> subspace.
    subroutine output_clv(out, exponents, stderr, stderr_block, vectors, saved_cycle, &
                          transient, unstable, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in), contiguous :: exponents(:), stderr(:), vectors(:, :, :)
        integer(i8), intent(in), contiguous :: stderr_block(:), saved_cycle(:)
        integer, intent(in) :: transient, unstable
        type(error_t), allocatable, intent(out) :: err

        associate (f => out%file)
            call h5_write(f, 'clv/exponents', exponents, err)
            call describe(f, 'clv/exponents', err)
            call h5_write(f, 'clv/stderr', stderr, err)
            call describe(f, 'clv/stderr', err)
            call h5_write(f, 'clv/stderr_block', stderr_block, err)
            call describe(f, 'clv/stderr_block', err)
            if (size(saved_cycle) > 0) then
                call index_coordinate(f, 'clv/component', 1, size(vectors, 1), err)
                call h5_write(f, 'clv/saved_cycle', saved_cycle, err)
                call h5_set_scale(f, 'clv/saved_cycle', err)
                call describe(f, 'clv/saved_cycle', err)
                call h5_write(f, 'clv/vectors', vectors, err)
                call describe(f, 'clv/vectors', err)
            end if
            call h5_write_attr(f, 'clv', 'clv_transient', transient, err)
            call h5_write_attr(f, 'clv', 'unstable', unstable, err)
        end associate
    end subroutine output_clv

    subroutine output_jacobian(out, jacobian, re, im, cycles, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in) :: jacobian(:, :)
        real(wp), intent(in), contiguous :: re(:), im(:)
        integer, intent(in) :: cycles
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: rows(:, :)

        associate (f => out%file)
            call h5_create_group(f, 'floquet', err)
            call bare_dimension(f, 'floquet/row', size(jacobian, 1, kind=i8), .false., err)
            call bare_dimension(f, 'floquet/column', size(jacobian, 2, kind=i8), .false., &
                                     err)
            call bare_dimension(f, 'floquet/multiplier', size(re, kind=i8), .false., err)
            ! rows of the Jacobian are rows in h5py
            rows = transpose(jacobian)
            call h5_write(f, 'floquet/jacobian', rows, err)
            call describe(f, 'floquet/jacobian', err)
            call h5_write(f, 'floquet/multipliers_re', re, err)
            call describe(f, 'floquet/multipliers_re', err)
            call h5_write(f, 'floquet/multipliers_im', im, err)
            call describe(f, 'floquet/multipliers_im', err)
            call h5_write_attr(f, 'floquet', 'cycles', cycles, err)
        end associate
    end subroutine output_jacobian

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

    ! ---- a run stopped early, and its continuation ----------------------------------------

    !> /resume of a run stopped early (see resume_data_t).
    subroutine output_resume(out, state, data, err)
        type(output_t), intent(inout) :: out
        type(chain_state_t), intent(in) :: state !! the chain's bookkeeping and tangent frame
        type(resume_data_t), intent(in) :: data  !! the Lyapunov accumulator
        type(error_t), allocatable, intent(out) :: err

        associate (f => out%file)
            call h5_create_group(f, 'resume', err)
            call h5_write(f, 'resume/start_cycle', state%start_cycle, err)
            call describe(f, 'resume/start_cycle', err)
            call h5_write(f, 'resume/start_time_in_cycle', state%start_time, err)
            call describe(f, 'resume/start_time_in_cycle', err)
            call h5_write(f, 'resume/last_event', state%last_event, err)
            call describe(f, 'resume/last_event', err)
            call h5_write(f, 'resume/same_instant', state%same_instant, err)
            call describe(f, 'resume/same_instant', err)
            if (.not. state%has_tangent) return
            call bare_dimension(f, 'resume/state', size(state%tangent%frame, 2, kind=i8), &
                                     .false., err)
            call bare_dimension(f, 'resume/vector', size(state%tangent%frame, 1, kind=i8), &
                                     .false., err)
            call bare_dimension(f, 'resume/packed_int', size(data%lyapunov_int, kind=i8), &
                                     .false., err)
            call bare_dimension(f, 'resume/packed_real', &
                                     size(data%lyapunov_real, kind=i8), .false., err)
            call h5_write(f, 'resume/tangent', state%tangent%frame, err)
            call describe(f, 'resume/tangent', err)
            call h5_write(f, 'resume/tangent_scale_bits', state%tangent%scale_bits, err)
            call describe(f, 'resume/tangent_scale_bits', err)
            call h5_write(f, 'resume/tangent_log', state%tangent%growth_log, err)
            call describe(f, 'resume/tangent_log', err)
            call h5_write(f, 'resume/rank_losses', state%tangent%rank_losses, err)
            call describe(f, 'resume/rank_losses', err)
            call h5_write(f, 'resume/jumps_volume', state%tangent%jumps_volume, err)
            call describe(f, 'resume/jumps_volume', err)
            call h5_write(f, 'resume/lyapunov_int', data%lyapunov_int, err)
            call describe(f, 'resume/lyapunov_int', err)
            call h5_write(f, 'resume/lyapunov_real', data%lyapunov_real, err)
            call describe(f, 'resume/lyapunov_real', err)
        end associate
    end subroutine output_resume

    !> What a continuation of the run stopped early in `path` needs besides /final: /resume,
    !> the counters of /stats, and the last min(cycles done, window) strobe records.
    subroutine read_resume(path, n, with_tangent, window, state, data, err)
        character(len=*), intent(in) :: path
        integer, intent(in) :: n, window
        logical, intent(in) :: with_tangent
        type(chain_state_t), intent(inout) :: state !! gets the bookkeeping and tangent frame
        type(resume_data_t), intent(out) :: data
        type(error_t), allocatable, intent(out) :: err
        type(h5_file_t) :: src
        integer(i8) :: m

        call open_for_reading(path, '&output', src, err)
        if (allocated(err)) return
        allocate (state%counts%site_counts(n + 1))
        call h5_read(src, 'stats/cycles_done', data%cycles_done, err)
        call h5_read_attr(src, 'stats', 'impacts', state%counts%impacts, err)
        call h5_read_attr(src, 'stats', 'sticks', state%counts%sticks, err)
        call h5_read_attr(src, 'stats', 'releases', state%counts%releases, err)
        call h5_read_attr(src, 'stats', 'touches', state%counts%touches, err)
        call h5_read(src, 'stats/site_counts', state%counts%site_counts, err)
        call h5_read(src, 'resume/start_cycle', state%start_cycle, err)
        call h5_read(src, 'resume/start_time_in_cycle', state%start_time, err)
        call h5_read(src, 'resume/last_event', state%last_event, err)
        call h5_read(src, 'resume/same_instant', state%same_instant, err)
        state%has_tangent = with_tangent
        if (with_tangent) then
            call h5_read_alloc(src, 'resume/tangent', state%tangent%frame, err)
            call h5_read(src, 'resume/tangent_scale_bits', state%tangent%scale_bits, err)
            allocate (state%tangent%growth_log(size(state%tangent%frame, 1)))
            call h5_read(src, 'resume/tangent_log', state%tangent%growth_log, err)
            call h5_read(src, 'resume/rank_losses', state%tangent%rank_losses, err)
            call h5_read(src, 'resume/jumps_volume', state%tangent%jumps_volume, err)
            call h5_read_alloc(src, 'resume/lyapunov_int', data%lyapunov_int, err)
            call h5_read_alloc(src, 'resume/lyapunov_real', data%lyapunov_real, err)
        end if
        if (.not. allocated(err) .and. data%cycles_done < 1) &
            call set_error(err, "hdf5: /stats/cycles_done = "//fmt_int8(data%cycles_done)// &
                           " is not a stopped run's (file "//path//")")
        if (.not. allocated(err)) then
            m = min(data%cycles_done, int(window, i8))
            allocate (data%x_last(n, m), data%v_last(n, m))
            call h5_read_slab(src, 'strobe/x', [0_i8, data%cycles_done - m], data%x_last, err)
            call h5_read_slab(src, 'strobe/v', [0_i8, data%cycles_done - m], data%v_last, err)
        end if
        if (allocated(err)) then
            if (err%message(1:5) == 'hdf5:') err%message = "&output: cannot continue the "// &
                                                          "run stopped early in '"//path// &
                                                          "': "//err%message
        end if
        call h5_close_file(src, err)
    end subroutine read_resume

    !> What is under an output file's name (file_absent, file_continuable, ...), for a run of
    !> `input_text` about to write there. Anything unreadable is file_other.
    subroutine output_inspect(path, input_text, kind)
        character(len=*), intent(in) :: path, input_text
        integer, intent(out) :: kind
        type(h5_file_t) :: src
        type(error_t), allocatable :: err
        integer(i8) :: complete, version
        character(len=:), allocatable :: text
        logical :: exists

        inquire (file=path, exist=exists)
        kind = merge(file_other, file_absent, exists)
        if (.not. exists) return
        call open_for_reading(path, '&output', src, err)
        if (allocated(err)) return
        call h5_read_attr(src, '/', 'schema_version', version, err)
        call h5_read_attr(src, '/', 'complete', complete, err)
        call h5_exists(src, 'resume', exists, err)
        call h5_read_attr(src, '/', 'input_namelist', text, err)
        ! (a run stopped early by an older version is not continued into another layout)
        if (.not. allocated(err) .and. complete == 0 .and. exists .and. &
            version == schema_version) then
            ! (trailing blanks of the text are not stored; whether a file may be replaced is
            ! not part of what is computed, so --overwrite does not make another input)
            kind = merge(file_continuable, file_other_input, text == input_text .or. &
                         same_input(text, input_text, 'output.overwrite'))
        end if
        call h5_close_file(src, err)
    end subroutine output_inspect

    !> Reopen the run stopped early in `path` to continue it: a copy `path.part` (the file
    !> under the final name stays as it is until the continuation ends), without the results
    !> that the end of the run writes again (/final, /stats, /lyapunov, /floquet, /resume,
    !> /strobe/period), with /strobe back at `n_records` records and /finite_time at
    !> `n_windows` windows.
    subroutine output_continue(out, path, n, n_records, n_windows, err)
        type(output_t), intent(out) :: out
        character(len=*), intent(in) :: path
        integer, intent(in) :: n
        integer(i8), intent(in) :: n_records
        integer(i8), intent(in) :: n_windows !! finite-time windows of the whole run
        type(error_t), allocatable, intent(out) :: err

        out%path = path
        out%part_path = path//'.part'
        out%n = n
        call check_part(out%part_path, err)
        if (.not. allocated(err)) call lock_file(out%part_path, out%lock, err)
        if (allocated(err)) then
            if (index(err%message, '&output') /= 1) err%message = "&"//err%message
            return
        end if
        call copy_file(path, out%part_path, err)
        if (.not. allocated(err)) call reopen_part(out, n_records, n_windows, err)
        if (allocated(err)) call output_abort(out)
    end subroutine output_continue

    !> A checkpoint of a run being written: the `.part` file, which holds a run stopped early
    !> (results and /resume written), closed (complete = 0) and copied to the final name, then
    !> reopened to go on as output_continue does. The lock on `.part` is held throughout, so
    !> no other run can take the file meanwhile. On failure (a full disk) the final name
    !> keeps the checkpoint before, and the `.part` file is deleted.
    subroutine output_checkpoint(out, n_records, n_windows, err)
        type(output_t), intent(inout) :: out
        integer(i8), intent(in) :: n_records, n_windows
        type(error_t), allocatable, intent(out) :: err
        character(len=:), allocatable :: copy

        copy = out%path//'.saving'
        call h5_write_attr(out%file, '/', 'complete', 0, err)
        if (.not. allocated(err)) call h5_close_file(out%file, err)
        if (.not. allocated(err)) call copy_file(out%part_path, copy, err)
        if (.not. allocated(err)) call rename_file(copy, out%path, err)
        if (allocated(err)) then
            call remove_file(copy)
            call output_abort(out)
            return
        end if
        out%events_created = .false.
        out%n_events = 0
        call reopen_part(out, n_records, n_windows, err)
        if (allocated(err)) call output_abort(out)
    end subroutine output_checkpoint

    !> Open the `.part` file of a run stopped early for writing, without the results the end
    !> of the run writes again, /strobe at `n_records` records, /finite_time at `n_windows`.
    subroutine reopen_part(out, n_records, n_windows, err)
        type(output_t), intent(inout) :: out
        integer(i8), intent(in) :: n_records, n_windows
        type(error_t), allocatable, intent(out) :: err
        character(len=14), parameter :: results(6) = [character(len=14) :: 'final', 'stats', &
                                                      'lyapunov', 'floquet', 'resume', &
                                                      'strobe/period']
        integer(i8), allocatable :: dims(:)
        integer :: j
        logical :: exists

        call h5_open_file(out%file, out%part_path, writable=.true., err=err)
        do j = 1, size(results)
            call h5_exists(out%file, trim(results(j)), exists, err)
            ! (/strobe/oscillator stays: no reference to the deleted period may stay with it)
            if (exists .and. results(j) == 'strobe/period') &
                call h5_detach_dimensions(out%file, 'strobe/period', 'oscillator', err)
            if (exists) call h5_delete(out%file, trim(results(j)), err)
        end do
        call set_strobe_records(out, n_records, err)
        if (.not. allocated(err)) call output_truncate_windows(out, n_windows, err)
        call h5_exists(out%file, 'events', out%events_created, err)
        if (out%events_created) then
            call h5_extent(out%file, 'events/time', dims, err)
            if (.not. allocated(err)) out%n_events = dims(1)
        end if
    end subroutine reopen_part

    ! ---- a start from a file --------------------------------------------------------------

    !> The final state of an earlier run, to continue from it.
    !> The state in /final of the run in `path` (n oscillators), with its schedule, and the
    !> model of its /params (the stick speed is not stored: the default).
    subroutine read_final_state(path, n, state, model, err)
        character(len=*), intent(in) :: path
        integer, intent(in) :: n
        type(chain_state_t), intent(out) :: state
        type(model_t), intent(out) :: model
        type(error_t), allocatable, intent(out) :: err
        type(h5_file_t) :: src
        integer(i8) :: version, n_file
        character(len=:), allocatable :: boundary

        allocate (state%x(n), state%v(n), state%contact(n), state%event_time(n + 1), &
                  state%event_action(n + 1), model%spacing(n + 1))
        model%n = n
        call open_for_reading(path, '&initial', src, err)
        if (allocated(err)) return
        call h5_read_attr(src, '/', 'schema_version', version, err)
        if (.not. allocated(err) .and. .not. any(version == readable_versions)) &
            call set_error(err, "&initial: file = '"//path//"' is not an impactchain "// &
                           "output of schema version 1 or 2")
        call h5_read_attr(src, 'params', 'n', n_file, err)
        if (.not. allocated(err) .and. n_file /= n) &
            call set_error(err, "&initial: file = '"//path//"' has n = "//fmt_int8(n_file)// &
                           " oscillators, the input n = "//fmt_int(n))
        call read_final_group(src, path, state, err)
        call h5_read_attr(src, 'params', 'damping', model%damping, err)
        call h5_read_attr(src, 'params', 'restitution', model%restitution, err)
        call h5_read_attr(src, 'params', 'amplitude', model%amplitude, err)
        call h5_read_attr(src, 'params', 'omega', model%omega, err)
        call h5_read_attr(src, 'params', 'boundary', boundary, err)
        if (.not. allocated(err)) model%walls = trim(boundary) == 'fixed'
        call h5_read(src, 'params/spacing', model%spacing, err)
        if (allocated(err)) then
            if (err%message(1:5) == 'hdf5:') err%message = "&initial: "//err%message
        end if
        call h5_close_file(src, err)
    end subroutine read_final_state

    !> /final into `state` (arrays allocated): a run's clock starts there.
    subroutine read_final_group(src, path, state, err)
        type(h5_file_t), intent(in) :: src
        character(len=*), intent(in) :: path
        type(chain_state_t), intent(inout) :: state
        type(error_t), allocatable, intent(inout) :: err
        logical :: exists
        real(wp) :: phase

        call h5_exists(src, 'final', exists, err)
        if (.not. allocated(err) .and. .not. exists) &
            call set_error(err, "&initial: file = '"//path//"' has no /final state")
        call h5_read(src, 'final/x', state%x, err)
        call h5_read(src, 'final/v', state%v, err)
        call h5_read(src, 'final/contact', state%contact, err)
        call h5_read(src, 'final/event_time', state%event_time, err)
        call h5_read(src, 'final/event_action', state%event_action, err)
        call h5_read(src, 'final/phase', phase, err) ! (read for its check: /final is whole)
        call h5_read(src, 'final/time_in_cycle', state%time, err)
        call h5_read(src, 'final/cycle', state%cycle, err)
        if (.not. allocated(err)) call check_final(path, state, phase, err)
        state%has_schedule = .true.
        state%start_cycle = state%cycle
        state%start_time = state%time
    end subroutine read_final_group

    !> Every value of /final in its range, as an explicit x0 is checked (the engine takes any
    !> value it is given on trust): finite positions, velocities, phase and time in the cycle
    !> (>= 0), a cycle >= 0, rests of -1, 0 or 1 (the left wall, free, the right wall), event
    !> times >= 0 (never: the largest number) and actions 0 to 3 (chain_engine's action_*).
    subroutine check_final(path, state, phase, err)
        character(len=*), intent(in) :: path
        type(chain_state_t), intent(in) :: state
        real(wp), intent(in) :: phase
        type(error_t), allocatable, intent(inout) :: err
        character(len=:), allocatable :: where
        integer :: j

        where = "&initial: file = '"//path//"': /final/"
        do j = 1, size(state%x)
            if (.not. ieee_is_finite(state%x(j))) then
                call set_error(err, where//"x("//fmt_int(j)//") = "//fmt_real(state%x(j))// &
                               " is not finite; allowed: finite positions")
                return
            else if (.not. ieee_is_finite(state%v(j))) then
                call set_error(err, where//"v("//fmt_int(j)//") = "//fmt_real(state%v(j))// &
                               " is not finite; allowed: finite velocities")
                return
            else if (abs(state%contact(j)) > 1) then
                call set_error(err, where//"contact("//fmt_int(j)//") = "// &
                               fmt_int(state%contact(j))//" is not a rest; allowed: -1 (the "// &
                               "left wall), 0 (free), 1 (the right wall)")
                return
            end if
        end do
        do j = 1, size(state%event_time)
            ! (NaN first: an ordered comparison with it traps in the runtime-checked build)
            if (ieee_is_nan(state%event_time(j)) .or. bad_time(state%event_time(j))) then
                call set_error(err, where//"event_time("//fmt_int(j)//") = "// &
                               fmt_real(state%event_time(j))//"; allowed: times >= 0")
                return
            else if (state%event_action(j) < 0 .or. state%event_action(j) > 3) then
                call set_error(err, where//"event_action("//fmt_int(j)//") = "// &
                               fmt_int(state%event_action(j))//"; allowed: 0 to 3")
                return
            end if
        end do
        if (.not. ieee_is_finite(state%time) .or. bad_time(state%time)) then
            call set_error(err, where//"time_in_cycle = "//fmt_real(state%time)// &
                           "; allowed: finite, >= 0")
        else if (.not. ieee_is_finite(phase)) then
            call set_error(err, where//"phase = "//fmt_real(phase)//"; allowed: finite")
        else if (state%cycle < 0) then
            call set_error(err, where//"cycle = "//fmt_int8(state%cycle)//"; allowed: >= 0")
        end if
    contains
        !> t < 0, for a t that is not NaN (asked only then: see above)
        logical function bad_time(t)
            real(wp), intent(in) :: t
            bad_time = .false.
            if (.not. ieee_is_nan(t)) bad_time = t < 0
        end function bad_time
    end subroutine check_final

    !> Open an existing file read-only (`where` names the input that points at it).
    subroutine open_for_reading(path, where, src, err)
        character(len=*), intent(in) :: path, where
        type(h5_file_t), intent(out) :: src
        type(error_t), allocatable, intent(out) :: err
        logical :: exists, is_hdf5

        inquire (file=path, exist=exists)
        if (.not. exists) then
            call set_error(err, where//": file = '"//path//"' does not exist")
            return
        end if
        call h5_is_hdf5_file(path, is_hdf5, err)
        if (allocated(err)) then
            err%message = where//": "//err%message
            return
        end if
        if (.not. is_hdf5) then
            call set_error(err, where//": file = '"//path//"' is not an HDF5 file")
            return
        end if
        call h5_open_file(src, path, writable=.false., err=err)
        if (allocated(err)) err%message = where//": "//err%message// &
                                          "; the file is damaged or truncated"
    end subroutine open_for_reading

end module chain_output
