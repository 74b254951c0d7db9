!> An autonomous or time-dependent ODE system dy/dt = f(t, y) for the integrators. The state is
!> a 2-D array y(3, N): bead positions, one column per bead (the error norm of the adaptive
!> integrator is the largest Euclidean norm of a column).
module kf_ode_system
  use kf_kinds, only: wp
  use kf_error, only: error_t
  implicit none
  private

  type, abstract, public :: ode_system_t
  contains
    procedure(derivative_i), deferred :: derivative
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

end module kf_ode_system
