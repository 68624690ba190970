!> HDF5 output (the only module that touches `use hdf5`): the layout of README.md "Output".
!>
!> A run writes to `name.h5.part` and renames it to `name.h5` when it ends, so a file under the
!> final name is never one whose writing was cut off. Strobe records and events go to disk in
!> chunks as the run proceeds, so memory does not grow with its length. Fortran arrays x(n, m)
!> appear in h5py as (m, n).
!>
!> Every HDF5 status code goes through one funnel, `check`, which turns a failure into
!> "hdf5: <call> failed on <object> (file <path>)" and never replaces an error already set, so
!> ids closed on the way out of a failure cannot hide it.
!> Infrastructure, no model section: it writes the records of docs/model.md sections 6-7.
module chain_output
    use, intrinsic :: iso_c_binding, only: c_null_char, c_ptr, c_loc
    use hdf5
    use h5lt
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int, fmt_int8
    use chain_files, only: rename_file, remove_file, copy_file
    implicit none
    private
    public :: output_t, output_begin, output_header, output_strobe_write, output_events_append
    public :: output_final, output_stats, output_periods, output_lyapunov, output_jacobian
    public :: output_end, output_abort, read_final_state, output_sweep_write, output_group
    public :: schema_version, code_version, output_truncate_strobe, output_sweep_attributes
    public :: output_sweep_write_int
    public :: resume_data_t, output_resume, read_resume, output_inspect, output_continue
    public :: file_absent, file_continuable, file_other_input, file_other

    integer, parameter :: schema_version = 1
    character(len=*), parameter :: code_version = '0.1.0'
    integer(hsize_t), parameter :: event_chunk = 65536

    !> What output_inspect finds under an output file's name.
    integer, parameter :: file_absent = 0       !! nothing
    integer, parameter :: file_continuable = 1  !! a run stopped early, of the same input text
    integer, parameter :: file_other_input = 2  !! a run stopped early, of another input
    integer, parameter :: file_other = 3        !! anything else (a finished run, not ours)

    !> What a run stopped early keeps for its continuation in /resume (written only while the
    !> file is incomplete), and what the continuation reads back from /stats and /strobe. The
    !> engine's state itself is /final (read_final_state). Plain arrays: this module knows no
    !> other module's types.
    type :: resume_data_t
        integer(i8) :: cycles_done = 0       !! records done (/stats/cycles_done)
        integer(i8) :: start_cycle = 0       !! cycle and time within it of the run's start
        real(wp) :: start_s = 0
        real(wp) :: last_event = 0           !! the engine's record of simultaneous impacts
        integer :: same_instant = 0
        logical :: has_tangent = .false.     !! with &lyapunov:
        real(wp), allocatable :: tangent(:, :)      !! (n_vectors, 2n), as the engine keeps it
        integer :: tangent_scale_bits = 0
        real(wp), allocatable :: tangent_log(:)     !! (n_vectors): growth kept by the engine
        integer(i8) :: rank_losses = 0              !! singular tangent maps since the QR step
        real(wp) :: jumps_volume = 0                !! ln |det| of the jumps since then
        integer(i8), allocatable :: lyapunov_int(:) !! the accumulator (lyapunov_pack)
        real(wp), allocatable :: lyapunov_real(:)
        integer(i8) :: impacts = 0, sticks = 0, releases = 0, touches = 0 !! /stats
        integer(i8), allocatable :: site_counts(:)
        real(wp), allocatable :: x_last(:, :), v_last(:, :) !! (n, m): the last m records
    end type resume_data_t

    type :: output_t
        integer(hid_t) :: file = -1
        character(len=:), allocatable :: path, part_path
        integer :: n = 0
        integer(i8) :: n_events = 0
        logical :: events_created = .false.
    end type output_t

contains

    !> The funnel for every HDF5 status code. A negative `status` becomes an error naming the
    !> call, the object (`/group/dataset`, or an attribute of one) and the file; an error that
    !> is already set is kept, because it is the first failure, the one to report.
    subroutine check(status, call_name, object, file, err)
        integer, intent(in) :: status
        character(len=*), intent(in) :: call_name, object, file
        type(error_t), allocatable, intent(inout) :: err

        if (status >= 0 .or. allocated(err)) return
        call set_error(err, "hdf5: "//call_name//" failed on "//object//" (file "//file//")")
    end subroutine check

    !> The HDF5 library, initialised (its H5T_* constants are set by h5open_f) and told to
    !> return errors to us rather than print them.
    subroutine open_library(file, err)
        character(len=*), intent(in) :: file
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        call h5open_f(e)
        call check(e, 'h5open_f', 'the HDF5 library', file, err)
        if (allocated(err)) return
        call h5eset_auto_f(0, e)
        call check(e, 'h5eset_auto_f', 'the HDF5 library', file, err)
    end subroutine open_library

    !> Refuse an existing file (unless overwrite) or an unwritable place, before any run starts;
    !> then create `path.part`.
    subroutine output_begin(out, path, overwrite, err)
        type(output_t), intent(out) :: out
        character(len=*), intent(in) :: path
        logical, intent(in) :: overwrite
        type(error_t), allocatable, intent(out) :: err
        logical :: exists
        integer :: e

        out%path = path
        out%part_path = path//'.part'
        inquire (file=path, exist=exists)
        if (exists .and. .not. overwrite) then
            call set_error(err, "&output: file = '"//path//"' exists; choose another name "// &
                           "or set overwrite = .true.")
            return
        end if
        call open_library(out%part_path, err)
        if (allocated(err)) return
        call h5fcreate_f(out%part_path, H5F_ACC_TRUNC_F, out%file, e)
        call check(e, 'h5fcreate_f', '/', out%part_path, err)
        if (allocated(err)) then
            out%file = -1
            err%message = "&output: cannot create '"//out%part_path// &
                          "' (missing directory or no permission to write there; "// &
                          err%message//")"
        end if
    end subroutine output_begin

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
        call attr_int(out, '/', 'schema_version', schema_version, err)
        call attr_string(out, '/', 'code_version', code_version, err)
        call attr_string(out, '/', 'input_namelist', input_text, err)
        call attr_string(out, '/', 'resolved_namelist', summary, err)
        call attr_int(out, '/', 'complete', 0, err)
        if (allocated(err)) return
        call output_group(out, 'params', err)
        if (allocated(err)) return
        call attr_int(out, 'params', 'n', n, err)
        call attr_real(out, 'params', 'damping', damping, err)
        call attr_real(out, 'params', 'restitution', restitution, err)
        call attr_real(out, 'params', 'amplitude', amplitude, err)
        call attr_real(out, 'params', 'omega', omega, err)
        call attr_string(out, 'params', 'boundary', boundary, err)
        call attr_real(out, 'params', 'drive_period', period, err)
        call attr_real(out, 'params', 'phase', phase, err)
        ! cycle counts go up to 1e12: 64-bit in the file as in memory
        call attr_int8(out, 'params', 'transient', transient, err)
        call attr_int8(out, 'params', 'cycles', cycles, err)
        if (allocated(err)) return
        call write_real_1d(out, 'params/spacing', spacing, 'length', err)
        if (allocated(err)) return
        call output_group(out, 'initial', err)
        if (allocated(err)) return
        call write_real_1d(out, 'initial/x', x0, 'length', err)
        if (allocated(err)) return
        call write_real_1d(out, 'initial/v', v0, 'length/time', err)
    end subroutine output_header

    !> Create a group (once).
    subroutine output_group(out, name, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: name
        type(error_t), allocatable, intent(out) :: err
        integer(hid_t) :: g
        integer :: e
        logical :: exists

        call h5lexists_f(out%file, name, exists, e)
        call check(e, 'h5lexists_f', '/'//name, out%part_path, err)
        if (allocated(err) .or. exists) return
        call h5gcreate_f(out%file, name, g, e)
        call check(e, 'h5gcreate_f', '/'//name, out%part_path, err)
        if (allocated(err)) return
        call h5gclose_f(g, e)
        call check(e, 'h5gclose_f', '/'//name, out%part_path, err)
    end subroutine output_group

    !> Write strobe records first .. first+m-1 (x, v of shape (n, m)) of n_records in all.
    subroutine output_strobe_write(out, n_records, first, x, v, cycle, err)
        type(output_t), intent(inout) :: out
        integer(i8), intent(in) :: n_records, first
        real(wp), intent(in), target, contiguous :: x(:, :), v(:, :)
        integer(i8), intent(in), target, contiguous :: cycle(:)
        type(error_t), allocatable, intent(out) :: err
        integer(hsize_t) :: dims(2), block(2), offset(2)
        integer :: m

        m = size(x, 2)
        dims = [int(out%n, hsize_t), int(n_records, hsize_t)]
        block = [int(out%n, hsize_t), int(m, hsize_t)]
        offset = [0_hsize_t, int(first - 1, hsize_t)]
        if (first == 1) then
            call output_group(out, 'strobe', err)
            if (allocated(err)) return
            call create_fixed(out, 'strobe/x', H5T_NATIVE_DOUBLE, dims, 'length', err)
            if (allocated(err)) return
            call create_fixed(out, 'strobe/v', H5T_NATIVE_DOUBLE, dims, 'length/time', err)
            if (allocated(err)) return
            call create_fixed(out, 'strobe/cycle', H5T_STD_I64LE, dims(2:2), 'drive cycles', err)
            if (allocated(err)) return
        end if
        call write_slab(out, 'strobe/x', offset, block, .false., H5T_NATIVE_DOUBLE, c_loc(x), err)
        if (allocated(err)) return
        call write_slab(out, 'strobe/v', offset, block, .false., H5T_NATIVE_DOUBLE, c_loc(v), err)
        if (allocated(err)) return
        call write_slab(out, 'strobe/cycle', offset(2:2), block(2:2), .false., &
                        h5kind_to_type(i8, H5_INTEGER_KIND), c_loc(cycle), err)
    end subroutine output_strobe_write

    !> Append events to the extendible /events datasets.
    subroutine output_events_append(out, time, site, speed, kind, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in), target, contiguous :: time(:), speed(:)
        integer, intent(in), target, contiguous :: site(:), kind(:)
        type(error_t), allocatable, intent(out) :: err
        integer(hsize_t) :: offset(1), block(1)

        if (.not. out%events_created) then
            call output_group(out, 'events', err)
            if (allocated(err)) return
            call create_extendible(out, 'events/time', H5T_NATIVE_DOUBLE, 'time', err)
            if (.not. allocated(err)) &
                call create_extendible(out, 'events/site', H5T_NATIVE_INTEGER, &
                                       'bond index (0 = left wall, n = right wall)', err)
            if (.not. allocated(err)) &
                call create_extendible(out, 'events/speed', H5T_NATIVE_DOUBLE, 'length/time', err)
            if (.not. allocated(err)) &
                call create_extendible(out, 'events/kind', H5T_NATIVE_INTEGER, &
                                       '0 impact, 1 impact starting a sticking contact, '// &
                                       '2 release, 3 touch (no impulse)', err)
            if (allocated(err)) return
            out%events_created = .true.
        end if
        if (size(time) == 0) return
        offset = [int(out%n_events, hsize_t)]
        block = [int(size(time), hsize_t)]
        call write_slab(out, 'events/time', offset, block, .true., H5T_NATIVE_DOUBLE, &
                        c_loc(time), err)
        if (.not. allocated(err)) call write_slab(out, 'events/site', offset, block, .true., &
                                                  H5T_NATIVE_INTEGER, c_loc(site), err)
        if (.not. allocated(err)) call write_slab(out, 'events/speed', offset, block, .true., &
                                                  H5T_NATIVE_DOUBLE, c_loc(speed), err)
        if (.not. allocated(err)) call write_slab(out, 'events/kind', offset, block, .true., &
                                                  H5T_NATIVE_INTEGER, c_loc(kind), err)
        if (.not. allocated(err)) out%n_events = out%n_events + size(time)
    end subroutine output_events_append

    !> /final: everything needed to continue bit-for-bit.
    subroutine output_final(out, x, v, cycle, phase, time_in_cycle, contact, queue_time, &
                            queue_action, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in), contiguous :: x(:), v(:), queue_time(:)
        real(wp), intent(in) :: phase, time_in_cycle
        integer(i8), intent(in) :: cycle
        integer, intent(in), contiguous :: contact(:), queue_action(:)
        type(error_t), allocatable, intent(out) :: err

        call output_group(out, 'final', err)
        if (allocated(err)) return
        call write_real_1d(out, 'final/x', x, 'length', err)
        if (.not. allocated(err)) call write_real_1d(out, 'final/v', v, 'length/time', err)
        if (.not. allocated(err)) call write_real_1d(out, 'final/phase', [phase], 'radians', err)
        if (.not. allocated(err)) call write_real_1d(out, 'final/time_in_cycle', &
                                                     [time_in_cycle], 'time', err)
        if (.not. allocated(err)) call write_int_1d(out, 'final/contact', contact, &
                                                    '-1 resting on left wall, 1 right, 0 free', err)
        if (.not. allocated(err)) &
            call write_real_1d(out, 'final/event_time', queue_time, &
                               'time within the drive cycle', err)
        if (.not. allocated(err)) call write_int_1d(out, 'final/event_action', &
                                                    queue_action, &
                                                    '0 none, 1 impact, 2 release, 3 recheck', err)
        if (.not. allocated(err)) call write_scalar_int8(out, 'final/cycle', cycle, &
                                                         'drive cycles', err)
    end subroutine output_final

    subroutine output_stats(out, collisions_per_cycle, impacts, sticks, releases, touches, &
                            site_counts, cycles_done, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in) :: collisions_per_cycle
        integer(i8), intent(in) :: impacts, sticks, releases, touches, cycles_done
        integer(i8), intent(in), target, contiguous :: site_counts(:)
        type(error_t), allocatable, intent(out) :: err
        integer(hsize_t) :: dims(1)

        call output_group(out, 'stats', err)
        if (allocated(err)) return
        call attr_real(out, 'stats', 'collisions_per_cycle', collisions_per_cycle, err)
        call attr_int8(out, 'stats', 'impacts', impacts, err)
        call attr_int8(out, 'stats', 'sticks', sticks, err)
        call attr_int8(out, 'stats', 'releases', releases, err)
        call attr_int8(out, 'stats', 'touches', touches, err)
        if (allocated(err)) return
        dims = [int(size(site_counts), hsize_t)]
        call write_dataset(out, 'stats/site_counts', H5T_STD_I64LE, &
                           h5kind_to_type(i8, H5_INTEGER_KIND), dims, c_loc(site_counts), &
                           'impacts', err)
        ! /params/cycles is the number planned; a run stopped early did fewer
        if (.not. allocated(err)) call write_scalar_int8(out, 'stats/cycles_done', cycles_done, &
                                                         'drive cycles', err)
    end subroutine output_stats

    subroutine output_periods(out, period, err)
        type(output_t), intent(inout) :: out
        integer, intent(in), contiguous :: period(:)
        type(error_t), allocatable, intent(out) :: err

        call write_int_1d(out, 'strobe/period', period, 'drive cycles (0 = aperiodic)', err)
    end subroutine output_periods

    !> /lyapunov; `running_bits(k, rows)` are the running estimates at drive cycles
    !> `running_cycle(rows)` (a bounded selection of the QR steps: chain_lyapunov).
    subroutine output_lyapunov(out, bits, per_time, stderr_bits, running_bits, running_cycle, &
                               ky, positive_sum, collisions_per_cycle, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in), contiguous :: bits(:), per_time(:), stderr_bits(:)
        real(wp), intent(in), contiguous :: running_bits(:, :)
        integer(i8), intent(in), target, contiguous :: running_cycle(:)
        real(wp), intent(in) :: ky, positive_sum, collisions_per_cycle
        type(error_t), allocatable, intent(out) :: err

        call output_group(out, 'lyapunov', err)
        if (.not. allocated(err)) call write_real_1d(out, 'lyapunov/exponents', bits, &
                                                     'bits per drive cycle', err)
        if (.not. allocated(err)) &
            call write_real_1d(out, 'lyapunov/exponents_per_time', per_time, &
                               'nats per unit time', err)
        if (.not. allocated(err)) call write_real_1d(out, 'lyapunov/stderr', stderr_bits, &
                                                     'bits per drive cycle', err)
        if (.not. allocated(err)) call write_real_2d(out, 'lyapunov/running', running_bits, &
                                                     'bits per drive cycle', err)
        if (.not. allocated(err)) &
            call write_dataset(out, 'lyapunov/running_cycle', H5T_STD_I64LE, &
                               h5kind_to_type(i8, H5_INTEGER_KIND), &
                               [int(size(running_cycle), hsize_t)], c_loc(running_cycle), &
                               'drive cycles', err)
        if (allocated(err)) return
        call attr_real(out, 'lyapunov', 'ky_dimension', ky, err)
        call attr_real(out, 'lyapunov', 'positive_sum', positive_sum, err)
        call attr_real(out, 'lyapunov', 'collisions_per_cycle', collisions_per_cycle, err)
    end subroutine output_lyapunov

    subroutine output_jacobian(out, jacobian, re, im, cycles, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in) :: jacobian(:, :)
        real(wp), intent(in), contiguous :: re(:), im(:)
        integer, intent(in) :: cycles
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: stored(:, :)

        ! rows of the Jacobian are rows in h5py
        stored = transpose(jacobian)
        call output_group(out, 'floquet', err)
        if (.not. allocated(err)) call write_real_2d(out, 'floquet/jacobian', stored, '1', err)
        if (.not. allocated(err)) call write_real_1d(out, 'floquet/multipliers_re', re, &
                                                     '1', err)
        if (.not. allocated(err)) call write_real_1d(out, 'floquet/multipliers_im', im, &
                                                     '1', err)
        if (.not. allocated(err)) call attr_int(out, 'floquet', 'cycles', cycles, err)
    end subroutine output_jacobian

    !> Attributes of /sweep: the swept parameters and the mode.
    subroutine output_sweep_attributes(out, parameter, parameter2, mode, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: parameter, parameter2, mode
        type(error_t), allocatable, intent(out) :: err

        call attr_string(out, 'sweep', 'parameter', parameter, err)
        call attr_string(out, 'sweep', 'parameter2', parameter2//' ', err)
        call attr_string(out, 'sweep', 'mode', mode, err)
    end subroutine output_sweep_attributes

    !> One integer sweep dataset, stored as given (Fortran order).
    subroutine output_sweep_write_int(out, name, values, dims, units, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: name, units
        integer, intent(in), target :: values(*)
        integer(hsize_t), intent(in) :: dims(:)
        type(error_t), allocatable, intent(out) :: err

        call write_dataset(out, name, H5T_NATIVE_INTEGER, H5T_NATIVE_INTEGER, dims, &
                           c_loc(values(1)), units, err)
    end subroutine output_sweep_write_int

    !> One sweep dataset: a real array of any rank up to 3, stored as given (Fortran order).
    subroutine output_sweep_write(out, name, values, dims, units, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: name, units
        real(wp), intent(in), target :: values(*)
        integer(hsize_t), intent(in) :: dims(:)
        type(error_t), allocatable, intent(out) :: err

        call write_dataset(out, name, H5T_NATIVE_DOUBLE, H5T_NATIVE_DOUBLE, dims, &
                           c_loc(values(1)), units, err)
    end subroutine output_sweep_write

    !> A run stopped early keeps only its finished records: shrink /strobe to them.
    subroutine output_truncate_strobe(out, records_done, err)
        type(output_t), intent(inout) :: out
        integer(i8), intent(in) :: records_done
        type(error_t), allocatable, intent(out) :: err
        character(len=12), parameter :: names(3) = &
            [character(len=12) :: 'strobe/x', 'strobe/v', 'strobe/cycle']
        integer(hsize_t) :: dims(2)
        integer :: j
        logical :: exists

        call link_exists(out%file, out%part_path, 'strobe', exists, err)
        if (allocated(err) .or. .not. exists) return
        dims = [int(out%n, hsize_t), int(records_done, hsize_t)]
        do j = 1, size(names)
            if (j == 3) then
                call set_extent(out, trim(names(j)), dims(2:2), err)
            else
                call set_extent(out, trim(names(j)), dims, err)
            end if
            if (allocated(err)) return
        end do
    end subroutine output_truncate_strobe

    !> Mark complete (or partial), close, and move `.part` to the final name.
    subroutine output_end(out, complete, err)
        type(output_t), intent(inout) :: out
        logical, intent(in) :: complete
        type(error_t), allocatable, intent(out) :: err
        integer :: e

        call attr_int(out, '/', 'complete', merge(1, 0, complete), err)
        call h5fclose_f(out%file, e)
        call check(e, 'h5fclose_f', '/', out%part_path, err)
        out%file = -1
        if (allocated(err)) return
        call rename_file(out%part_path, out%path, err)
    end subroutine output_end

    !> Close and delete the partial file after an error. The error that brought us here is
    !> the one reported; a failure to close the file now is part of it (the file is deleted).
    subroutine output_abort(out)
        type(output_t), intent(inout) :: out
        type(error_t), allocatable :: ignored
        integer :: e

        if (out%file >= 0) then
            call h5fclose_f(out%file, e)
            call check(e, 'h5fclose_f', '/', out%part_path, ignored)
        end if
        out%file = -1
        if (allocated(out%part_path)) call remove_file(out%part_path)
    end subroutine output_abort

    !> /resume of a run stopped early (see resume_data_t).
    subroutine output_resume(out, data, err)
        type(output_t), intent(inout) :: out
        type(resume_data_t), intent(in), target :: data
        type(error_t), allocatable, intent(out) :: err

        call output_group(out, 'resume', err)
        if (.not. allocated(err)) call write_scalar_int8(out, 'resume/start_cycle', &
                                                         data%start_cycle, 'drive cycles', err)
        if (.not. allocated(err)) call write_real_1d(out, 'resume/start_time_in_cycle', &
                                                     [data%start_s], 'time', err)
        if (.not. allocated(err)) call write_real_1d(out, 'resume/last_event', &
                                                     [data%last_event], &
                                                     'time within the drive cycle', err)
        if (.not. allocated(err)) call write_int_1d(out, 'resume/same_instant', &
                                                    [data%same_instant], &
                                                    'impacts at the time of last_event', err)
        if (allocated(err) .or. .not. data%has_tangent) return
        call write_real_2d(out, 'resume/tangent', data%tangent, &
                           '1 (times 2**-tangent_scale_bits)', err)
        if (.not. allocated(err)) call write_int_1d(out, 'resume/tangent_scale_bits', &
                                                    [data%tangent_scale_bits], '1', err)
        if (.not. allocated(err)) call write_real_1d(out, 'resume/tangent_log', &
                                                     data%tangent_log, '1', err)
        if (.not. allocated(err)) call write_scalar_int8(out, 'resume/rank_losses', &
                                                         data%rank_losses, '1', err)
        if (.not. allocated(err)) call write_real_1d(out, 'resume/jumps_volume', &
                                                     [data%jumps_volume], '1', err)
        if (.not. allocated(err)) &
            call write_dataset(out, 'resume/lyapunov_int', H5T_STD_I64LE, &
                               h5kind_to_type(i8, H5_INTEGER_KIND), &
                               [int(size(data%lyapunov_int), hsize_t)], &
                               c_loc(data%lyapunov_int), '1', err)
        if (.not. allocated(err)) call write_real_1d(out, 'resume/lyapunov_real', &
                                                     data%lyapunov_real, 'nats', err)
    end subroutine output_resume

    !> What a continuation of the run stopped early in `path` needs besides /final: /resume,
    !> the counters of /stats, and the last min(cycles done, window) strobe records.
    subroutine read_resume(path, n, with_tangent, window, data, err)
        character(len=*), intent(in) :: path
        integer, intent(in) :: n, window
        logical, intent(in) :: with_tangent
        type(resume_data_t), intent(out), target :: data
        type(error_t), allocatable, intent(out) :: err
        type(output_t) :: src
        integer(hsize_t), allocatable :: dims(:)
        integer :: scalar(1), m
        real(wp) :: volume(1)

        call open_for_reading(path, '&output', src, err)
        if (allocated(err)) return
        allocate (data%site_counts(n + 1))
        call read_int8_scalar(src, 'stats/cycles_done', data%cycles_done, err)
        call read_attr_int8(src, 'stats', 'impacts', data%impacts, err)
        call read_attr_int8(src, 'stats', 'sticks', data%sticks, err)
        call read_attr_int8(src, 'stats', 'releases', data%releases, err)
        call read_attr_int8(src, 'stats', 'touches', data%touches, err)
        call read_dataset(src, 'stats/site_counts', h5kind_to_type(i8, H5_INTEGER_KIND), &
                          [int(n + 1, hsize_t)], c_loc(data%site_counts), err)
        call read_int8_scalar(src, 'resume/start_cycle', data%start_cycle, err)
        call read_real_scalar(src, 'resume/start_time_in_cycle', data%start_s, err)
        call read_real_scalar(src, 'resume/last_event', data%last_event, err)
        call read_int_1d(src, 'resume/same_instant', scalar, err)
        data%same_instant = scalar(1)
        data%has_tangent = with_tangent
        if (with_tangent) then
            call read_real_2d(src, 'resume/tangent', data%tangent, err)
            call read_int_1d(src, 'resume/tangent_scale_bits', scalar, err)
            data%tangent_scale_bits = scalar(1)
            if (allocated(data%tangent)) allocate (data%tangent_log(size(data%tangent, 1)))
            if (allocated(data%tangent_log)) &
                call read_real_1d(src, 'resume/tangent_log', data%tangent_log, err)
            call read_int8_scalar(src, 'resume/rank_losses', data%rank_losses, err)
            call read_real_1d(src, 'resume/jumps_volume', volume, err)
            data%jumps_volume = volume(1)
            call dataset_extent(src, 'resume/lyapunov_int', dims, err)
            if (.not. allocated(err)) then
                allocate (data%lyapunov_int(product(dims)))
                call read_dataset(src, 'resume/lyapunov_int', &
                                  h5kind_to_type(i8, H5_INTEGER_KIND), dims, &
                                  c_loc(data%lyapunov_int), err)
            end if
            call dataset_extent(src, 'resume/lyapunov_real', dims, err)
            if (.not. allocated(err)) then
                allocate (data%lyapunov_real(product(dims)))
                call read_real_1d(src, 'resume/lyapunov_real', data%lyapunov_real, err)
            end if
        end if
        if (.not. allocated(err)) then
            m = int(min(data%cycles_done, int(window, i8)))
            if (data%cycles_done < 1) call set_error(err, "hdf5: /stats/cycles_done = "// &
                                                     fmt_int8(data%cycles_done)// &
                                                     " is not a stopped run's (file "// &
                                                     path//")")
        end if
        if (.not. allocated(err)) then
            allocate (data%x_last(n, m), data%v_last(n, m))
            call read_slab(src, 'strobe/x', [0_hsize_t, int(data%cycles_done - m, hsize_t)], &
                           [int(n, hsize_t), int(m, hsize_t)], c_loc(data%x_last), err)
            call read_slab(src, 'strobe/v', [0_hsize_t, int(data%cycles_done - m, hsize_t)], &
                           [int(n, hsize_t), int(m, hsize_t)], c_loc(data%v_last), err)
        end if
        if (allocated(err)) then
            if (err%message(1:5) == 'hdf5:') err%message = "&output: cannot continue the "// &
                                                          "run stopped early in '"//path// &
                                                          "': "//err%message
        end if
        call close_file(src, err)
    end subroutine read_resume

    !> What is under an output file's name (file_absent, file_continuable, ...), for a run of
    !> `input_text` about to write there. Anything unreadable is file_other.
    subroutine output_inspect(path, input_text, kind)
        character(len=*), intent(in) :: path, input_text
        integer, intent(out) :: kind
        type(output_t) :: src
        type(error_t), allocatable :: err
        integer(i8) :: complete
        character(len=:), allocatable :: text
        logical :: exists

        inquire (file=path, exist=exists)
        kind = merge(file_other, file_absent, exists)
        if (.not. exists) return
        call open_for_reading(path, '&output', src, err)
        if (allocated(err)) return
        call read_attr_int8(src, '/', 'complete', complete, err)
        call link_exists(src%file, path, 'resume', exists, err)
        call read_attr_string(src, '/', 'input_namelist', text, err)
        if (.not. allocated(err) .and. complete == 0 .and. exists) then
            ! (trailing blanks of the text are not stored)
            kind = merge(file_continuable, file_other_input, text == input_text)
        end if
        call close_file(src, err)
    end subroutine output_inspect

    !> Reopen the run stopped early in `path` to continue it: a copy `path.part` (the file
    !> under the final name stays as it is until the continuation ends), without the results
    !> that the end of the run writes again (/final, /stats, /lyapunov, /floquet, /resume,
    !> /strobe/period), with /strobe back at `n_records` records.
    subroutine output_continue(out, path, n, n_records, err)
        type(output_t), intent(out) :: out
        character(len=*), intent(in) :: path
        integer, intent(in) :: n
        integer(i8), intent(in) :: n_records
        type(error_t), allocatable, intent(out) :: err
        character(len=14), parameter :: results(6) = [character(len=14) :: 'final', 'stats', &
                                                      'lyapunov', 'floquet', 'resume', &
                                                      'strobe/period']
        integer(hsize_t), allocatable :: dims(:)
        integer :: j, e
        logical :: exists

        out%path = path
        out%part_path = path//'.part'
        out%n = n
        call copy_file(path, out%part_path, err)
        if (allocated(err)) return
        call open_library(out%part_path, err)
        if (.not. allocated(err)) then
            call h5fopen_f(out%part_path, H5F_ACC_RDWR_F, out%file, e)
            call check(e, 'h5fopen_f', '/', out%part_path, err)
            if (allocated(err)) out%file = -1
        end if
        do j = 1, size(results)
            call link_exists(out%file, out%part_path, trim(results(j)), exists, err)
            if (allocated(err)) exit
            if (.not. exists) cycle
            call h5ldelete_f(out%file, trim(results(j)), e)
            call check(e, 'h5ldelete_f', '/'//trim(results(j)), out%part_path, err)
        end do
        if (.not. allocated(err)) call set_extent(out, 'strobe/x', &
                                                  [int(n, hsize_t), int(n_records, hsize_t)], err)
        if (.not. allocated(err)) call set_extent(out, 'strobe/v', &
                                                  [int(n, hsize_t), int(n_records, hsize_t)], err)
        if (.not. allocated(err)) call set_extent(out, 'strobe/cycle', &
                                                  [int(n_records, hsize_t)], err)
        if (.not. allocated(err)) call link_exists(out%file, out%part_path, 'events', &
                                                   out%events_created, err)
        if (.not. allocated(err) .and. out%events_created) then
            call dataset_extent(out, 'events/time', dims, err)
            if (.not. allocated(err)) out%n_events = int(dims(1), i8)
        end if
        if (allocated(err)) call output_abort(out)
    end subroutine output_continue

    !> The final state of an earlier run, to continue from it.
    subroutine read_final_state(path, n, x, v, cycle, phase, contact, queue_time, &
                                queue_action, time_in_cycle, model, spacing, boundary, err)
        character(len=*), intent(in) :: path
        integer, intent(in) :: n
        real(wp), allocatable, intent(out) :: x(:), v(:), queue_time(:)
        integer(i8), intent(out) :: cycle
        real(wp), intent(out) :: phase, time_in_cycle
        real(wp), intent(out) :: model(4) !! damping, restitution, amplitude, omega of the file
        real(wp), allocatable, intent(out) :: spacing(:)
        character(len=8), intent(out) :: boundary
        integer, allocatable, intent(out) :: contact(:), queue_action(:)
        type(error_t), allocatable, intent(out) :: err
        type(output_t) :: src
        integer(i8) :: version, n_file
        character(len=:), allocatable :: text
        logical :: exists

        cycle = 0
        phase = 0
        time_in_cycle = 0
        model = 0
        boundary = ''
        allocate (x(n), v(n), queue_time(n + 1), contact(n), queue_action(n + 1))
        allocate (spacing(n + 1))
        call open_for_reading(path, '&initial', src, err)
        if (allocated(err)) return
        call read_attr_int8(src, '/', 'schema_version', version, err)
        if (.not. allocated(err)) then
            if (version /= schema_version) call set_error(err, "&initial: file = '"//path// &
                                                          "' is not an impactchain output "// &
                                                          "of schema version 1")
        end if
        if (.not. allocated(err)) call read_attr_int8(src, 'params', 'n', n_file, err)
        if (.not. allocated(err)) then
            if (n_file /= n) call set_error(err, "&initial: file = '"//path//"' has n = "// &
                                            fmt_int8(n_file)//" oscillators, the input n = "// &
                                            fmt_int(n))
        end if
        if (.not. allocated(err)) call link_exists(src%file, path, 'final', exists, err)
        if (.not. allocated(err) .and. .not. exists) &
            call set_error(err, "&initial: file = '"//path//"' has no /final state")
        if (.not. allocated(err)) then
            call read_real_1d(src, 'final/x', x, err)
            call read_real_1d(src, 'final/v', v, err)
            call read_int_1d(src, 'final/contact', contact, err)
            call read_real_1d(src, 'final/event_time', queue_time, err)
            call read_int_1d(src, 'final/event_action', queue_action, err)
            call read_real_scalar(src, 'final/phase', phase, err)
            call read_real_scalar(src, 'final/time_in_cycle', time_in_cycle, err)
            call read_int8_scalar(src, 'final/cycle', cycle, err)
            call read_attr_real(src, 'params', 'damping', model(1), err)
            call read_attr_real(src, 'params', 'restitution', model(2), err)
            call read_attr_real(src, 'params', 'amplitude', model(3), err)
            call read_attr_real(src, 'params', 'omega', model(4), err)
            call read_attr_string(src, 'params', 'boundary', text, err)
            if (.not. allocated(err)) boundary = text
            call read_real_1d(src, 'params/spacing', spacing, err)
            if (allocated(err)) then
                if (err%message(1:5) == 'hdf5:') err%message = "&initial: "//err%message
            end if
        end if
        call close_file(src, err)
    end subroutine read_final_state

    ! ---- reading ---------------------------------------------------------------------------

    !> Open an existing file read-only (`where` names the input that points at it).
    subroutine open_for_reading(path, where, src, err)
        character(len=*), intent(in) :: path, where
        type(output_t), intent(out) :: src
        type(error_t), allocatable, intent(out) :: err
        logical :: exists, is_hdf5
        integer :: e

        src%path = path
        src%part_path = path   ! the name in messages
        inquire (file=path, exist=exists)
        if (.not. exists) then
            call set_error(err, where//": file = '"//path//"' does not exist")
            return
        end if
        call open_library(path, err)
        if (allocated(err)) return
        call h5fis_hdf5_f(path, is_hdf5, e)
        call check(e, 'h5fis_hdf5_f', '/', path, err)
        if (allocated(err)) then
            err%message = where//": "//err%message
            return
        end if
        if (.not. is_hdf5) then
            call set_error(err, where//": file = '"//path//"' is not an HDF5 file")
            return
        end if
        call h5fopen_f(path, H5F_ACC_RDONLY_F, src%file, e)
        call check(e, 'h5fopen_f', '/', path, err)
        if (allocated(err)) then
            src%file = -1
            err%message = where//": "//err%message//"; the file is damaged or truncated"
        end if
    end subroutine open_for_reading

    !> Close a file opened for reading (keeps an earlier error).
    subroutine close_file(src, err)
        type(output_t), intent(inout) :: src
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        if (src%file < 0) return
        call h5fclose_f(src%file, e)
        call check(e, 'h5fclose_f', '/', src%part_path, err)
        src%file = -1
    end subroutine close_file

    !> Read dataset `name` whole into `buf` (memory type `mem_type`), after checking that its
    !> extents are `dims` (rank 0: a scalar, or one value). Nothing is read after an error.
    subroutine read_dataset(src, name, mem_type, dims, buf, err)
        type(output_t), intent(in) :: src
        character(len=*), intent(in) :: name
        integer(hid_t), intent(in) :: mem_type
        integer(hsize_t), intent(in) :: dims(:)
        type(c_ptr), intent(in) :: buf
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: dset
        integer(hsize_t), allocatable :: found(:)
        integer :: e
        type(c_ptr) :: target_buf ! (h5dread_f wants a definable pointer)

        if (allocated(err)) return
        call h5dopen_f(src%file, name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, src%part_path, err)
        if (allocated(err)) return
        call dataset_dims(src, dset, name, found, err)
        if (.not. allocated(err)) then
            if (.not. same_extent(found, dims)) &
                call set_error(err, "hdf5: /"//name//" has shape "//dims_text(found)// &
                               ", expected "//dims_text(dims)//" (file "//src%part_path//")")
        end if
        if (.not. allocated(err)) then
            target_buf = buf
            call h5dread_f(dset, mem_type, target_buf, e)
            call check(e, 'h5dread_f', '/'//name, src%part_path, err)
        end if
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, src%part_path, err)
    end subroutine read_dataset

    !> Extents of an open dataset (Fortran order; none for a scalar).
    subroutine dataset_dims(src, dset, name, dims, err)
        type(output_t), intent(in) :: src
        integer(hid_t), intent(in) :: dset
        character(len=*), intent(in) :: name
        integer(hsize_t), allocatable, intent(out) :: dims(:)
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: space
        integer(hsize_t), allocatable :: maxdims(:)
        integer :: e, rank

        allocate (dims(0))
        call h5dget_space_f(dset, space, e)
        call check(e, 'h5dget_space_f', '/'//name, src%part_path, err)
        if (allocated(err)) return
        call h5sget_simple_extent_ndims_f(space, rank, e)
        call check(e, 'h5sget_simple_extent_ndims_f', '/'//name, src%part_path, err)
        if (.not. allocated(err)) then
            deallocate (dims)
            allocate (dims(rank), maxdims(rank))
            ! (returns the rank on success)
            call h5sget_simple_extent_dims_f(space, dims, maxdims, e)
            call check(e, 'h5sget_simple_extent_dims_f', '/'//name, src%part_path, err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', '/'//name, src%part_path, err)
    end subroutine dataset_dims

    !> Do extents `found` hold what `want` asks for (rank 0: one value, as a scalar or (1,))?
    pure logical function same_extent(found, want)
        integer(hsize_t), intent(in) :: found(:), want(:)

        if (size(want) == 0) then
            same_extent = product(found) == 1
        else
            same_extent = size(found) == size(want)
            if (same_extent) same_extent = all(found == want)
        end if
    end function same_extent

    !> Extents as h5py shows them: "(3, 16)" for a Fortran (16, 3).
    pure function dims_text(dims) result(text)
        integer(hsize_t), intent(in) :: dims(:)
        character(len=:), allocatable :: text
        integer :: j

        text = '('
        do j = size(dims), 1, -1
            text = text//fmt_int8(int(dims(j), i8))
            if (j > 1) text = text//', '
        end do
        if (size(dims) == 1) text = text//','
        text = text//')'
    end function dims_text

    !> Extents of dataset `name` (Fortran order).
    subroutine dataset_extent(src, name, dims, err)
        type(output_t), intent(in) :: src
        character(len=*), intent(in) :: name
        integer(hsize_t), allocatable, intent(out) :: dims(:)
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: dset
        integer :: e

        allocate (dims(0))
        if (allocated(err)) return
        call h5dopen_f(src%file, name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, src%part_path, err)
        if (allocated(err)) return
        call dataset_dims(src, dset, name, dims, err)
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, src%part_path, err)
    end subroutine dataset_extent

    !> A 2-D real dataset, whatever its extents.
    subroutine read_real_2d(src, name, values, err)
        type(output_t), intent(in) :: src
        character(len=*), intent(in) :: name
        real(wp), allocatable, target, intent(out) :: values(:, :)
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t), allocatable :: dims(:)

        allocate (values(0, 0))
        call dataset_extent(src, name, dims, err)
        if (allocated(err)) return
        if (size(dims) /= 2) then
            call set_error(err, "hdf5: /"//name//" has shape "//dims_text(dims)// &
                           ", expected two axes (file "//src%part_path//")")
            return
        end if
        deallocate (values)
        allocate (values(dims(1), dims(2)))
        call read_dataset(src, name, H5T_NATIVE_DOUBLE, dims, c_loc(values), err)
    end subroutine read_real_2d

    !> Read the hyperslab offset/block of a real dataset into `buf`.
    subroutine read_slab(src, name, offset, block, buf, err)
        type(output_t), intent(in) :: src
        character(len=*), intent(in) :: name
        integer(hsize_t), intent(in) :: offset(:), block(:)
        type(c_ptr), intent(in) :: buf
        type(error_t), allocatable, intent(inout) :: err

        call transfer_slab(src, name, offset, block, H5T_NATIVE_DOUBLE, buf, .false., .false., &
                           err)
    end subroutine read_slab

    subroutine read_real_1d(src, name, values, err)
        type(output_t), intent(in) :: src
        character(len=*), intent(in) :: name
        real(wp), intent(out), target, contiguous :: values(:)
        type(error_t), allocatable, intent(inout) :: err

        values = 0
        call read_dataset(src, name, H5T_NATIVE_DOUBLE, [int(size(values), hsize_t)], &
                          c_loc(values), err)
    end subroutine read_real_1d

    subroutine read_int_1d(src, name, values, err)
        type(output_t), intent(in) :: src
        character(len=*), intent(in) :: name
        integer, intent(out), target, contiguous :: values(:)
        type(error_t), allocatable, intent(inout) :: err

        values = 0
        call read_dataset(src, name, H5T_NATIVE_INTEGER, [int(size(values), hsize_t)], &
                          c_loc(values), err)
    end subroutine read_int_1d

    subroutine read_real_scalar(src, name, value, err)
        type(output_t), intent(in) :: src
        character(len=*), intent(in) :: name
        real(wp), intent(out), target :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: scalar(0)

        value = 0
        call read_dataset(src, name, H5T_NATIVE_DOUBLE, scalar, c_loc(value), err)
    end subroutine read_real_scalar

    subroutine read_int8_scalar(src, name, value, err)
        type(output_t), intent(in) :: src
        character(len=*), intent(in) :: name
        integer(i8), intent(out), target :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: scalar(0)

        value = 0
        call read_dataset(src, name, h5kind_to_type(i8, H5_INTEGER_KIND), scalar, &
                          c_loc(value), err)
    end subroutine read_int8_scalar

    !> One attribute value of object `obj`, into `buf` of memory type `mem_type`; the
    !> attribute must hold exactly one value.
    subroutine read_attr(src, obj, name, mem_type, buf, err)
        type(output_t), intent(in) :: src
        character(len=*), intent(in) :: obj, name
        integer(hid_t), intent(in) :: mem_type
        type(c_ptr), intent(in) :: buf
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: attr, space
        integer(hsize_t) :: points
        integer :: e
        character(len=:), allocatable :: what
        type(c_ptr) :: target_buf ! (h5aread_f wants a definable pointer)

        if (allocated(err)) return
        what = "attribute '"//name//"' of "//object_name(obj)
        call h5aopen_by_name_f(src%file, obj, name, attr, e)
        call check(e, 'h5aopen_by_name_f', what, src%part_path, err)
        if (allocated(err)) return
        call h5aget_space_f(attr, space, e)
        call check(e, 'h5aget_space_f', what, src%part_path, err)
        if (.not. allocated(err)) then
            call h5sget_simple_extent_npoints_f(space, points, e)
            call check(e, 'h5sget_simple_extent_npoints_f', what, src%part_path, err)
            if (.not. allocated(err) .and. points /= 1) &
                call set_error(err, "hdf5: "//what//" holds "//fmt_int8(int(points, i8))// &
                               " values, expected one (file "//src%part_path//")")
            call h5sclose_f(space, e)
            call check(e, 'h5sclose_f', what, src%part_path, err)
        end if
        if (.not. allocated(err)) then
            target_buf = buf
            call h5aread_f(attr, mem_type, target_buf, e)
            call check(e, 'h5aread_f', what, src%part_path, err)
        end if
        call h5aclose_f(attr, e)
        call check(e, 'h5aclose_f', what, src%part_path, err)
    end subroutine read_attr

    subroutine read_attr_int8(src, obj, name, value, err)
        type(output_t), intent(in) :: src
        character(len=*), intent(in) :: obj, name
        integer(i8), intent(out), target :: value
        type(error_t), allocatable, intent(inout) :: err

        value = 0
        call read_attr(src, obj, name, h5kind_to_type(i8, H5_INTEGER_KIND), c_loc(value), err)
    end subroutine read_attr_int8

    subroutine read_attr_real(src, obj, name, value, err)
        type(output_t), intent(in) :: src
        character(len=*), intent(in) :: obj, name
        real(wp), intent(out), target :: value
        type(error_t), allocatable, intent(inout) :: err

        value = 0
        call read_attr(src, obj, name, H5T_NATIVE_DOUBLE, c_loc(value), err)
    end subroutine read_attr_real

    !> A string attribute, without the terminating NUL or the blanks that the Fortran layer of
    !> HDF5 pads it with (it also drops trailing blanks when it writes one).
    subroutine read_attr_string(src, obj, name, text, err)
        type(output_t), intent(in) :: src
        character(len=*), intent(in) :: obj, name
        character(len=:), allocatable, intent(out) :: text
        type(error_t), allocatable, intent(inout) :: err
        integer(hsize_t) :: dims(1)
        integer(size_t) :: type_size
        integer :: e, type_class, length
        character(len=:), allocatable :: what

        text = ''
        if (allocated(err)) return
        what = "attribute '"//name//"' of "//object_name(obj)
        dims = 0
        type_class = -1
        type_size = 0
        call h5ltget_attribute_info_f(src%file, obj, name, dims, type_class, type_size, e)
        call check(e, 'h5ltget_attribute_info_f', what, src%part_path, err)
        if (allocated(err)) return
        if (type_class /= H5T_STRING_F) then
            call set_error(err, "hdf5: "//what//" is not a string (file "//src%part_path//")")
            return
        end if
        deallocate (text)
        allocate (character(len=int(type_size)) :: text)
        call h5ltget_attribute_string_f(src%file, obj, name, text, e)
        call check(e, 'h5ltget_attribute_string_f', what, src%part_path, err)
        if (allocated(err)) then
            text = ''
            return
        end if
        length = index(text, c_null_char) - 1
        if (length >= 0) text = text(:length)
        text = trim(text)
    end subroutine read_attr_string

    ! ---- writing ---------------------------------------------------------------------------

    !> "/" for the root, "/params" for 'params'.
    pure function object_name(obj) result(name)
        character(len=*), intent(in) :: obj
        character(len=:), allocatable :: name

        if (obj == '/') then
            name = '/'
        else
            name = '/'//obj
        end if
    end function object_name

    subroutine link_exists(loc, file, name, exists, err)
        integer(hid_t), intent(in) :: loc
        character(len=*), intent(in) :: file, name
        logical, intent(out) :: exists
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        exists = .false.
        if (allocated(err)) return
        call h5lexists_f(loc, name, exists, e)
        call check(e, 'h5lexists_f', '/'//name, file, err)
        if (allocated(err)) exists = .false.
    end subroutine link_exists

    !> Attribute writers (keep an earlier error; write nothing after one).
    subroutine attr_string(out, obj, name, text, err)
        type(output_t), intent(in) :: out
        character(len=*), intent(in) :: obj, name, text
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        if (allocated(err)) return
        call h5ltset_attribute_string_f(out%file, obj, name, text, e)
        call check(e, 'h5ltset_attribute_string_f', "attribute '"//name//"' of "// &
                   object_name(obj), out%part_path, err)
    end subroutine attr_string

    subroutine attr_int(out, obj, name, value, err)
        type(output_t), intent(in) :: out
        character(len=*), intent(in) :: obj, name
        integer, intent(in) :: value
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        if (allocated(err)) return
        call h5ltset_attribute_int_f(out%file, obj, name, [value], 1_size_t, e)
        call check(e, 'h5ltset_attribute_int_f', "attribute '"//name//"' of "// &
                   object_name(obj), out%part_path, err)
    end subroutine attr_int

    subroutine attr_real(out, obj, name, value, err)
        type(output_t), intent(in) :: out
        character(len=*), intent(in) :: obj, name
        real(wp), intent(in) :: value
        type(error_t), allocatable, intent(inout) :: err
        integer :: e

        if (allocated(err)) return
        call h5ltset_attribute_double_f(out%file, obj, name, [value], 1_size_t, e)
        call check(e, 'h5ltset_attribute_double_f', "attribute '"//name//"' of "// &
                   object_name(obj), out%part_path, err)
    end subroutine attr_real

    !> A 64-bit integer attribute (cycle counts and counters of long runs exceed 32 bits).
    subroutine attr_int8(out, obj, name, value, err)
        type(output_t), intent(in) :: out
        character(len=*), intent(in) :: obj, name
        integer(i8), intent(in), target :: value
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: space, attr
        integer :: e
        character(len=:), allocatable :: what

        if (allocated(err)) return
        what = "attribute '"//name//"' of "//object_name(obj)
        call h5screate_f(H5S_SCALAR_F, space, e)
        call check(e, 'h5screate_f', what, out%part_path, err)
        if (allocated(err)) return
        call h5acreate_by_name_f(out%file, obj, name, H5T_STD_I64LE, space, attr, e)
        call check(e, 'h5acreate_by_name_f', what, out%part_path, err)
        if (.not. allocated(err)) then
            call h5awrite_f(attr, h5kind_to_type(i8, H5_INTEGER_KIND), c_loc(value), e)
            call check(e, 'h5awrite_f', what, out%part_path, err)
            call h5aclose_f(attr, e)
            call check(e, 'h5aclose_f', what, out%part_path, err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', what, out%part_path, err)
    end subroutine attr_int8

    !> A dataset of extents `dims` (none: a scalar) and file type `file_type`, written whole
    !> from `buf` (memory type `mem_type`), with its `units`.
    subroutine write_dataset(out, name, file_type, mem_type, dims, buf, units, err)
        type(output_t), intent(in) :: out
        character(len=*), intent(in) :: name, units
        integer(hid_t), intent(in) :: file_type, mem_type
        integer(hsize_t), intent(in) :: dims(:)
        type(c_ptr), intent(in) :: buf
        type(error_t), allocatable, intent(out) :: err
        integer(hid_t) :: space, dset
        integer :: e

        if (size(dims) == 0) then
            call h5screate_f(H5S_SCALAR_F, space, e)
            call check(e, 'h5screate_f', '/'//name, out%part_path, err)
        else
            call h5screate_simple_f(size(dims), dims, space, e)
            call check(e, 'h5screate_simple_f', '/'//name, out%part_path, err)
        end if
        if (allocated(err)) return
        call h5dcreate_f(out%file, name, file_type, space, dset, e)
        call check(e, 'h5dcreate_f', '/'//name, out%part_path, err)
        if (.not. allocated(err)) then
            call h5dwrite_f(dset, mem_type, buf, e)
            call check(e, 'h5dwrite_f', '/'//name, out%part_path, err)
            call h5dclose_f(dset, e)
            call check(e, 'h5dclose_f', '/'//name, out%part_path, err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', '/'//name, out%part_path, err)
        call attr_string(out, name, 'units', units, err)
    end subroutine write_dataset

    subroutine write_real_1d(out, name, values, units, err)
        type(output_t), intent(in) :: out
        character(len=*), intent(in) :: name, units
        real(wp), intent(in), target, contiguous :: values(:)
        type(error_t), allocatable, intent(out) :: err

        call write_dataset(out, name, H5T_NATIVE_DOUBLE, H5T_NATIVE_DOUBLE, &
                           [int(size(values), hsize_t)], c_loc(values), units, err)
    end subroutine write_real_1d

    subroutine write_real_2d(out, name, values, units, err)
        type(output_t), intent(in) :: out
        character(len=*), intent(in) :: name, units
        real(wp), intent(in), target, contiguous :: values(:, :)
        type(error_t), allocatable, intent(out) :: err

        call write_dataset(out, name, H5T_NATIVE_DOUBLE, H5T_NATIVE_DOUBLE, &
                           int(shape(values), hsize_t), c_loc(values), units, err)
    end subroutine write_real_2d

    subroutine write_int_1d(out, name, values, units, err)
        type(output_t), intent(in) :: out
        character(len=*), intent(in) :: name, units
        integer, intent(in), target, contiguous :: values(:)
        type(error_t), allocatable, intent(out) :: err

        call write_dataset(out, name, H5T_NATIVE_INTEGER, H5T_NATIVE_INTEGER, &
                           [int(size(values), hsize_t)], c_loc(values), units, err)
    end subroutine write_int_1d

    subroutine write_scalar_int8(out, name, value, units, err)
        type(output_t), intent(in) :: out
        character(len=*), intent(in) :: name, units
        integer(i8), intent(in), target :: value
        type(error_t), allocatable, intent(out) :: err
        integer(hsize_t) :: scalar(0)

        call write_dataset(out, name, H5T_STD_I64LE, h5kind_to_type(i8, H5_INTEGER_KIND), &
                           scalar, c_loc(value), units, err)
    end subroutine write_scalar_int8

    !> A chunked dataset of extents `dims` whose last axis can grow (or shrink: a run stopped
    !> early), with its `units`.
    subroutine create_fixed(out, name, dtype, dims, units, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: name, units
        integer(hid_t), intent(in) :: dtype
        integer(hsize_t), intent(in) :: dims(:)
        type(error_t), allocatable, intent(out) :: err
        integer(hsize_t) :: chunk(size(dims)), maxdims(size(dims))

        chunk = dims
        chunk(size(dims)) = max(1_hsize_t, min(dims(size(dims)), &
                                               int(262144/max(1_hsize_t, product(dims) &
                                                              /max(1_hsize_t, dims(size(dims)))) &
                                                   , hsize_t)))
        maxdims = dims
        maxdims(size(dims)) = H5S_UNLIMITED_F
        call create_chunked(out, name, dtype, dims, maxdims, chunk, units, err)
    end subroutine create_fixed

    !> An empty 1-D dataset that grows as events are appended.
    subroutine create_extendible(out, name, dtype, units, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: name, units
        integer(hid_t), intent(in) :: dtype
        type(error_t), allocatable, intent(out) :: err

        call create_chunked(out, name, dtype, [0_hsize_t], [H5S_UNLIMITED_F], [event_chunk], &
                            units, err)
    end subroutine create_extendible

    subroutine create_chunked(out, name, dtype, dims, maxdims, chunk, units, err)
        type(output_t), intent(in) :: out
        character(len=*), intent(in) :: name, units
        integer(hid_t), intent(in) :: dtype
        integer(hsize_t), intent(in) :: dims(:), maxdims(:), chunk(:)
        type(error_t), allocatable, intent(out) :: err
        integer(hid_t) :: space, dset, plist
        integer :: e

        call h5screate_simple_f(size(dims), dims, space, e, maxdims=maxdims)
        call check(e, 'h5screate_simple_f', '/'//name, out%part_path, err)
        if (allocated(err)) return
        call h5pcreate_f(H5P_DATASET_CREATE_F, plist, e)
        call check(e, 'h5pcreate_f', '/'//name, out%part_path, err)
        if (.not. allocated(err)) then
            call h5pset_chunk_f(plist, size(dims), chunk, e)
            call check(e, 'h5pset_chunk_f', '/'//name, out%part_path, err)
            if (.not. allocated(err)) then
                call h5dcreate_f(out%file, name, dtype, space, dset, e, dcpl_id=plist)
                call check(e, 'h5dcreate_f', '/'//name, out%part_path, err)
                if (.not. allocated(err)) then
                    call h5dclose_f(dset, e)
                    call check(e, 'h5dclose_f', '/'//name, out%part_path, err)
                end if
            end if
            call h5pclose_f(plist, e)
            call check(e, 'h5pclose_f', '/'//name, out%part_path, err)
        end if
        call h5sclose_f(space, e)
        call check(e, 'h5sclose_f', '/'//name, out%part_path, err)
        call attr_string(out, name, 'units', units, err)
    end subroutine create_chunked

    !> Change the extents of a chunked dataset.
    subroutine set_extent(out, name, dims, err)
        type(output_t), intent(in) :: out
        character(len=*), intent(in) :: name
        integer(hsize_t), intent(in) :: dims(:)
        type(error_t), allocatable, intent(out) :: err
        integer(hid_t) :: dset
        integer :: e

        call h5dopen_f(out%file, name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, out%part_path, err)
        if (allocated(err)) return
        call h5dset_extent_f(dset, dims, e)
        call check(e, 'h5dset_extent_f', '/'//name, out%part_path, err)
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, out%part_path, err)
    end subroutine set_extent

    !> Write `buf` (memory type `mem_type`) into the hyperslab offset/block of dataset
    !> `name`, first growing the dataset to hold it when `extend`.
    subroutine write_slab(out, name, offset, block, extend, mem_type, buf, err)
        type(output_t), intent(in) :: out
        character(len=*), intent(in) :: name
        integer(hsize_t), intent(in) :: offset(:), block(:)
        logical, intent(in) :: extend
        integer(hid_t), intent(in) :: mem_type
        type(c_ptr), intent(in) :: buf
        type(error_t), allocatable, intent(out) :: err

        call transfer_slab(out, name, offset, block, mem_type, buf, .true., extend, err)
    end subroutine write_slab

    !> Move `buf` (memory type `mem_type`) between memory and the hyperslab offset/block of
    !> dataset `name`: write it (`writing`), first growing the dataset to hold it when
    !> `extend`, or read it. Nothing is done after an earlier error.
    subroutine transfer_slab(file, name, offset, block, mem_type, buf, writing, extend, err)
        type(output_t), intent(in) :: file
        character(len=*), intent(in) :: name
        integer(hsize_t), intent(in) :: offset(:), block(:)
        integer(hid_t), intent(in) :: mem_type
        type(c_ptr), intent(in) :: buf
        logical, intent(in) :: writing, extend
        type(error_t), allocatable, intent(inout) :: err
        integer(hid_t) :: dset, fspace, mspace
        integer :: e
        type(c_ptr) :: target_buf ! (h5dread_f wants a definable pointer)

        if (allocated(err)) return
        call h5dopen_f(file%file, name, dset, e)
        call check(e, 'h5dopen_f', '/'//name, file%part_path, err)
        if (allocated(err)) return
        if (extend) then
            call h5dset_extent_f(dset, offset + block, e)
            call check(e, 'h5dset_extent_f', '/'//name, file%part_path, err)
        end if
        if (.not. allocated(err)) then
            call h5dget_space_f(dset, fspace, e)
            call check(e, 'h5dget_space_f', '/'//name, file%part_path, err)
            if (.not. allocated(err)) then
                call h5sselect_hyperslab_f(fspace, H5S_SELECT_SET_F, offset, block, e)
                call check(e, 'h5sselect_hyperslab_f', '/'//name, file%part_path, err)
                if (.not. allocated(err)) then
                    call h5screate_simple_f(size(block), block, mspace, e)
                    call check(e, 'h5screate_simple_f', '/'//name, file%part_path, err)
                    if (.not. allocated(err)) then
                        if (writing) then
                            call h5dwrite_f(dset, mem_type, buf, e, mem_space_id=mspace, &
                                            file_space_id=fspace)
                            call check(e, 'h5dwrite_f', '/'//name, file%part_path, err)
                        else
                            target_buf = buf
                            call h5dread_f(dset, mem_type, target_buf, e, &
                                           mem_space_id=mspace, file_space_id=fspace)
                            call check(e, 'h5dread_f', '/'//name, file%part_path, err)
                        end if
                        call h5sclose_f(mspace, e)
                        call check(e, 'h5sclose_f', '/'//name, file%part_path, err)
                    end if
                end if
                call h5sclose_f(fspace, e)
                call check(e, 'h5sclose_f', '/'//name, file%part_path, err)
            end if
        end if
        call h5dclose_f(dset, e)
        call check(e, 'h5dclose_f', '/'//name, file%part_path, err)
    end subroutine transfer_slab

end module chain_output
