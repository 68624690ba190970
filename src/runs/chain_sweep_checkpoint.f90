!> A sweep's results outside memory (docs/model.md section 8): its checkpoint `file.h5.ckpt`
!> (chain_checkpoint's protocol), and the one layout of a branch as plain arrays that the
!> checkpoint and the MPI driver's gather both use (values as they are, so bit for bit).
module chain_sweep_checkpoint
    use chain_kinds, only: wp, i8
    use chain_error, only: error_t
    use chain_state, only: chain_state_t, moving_state
    use chain_config, only: config_t
    use chain_sweep, only: sweep_plan_t, sweep_result_t
    use chain_checkpoint, only: checkpoint_t, checkpoint_create, checkpoint_commit, &
                                checkpoint_open, checkpoint_refuse, checkpoint_close
    use chain_monitor, only: saving_monitor_t
    implicit none
    private
    public :: save_checkpoint, load_checkpoint, checkpoint_monitor_t
    public :: branch_record_sizes, pack_branch, unpack_branch

    !> The checkpoint's first bytes; the number changes with the layout of pack_branch.
    character(len=8), parameter :: checkpoint_magic = 'ICSWEEP3'

    !> run_sweep's monitor: the caller's, and a checkpoint every few seconds. It is told
    !> inside the task farm's critical section, so one thread at a time, with `res` and
    !> `starts` consistent. A checkpoint that cannot be written stops the sweep with that error
    !> (`err`): going on would risk hours of points on a full disk.
    type, extends(saving_monitor_t) :: checkpoint_monitor_t
        type(config_t) :: cfg
        type(sweep_plan_t) :: plan
        type(sweep_result_t), pointer :: res => null()
        type(chain_state_t), pointer :: starts(:) => null()
        character(len=:), allocatable :: path          !! of the checkpoint
    contains
        procedure :: save => save_sweep_checkpoint
    end type checkpoint_monitor_t

contains

    !> Finished points and where each branch resumes: after the input, a header of the
    !> sweep's sizes, then every branch as pack_branch lays it out. A failed write is an error
    !> and leaves the previous checkpoint as it was.
    subroutine save_checkpoint(path, cfg, plan, res, starts, err)
        character(len=*), intent(in) :: path
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(sweep_result_t), intent(in) :: res
        type(chain_state_t), intent(in) :: starts(:)
        type(error_t), allocatable, intent(out) :: err
        type(checkpoint_t) :: ck
        integer :: b, nr, ni
        real(wp), allocatable :: reals(:)
        integer(i8), allocatable :: ints(:)

        call checkpoint_create(ck, path, '&sweep', checkpoint_magic, cfg%input_text, err)
        if (allocated(err)) return
        if (ck%ios == 0) write (ck%unit, iostat=ck%ios, iomsg=ck%msg) plan%n_points, &
            cfg%model%n, cfg%record%cycles, plan%k, plan%n_branches
        call branch_record_sizes(cfg, plan, nr, ni)
        allocate (reals(nr), ints(ni))
        do b = 1, plan%n_branches
            if (ck%ios /= 0) exit
            call pack_branch(cfg, plan, res, starts, b, reals, ints)
            write (ck%unit, iostat=ck%ios, iomsg=ck%msg) reals, ints
        end do
        call checkpoint_commit(ck, err)
    end subroutine save_checkpoint

    !> Resume from a checkpoint of the same input, if there is one.
    subroutine load_checkpoint(path, cfg, plan, res, starts, err)
        character(len=*), intent(in) :: path
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(sweep_result_t), intent(inout) :: res
        type(chain_state_t), intent(inout) :: starts(:)
        type(error_t), allocatable, intent(out) :: err
        type(checkpoint_t) :: ck
        integer :: n_points, n, k, n_branches, b, nr, ni
        integer(i8) :: cycles
        real(wp), allocatable :: reals(:)
        integer(i8), allocatable :: ints(:)
        logical :: found

        call checkpoint_open(ck, path, '&sweep', checkpoint_magic, cfg%input_text, found, err)
        if (.not. found .or. allocated(err)) return
        read (ck%unit, iostat=ck%ios) n_points, n, cycles, k, n_branches
        if (ck%ios /= 0 .or. n_points /= plan%n_points .or. n /= cfg%model%n .or. &
            cycles /= cfg%record%cycles .or. k /= plan%k .or. n_branches /= plan%n_branches) then
            call checkpoint_refuse(ck, err)
            return
        end if
        call branch_record_sizes(cfg, plan, nr, ni)
        allocate (reals(nr), ints(ni))
        do b = 1, n_branches
            read (ck%unit, iostat=ck%ios) reals, ints
            if (ck%ios /= 0) exit
            call unpack_branch(cfg, plan, b, reals, ints, res, starts)
        end do
        call checkpoint_close(ck, err)
    end subroutine load_checkpoint

    subroutine save_sweep_checkpoint(monitor)
        class(checkpoint_monitor_t), intent(inout) :: monitor

        call save_checkpoint(monitor%path, monitor%cfg, monitor%plan, monitor%res, &
                             monitor%starts, monitor%err)
    end subroutine save_sweep_checkpoint

    !> Lengths of one branch in pack_branch's layout: nr reals and ni integers.
    pure subroutine branch_record_sizes(cfg, plan, nr, ni)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        integer, intent(out) :: nr, ni

        nr = plan%points_per_branch*point_reals(cfg, plan) + 2*cfg%model%n + 1
        ni = plan%points_per_branch*point_ints(cfg, plan) + cfg%model%n + 2
    end subroutine branch_record_sizes

    !> Reals per point: collisions, x (n x cycles), exponents, stderr, Kaplan-Yorke dimension.
    pure integer function point_reals(cfg, plan)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan

        point_reals = 2 + cfg%model%n*int(cfg%record%cycles) + 2*plan%k
    end function point_reals

    !> Integers per point: done, periods (n), the standard errors' blocks (k).
    pure integer function point_ints(cfg, plan)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan

        point_ints = 1 + cfg%model%n + plan%k
    end function point_ints

    !> Branch b of a sweep, its points and the state it resumes from, as two plain arrays
    !> (sizes from branch_record_sizes): the one layout of the sweep's results outside
    !> memory, for the checkpoint and for MPI (values as they are, so bit for bit). Point
    !> by point, the reals of point_reals and the integers of point_ints; then the resume
    !> state, reals x, v, s and integers resume, contact, cycle (zeros when not resuming).
    pure subroutine pack_branch(cfg, plan, res, starts, b, reals, ints)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        type(sweep_result_t), intent(in) :: res
        type(chain_state_t), intent(in) :: starts(:)
        integer, intent(in) :: b
        real(wp), intent(out) :: reals(:)
        integer(i8), intent(out) :: ints(:)
        integer :: q, p, nr, ni

        nr = point_reals(cfg, plan)
        ni = point_ints(cfg, plan)
        do q = 1, plan%points_per_branch
            p = (b - 1)*plan%points_per_branch + q
            reals((q - 1)*nr + 1:q*nr) = [res%collisions(p), &
                                          reshape(res%x(:, :, p), &
                                              [cfg%model%n*int(cfg%record%cycles)]), &
                                          res%exponents(:, p), res%stderr(:, p), res%ky(p)]
            ints((q - 1)*ni + 1:q*ni) = [merge(1_i8, 0_i8, res%done(p)), &
                                         int(res%period(:, p), i8), res%stderr_block(:, p)]
        end do
        reals(plan%points_per_branch*nr + 1:) = 0
        ints(plan%points_per_branch*ni + 1:) = 0
        if (.not. allocated(starts(b)%x)) return
        reals(plan%points_per_branch*nr + 1:) = [starts(b)%x, starts(b)%v, starts(b)%time]
        ints(plan%points_per_branch*ni + 1:) = [1_i8, int(starts(b)%contact, i8), &
                                                starts(b)%cycle]
    end subroutine pack_branch

    !> Branch b of a sweep back from pack_branch's arrays into `res` and `starts`.
    pure subroutine unpack_branch(cfg, plan, b, reals, ints, res, starts)
        type(config_t), intent(in) :: cfg
        type(sweep_plan_t), intent(in) :: plan
        integer, intent(in) :: b
        real(wp), intent(in) :: reals(:)
        integer(i8), intent(in) :: ints(:)
        type(sweep_result_t), intent(inout) :: res
        type(chain_state_t), intent(inout) :: starts(:)
        integer :: q, p, n, m, k, j, i

        n = cfg%model%n
        m = n*int(cfg%record%cycles)
        k = plan%k
        do q = 1, plan%points_per_branch
            p = (b - 1)*plan%points_per_branch + q
            j = (q - 1)*point_reals(cfg, plan)
            i = (q - 1)*point_ints(cfg, plan)
            res%collisions(p) = reals(j + 1)
            res%x(:, :, p) = reshape(reals(j + 2:j + 1 + m), [n, int(cfg%record%cycles)])
            res%exponents(:, p) = reals(j + 2 + m:j + 1 + m + k)
            res%stderr(:, p) = reals(j + 2 + m + k:j + 1 + m + 2*k)
            res%ky(p) = reals(j + 2 + m + 2*k)
            res%done(p) = ints(i + 1) == 1
            res%period(:, p) = int(ints(i + 2:i + 1 + n))
            res%stderr_block(:, p) = ints(i + 2 + n:i + 1 + n + k)
        end do
        j = plan%points_per_branch*point_reals(cfg, plan)
        i = plan%points_per_branch*point_ints(cfg, plan)
        if (ints(i + 1) /= 1) then
            starts(b) = chain_state_t()
            return
        end if
        starts(b) = moving_state(reals(j + 1:j + n), reals(j + n + 1:j + 2*n), ints(i + 2 + n), &
                                 reals(j + 2*n + 1))
        starts(b)%contact = int(ints(i + 2:i + 1 + n))
    end subroutine unpack_branch
end module chain_sweep_checkpoint
