!> A run stopped early and its continuation (docs/output.md): /resume, what a continuation
!> reads back, what is under an output file's name, the checkpoint of a run being written and
!> the reopening of its `.part` file; and the final state of an earlier run, a start from a
!> file (&initial kind = 'file'), with every value checked. The file is chain_run_file's.
!> Infrastructure, no model section.
module chain_run_file_resume
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int, fmt_int8, fmt_real
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_is_nan
    use chain_files, only: lock_file, rename_file, remove_file, copy_file
    use chain_model, only: model_t
    use chain_namelist, only: same_input
    use chain_state, only: chain_state_t
    use chain_describe, only: describe, bare_dimension
    use chain_run_file, only: output_t, output_abort, schema_version, check_part, &
                              set_strobe_records
    use chain_run_file_spectra, only: output_truncate_windows
    use chain_hdf5, only: h5_file_t, h5_open_file, h5_close_file, h5_is_hdf5_file, &
                          h5_create_group, h5_exists, h5_delete, h5_write_attr, h5_read_attr, &
                          h5_write, h5_read, h5_read_alloc, h5_extent, h5_read_slab, &
                          h5_detach_dimensions
    implicit none
    private
    public :: resume_data_t, output_resume, read_resume, output_inspect, output_continue
    public :: output_checkpoint, read_final_state
    public :: file_absent, file_continuable, file_other_input, file_other

    !> The schema versions whose /final a run can start from (&initial kind = 'file').
    integer, parameter :: readable_versions(2) = [1, 2]

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

contains

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
            allocate (state%tangent%jumps_volume(size(state%tangent%frame, 1)))
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

end module chain_run_file_resume
