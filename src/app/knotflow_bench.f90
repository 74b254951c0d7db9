!> Program knotflow-bench: time one velocity evaluation (forces + hydrodynamics + flow) for the trefoil
!> (N = 99) and the candy-cane (N = 152) with the `none` and `rpy` models (median over many
!> repetitions); with --trefoil-case also integrate the reference trefoil case (A = 2.2,
!> orientation c, rpy, t_end = 1000, tolerance 1e-4) and report wall time, steps, rejections.
!> It also compares, for RPY, the pair loop (prepare + apply_mobility) with assembling the
!> 3N x 3N matrix (prepare + mobility_matrix) and applying it with DSYMV.
program knotflow_bench
  use, intrinsic :: iso_fortran_env, only: int64, output_unit
  use kf_kinds, only: wp
  use kf_blas, only: dsymv
  use kf_error, only: error_t
  use kf_accuracy, only: wall_seconds, median
  use kf_scene, only: scene_t
  use kf_chain_shapes, only: build_initial_chain
  use kf_dynamics, only: dynamics_t
  use kf_stepper, only: stepper_t
  use kf_stepper_factory, only: make_stepper
  use kf_hydro_rpy, only: rpy_model_t
  use kf_cli, only: standard_option, argument, die
  implicit none

  character(len=*), parameter :: program_name = 'knotflow-bench'

  type(scene_t) :: scene
  type(error_t), allocatable :: error
  character(len=:), allocatable :: arg
  logical :: trefoil_case
  integer :: i, ishape, imodel
  character(len=9), parameter :: shapes(2) = ['trefoil  ', 'candycane']
  character(len=4), parameter :: models(2) = ['none', 'rpy ']
  real(wp) :: t_eval

  trefoil_case = .false.
  do i = 1, command_argument_count()
    arg = argument(i)
    call standard_option(program_name, arg, 'usage: knotflow-bench [--trefoil-case]'//new_line('a')// &
      '       knotflow-bench --help | --version'//new_line('a')// &
      'Times one velocity evaluation (none, rpy; trefoil and candy-cane); --trefoil-case also runs'// &
      new_line('a')//'the reference trefoil case (rpy, t_end = 1000).')
    select case (trim(arg))
    case ('--trefoil-case')
      trefoil_case = .true.
    case default
      call die(program_name, "unknown argument '"//arg//"' (allowed: --trefoil-case, --help, --version)", 2)
    end select
  end do

  write (output_unit, '(a)') '# one velocity evaluation (forces + hydrodynamics + flow), median'
  write (output_unit, '(a10,a6,a6,a16)') 'shape', 'N', 'model', 'time [us]'
  do ishape = 1, 2
    do imodel = 1, 2
      scene = scene_t()
      scene%chain%shape = shapes(ishape)
      scene%hydro%model = models(imodel)
      call time_velocity(scene, t_eval, error)
      if (allocated(error)) call die(program_name, error%message, 1)
      write (output_unit, '(a10,i6,a6,f16.3)') trim(shapes(ishape)), merge(99, 152, ishape == 1), &
        trim(models(imodel)), 1.0e6_wp*t_eval
    end do
  end do

  scene = scene_t()
  call compare_matrix(scene, error)
  if (allocated(error)) call die(program_name, error%message, 1)

  if (trefoil_case) then
    scene = scene_t()
    scene%chain%orientation = 'c'
    scene%forces%bending_a = 2.2_wp
    scene%hydro%model = 'rpy'
    scene%integrator%t_end = 1000.0_wp
    call run_case(scene, error)
    if (allocated(error)) call die(program_name, error%message, 1)
  end if

contains

  !> Median over 41 batches of the time per evaluation (a batch lasts about 10 ms).
  subroutine time_velocity(scene, t_eval, error)
    type(scene_t), intent(in) :: scene
    real(wp), intent(out) :: t_eval
    type(error_t), allocatable, intent(out) :: error
    type(dynamics_t) :: dyn
    real(wp), allocatable :: r(:, :), v(:, :)
    real(wp) :: rot(3, 3), t0, samples(41), checksum
    integer :: n, batch, k, rep
    t_eval = 0.0_wp   ! defined also when an error returns early
    call build_initial_chain(scene%chain, r, rot, error)
    if (allocated(error)) return
    n = size(r, 2)
    call dyn%init(scene, n, error)
    if (allocated(error)) return
    allocate (v(3, n))
    ! Calibrate the batch size.
    batch = 1
    do
      t0 = wall_seconds()
      do k = 1, batch
        call dyn%velocity(r, v, error)
      end do
      if (wall_seconds() - t0 > 0.01_wp .or. batch > 10**7) exit
      batch = 2*batch
    end do
    checksum = 0.0_wp
    do rep = 1, size(samples)
      t0 = wall_seconds()
      do k = 1, batch
        r(1, 1) = r(1, 1) + 1.0e-12_wp   ! keep the work from being hoisted
        call dyn%velocity(r, v, error)
        if (allocated(error)) return
        checksum = checksum + v(1, 1)
      end do
      samples(rep) = (wall_seconds() - t0)/batch
    end do
    t_eval = median(samples)
    if (.not. abs(checksum) <= huge(1.0_wp)) t_eval = -1.0_wp
  end subroutine time_velocity

  !> RPY mobility product for the trefoil: pair loop versus matrix + DSYMV (median times).
  subroutine compare_matrix(scene, error)
    type(scene_t), intent(in) :: scene
    type(error_t), allocatable, intent(out) :: error
    type(rpy_model_t) :: model
    real(wp), allocatable :: r(:, :), f(:, :), u(:, :), mu(:, :), u2(:)
    real(wp) :: rot(3, 3), t0, s_loop(21), s_mat(21)
    integer :: n, k, rep, reps
    call build_initial_chain(scene%chain, r, rot, error)
    if (allocated(error)) return
    n = size(r, 2)
    allocate (f(3, n), u(3, n), mu(3*n, 3*n), u2(3*n))
    call random_number(f)
    reps = 200
    do rep = 1, size(s_loop)
      t0 = wall_seconds()
      do k = 1, reps
        call model%prepare(r, error)
        call model%apply_mobility(f, u)
      end do
      s_loop(rep) = (wall_seconds() - t0)/reps
      t0 = wall_seconds()
      do k = 1, reps
        call model%prepare(r, error)
        call model%mobility_matrix(mu)
        call dsymv('L', 3*n, 1.0_wp, mu, 3*n, f, 1, 0.0_wp, u2, 1)
      end do
      s_mat(rep) = (wall_seconds() - t0)/reps
    end do
    write (output_unit, '(a)') '# RPY mu F for the trefoil (N = 99), median'
    write (output_unit, '(a,f12.3)') 'pair loop            [us]', 1.0e6_wp*median(s_loop)
    write (output_unit, '(a,f12.3)') 'matrix + DSYMV       [us]', 1.0e6_wp*median(s_mat)
    write (output_unit, '(a,es12.3)') 'max |difference|        ', maxval(abs(reshape(u, [3*n]) - u2))
  end subroutine compare_matrix

  !> Integrate the scene to t_end with no output and report the cost.
  subroutine run_case(scene, error)
    type(scene_t), intent(in) :: scene
    type(error_t), allocatable, intent(out) :: error
    type(dynamics_t) :: dyn
    class(stepper_t), allocatable :: integ
    real(wp), allocatable :: r(:, :)
    real(wp) :: rot(3, 3), t, t0, wall
    integer :: n
    call build_initial_chain(scene%chain, r, rot, error)
    if (allocated(error)) return
    n = size(r, 2)
    call dyn%init(scene, n, error)
    if (allocated(error)) return
    call make_stepper(scene%integrator, integ, error)
    if (allocated(error)) return
    t = 0.0_wp
    t0 = wall_seconds()
    call integ%advance(dyn, t, r, scene%integrator%t_end, error)
    wall = wall_seconds() - t0
    if (allocated(error)) return
    write (output_unit, '(a)') '# trefoil case: N = 99, A = 2.2, orientation c, rpy, t_end = 1000, tolerance 1e-4'
    write (output_unit, '(a,f12.3)') 'wall time [s]      ', wall
    write (output_unit, '(a,i12)') 'steps              ', integ%steps()
    write (output_unit, '(a,i12)') 'rejected           ', integ%rejected()
    write (output_unit, '(a,i12)') 'evaluations        ', integ%evaluations()
    write (output_unit, '(a,es12.4)') 'dt min used        ', integ%dt_min_used()
    write (output_unit, '(a,es12.4)') 'dt max used        ', integ%dt_max_used()
    write (output_unit, '(a,f12.3)') 'us per evaluation  ', 1.0e6_wp*wall/max(1_int64, integ%evaluations())
    write (output_unit, '(a,3f12.4)') 'centre of mass     ', sum(r, dim=2)/n
  end subroutine run_case

end program knotflow_bench
