!> Error reporting without `stop`: library procedures return an allocated `error_t` whose
!> message reads "where: what (offending value, allowed range)"; only app/ turns it into an
!> exit code.
module chain_error
    implicit none
    private
    public :: error_t, set_error

    type :: error_t
        character(len=:), allocatable :: message
    end type error_t

contains

    !> Allocate `err` with `message`.
    pure subroutine set_error(err, message)
        type(error_t), allocatable, intent(out) :: err
        character(len=*), intent(in) :: message
        allocate (err)
        err%message = message
    end subroutine set_error

end module chain_error
