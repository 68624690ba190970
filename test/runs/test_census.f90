!> Attractor censuses (docs/model.md section 13, chain_attractor and chain_census) through the
!> library, without the CLI. Suite `census`: the rules on hand-made states; each sample's
!> start from its own stream; figure 3's chain, whose two known period-8 patterns (the starts
!> of its seeds 2 and 3) are mirror images, counted as two attractors with their fractions
!> (mirror = 'separate') or as one with a flag ('merge', also with the section past half a
!> cycle); a sample rerun alone from its stored start; a phase-shifted copy of an orbit; 1 and
!> 2 threads, and a census stopped and resumed, equal bit for bit; a census along a sweep; bad
!> input named with its key and range; the starts of a census plane exactly its grid. An
!> ensemble of spectra (`exponents = k`, k = 2n and 3): each sample's k exponents those of an
!> ordinary run from its start, bit for bit, the full spectra on the sum rule, each
!> attractor's mean and spread those of its samples; threads, stop and resume, the MPI record
!> and a checkpoint of another k.
module test_census
    use, intrinsic :: iso_fortran_env, only: output_unit
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_negative_inf, ieee_positive_inf
    !$ use omp_lib, only: omp_set_num_threads
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, fmt_int
    use chain_flow, only: flow_t
    use chain_config, only: config_t, read_config
    use chain_state, only: chain_state_t
    use chain_engine, only: chain_t, chain_positions, chain_velocities
    use chain_record, only: memory_sink_t, record_result_t, record_cycles
    use chain_sim, only: initial_state, start_chain
    use chain_files, only: remove_file
    use chain_attractor, only: attractor_t, kind_periodic, kind_chaotic, kind_aperiodic, &
                               orbit_period, sample_kind, mirror_image, mirror_symmetric, &
                               states_close, orbit_offset, match_attractor, site_fractions
    use chain_census, only: census_result_t, census_result_init, census_point_config, &
                            run_census_samples, census_starts, plane_value
    use chain_census_classify, only: classify_census, ensemble_statistics
    use chain_census_checkpoint, only: save_census_checkpoint, load_census_checkpoint, &
                                       sample_record_sizes, pack_sample, unpack_sample
    use chain_monitor, only: monitor_t, stage_samples
    use test_chains, only: flow_of
    use test_sum_rule, only: check_sum_rule
    use testing, only: tally_t, check, check_close
    implicit none
    private
    public :: run_census_tests

    !> Figure 3's chain (n = 15, A = 2.2) with a transient long enough for its period-8
    !> orbits to settle within 1e-6 (their largest exponent is about -0.025 bits per cycle).
    character(len=*), parameter :: fig3 = &
        "&chain n = 15, amplitude = 2.2, omega = 1.5, damping = 0.05, restitution = 0.7 /"// &
        new_line('a')//"&run transient = 2000, cycles = 48, max_period = 8 /"//new_line('a')

    !> A chain of four with three attractors among twelve starts of seed 3 (x_amp = 0.3,
    !> v_amp = 1): aperiodic-nonchaotic (3 samples), chaotic (7), period 3 (2); no rests.
    character(len=*), parameter :: small = &
        "&chain n = 4, amplitude = 1.0, omega = 0.9, damping = 0.05, restitution = 0.7 /"// &
        new_line('a')//"&run transient = 300, cycles = 200, max_period = 8 /"//new_line('a')
    character(len=*), parameter :: small_census = &
        "&census samples = 12, seed = 3, x_amp = 0.3, v_amp = 1.0"

    !> Asks the census to stop once three samples are done.
    type, extends(monitor_t) :: stop_after_three_t
        integer :: calls = 0
        logical :: told_samples = .true.  !! every call was about samples, of the right total
        integer :: total = 0
    contains
        procedure :: keep_going => stop_after_three
    end type stop_after_three_t

contains

    subroutine run_census_tests(t)
        type(tally_t), intent(inout) :: t

        call test_rules(t)
        call test_streams(t)
        call test_two_attractors(t)
        call test_mirror_late_section(t)
        call test_threads_and_resume(t)
        call test_sweep_census(t)
        call test_bad_input(t)
        call test_plane(t)
        call test_bad_plane(t)
        call test_ensemble_statistics(t)
        call test_ensemble(t, 8)
        call test_ensemble(t, 3)
        call test_ensemble_threads_and_resume(t)
    end subroutine run_census_tests

    !> The rules on hand-made numbers: periods, kinds, closeness, the cycle offset, mirror
    !> images, and the site-distance limit.
    subroutine test_rules(t)
        type(tally_t), intent(inout) :: t
        type(attractor_t) :: known(2)
        real(wp) :: orbit(3, 4), half(3, 4)
        integer :: k, id
        logical :: mirrored

        call check(t, orbit_period([8, 8, 4, 2, 1], 16) == 8, 'p = lcm of the periods (8)')
        call check(t, orbit_period([3, 4], 16) == 12 .and. orbit_period([3, 4], 8) == 0, &
                   'p = 12 for periods 3 and 4, or 0 beyond max_period')
        call check(t, orbit_period([2, 0, 2], 16) == 0, 'p = 0 when an oscillator has none')
        call check(t, sample_kind(8, 0.5_wp, 0.0_wp) == kind_periodic, 'periodic first')
        call check(t, sample_kind(0, 0.31_wp, 0.1_wp) == kind_chaotic .and. &
                   sample_kind(0, 0.29_wp, 0.1_wp) == kind_aperiodic .and. &
                   sample_kind(0, -0.1_wp, 0.0_wp) == kind_aperiodic, &
                   'chaotic only when lambda1 > 3 standard errors')
        call check(t, all(mirror_image([1.0_wp, 2.0_wp, 3.0_wp]) == [-3.0_wp, -2.0_wp, -1.0_wp]), &
                   'mirror image: x(i) -> -x(n+1-i)')
        call check(t, mirror_symmetric([1.0_wp, 0.8_wp, 0.8_wp, 1.0_wp]) .and. &
                   .not. mirror_symmetric([1.0_wp, 0.8_wp, 1.0_wp, 1.0_wp]), &
                   'mirror symmetry of the spacings')
        call check(t, states_close([1.0_wp], [0.0_wp], [1.0_wp + 1.9e-6_wp], [1.0e-7_wp], &
                                   1.0e-6_wp) .and. &
                   .not. states_close([1.0_wp], [0.0_wp], [1.0_wp], [1.1e-6_wp], 1.0e-6_wp), &
                   'closeness relative to 1 + |state|, in x and in v')
        ! a period-4 orbit of 3 oscillators, and its states half a period later
        do k = 1, 4
            orbit(:, k) = [0.1_wp*k, -0.2_wp*k, 0.05_wp*k*k]
            half(:, k) = orbit(:, k) + 0.01_wp
        end do
        call check(t, orbit_offset(orbit(:, 3), orbit(:, 3), orbit, orbit, 1.0e-9_wp) == 2, &
                   'cycle offset of the third state: 2')
        known(1)%point = 1
        known(1)%kind = kind_periodic
        known(1)%periods = [4, 2, 4]
        known(1)%orbit_x = orbit
        known(1)%orbit_v = -orbit
        known(1)%half_x = half
        known(1)%half_v = -half
        known(1)%sites = [0.5_wp, 0.5_wp, 0.0_wp, 0.0_wp]
        known(2) = known(1)
        known(2)%kind = kind_chaotic
        call match_attractor(known, 1, kind_periodic, [4, 2, 4], orbit(:, 4), -orbit(:, 4), &
                             [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], 1.0e-9_wp, .true., id, mirrored)
        call check(t, id == 1 .and. .not. mirrored, 'a phase-shifted state is the attractor')
        call match_attractor(known, 2, kind_periodic, [4, 2, 4], orbit(:, 4), -orbit(:, 4), &
                             [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], 1.0e-9_wp, .true., id, mirrored)
        call check(t, id == 0, 'attractors of another point are not matched')
        call match_attractor(known, 1, kind_periodic, [4, 2, 4], mirror_image(half(:, 2)), &
                             -mirror_image(half(:, 2)), [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], &
                             1.0e-9_wp, .true., id, mirrored)
        call check(t, id == 1 .and. mirrored, 'the mirror image half a period on: merged')
        call match_attractor(known, 1, kind_periodic, [4, 2, 4], mirror_image(half(:, 2)), &
                             -mirror_image(half(:, 2)), [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], &
                             1.0e-9_wp, .false., id, mirrored)
        call check(t, id == 0, 'the mirror image kept apart when not merging')
        call match_attractor(known, 1, kind_chaotic, [0, 0, 0], orbit(:, 1), orbit(:, 1), &
                             [0.4_wp, 0.5_wp, 0.1_wp, 0.0_wp], 1.0e-9_wp, .false., id, mirrored)
        call check(t, id == 2, 'sites at L1 distance 0.2 - 0: the same chaotic attractor')
        call match_attractor(known, 1, kind_chaotic, [0, 0, 0], orbit(:, 1), orbit(:, 1), &
                             [0.39_wp, 0.5_wp, 0.11_wp, 0.0_wp], 1.0e-9_wp, .false., id, mirrored)
        call check(t, id == 0, 'sites at L1 distance 0.22: another chaotic attractor')
        call match_attractor(known, 1, kind_chaotic, [0, 0, 0], orbit(:, 1), orbit(:, 1), &
                             [0.0_wp, 0.0_wp, 0.5_wp, 0.5_wp], 1.0e-9_wp, .true., id, mirrored)
        call check(t, id == 2 .and. mirrored, 'sites reversed: the mirror image')
        call check(t, all(site_fractions([1_i8, 3_i8]) == [0.25_wp, 0.75_wp]) .and. &
                   all(site_fractions([0_i8, 0_i8]) == 0), 'site fractions')
    end subroutine test_rules

    !> Sample s starts the same whatever the number of samples, every point alike, within the
    !> amplitudes; samples differ.
    subroutine test_streams(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: few, many
        type(census_result_t) :: a, b

        call config_text(few, fig3//"&census samples = 3, seed = 7, x_amp = 0.3, "// &
                         "v_amp = 1.0 /"//new_line('a')//"&sweep parameter = 'amplitude', "// &
                         "start = 2.2, stop = 2.3, step = 0.1 /", 'streams')
        call config_text(many, fig3//"&census samples = 50, seed = 7, x_amp = 0.3, "// &
                         "v_amp = 1.0 /", 'streams')
        call census_result_init(a, few)
        call census_result_init(b, many)
        call check(t, all(a%x0(:, :, 1) == b%x0(:, :3, 1)) .and. &
                   all(a%v0(:, :, 1) == b%v0(:, :3, 1)), 'sample s does not depend on N')
        call check(t, a%n_points == 2 .and. all(a%x0(:, :, 2) == a%x0(:, :, 1)) .and. &
                   all(a%v0(:, :, 2) == a%v0(:, :, 1)), 'every point gets the same starts')
        call check(t, all(abs(b%x0) <= 0.3_wp) .and. all(abs(b%v0) <= 1.0_wp) .and. &
                   maxval(b%x0) > 0.25_wp .and. minval(b%v0) < -0.9_wp, &
                   'starts uniform within the amplitudes')
        call check(t, any(b%x0(:, 1, 1) /= b%x0(:, 2, 1)) .and. &
                   abs(sum(b%x0(1, :, 1)*b%x0(2, :, 1)))/50 < 0.02_wp, &
                   'samples differ, x(1) and x(2) uncorrelated over the samples')
    end subroutine test_streams

    !> Figure 3's two patterns (the starts of &initial random seeds 2 and 3, x_amp = 0.3,
    !> v_amp = 1): in the order 1, 3, 1, 1 two attractors with fractions 3/4 and 1/4 when kept
    !> apart; one, with the second sample flagged, when merged (they are mirror images). A
    !> sample rerun alone from its stored start; the representative advanced by one cycle as a
    !> start: the same attractor at cycle offset 1.
    subroutine test_two_attractors(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg, point, plain
        type(census_result_t) :: res, shifted
        type(chain_state_t) :: one, three
        type(error_t), allocatable :: err
        integer :: s

        call config_text(cfg, fig3//"&initial kind = 'random', seed = 2, x_amp = 0.3, "// &
                         "v_amp = 1.0 /"//new_line('a')//"&census samples = 4, "// &
                         "mirror = 'separate' /", 'two')
        call initial_state(cfg, one, err)
        cfg%seed = 3
        call initial_state(cfg, three, err)
        call census_result_init(res, cfg)
        do s = 1, 4
            res%x0(:, s, 1) = merge(three%x, one%x, s == 2)
            res%v0(:, s, 1) = merge(three%v, one%v, s == 2)
        end do
        call run_census_samples(cfg, res, err)
        call check(t, .not. allocated(err) .and. all(res%done), 'census of 4 samples runs')
        if (allocated(err)) return
        call classify_census(cfg, res, err)
        call check(t, .not. allocated(err), 'classified')
        if (allocated(err)) return
        call check(t, res%n_attractors == 2, 'separate: two attractors')
        if (res%n_attractors /= 2) return
        call check(t, all(res%attractor(:, 1) == [1, 2, 1, 1]) .and. .not. any(res%mirrored), &
                   'separate: samples 1, 3, 4 on the first, 2 on the second')
        call check(t, all(res%attractors%kind == kind_periodic) .and. &
                   all(res%attractors%period == 8), 'both periodic, period 8')
        call check(t, all(res%fraction(:, 1) == [0.75_wp, 0.25_wp]), 'fractions 3/4, 1/4')
        call check_close(t, res%fraction_stderr(1, 1), sqrt(0.75_wp*0.25_wp/4), &
                         'binomial standard error', rel_tol=4*epsilon(1.0_wp))
        call check_close(t, sum(res%fraction(:, 1)), 1.0_wp, 'fractions sum to one', &
                         abs_tol=4*epsilon(1.0_wp))
        call check(t, all(res%attractors(1)%x == res%x(:, 1, 1)) .and. &
                   res%attractors(2)%first_sample == 2, 'representatives: the first samples')
        cfg%census_mirror = 'merge'
        call classify_census(cfg, res, err)
        call check(t, .not. allocated(err) .and. res%n_attractors == 1, &
                   'merge: the two patterns are mirror images, one attractor')
        if (res%n_attractors /= 1) return
        call check(t, all(res%mirrored(:, 1) .eqv. [.false., .true., .false., .false.]) .and. &
                   res%fraction(1, 1) == 1, 'merge: sample 2 flagged as the mirror image')
        ! sample 2 rerun alone as a plain run from its stored start
        call census_point_config(cfg, 1, point, err)
        plain = point
        plain%initial_kind = 'explicit'
        plain%x0 = res%x0(:, 2, 1)
        plain%v0 = res%v0(:, 2, 1)
        call check(t, rerun_matches(plain, res%x(:, 2, 1), res%v(:, 2, 1), &
                                    res%periods(:, 2, 1)), &
                   'a sample rerun alone from its start ends where the census had it')
        ! the representative, and it advanced by one drive cycle, as starts
        call census_result_init(shifted, cfg)
        shifted%x0(:, 1, 1) = res%attractors(1)%x
        shifted%v0(:, 1, 1) = res%attractors(1)%v
        shifted%x0(:, 2, 1) = res%attractors(1)%orbit_x(:, 2)
        shifted%v0(:, 2, 1) = res%attractors(1)%orbit_v(:, 2)
        shifted%x0(:, 3:, 1) = shifted%x0(:, 1:2, 1)
        shifted%v0(:, 3:, 1) = shifted%v0(:, 1:2, 1)
        call run_census_samples(cfg, shifted, err)
        if (.not. allocated(err)) call classify_census(cfg, shifted, err)
        call check(t, .not. allocated(err) .and. shifted%n_attractors == 1 .and. &
                   .not. any(shifted%mirrored), 'a phase-shifted copy: the same attractor')
        if (shifted%n_attractors /= 1) return
        associate (a => shifted%attractors(1))
            call check(t, orbit_offset(shifted%x(:, 2, 1), shifted%v(:, 2, 1), a%orbit_x, &
                                       a%orbit_v, cfg%census_tolerance) == 1, &
                       'the copy is one cycle ahead (offset 1)')
        end associate
    end subroutine test_two_attractors

    !> With the section at phase 4 (past half a cycle, where half a period later is in the
    !> next cycle) figure 3's two patterns are still found mirror images.
    subroutine test_mirror_late_section(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg
        type(census_result_t) :: res
        type(chain_state_t) :: one, three
        type(error_t), allocatable :: err

        call config_text(cfg, fig3//"&initial kind = 'random', seed = 2, x_amp = 0.3, "// &
                         "v_amp = 1.0 /"//new_line('a')//"&census samples = 2 /", 'late')
        cfg%record%phase = 4
        call initial_state(cfg, one, err)
        cfg%seed = 3
        call initial_state(cfg, three, err)
        call census_result_init(res, cfg)
        res%x0(:, :, 1) = reshape([one%x, three%x], [cfg%model%n, 2])
        res%v0(:, :, 1) = reshape([one%v, three%v], [cfg%model%n, 2])
        call run_census_samples(cfg, res, err)
        if (.not. allocated(err)) call classify_census(cfg, res, err)
        call check(t, .not. allocated(err) .and. res%n_attractors == 1 .and. &
                   all(res%mirrored(:, 1) .eqv. [.false., .true.]), &
                   'section at phase 4: the mirror image found half a period on')
    end subroutine test_mirror_late_section

    !> The run of `plain` (a validated explicit start) ends at (x, v) bit for bit, with the
    !> periods given.
    logical function rerun_matches(plain, x, v, periods) result(same)
        type(config_t), intent(in) :: plain
        real(wp), intent(in) :: x(:), v(:)
        integer, intent(in) :: periods(:)
        type(chain_t) :: chain
        type(memory_sink_t) :: sink
        type(record_result_t) :: out
        type(error_t), allocatable :: err

        same = .false.
        call start_chain(plain, chain, err)
        if (allocated(err)) return
        call record_cycles(plain%record, chain, sink, out, err)
        if (allocated(err)) return
        same = all(chain_positions(chain) == x) .and. all(chain_velocities(chain) == v) .and. &
               all(out%periods == periods)
    end function rerun_matches

    !> A random census of figure 3's chain with 1 and 2 threads, and stopped after three
    !> samples, checkpointed, loaded into a fresh census and finished: equal bit for bit.
    subroutine test_threads_and_resume(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg, other
        type(census_result_t) :: one, two, part, loaded
        type(stop_after_three_t) :: monitor
        type(error_t), allocatable :: err
        character(len=:), allocatable :: path

        call config_text(cfg, fig3//"&census samples = 6, seed = 11, x_amp = 0.3, "// &
                         "v_amp = 1.0 /", 'threads')
        !$ call omp_set_num_threads(1)
        call whole_census(t, cfg, one)
        !$ call omp_set_num_threads(2)
        call whole_census(t, cfg, two)
        call check(t, same(one, two), '1 and 2 threads agree bit for bit')
        call check(t, one%n_attractors >= 1 .and. all(one%attractor(:, 1) >= 1), &
                   'every sample has an attractor')
        call check_close(t, sum(one%fraction(:, 1)), 1.0_wp, 'fractions sum to one', &
                         abs_tol=8*epsilon(1.0_wp))
        call census_result_init(part, cfg)
        monitor%total = 6
        call run_census_samples(cfg, part, err, monitor)
        call check(t, .not. allocated(err) .and. count(part%done) >= 3 .and. &
                   .not. all(part%done), 'the census stops early when asked')
        call check(t, monitor%calls == count(part%done) .and. monitor%told_samples, &
                   'the monitor is told every finished sample, with the total')
        path = temp_prefix()//'census.ckpt'
        call save_census_checkpoint(path, cfg, part, err)
        call check(t, .not. allocated(err), 'checkpoint written')
        call census_result_init(loaded, cfg)
        call load_census_checkpoint(path, cfg, loaded, err)
        call check(t, .not. allocated(err) .and. all(loaded%done .eqv. part%done) .and. &
                   all(loaded%x == part%x) .and. all(loaded%exponents == part%exponents), &
                   'checkpoint round trip keeps the finished samples bit for bit')
        call run_census_samples(cfg, loaded, err)
        if (.not. allocated(err)) call classify_census(cfg, loaded, err)
        call check(t, .not. allocated(err) .and. all(loaded%done), 'the resumed census ends')
        call check(t, same(one, loaded), 'stopped + resumed = uninterrupted, bit for bit')
        other = cfg
        other%input_text = cfg%input_text//' '
        call load_census_checkpoint(path, other, loaded, err)
        call check(t, allocated(err), 'a checkpoint of another input is refused')
        call remove_file(path)
    end subroutine test_threads_and_resume

    !> Along a sweep: the same starts at each point, attractors distinct between points, the
    !> fractions of each point summing to one.
    subroutine test_sweep_census(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg
        type(census_result_t) :: res
        integer, allocatable :: points(:)
        integer :: a

        call config_text(cfg, fig3//"&census samples = 3, x_amp = 0.3, v_amp = 1.0 /"// &
                         new_line('a')//"&sweep parameter = 'amplitude', start = 2.2, "// &
                         "stop = 2.3, step = 0.1 /", 'sweep')
        call whole_census(t, cfg, res)
        call check(t, res%n_points == 2 .and. all(res%values == [2.2_wp, 2.2_wp + 0.1_wp]), &
                   'two points, values from the index')
        points = [(res%attractors(a)%point, a=1, res%n_attractors)]
        call check(t, all(points(res%attractor(:, 1)) == 1) .and. &
                   all(points(res%attractor(:, 2)) == 2), &
                   'attractors at different points are distinct, each of its own point')
        call check(t, all(points(2:) >= points(:size(points) - 1)), &
                   'ids in the order found, point by point')
        call check_close(t, sum(res%fraction(:, 1)), 1.0_wp, 'fractions of point 1 sum to one', &
                         abs_tol=4*epsilon(1.0_wp))
        call check_close(t, sum(res%fraction(:, 2)), 1.0_wp, 'fractions of point 2 sum to one', &
                         abs_tol=4*epsilon(1.0_wp))
    end subroutine test_sweep_census

    !> Each bad value of &census refused with its key and the allowed range.
    subroutine test_bad_input(t)
        type(tally_t), intent(inout) :: t
        character(len=*), parameter :: nl = achar(10)
        character(len=*), parameter :: cases(10) = [character(len=160) :: &
            "&census samples = 0 /", "&census samples = 10000001 /", &
            "&census exponents = 0 /", "&census exponents = 31 /", &
            "&census x_amp = 0.5 /", "&census v_amp = -1 /", "&census tolerance = 0 /", &
            "&census mirror = 'both' /", &
            "&census /"//nl//"&continuation parameter = 'amplitude', stop = 2.5, step = 0.1 /", &
            "&census /"//nl//"&sweep parameter = 'amplitude', start = 2, stop = 3, step = 1, "// &
            "parameter2 = 'omega', start2 = 1, stop2 = 2, step2 = 1 /"]
        !> what the message must say: the key and its value, and the allowed range
        character(len=*), parameter :: keys(10) = [character(len=40) :: &
            "&census: samples = 0 ", "&census: samples = 10000001 ", &
            "&census: exponents = 0 ", "&census: exponents = 31 ", "&census: x_amp = 0.5", &
            "&census: v_amp = -1.0", "&census: tolerance = 0.0", "&census: mirror = 'both'", &
            "&census cannot be combined", "&census runs at one point"]
        character(len=*), parameter :: ranges(10) = [character(len=40) :: &
            "is outside [1, 10000000]", "is outside [1, 10000000]", &
            "is outside [1, 2n = 30]", "is outside [1, 2n = 30]", &
            "outside [0, half the smallest spacing", "is outside [0, 1e6]", &
            "is outside (0, 1)", "is not one of 'merge', 'separate'", "with &continuation", &
            "with parameter2 is not supported"]
        type(config_t) :: cfg
        type(error_t), allocatable :: err
        integer :: j

        do j = 1, size(cases)
            call read_text_config(fig3//trim(cases(j)), 'bad', cfg, err)
            call check(t, allocated(err), 'refused: '//trim(cases(j)))
            if (allocated(err)) call check(t, index(err%message, trim(keys(j))) > 0 .and. &
                                           index(err%message, trim(ranges(j))) > 0, &
                                           'the message names the key and range: '// &
                                           err%message)
        end do
    end subroutine test_bad_input

    !> A census plane (x3, v5) around an explicit state: plane_points**2 samples, sample
    !> 1 + i + m j at grid value i of x3 and j of v5, the ends of each range exact, the steps
    !> even, every other coordinate the fixed state's bit for bit; every point of a sweep
    !> alike. Then the same plane from &initial rest: the other coordinates zero.
    subroutine test_plane(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg
        type(census_result_t) :: res
        type(error_t), allocatable :: err
        integer, parameter :: m = 7
        real(wp), parameter :: x_lo = -0.35_wp, x_hi = 0.3_wp, v_lo = -1.1_wp, v_hi = 0.9_wp
        real(wp) :: fixed_x(15), fixed_v(15), grid_x(m), grid_v(m)
        integer :: i, j, s, k
        logical :: grid_ok, others_ok
        character(len=:), allocatable :: state

        do k = 1, 15
            fixed_x(k) = 0.01_wp*k - 0.07_wp
            fixed_v(k) = 0.1_wp - 0.02_wp*k
        end do
        state = "&initial kind = 'explicit', x0 = "//list(fixed_x)//", v0 = "// &
                list(fixed_v)//" /"//new_line('a')
        call config_text(cfg, fig3//state//"&census plane = 'x3', 'V5', plane_range = "// &
                         "-0.35, 0.3, -1.1, 0.9, plane_points = 7 /"//new_line('a')// &
                         "&sweep parameter = 'amplitude', start = 2.2, stop = 2.3, "// &
                         "step = 0.1 /", 'plane')
        call check(t, cfg%census_samples == m*m, 'samples = plane_points**2 when left out')
        call census_starts(res, cfg, err)
        call check(t, .not. allocated(err), 'the plane starts are made')
        if (allocated(err)) return
        grid_x = [(plane_value(x_lo, x_hi, i, m), i=0, m - 1)]
        grid_v = [(plane_value(v_lo, v_hi, i, m), i=0, m - 1)]
        call check(t, grid_x(1) == x_lo .and. grid_x(m) == x_hi .and. grid_v(1) == v_lo .and. &
                   grid_v(m) == v_hi, 'the grid ends are the range ends, exactly')
        call check_close(t, maxval(grid_x(2:) - grid_x(:m - 1)), (x_hi - x_lo)/(m - 1), &
                         'even steps in x3 (largest)', abs_tol=4*epsilon(1.0_wp))
        call check_close(t, minval(grid_v(2:) - grid_v(:m - 1)), (v_hi - v_lo)/(m - 1), &
                         'even steps in v5 (smallest)', abs_tol=4*epsilon(1.0_wp))
        grid_ok = .true.
        others_ok = .true.
        do j = 0, m - 1
            do i = 0, m - 1
                s = 1 + i + m*j
                grid_ok = grid_ok .and. res%x0(3, s, 1) == grid_x(i + 1) .and. &
                          res%v0(5, s, 1) == grid_v(j + 1)
                others_ok = others_ok .and. all(res%x0([1, 2, (k, k=4, 15)], s, 1) == &
                                                fixed_x([1, 2, (k, k=4, 15)])) .and. &
                            all(res%v0([(k, k=1, 4), (k, k=6, 15)], s, 1) == &
                                fixed_v([(k, k=1, 4), (k, k=6, 15)]))
            end do
        end do
        call check(t, grid_ok, 'sample 1 + i + m j at grid value i of x3 and j of v5')
        call check(t, others_ok, 'every other coordinate the explicit state, bit for bit')
        call check(t, all(res%x0(:, :, 2) == res%x0(:, :, 1)) .and. &
                   all(res%v0(:, :, 2) == res%v0(:, :, 1)), 'every point gets the same plane')
        call config_text(cfg, fig3//"&census plane = 'v1', 'x15', plane_range = -1, 1, "// &
                         "-0.2, 0.2, plane_points = 3, samples = 9 /", 'plane_rest')
        call census_starts(res, cfg, err)
        call check(t, .not. allocated(err), 'a plane from rest')
        if (allocated(err)) return
        call check(t, all(res%v0(1, :, 1) == [-1, 0, 1, -1, 0, 1, -1, 0, 1]) .and. &
                   all(res%x0(15, :, 1) == [-0.2_wp, -0.2_wp, -0.2_wp, 0.0_wp, 0.0_wp, &
                                           0.0_wp, 0.2_wp, 0.2_wp, 0.2_wp]) .and. &
                   all(res%x0(:14, :, 1) == 0) .and. all(res%v0(2:, :, 1) == 0), &
                   'v1 fastest, then x15; the rest at rest')
    end subroutine test_plane

    !> Each bad plane refused, naming what is wrong.
    subroutine test_bad_plane(t)
        type(tally_t), intent(inout) :: t
        character(len=*), parameter :: cases(8) = [character(len=120) :: &
            "plane = 'x3', 'v3', plane_range = -0.1, 0.1, -1, 1, samples = 50", &
            "plane = 'x3', 'x3', plane_range = -0.1, 0.1, -1, 1", &
            "plane = 'x16', 'v3', plane_range = -0.1, 0.1, -1, 1", &
            "plane = 'y3', 'v3', plane_range = -0.1, 0.1, -1, 1", &
            "plane = 'x3', 'v3'", "plane_points = 10", &
            "plane = 'x3', 'v3', plane_range = -0.1, 0.1, 1, -1", &
            "plane = 'x3', 'v3', plane_range = -0.1, 0.1, -1, 1, plane_points = 1"]
        character(len=*), parameter :: needles(8) = [character(len=72) :: &
            "samples = 50 with a plane must be left out or equal plane_points**2 = 10000", &
            "names one coordinate twice", "plane = 'x16' is not a coordinate", &
            "plane = 'y3' is not a coordinate", "a plane needs plane_range", &
            "plane_range and plane_points need a plane", &
            "second coordinate (v3) = 1.0000000, -1.0000000 must be finite with min < max", &
            "plane_points = 1 is outside [2, 3162]"]
        type(config_t) :: cfg
        type(census_result_t) :: res
        type(error_t), allocatable :: err
        integer :: j

        do j = 1, size(cases)
            call read_text_config(fig3//"&census "//trim(cases(j))//" /", 'bad_plane', cfg, err)
            call check(t, allocated(err), 'refused: '//trim(cases(j)))
            if (allocated(err)) call check(t, index(err%message, trim(needles(j))) > 0, &
                                           'the message says why: '//err%message)
        end do
        ! a start through the neighbour: found when the starts are made, before any run
        call config_text(cfg, fig3//"&census plane = 'x3', 'x4', plane_range = -0.6, 0.6, "// &
                         "-0.6, 0.6, plane_points = 3 /", 'plane_overlap')
        call census_starts(res, cfg, err)
        call check(t, allocated(err), 'a start overlapping its neighbour is refused')
        if (allocated(err)) call check(t, index(err%message, "x3 = 0.60000000, x4 = "// &
                                                "-0.60000000) puts an oscillator through") > 0, &
                                       'the message names the start: '//err%message)
    end subroutine test_bad_plane

    !> ensemble_statistics on hand-made numbers: the mean and the sample standard deviation
    !> (n - 1), 0 for one member; -infinity in every member, or in some.
    subroutine test_ensemble_statistics(t)
        type(tally_t), intent(inout) :: t
        real(wp) :: values(3, 4), mean(3), spread(3), one_mean(1), one_spread(1), minus_inf

        minus_inf = ieee_value(1.0_wp, ieee_negative_inf)
        values(1, :) = [1.0_wp, 2.0_wp, 3.0_wp, 4.0_wp]
        values(2, :) = minus_inf
        values(3, :) = [0.5_wp, minus_inf, 0.25_wp, 0.5_wp]
        call ensemble_statistics(values, mean, spread)
        call check_close(t, mean(1), 2.5_wp, 'ensemble mean of 1, 2, 3, 4', &
                         abs_tol=4*epsilon(1.0_wp))
        call check_close(t, spread(1), sqrt(5.0_wp/3), 'ensemble spread of 1, 2, 3, 4: '// &
                         'sqrt(5/3), n - 1 in the denominator', rel_tol=4*epsilon(1.0_wp))
        call check(t, mean(2) == minus_inf .and. spread(2) == 0, &
                   'every member -infinity: mean -infinity, spread 0')
        call check(t, mean(3) == minus_inf .and. spread(3) == ieee_value(1.0_wp, &
                                                                         ieee_positive_inf), &
                   'some members -infinity: mean -infinity, spread +infinity')
        call ensemble_statistics(reshape([-0.3_wp], [1, 1]), one_mean, one_spread)
        call check(t, one_mean(1) == -0.3_wp .and. one_spread(1) == 0, &
                   'one member: its value, spread 0')
    end subroutine test_ensemble_statistics

    !> A census of the small chain with exponents = k: k exponents per sample, descending, the
    !> first lambda1 itself; every sample's exponents and standard errors those of an ordinary
    !> run with &lyapunov vectors = k from its start, bit for bit (and its impacts per bond);
    !> with k = 2n each sample's full spectrum on the sum rule, its impacts per cycle from the
    !> census's own counts; each attractor's mean and spread those of its samples' exponents,
    !> recomputed here by Welford's updates (another order of the sums: rounding only).
    subroutine test_ensemble(t, k)
        type(tally_t), intent(inout) :: t
        integer, intent(in) :: k
        type(config_t) :: cfg, plain
        type(census_result_t) :: res
        type(chain_t) :: chain
        type(memory_sink_t) :: sink
        type(record_result_t) :: out
        type(error_t), allocatable :: err
        type(flow_t) :: flow
        character(len=:), allocatable :: label
        real(wp) :: residual, worst, expected, spread, mean(k), m2(k), step(k)
        integer :: s, a, j, members, reruns_equal, largest
        logical :: reran

        label = 'k = '//fmt_int(k)
        call config_text(cfg, small//small_census//", exponents = "//fmt_int(k)//" /", &
                         'ensemble')
        call whole_census(t, cfg, res)
        if (.not. all(res%done)) return
        call check(t, all(shape(res%exponents) == [k, 12, 1]) .and. &
                   all(shape(res%exponents_stderr) == [k, 12, 1]) .and. &
                   all(shape(res%attractor_exponents) == [k, res%n_attractors]) .and. &
                   all(shape(res%attractor_spread) == [k, res%n_attractors]), &
                   label//': k exponents per sample and per attractor')
        call check(t, all([(res%attractors(a)%lambda1 == &
                            res%exponents(1, res%attractors(a)%first_sample, &
                                          res%attractors(a)%point) .and. &
                            res%attractors(a)%stderr1 == &
                            res%exponents_stderr(1, res%attractors(a)%first_sample, &
                                                 res%attractors(a)%point), &
                            a=1, res%n_attractors)]), &
                   label//': the first exponent is lambda1, bit for bit')
        call check(t, all(res%exponents(2:, :, :) <= res%exponents(:k - 1, :, :)), &
                   label//': descending')
        call check(t, res%n_attractors == 3, label//': three attractors')
        ! each sample alone, as an ordinary run of the same chain from its start
        reruns_equal = 0
        worst = 0
        do s = 1, res%n_samples
            call config_text(plain, small//"&initial kind = 'explicit', x0 = "// &
                             list(res%x0(:, s, 1))//", v0 = "//list(res%v0(:, s, 1))//" /"// &
                             new_line('a')//"&lyapunov enabled = .true., vectors = "// &
                             fmt_int(k)//" /", 'ensemble_rerun')
            call start_chain(plain, chain, err)
            if (.not. allocated(err)) call record_cycles(plain%record, chain, sink, out, err)
            reran = .not. allocated(err)
            if (reran) reran = size(out%lyapunov%bits_per_cycle) == k
            if (reran) then
                if (all(out%lyapunov%bits_per_cycle == res%exponents(:, s, 1)) .and. &
                    all(out%lyapunov%stderr_bits == res%exponents_stderr(:, s, 1)) .and. &
                    all(out%site_counts == res%sites(:, s, 1))) reruns_equal = reruns_equal + 1
            end if
            if (k /= 2*cfg%model%n .or. .not. reran) cycle
            ! the sum rule, with the impacts per cycle the census counted
            flow = flow_of(chain)
            ! (check_sum_rule passes over runs with rests, whose sum is -infinity)
            call check(t, out%sticks == 0, label//', census sample '//fmt_int(s)// &
                       ': no rests, so the sum rule applies')
            associate (c => real(sum(res%sites(:, s, 1)), wp)/cfg%record%cycles)
                call check_sum_rule(t, label//', census sample '//fmt_int(s), cfg%model%n, &
                                    flow, cfg%model%restitution, c, res%exponents(:, s, 1), &
                                    out%sticks)
                expected = -2*flow%damping*cfg%model%n*flow%period + &
                           2*log(cfg%model%restitution)*c
                residual = abs(sum(res%exponents(:, s, 1))*log(2.0_wp) - expected)
                worst = max(worst, residual)
            end associate
        end do
        call check(t, reruns_equal == res%n_samples, label//': every sample rerun alone '// &
                   'with &lyapunov vectors = k gives its k exponents and errors, bit for '// &
                   'bit ('//fmt_int(reruns_equal)//' of '//fmt_int(res%n_samples)//')')
        if (k == 2*cfg%model%n) write (output_unit, '(a,i0,a,es9.2,a)') &
            '  census ensemble of ', res%n_samples, ' full spectra (2n = 8): largest sum-rule '// &
            'residual ', worst, ' nats per cycle'
        ! each attractor's mean and spread, from its samples
        largest = 0
        do a = 1, res%n_attractors
            members = 0
            mean = 0
            m2 = 0
            do s = 1, res%n_samples
                if (res%attractor(s, 1) /= a) cycle
                members = members + 1
                step = res%exponents(:, s, 1) - mean
                mean = mean + step/members
                m2 = m2 + step*(res%exponents(:, s, 1) - mean)
            end do
            largest = max(largest, members)
            do j = 1, k
                call check_close(t, res%attractor_exponents(j, a), mean(j), label// &
                                 ': attractor '//fmt_int(a)//', exponent '//fmt_int(j)// &
                                 ': mean of its samples', abs_tol=1.0e-13_wp, rel_tol=1.0e-13_wp)
                spread = 0
                if (members > 1) spread = sqrt(m2(j)/(members - 1))
                call check_close(t, res%attractor_spread(j, a), spread, label// &
                                 ': attractor '//fmt_int(a)//', exponent '//fmt_int(j)// &
                                 ': spread of its samples', abs_tol=1.0e-13_wp, &
                                 rel_tol=1.0e-12_wp)
            end do
        end do
        call check(t, largest >= 2 .and. any(res%attractor_spread > 0), &
                   label//': an attractor of several samples, with a spread')
    end subroutine test_ensemble

    !> The small chain's census of full spectra (k = 2n = 8) with 1 and 2 threads, and stopped
    !> after three samples, checkpointed and resumed: equal bit for bit, exponents, errors,
    !> means and spreads included. A sample's MPI record (pack_sample) restores its exponents
    !> bit for bit; a checkpoint of another k is refused, by its input text and by its header.
    subroutine test_ensemble_threads_and_resume(t)
        type(tally_t), intent(inout) :: t
        type(config_t) :: cfg, other
        type(census_result_t) :: one, two, part, loaded, fresh
        type(stop_after_three_t) :: monitor
        type(error_t), allocatable :: err
        character(len=:), allocatable :: path
        real(wp), allocatable :: reals(:)
        integer(i8), allocatable :: ints(:)
        integer :: nr, ni

        call config_text(cfg, small//small_census//", exponents = 8 /", 'ensemble_threads')
        !$ call omp_set_num_threads(1)
        call whole_census(t, cfg, one)
        !$ call omp_set_num_threads(2)
        call whole_census(t, cfg, two)
        call check(t, same(one, two), 'k = 8: 1 and 2 threads agree bit for bit')
        ! one sample's record, as the MPI driver sends it
        call sample_record_sizes(cfg%model%n, 8, nr, ni)
        call check(t, nr == 2*4 + 2*8 .and. ni == 2 + 2*4, &
                   'k = 8: a record of 24 reals and 10 integers')
        allocate (reals(nr), ints(ni))
        call pack_sample(one, 5, 1, reals, ints)
        call census_result_init(fresh, cfg)
        call unpack_sample(reals, ints, 5, 1, fresh)
        call check(t, all(fresh%exponents(:, 5, 1) == one%exponents(:, 5, 1)) .and. &
                   all(fresh%exponents_stderr(:, 5, 1) == one%exponents_stderr(:, 5, 1)) .and. &
                   fresh%done(5, 1), &
                   'k = 8: the MPI record restores the exponents and errors bit for bit')
        ! stopped after three samples, resumed from the checkpoint
        call census_result_init(part, cfg)
        monitor%total = 12
        call run_census_samples(cfg, part, err, monitor)
        call check(t, .not. allocated(err) .and. count(part%done) >= 3 .and. &
                   .not. all(part%done), 'k = 8: the census stops early when asked')
        path = temp_prefix()//'ensemble.ckpt'
        call save_census_checkpoint(path, cfg, part, err)
        call check(t, .not. allocated(err), 'k = 8: checkpoint written')
        call census_result_init(loaded, cfg)
        call load_census_checkpoint(path, cfg, loaded, err)
        call check(t, .not. allocated(err) .and. all(loaded%done .eqv. part%done) .and. &
                   all(loaded%exponents == part%exponents) .and. &
                   all(loaded%exponents_stderr == part%exponents_stderr), &
                   'k = 8: the checkpoint keeps the finished samples exponents bit for bit')
        call run_census_samples(cfg, loaded, err)
        if (.not. allocated(err)) call classify_census(cfg, loaded, err)
        call check(t, .not. allocated(err) .and. same(one, loaded), &
                   'k = 8: stopped + resumed = uninterrupted, bit for bit')
        ! a checkpoint of another k: another input, or (the same text) another header
        call config_text(other, small//small_census//", exponents = 3 /", 'ensemble_threads')
        call census_result_init(fresh, other)
        call load_census_checkpoint(path, other, fresh, err)
        call check(t, allocated(err), 'a checkpoint of exponents = 8 refused with exponents = 3')
        other = cfg
        other%census_exponents = 3
        call census_result_init(fresh, other)
        call load_census_checkpoint(path, other, fresh, err)
        call check(t, allocated(err), 'a checkpoint with k = 8 in its header refused for k = 3')
        call remove_file(path)
    end subroutine test_ensemble_threads_and_resume

    logical function stop_after_three(monitor, stage, done, total) result(keep_going)
        class(stop_after_three_t), intent(inout) :: monitor
        integer, intent(in) :: stage
        integer(i8), intent(in) :: done, total

        monitor%calls = monitor%calls + 1
        monitor%told_samples = monitor%told_samples .and. stage == stage_samples .and. &
                               done == monitor%calls .and. total == monitor%total
        keep_going = done < 3
    end function stop_after_three

    subroutine whole_census(t, cfg, res)
        type(tally_t), intent(inout) :: t
        type(config_t), intent(in) :: cfg
        type(census_result_t), intent(out) :: res
        type(error_t), allocatable :: err

        call census_result_init(res, cfg)
        call run_census_samples(cfg, res, err)
        if (.not. allocated(err)) call classify_census(cfg, res, err)
        call check(t, .not. allocated(err) .and. all(res%done), 'census runs')
    end subroutine whole_census

    logical function same(a, b)
        type(census_result_t), intent(in) :: a, b
        integer :: k

        same = all(a%x == b%x) .and. all(a%v == b%v) .and. all(a%periods == b%periods) .and. &
               all(a%sites == b%sites) .and. all(a%x0 == b%x0) .and. &
               all(a%attractor == b%attractor) .and. all(a%mirrored .eqv. b%mirrored) .and. &
               a%n_attractors == b%n_attractors .and. a%n_exponents == b%n_exponents
        if (.not. same) return
        same = all(a%exponents == b%exponents) .and. &
               all(a%exponents_stderr == b%exponents_stderr) .and. &
               all(a%attractor_exponents == b%attractor_exponents) .and. &
               all(a%attractor_spread == b%attractor_spread)
        if (.not. same) return
        same = all(a%fraction == b%fraction)
        do k = 1, a%n_attractors
            same = same .and. all(a%attractors(k)%x == b%attractors(k)%x) .and. &
                   a%attractors(k)%kind == b%attractors(k)%kind
        end do
    end function same

    !> Reals as a namelist list, each to 17 significant digits (read back bit for bit).
    function list(values) result(text)
        real(wp), intent(in) :: values(:)
        character(len=:), allocatable :: text
        character(len=32) :: item
        integer :: q

        text = ''
        do q = 1, size(values)
            write (item, '(es24.17)') values(q)
            text = text//trim(adjustl(item))
            if (q < size(values)) text = text//', '
        end do
    end function list

    !> The configuration of a namelist text (the test stops on a bad one).
    subroutine config_text(cfg, text, name)
        type(config_t), intent(out) :: cfg
        character(len=*), intent(in) :: text, name
        type(error_t), allocatable :: err

        call read_text_config(text, name, cfg, err)
        if (allocated(err)) then
            write (output_unit, '(a)') 'test_census: bad test input: '//err%message
            error stop 1
        end if
    end subroutine config_text

    !> A namelist text written to a temporary file and read back.
    subroutine read_text_config(text, name, cfg, err)
        character(len=*), intent(in) :: text, name
        type(config_t), intent(out) :: cfg
        type(error_t), allocatable, intent(out) :: err
        character(len=:), allocatable :: tmp
        integer :: u

        tmp = temp_prefix()
        open (newunit=u, file=tmp//name//'.nml', status='replace', action='write')
        write (u, '(a)') text
        write (u, '(a)') "&output file = '"//tmp//name//".h5' /"
        close (u)
        call read_config(tmp//name//'.nml', cfg, err)
        call remove_file(tmp//name//'.nml')
    end subroutine read_text_config

    !> A fresh prefix for temporary files: $TMPDIR (or /tmp)/impactchain-test-census-<clock>-
    function temp_prefix() result(prefix)
        character(len=:), allocatable :: prefix
        character(len=512) :: dir
        character(len=24) :: stamp
        integer :: length, status
        integer(i8) :: clock

        call get_environment_variable('TMPDIR', dir, length, status)
        if (status /= 0 .or. length == 0) dir = '/tmp'
        call system_clock(clock)
        write (stamp, '(i0)') clock
        prefix = trim(dir)//'/impactchain-test-census-'//trim(stamp)//'-'
    end function temp_prefix

end module test_census
