!> A census run (docs/model.md section 13): the samples of chain_census, resumed from and
!> checkpointed to `file.h5.ckpt` like a sweep, classified when all are done, and the HDF5
!> group /census that holds them, written only then (the file appears whole or not at all).
module chain_census_file
    use chain_kinds, only: wp
    use chain_error, only: error_t, set_error, fmt_real
    use chain_config, only: config_t
    use chain_sim, only: write_run_header
    use chain_sweep, only: validate_sweep_points, plan_sweep
    use chain_files, only: remove_file
    use chain_checkpoint, only: checkpoint_path
    use chain_census, only: census_result_t, census_starts, run_census_samples, census_points
    use chain_census_classify, only: classify_census
    use chain_census_checkpoint, only: save_census_checkpoint, load_census_checkpoint, &
                                       census_checkpoint_monitor_t
    use chain_attractor, only: kind_names, classification_rule, site_distance_limit, &
                               chaos_sigmas
    use chain_output, only: output_t, output_begin, output_group, output_end, output_abort, &
                            output_unset_param
    use chain_hdf5, only: h5_write, h5_write_attr, h5_write_strings, h5_set_scale
    use chain_describe, only: describe, describe_group, index_coordinate
    use chain_monitor, only: monitor_t
    implicit none
    private
    public :: census_to_file, write_census_file, check_census, check_census_size

contains

    !> The whole census described by cfg: resumes from `file.ckpt` when one exists for the same
    !> input, checkpoints every few seconds, and writes the HDF5 file when every sample is
    !> done. `monitor`, told the samples done, may ask to stop: the checkpoint then keeps the
    !> finished samples and no file is written (`all(res%done)` is then false).
    subroutine census_to_file(cfg, res, err, monitor)
        type(config_t), intent(in) :: cfg
        type(census_result_t), intent(out), target :: res
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional, target :: monitor
        type(output_t) :: out
        type(error_t), allocatable :: err2
        type(census_checkpoint_monitor_t) :: watch
        character(len=:), allocatable :: checkpoint

        call check_census(cfg, err)
        if (allocated(err)) return
        call output_begin(out, cfg%output_file, cfg%overwrite, err)
        if (allocated(err)) return
        checkpoint = checkpoint_path(cfg)
        call census_starts(res, cfg, err)
        if (.not. allocated(err)) call load_census_checkpoint(checkpoint, cfg, res, err)
        if (allocated(err)) then
            call output_abort(out)
            return
        end if
        res%resumed = count(res%done)
        if (present(monitor)) watch%outer => monitor
        watch%cfg = cfg
        watch%res => res
        watch%path = checkpoint
        call system_clock(watch%clock_last, watch%clock_rate)
        call run_census_samples(cfg, res, err, watch)
        ! a periodic checkpoint that could not be written stopped the census
        if (allocated(watch%err) .and. .not. allocated(err)) call move_alloc(watch%err, err)
        if (.not. all(res%done) .or. allocated(err)) then
            call save_census_checkpoint(checkpoint, cfg, res, err2)
            call output_abort(out)
            if (allocated(err2) .and. .not. allocated(err)) call move_alloc(err2, err)
            return
        end if
        call classify_census(cfg, res, err)
        if (.not. allocated(err)) call write_census_file(out, cfg, res, err)
        if (allocated(err)) then
            call output_abort(out)
            return
        end if
        call output_end(out, .true., err)
        if (.not. allocated(err)) call remove_file(checkpoint)
    end subroutine census_to_file

    !> Everything that refuses the census itself before any work: its size, and along a
    !> sweep every point's configuration. (The output file is output_begin's, or
    !> output_check's.)
    subroutine check_census(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err

        call check_census_size(cfg, err)
        if (.not. allocated(err) .and. cfg%sweep) &
            call validate_sweep_points(cfg, plan_sweep(cfg), err)
    end subroutine check_census

    !> Refuse, before anything runs, a census whose results exceed &output max_size_mb: per
    !> sample its start, state, periods, impacts per bond and k exponents with their errors (in
    !> memory and in the file).
    subroutine check_census_size(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: mb

        associate (n => real(cfg%model%n, wp), k => real(cfg%census_exponents, wp))
            mb = real(cfg%census_samples, wp)*census_points(cfg)*(44*n + 34 + 16*k)/1.0e6_wp
        end associate
        if (mb > cfg%max_size_mb) call set_error(err, "&census: the samples of this census "// &
            "need about "//fmt_real(mb)//" MB (points x samples x (44 n + 34 + 16 k) bytes, "// &
            "k = exponents), more "// &
            "than &output max_size_mb = "//fmt_real(cfg%max_size_mb)//"; lower samples or "// &
            "raise max_size_mb")
    end subroutine check_census_size

    !> The run's header (for a sweep without the swept parameter, which /params cannot hold
    !> as one number) and /census: per point and sample the start, the attractor reached and
    !> whether its mirror image, its k leading exponents and their errors; per attractor its
    !> kind, periods, largest exponent, representative state and impact sites, and the mean
    !> and spread of its samples' exponents; per point and attractor the basin fraction.
    !> Attractor ids (0-based) are global: an attractor belongs to the point where it was found.
    subroutine write_census_file(out, cfg, res, err)
        type(output_t), intent(inout) :: out
        type(config_t), intent(in) :: cfg
        type(census_result_t), intent(in) :: res
        type(error_t), allocatable, intent(out) :: err
        integer, allocatable :: periods(:, :)
        real(wp), allocatable :: ax(:, :), av(:, :), sites(:, :)
        character(len=20), allocatable :: kinds(:)
        integer :: n, na, a

        n = cfg%model%n
        na = res%n_attractors
        allocate (periods(n, na), ax(n, na), av(n, na), sites(n + 1, na), kinds(na))
        do a = 1, na
            associate (t => res%attractors(a))
                periods(:, a) = t%periods
                ax(:, a) = t%x
                av(:, a) = t%v
                sites(:, a) = t%sites
                kinds(a) = kind_names(t%kind)
            end associate
        end do
        call write_run_header(out, cfg, err)
        if (cfg%sweep .and. .not. allocated(err)) &
            call output_unset_param(out, cfg%sweep_parameter, err)
        if (.not. allocated(err)) call output_group(out, 'census', err)
        if (allocated(err)) return
        call census_attributes(out, cfg, err)
        call census_axes(out, cfg, res, err)
        if (allocated(err)) return
        associate (f => out%file, ts => res%attractors(:na))
            call h5_write(f, 'census/x0', res%x0, err)
            call h5_write(f, 'census/v0', res%v0, err)
            call h5_write(f, 'census/sample_attractor', res%attractor - 1, err)
            call h5_write(f, 'census/mirrored', merge(1, 0, res%mirrored), err)
            ! (the first of each sample's exponents, a contiguous copy)
            call h5_write(f, 'census/lambda1', res%exponents(1, :, :) + 0.0_wp, err)
            call h5_write(f, 'census/attractor_period', periods, err)
            call h5_write(f, 'census/attractor_lambda1', [(ts(a)%lambda1, a=1, na)], err)
            call h5_write(f, 'census/attractor_lambda1_stderr', [(ts(a)%stderr1, a=1, na)], err)
            call h5_write(f, 'census/attractor_x', ax, err)
            call h5_write(f, 'census/attractor_v', av, err)
            call h5_write(f, 'census/attractor_point', [(ts(a)%point - 1, a=1, na)], err)
            call h5_write(f, 'census/attractor_sample', [(ts(a)%first_sample, a=1, na)], err)
            call h5_write_strings(f, 'census/attractor_kind', kinds, err)
            call h5_write(f, 'census/attractor_sites', sites, err)
            call h5_write(f, 'census/fraction', res%fraction, err)
            call h5_write(f, 'census/fraction_stderr', res%fraction_stderr, err)
            call h5_write(f, 'census/sample_exponents', res%exponents, err)
            call h5_write(f, 'census/sample_exponents_stderr', res%exponents_stderr, err)
            call h5_write(f, 'census/attractor_exponents', res%attractor_exponents, err)
            call h5_write(f, 'census/attractor_exponents_spread', res%attractor_spread, err)
        end associate
        call describe_group(out%file, 'census', err)
    end subroutine write_census_file

    !> /census attributes: the &census keys, the swept parameter ('' at one point) and the
    !> classification rule in words; with a plane, its coordinates (blank-separated, as
    !> written), range and points per side.
    subroutine census_attributes(out, cfg, err)
        type(output_t), intent(inout) :: out
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(inout) :: err
        character(len=:), allocatable :: parameter

        parameter = ''
        if (cfg%sweep) parameter = cfg%sweep_parameter
        associate (f => out%file)
            call h5_write_attr(f, 'census', 'samples', cfg%census_samples, err)
            call h5_write_attr(f, 'census', 'seed', cfg%census_seed, err)
            call h5_write_attr(f, 'census', 'x_amp', cfg%census_x_amp, err)
            call h5_write_attr(f, 'census', 'v_amp', cfg%census_v_amp, err)
            call h5_write_attr(f, 'census', 'tolerance', cfg%census_tolerance, err)
            call h5_write_attr(f, 'census', 'mirror', cfg%census_mirror, err)
            call h5_write_attr(f, 'census', 'parameter', parameter, err)
            call h5_write_attr(f, 'census', 'site_distance_limit', site_distance_limit, err)
            call h5_write_attr(f, 'census', 'chaos_sigmas', chaos_sigmas, err)
            call h5_write_attr(f, 'census', 'rule', classification_rule, err)
            if (cfg%census_plane_points > 0) then
                call h5_write_attr(f, 'census', 'plane', trim(cfg%census_plane(1))//' '// &
                                   trim(cfg%census_plane(2)), err)
                call h5_write_attr(f, 'census', 'plane_range', cfg%census_plane_range, err)
                call h5_write_attr(f, 'census', 'plane_points', cfg%census_plane_points, err)
            end if
        end associate
    end subroutine census_attributes

    !> The dimensions of /census: `point` (the swept parameter's values, or index 0 at one
    !> point), `sample` (1..samples, the stream of each), `oscillator`, `attractor` (its id),
    !> `bond` and `exponent` (1..k).
    subroutine census_axes(out, cfg, res, err)
        type(output_t), intent(inout) :: out
        type(config_t), intent(in) :: cfg
        type(census_result_t), intent(in) :: res
        type(error_t), allocatable, intent(inout) :: err

        if (allocated(err)) return
        associate (f => out%file)
            if (cfg%sweep) then
                call h5_write(f, 'census/point', res%values, err)
                call h5_set_scale(f, 'census/point', err)
                call describe(f, 'census/point', err, parameter=cfg%sweep_parameter, &
                              when='a census over a sweep')
            else
                call index_coordinate(f, 'census/point', 0, 1, err, when='a census at one point')
            end if
            call index_coordinate(f, 'census/sample', 1, res%n_samples, err)
            call index_coordinate(f, 'census/oscillator', 1, cfg%model%n, err)
            call index_coordinate(f, 'census/attractor', 0, res%n_attractors, err)
            call index_coordinate(f, 'census/bond', 0, cfg%model%n + 1, err)
            call index_coordinate(f, 'census/exponent', 1, res%n_exponents, err)
        end associate
    end subroutine census_axes

end module chain_census_file
