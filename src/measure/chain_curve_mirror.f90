!> The half map of a mirror-symmetric chain, on which a branch-point curve is regular
!> (docs/model.md section 12.6): Q(z) = R Phi(z), Phi the flow over half a drive period from
!> the section and R the mirror x(i) -> -x(n+1-i), v(i) -> -v(n+1-i). R maps the flow from one
!> half period onto the next, so P = Q o Q: a symmetric orbit is a fixed point of Q, and the
!> pitchfork of the symmetry (a multiplier +1 of J = DQ**2 with an odd eigenvector) is a
!> multiplier -1 of DQ, where DQ - I stays regular.
module chain_curve_mirror
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_model, only: model_t, model_parameter, set_model_parameter, bond_gaps
    use chain_engine, only: chain_t, chain_positions, chain_velocities, chain_cycle, &
                            chain_time, chain_period, chain_set_tangent, chain_tangent_frame
    use chain_event_log, only: event_log_init
    use chain_section, only: chain_at_section, advance_to_point
    use chain_floquet, only: pass_end
    use chain_orbit, only: orbit_pass_t, interleave
    implicit none
    private
    public :: half_pass, half_parameter_column, mirrored, mirror_symmetric_chain

contains

    !> Q(z) and, with `jacobian`, DQ = R DPhi at z, with the events of the half period: one
    !> run of a fresh chain on the section, as chain_orbit's orbit_pass over a whole period.
    subroutine half_pass(model, phase, z, pass, err, jacobian)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase, z(:)
        type(orbit_pass_t), intent(out) :: pass
        type(error_t), allocatable, intent(out) :: err
        logical, intent(in) :: jacobian
        type(chain_t) :: chain
        real(wp), allocatable :: frame(:, :)
        real(wp) :: s
        integer(i8) :: cycle
        integer :: i, m

        pass%z = z
        pass%admissible = .not. any(bond_gaps(model%spacing, model%walls, z(1::2)) < 0)
        if (.not. pass%admissible) return
        call chain_at_section(model, phase, z(1::2), z(2::2), chain, err)
        if (allocated(err)) return
        m = size(z)
        if (jacobian) then
            allocate (frame(m, m))
            frame = 0
            do i = 1, m
                frame(i, i) = 1
            end do
            call chain_set_tangent(chain, frame)
        end if
        call event_log_init(pass%log, .true., 64)
        s = chain_time(chain) + chain_period(chain)/2
        cycle = chain_cycle(chain)
        if (s >= chain_period(chain)) then
            s = s - chain_period(chain)
            cycle = cycle + 1
        end if
        call advance_to_point(chain, cycle, s, pass%log, err)
        if (allocated(err)) return
        pass%image = mirrored(interleave(chain_positions(chain), chain_velocities(chain)))
        call pass_end(chain, pass%log, pass%rests, pass%collapse)
        pass%residual = maxval(abs(pass%image - z))/(1 + maxval(abs(z)))
        if (.not. jacobian) return
        frame = chain_tangent_frame(chain)
        allocate (pass%jacobian(m, m))
        do i = 1, m
            pass%jacobian(:, i) = mirrored(frame(:, i))
        end do
    end subroutine half_pass

    !> dQ/dmu at z for `parameter` (model at its value), by central differences of Q (a
    !> relative step 1e-6: Q is smooth in mu while its impacts stay, its error of order
    !> step**2). `failure` when a shifted pass is refused (chain_orbit's pass_refusal).
    subroutine half_parameter_column(model, phase, z, parameter, column, failure, err)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase, z(:)
        character(len=*), intent(in) :: parameter
        real(wp), allocatable, intent(out) :: column(:)
        character(len=:), allocatable, intent(inout) :: failure
        type(error_t), allocatable, intent(out) :: err
        real(wp), parameter :: relative = 1.0e-6_wp
        type(orbit_pass_t) :: plus, minus
        type(model_t) :: shifted
        real(wp) :: mu, h

        mu = model_parameter(model, parameter)
        h = relative*(1 + abs(mu))
        shifted = model
        call set_model_parameter(shifted, parameter, mu + h)
        call half_pass(shifted, phase, z, plus, err, .false.)
        if (allocated(err)) return
        call set_model_parameter(shifted, parameter, mu - h)
        call half_pass(shifted, phase, z, minus, err, .false.)
        if (allocated(err)) return
        if (.not. (plus%admissible .and. minus%admissible)) then
            failure = "a negative gap"
            return
        end if
        column = (plus%image - minus%image)/(2*h)
    end subroutine half_parameter_column

    !> R z for an interleaved state z = (x(1), v(1), ..., x(n), v(n)): the oscillators in
    !> reverse order, every coordinate negated.
    pure function mirrored(z) result(r)
        real(wp), intent(in) :: z(:)
        real(wp) :: r(size(z))
        integer :: n, i

        n = size(z)/2
        do i = 1, n
            r(2*i - 1:2*i) = -z(2*(n + 1 - i) - 1:2*(n + 1 - i))
        end do
    end function mirrored

    !> Is the chain its own mirror image: bond k's spacing that of bond n - k?
    pure logical function mirror_symmetric_chain(model)
        type(model_t), intent(in) :: model

        associate (a => model%spacing)
            mirror_symmetric_chain = all(a == a(ubound(a, 1):lbound(a, 1):-1))
        end associate
    end function mirror_symmetric_chain

end module chain_curve_mirror
