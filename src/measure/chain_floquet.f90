!> The Poincare-map Jacobian and the Floquet multipliers (docs/model.md section 7.9): the
!> tangent map of p drive cycles at a chain's state, the plain product of the exact flow's
!> propagators and the impacts' saltation matrices (no re-orthonormalisation), and its
!> eigenvalues.
module chain_floquet
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t, set_error
    use chain_engine, only: chain_t, chain_set_tangent, chain_size, chain_cycle, chain_time, &
                            chain_tangent_frame, chain_counts, chain_contacts
    use chain_state, only: event_counts_t
    use chain_event_log, only: event_log_t, event_log_init, event_impact
    use chain_lapack, only: general_eigenvalues
    use chain_section, only: advance_to_point
    implicit none
    private
    public :: poincare_jacobian, advance_with_jacobian, pass_end, floquet_multipliers, &
              floquet_result

contains

    !> Jacobian (2n x 2n) of the p-cycle Poincare map at the chain's current (synced) state;
    !> the chain itself is not moved.
    subroutine poincare_jacobian(chain, cycles, jacobian, err)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: cycles
        real(wp), allocatable, intent(out) :: jacobian(:, :)
        type(error_t), allocatable, intent(out) :: err
        type(chain_t) :: copy
        type(event_log_t) :: log

        copy = chain
        call event_log_init(log, .false., 0)
        call advance_with_jacobian(copy, cycles, log, jacobian, err)
    end subroutine poincare_jacobian

    !> Run the chain (synced) through p drive cycles to the same in-cycle time, carrying the
    !> identity frame: the one pass that gives both the p-cycle map (the chain's state after)
    !> and its Jacobian (2n x 2n). Events go to `log`.
    subroutine advance_with_jacobian(chain, cycles, log, jacobian, err)
        type(chain_t), intent(inout) :: chain
        integer, intent(in) :: cycles
        type(event_log_t), intent(inout) :: log
        real(wp), allocatable, intent(out) :: jacobian(:, :)
        type(error_t), allocatable, intent(out) :: err
        real(wp), allocatable :: frame(:, :)
        integer :: i, m

        m = 2*chain_size(chain)
        allocate (frame(m, m))
        frame = 0
        do i = 1, m
            frame(i, i) = 1
        end do
        call chain_set_tangent(chain, frame)
        call advance_to_point(chain, chain_cycle(chain) + cycles, chain_time(chain), log, err)
        if (allocated(err)) return
        ! (the engine's power-of-two scaling undone, saturating at huge: such a map is singular)
        jacobian = chain_tangent_frame(chain)
    end subroutine advance_with_jacobian

    !> At the end of a pass of the map (its events in `log`): did an oscillator come to rest,
    !> and did the cluster rule act (an impact of speed 0)? Either makes the map not smooth.
    subroutine pass_end(chain, log, rests, collapse)
        type(chain_t), intent(in) :: chain
        type(event_log_t), intent(in) :: log
        logical, intent(out) :: rests, collapse
        type(event_counts_t) :: counts
        integer :: k

        counts = chain_counts(chain)
        rests = counts%sticks > 0 .or. any(chain_contacts(chain) /= 0)
        collapse = .false.
        do k = 1, log%count
            if (log%kind(k) == event_impact .and. log%speed(k) == 0) collapse = .true.
        end do
    end subroutine pass_end

    !> The Jacobian of the p-cycle Poincare map at the chain's final state and its
    !> eigenvalues, the Floquet multipliers.
    subroutine floquet_result(chain, cycles, jacobian, multipliers_re, multipliers_im, err)
        type(chain_t), intent(in) :: chain
        integer, intent(in) :: cycles
        real(wp), allocatable, intent(out) :: jacobian(:, :)
        real(wp), allocatable, intent(out) :: multipliers_re(:), multipliers_im(:)
        type(error_t), allocatable, intent(out) :: err
        integer :: info

        call poincare_jacobian(chain, cycles, jacobian, err)
        if (allocated(err)) return
        allocate (multipliers_re(2*chain_size(chain)), multipliers_im(2*chain_size(chain)))
        call floquet_multipliers(jacobian, multipliers_re, multipliers_im, info)
        if (info /= 0) call set_error(err, "floquet: the eigenvalue solver (LAPACK dgeev) "// &
                                      "failed")
    end subroutine floquet_result

    !> Eigenvalues of a Poincare-map Jacobian (Floquet multipliers), by LAPACK dgeev.
    subroutine floquet_multipliers(jacobian, re, im, info)
        real(wp), intent(in) :: jacobian(:, :)
        real(wp), intent(out) :: re(:), im(:)
        integer, intent(out) :: info
        real(wp), allocatable :: a(:, :)

        a = jacobian
        call general_eigenvalues(a, re, im, info)
    end subroutine floquet_multipliers

end module chain_floquet
