!> Contacts at the limit of resolution (docs/model.md sections 5.2-5.5): touches, whether a
!> resting oscillator is pressed into its wall or stack, where it rests, and when it leaves.
!>
!> An approach slower than the resolvable speed of its gap (chain_gaps) is decided by
!> rounding. Pressed into a wall or a resting stack it ends in rest (as does one below
!> `stick_speed`: chatter ends); otherwise it is a touch, with no impulse and no jump of the
!> tangent. Oscillators can stack on a resting one: oscillator i rests at
!> x = -(a(0) + ... + a(i-1)), where its acceleration is a(0) + ... + a(i-1) + A sin(w t)
!> (mirror image on the right wall). Each resting oscillator leaves when that force turns away
!> from the wall, a time known in closed form; the top of a stack always leaves first. An
!> impact on a resting oscillator sets it moving again. Two moving oscillators in contact
!> always separate (their springs differ by a at contact), so sticking happens only against
!> walls.
submodule(chain_engine) chain_engine_contact
    use chain_kinds, only: two_pi
    use chain_phases, only: phase_asin
    use chain_queue, only: queue_set
    use chain_event_log, only: event_log_append, event_touch, event_stick
    use chain_state, only: contact_left
    implicit none

contains

    !> It is placed on the wall (or the stack) with v = 0, its tangent rows become zero, and the
    !> arrival counts as an impact if its speed was above zero.
    module procedure stick_event
        chain%contact(i) = side
        chain%synced = .false.
        chain%counts%sticks = chain%counts%sticks + 1
        if (chain%n_vectors > 0) call forget_rows(chain, i)
        if (u > 0) then
            chain%counts%impacts = chain%counts%impacts + 1
            chain%counts%site_counts(bond) = chain%counts%site_counts(bond) + 1
        end if
        call event_log_append(log, chain_elapsed(chain, chain%s), bond, max(u, 0.0_wp), &
                              event_stick)
    end procedure stick_event

    !> Whether it is an impact at all is decided by rounding, so it is a touch, with no impulse
    !> and no jump of the tangent (the derivative of the map on its no-impact side). The gap
    !> dips below zero by at most u**2 / (2 g'') < its rounding level and opens again; the bond
    !> is looked at again once it is clearly open (4 u_min / g'' later: the gap is then above 8
    !> times its rounding level and opening at 3 u_min or more).
    module procedure touch_event
        real(wp) :: wait

        wait = 4*u_min/max(abs(curvature), tiny(1.0_wp))
        wait = max(wait, 64*epsilon(1.0_wp)*chain%flow%period)
        chain%action(bond) = action_recheck
        call queue_set(chain%queue, bond, chain%s + min(wait, 0.25_wp*chain%flow%period))
        chain%counts%touches = chain%counts%touches + 1
        call event_log_append(log, chain_elapsed(chain, chain%s), bond, u, event_touch)
    end procedure touch_event

    !> At rest x = -S (left), so its acceleration is S + A sin(w t); on the right, x = S and
    !> it is A sin(w t) - S.
    module procedure pressed
        real(wp) :: depth, push, rate, tol, cos_wt, sin_wt

        ! the drive's phase as everywhere else in the engine (chain_phases)
        call drive_phase(chain%flow%phases, chain%s, cos_wt, sin_wt)
        depth = abs(rest_position(chain, i, side))
        if (side == contact_left) then
            push = depth + chain%flow%amplitude*sin_wt
            rate = chain%flow%amplitude*chain%flow%omega*cos_wt
        else
            push = depth - chain%flow%amplitude*sin_wt
            rate = -chain%flow%amplitude*chain%flow%omega*cos_wt
        end if
        tol = 64*epsilon(1.0_wp)*(depth + chain%flow%amplitude)
        pressed = push < -tol .or. (abs(push) <= tol .and. rate <= 0)
    end procedure pressed

    !> In closed form (section 5.5).
    module procedure release_time
        real(wp) :: ratio, target_phase
        integer :: side

        side = chain%contact(i)
        ratio = min(1.0_wp, abs(rest_position(chain, i, side))/chain%flow%amplitude)
        ! left: the force a + A sin(wt) turns positive as sin rises through -ratio; right (the
        ! mirror image, drive shifted by half a period): A sin(wt) - a turns negative as sin
        ! falls through +ratio
        if (side == contact_left) then
            target_phase = -phase_asin(ratio)
        else
            target_phase = 0.5_wp*two_pi - phase_asin(ratio)
        end if
        s_release = chain%s + modulo(target_phase - chain%flow%omega*chain%s, two_pi) &
                    /chain%flow%omega
    end procedure release_time

    !> Left wall: -(a(0) + ... + a(i-1)); right wall: a(i) + ... + a(n).
    module procedure rest_position
        if (side == contact_left) then
            x = -sum(chain%spacing(0:i - 1))
        else
            x = sum(chain%spacing(i:chain%n))
        end if
    end procedure rest_position

end submodule chain_engine_contact
