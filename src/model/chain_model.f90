!> The physical model of one chain (docs/model.md sections 1-5): n oscillators x'' + 2 b x' + x
!> = A sin(w t) between walls (or free ends), bond k between oscillators k and k+1 of rest
!> spacing a(k), impacts with restitution K, and the rebound speed below which chatter against
!> a wall ends in rest. Everything the dynamics depends on, and nothing about how a run is
!> recorded: the configuration builds it, the engine takes it.
module chain_model
    use chain_kinds, only: wp
    implicit none
    private
    public :: model_t, model_walls, bond_gaps
    public :: model_parameters, is_model_parameter, model_parameter, set_model_parameter

    !> The parameters a sweep or a branch of orbits can vary ('spacing': every bond's rest
    !> gap at once).
    character(len=*), parameter :: model_parameters(5) = &
        [character(len=11) :: 'amplitude', 'omega', 'damping', 'restitution', 'spacing']

    type :: model_t
        integer :: n = 0                    !! oscillators
        real(wp) :: damping = 0.05_wp       !! b, 0 <= b < 1
        real(wp) :: restitution = 0.7_wp    !! K, 0 <= K <= 1
        real(wp) :: amplitude = 0           !! A of the drive
        real(wp) :: omega = 1               !! w of the drive
        !> spacing(n+1): the rest gap of bond k (oscillators k, k+1; bond 0 the left wall,
        !> bond n the right) is spacing(k+1)
        real(wp), allocatable :: spacing(:)
        logical :: walls = .true.           !! fixed walls (true) or free ends (false)
        real(wp) :: stick_speed = 1.0e-9_wp !! rebound speed below which chatter ends in rest
    end type model_t

contains

    !> The boundary as the input names it: 'fixed' or 'free'.
    pure function model_walls(model) result(boundary)
        type(model_t), intent(in) :: model
        character(len=:), allocatable :: boundary

        if (model%walls) then
            boundary = 'fixed'
        else
            boundary = 'free'
        end if
    end function model_walls

    !> Gaps of bonds 0..n at displacements x(n) (section 1.2): spacing(0:n) the rest gaps;
    !> the end bonds of a free chain never close (huge).
    pure function bond_gaps(spacing, walls, x) result(gaps)
        real(wp), intent(in) :: spacing(0:), x(:)
        logical, intent(in) :: walls
        real(wp) :: gaps(0:size(x))
        integer :: n

        n = size(x)
        gaps(1:n - 1) = spacing(1:n - 1) + x(2:n) - x(1:n - 1)
        if (walls) then
            gaps(0) = spacing(0) + x(1)
            gaps(n) = spacing(n) - x(n)
        else
            gaps(0) = huge(1.0_wp)
            gaps(n) = huge(1.0_wp)
        end if
    end function bond_gaps

    pure logical function is_model_parameter(name)
        character(len=*), intent(in) :: name

        is_model_parameter = any(model_parameters == name)
    end function is_model_parameter

    !> The value of parameter `name` in the model (spacing: bond 0's, the same for all).
    pure real(wp) function model_parameter(model, name) result(value)
        type(model_t), intent(in) :: model
        character(len=*), intent(in) :: name

        select case (name)
        case ('amplitude')
            value = model%amplitude
        case ('omega')
            value = model%omega
        case ('damping')
            value = model%damping
        case ('restitution')
            value = model%restitution
        case default
            value = model%spacing(1)
        end select
    end function model_parameter

    !> Set parameter `name` of the model to `value` (spacing: every bond's).
    pure subroutine set_model_parameter(model, name, value)
        type(model_t), intent(inout) :: model
        character(len=*), intent(in) :: name
        real(wp), intent(in) :: value

        select case (name)
        case ('amplitude')
            model%amplitude = value
        case ('omega')
            model%omega = value
        case ('damping')
            model%damping = value
        case ('restitution')
            model%restitution = value
        case ('spacing')
            model%spacing = value
        end select
    end subroutine set_model_parameter

end module chain_model
