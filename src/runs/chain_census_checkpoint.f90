!> A census's samples outside memory (docs/model.md section 13): its checkpoint
!> `file.h5.ckpt` (chain_checkpoint's protocol), and one sample's record as plain arrays, the
!> MPI driver's (values as they are, so bit for bit).
module chain_census_checkpoint
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_config, only: config_t
    use chain_census, only: census_result_t
    use chain_checkpoint, only: checkpoint_t, checkpoint_create, checkpoint_commit, &
                                checkpoint_open, checkpoint_refuse, checkpoint_close
    use chain_monitor, only: saving_monitor_t
    implicit none
    private
    public :: save_census_checkpoint, load_census_checkpoint, census_checkpoint_monitor_t
    public :: sample_record_sizes, pack_sample, unpack_sample

    !> The checkpoint's first bytes; the number changes with its layout.
    character(len=8), parameter :: checkpoint_magic = 'ICCENSU3'

    !> The census's monitor: the caller's, and a checkpoint every few seconds. It is told
    !> inside the task farm's critical section, with `res` consistent. A checkpoint that
    !> cannot be written stops the census with that error (`err`).
    type, extends(saving_monitor_t) :: census_checkpoint_monitor_t
        type(config_t) :: cfg
        type(census_result_t), pointer :: res => null()
        character(len=:), allocatable :: path          !! of the checkpoint
    contains
        procedure :: save => save_census_progress
    end type census_checkpoint_monitor_t

contains

    !> The finished samples: after the input, a header of the census's sizes, then the
    !> per-sample arrays whole. A failed write is an error and leaves the previous checkpoint
    !> as it was.
    subroutine save_census_checkpoint(path, cfg, res, err)
        character(len=*), intent(in) :: path
        type(config_t), intent(in) :: cfg
        type(census_result_t), intent(in) :: res
        type(error_t), allocatable, intent(out) :: err
        type(checkpoint_t) :: ck

        call checkpoint_create(ck, path, '&census', checkpoint_magic, cfg%input_text, err)
        if (allocated(err)) return
        if (ck%ios == 0) write (ck%unit, iostat=ck%ios, iomsg=ck%msg) res%n_points, &
            res%n_samples, cfg%model%n, res%n_exponents
        if (ck%ios == 0) write (ck%unit, iostat=ck%ios, iomsg=ck%msg) merge(1, 0, res%done), &
            res%periods, res%sites, res%x0, res%v0, res%x, res%v, res%exponents, &
            res%exponents_stderr
        call checkpoint_commit(ck, err)
    end subroutine save_census_checkpoint

    !> Resume from a checkpoint of the same input, if there is one (`res` from
    !> census_result_init); `res` is left as it was when the checkpoint is refused or damaged.
    subroutine load_census_checkpoint(path, cfg, res, err)
        character(len=*), intent(in) :: path
        type(config_t), intent(in) :: cfg
        type(census_result_t), intent(inout) :: res
        type(error_t), allocatable, intent(out) :: err
        type(checkpoint_t) :: ck
        integer :: n_points, n_samples, n, k
        integer, allocatable :: done(:, :)
        type(census_result_t) :: got
        logical :: found

        call checkpoint_open(ck, path, '&census', checkpoint_magic, cfg%input_text, found, err)
        if (.not. found .or. allocated(err)) return
        read (ck%unit, iostat=ck%ios) n_points, n_samples, n, k
        if (ck%ios /= 0 .or. n_points /= res%n_points .or. n_samples /= res%n_samples .or. &
            n /= cfg%model%n .or. k /= res%n_exponents) then
            call checkpoint_refuse(ck, err)
            return
        end if
        got = res
        allocate (done(n_samples, n_points))
        read (ck%unit, iostat=ck%ios) done, got%periods, got%sites, got%x0, got%v0, got%x, &
            got%v, got%exponents, got%exponents_stderr
        call checkpoint_close(ck, err)
        if (allocated(err)) return
        got%done = done == 1
        call move_alloc(got%done, res%done)
        call move_alloc(got%periods, res%periods)
        call move_alloc(got%sites, res%sites)
        call move_alloc(got%x0, res%x0)
        call move_alloc(got%v0, res%v0)
        call move_alloc(got%x, res%x)
        call move_alloc(got%v, res%v)
        call move_alloc(got%exponents, res%exponents)
        call move_alloc(got%exponents_stderr, res%exponents_stderr)
    end subroutine load_census_checkpoint

    subroutine save_census_progress(monitor)
        class(census_checkpoint_monitor_t), intent(inout) :: monitor

        call save_census_checkpoint(monitor%path, monitor%cfg, monitor%res, monitor%err)
    end subroutine save_census_progress

    !> One sample's record as pack_sample lays it out: nr reals and ni 64-bit integers for a
    !> chain of n oscillators and k exponents per sample.
    pure subroutine sample_record_sizes(n, k, nr, ni)
        integer, intent(in) :: n, k
        integer, intent(out) :: nr, ni

        nr = 2*n + 2*k       ! x(n), v(n), exponents(k), their stderrs(k)
        ni = 2 + 2*n         ! done, periods(n), sites(n+1)
    end subroutine sample_record_sizes

    !> Sample s of point p's results as plain numbers (sent between MPI ranks): values as they
    !> are, so unpack_sample restores them bit for bit.
    pure subroutine pack_sample(res, s, p, reals, ints)
        type(census_result_t), intent(in) :: res
        integer, intent(in) :: s, p
        real(wp), intent(out) :: reals(:)
        integer(i8), intent(out) :: ints(:)
        integer :: n, k

        n = size(res%x, 1)
        k = res%n_exponents
        reals(1:n) = res%x(:, s, p)
        reals(1 + n:2*n) = res%v(:, s, p)
        reals(1 + 2*n:2*n + k) = res%exponents(:, s, p)
        reals(1 + 2*n + k:2*n + 2*k) = res%exponents_stderr(:, s, p)
        ints(1) = merge(1_i8, 0_i8, res%done(s, p))
        ints(2:1 + n) = int(res%periods(:, s, p), i8)
        ints(2 + n:2 + 2*n) = res%sites(:, s, p)
    end subroutine pack_sample

    !> The inverse of pack_sample: sample s of point p takes the record's results.
    pure subroutine unpack_sample(reals, ints, s, p, res)
        real(wp), intent(in) :: reals(:)
        integer(i8), intent(in) :: ints(:)
        integer, intent(in) :: s, p
        type(census_result_t), intent(inout) :: res
        integer :: n, k

        n = size(res%x, 1)
        k = res%n_exponents
        res%x(:, s, p) = reals(1:n)
        res%v(:, s, p) = reals(1 + n:2*n)
        res%exponents(:, s, p) = reals(1 + 2*n:2*n + k)
        res%exponents_stderr(:, s, p) = reals(1 + 2*n + k:2*n + 2*k)
        res%done(s, p) = ints(1) == 1
        res%periods(:, s, p) = int(ints(2:1 + n))
        res%sites(:, s, p) = ints(2 + n:2 + 2*n)
    end subroutine unpack_sample

end module chain_census_checkpoint
