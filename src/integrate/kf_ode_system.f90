!> An autonomous or time-dependent ODE system dy/dt = f(t, y) for the integrators. The state is
!> a 2-D array y(3, N): bead positions, one column per bead (the error norm of the adaptive
!> integrator is the largest Euclidean norm of a column).
!>
!> The steppers tell the system where each step begins and whether it was accepted or
!> rejected, so that a system can reuse work across stages and steps; the defaults do nothing.
module kf_ode_system
  use kf_kinds, only: wp
  use kf_error, only: error_t
  implicit none
  private

  type, abstract, public :: ode_system_t
  contains
    procedure(derivative_i), deferred :: derivative
    procedure :: step_begin
    procedure :: step_accepted
    procedure :: step_rejected
  end type ode_system_t

  abstract interface
    !> dydt = f(t, y); an error stops the integration.
    subroutine derivative_i(this, t, y, dydt, error)
      import :: ode_system_t, wp, error_t
      class(ode_system_t), intent(inout) :: this
      real(wp), intent(in) :: t
      real(wp), intent(in) :: y(:, :)
      real(wp), intent(out) :: dydt(:, :)
      type(error_t), allocatable, intent(out) :: error
    end subroutine derivative_i
  end interface

contains

  !> A trial step of size h starts from (t, y).
  subroutine step_begin(this, t, y, h)
    class(ode_system_t), intent(inout) :: this
    real(wp), intent(in) :: t, y(:, :), h
  end subroutine step_begin

  !> The step ending at (t, y) was accepted.
  subroutine step_accepted(this, t, y)
    class(ode_system_t), intent(inout) :: this
    real(wp), intent(in) :: t, y(:, :)
  end subroutine step_accepted

  !> The last trial step was rejected.
  subroutine step_rejected(this)
    class(ode_system_t), intent(inout) :: this
  end subroutine step_rejected

end module kf_ode_system
