!> A census run (docs/model.md section 13): the samples of chain_census, resumed from and
!> checkpointed to `file.h5.ckpt` like a sweep, classified when all are done, and the HDF5
!> group /census that holds them, written only then (the file appears whole or not at all).
module chain_census_file
    use chain_kinds, only: wp
    use chain_error, only: error_t, set_error, fmt_real
    use chain_config, only: config_t
    use chain_model, only: parameter_units
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
                            output_describe, output_index, output_unset_param
    use chain_hdf5, only: h5_write, h5_write_attr, h5_write_strings, h5_set_scale
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
            call h5_write(f, 'census/x0', res%x0, '1', err)
            call h5_write(f, 'census/v0', res%v0, '1', err)
            call h5_write(f, 'census/sample_attractor', res%attractor - 1, '1', err)
            call h5_write(f, 'census/mirrored', merge(1, 0, res%mirrored), '1', err)
            ! (the first of each sample's exponents, a contiguous copy)
            call h5_write(f, 'census/lambda1', res%exponents(1, :, :) + 0.0_wp, 'bit', err)
            call h5_write(f, 'census/attractor_period', periods, '1', err)
            call h5_write(f, 'census/attractor_lambda1', [(ts(a)%lambda1, a=1, na)], 'bit', err)
            call h5_write(f, 'census/attractor_lambda1_stderr', [(ts(a)%stderr1, a=1, na)], &
                          'bit', err)
            call h5_write(f, 'census/attractor_x', ax, '1', err)
            call h5_write(f, 'census/attractor_v', av, '1', err)
            call h5_write(f, 'census/attractor_point', [(ts(a)%point - 1, a=1, na)], '1', err)
            call h5_write(f, 'census/attractor_sample', [(ts(a)%first_sample, a=1, na)], &
                          '1', err)
            call h5_write_strings(f, 'census/attractor_kind', kinds, '1', err)
            call h5_write(f, 'census/attractor_sites', sites, '1', err)
            call h5_write(f, 'census/fraction', res%fraction, '1', err)
            call h5_write(f, 'census/fraction_stderr', res%fraction_stderr, '1', err)
            call h5_write(f, 'census/sample_exponents', res%exponents, 'bit', err)
            call h5_write(f, 'census/sample_exponents_stderr', res%exponents_stderr, 'bit', err)
            call h5_write(f, 'census/attractor_exponents', res%attractor_exponents, 'bit', err)
            call h5_write(f, 'census/attractor_exponents_spread', res%attractor_spread, 'bit', &
                          err)
        end associate
        if (.not. allocated(err)) call describe_all(out, err)
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
        if (cfg%sweep) then
            call h5_write(out%file, 'census/point', res%values, '1', err)
            call h5_set_scale(out%file, 'census/point', err)
            if (.not. allocated(err)) call output_describe(out, 'census/point', &
                cfg%sweep_parameter//' (the swept parameter) at the point', &
                parameter_units(cfg%sweep_parameter), '', err)
        else
            call output_index(out, 'census/point', 0, 1, 'point index (a census at one '// &
                              'parameter point)', err)
        end if
        if (.not. allocated(err)) call output_index(out, 'census/sample', 1, res%n_samples, &
            'sample index (the stream of its random start)', err)
        if (.not. allocated(err)) call output_index(out, 'census/oscillator', 1, &
                                                    cfg%model%n, 'oscillator index', err)
        if (.not. allocated(err)) call output_index(out, 'census/attractor', 0, &
                                                    res%n_attractors, 'attractor id', err)
        if (.not. allocated(err)) call output_index(out, 'census/bond', 0, cfg%model%n + 1, &
            'bond index: bond k joins oscillators k and k+1 (0: the left wall, n: the '// &
            'right wall)', err)
        if (.not. allocated(err)) call output_index(out, 'census/exponent', 1, &
                                                    res%n_exponents, 'exponent index '// &
                                                    '(descending order)', err)
    end subroutine census_axes

    !> The long names, units and dimensions of /census's datasets.
    subroutine describe_all(out, err)
        type(output_t), intent(inout) :: out
        type(error_t), allocatable, intent(inout) :: err

        call describe('x0', "displacement at t = 0, the sample's start", 'length', &
                      'point sample oscillator')
        call describe('v0', "velocity at t = 0, the sample's start", 'length/time', &
                      'point sample oscillator')
        call describe('sample_attractor', 'the attractor the sample reached (its id)', '', &
                      'point sample')
        call describe('mirrored', "1: the sample reached the attractor's mirror image "// &
                      "(mirror = 'merge'), 0: the attractor itself", '', 'point sample')
        call describe('lambda1', "the sample's largest Lyapunov exponent over its records", &
                      'bits per drive cycle', 'point sample')
        call describe('attractor_period', "period of each oscillator's strobe record on "// &
                      'the attractor (0: none found, aperiodic)', 'drive cycles', &
                      'attractor oscillator')
        call describe('attractor_lambda1', "largest Lyapunov exponent of the attractor's "// &
                      'representative (its first sample)', 'bits per drive cycle', 'attractor')
        call describe('attractor_lambda1_stderr', 'standard error of attractor_lambda1 '// &
                      '(block averages)', 'bits per drive cycle', 'attractor')
        call describe('attractor_x', "displacement of the representative at its last "// &
                      "record, on the section: a state the attractor's runs can start from", &
                      'length', 'attractor oscillator')
        call describe('attractor_v', 'velocity of the representative at its last record', &
                      'length/time', 'attractor oscillator')
        call describe('attractor_point', 'the point (0-based index) where the attractor '// &
                      'was found', '', 'attractor')
        call describe('attractor_sample', 'its representative: the first sample (1-based) '// &
                      'that reached it', '', 'attractor')
        call describe('attractor_kind', 'periodic, chaotic or aperiodic-nonchaotic', '', &
                      'attractor')
        call describe('attractor_sites', "fraction of the representative's impacts on "// &
                      'each bond over its records', '', 'attractor bond')
        call describe('fraction', "fraction of the point's samples that reached the "// &
                      'attractor (its basin fraction)', '', 'point attractor')
        call describe('fraction_stderr', 'binomial standard error of fraction, '// &
                      'sqrt(f (1 - f) / samples)', '', 'point attractor')
        call describe('sample_exponents', "the sample's leading Lyapunov exponents over its "// &
                      'records (&census exponents; the first is lambda1)', &
                      'bits per drive cycle', 'point sample exponent')
        call describe('sample_exponents_stderr', 'standard error of sample_exponents '// &
                      "(block averages along the sample's own run)", 'bits per drive cycle', &
                      'point sample exponent')
        call describe('attractor_exponents', "mean of sample_exponents over the attractor's "// &
                      'samples (mirror images included)', 'bits per drive cycle', &
                      'attractor exponent')
        call describe('attractor_exponents_spread', 'standard deviation of '// &
                      "sample_exponents between the attractor's samples (n - 1 in the "// &
                      'denominator; 0 for one sample): the spread between trajectories', &
                      'bits per drive cycle', 'attractor exponent')
    contains
        subroutine describe(name, long_name, model_units, dims)
            character(len=*), intent(in) :: name, long_name, model_units, dims

            if (.not. allocated(err)) call output_describe(out, 'census/'//name, long_name, &
                                                           model_units, dims, err)
        end subroutine describe
    end subroutine describe_all

end module chain_census_file
