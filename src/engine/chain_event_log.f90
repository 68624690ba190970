!> The collision event stream: a growable buffer of (time, site, speed, kind) that the run
!> driver drains to the output file in chunks, so memory does not grow with the run length.
!> The event kinds (impact, rest, release, touch) are those of docs/model.md section 5.8.
module chain_event_log
    use chain_kinds, only: wp
    implicit none
    private
    public :: event_log_t, event_log_init, event_log_append, event_log_clear
    public :: event_impact, event_stick, event_release, event_touch

    integer, parameter :: event_impact = 0  !! an impact
    integer, parameter :: event_stick = 1   !! an impact that ends chatter: the contact sticks
    integer, parameter :: event_release = 2 !! a sticking contact lets go
    !> a contact closing slower than the resolvable speed: no impulse, no jump of the tangent
    integer, parameter :: event_touch = 3

    type :: event_log_t
        logical :: enabled = .false.
        integer :: count = 0
        real(wp), allocatable :: time(:)  !! from the start of the run
        real(wp), allocatable :: speed(:) !! approach speed >= 0
        integer, allocatable :: site(:)   !! bond 0..n
        integer, allocatable :: kind(:)   !! event_impact, event_stick, event_release, event_touch
    end type event_log_t

contains

    pure subroutine event_log_init(log, enabled, capacity)
        type(event_log_t), intent(out) :: log
        logical, intent(in) :: enabled
        integer, intent(in) :: capacity

        log%enabled = enabled
        log%count = 0
        if (enabled) allocate (log%time(capacity), log%speed(capacity), &
                               log%site(capacity), log%kind(capacity))
    end subroutine event_log_init

    pure subroutine event_log_append(log, time, site, speed, kind)
        type(event_log_t), intent(inout) :: log
        real(wp), intent(in) :: time, speed
        integer, intent(in) :: site, kind

        if (.not. log%enabled) return
        if (log%count == size(log%time)) call grow(log)
        log%count = log%count + 1
        log%time(log%count) = time
        log%site(log%count) = site
        log%speed(log%count) = speed
        log%kind(log%count) = kind
    end subroutine event_log_append

    pure subroutine event_log_clear(log)
        type(event_log_t), intent(inout) :: log
        log%count = 0
    end subroutine event_log_clear

    !> Double the capacity (at least 16), keeping the events logged.
    pure subroutine grow(log)
        type(event_log_t), intent(inout) :: log
        integer :: m

        m = max(16, 2*size(log%time))
        call grow_real(log%time, m, log%count)
        call grow_real(log%speed, m, log%count)
        call grow_int(log%site, m, log%count)
        call grow_int(log%kind, m, log%count)
    end subroutine grow

    !> `a` with room for m entries, its first `kept` kept.
    pure subroutine grow_real(a, m, kept)
        real(wp), allocatable, intent(inout) :: a(:)
        integer, intent(in) :: m, kept
        real(wp), allocatable :: tmp(:)

        allocate (tmp(m))
        tmp(:kept) = a(:kept)
        call move_alloc(tmp, a)
    end subroutine grow_real

    !> `a` with room for m entries, its first `kept` kept.
    pure subroutine grow_int(a, m, kept)
        integer, allocatable, intent(inout) :: a(:)
        integer, intent(in) :: m, kept
        integer, allocatable :: tmp(:)

        allocate (tmp(m))
        tmp(:kept) = a(:kept)
        call move_alloc(tmp, a)
    end subroutine grow_int

end module chain_event_log
