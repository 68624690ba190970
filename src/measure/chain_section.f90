!> The Poincare section (docs/model.md section 6.1): the drive phase at which the strobe
!> records are taken, and running a chain to a point of it, or through whole drive cycles.
!> Strobe record j (j = 1..cycles) is the state at elapsed time (transient + j) T + delta, with
!> delta the offset from the initial drive phase to the section phase (0 for a fresh run with
!> phase = 0).
module chain_section
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_engine, only: chain_t, chain_advance, chain_sync, chain_new_cycle, chain_cycle, &
                            chain_start, chain_period, chain_section_time, &
                            chain_reorthonormalise, chain_rank_lost, chain_vectors, chain_init
    use chain_model, only: model_t
    use chain_state, only: moving_state
    use chain_lyapunov, only: adaptive_interval, longest_interval
    use chain_event_log, only: event_log_t
    use chain_monitor, only: monitor_t, stage_transient
    implicit none
    private
    public :: section_target, advance_to_point, advance_cycles, chain_at_section

contains

    !> Cycle and in-cycle time of strobe point j (j = 0: the end of the transient).
    pure subroutine section_target(chain, transient, phase, j, cycle, s)
        type(chain_t), intent(in) :: chain
        integer(i8), intent(in) :: transient, j
        real(wp), intent(in) :: phase
        integer(i8), intent(out) :: cycle
        real(wp), intent(out) :: s
        real(wp) :: s_section, start_s
        integer(i8) :: start_cycle

        s_section = chain_section_time(chain, phase)
        call chain_start(chain, start_cycle, start_s)
        cycle = start_cycle + transient + j
        s = s_section
        ! the start is already on the section (a continued run): keep its exact time
        if (abs(s_section - start_s) <= 1.0e-12_wp*chain_period(chain)) then
            s = start_s
        else if (s_section < start_s) then
            cycle = cycle + 1
        end if
    end subroutine section_target

    !> A fresh chain of `model` in state (x, v) on the section (drive phase `phase` of cycle 0),
    !> every oscillator moving and every bond scheduled from scratch: where a Poincare map and
    !> its Jacobian start from an arbitrary state.
    subroutine chain_at_section(model, phase, x, v, chain, err)
        type(model_t), intent(in) :: model
        real(wp), intent(in) :: phase
        real(wp), intent(in) :: x(:), v(:)
        type(chain_t), intent(out) :: chain
        type(error_t), allocatable, intent(out) :: err

        call chain_init(chain, model, moving_state(x, v, 0_i8, phase/model%omega), err)
    end subroutine chain_at_section

    !> Run the chain to (cycle, s) and bring every oscillator there. With `watch` (and
    !> `stopped`), the monitor is told within cycles (chain_advance) and may stop the chain
    !> between two events: `stopped` then comes back .true., the chain fit only to be replaced.
    subroutine advance_to_point(chain, cycle, s, log, err, watch, stopped)
        type(chain_t), intent(inout) :: chain
        ! by value: a caller may pass the chain's own clock (chain_time), which moves meanwhile
        integer(i8), value :: cycle
        real(wp), value :: s
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        class(monitor_t), intent(inout), optional :: watch
        logical, intent(out), optional :: stopped
        logical :: cut

        cut = .false.
        if (present(stopped)) then
            call advance_cycles(chain, cycle, log, err, watch=watch, stopped=cut)
            if (.not. cut .and. .not. allocated(err)) &
                call chain_advance(chain, s, log, err, watch, cut)
            stopped = cut
        else
            call advance_cycles(chain, cycle, log, err)
            if (.not. allocated(err)) call chain_advance(chain, s, log, err)
        end if
        if (cut .or. allocated(err)) return
        call chain_sync(chain)
    end subroutine advance_to_point

    !> Run the chain through the ends of drive cycles up to the start of `cycle`.
    !> With `monitor` (a transient), it is told every cycle end (done = the chain's cycle,
    !> total = `monitor_total`, default `cycle`) and may stop the run there: `stopped` then
    !> comes back .true. With `watch` or `monitor`, the monitor is also told within cycles
    !> (chain_advance) and may stop the chain between two events (`stopped` too; the chain is
    !> then fit only to be replaced, or dropped).
    subroutine advance_cycles(chain, cycle, log, err, tangent_qr_every, monitor, stopped, &
                              monitor_total, watch)
        type(chain_t), intent(inout) :: chain
        integer(i8), intent(in) :: cycle
        type(event_log_t), intent(inout) :: log
        type(error_t), allocatable, intent(out) :: err
        !> re-orthonormalise the tangent frame, unaveraged, at every this many cycle ends
        !> (0: at the adaptive interval of chain_lyapunov, from the growths of each step)
        integer, intent(in), optional :: tangent_qr_every
        class(monitor_t), intent(inout), optional :: monitor
        logical, intent(out), optional :: stopped
        integer(i8), intent(in), optional :: monitor_total
        class(monitor_t), intent(inout), optional :: watch
        real(wp), allocatable :: growth(:)
        integer(i8) :: total
        integer :: since, interval
        logical :: cut

        total = cycle
        if (present(monitor_total)) total = monitor_total
        if (present(stopped)) stopped = .false.
        since = 0
        interval = 1
        if (present(tangent_qr_every)) interval = max(1, tangent_qr_every)
        do while (chain_cycle(chain) < cycle)
            ! (a stop within a cycle needs `stopped` to say so)
            cut = .false.
            if (present(monitor) .and. present(stopped)) then
                call chain_advance(chain, chain_period(chain), log, err, monitor, cut)
            else if (present(watch) .and. present(stopped)) then
                call chain_advance(chain, chain_period(chain), log, err, watch, cut)
            else
                call chain_advance(chain, chain_period(chain), log, err)
            end if
            if (cut) stopped = .true.
            if (cut .or. allocated(err)) return
            call chain_new_cycle(chain)
            if (present(monitor)) then
                if (.not. monitor%keep_going(stage_transient, chain_cycle(chain), total)) then
                    if (present(stopped)) stopped = .true.
                    return
                end if
            end if
            since = since + 1
            if (.not. present(tangent_qr_every)) cycle
            if (since < interval .and. .not. (tangent_qr_every == 0 .and. &
                                               chain_rank_lost(chain))) cycle
            if (tangent_qr_every > 0) then
                call chain_reorthonormalise(chain, err)
            else
                allocate (growth(chain_vectors(chain)))
                call chain_reorthonormalise(chain, err, growth)
                interval = adaptive_interval(growth/since, longest_interval)
                deallocate (growth)
            end if
            if (allocated(err)) return
            since = 0
        end do
    end subroutine advance_cycles

end module chain_section
