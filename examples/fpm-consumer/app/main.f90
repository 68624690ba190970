!> A program of one's own on impactchain's public API: read a namelist, run the chain with
!> its whole Lyapunov spectrum in memory, and check the sum rule of docs/model.md section 7:
!> the exponents add up to the phase-space contraction, -2 b n T per cycle from the damping
!> plus 2 ln K per collision.
program chain_consumer
    use, intrinsic :: iso_fortran_env, only: error_unit
    use impactchain, only: wp, error_t, config_t, read_config, chain_t, start_chain, &
                           memory_sink_t, record_result_t, record_cycles, chain_period
    implicit none
    type(config_t) :: cfg
    type(chain_t) :: chain
    type(memory_sink_t) :: sink
    type(record_result_t) :: res
    type(error_t), allocatable :: err
    character(len=256) :: path
    real(wp) :: period, spectrum_sum, contraction

    path = 'chain.nml'
    if (command_argument_count() > 0) call get_command_argument(1, path)
    call read_config(trim(path), cfg, err)
    if (.not. allocated(err)) call start_chain(cfg, chain, err)
    sink%keep_strobe = .false.
    if (.not. allocated(err)) call record_cycles(cfg%record, chain, sink, res, err)
    if (allocated(err)) then
        write (error_unit, '(a)') 'chain-consumer: '//err%message
        error stop 1
    end if
    period = chain_period(chain)
    spectrum_sum = sum(res%lyapunov%nats_per_time)*period
    contraction = -2*cfg%model%damping*cfg%model%n*period + &
                  2*res%collisions_per_cycle*log(cfg%model%restitution)
    print '(a,i0,a,i0,a)', 'chain of ', cfg%model%n, ' oscillators, ', res%cycles_done, &
        ' cycles recorded'
    print '(a,es12.4,a)', 'largest Lyapunov exponent ', res%lyapunov%bits_per_cycle(1), &
        ' bits/cycle'
    print '(a,es22.14)', 'sum of the exponents (per cycle)  ', spectrum_sum
    print '(a,es22.14)', '-2 b n T + 2 c ln K (per cycle)   ', contraction
end program chain_consumer
