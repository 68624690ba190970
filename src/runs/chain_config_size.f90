!> Size estimates: a run's records, tangent vectors and covariant vectors against &output
!> max_size_mb, refused before anything is written.
module chain_config_size
    use chain_kinds, only: wp
    use chain_error, only: error_t, set_error, fmt_real
    use chain_lyapunov, only: running_rows
    use chain_clv, only: clv_scratch_bytes
    use chain_config_type, only: config_t, lyapunov_vectors
    implicit none
    private
    public :: check_size

contains

    !> Refuse, before anything is written, records larger than &output max_size_mb.
    subroutine check_size(cfg, err)
        type(config_t), intent(in) :: cfg
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: mb
        integer :: k

        k = lyapunov_vectors(cfg)
        ! strobe x, v, cycle; running estimates (k values and a cycle per kept row)
        mb = (16.0_wp*cfg%model%n + 8)*real(cfg%record%cycles, wp)/1.0e6_wp
        if (cfg%record%lyapunov) mb = mb + (8.0_wp*k + 8)* &
                                      running_rows(cfg%record%cycles/ &
                                                   max(1, cfg%record%qr_every))/1.0e6_wp
        ! finite-time exponents: k values and a cycle per window
        if (cfg%record%lyapunov .and. cfg%record%window > 0) &
            mb = mb + (8.0_wp*k + 8)*(cfg%record%cycles/cfg%record%window)/1.0e6_wp
        if (mb > cfg%max_size_mb) then
            call set_error(err, "&output: the strobe records of this run need about "// &
                           fmt_real(mb)//" MB (n x cycles x 16 bytes, plus Lyapunov "// &
                           "estimates and finite-time exponents), more than max_size_mb = "// &
                           fmt_real(cfg%max_size_mb)//"; lower &run cycles (or raise "// &
                           "&lyapunov window) or raise &output max_size_mb")
            return
        end if
        ! tangent frames in memory: the frame, the QR's copy, the copy kept while lost
        ! directions are looked for, and a bound on the rest; for the Poincare-map Jacobian the
        ! same for a full 2n x 2n frame
        mb = 32.0_wp*k*2*cfg%model%n/1.0e6_wp
        if (cfg%record%jacobian) mb = max(mb, 32.0_wp*(2.0_wp*cfg%model%n)**2/1.0e6_wp)
        if (mb > cfg%max_size_mb) then
            call set_error(err, "&lyapunov: the tangent vectors of this run need about "// &
                           fmt_real(mb)//" MB of memory, more than &output max_size_mb = "// &
                           fmt_real(cfg%max_size_mb)//"; lower vectors, leave jacobian off, "// &
                           "or raise max_size_mb")
            return
        end if
        if (cfg%record%lyapunov .and. cfg%record%covariant) call check_clv_size(cfg, k, err)
    end subroutine check_size

    !> Covariant vectors: /clv in the file, and the scratch files of the forward pass
    !> (docs/model.md section 14.3), each within max_size_mb.
    subroutine check_clv_size(cfg, k, err)
        type(config_t), intent(in) :: cfg
        integer, intent(in) :: k
        type(error_t), allocatable, intent(out) :: err
        real(wp) :: mb
        integer :: n

        n = cfg%model%n
        associate (r => cfg%record)
            mb = (8.0_wp*(k + 2) + 8.0_wp*min(r%clv_store, k)*n)*(r%cycles - r%clv_transient)
            mb = (mb + 8.0_wp*r%clv_save*k*2*n)/1.0e6_wp
            if (mb > cfg%max_size_mb) then
                call set_error(err, "&output: /clv of this run needs about "//fmt_real(mb)// &
                               " MB, more than max_size_mb = "//fmt_real(cfg%max_size_mb)// &
                               "; lower &run cycles, &lyapunov vectors, clv_store or "// &
                               "clv_save, or raise max_size_mb")
                return
            end if
            mb = clv_scratch_bytes(n, k, r%cycles, r%clv_transient)/1.0e6_wp
            if (mb > cfg%max_size_mb) &
                call set_error(err, "&lyapunov: the covariant vectors' scratch files need "// &
                               "about "//fmt_real(mb)//" MB of disk (2n x vectors x 8 bytes "// &
                               "per record), more than &output max_size_mb = "// &
                               fmt_real(cfg%max_size_mb)//"; lower &run cycles or vectors, "// &
                               "or raise max_size_mb")
        end associate
    end subroutine check_clv_size

end module chain_config_size
