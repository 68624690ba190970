!> The spectra of a run's file (docs/output.md): /lyapunov at the end of a run, the
!> finite-time windows of /finite_time as the run goes (docs/model.md section 7.10), the
!> covariant vectors of /clv (section 14.5) and the Jacobian and Floquet multipliers of
!> /floquet. Names, units and long names are the file schema's (chain_describe); the file is
!> chain_run_file's.
!> Infrastructure, no model section.
module chain_run_file_spectra
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_describe, only: describe, index_coordinate, bare_dimension
    use chain_run_file, only: output_t, oscillator_coordinate
    use chain_hdf5, only: h5_real, h5_int8, h5_create_group, h5_exists, h5_write_attr, &
                          h5_write, h5_extent, h5_create_growing, h5_set_extent, &
                          h5_write_slab, h5_set_scale
    implicit none
    private
    public :: output_lyapunov, output_windows_write, output_truncate_windows
    public :: output_clv_rows, output_clv, output_jacobian

contains

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

end module chain_run_file_spectra
