!> The classification of a census (docs/model.md section 13): its samples, all done, told apart
!> by the rules of chain_attractor into attractors (a periodic one with its states over one
!> period), each point's fraction of samples on each, and each attractor's ensemble of
!> spectra (section 13.4).
module chain_census_classify
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_positive_inf
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_engine, only: chain_t, chain_positions, chain_velocities, chain_period
    use chain_config, only: config_t
    use chain_model, only: model_t
    use chain_section, only: chain_at_section, advance_to_point
    use chain_event_log, only: event_log_t, event_log_init
    use chain_attractor, only: attractor_t, kind_periodic, orbit_period, sample_kind, &
                               site_fractions, mirror_symmetric, match_attractor
    use chain_census, only: census_result_t, census_point_config
    implicit none
    private
    public :: classify_census, ensemble_statistics, orbit_states

contains

    !> Classify every sample (all done), point by point in sample order, by the rules of
    !> chain_attractor; then the fractions. A periodic attractor's states over one period, and
    !> half a drive period after each, come from its representative's last record
    !> (orbit_states). Attractors at different points are distinct.
    subroutine classify_census(cfg, res, err)
        type(config_t), intent(in) :: cfg
        type(census_result_t), intent(inout) :: res
        type(error_t), allocatable, intent(out) :: err
        type(config_t) :: point
        type(attractor_t), allocatable :: grown(:)
        real(wp), allocatable :: sites(:)
        integer :: s, p, a, period, kind, id
        logical :: mirror, mirrored

        res%n_attractors = 0
        if (allocated(res%attractors)) deallocate (res%attractors)
        allocate (res%attractors(8))
        do p = 1, res%n_points
            call census_point_config(cfg, p, point, err)
            if (allocated(err)) return
            mirror = cfg%census_mirror == 'merge' .and. mirror_symmetric(point%model%spacing)
            do s = 1, res%n_samples
                period = orbit_period(res%periods(:, s, p), point%record%max_period)
                kind = sample_kind(period, res%exponents(1, s, p), &
                                   res%exponents_stderr(1, s, p))
                sites = site_fractions(res%sites(:, s, p))
                call match_attractor(res%attractors(:res%n_attractors), p, kind, &
                                     res%periods(:, s, p), res%x(:, s, p), res%v(:, s, p), &
                                     sites, cfg%census_tolerance, mirror, id, mirrored)
                if (id == 0) then
                    if (res%n_attractors == size(res%attractors)) then
                        allocate (grown(2*size(res%attractors)))
                        grown(:res%n_attractors) = res%attractors
                        call move_alloc(grown, res%attractors)
                    end if
                    id = res%n_attractors + 1
                    call new_attractor(point, res, s, p, kind, period, sites, &
                                       res%attractors(id), err)
                    if (allocated(err)) return
                    res%n_attractors = id
                end if
                res%attractor(s, p) = id
                res%mirrored(s, p) = mirrored
            end do
        end do
        res%attractors = res%attractors(:res%n_attractors)
        deallocate (res%fraction, res%fraction_stderr)
        allocate (res%fraction(res%n_attractors, res%n_points))
        allocate (res%fraction_stderr(res%n_attractors, res%n_points))
        do p = 1, res%n_points
            do a = 1, res%n_attractors
                res%fraction(a, p) = real(count(res%attractor(:, p) == a), wp)/res%n_samples
            end do
        end do
        res%fraction_stderr = sqrt(res%fraction*(1 - res%fraction)/res%n_samples)
        call attractor_ensembles(res)
    end subroutine classify_census

    !> Each attractor's samples (at its point, in sample order) as an ensemble of spectra: the
    !> mean of their exponents and the spread between them (ensemble_statistics).
    subroutine attractor_ensembles(res)
        type(census_result_t), intent(inout) :: res
        integer, allocatable :: sizes(:), first(:), filled(:), members(:)
        integer :: s, p, a, na

        na = res%n_attractors
        if (allocated(res%attractor_exponents)) deallocate (res%attractor_exponents)
        if (allocated(res%attractor_spread)) deallocate (res%attractor_spread)
        allocate (res%attractor_exponents(res%n_exponents, na))
        allocate (res%attractor_spread(res%n_exponents, na))
        ! the members of each attractor, one after the other (a counting sort of the samples)
        allocate (sizes(na), first(na), filled(na), members(res%n_samples*res%n_points))
        sizes = 0
        do p = 1, res%n_points
            do s = 1, res%n_samples
                sizes(res%attractor(s, p)) = sizes(res%attractor(s, p)) + 1
            end do
        end do
        if (na > 0) first(1) = 1
        do a = 2, na
            first(a) = first(a - 1) + sizes(a - 1)
        end do
        filled = 0
        do p = 1, res%n_points
            do s = 1, res%n_samples
                a = res%attractor(s, p)
                members(first(a) + filled(a)) = s
                filled(a) = filled(a) + 1
            end do
        end do
        do a = 1, na
            associate (mine => members(first(a):first(a) + sizes(a) - 1))
                call ensemble_statistics(res%exponents(:, mine, res%attractors(a)%point), &
                                         res%attractor_exponents(:, a), &
                                         res%attractor_spread(:, a))
            end associate
        end do
    end subroutine attractor_ensembles

    !> The mean over m members of k exponents each (values(k, m); the members in the order
    !> given; zeros without members) and the spread between them, the sample standard deviation
    !> sqrt(sum (x - mean)**2 / (m - 1)), 0 for one member. An exponent of -infinity in a
    !> member (a direction removed by a rest on a wall, or K = 0) makes that mean -infinity, and
    !> its spread 0 when every member's is -infinity, +infinity when some are finite.
    pure subroutine ensemble_statistics(values, mean, spread)
        real(wp), intent(in) :: values(:, :)
        real(wp), intent(out) :: mean(:), spread(:)
        integer :: j, m

        m = size(values, 2)
        mean = 0
        spread = 0
        if (m == 0) return
        do j = 1, size(values, 1)
            mean(j) = sum(values(j, :))/m
            if (m == 1) then
                spread(j) = 0
            else if (all(ieee_is_finite(values(j, :)))) then
                spread(j) = sqrt(sum((values(j, :) - mean(j))**2)/(m - 1))
            else if (all(values(j, :) == values(j, 1))) then
                spread(j) = 0
            else
                spread(j) = ieee_value(1.0_wp, ieee_positive_inf)
            end if
        end do
    end subroutine ensemble_statistics

    !> The attractor that sample s of point p founds, with it as the representative. When its
    !> state cannot be run again as a fresh chain (chain_at_section refuses it), the orbit is
    !> its own state alone: copies at another cycle offset, and mirror images, then found
    !> attractors of their own.
    subroutine new_attractor(point, res, s, p, kind, period, sites, attractor, err)
        type(config_t), intent(in) :: point
        type(census_result_t), intent(in) :: res
        integer, intent(in) :: s, p, kind, period
        real(wp), intent(in) :: sites(:)
        type(attractor_t), intent(out) :: attractor
        type(error_t), allocatable, intent(out) :: err

        attractor%point = p
        attractor%first_sample = s
        attractor%kind = kind
        attractor%period = period
        attractor%periods = res%periods(:, s, p)
        attractor%lambda1 = res%exponents(1, s, p)
        attractor%stderr1 = res%exponents_stderr(1, s, p)
        attractor%x = res%x(:, s, p)
        attractor%v = res%v(:, s, p)
        attractor%sites = sites
        if (kind /= kind_periodic) return
        call orbit_states(point%model, point%record%phase, attractor%x, attractor%v, period, &
                          attractor%orbit_x, attractor%orbit_v, attractor%half_x, &
                          attractor%half_v, err)
        if (.not. allocated(err)) return
        deallocate (err)
        attractor%orbit_x = reshape(attractor%x, [size(attractor%x), 1])
        attractor%orbit_v = reshape(attractor%v, [size(attractor%v), 1])
        allocate (attractor%half_x(size(attractor%x), 0), attractor%half_v(size(attractor%x), 0))
    end subroutine new_attractor

    !> The states of a period-p orbit through (x, v) on the section (drive phase `phase`):
    !> orbit(:, k+1) k drive cycles later (k = 0..p-1; orbit(:, 1) is (x, v) itself), and
    !> half(:, k+1) half a drive period after each. They are run from (x, v) as a fresh chain
    !> on the section (chain_at_section: every oscillator moving, every bond searched).
    subroutine orbit_states(model, phase, x, v, p, orbit_x, orbit_v, half_x, half_v, err)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase, x(:), v(:)
        integer, intent(in) :: p
        real(wp), allocatable, intent(out) :: orbit_x(:, :), orbit_v(:, :)
        real(wp), allocatable, intent(out) :: half_x(:, :), half_v(:, :)
        type(error_t), allocatable, intent(out) :: err
        type(chain_t) :: chain
        type(event_log_t) :: log
        real(wp) :: s0, s_half, period
        integer(i8) :: cycle_half
        integer :: k

        allocate (orbit_x(size(x), p), orbit_v(size(x), p), half_x(size(x), p))
        allocate (half_v(size(x), p))
        orbit_x(:, 1) = x
        orbit_v(:, 1) = v
        call event_log_init(log, .false., 0)
        call chain_at_section(model, phase, x, v, chain, err)
        if (allocated(err)) return
        period = chain_period(chain)
        s0 = phase/model%omega
        do k = 0, p - 1
            cycle_half = k
            s_half = s0 + period/2
            if (s_half >= period) then
                cycle_half = k + 1
                s_half = s_half - period
            end if
            call advance_to_point(chain, cycle_half, s_half, log, err)
            if (allocated(err)) return
            half_x(:, k + 1) = chain_positions(chain)
            half_v(:, k + 1) = chain_velocities(chain)
            if (k == p - 1) exit
            call advance_to_point(chain, int(k + 1, i8), s0, log, err)
            if (allocated(err)) return
            orbit_x(:, k + 2) = chain_positions(chain)
            orbit_v(:, k + 2) = chain_velocities(chain)
        end do
    end subroutine orbit_states

end module chain_census_classify
