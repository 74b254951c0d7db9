!> Builds the time stepper named by &integrator method, validating its parameters. The only
!> place that knows the names of the steppers: `stepper_names` lists them for others (e.g.
!> the scene validation).
module kf_stepper_factory
  use kf_kinds, only: wp
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_scene, only: integrator_params_t
  use kf_stepper, only: stepper_t
  use kf_stepper_rk4, only: rk4_stepper_t
  use kf_stepper_dopri45, only: dopri45_stepper_t
  implicit none
  private

  public :: make_stepper, stepper_name_list

  !> The valid values of &integrator method.
  character(len=*), parameter, public :: stepper_names(2) = [character(len=7) :: 'dopri45', 'rk4']

contains

  !> The valid names as one string: 'dopri45, rk4'.
  function stepper_name_list() result(list)
    character(len=:), allocatable :: list
    integer :: k
    list = trim(stepper_names(1))
    do k = 2, size(stepper_names)
      list = list//', '//trim(stepper_names(k))
    end do
  end function stepper_name_list

  !> A new stepper for the &integrator parameters (statistics zeroed). Errors name the
  !> parameter, its value and what is allowed.
  subroutine make_stepper(params, stepper, error)
    type(integrator_params_t), intent(in) :: params
    class(stepper_t), allocatable, intent(out) :: stepper
    type(error_t), allocatable, intent(out) :: error
    type(rk4_stepper_t), allocatable :: rk4
    type(dopri45_stepper_t), allocatable :: dopri45
    call check_params(params, error)
    if (allocated(error)) return
    select case (trim(params%method))
    case ('dopri45')
      allocate (dopri45)
      call dopri45%init(params%tolerance, params%dt_initial, params%dt_min, params%dt_max, params%max_steps)
      call move_alloc(dopri45, stepper)
    case ('rk4')
      allocate (rk4)
      call rk4%init(params%dt_initial, params%max_steps)
      call move_alloc(rk4, stepper)
    end select
  end subroutine make_stepper

  subroutine check_params(params, error)
    type(integrator_params_t), intent(in) :: params
    type(error_t), allocatable, intent(out) :: error
    if (.not. any(stepper_names == params%method)) then
      call fatal_error(error, "integrator: method = '"//trim(params%method)// &
        "' is unknown (allowed: "//stepper_name_list()//')')
      return
    end if
    if (.not. params%tolerance > 0.0_wp) then
      call fatal_error(error, 'integrator: tolerance = '//to_str(params%tolerance, '(es10.3)')//' (must be > 0)')
      return
    end if
    if (.not. params%dt_initial > 0.0_wp) then
      call fatal_error(error, 'integrator: dt_initial = '//to_str(params%dt_initial, '(es10.3)')//' (must be > 0)')
      return
    end if
    if (.not. (params%dt_min > 0.0_wp .and. params%dt_min <= params%dt_max)) then
      call fatal_error(error, 'integrator: dt_min = '//to_str(params%dt_min, '(es10.3)')//' (must be > 0 and <= dt_max)')
      return
    end if
    if (params%max_steps < 1) then
      call fatal_error(error, 'integrator: max_steps = '//to_str(params%max_steps)//' (must be >= 1)')
      return
    end if
  end subroutine check_params

end module kf_stepper_factory
