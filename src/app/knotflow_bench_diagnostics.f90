!> Program knotflow-bench-diagnostics: the cost of the run diagnostics (kf_run_diagnostics) per accepted
!> step against one RPY velocity evaluation (a dopri45 step makes 6 of them), for the trefoil
!> (N = 99) and the candy-cane (N = 152), on a real step of each (taken after t = 5 of the RPY
!> dynamics with excluded volume); medians over batches. Then the trefoil (A = 2.2, orientation
!> c, rpy, excluded volume) integrated to t = 50 with and without the monitor (wall times).
program knotflow_bench_diagnostics
  use, intrinsic :: iso_fortran_env, only: output_unit
  use kf_kinds, only: wp, i8
  use kf_error, only: error_t
  use kf_accuracy, only: wall_seconds, median
  use kf_scene, only: scene_t
  use kf_chain_shapes, only: build_initial_chain
  use kf_dynamics, only: dynamics_t
  use kf_stepper, only: stepper_t
  use kf_stepper_factory, only: make_stepper
  use kf_run_diagnostics, only: run_diagnostics_t
  use kf_cli, only: standard_option, argument, die
  implicit none

  character(len=*), parameter :: program_name = 'knotflow-bench-diagnostics'

  type(scene_t) :: scene
  type(error_t), allocatable :: error
  character(len=9), parameter :: shapes(2) = ['trefoil  ', 'candycane']
  integer :: ishape
  real(wp) :: t_eval, t_diag, t_with, t_without
  character(len=:), allocatable :: arg

  if (command_argument_count() > 0) then
    arg = argument(1)
    call standard_option(program_name, arg, 'usage: knotflow-bench-diagnostics'// &
      new_line('a')//'       knotflow-bench-diagnostics --help | --version'//new_line('a')// &
      'Times the run diagnostics of one accepted step against one RPY evaluation (trefoil, candy-cane).')
    call die(program_name, "unknown argument '"//arg//"' (allowed: no arguments, --help, --version)", 2)
  end if
  write (output_unit, '(a)') '# run diagnostics per accepted step against one RPY evaluation, median'
  write (output_unit, '(a10,a6,a16,a18,a22)') 'shape', 'N', 'rpy eval [us]', 'diagnostics [us]', &
    '% of a dopri45 step'
  do ishape = 1, 2
    scene = bench_scene(shapes(ishape))
    call time_step_costs(scene, t_eval, t_diag, error)
    if (allocated(error)) call die(program_name, error%message, 1)
    write (output_unit, '(a10,i6,f16.2,f18.2,f22.2)') trim(shapes(ishape)), merge(99, 152, ishape == 1), &
      1.0e6_wp*t_eval, 1.0e6_wp*t_diag, 100.0_wp*t_diag/(6.0_wp*t_eval)
  end do

  scene = bench_scene('trefoil')
  call time_run(scene, 50.0_wp, .false., t_without, error)
  if (.not. allocated(error)) call time_run(scene, 50.0_wp, .true., t_with, error)
  if (allocated(error)) call die(program_name, error%message, 1)
  write (output_unit, '(a)') '# trefoil (A = 2.2, orientation c, rpy, excluded volume) to t = 50, wall time'
  write (output_unit, '(a,f10.3)') 'without diagnostics [s]', t_without
  write (output_unit, '(a,f10.3)') 'with diagnostics    [s]', t_with

contains

  function bench_scene(shape) result(sc)
    character(len=*), intent(in) :: shape
    type(scene_t) :: sc
    sc%chain%shape = shape
    sc%chain%orientation = 'c'
    sc%forces%bending_a = 2.2_wp
    sc%forces%excluded_volume = .true.
    sc%hydro%model = 'rpy'
  end function bench_scene

  !> Median times of one velocity evaluation and of one `on_step` of the diagnostics, on the
  !> step of the proposed size that follows t = 5.
  subroutine time_step_costs(sc, t_eval, t_diag, error)
    type(scene_t), intent(in) :: sc
    real(wp), intent(out) :: t_eval, t_diag
    type(error_t), allocatable, intent(out) :: error
    type(dynamics_t) :: dyn
    class(stepper_t), allocatable :: integ
    type(run_diagnostics_t) :: diag
    real(wp), allocatable :: r(:, :), v(:, :), y_old(:, :)
    real(wp) :: rot(3, 3), t, t_old, s_eval(21), s_diag(21), t0, checksum
    integer :: n, k, rep, batch_eval, batch_diag
    t_eval = 0.0_wp   ! defined also when an error returns early
    t_diag = 0.0_wp
    call build_initial_chain(sc%chain, r, rot, error)
    if (allocated(error)) return
    n = size(r, 2)
    call dyn%init(sc, n, error)
    if (.not. allocated(error)) call make_stepper(sc%integrator, integ, error)
    if (allocated(error)) return
    t = 0.0_wp
    call integ%advance(dyn, t, r, 5.0_wp, error)
    if (allocated(error)) return
    y_old = r
    t_old = t
    call integ%advance(dyn, t, r, t + integ%dt(), error)
    if (allocated(error)) return
    call diag%init(n, sc%chain%bond_length)
    call diag%start(t_old, y_old)
    allocate (v(3, n))
    batch_eval = 100
    batch_diag = 1000
    checksum = 0.0_wp
    do rep = 1, size(s_eval)
      t0 = wall_seconds()
      do k = 1, batch_eval
        call dyn%velocity(r, v, error)
        if (allocated(error)) return
        checksum = checksum + v(1, 1)
      end do
      s_eval(rep) = (wall_seconds() - t0)/batch_eval
      t0 = wall_seconds()
      do k = 1, batch_diag
        call diag%on_step(t_old, y_old, t, r)
      end do
      s_diag(rep) = (wall_seconds() - t0)/batch_diag
    end do
    t_eval = median(s_eval)
    t_diag = median(s_diag)
    if (.not. abs(checksum) <= huge(1.0_wp) .or. diag%strand_passages < 0_i8) t_eval = -1.0_wp
  end subroutine time_step_costs

  !> Wall time of integrating the scene from its initial chain to t_end, with or without the
  !> diagnostics monitor.
  subroutine time_run(sc, t_end, with_monitor, wall, error)
    type(scene_t), intent(in) :: sc
    real(wp), intent(in) :: t_end
    logical, intent(in) :: with_monitor
    real(wp), intent(out) :: wall
    type(error_t), allocatable, intent(out) :: error
    type(dynamics_t) :: dyn
    class(stepper_t), allocatable :: integ
    type(run_diagnostics_t) :: diag
    real(wp), allocatable :: r(:, :)
    real(wp) :: rot(3, 3), t, t0
    integer :: n
    call build_initial_chain(sc%chain, r, rot, error)
    if (allocated(error)) return
    n = size(r, 2)
    call dyn%init(sc, n, error)
    if (.not. allocated(error)) call make_stepper(sc%integrator, integ, error)
    if (allocated(error)) return
    t = 0.0_wp
    t0 = wall_seconds()
    if (with_monitor) then
      call diag%init(n, sc%chain%bond_length)
      call diag%start(t, r)
      call integ%advance(dyn, t, r, t_end, error, diag)
    else
      call integ%advance(dyn, t, r, t_end, error)
    end if
    wall = wall_seconds() - t0
  end subroutine time_run

end program knotflow_bench_diagnostics
