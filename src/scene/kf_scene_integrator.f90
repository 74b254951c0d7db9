!> The &integrator group: time stepping. Owns the parameter type with its defaults, the reading
!> of the group, its part of the item catalogue, its validation and the names of the steppers
!> (kf_stepper_factory builds from them).
module kf_scene_integrator
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str, to_str_exact
  use kf_error, only: error_t
  use kf_scene_item, only: scene_item_t, add_s, add_i, add_r, name_len
  use kf_scene_check, only: refuse, name_list, quoted, check_finite
  implicit none
  private

  character(len=*), parameter, public :: method_dopri45 = 'dopri45', method_rk4 = 'rk4', &
                                         method_ros34pw2 = 'ros34pw2', method_ros34pw3 = 'ros34pw3'
  !> The valid values of &integrator method.
  character(len=*), parameter, public :: method_names(4) = [character(len=8) :: method_dopri45, method_rk4, &
                                                            method_ros34pw2, method_ros34pw3]

  ! The allowed values, in the words of the refusals and of the scene reference.
  character(len=*), parameter :: t_end_allowed = 'a number > 0'
  character(len=*), parameter :: tolerance_allowed = 'a number in (0, 1)'
  character(len=*), parameter :: dt_min_allowed = 'a number > 0'
  character(len=*), parameter :: max_steps_allowed = 'an integer >= 1'
  !> The largest &integrator jacobian_steps.
  integer, parameter, public :: jacobian_steps_max = 1000

  !> &integrator: time stepping.
  type, public :: integrator_params_t
    character(len=name_len) :: method = method_dopri45 !< dopri45 | ros34pw2 | ros34pw3 (adaptive) | rk4 (fixed step)
    real(wp) :: t_end = 1000.0_wp
    real(wp) :: tolerance = 1.0e-4_wp               !< error per step on positions, units of d
    real(wp) :: dt_initial = 1.0e-3_wp
    real(wp) :: dt_min = 1.0e-9_wp                  !< below this the case fails (step underflow)
    real(wp) :: dt_max = 0.5_wp
    integer(i8) :: max_steps = 100000000_i8
    integer :: jacobian_steps = 4                   !< ros34pw2/3: Jacobians a kept mobility serves
  end type integrator_params_t

  public :: read_integrator_group, integrator_items, check_integrator

contains

  !> Read the namelist text of &integrator into `p` (the values `p` holds are the defaults).
  subroutine read_integrator_group(p, text, ios, msg)
    type(integrator_params_t), intent(inout) :: p
    character(len=*), intent(in) :: text
    integer, intent(out) :: ios
    character(len=*), intent(inout) :: msg
    character(len=name_len) :: method
    real(wp) :: t_end, tolerance, dt_initial, dt_min, dt_max
    integer(i8) :: max_steps
    integer :: jacobian_steps
    namelist /integrator/ method, t_end, tolerance, dt_initial, dt_min, dt_max, max_steps, jacobian_steps
    method = p%method; t_end = p%t_end; tolerance = p%tolerance; dt_initial = p%dt_initial
    dt_min = p%dt_min; dt_max = p%dt_max; max_steps = p%max_steps; jacobian_steps = p%jacobian_steps
    read (text, nml=integrator, iostat=ios, iomsg=msg)
    p%method = method; p%t_end = t_end; p%tolerance = tolerance; p%dt_initial = dt_initial
    p%dt_min = dt_min; p%dt_max = dt_max; p%max_steps = max_steps; p%jacobian_steps = jacobian_steps
  end subroutine read_integrator_group

  !> The variables of &integrator, in namelist order, appended to `items`.
  subroutine integrator_items(p, items)
    type(integrator_params_t), intent(in) :: p
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    call add_s(items, 'integrator.method', p%method, 'one of '//name_list(method_names), &
      'dopri45: adaptive Dormand-Prince 5(4); rk4: classical Runge-Kutta with the fixed step dt_initial; '// &
      'ros34pw2: adaptive linearly implicit Rosenbrock-W 3(2) (Rang and Angermann 2005), its Jacobian mobility '// &
      'times the force Jacobian plus the flow gradient; ros34pw3: the same with the 4-stage ROS34PW3 of the same '// &
      'paper (order 4 with the exact Jacobian, 3 with this one; its error estimate is of order 2, so at one '// &
      'tolerance it is more accurate than ros34pw2 with about 2.3 times the steps: docs/accuracy.md)')
    call add_r(items, 'integrator.t_end', p%t_end, t_end_allowed, 'end time, units of 1/shear rate')
    call add_r(items, 'integrator.tolerance', p%tolerance, tolerance_allowed, &
      'dopri45, ros34pw2, ros34pw3: error per step on the bead positions, units of d')
    call add_r(items, 'integrator.dt_initial', p%dt_initial, 'a number in [dt_min, dt_max]', &
      'first step (rk4: every step)')
    call add_r(items, 'integrator.dt_min', p%dt_min, dt_min_allowed, &
      'smallest step: a step below it fails the case (step size underflow)')
    call add_r(items, 'integrator.dt_max', p%dt_max, 'a number > dt_min', 'largest step')
    call add_i(items, 'integrator.max_steps', p%max_steps, max_steps_allowed, 'the most steps a case may take')
    call add_i(items, 'integrator.jacobian_steps', int(p%jacobian_steps, i8), jacobian_steps_allowed(), &
      'ros34pw2, ros34pw3 with update = ''adaptive'' or ''iterative'': steps whose Jacobians share one mobility (the '// &
      'force Jacobian is new at every step; 1: a new mobility too); ignored otherwise')
  end subroutine integrator_items

  !> Check &integrator (`file`: the scene file named in the messages, '' from code).
  subroutine check_integrator(p, file, error)
    type(integrator_params_t), intent(in) :: p
    character(len=*), intent(in) :: file
    type(error_t), allocatable, intent(out) :: error
    type(scene_item_t), allocatable :: items(:)
    allocate (items(0))
    call integrator_items(p, items)
    call check_finite(items, file, error)
    if (allocated(error)) return
    if (.not. any(method_names == p%method)) then
      call refuse(error, file, 'integrator', 'method', quoted(p%method), 'one of '//name_list(method_names)); return
    end if
    if (.not. (p%t_end > 0.0_wp .and. p%t_end < 1.0e12_wp)) then
      call refuse(error, file, 'integrator', 't_end', to_str_exact(p%t_end), t_end_allowed); return
    end if
    if (.not. (p%tolerance > 0.0_wp .and. p%tolerance < 1.0_wp)) then
      call refuse(error, file, 'integrator', 'tolerance', to_str_exact(p%tolerance), tolerance_allowed); return
    end if
    if (.not. (p%dt_min > 0.0_wp)) then
      call refuse(error, file, 'integrator', 'dt_min', to_str_exact(p%dt_min), dt_min_allowed); return
    end if
    if (.not. (p%dt_max > p%dt_min)) then
      call refuse(error, file, 'integrator', 'dt_max', to_str_exact(p%dt_max), 'a number > dt_min = '// &
        to_str_exact(p%dt_min)); return
    end if
    if (.not. (p%dt_initial >= p%dt_min .and. p%dt_initial <= p%dt_max)) then
      call refuse(error, file, 'integrator', 'dt_initial', to_str_exact(p%dt_initial), &
        'a number in [dt_min, dt_max] = ['//to_str_exact(p%dt_min)//', '//to_str_exact(p%dt_max)//']'); return
    end if
    if (p%max_steps < 1) then
      call refuse(error, file, 'integrator', 'max_steps', to_str(p%max_steps), max_steps_allowed); return
    end if
    if (p%jacobian_steps < 1 .or. p%jacobian_steps > jacobian_steps_max) then
      call refuse(error, file, 'integrator', 'jacobian_steps', to_str(p%jacobian_steps), jacobian_steps_allowed()); return
    end if
  end subroutine check_integrator

  !> The allowed values of jacobian_steps, in the words of the refusals and the reference.
  function jacobian_steps_allowed() result(text)
    character(len=:), allocatable :: text
    text = 'an integer in [1, '//to_str(jacobian_steps_max)//']'
  end function jacobian_steps_allowed

end module kf_scene_integrator
