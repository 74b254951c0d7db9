!> Classic fixed-step fourth-order Runge-Kutta (kf_stepper): every step has the size given at
!> `init` except the last of each `advance`, clipped onto its target. Its state is the common one
!> (no method part).
module kf_stepper_rk4
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_ode_system, only: ode_system_t
  use kf_step_monitor, only: step_monitor_t
  use kf_stepper, only: stepper_t, check_target, all_finite, nonfinite_error
  implicit none
  private

  !> Fixed-step RK4 and its work space.
  type, extends(stepper_t), public :: rk4_stepper_t
    private
    real(wp), allocatable :: k1(:, :), k2(:, :), k3(:, :), k4(:, :), ytmp(:, :), ynew(:, :)
  contains
    procedure :: init => rk4_init
    procedure :: advance => rk4_advance
    procedure :: get_method_state => rk4_get_method_state
    procedure :: set_method_state => rk4_set_method_state
  end type rk4_stepper_t

contains

  !> Fixed step dt (> 0, validated by the factory), at most max_steps accepted steps.
  subroutine rk4_init(this, dt, max_steps)
    class(rk4_stepper_t), intent(out) :: this
    real(wp), intent(in) :: dt
    integer(i8), intent(in) :: max_steps
    call this%reset_stepper(dt, max_steps)
  end subroutine rk4_init

  !> Integrate exactly to t_target with the fixed step (contract in kf_stepper).
  subroutine rk4_advance(this, sys, t, y, t_target, error, monitor)
    class(rk4_stepper_t), intent(inout) :: this
    class(ode_system_t), intent(inout) :: sys
    real(wp), intent(inout) :: t
    real(wp), intent(inout) :: y(:, :)
    real(wp), intent(in) :: t_target
    type(error_t), allocatable, intent(out) :: error
    class(step_monitor_t), intent(inout), optional :: monitor
    real(wp) :: h
    logical :: last
    call check_target(t, t_target, error)
    if (allocated(error)) return
    call ensure_work(this, y)
    do while (t < t_target)
      call this%check_max_steps(t, error)
      if (allocated(error)) return
      h = this%dt()
      last = t + h*(1.0_wp + 1.0e-12_wp) >= t_target
      if (last) h = t_target - t
      call sys%step_begin(t, y, h)
      call sys%derivative(t, y, this%k1, error)
      if (allocated(error)) return
      this%ytmp = y + 0.5_wp*h*this%k1
      call sys%derivative(t + 0.5_wp*h, this%ytmp, this%k2, error)
      if (allocated(error)) return
      this%ytmp = y + 0.5_wp*h*this%k2
      call sys%derivative(t + 0.5_wp*h, this%ytmp, this%k3, error)
      if (allocated(error)) return
      this%ytmp = y + h*this%k3
      call sys%derivative(t + h, this%ytmp, this%k4, error)
      if (allocated(error)) return
      call this%add_evaluations(4)
      this%ynew = y + (h/6.0_wp)*(this%k1 + 2.0_wp*(this%k2 + this%k3) + this%k4)
      if (.not. all_finite(this%ynew)) then
        call nonfinite_error(error, t)
        return
      end if
      call this%accept_step(sys, t, y, this%ynew, h, last, t_target, monitor)
    end do
  end subroutine rk4_advance

  subroutine ensure_work(this, y)
    type(rk4_stepper_t), intent(inout) :: this
    real(wp), intent(in) :: y(:, :)
    if (allocated(this%k1)) then
      if (all(shape(this%k1) == shape(y))) return
      deallocate (this%k1, this%k2, this%k3, this%k4, this%ytmp, this%ynew)
    end if
    allocate (this%k1, this%k2, this%k3, this%k4, this%ytmp, this%ynew, mold=y)
  end subroutine ensure_work

  !> RK4 keeps nothing between steps: its method part of the state is empty.
  subroutine rk4_get_method_state(this, reals, ints)
    class(rk4_stepper_t), intent(in) :: this
    real(wp), allocatable, intent(out) :: reals(:)
    integer(i8), allocatable, intent(out) :: ints(:)
    allocate (reals(0), ints(0))
    associate (unused_this => this)
    end associate
  end subroutine rk4_get_method_state

  subroutine rk4_set_method_state(this, reals, ints, error)
    class(rk4_stepper_t), intent(inout) :: this
    real(wp), intent(in) :: reals(:)
    integer(i8), intent(in) :: ints(:)
    type(error_t), allocatable, intent(out) :: error
    if (size(reals) /= 0 .or. size(ints) /= 0) then
      call fatal_error(error, 'rk4 stepper state: '//to_str(size(reals))//' reals and '//to_str(size(ints))// &
        ' integers after the common entries (none expected: a state of another method?)')
    end if
    associate (unused_this => this)
    end associate
  end subroutine rk4_set_method_state

end module kf_stepper_rk4
