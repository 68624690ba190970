!> HDF5 output (the only module that touches `use hdf5`): the layout of README.md "Output".
!>
!> A run writes to `name.h5.part` and renames it to `name.h5` when it ends, so a file under the
!> final name is never one whose writing was cut off. Strobe records and events go to disk in
!> chunks as the run proceeds, so memory does not grow with its length. Fortran arrays x(n, m)
!> appear in h5py as (m, n).
!> Infrastructure, no model section: it writes the records of docs/model.md sections 6-7.
module chain_output
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char, c_ptr, c_loc
    use hdf5
    use h5lt
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error, fmt_int
    implicit none
    private
    public :: output_t, output_begin, output_header, output_strobe_write, output_events_append
    public :: output_final, output_stats, output_periods, output_lyapunov, output_jacobian
    public :: output_end, output_abort, read_final_state, output_sweep_write, output_group
    public :: schema_version, code_version, output_truncate_strobe, output_sweep_attributes
    public :: output_sweep_write_int, rename_file

    integer, parameter :: schema_version = 1
    character(len=*), parameter :: code_version = '0.1.0'
    integer(hsize_t), parameter :: event_chunk = 65536

    type :: output_t
        integer(hid_t) :: file = -1
        character(len=:), allocatable :: path, part_path
        integer :: n = 0
        integer(i8) :: n_events = 0
        logical :: events_created = .false.
    end type output_t

    interface
        function c_rename(old, new) bind(C, name='rename') result(status)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: old(*), new(*)
            integer(c_int) :: status
        end function c_rename
    end interface

contains

    !> Refuse an existing file (unless overwrite) or an unwritable place, before any run starts;
    !> then create `path.part`.
    subroutine output_begin(out, path, overwrite, err)
        type(output_t), intent(out) :: out
        character(len=*), intent(in) :: path
        logical, intent(in) :: overwrite
        type(error_t), allocatable, intent(out) :: err
        logical :: exists
        integer :: hdferr

        out%path = path
        out%part_path = path//'.part'
        inquire (file=path, exist=exists)
        if (exists .and. .not. overwrite) then
            call set_error(err, "&output: file = '"//path//"' exists; choose another name "// &
                           "or set overwrite = .true.")
            return
        end if
        call h5open_f(hdferr)
        call h5eset_auto_f(0, hdferr)
        call h5fcreate_f(out%part_path, H5F_ACC_TRUNC_F, out%file, hdferr)
        if (hdferr < 0) then
            out%file = -1
            call set_error(err, "&output: cannot create '"//out%part_path// &
                           "' (missing directory or no permission to write there)")
        end if
    end subroutine output_begin

    !> Root attributes, /params, /initial.
    subroutine output_header(out, input_text, summary, n, spacing, damping, restitution, &
                             amplitude, omega, boundary, period, phase, transient, cycles, &
                             x0, v0, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: input_text, summary, boundary
        integer, intent(in) :: n
        real(wp), intent(in) :: spacing(:), damping, restitution, amplitude, omega, period, phase
        integer(i8), intent(in) :: transient, cycles
        real(wp), intent(in) :: x0(:), v0(:)
        type(error_t), allocatable, intent(out) :: err
        integer :: e(20)
        integer(hid_t) :: g

        out%n = n
        e = 0
        call h5ltset_attribute_int_f(out%file, '/', 'schema_version', [schema_version], &
                                     1_size_t, e(1))
        call h5ltset_attribute_string_f(out%file, '/', 'code_version', code_version, e(2))
        call h5ltset_attribute_string_f(out%file, '/', 'input_namelist', input_text, e(3))
        call h5ltset_attribute_string_f(out%file, '/', 'resolved_namelist', summary, e(4))
        call h5ltset_attribute_int_f(out%file, '/', 'complete', [0], 1_size_t, e(5))
        call h5gcreate_f(out%file, 'params', g, e(6))
        call h5gclose_f(g, e(7))
        call h5ltset_attribute_int_f(out%file, 'params', 'n', [n], 1_size_t, e(8))
        call set_real_attr(out%file, 'params', 'damping', damping, e(9))
        call set_real_attr(out%file, 'params', 'restitution', restitution, e(10))
        call set_real_attr(out%file, 'params', 'amplitude', amplitude, e(11))
        call set_real_attr(out%file, 'params', 'omega', omega, e(12))
        call h5ltset_attribute_string_f(out%file, 'params', 'boundary', boundary, e(13))
        call set_real_attr(out%file, 'params', 'drive_period', period, e(14))
        call set_real_attr(out%file, 'params', 'phase', phase, e(15))
        call h5ltset_attribute_int_f(out%file, 'params', 'transient', [int(transient)], &
                                     1_size_t, e(16))
        call h5ltset_attribute_int_f(out%file, 'params', 'cycles', [int(cycles)], 1_size_t, e(17))
        if (any(e < 0)) then
            call set_error(err, "output: cannot write the header of '"//out%part_path//"'")
            return
        end if
        call write_real_1d(out%file, 'params/spacing', spacing, 'length', err)
        if (allocated(err)) return
        call output_group(out, 'initial', err)
        if (allocated(err)) return
        call write_real_1d(out%file, 'initial/x', x0, 'length', err)
        if (allocated(err)) return
        call write_real_1d(out%file, 'initial/v', v0, 'length/time', err)
    end subroutine output_header

    !> Create a group (once).
    subroutine output_group(out, name, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: name
        type(error_t), allocatable, intent(out) :: err
        integer(hid_t) :: g
        integer :: e1, e2
        logical :: exists

        call h5lexists_f(out%file, name, exists, e1)
        if (exists) return
        call h5gcreate_f(out%file, name, g, e1)
        call h5gclose_f(g, e2)
        if (e1 < 0 .or. e2 < 0) call set_error(err, "output: cannot create group /"//name)
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
        real(wp), intent(in) :: x(:), v(:), phase, time_in_cycle, queue_time(:)
        integer(i8), intent(in) :: cycle
        integer, intent(in) :: contact(:), queue_action(:)
        type(error_t), allocatable, intent(out) :: err
        integer :: e

        call output_group(out, 'final', err)
        if (allocated(err)) return
        call write_real_1d(out%file, 'final/x', x, 'length', err)
        if (.not. allocated(err)) call write_real_1d(out%file, 'final/v', v, 'length/time', err)
        if (.not. allocated(err)) &
            call write_real_1d(out%file, 'final/phase', [phase], 'radians', err)
        if (.not. allocated(err)) call write_real_1d(out%file, 'final/time_in_cycle', &
                                                     [time_in_cycle], 'time', err)
        if (.not. allocated(err)) call write_int_1d(out%file, 'final/contact', contact, &
                                                    '-1 resting on left wall, 1 right, 0 free', err)
        if (.not. allocated(err)) &
            call write_real_1d(out%file, 'final/event_time', queue_time, &
                               'time within the drive cycle', err)
        if (.not. allocated(err)) call write_int_1d(out%file, 'final/event_action', &
                                                    queue_action, &
                                                    '0 none, 1 impact, 2 release, 3 recheck', err)
        if (allocated(err)) return
        call write_scalar_int8(out%file, 'final/cycle', cycle, e)
        if (e < 0) call set_error(err, "output: cannot write /final/cycle")
        if (allocated(err)) return
        call h5ltset_attribute_string_f(out%file, 'final/cycle', 'units', 'drive cycles', e)
    end subroutine output_final

    subroutine output_stats(out, collisions_per_cycle, impacts, sticks, releases, &
                            site_counts, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in) :: collisions_per_cycle
        integer(i8), intent(in) :: impacts, sticks, releases
        integer(i8), intent(in), target, contiguous :: site_counts(:)
        type(error_t), allocatable, intent(out) :: err
        integer :: e(4)
        integer(hsize_t) :: dims(1)

        call output_group(out, 'stats', err)
        if (allocated(err)) return
        call set_real_attr(out%file, 'stats', 'collisions_per_cycle', collisions_per_cycle, e(1))
        call set_int8_attr(out%file, 'stats', 'impacts', impacts, e(2))
        call set_int8_attr(out%file, 'stats', 'sticks', sticks, e(3))
        call set_int8_attr(out%file, 'stats', 'releases', releases, e(4))
        if (any(e < 0)) then
            call set_error(err, "output: cannot write /stats")
            return
        end if
        dims = [int(size(site_counts), hsize_t)]
        call create_fixed(out, 'stats/site_counts', H5T_STD_I64LE, dims, 'impacts', err)
        if (.not. allocated(err)) call write_slab(out, 'stats/site_counts', [0_hsize_t], dims, &
                                                  .false., h5kind_to_type(i8, H5_INTEGER_KIND), &
                                                  c_loc(site_counts), err)
    end subroutine output_stats

    subroutine output_periods(out, period, err)
        type(output_t), intent(inout) :: out
        integer, intent(in) :: period(:)
        type(error_t), allocatable, intent(out) :: err

        call write_int_1d(out%file, 'strobe/period', period, 'drive cycles (0 = aperiodic)', err)
    end subroutine output_periods

    subroutine output_lyapunov(out, bits, per_time, stderr_bits, running_bits, ky, positive_sum, &
                               collisions_per_cycle, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in) :: bits(:), per_time(:), stderr_bits(:), running_bits(:, :)
        real(wp), intent(in) :: ky, positive_sum, collisions_per_cycle
        type(error_t), allocatable, intent(out) :: err
        integer :: e(3)

        call output_group(out, 'lyapunov', err)
        if (.not. allocated(err)) call write_real_1d(out%file, 'lyapunov/exponents', bits, &
                                                     'bits per drive cycle', err)
        if (.not. allocated(err)) &
            call write_real_1d(out%file, 'lyapunov/exponents_per_time', per_time, &
                               'nats per unit time', err)
        if (.not. allocated(err)) call write_real_1d(out%file, 'lyapunov/stderr', stderr_bits, &
                                                     'bits per drive cycle', err)
        if (.not. allocated(err)) call write_real_2d(out%file, 'lyapunov/running', running_bits, &
                                                     'bits per drive cycle', err)
        if (allocated(err)) return
        call set_real_attr(out%file, 'lyapunov', 'ky_dimension', ky, e(1))
        call set_real_attr(out%file, 'lyapunov', 'positive_sum', positive_sum, e(2))
        call set_real_attr(out%file, 'lyapunov', 'collisions_per_cycle', collisions_per_cycle, &
                           e(3))
        if (any(e < 0)) call set_error(err, "output: cannot write /lyapunov attributes")
    end subroutine output_lyapunov

    subroutine output_jacobian(out, jacobian, re, im, cycles, err)
        type(output_t), intent(inout) :: out
        real(wp), intent(in) :: jacobian(:, :), re(:), im(:)
        integer, intent(in) :: cycles
        type(error_t), allocatable, intent(out) :: err
        integer :: e

        call output_group(out, 'floquet', err)
        if (.not. allocated(err)) call write_real_2d(out%file, 'floquet/jacobian', &
                                                     transpose(jacobian), '1', err)
        if (.not. allocated(err)) call write_real_1d(out%file, 'floquet/multipliers_re', re, &
                                                     '1', err)
        if (.not. allocated(err)) call write_real_1d(out%file, 'floquet/multipliers_im', im, &
                                                     '1', err)
        if (allocated(err)) return
        call h5ltset_attribute_int_f(out%file, 'floquet', 'cycles', [cycles], 1_size_t, e)
        if (e < 0) call set_error(err, "output: cannot write /floquet")
    end subroutine output_jacobian

    !> Attributes of /sweep: the swept parameters and the mode.
    subroutine output_sweep_attributes(out, parameter, parameter2, mode, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: parameter, parameter2, mode
        type(error_t), allocatable, intent(out) :: err
        integer :: e(3)

        call h5ltset_attribute_string_f(out%file, 'sweep', 'parameter', parameter, e(1))
        call h5ltset_attribute_string_f(out%file, 'sweep', 'parameter2', parameter2//' ', e(2))
        call h5ltset_attribute_string_f(out%file, 'sweep', 'mode', mode, e(3))
        if (any(e < 0)) call set_error(err, "output: cannot write the /sweep attributes")
    end subroutine output_sweep_attributes

    !> One integer sweep dataset, stored as given (Fortran order).
    subroutine output_sweep_write_int(out, name, values, dims, units, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: name, units
        integer, intent(in) :: values(*)
        integer(hsize_t), intent(in) :: dims(:)
        type(error_t), allocatable, intent(out) :: err
        integer :: e

        call h5ltmake_dataset_int_f(out%file, name, size(dims), dims, values, e)
        if (e >= 0) call h5ltset_attribute_string_f(out%file, name, 'units', units, e)
        if (e < 0) call set_error(err, "output: cannot write /"//name)
    end subroutine output_sweep_write_int

    !> One sweep dataset: a real array of any rank up to 3, stored as given (Fortran order).
    subroutine output_sweep_write(out, name, values, dims, units, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: name, units
        real(wp), intent(in) :: values(*)
        integer(hsize_t), intent(in) :: dims(:)
        type(error_t), allocatable, intent(out) :: err
        integer :: e

        call h5ltmake_dataset_double_f(out%file, name, size(dims), dims, values, e)
        if (e >= 0) call h5ltset_attribute_string_f(out%file, name, 'units', units, e)
        if (e < 0) call set_error(err, "output: cannot write /"//name)
    end subroutine output_sweep_write

    !> A run stopped early keeps only its finished records: shrink /strobe to them.
    subroutine output_truncate_strobe(out, records_done, err)
        type(output_t), intent(inout) :: out
        integer(i8), intent(in) :: records_done
        type(error_t), allocatable, intent(out) :: err
        character(len=12), parameter :: names(3) = &
            [character(len=12) :: 'strobe/x', 'strobe/v', 'strobe/cycle']
        integer(hid_t) :: dset
        integer :: j, e, e2, rank
        integer(hsize_t) :: dims(2)
        logical :: exists

        call h5lexists_f(out%file, 'strobe', exists, e)
        if (.not. exists) return
        do j = 1, size(names)
            rank = merge(1, 2, j == 3)
            dims = [int(out%n, hsize_t), int(records_done, hsize_t)]
            call h5dopen_f(out%file, trim(names(j)), dset, e)
            if (e >= 0) then
                if (rank == 1) then
                    call h5dset_extent_f(dset, dims(2:2), e)
                else
                    call h5dset_extent_f(dset, dims, e)
                end if
                call h5dclose_f(dset, e2)
            end if
            if (e < 0) then
                call set_error(err, "output: cannot shrink /"//trim(names(j)))
                return
            end if
        end do
    end subroutine output_truncate_strobe

    !> Mark complete (or partial), close, and move `.part` to the final name.
    subroutine output_end(out, complete, err)
        type(output_t), intent(inout) :: out
        logical, intent(in) :: complete
        type(error_t), allocatable, intent(out) :: err
        integer :: e1, e2

        call h5ltset_attribute_int_f(out%file, '/', 'complete', [merge(1, 0, complete)], &
                                     1_size_t, e1)
        call h5fclose_f(out%file, e2)
        out%file = -1
        if (e1 < 0 .or. e2 < 0) then
            call set_error(err, "output: cannot finish '"//out%part_path//"'")
            return
        end if
        call rename_file(out%part_path, out%path, err)
    end subroutine output_end

    !> Move a finished file to its final name (atomic on one file system).
    subroutine rename_file(from, to, err)
        character(len=*), intent(in) :: from, to
        type(error_t), allocatable, intent(out) :: err

        if (c_rename(from//c_null_char, to//c_null_char) /= 0) &
            call set_error(err, "output: cannot rename '"//from//"' to '"//to//"'")
    end subroutine rename_file

    !> Close and delete the partial file after an error.
    subroutine output_abort(out)
        type(output_t), intent(inout) :: out
        integer :: e, u

        if (out%file >= 0) call h5fclose_f(out%file, e)
        out%file = -1
        if (.not. allocated(out%part_path)) return
        open (newunit=u, file=out%part_path, status='old', iostat=e)
        if (e == 0) close (u, status='delete')
    end subroutine output_abort

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
        integer(hid_t) :: f, d
        integer :: e, version(1), n_file(1), complete(1)
        integer(hsize_t) :: dims(1)
        real(wp) :: ph(1)
        integer(i8), target :: cycle_buf
        type(c_ptr) :: cptr
        logical :: exists

        inquire (file=path, exist=exists)
        if (.not. exists) then
            call set_error(err, "&initial: file = '"//path//"' does not exist")
            return
        end if
        call h5open_f(e)
        call h5eset_auto_f(0, e)
        call h5fopen_f(path, H5F_ACC_RDONLY_F, f, e)
        if (e < 0) then
            call set_error(err, "&initial: file = '"//path//"' is not an HDF5 file")
            return
        end if
        call h5ltget_attribute_int_f(f, '/', 'schema_version', version, e)
        if (e < 0 .or. version(1) /= schema_version) then
            call set_error(err, "&initial: file = '"//path//"' is not an impactchain output "// &
                           "of schema version 1")
        end if
        if (.not. allocated(err)) then
            call h5ltget_attribute_int_f(f, '/', 'complete', complete, e)
            call h5ltget_attribute_int_f(f, 'params', 'n', n_file, e)
            if (n_file(1) /= n) call set_error(err, "&initial: file = '"//path// &
                                                "' has n = "//fmt_int(n_file(1))// &
                                                " oscillators, the input n = "//fmt_int(n))
        end if
        if (.not. allocated(err)) then
            call h5lexists_f(f, 'final', exists, e)
            if (.not. exists) call set_error(err, "&initial: file = '"//path// &
                                             "' has no /final state (an interrupted run)")
        end if
        if (allocated(err)) then
            call h5fclose_f(f, e)
            return
        end if
        allocate (x(n), v(n), queue_time(n + 1), contact(n), queue_action(n + 1))
        dims = [int(n, hsize_t)]
        call h5ltread_dataset_double_f(f, 'final/x', x, dims, e)
        if (e >= 0) call h5ltread_dataset_double_f(f, 'final/v', v, dims, e)
        if (e >= 0) call h5ltread_dataset_int_f(f, 'final/contact', contact, dims, e)
        dims = [int(n + 1, hsize_t)]
        if (e >= 0) call h5ltread_dataset_double_f(f, 'final/event_time', queue_time, dims, e)
        if (e >= 0) call h5ltread_dataset_int_f(f, 'final/event_action', queue_action, dims, e)
        dims = [1_hsize_t]
        if (e >= 0) call h5ltread_dataset_double_f(f, 'final/phase', ph, dims, e)
        phase = ph(1)
        if (e >= 0) call h5ltread_dataset_double_f(f, 'final/time_in_cycle', ph, dims, e)
        time_in_cycle = ph(1)
        if (e >= 0) call h5ltget_attribute_double_f(f, 'params', 'damping', model(1:1), e)
        if (e >= 0) call h5ltget_attribute_double_f(f, 'params', 'restitution', model(2:2), e)
        if (e >= 0) call h5ltget_attribute_double_f(f, 'params', 'amplitude', model(3:3), e)
        if (e >= 0) call h5ltget_attribute_double_f(f, 'params', 'omega', model(4:4), e)
        boundary = ''
        if (e >= 0) call h5ltget_attribute_string_f(f, 'params', 'boundary', boundary, e)
        allocate (spacing(n + 1))
        dims = [int(n + 1, hsize_t)]
        if (e >= 0) call h5ltread_dataset_double_f(f, 'params/spacing', spacing, dims, e)
        dims = [1_hsize_t]
        if (e >= 0) then
            call h5dopen_f(f, 'final/cycle', d, e)
            cycle_buf = 0
            cptr = c_loc(cycle_buf)
            if (e >= 0) call h5dread_f(d, h5kind_to_type(i8, H5_INTEGER_KIND), cptr, e)
            cycle = cycle_buf
            call h5dclose_f(d, e)
        end if
        if (e < 0) call set_error(err, "&initial: file = '"//path//"' has an unreadable /final")
        call h5fclose_f(f, e)
    end subroutine read_final_state

    ! ---- small helpers -------------------------------------------------------------------

    subroutine set_real_attr(loc, obj, name, value, e)
        integer(hid_t), intent(in) :: loc
        character(len=*), intent(in) :: obj, name
        real(wp), intent(in) :: value
        integer, intent(out) :: e

        call h5ltset_attribute_double_f(loc, obj, name, [value], 1_size_t, e)
    end subroutine set_real_attr

    !> A 64-bit integer attribute (counters of long runs exceed 32 bits).
    subroutine set_int8_attr(loc, obj, name, value, e)
        integer(hid_t), intent(in) :: loc
        character(len=*), intent(in) :: obj, name
        integer(i8), intent(in), target :: value
        integer, intent(out) :: e
        integer(hid_t) :: space, attr
        integer :: e2

        call h5screate_f(H5S_SCALAR_F, space, e)
        if (e < 0) return
        call h5acreate_by_name_f(loc, obj, name, H5T_STD_I64LE, space, attr, e)
        if (e >= 0) then
            call h5awrite_f(attr, h5kind_to_type(i8, H5_INTEGER_KIND), c_loc(value), e)
            call h5aclose_f(attr, e2)
        end if
        call h5sclose_f(space, e2)
    end subroutine set_int8_attr

    subroutine write_real_1d(loc, name, values, units, err)
        integer(hid_t), intent(in) :: loc
        character(len=*), intent(in) :: name, units
        real(wp), intent(in) :: values(:)
        type(error_t), allocatable, intent(out) :: err
        integer :: e

        call h5ltmake_dataset_double_f(loc, name, 1, [int(size(values), hsize_t)], values, e)
        if (e >= 0) call h5ltset_attribute_string_f(loc, name, 'units', units, e)
        if (e < 0) call set_error(err, "output: cannot write /"//name)
    end subroutine write_real_1d

    subroutine write_real_2d(loc, name, values, units, err)
        integer(hid_t), intent(in) :: loc
        character(len=*), intent(in) :: name, units
        real(wp), intent(in) :: values(:, :)
        type(error_t), allocatable, intent(out) :: err
        integer :: e

        call h5ltmake_dataset_double_f(loc, name, 2, &
                                       [int(size(values, 1), hsize_t), &
                                        int(size(values, 2), hsize_t)], values, e)
        if (e >= 0) call h5ltset_attribute_string_f(loc, name, 'units', units, e)
        if (e < 0) call set_error(err, "output: cannot write /"//name)
    end subroutine write_real_2d

    subroutine write_int_1d(loc, name, values, units, err)
        integer(hid_t), intent(in) :: loc
        character(len=*), intent(in) :: name, units
        integer, intent(in) :: values(:)
        type(error_t), allocatable, intent(out) :: err
        integer :: e

        call h5ltmake_dataset_int_f(loc, name, 1, [int(size(values), hsize_t)], values, e)
        if (e >= 0) call h5ltset_attribute_string_f(loc, name, 'units', units, e)
        if (e < 0) call set_error(err, "output: cannot write /"//name)
    end subroutine write_int_1d

    subroutine write_scalar_int8(loc, name, value, e)
        integer(hid_t), intent(in) :: loc
        character(len=*), intent(in) :: name
        integer(i8), intent(in), target :: value
        integer, intent(out) :: e
        integer(hid_t) :: space, dset
        integer :: e2
        type(c_ptr) :: buf

        call h5screate_f(H5S_SCALAR_F, space, e)
        if (e < 0) return
        call h5dcreate_f(loc, name, H5T_STD_I64LE, space, dset, e)
        if (e >= 0) then
            buf = c_loc(value)
            call h5dwrite_f(dset, h5kind_to_type(i8, H5_INTEGER_KIND), buf, e)
            call h5dclose_f(dset, e2)
        end if
        call h5sclose_f(space, e2)
    end subroutine write_scalar_int8

    subroutine create_fixed(out, name, dtype, dims, units, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: name, units
        integer(hid_t), intent(in) :: dtype
        integer(hsize_t), intent(in) :: dims(:)
        type(error_t), allocatable, intent(out) :: err
        integer(hid_t) :: space, dset, plist
        integer(hsize_t) :: chunk(size(dims)), maxdims(size(dims))
        integer :: e, e2

        chunk = dims
        chunk(size(dims)) = max(1_hsize_t, min(dims(size(dims)), &
                                               int(262144/max(1_hsize_t, product(dims) &
                                                              /max(1_hsize_t, dims(size(dims)))) &
                                                   , hsize_t)))
        maxdims = dims
        maxdims(size(dims)) = H5S_UNLIMITED_F
        call h5screate_simple_f(size(dims), dims, space, e, maxdims=maxdims)
        call h5pcreate_f(H5P_DATASET_CREATE_F, plist, e2)
        call h5pset_chunk_f(plist, size(dims), chunk, e2)
        call h5dcreate_f(out%file, name, dtype, space, dset, e, dcpl_id=plist)
        if (e >= 0) call h5dclose_f(dset, e2)
        call h5pclose_f(plist, e2)
        call h5sclose_f(space, e2)
        if (e >= 0) call h5ltset_attribute_string_f(out%file, name, 'units', units, e)
        if (e < 0) call set_error(err, "output: cannot create /"//name)
    end subroutine create_fixed

    subroutine create_extendible(out, name, dtype, units, err)
        type(output_t), intent(inout) :: out
        character(len=*), intent(in) :: name, units
        integer(hid_t), intent(in) :: dtype
        type(error_t), allocatable, intent(out) :: err
        integer(hid_t) :: space, dset, plist
        integer :: e, e2

        call h5screate_simple_f(1, [0_hsize_t], space, e, maxdims=[H5S_UNLIMITED_F])
        call h5pcreate_f(H5P_DATASET_CREATE_F, plist, e2)
        call h5pset_chunk_f(plist, 1, [event_chunk], e2)
        call h5dcreate_f(out%file, name, dtype, space, dset, e, dcpl_id=plist)
        if (e >= 0) call h5dclose_f(dset, e2)
        call h5pclose_f(plist, e2)
        call h5sclose_f(space, e2)
        if (e >= 0) call h5ltset_attribute_string_f(out%file, name, 'units', units, e)
        if (e < 0) call set_error(err, "output: cannot create /"//name)
    end subroutine create_extendible

    !> Select the hyperslab offset/block of dataset `name` (extending it first if asked).
    subroutine open_slab(out, name, offset, block, extend, dset, fspace, mspace, e)
        type(output_t), intent(in) :: out
        character(len=*), intent(in) :: name
        integer(hsize_t), intent(in) :: offset(:), block(:)
        logical, intent(in) :: extend
        integer(hid_t), intent(out) :: dset, fspace, mspace
        integer, intent(out) :: e

        call h5dopen_f(out%file, name, dset, e)
        if (e < 0) return
        if (extend) call h5dset_extent_f(dset, offset + block, e)
        if (e < 0) return
        call h5dget_space_f(dset, fspace, e)
        if (e < 0) return
        call h5sselect_hyperslab_f(fspace, H5S_SELECT_SET_F, offset, block, e)
        if (e < 0) return
        call h5screate_simple_f(size(block), block, mspace, e)
    end subroutine open_slab

    subroutine close_slab(dset, fspace, mspace)
        integer(hid_t), intent(in) :: dset, fspace, mspace
        integer :: e

        call h5sclose_f(mspace, e)
        call h5sclose_f(fspace, e)
        call h5dclose_f(dset, e)
    end subroutine close_slab

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
        integer(hid_t) :: dset, fspace, mspace
        integer :: e

        call open_slab(out, name, offset, block, extend, dset, fspace, mspace, e)
        if (e >= 0) call h5dwrite_f(dset, mem_type, buf, e, mem_space_id=mspace, &
                                    file_space_id=fspace)
        call close_slab(dset, fspace, mspace)
        if (e < 0) call set_error(err, "output: cannot write /"//name)
    end subroutine write_slab

end module chain_output
