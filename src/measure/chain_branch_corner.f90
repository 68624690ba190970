!> Through a corner (docs/model.md section 12.5): where an oscillator is hit by both
!> neighbours at one instant, the two impacts swap their order. Pair impacts do not commute,
!> so the map jumps there: the family with the old order ends at the corner, and the orbit on
!> the other side, as many impacts in another order, lies a finite distance away (it
!> is no continuation of the old orbit, and may exist on both sides). It is sought at a small
!> distance past the corner by Newton from the corner orbit's images under the map there (a
!> pass applies the swapped order; the images approach the new orbit as the map's dynamics
!> allow).
module chain_branch_corner
    use chain_kinds, only: wp
    use chain_error, only: error_t
    use chain_model, only: model_t, set_model_parameter
    use chain_orbit, only: orbit_t, orbit_pass_t, orbit_pass, find_orbit, impact_bonds
    use chain_branch_points, only: cursor_t, setting_t
    use chain_branch_corrector, only: cursor_ahead
    implicit none
    private
    public :: pass_corner

contains

    !> From c, the orbit at the corner (old order), at mu_c, reached from `before`: the orbit
    !> with another order of impacts at mu_c + delta on the side ahead, by Newton from the
    !> first `images` images of c's state under the map there; ok = .false. when none
    !> converges to an orbit with as many impacts as c's in another order. `found`: the orbit,
    !> its tangent oriented ahead; `distance`: its state's distance from c's.
    subroutine pass_corner(set, c, before, mu_c, delta, found, distance, ok, err)
        type(setting_t), intent(in) :: set
        type(cursor_t), intent(in) :: c, before
        real(wp), intent(in) :: mu_c, delta
        type(cursor_t), intent(out) :: found
        real(wp), intent(out) :: distance
        logical, intent(out) :: ok
        type(error_t), allocatable, intent(out) :: err
        integer, parameter :: images = 5
        type(model_t) :: model
        type(orbit_pass_t) :: pass
        real(wp), allocatable :: z(:)
        real(wp) :: ahead, mu
        integer :: m, k

        ok = .false.
        distance = 0
        m = size(c%y) - 1
        ahead = sign(1.0_wp, mu_c - before%y(m + 1))
        mu = mu_c + ahead*delta
        if (mu < set%low .or. mu > set%high) return
        model = set%model
        call set_model_parameter(model, set%opt%parameter, mu)
        z = c%y(:m)
        do k = 1, images
            call orbit_pass(model, set%phase, set%cycles, z, pass, err)
            if (allocated(err) .or. .not. pass%admissible) return
            z = pass%image
            call newton_swapped(set, model, c, z, mu, ahead, found, ok, err)
            if (allocated(err)) return
            if (ok) ok = sum(found%impacts) == sum(c%impacts)
            if (ok) then
                distance = norm2(found%y(:m) - c%y(:m))
                return
            end if
        end do
    end subroutine pass_corner

    !> Newton from z at mu (the model set there): ok when it converges, without a touch, to an
    !> orbit whose impacts come in another order than c's, and it has a tangent.
    subroutine newton_swapped(set, model, c, z, mu, ahead, found, ok, err)
        type(setting_t), intent(in) :: set
        type(model_t), intent(in) :: model
        type(cursor_t), intent(in) :: c
        real(wp), intent(in) :: z(:), mu, ahead
        type(cursor_t), intent(out) :: found
        logical, intent(out) :: ok
        type(error_t), allocatable, intent(out) :: err
        type(orbit_t) :: orbit
        integer, allocatable :: old(:), new(:)

        ok = .false.
        call find_orbit(model, set%phase, set%cycles, z(1::2), z(2::2), orbit, err, &
                        set%opt%newton)
        if (allocated(err) .or. .not. orbit%converged) return
        if (orbit%min_gap < 0) return
        old = impact_bonds(c%orbit)
        new = impact_bonds(orbit)
        if (size(old) == size(new)) then
            if (all(old == new)) return
        end if
        call cursor_ahead(set, orbit, mu, ahead, found, ok, err)
    end subroutine newton_swapped

end module chain_branch_corner
