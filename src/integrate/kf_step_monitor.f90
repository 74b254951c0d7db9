!> A hook into the time steppers: `stepper_t%advance` (kf_stepper) calls `on_step` of an optional
!> monitor after every accepted step, with the configurations before and after the step.
!> Rejected trial steps are never shown. A monitor only observes: it cannot change the step.
module kf_step_monitor
  use kf_kinds, only: wp
  implicit none
  private

  type, abstract, public :: step_monitor_t
  contains
    procedure(on_step_i), deferred :: on_step
  end type step_monitor_t

  abstract interface
    !> One accepted step from (t_old, y_old) to (t_new, y_new); y(3, N) as in kf_ode_system.
    subroutine on_step_i(this, t_old, y_old, t_new, y_new)
      import :: step_monitor_t, wp
      class(step_monitor_t), intent(inout) :: this
      real(wp), intent(in) :: t_old
      real(wp), intent(in) :: y_old(:, :)
      real(wp), intent(in) :: t_new
      real(wp), intent(in) :: y_new(:, :)
    end subroutine on_step_i
  end interface

end module kf_step_monitor
