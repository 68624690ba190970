!> Where the records of a run go (docs/model.md sections 6-7 and 14): the sink a run sends
!> its strobe records, events, finite-time exponents and covariant-vector numbers to, chunk by
!> chunk (an HDF5 file of the CLI, a memory sink of sweeps and of the Python extension, or a
!> sink of one's own), and the chunk that holds them on the way. What is recorded and when:
!> chain_record, which also offers these types with `record_cycles`.
module chain_record_sink
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_event_log, only: event_log_t, event_log_init, event_log_clear, event_log_append
    use chain_lyapunov, only: lyapunov_acc_t
    use chain_clv, only: clv_rows_t
    implicit none
    private
    public :: record_sink_t, memory_sink_t, record_chunk_t, chunk_start, chunk_flush
    public :: chunk_take_window, window_buffer_start

    !> Where strobe records and events go, chunk by chunk.
    type, abstract :: record_sink_t
    contains
        procedure(put_strobe_i), deferred :: put_strobe
        procedure(put_events_i), deferred :: put_events
        !> per-record numbers of covariant vectors, a block at a time, last block first
        !> (by default dropped)
        procedure :: put_clv => discard_clv
        !> finite-time exponents, a chunk of windows at a time (by default dropped)
        procedure :: put_windows => discard_windows
    end type record_sink_t

    abstract interface
        subroutine put_strobe_i(sink, n_records, first, x, v, cycle, err)
            import :: record_sink_t, wp, i8, error_t
            class(record_sink_t), intent(inout) :: sink
            integer(i8), intent(in) :: n_records, first
            real(wp), intent(in), contiguous :: x(:, :), v(:, :) !! records are whole columns
            integer(i8), intent(in), contiguous :: cycle(:)
            type(error_t), allocatable, intent(out) :: err
        end subroutine put_strobe_i
        subroutine put_events_i(sink, log, err)
            import :: record_sink_t, event_log_t, error_t
            class(record_sink_t), intent(inout) :: sink
            type(event_log_t), intent(in) :: log
            type(error_t), allocatable, intent(out) :: err
        end subroutine put_events_i
    end interface

    !> Keeps every record in memory: x(n, cycles), v(n, cycles), and all events; the
    !> per-record numbers of covariant vectors (records with vectors in order, clv_rows_t's
    !> arrays whole); and the finite-time exponents (k, windows) with their cycles.
    type, extends(record_sink_t) :: memory_sink_t
        logical :: keep_strobe = .true.
        real(wp), allocatable :: x(:, :), v(:, :)
        integer(i8), allocatable :: cycle(:)
        type(event_log_t) :: events
        integer(i8), allocatable :: clv_cycle(:)
        real(wp), allocatable :: clv_ipr(:, :), clv_site_weight(:, :, :), clv_min_angle(:)
        real(wp), allocatable :: window_exponents(:, :)
        integer(i8), allocatable :: window_cycle(:)
    contains
        procedure :: put_strobe => memory_put_strobe
        procedure :: put_events => memory_put_events
        procedure :: put_clv => memory_put_clv
        procedure :: put_windows => memory_put_windows
    end type memory_sink_t

    !> Finite-time exponents held for the sink: windows first .. first + count - 1 of `total`.
    type :: window_buffer_t
        integer(i8) :: total = 0, first = 1, seen = 0
        integer :: count = 0
        real(wp), allocatable :: exponents(:, :)  !! exponents(k, chunk), bits per cycle
        integer(i8), allocatable :: cycle(:)      !! drive cycle at each window's end
    end type window_buffer_t

    !> Records on their way to a sink: strobe records from record `first` on (record
    !> first + i - 1 in column i), the events since the last flush, and the finite-time
    !> exponents held.
    type :: record_chunk_t
        real(wp), allocatable :: x(:, :), v(:, :) !! (n, columns)
        integer(i8), allocatable :: cycle(:)      !! drive cycle of each record
        integer(i8) :: first = 1
        type(event_log_t) :: log
        type(window_buffer_t) :: windows
    end type record_chunk_t

contains

    !> A chunk of `columns` records of n oscillators from record `first` on, with every event
    !> when `keep_events` (else the log counts them only).
    subroutine chunk_start(chunk, n, columns, first, keep_events)
        type(record_chunk_t), intent(inout) :: chunk
        integer, intent(in) :: n, columns
        integer(i8), intent(in) :: first
        logical, intent(in) :: keep_events

        call event_log_init(chunk%log, keep_events, 1024)
        allocate (chunk%x(n, columns), chunk%v(n, columns), chunk%cycle(columns))
        chunk%first = first
    end subroutine chunk_start

    !> The first `count` records of the chunk (of a run of `n_records`), the events and the
    !> windows to the sink; the chunk then starts again after them.
    subroutine chunk_flush(chunk, n_records, count, sink, err)
        type(record_chunk_t), intent(inout) :: chunk
        integer(i8), intent(in) :: n_records
        integer, intent(in) :: count
        class(record_sink_t), intent(inout) :: sink
        type(error_t), allocatable, intent(out) :: err

        if (count > 0) call sink%put_strobe(n_records, chunk%first, chunk%x(:, :count), &
                                            chunk%v(:, :count), chunk%cycle(:count), err)
        if (.not. allocated(err) .and. chunk%log%enabled) call sink%put_events(chunk%log, err)
        if (.not. allocated(err) .and. allocated(chunk%windows%exponents)) &
            call window_buffer_flush(chunk%windows, sink, err)
        if (allocated(err)) return
        call event_log_clear(chunk%log)
        chunk%first = chunk%first + count
    end subroutine chunk_flush

    !> With finite-time exponents: the window the last QR step ended, if any, at drive cycle
    !> `cycle`; a full buffer goes to the sink.
    subroutine chunk_take_window(chunk, acc, cycle, sink, err)
        type(record_chunk_t), intent(inout) :: chunk
        type(lyapunov_acc_t), intent(in) :: acc
        integer(i8), intent(in) :: cycle
        class(record_sink_t), intent(inout) :: sink
        type(error_t), allocatable, intent(out) :: err

        if (.not. allocated(chunk%windows%exponents)) return
        call window_buffer_take(chunk%windows, acc, cycle)
        if (chunk%windows%count == size(chunk%windows%cycle)) &
            call window_buffer_flush(chunk%windows, sink, err)
    end subroutine chunk_take_window

    !> Finite-time exponents of a run of `total` windows: a chunk of at most 1 MiB held for the
    !> sink (each record's QR step ends at most one window).
    pure subroutine window_buffer_start(buf, acc, total)
        type(window_buffer_t), intent(out) :: buf
        type(lyapunov_acc_t), intent(in) :: acc
        integer(i8), intent(in) :: total
        integer :: chunk

        chunk = int(max(1_i8, min(total, 131072_i8/acc%k)))
        allocate (buf%exponents(acc%k, chunk), buf%cycle(chunk))
        buf%total = total
        buf%seen = acc%windows
        buf%first = acc%windows + 1
    end subroutine window_buffer_start

    !> The window the last QR step ended, if it ended one, at drive cycle `cycle`, in bits per
    !> cycle.
    pure subroutine window_buffer_take(buf, acc, cycle)
        type(window_buffer_t), intent(inout) :: buf
        type(lyapunov_acc_t), intent(in) :: acc
        integer(i8), intent(in) :: cycle

        if (acc%windows == buf%seen) return
        buf%seen = acc%windows
        buf%count = buf%count + 1
        buf%exponents(:, buf%count) = acc%window_last/log(2.0_wp)
        buf%cycle(buf%count) = cycle
    end subroutine window_buffer_take

    !> The held windows to the sink.
    subroutine window_buffer_flush(buf, sink, err)
        type(window_buffer_t), intent(inout) :: buf
        class(record_sink_t), intent(inout) :: sink
        type(error_t), allocatable, intent(out) :: err

        if (buf%count == 0) return
        call sink%put_windows(buf%total, buf%first, buf%exponents(:, :buf%count), &
                              buf%cycle(:buf%count), err)
        buf%first = buf%first + buf%count
        buf%count = 0
    end subroutine window_buffer_flush

    !> A sink that keeps no finite-time exponents.
    subroutine discard_windows(sink, n_windows, first, exponents, cycle, err)
        class(record_sink_t), intent(inout) :: sink
        integer(i8), intent(in) :: n_windows, first
        real(wp), intent(in), contiguous :: exponents(:, :)
        integer(i8), intent(in), contiguous :: cycle(:)
        type(error_t), allocatable, intent(out) :: err
    end subroutine discard_windows

    !> A sink that keeps no covariant vectors.
    subroutine discard_clv(sink, rows, err)
        class(record_sink_t), intent(inout) :: sink
        type(clv_rows_t), intent(in) :: rows
        type(error_t), allocatable, intent(out) :: err
    end subroutine discard_clv

    subroutine memory_put_strobe(sink, n_records, first, x, v, cycle, err)
        class(memory_sink_t), intent(inout) :: sink
        integer(i8), intent(in) :: n_records, first
        real(wp), intent(in), contiguous :: x(:, :), v(:, :)
        integer(i8), intent(in), contiguous :: cycle(:)
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: last

        if (.not. sink%keep_strobe) return
        if (.not. allocated(sink%x)) then
            allocate (sink%x(size(x, 1), n_records), sink%v(size(x, 1), n_records))
            allocate (sink%cycle(n_records))
        end if
        last = first + size(x, 2) - 1
        sink%x(:, first:last) = x
        sink%v(:, first:last) = v
        sink%cycle(first:last) = cycle
    end subroutine memory_put_strobe

    subroutine memory_put_events(sink, log, err)
        class(memory_sink_t), intent(inout) :: sink
        type(event_log_t), intent(in) :: log
        type(error_t), allocatable, intent(out) :: err
        integer :: j

        if (.not. sink%events%enabled) call event_log_init(sink%events, .true., 1024)
        do j = 1, log%count
            call event_log_append(sink%events, log%time(j), log%site(j), log%speed(j), &
                                  log%kind(j))
        end do
    end subroutine memory_put_events

    subroutine memory_put_windows(sink, n_windows, first, exponents, cycle, err)
        class(memory_sink_t), intent(inout) :: sink
        integer(i8), intent(in) :: n_windows, first
        real(wp), intent(in), contiguous :: exponents(:, :)
        integer(i8), intent(in), contiguous :: cycle(:)
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: last

        if (.not. allocated(sink%window_cycle)) &
            allocate (sink%window_exponents(size(exponents, 1), n_windows), &
                      sink%window_cycle(n_windows))
        last = first + size(cycle) - 1
        sink%window_exponents(:, first:last) = exponents
        sink%window_cycle(first:last) = cycle
    end subroutine memory_put_windows

    subroutine memory_put_clv(sink, rows, err)
        class(memory_sink_t), intent(inout) :: sink
        type(clv_rows_t), intent(in) :: rows
        type(error_t), allocatable, intent(out) :: err
        integer(i8) :: last

        if (.not. allocated(sink%clv_cycle)) then
            allocate (sink%clv_cycle(rows%total), sink%clv_min_angle(rows%total))
            allocate (sink%clv_ipr(size(rows%ipr, 1), rows%total))
            allocate (sink%clv_site_weight(size(rows%site_weight, 1), &
                                           size(rows%site_weight, 2), rows%total))
        end if
        last = rows%first + rows%count - 1
        sink%clv_cycle(rows%first:last) = rows%cycle
        sink%clv_ipr(:, rows%first:last) = rows%ipr
        sink%clv_site_weight(:, :, rows%first:last) = rows%site_weight
        sink%clv_min_angle(rows%first:last) = rows%min_angle
    end subroutine memory_put_clv

end module chain_record_sink
