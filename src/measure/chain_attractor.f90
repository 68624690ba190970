!> The rules by which an attractor census (chain_census) tells attractors apart: what a sample
!> reached (periodic, chaotic or aperiodic but not chaotic), when two samples reached the same
!> attractor, and when one reached the mirror image of another's. Pure procedures on plain
!> arrays; the census applies them to its samples one by one, in sample order.
!> Implements docs/model.md section 13.
module chain_attractor
    use chain_kinds, only: wp, i8
    implicit none
    private
    public :: attractor_t, kind_periodic, kind_chaotic, kind_aperiodic, kind_names
    public :: site_distance_limit, chaos_sigmas, classification_rule
    public :: orbit_period, sample_kind, site_fractions, mirror_image, mirror_symmetric
    public :: states_close, orbit_offset, match_attractor

    integer, parameter :: kind_periodic = 1   !! every oscillator periodic, p <= max_period
    integer, parameter :: kind_chaotic = 2    !! not periodic, lambda1 > 3 standard errors
    integer, parameter :: kind_aperiodic = 3  !! neither (quasi-periodic, a long period, ...)
    character(len=*), parameter :: kind_names(3) = &
        [character(len=20) :: 'periodic', 'chaotic', 'aperiodic-nonchaotic']
    !> Two aperiodic samples of one kind are one attractor when the L1 distance between their
    !> impact-site distributions (fractions of impacts per bond, summing to 1) is below this.
    real(wp), parameter :: site_distance_limit = 0.2_wp
    !> Chaotic: the largest exponent this many standard errors above zero.
    real(wp), parameter :: chaos_sigmas = 3
    !> The rules in words (an attribute of /census).
    character(len=*), parameter :: classification_rule = &
        "periodic: every oscillator has a period (&run max_period, period_tol) and their "// &
        "lcm p is at most max_period; two periodic samples are one attractor when their "// &
        "periods agree and the state at the last record of one is within tolerance "// &
        "(|a - b| <= tolerance (1 + |b|), every x and v) of the state of the other's "// &
        "representative k drive cycles later, for some k in 0..p-1; a mirror image "// &
        "(x(i) -> -x(n+1-i), v(i) -> -v(n+1-i)) is compared with the representative's "// &
        "states half a drive period later. Not periodic: chaotic when lambda1 > 3 standard "// &
        "errors, else aperiodic-nonchaotic; two such samples of one kind are one attractor "// &
        "when the L1 distance between their fractions of impacts per bond is below 0.2 "// &
        "(mirror: the bonds reversed). Samples are taken in order at each point; a sample "// &
        "that matches no attractor found so far at its point founds a new one, whose "// &
        "representative it is."

    !> One attractor of a census, as its first sample (the representative) found it.
    type :: attractor_t
        integer :: point = 0                 !! the point (1-based) where it was found
        integer :: first_sample = 0          !! its representative
        integer :: kind = 0                  !! kind_periodic, kind_chaotic, kind_aperiodic
        integer :: period = 0                !! p, drive cycles (0: not periodic)
        integer, allocatable :: periods(:)   !! periods(n) of the oscillators, 0 = none
        real(wp) :: lambda1 = 0, stderr1 = 0 !! largest exponent, its standard error (bits/cycle)
        real(wp), allocatable :: x(:), v(:)  !! the representative's state at its last record
        real(wp), allocatable :: sites(:)    !! sites(n+1): fraction of impacts per bond 0..n
        !> (n, p): the states on the section k = 0..p-1 drive cycles after (x, v); and half a
        !> drive period after each (periodic attractors only)
        real(wp), allocatable :: orbit_x(:, :), orbit_v(:, :), half_x(:, :), half_v(:, :)
    end type attractor_t

contains

    !> The period p of the whole chain: the lcm of the oscillators' periods, or 0 when one
    !> has none or the lcm exceeds `max_period` (a period that long is not looked for).
    pure integer function orbit_period(periods, max_period) result(p)
        integer, intent(in) :: periods(:), max_period
        integer :: i

        p = 0
        if (size(periods) == 0) return
        if (any(periods < 1)) return
        p = 1
        do i = 1, size(periods)
            p = p/gcd(p, periods(i))*periods(i)
            if (p > max_period) then
                p = 0
                return
            end if
        end do
    end function orbit_period

    pure integer function gcd(a, b)
        integer, intent(in) :: a, b
        integer :: m, r

        gcd = a
        m = b
        do while (m /= 0)
            r = modulo(gcd, m)
            gcd = m
            m = r
        end do
    end function gcd

    !> Periodic when p > 0; else chaotic when lambda1 > chaos_sigmas standard errors (and > 0),
    !> else aperiodic-nonchaotic.
    pure integer function sample_kind(p, lambda1, stderr1) result(kind)
        integer, intent(in) :: p
        real(wp), intent(in) :: lambda1, stderr1

        if (p > 0) then
            kind = kind_periodic
        else if (lambda1 > 0 .and. lambda1 > chaos_sigmas*stderr1) then
            kind = kind_chaotic
        else
            kind = kind_aperiodic
        end if
    end function sample_kind

    !> Impacts per bond as fractions of all impacts (all zero without impacts).
    pure function site_fractions(counts) result(fractions)
        integer(i8), intent(in) :: counts(:)
        real(wp) :: fractions(size(counts))

        fractions = 0
        if (sum(counts) > 0) fractions = real(counts, wp)/real(sum(counts), wp)
    end function site_fractions

    !> The mirror image of a chain's positions or velocities: x(i) -> -x(n+1-i).
    pure function mirror_image(x) result(y)
        real(wp), intent(in) :: x(:)
        real(wp) :: y(size(x))

        y = -x(size(x):1:-1)
    end function mirror_image

    !> Is the chain its own mirror image (bond k and bond n - k alike)? Both ends are walls
    !> or both free, so only the spacings can break the symmetry.
    pure logical function mirror_symmetric(spacing)
        real(wp), intent(in) :: spacing(:)

        mirror_symmetric = all(spacing == spacing(size(spacing):1:-1))
    end function mirror_symmetric

    !> (x, v) within `tol` of (y, w): |x - y| <= tol (1 + |y|), and so for v, everywhere.
    pure logical function states_close(x, v, y, w, tol)
        real(wp), intent(in) :: x(:), v(:), y(:), w(:), tol

        states_close = all(abs(x - y) <= tol*(1 + abs(y))) .and. &
                       all(abs(v - w) <= tol*(1 + abs(w)))
    end function states_close

    !> The first k in 0..p-1 with (x, v) close to the orbit's state k (orbit_x(:, k+1)), or -1.
    pure integer function orbit_offset(x, v, orbit_x, orbit_v, tol) result(offset)
        real(wp), intent(in) :: x(:), v(:), orbit_x(:, :), orbit_v(:, :), tol
        integer :: k

        offset = -1
        do k = 1, size(orbit_x, 2)
            if (states_close(x, v, orbit_x(:, k), orbit_v(:, k), tol)) then
                offset = k - 1
                return
            end if
        end do
    end function orbit_offset

    !> The attractor found so far at `point` that a sample reached, by the rules above: the
    !> first of its kind met directly, else (with `mirror`) the first met by its mirror
    !> image, which sets `mirrored`; id = 0 when none. The sample: its oscillators' periods
    !> and p, its state (x, v) at its last record, its fractions of impacts per bond.
    pure subroutine match_attractor(attractors, point, kind, periods, x, v, sites, tol, mirror, &
                                    id, mirrored)
        type(attractor_t), intent(in) :: attractors(:)
        integer, intent(in) :: point, kind, periods(:)
        real(wp), intent(in) :: x(:), v(:), sites(:), tol
        logical, intent(in) :: mirror
        integer, intent(out) :: id
        logical, intent(out) :: mirrored
        integer :: a, pass

        id = 0
        mirrored = .false.
        do pass = 1, merge(2, 1, mirror)
            do a = 1, size(attractors)
                if (attractors(a)%point /= point .or. attractors(a)%kind /= kind) cycle
                if (same(attractors(a), pass == 2)) then
                    id = a
                    mirrored = pass == 2
                    return
                end if
            end do
        end do

    contains

        pure logical function same(attractor, image)
            type(attractor_t), intent(in) :: attractor
            logical, intent(in) :: image

            if (kind == kind_periodic) then
                if (image) then
                    same = all(periods(size(periods):1:-1) == attractor%periods)
                    if (same) same = orbit_offset(mirror_image(x), mirror_image(v), &
                                                  attractor%half_x, attractor%half_v, tol) >= 0
                else
                    same = all(periods == attractor%periods)
                    if (same) same = orbit_offset(x, v, attractor%orbit_x, attractor%orbit_v, &
                                                  tol) >= 0
                end if
            else if (image) then
                same = sum(abs(sites(size(sites):1:-1) - attractor%sites)) < site_distance_limit
            else
                same = sum(abs(sites - attractor%sites)) < site_distance_limit
            end if
        end function same

    end subroutine match_attractor

end module chain_attractor
