!> The complete restart state of a chain (docs/model.md sections 4-5 and 10): where every
!> oscillator is, which rest on a wall, and what the engine needs to go on bit for bit as if it
!> had never stopped (its event schedule, its record of simultaneous impacts, its counters and,
!> for Lyapunov spectra, its tangent frame). One type for every place a state travels: the
!> start of a run, its final state in the file, a sweep's checkpoint and the MPI messages.
!> A state without a schedule (`has_schedule` false: a new start, or a continuation step of a
!> sweep with other parameters) makes the engine search every bond afresh.
module chain_state
    use chain_kinds, only: wp, i8
    implicit none
    private
    public :: chain_state_t, event_counts_t, tangent_state_t, contact_free, contact_left, &
              contact_right, moving_state

    integer, parameter :: contact_free = 0   !! moving freely
    integer, parameter :: contact_left = -1  !! resting on the left wall
    integer, parameter :: contact_right = 1  !! resting on the right wall

    !> What happened since the run started (written to /stats).
    type :: event_counts_t
        integer(i8) :: impacts = 0, sticks = 0, releases = 0, touches = 0
        integer(i8), allocatable :: site_counts(:) !! site_counts(0:n): impacts per bond
    end type event_counts_t

    !> The tangent frame as the engine carries it (docs/model.md section 9).
    type :: tangent_state_t
        real(wp), allocatable :: frame(:, :) !! (n_vectors, 2n), transposed, scaled as below
        integer :: scale_bits = 0            !! the frame is the true one times 2**(-bits)
        real(wp), allocatable :: growth_log(:) !! (n_vectors): ln growth kept since the QR step
        integer(i8) :: rank_losses = 0       !! singular tangent maps since the QR step
        real(wp), allocatable :: jumps_volume(:) !! (n_vectors): ln |det| of the jumps since
                                             !! each piece of the frame was orthonormal,
                                             !! on the piece's first column
        !> Re-orthonormalised right after large jumps (a Lyapunov frame, section 7.6); false
        !> for a Poincare-map Jacobian, which must be the plain product.
        logical :: orthonormalise_jumps = .true.
    end type tangent_state_t

    type :: chain_state_t
        integer(i8) :: cycle = 0             !! drive cycles completed since t = 0
        real(wp) :: time = 0                 !! time within the current drive cycle
        real(wp), allocatable :: x(:), v(:)  !! x(n), v(n)
        integer, allocatable :: contact(:)   !! contact(n): contact_free / left / right
        !> The engine's schedule: next event time within the cycle and its kind, n+1 entries
        !> for bonds 0 to n in order.
        logical :: has_schedule = .false.
        real(wp), allocatable :: event_time(:)
        integer, allocatable :: event_action(:)
        !> Where the run started (elapsed time is measured from there), the engine's record of
        !> simultaneous impacts, and its counters.
        integer(i8) :: start_cycle = 0
        real(wp) :: start_time = 0
        real(wp) :: last_event = -huge(1.0_wp)
        integer :: same_instant = 0
        type(event_counts_t) :: counts
        !> With a tangent frame (Lyapunov spectra, Jacobians).
        logical :: has_tangent = .false.
        type(tangent_state_t) :: tangent
    end type chain_state_t

contains

    !> Oscillators at x, v, all moving, at time `time` of cycle `cycle`, no schedule.
    pure function moving_state(x, v, cycle, time) result(state)
        real(wp), intent(in) :: x(:), v(:)
        integer(i8), intent(in) :: cycle
        real(wp), intent(in) :: time
        type(chain_state_t) :: state

        state%x = x
        state%v = v
        allocate (state%contact(size(x)))
        state%contact = contact_free
        state%cycle = cycle
        state%time = time
        state%start_cycle = cycle
        state%start_time = time
    end function moving_state

end module chain_state
