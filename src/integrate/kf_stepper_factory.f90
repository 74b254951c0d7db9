!> Builds the time stepper named by &integrator method. The names of the steppers and the
!> validation of their parameters are those of the &integrator group (kf_scene_integrator, the
!> one source the scene validation uses too); `stepper_names` passes the names on.
module kf_stepper_factory
  use kf_error, only: error_t
  use kf_scene_integrator, only: integrator_params_t, stepper_names => method_names, method_dopri45, &
                                 method_rk4, method_ros34pw2, method_ros34pw3, check_integrator
  use kf_stepper, only: stepper_t
  use kf_stepper_rk4, only: rk4_stepper_t
  use kf_stepper_dopri45, only: dopri45_stepper_t
  use kf_stepper_rosenbrock, only: rosenbrock_stepper_t, ros34pw2_tableau, ros34pw3_tableau
  implicit none
  private

  public :: make_stepper, stepper_names

contains

  !> A new stepper for the &integrator parameters (statistics zeroed). Errors name the
  !> parameter, its value and what is allowed.
  subroutine make_stepper(params, stepper, error)
    type(integrator_params_t), intent(in) :: params
    class(stepper_t), allocatable, intent(out) :: stepper
    type(error_t), allocatable, intent(out) :: error
    type(rk4_stepper_t), allocatable :: rk4
    type(dopri45_stepper_t), allocatable :: dopri45
    type(rosenbrock_stepper_t), allocatable :: ros
    call check_integrator(params, '', error)
    if (allocated(error)) return
    select case (trim(params%method))
    case (method_dopri45)
      allocate (dopri45)
      call dopri45%init(params%tolerance, params%dt_initial, params%dt_min, params%dt_max, params%max_steps)
      call move_alloc(dopri45, stepper)
    case (method_ros34pw2)
      allocate (ros)
      call ros%init(ros34pw2_tableau(), params%tolerance, params%dt_initial, params%dt_min, params%dt_max, &
                    params%max_steps)
      call move_alloc(ros, stepper)
    case (method_ros34pw3)
      allocate (ros)
      call ros%init(ros34pw3_tableau(), params%tolerance, params%dt_initial, params%dt_min, params%dt_max, &
                    params%max_steps)
      call move_alloc(ros, stepper)
    case (method_rk4)
      allocate (rk4)
      call rk4%init(params%dt_initial, params%max_steps)
      call move_alloc(rk4, stepper)
    end select
  end subroutine make_stepper

end module kf_stepper_factory
