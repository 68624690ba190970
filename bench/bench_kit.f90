!> Helpers of the impactchain benchmark (`bench/bench.f90`): a wall clock, the process's peak
!> resident memory, the machine line, and the result rows with their two printed forms (a
!> Markdown table for people, tab-separated lines for `bench/run_bench.py`).
!>
!> Timings are reported, never asserted: nothing here decides whether a number is good.
module bench_kit
    use, intrinsic :: iso_fortran_env, only: int64, output_unit
    use impactchain, only: wp, provenance_item_t, provenance
    implicit none
    private
    public :: row_t, wall_seconds, peak_memory_kib, print_machine
    public :: print_table_head, print_row_markdown, print_row_tsv

    !> One measured case. Every derived number (per cycle, per collision, per unit) is computed
    !> from these counts of the best repetition, so the printed columns always agree.
    type :: row_t
        character(len=:), allocatable :: name   !! short id, the value of --case
        character(len=:), allocatable :: label  !! what was run, for the table
        integer :: n = 0                        !! oscillators
        integer(int64) :: cycles = 0            !! drive cycles in the best repetition
        integer(int64) :: collisions = 0        !! impacts in the best repetition
        real(wp) :: seconds = 0                 !! wall time of the best repetition
        integer(int64) :: units = 0             !! sweep points or oscillator snapshots (0: none)
        character(len=:), allocatable :: unit_name
        integer(int64) :: peak_kib = -1         !! VmHWM after the case (process high-water mark)
        real(wp) :: min_bond_share = -1         !! least-colliding bond over the mean (-1: n/a)
        integer :: vectors = 0                  !! Lyapunov exponents computed (0: none)
        integer :: reps = 0                     !! repetitions timed (the best is reported)
        !> wall time of the same cycles without the work the row is about, timed alternately
        !> with it (covariant vectors: the spectrum alone; 0: none)
        real(wp) :: baseline_seconds = 0
    end type row_t

contains

    !> Wall-clock seconds from an arbitrary origin (int64 system_clock: no wrap in practice).
    function wall_seconds() result(t)
        real(wp) :: t
        integer(int64) :: count, rate

        call system_clock(count, rate)
        t = real(count, wp)/real(rate, wp)
    end function wall_seconds

    !> The process's peak resident set size (VmHWM of /proc/self/status) in KiB; -1 if unknown.
    function peak_memory_kib() result(kib)
        integer(int64) :: kib
        integer :: u, ios
        character(len=256) :: line

        kib = -1
        open (newunit=u, file='/proc/self/status', status='old', action='read', iostat=ios)
        if (ios /= 0) return
        do
            read (u, '(a)', iostat=ios) line
            if (ios /= 0) exit
            if (line(1:6) == 'VmHWM:') then
                read (line(7:), *, iostat=ios) kib
                if (ios /= 0) kib = -1
                exit
            end if
        end do
        close (u)
    end function peak_memory_kib

    !> Where the bench runs, above its table: the provenance every output file carries
    !> (chain_provenance: code version, compiler and flags, BLAS and its kernels, CPU).
    subroutine print_machine(tsv)
        logical, intent(in) :: tsv
        type(provenance_item_t), allocatable :: items(:)
        integer :: i

        items = provenance()
        do i = 1, size(items)
            if (tsv) then
                write (output_unit, '(a)') 'provenance'//achar(9)//items(i)%key//achar(9)// &
                    items(i)%value
            else
                write (output_unit, '(a)') items(i)%key//': '//items(i)%value
            end if
        end do
        if (.not. tsv) write (output_unit, '(a)') 'one core, fpm --profile release', ''
    end subroutine print_machine

    subroutine print_table_head()
        write (output_unit, '(a)') '| case | n | collisions per cycle | us per drive cycle | '// &
            'collisions per second | ns per collision | peak memory (MiB) |'
        write (output_unit, '(a)') '|---|---:|---:|---:|---:|---:|---:|'
    end subroutine print_table_head

    subroutine print_row_markdown(row)
        type(row_t), intent(in) :: row
        character(len=:), allocatable :: label

        label = row%label
        if (row%units > 0) label = label//'; '//rate_text(row)
        write (output_unit, '(a)') '| '//label//' | '//itoa(row%n)//' | '// &
            real_text(per(real(row%collisions, wp), real(row%cycles, wp)))//' | '// &
            real_text(1.0e6_wp*per(row%seconds, real(row%cycles, wp)))//' | '// &
            real_text(per(real(row%collisions, wp), row%seconds))//' | '// &
            real_text(1.0e9_wp*per(row%seconds, real(row%collisions, wp)))//' | '// &
            real_text(real(row%peak_kib, wp)/1024)//' |'
    end subroutine print_row_markdown

    !> row, name, n, cycles, collisions, seconds, units, unit name, peak KiB, bond share,
    !> vectors, repetitions, label, baseline seconds
    subroutine print_row_tsv(row)
        type(row_t), intent(in) :: row
        character(len=32) :: sec, share, baseline
        character, parameter :: tab = achar(9)

        write (sec, '(es24.16)') row%seconds
        write (share, '(es12.4)') row%min_bond_share
        write (baseline, '(es24.16)') row%baseline_seconds
        write (output_unit, '(a)') 'row'//tab//row%name//tab//itoa(row%n)//tab// &
            itoa(row%cycles)//tab//itoa(row%collisions)//tab//trim(adjustl(sec))//tab// &
            itoa(row%units)//tab//row%unit_name//tab//itoa(row%peak_kib)//tab// &
            trim(adjustl(share))//tab//itoa(row%vectors)//tab//itoa(row%reps)//tab// &
            row%label//tab//trim(adjustl(baseline))
    end subroutine print_row_tsv

    !> Rate of the row's units: points or census samples per second, or ns per oscillator
    !> snapshot.
    function rate_text(row) result(text)
        type(row_t), intent(in) :: row
        character(len=:), allocatable :: text

        if (row%unit_name == 'points' .or. row%unit_name == 'samples') then
            text = real_text(per(real(row%units, wp), row%seconds))//' '//row%unit_name//'/s'
        else
            text = real_text(1.0e9_wp*per(row%seconds, real(row%units, wp)))//' ns per '// &
                   row%unit_name
        end if
    end function rate_text

    !> a / b, or 0 when b is 0 (a case without collisions has no cost per collision).
    pure function per(a, b) result(q)
        real(wp), intent(in) :: a, b
        real(wp) :: q

        q = 0
        if (b > 0) q = a/b
    end function per

    !> Three significant digits, no exponent below 1e7 (table cells).
    function real_text(x) result(text)
        real(wp), intent(in) :: x
        character(len=:), allocatable :: text
        character(len=32) :: buf

        if (x == 0) then
            buf = '0'
        else if (abs(x) >= 1.0e7_wp) then
            write (buf, '(es10.3)') x
        else if (abs(x) >= 100) then
            write (buf, '(i0)') nint(x, int64)
        else if (abs(x) >= 10) then
            write (buf, '(f0.1)') x
        else if (abs(x) >= 1) then
            write (buf, '(f0.2)') x
        else
            write (buf, '(f0.3)') x
            if (buf(1:1) == '.') buf = '0'//buf
        end if
        text = trim(adjustl(buf))
    end function real_text

    pure function itoa(i) result(text)
        class(*), intent(in) :: i
        character(len=:), allocatable :: text
        character(len=24) :: buf

        select type (i)
        type is (integer)
            write (buf, '(i0)') i
        type is (integer(int64))
            write (buf, '(i0)') i
        class default
            buf = '?'
        end select
        text = trim(buf)
    end function itoa

end module bench_kit
