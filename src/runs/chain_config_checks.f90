!> The checks of a configuration that involve several keys, or a key and the model: counts
!> of lists, ranges that name another key ("[0, 2n]"), groups that exclude each other, the
!> far end of a continuation, near resonance. Each key against its own range is the input
!> schema's (chain_inputs), checked on reading; the model's parameters are checked here again
!> against it, as sweeps and continuations change them. Messages name the group, the key, the
!> value and the allowed range.
module chain_config_checks
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use chain_kinds, only: wp, i8, two_pi
    use chain_error, only: error_t, set_error, fmt_real, fmt_int, fmt_int8
    use chain_gaps, only: max_steps
    use chain_model, only: model_parameters, model_parameter, set_model_parameter
    use chain_namelist, only: lower
    use chain_inputs, only: check_input
    use chain_config_type, only: config_t, lyapunov_vectors
    implicit none
    private
    public :: validate_config, sweep_parameters, sweep_axis_points, plane_coordinate
    public :: check_spacing_count, amplitudes_allowed

    character(len=*), parameter :: sweep_parameters(*) = model_parameters
    !> Most points of a sweep, along one parameter or in a 2-D grid.
    integer, parameter :: max_sweep_points = 10000000

contains

    !> The checks that involve several keys, or a key and the model (each value against its
    !> own range is checked when read: chain_input_values), group by group; the model's
    !> parameters again, as a sweep or continuation changes them. The first failure is the
    !> error.
    subroutine validate_config(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err

        call validate_chain(cfg, err)
        if (.not. allocated(err)) call validate_initial(cfg, err)
        if (.not. allocated(err)) call validate_lyapunov(cfg, err)
        if (.not. allocated(err)) call validate_output(cfg, err)
        if (.not. allocated(err) .and. cfg%sweep) call validate_sweep(cfg, err)
        if (.not. allocated(err) .and. cfg%continuation) call validate_continuation(cfg, err)
        if (.not. allocated(err) .and. cfg%census) call validate_census(cfg, err)
    end subroutine validate_config

    subroutine validate_chain(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        integer :: j

        call check_input(err, 'chain', 'n', i=int(cfg%model%n, i8))
        if (allocated(err)) return
        call check_spacing_count(err, cfg%model%n, size(cfg%model%spacing))
        if (allocated(err)) return
        do j = 1, size(cfg%model%spacing)
            if (.not. (ieee_is_finite(cfg%model%spacing(j)) .and. cfg%model%spacing(j) > 0)) then
                call set_error(err, "&chain: spacing of bond "//fmt_int(j - 1)//" = "// &
                               fmt_real(cfg%model%spacing(j))//" must be finite and > 0")
                return
            end if
        end do
        do j = 1, size(model_parameters)
            call check_input(err, 'chain', trim(model_parameters(j)), &
                             x=model_parameter(cfg%model, trim(model_parameters(j))))
        end do
        if (allocated(err)) return
        if (cfg%model%damping == 0 .and. cfg%model%omega == 1 .and. cfg%model%amplitude /= 0) then
            call set_error(err, "&chain: omega = 1 with damping = 0 is exact resonance: the "// &
                           "linear response grows without bound; use damping > 0 or omega /= 1")
            return
        end if
        call check_near_resonance(err, cfg%model%amplitude, cfg%model%omega, &
                                  cfg%model%damping, minval(cfg%model%spacing))
    end subroutine validate_chain

    !> Near resonance the engine's gap search cannot finish (chain_gaps, forced_gap_zero): it
    !> bounds a gap's curvature by its share of the drive, (1 + w**2) rp with rp = A / d,
    !> d = sqrt((1 - w**2)**2 + (2 b w)**2) the steady response's amplitude, and so steps
    !> h = sqrt(2 g / ((1 + w**2) rp)) at a gap g. A gap that stays at g for a drive period
    !> 2 pi / w takes (2 pi / w) / h steps, at most max_steps:
    !>     rp / g <= (max_steps w / (2 pi))**2 * 2 / (1 + w**2).
    !> Gaps linger far below their offset c (the spacing): with g = c / 100 the bound is
    !> rp / c <= 1.0e7 at w = 1, and it holds what was measured on the engine (undamped, 200
    !> cycles of 4 oscillators failed from rp / c = 2.5e8 to 7e8 whatever A and c; 2000 cycles
    !> of 16 failed at 1e8 and ran at 1e7). Refused above it, naming the keys and the range:
    !> (computed without dividing, so that no d, however small, overflows).
    subroutine check_near_resonance(err, amplitude, omega, damping, spacing)
        type(error_t), allocatable, intent(inout) :: err
        real(wp), intent(in) :: amplitude, omega, damping, spacing !! spacing: the smallest
        real(wp), parameter :: linger = 0.01_wp !! g / c
        real(wp) :: limit, s, d

        if (allocated(err) .or. amplitude == 0) return
        limit = (max_steps*omega/two_pi)**2*2/(1 + omega**2)*linger
        s = max(abs(1 - omega**2), 2*damping*omega)
        d = 0
        if (s > 0) d = s*sqrt((abs(1 - omega**2)/s)**2 + (2*damping*omega/s)**2)
        if (amplitude <= limit*spacing*d) return
        call set_error(err, "&chain: omega = "//fmt_real(omega)//" with damping = "// &
                       fmt_real(damping)//" is too near resonance for amplitude = "// &
                       fmt_real(amplitude)//" and the smallest spacing "// &
                       fmt_real(spacing)//": the gap search cannot resolve a steady "// &
                       "response of more than "//fmt_real(limit)//" spacings; keep "// &
                       "sqrt((1 - omega**2)**2 + (2 damping omega)**2) >= amplitude / ("// &
                       fmt_real(limit)//" spacing) = "// &
                       fmt_real(amplitude/(limit*spacing)))
    end subroutine check_near_resonance

    subroutine validate_initial(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: smallest

        if (cfg%initial_kind == 'random') then
            smallest = minval(cfg%model%spacing)
            call check_range(err, 'initial', 'x_amp', cfg%x_amp, 0.0_wp, &
                             0.5_wp*smallest, '[0, half the smallest spacing = '// &
                             fmt_real(0.5_wp*smallest)//') so that no start overlaps', &
                             open_high=.true.)
            if (allocated(err)) return
            call check_input(err, 'initial', 'v_amp', x=cfg%v_amp)
            if (allocated(err)) return
            ! both 0 (their defaults) is rest whatever the seed: a study that changes only
            ! the seed would get identical runs
            if (cfg%x_amp == 0 .and. cfg%v_amp == 0) then
                call set_error(err, "&initial: kind = 'random' needs x_amp or v_amp above 0 "// &
                               "(both are 0: every seed would start from rest); "// &
                               amplitudes_allowed(smallest))
                return
            end if
        end if
        if (cfg%initial_kind == 'explicit') then
            if (size(cfg%x0) /= cfg%model%n) then
                call set_error(err, "&initial: kind = 'explicit' needs x0 with n = "// &
                               fmt_int(cfg%model%n)//" values, got "//fmt_int(size(cfg%x0)))
                return
            end if
            if (size(cfg%v0) /= cfg%model%n .and. size(cfg%v0) /= 0) then
                call set_error(err, "&initial: v0 needs n = "//fmt_int(cfg%model%n)// &
                               " values (or none for rest), got "//fmt_int(size(cfg%v0)))
                return
            end if
            if (.not. (all(ieee_is_finite(cfg%x0)) .and. all(ieee_is_finite(cfg%v0)))) then
                call set_error(err, "&initial: x0 and v0 must be finite")
                return
            end if
        end if
        if (cfg%initial_kind == 'file' .and. len_trim(cfg%initial_file) == 0) then
            call set_error(err, "&initial: kind = 'file' needs file = 'earlier-run.h5'")
        end if
    end subroutine validate_initial

    subroutine validate_lyapunov(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err

        if (cfg%record%vectors < 0 .or. cfg%record%vectors > 2*cfg%model%n) then
            call set_error(err, "&lyapunov: vectors = "//fmt_int(cfg%record%vectors)// &
                           " is outside [0, 2n = "//fmt_int(2*cfg%model%n)//"] (0 means all 2n)")
            return
        end if
        if (cfg%record%qr_every < 0 .or. cfg%record%qr_every > cfg%record%cycles) then
            call set_error(err, "&lyapunov: qr_every = "//fmt_int(cfg%record%qr_every)// &
                           " is outside [0, cycles = "//fmt_int8(cfg%record%cycles)// &
                           "] (0: adaptive)")
            return
        end if
        if (cfg%record%window /= 0) call validate_window(cfg, err)
        if (allocated(err)) return
        if (cfg%record%covariant) call validate_covariant(cfg, err)
    end subroutine validate_lyapunov

    !> The window of finite-time exponents (docs/model.md section 7.10).
    subroutine validate_window(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err

        associate (r => cfg%record)
            if (r%window < 0 .or. r%window > r%cycles) then
                call set_error(err, "&lyapunov: window = "//fmt_int(r%window)// &
                               " is outside [0, cycles = "//fmt_int8(r%cycles)//"] (recorded "// &
                               "cycles per finite-time exponent; 0: none)")
            else if (.not. r%lyapunov) then
                call set_error(err, "&lyapunov: window = "//fmt_int(r%window)// &
                               " needs enabled = .true.")
            else if (cfg%sweep .or. cfg%census) then
                call set_error(err, "&lyapunov: window = "//fmt_int(r%window)//" is for a "// &
                               "single run, not a &sweep or a &census")
            else if (r%qr_every > 1) then
                if (modulo(r%window, r%qr_every) /= 0) &
                    call set_error(err, "&lyapunov: window = "//fmt_int(r%window)// &
                                   " must be a multiple of qr_every = "// &
                                   fmt_int(r%qr_every)//" (a window ends at a QR step)")
            end if
        end associate
    end subroutine validate_window

    !> The keys of covariant Lyapunov vectors (docs/model.md section 14.5).
    subroutine validate_covariant(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: kept

        associate (r => cfg%record)
            if (.not. r%lyapunov) then
                call set_error(err, "&lyapunov: covariant = .true. needs enabled = .true.")
            else if (cfg%sweep .or. cfg%census) then
                call set_error(err, "&lyapunov: covariant = .true. is for a single run, not "// &
                               "a &sweep or a &census")
            else if (r%qr_every > 1) then
                call set_error(err, "&lyapunov: covariant = .true. takes a QR step at every "// &
                               "record: qr_every = "//fmt_int(r%qr_every)//" must be 0 or 1")
            else if (r%cycles < 2) then
                call set_error(err, "&lyapunov: covariant = .true. needs &run cycles >= 2 "// &
                               "(records with vectors, then records over which the "// &
                               "backward pass converges), not "//fmt_int8(r%cycles))
            else if (r%clv_transient < 1 .or. r%clv_transient >= r%cycles) then
                call set_error(err, "&lyapunov: clv_transient = "//fmt_int(r%clv_transient)// &
                               " is outside [1, cycles - 1 = "//fmt_int8(r%cycles - 1)// &
                               "] (the last records, without vectors, over which the "// &
                               "backward pass converges)")
            else if (r%clv_store < 0 .or. r%clv_store > lyapunov_vectors(cfg)) then
                call set_error(err, "&lyapunov: clv_store = "//fmt_int(r%clv_store)// &
                               " is outside [0, vectors = "//fmt_int(lyapunov_vectors(cfg))// &
                               "] (the vectors whose per-oscillator weights are stored)")
            else
                kept = r%cycles - r%clv_transient
                if (r%clv_save < 0 .or. r%clv_save > kept) &
                    call set_error(err, "&lyapunov: clv_save = "//fmt_int(r%clv_save)// &
                                   " is outside [0, cycles - clv_transient = "// &
                                   fmt_int8(kept)//"] (the last records with vectors whose "// &
                                   "vectors are stored)")
            end if
        end associate
    end subroutine validate_covariant

    subroutine validate_output(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err

        if (len_trim(cfg%output_file) == 0) then
            call set_error(err, "&output: file must not be empty")
        end if
    end subroutine validate_output

    !> m spacings for n oscillators: one per bond, 0..n (a single value is expanded on reading).
    subroutine check_spacing_count(err, n, m)
        type(error_t), allocatable, intent(out) :: err
        integer, intent(in) :: n, m

        if (m /= n + 1) call set_error(err, "&chain: spacing has "//fmt_int(m)// &
                                       " values; give one (uniform) or n+1 = "// &
                                       fmt_int(n + 1)//" (one per bond, 0..n)")
    end subroutine check_spacing_count

    subroutine validate_sweep(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err

        if (.not. any(sweep_parameters == cfg%sweep_parameter)) then
            call set_error(err, "&sweep: parameter = '"//cfg%sweep_parameter//"' is not one "// &
                           "of 'amplitude', 'omega', 'damping', 'restitution', 'spacing'")
            return
        end if
        call check_axis(err, '', cfg%sweep_start, cfg%sweep_stop, cfg%sweep_step)
        if (allocated(err)) return
        if (len(cfg%sweep_parameter2) > 0) then
            if (.not. any(sweep_parameters == cfg%sweep_parameter2) .or. &
                cfg%sweep_parameter2 == cfg%sweep_parameter) then
                call set_error(err, "&sweep: parameter2 = '"//cfg%sweep_parameter2// &
                               "' must be another of 'amplitude', 'omega', 'damping', "// &
                               "'restitution', 'spacing'")
                return
            end if
            call check_axis(err, '2', cfg%sweep_start2, cfg%sweep_stop2, cfg%sweep_step2)
            if (allocated(err)) return
        end if
        call check_sweep_points(err, cfg)
    end subroutine validate_sweep

    !> The points of the whole sweep (in a 2-D grid the product of its axes) within
    !> max_sweep_points; each axis is already within 1e7 steps.
    subroutine check_sweep_points(err, cfg)
        type(error_t), allocatable, intent(out) :: err
        type(config_t), intent(in) :: cfg
        integer(i8) :: n1, n2

        n1 = sweep_axis_points(cfg%sweep_start, cfg%sweep_stop, cfg%sweep_step)
        if (len(cfg%sweep_parameter2) == 0) then
            if (n1 > max_sweep_points) call set_error(err, "&sweep: start, stop, step give "// &
                fmt_int8(n1)//" points; a sweep has at most 1e7")
            return
        end if
        n2 = sweep_axis_points(cfg%sweep_start2, cfg%sweep_stop2, cfg%sweep_step2)
        if (n1*n2 > max_sweep_points) call set_error(err, "&sweep: start, stop, step and "// &
            "start2, stop2, step2 give "//fmt_int8(n1)//" x "//fmt_int8(n2)//" = "// &
            fmt_int8(n1*n2)//" points; a sweep has at most 1e7")
    end subroutine check_sweep_points

    !> Number of points from start to stop in steps of step (rounding-safe), for a checked
    !> axis (finite, step towards stop, at most 1e7 steps).
    pure integer function sweep_axis_points(start, stop, step) result(points)
        real(wp), intent(in) :: start, stop, step

        points = nint((stop - start)/step) + 1
        if (start + (points - 1)*step > max(start, stop) + 1.0e-9_wp*abs(step) .or. &
            start + (points - 1)*step < min(start, stop) - 1.0e-9_wp*abs(step)) &
            points = points - 1
    end function sweep_axis_points

    !> The start value is the one in &chain; the branch runs from it towards `stop`.
    subroutine validate_continuation(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        type(config_t) :: far

        if (cfg%sweep) then
            call set_error(err, "&continuation cannot be combined with &sweep (run them as "// &
                             "two inputs)")
        else if (.not. any(sweep_parameters == cfg%cont_parameter)) then
            call set_error(err, "&continuation: parameter = '"//cfg%cont_parameter// &
                           "' is not one of amplitude, omega, damping, restitution, spacing")
        else if (cfg%cont_parameter == 'spacing' .and. &
                 any(cfg%model%spacing /= cfg%model%spacing(1))) then
            call set_error(err, "&continuation: parameter = 'spacing' needs one spacing for "// &
                           "every bond (&chain spacing = one value)")
        end if
        if (.not. allocated(err)) call validate_curve(cfg, err)
        if (allocated(err) .or. cfg%cont_max_points == 1) return
        associate (start => model_parameter(cfg%model, cfg%cont_parameter))
        if (.not. (ieee_is_finite(cfg%cont_stop) .and. cfg%cont_stop /= start)) then
            call set_error(err, "&continuation: stop = "//fmt_real(cfg%cont_stop)// &
                           " must be finite and differ from the start, &chain "// &
                           cfg%cont_parameter//" = "//fmt_real(start))
        else if (.not. (ieee_is_finite(cfg%cont_step) .and. cfg%cont_step /= 0 .and. &
                        (cfg%cont_step > 0 .eqv. cfg%cont_stop > start))) then
            call set_error(err, "&continuation: step = "//fmt_real(cfg%cont_step)// &
                           " must be nonzero with the sign of stop - start ("// &
                           fmt_real(cfg%cont_stop)//" - "//fmt_real(start)//")")
        else if (abs(cfg%cont_step) > abs(cfg%cont_stop - start)) then
            call set_error(err, "&continuation: |step| = "//fmt_real(abs(cfg%cont_step))// &
                           " is larger than |stop - start| = "// &
                           fmt_real(abs(cfg%cont_stop - start)))
        end if
        end associate
        if (allocated(err)) return
        ! the far end must be a valid chain too
        far = cfg
        far%continuation = .false.
        call set_model_parameter(far%model, cfg%cont_parameter, cfg%cont_stop)
        call validate_chain(far, err)
        if (allocated(err)) err%message = "&continuation: stop = "//fmt_real(cfg%cont_stop)// &
                                          ": "//err%message
    end subroutine validate_continuation

    !> The curve's second parameter is another parameter than the first, its step moves, and
    !> its bound gives a valid chain.
    subroutine validate_curve(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        type(config_t) :: far

        if (len(cfg%cont_follow) == 0) return
        if (cfg%cont_parameter2 == cfg%cont_parameter) then
            call set_error(err, "&continuation: parameter2 = '"//cfg%cont_parameter2// &
                           "' must differ from parameter = '"//cfg%cont_parameter//"'")
        else if (cfg%cont_parameter2 == 'spacing' .and. &
                 any(cfg%model%spacing /= cfg%model%spacing(1))) then
            call set_error(err, "&continuation: parameter2 = 'spacing' needs one spacing "// &
                           "for every bond (&chain spacing = one value)")
        else if (.not. (ieee_is_finite(cfg%cont_step2) .and. cfg%cont_step2 /= 0)) then
            call set_error(err, "&continuation: step2 = "//fmt_real(cfg%cont_step2)// &
                           " must be finite and nonzero")
        else if (.not. ieee_is_finite(cfg%cont_stop2)) then
            call set_error(err, "&continuation: stop2 = "//fmt_real(cfg%cont_stop2)// &
                           " must be finite")
        end if
        if (allocated(err)) return
        far = cfg
        far%continuation = .false.
        call set_model_parameter(far%model, cfg%cont_parameter2, cfg%cont_stop2)
        call validate_chain(far, err)
        if (allocated(err)) err%message = "&continuation: stop2 = "// &
                                          fmt_real(cfg%cont_stop2)//": "//err%message
    end subroutine validate_curve

    !> A census's starts must not overlap (as &initial random's), and it runs at one point
    !> or along one swept parameter.
    subroutine validate_census(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: half

        half = 0.5_wp*minval(cfg%model%spacing)
        call check_range(err, 'census', 'x_amp', cfg%census_x_amp, 0.0_wp, half, &
                         '[0, half the smallest spacing = '//fmt_real(half)// &
                         ') so that no start overlaps', open_high=.true.)
        if (allocated(err)) return
        ! (a plane's starts take the coordinates off the plane from &initial, not these)
        if (cfg%census_x_amp == 0 .and. cfg%census_v_amp == 0 .and. &
            all(cfg%census_plane == '')) then
            call set_error(err, "&census: x_amp or v_amp must be above 0 (both are 0: every "// &
                           "sample would start from rest); "// &
                           amplitudes_allowed(minval(cfg%model%spacing)))
            return
        end if
        if (cfg%census_exponents < 1 .or. cfg%census_exponents > 2*cfg%model%n) then
            call set_error(err, "&census: exponents = "//fmt_int(cfg%census_exponents)// &
                           " is outside [1, 2n = "//fmt_int(2*cfg%model%n)//"] (the leading "// &
                           "Lyapunov exponents of each sample)")
            return
        end if
        if (cfg%continuation) then
            call set_error(err, "&census cannot be combined with &continuation (run them as "// &
                           "two inputs)")
        else if (cfg%sweep .and. len(cfg%sweep_parameter2) > 0) then
            call set_error(err, "&census runs at one point or along one parameter: a &sweep "// &
                           "with parameter2 is not supported")
        end if
        if (.not. allocated(err) .and. any(cfg%census_plane /= '')) call validate_plane(cfg, err)
    end subroutine validate_census

    !> A census plane: two distinct coordinates of the chain, a grid of 2 .. max_plane_points
    !> points along each with samples = plane_points**2, over finite ranges min < max.
    subroutine validate_plane(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        logical :: velocity
        integer :: k, i
        character(len=*), parameter :: sides(2) = [character(len=6) :: 'first', 'second']

        do k = 1, 2
            call plane_coordinate(cfg%census_plane(k), cfg%model%n, velocity, i)
            if (i == 0) then
                call set_error(err, "&census: plane = '"//trim(cfg%census_plane(k))// &
                               "' is not a coordinate 'x<i>' or 'v<i>' with i in 1.."// &
                               fmt_int(cfg%model%n))
                return
            end if
        end do
        if (lower(trim(adjustl(cfg%census_plane(1)))) == &
            lower(trim(adjustl(cfg%census_plane(2))))) then
            call set_error(err, "&census: plane = '"//trim(cfg%census_plane(1))//"', '"// &
                           trim(cfg%census_plane(2))//"' names one coordinate twice")
            return
        end if
        call check_input(err, 'census', 'plane_points', i=int(cfg%census_plane_points, i8))
        if (allocated(err)) return
        if (cfg%census_samples /= cfg%census_plane_points**2) then
            call set_error(err, "&census: samples = "//fmt_int(cfg%census_samples)// &
                           " with a plane must equal plane_points**2 = "// &
                           fmt_int(cfg%census_plane_points**2))
            return
        end if
        do k = 1, 2
            associate (lo => cfg%census_plane_range(2*k - 1), hi => cfg%census_plane_range(2*k))
                if (.not. (ieee_is_finite(lo) .and. ieee_is_finite(hi)) .or. .not. lo < hi) then
                    call set_error(err, "&census: plane_range of the "//trim(sides(k))// &
                                   " coordinate ("//trim(cfg%census_plane(k))//") = "// &
                                   fmt_real(lo)//", "//fmt_real(hi)//" must be finite "// &
                                   "with min < max")
                    return
                end if
            end associate
        end do
    end subroutine validate_plane

    !> The coordinate a census plane names: 'x<i>' (velocity false) or 'v<i>' (true), i in
    !> 1..n, any case, blanks around ignored; i = 0 when `name` is none of these.
    pure subroutine plane_coordinate(name, n, velocity, i)
        character(len=*), intent(in) :: name
        integer, intent(in) :: n
        logical, intent(out) :: velocity
        integer, intent(out) :: i
        character(len=:), allocatable :: text
        integer :: k

        i = 0
        velocity = .false.
        text = lower(trim(adjustl(name)))
        if (len(text) < 2 .or. len(text) > 10) return
        if (text(1:1) /= 'x' .and. text(1:1) /= 'v') return
        if (verify(text(2:), '0123456789') /= 0) return
        velocity = text(1:1) == 'v'
        k = 0
        read (text(2:), *) k
        if (k >= 1 .and. k <= n) i = k
    end subroutine plane_coordinate

    subroutine check_axis(err, suffix, start, stop, step)
        type(error_t), allocatable, intent(out) :: err
        character(len=*), intent(in) :: suffix
        real(wp), intent(in) :: start, stop, step

        if (.not. (ieee_is_finite(start) .and. ieee_is_finite(stop) .and. &
                   ieee_is_finite(step))) then
            call set_error(err, "&sweep: start"//suffix//", stop"//suffix//" and step"// &
                           suffix//" must be finite")
        else if (step == 0 .or. (stop - start)*step < 0) then
            call set_error(err, "&sweep: step"//suffix//" = "//fmt_real(step)// &
                           " must be nonzero and point from start"//suffix//" to stop"//suffix)
        else if ((stop - start)/step > 1.0e7_wp) then
            call set_error(err, "&sweep: more than 1e7 points along parameter"//suffix)
        end if
    end subroutine check_axis

    !> The ranges of a random start's x_amp and v_amp, for a message.
    pure function amplitudes_allowed(smallest_spacing) result(text)
        real(wp), intent(in) :: smallest_spacing
        character(len=:), allocatable :: text

        text = "x_amp in [0, half the smallest spacing = "//fmt_real(0.5_wp*smallest_spacing)// &
               "), v_amp in [0, 1e6]"
    end function amplitudes_allowed

    subroutine check_range(err, group, key, value, low, high, allowed, open_high)
        type(error_t), allocatable, intent(out) :: err
        character(len=*), intent(in) :: group, key, allowed
        real(wp), intent(in) :: value, low, high
        logical, intent(in), optional :: open_high
        logical :: inside

        inside = ieee_is_finite(value) .and. value >= low .and. value <= high
        if (present(open_high)) then
            if (open_high) inside = inside .and. value < high
        end if
        if (.not. inside) call set_error(err, "&"//group//": "//key//" = "//fmt_real(value)// &
                                         " is outside "//allowed)
    end subroutine check_range

end module chain_config_checks
