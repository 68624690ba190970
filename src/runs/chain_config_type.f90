!> The run configuration every run starts from (docs/model.md sections 1, 6-8 and 13): the
!> model, the start, what is recorded, the output, and a sweep, continuation or census, as
!> read from the input (chain_config) and checked (chain_config_checks). `inputs` holds every
!> key of the input schema as used (chain_inputs); the typed components are what the runs use.
module chain_config_type
    use chain_kinds, only: wp
    use chain_model, only: model_t
    use chain_record, only: record_spec_t, vector_count
    use chain_input_values, only: input_values_t
    implicit none
    private
    public :: config_t, lyapunov_vectors

    type :: config_t
        !> &chain, and &run stick_speed: everything the dynamics depends on
        type(model_t) :: model
        ! &initial
        character(len=:), allocatable :: initial_kind
        integer :: seed = 1
        real(wp) :: x_amp = 0, v_amp = 0
        real(wp), allocatable :: x0(:), v0(:)
        character(len=:), allocatable :: initial_file
        !> &run (but stick_speed, a parameter of the model) and &lyapunov
        type(record_spec_t) :: record
        ! &output
        character(len=:), allocatable :: output_file
        logical :: overwrite = .false.
        real(wp) :: max_size_mb = 4096
        ! &sweep
        logical :: sweep = .false.
        character(len=:), allocatable :: sweep_parameter, sweep_parameter2, sweep_mode
        real(wp) :: sweep_start = 0, sweep_stop = 0, sweep_step = 0
        real(wp) :: sweep_start2 = 0, sweep_stop2 = 0, sweep_step2 = 0
        ! &continuation: periodic orbits and their branches (chain_branch)
        logical :: continuation = .false.
        character(len=:), allocatable :: cont_parameter
        real(wp) :: cont_stop = 0, cont_step = 0
        integer :: cont_period = 1, cont_max_points = 200, cont_doublings = 0
        integer :: cont_branch_points = 0
        !> a curve of special points in (parameter, parameter2) (chain_curve): follow
        !> ('' none) and parameter2, the bound stop2 and step step2
        character(len=:), allocatable :: cont_follow, cont_parameter2
        real(wp) :: cont_stop2 = 0, cont_step2 = 0
        ! &census: the attractors reached from random starts (chain_census)
        logical :: census = .false.
        integer :: census_samples = 100, census_seed = 1
        real(wp) :: census_x_amp = 0.3_wp, census_v_amp = 0.3_wp
        real(wp) :: census_tolerance = 1.0e-6_wp
        character(len=:), allocatable :: census_mirror   !! 'merge' or 'separate'
        !> A census on a plane of two initial coordinates ('x<i>' or 'v<i>'; '' without a
        !> plane): plane_points**2 starts on a grid over plane_range (first coordinate's
        !> min, max, then the second's), the other coordinates those of &initial.
        character(len=16) :: census_plane(2) = ''
        real(wp) :: census_plane_range(4) = 0
        integer :: census_plane_points = 0
        !> Leading Lyapunov exponents of each sample (1 .. 2n): an ensemble of spectra
        integer :: census_exponents = 1
        ! the input as read, and every key's value as used
        character(len=:), allocatable :: input_text
        type(input_values_t) :: inputs
    end type config_t

contains

    !> Lyapunov exponents (tangent vectors) a validated configuration computes: none without
    !> &lyapunov, else `vectors`, 0 meaning all 2n.
    pure integer function lyapunov_vectors(cfg)
        type(config_t), intent(in) :: cfg

        lyapunov_vectors = vector_count(cfg%record, cfg%model%n)
    end function lyapunov_vectors

end module chain_config_type
