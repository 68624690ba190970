!> Chains for the tests, set up from the parameters the tests name (a flow, K, the spacings,
!> the boundary and a state) through the engine's own `chain_init`, and the flow of a chain
!> read back from its model. (Infrastructure of the tests: docs/model.md sections 1-2 define
!> what these parameters are.)
module test_chains
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_flow, only: flow_t, make_flow
    use chain_model, only: model_t
    use chain_state, only: chain_state_t, moving_state
    use chain_engine, only: chain_t, chain_init, chain_model
    implicit none
    private
    public :: init_chain, model_of, flow_of, fig10_model, make_chain

contains

    !> Figure 10's chain at amplitude A: n = 8, w = 1.9, b = 0.05, K = 0.5, a = 1, fixed walls
    !> (the periodic-orbit suites' reference chain).
    function fig10_model(amplitude) result(model)
        real(wp), intent(in) :: amplitude
        type(model_t) :: model
        integer :: i

        model = model_of(make_flow(0.05_wp, amplitude, 1.9_wp), 0.5_wp, [(1.0_wp, i=0, 8)], &
                         .true., 1.0e-9_wp)
    end function fig10_model

    !> The model of a chain with this flow (b, A, w), restitution, spacings a(0:n), boundary
    !> and stick speed.
    pure function model_of(flow, restitution, spacing, walls, stick_speed) result(model)
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: restitution, spacing(0:), stick_speed
        logical, intent(in) :: walls
        type(model_t) :: model

        model%n = size(spacing) - 1
        model%damping = flow%damping
        model%restitution = restitution
        model%amplitude = flow%amplitude
        model%omega = flow%omega
        model%spacing = spacing
        model%walls = walls
        model%stick_speed = stick_speed
    end function model_of

    !> A chain of that model in state (x, v) at (cycle, s), every bond scheduled; `contact`
    !> rests oscillators on the walls (contact_free / left / right of chain_state).
    subroutine init_chain(chain, flow, restitution, spacing, walls, stick_speed, x, v, cycle, &
                          s, err, contact)
        type(chain_t), intent(out) :: chain
        type(flow_t), intent(in) :: flow
        real(wp), intent(in) :: restitution, spacing(0:), stick_speed, x(:), v(:), s
        logical, intent(in) :: walls
        integer(i8), intent(in) :: cycle
        type(error_t), allocatable, intent(out) :: err
        integer, intent(in), optional :: contact(:)
        type(chain_state_t) :: state

        state = moving_state(x, v, cycle, s)
        if (present(contact)) state%contact = contact
        call chain_init(chain, model_of(flow, restitution, spacing, walls, stick_speed), state, &
                        err)
    end subroutine init_chain

    !> The flow of a chain's model (the engine builds its own the same way).
    pure function flow_of(chain) result(flow)
        type(chain_t), intent(in) :: chain
        type(flow_t) :: flow
        type(model_t) :: model

        model = chain_model(chain)
        flow = make_flow(model%damping, model%amplitude, model%omega)
    end function flow_of

    !> A chain with a deterministic, spread-out start.
    subroutine make_chain(chain, n, amplitude, omega, damping, restitution, walls, x_amp, &
                          v_amp, err, spacing)
        type(chain_t), intent(out) :: chain
        integer, intent(in) :: n
        real(wp), intent(in) :: amplitude, omega, damping, restitution, x_amp, v_amp
        logical, intent(in) :: walls
        type(error_t), allocatable, intent(out) :: err
        real(wp), intent(in), optional :: spacing
        real(wp) :: x(n), v(n), a
        integer :: i

        a = 1
        if (present(spacing)) a = spacing
        do i = 1, n
            x(i) = x_amp*sin(1.7_wp*i + 0.3_wp)
            v(i) = v_amp*cos(2.3_wp*i)
        end do
        call init_chain(chain, make_flow(damping, amplitude, omega), restitution, &
                        [(a, i=0, n)], walls, 1.0e-9_wp, x, v, 0_i8, 0.0_wp, err)
    end subroutine make_chain
end module test_chains
