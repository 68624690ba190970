!> Simultaneous contacts (docs/model.md sections 5.6 and 5.7): the count of the impacts of one
!> instant (chain_advance decides which belong to it), the order of contacts due at exactly one
!> time, and the cluster of the cluster rule.
!>
!> Triple contacts are resolved as a sequence of pair impacts in time order; contacts due at
!> exactly one time go fastest first, then nearest the middle (a rule the mirror image keeps);
!> after each, the neighbouring bonds are re-examined and any that is closed and closing fires
!> at the same instant. After many impacts at one instant a touching cluster is resolved at
!> once (its inelastic collapse); far more means the engine is stuck, which is reported.
submodule(chain_engine) chain_engine_instants
    use chain_error, only: set_error, fmt_int
    use chain_portable_math, only: portable_hypot
    use chain_state, only: contact_free
    implicit none

    integer, parameter :: max_same_instant = 100000

contains

    !> (chain_advance decides what belongs to the current instant: events within 16 eps T of
    !> its first.)
    module procedure count_instant
        character(len=32) :: buf

        chain%same_instant = chain%same_instant + 1
        if (chain%same_instant > max_same_instant) then
            write (buf, '(es14.6)') chain_elapsed(chain, time)
            call set_error(err, "event loop: more than "//fmt_int(max_same_instant)// &
                           " impacts at t = "//trim(adjustl(buf))//" (inelastic collapse "// &
                           "of a multi-body contact); raise restitution")
        end if
    end procedure count_instant

    !> Of several contacts due at one instant (a cascade through touching oscillators: one
    !> impact makes both neighbouring bonds close at once), the one that closes fastest goes
    !> first; then the one nearer the middle of the chain; then the lower bond. The first two
    !> keys are the same for a chain and its mirror image, so the two resolve their cascades
    !> alike (the bond index alone would reverse the order).
    module procedure tie_winner
        integer :: j, bond
        real(wp) :: best, u, middle

        middle = 0.5_wp*n
        first = ties(1)
        best = -huge(1.0_wp)
        do j = 1, size(ties)
            bond = ties(j)
            u = speeds(j)
            if (u > best .or. (u == best .and. (abs(bond - middle) < abs(first - middle) .or. &
                (abs(bond - middle) == abs(first - middle) .and. bond < first)))) then
                best = u
                first = bond
            end if
        end do
    end procedure tie_winner

    !> Inelastic collapse: a cluster of touching oscillators meets infinitely many impacts in
    !> no time (a crowded chain with small K). Its limit: the cluster moves with its mean
    !> velocity, or comes to rest if it is pressed into a wall or a resting stack. The cluster
    !> holds moving oscillators only: a resting one is a fixed side, like a wall (its velocity
    !> and its zero tangent rows stay out of the averages). `gaps` are those of the synced
    !> chain now.
    module procedure find_cluster
        integer :: m
        real(wp) :: tol
        logical :: against_left, against_right

        mean = 0
        stopped = .false.
        ! touching, to within the rounding of positions built from free part and drive (large
        ! near resonance)
        tol = 1.0e-12_wp + 256*epsilon(1.0_wp)*(maxval(chain%spacing) + maxval(abs(chain%x)) + &
                                                 portable_hypot(chain%flow%p_sin, chain%flow%q_cos))
        first = max(1, bond)
        last = min(chain%n, bond + 1)
        if (chain%contact(first) /= contact_free) first = first + 1
        if (chain%contact(last) /= contact_free) last = last - 1
        ! (both sides fixed: nothing moves here)
        if (first > last) return
        do while (first > 1)
            if (gaps(first - 1) > tol .or. chain%contact(first - 1) /= contact_free) exit
            first = first - 1
        end do
        do while (last < chain%n)
            if (gaps(last) > tol .or. chain%contact(last + 1) /= contact_free) exit
            last = last + 1
        end do
        m = last - first + 1
        mean = sum(chain%v(first:last))/m
        against_left = gaps(first - 1) <= tol .and. (first == 1 .and. chain%walls .or. first > 1)
        against_right = gaps(last) <= tol .and. &
                        (last == chain%n .and. chain%walls .or. last < chain%n)
        stopped = (against_left .and. mean < 0) .or. (against_right .and. mean > 0)
        if (stopped) mean = 0
    end procedure find_cluster

end submodule chain_engine_instants
