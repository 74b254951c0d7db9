!> An autonomous or time-dependent ODE system dy/dt = f(t, y) for the time steppers. The state is
!> a 2-D array y(3, N): bead positions, one column per bead (the error norm of the adaptive
!> stepper is the largest Euclidean norm of a column).
!>
!> Besides the derivative, a system may override three hooks through which every stepper
!> (kf_stepper) tells it where it is, so that it can reuse work between stages and steps:
!>  - `step_begin(t, y, h)`: a trial step of size h from (t, y) begins; called before the stages
!>    of the step (for dopri45 after the first-same-as-last stage at (t, y) is known);
!>  - `step_accepted(t, y)`: the trial step was accepted; (t, y) is the new time and state;
!>  - `step_rejected()`: the trial step was rejected (dopri45: error too large or non-finite);
!>    the next trial starts again from the same (t, y).
!> A step abandoned with an error (of the system, non-finite values in rk4) gets neither
!> `step_accepted` nor `step_rejected`. The defaults do nothing.
!>
!> The linearly implicit steppers (kf_stepper_rosenbrock) also ask for `jacobian(t, y, jac,
!> evaluations, error)`: an approximation of df/dy at (t, y) as a dense n x n matrix, n =
!> size(y), the entries of y taken column by column (y(a, i) is entry 3(i - 1) + a for 3-row
!> states). Any approximation keeps a W-method's order; how well it captures the stiff part
!> sets its stability. The default is central differences of `derivative` (2n evaluations,
!> reported in `evaluations`); a system that knows its stiff part better overrides it.
module kf_ode_system
  use kf_kinds, only: wp
  use kf_error, only: error_t
  implicit none
  private

  type, abstract, public :: ode_system_t
  contains
    procedure(derivative_i), deferred :: derivative
    !> A trial step of size h from (t, y) begins.
    procedure :: step_begin => ode_step_begin
    !> The trial step was accepted: (t, y) is the new time and state.
    procedure :: step_accepted => ode_step_accepted
    !> The trial step was rejected.
    procedure :: step_rejected => ode_step_rejected
    !> An approximation of df/dy at (t, y) (default: central differences of derivative).
    procedure :: jacobian => ode_jacobian
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

  ! The defaults do nothing: the associate blocks only reference the dummy arguments.

  subroutine ode_step_begin(this, t, y, h)
    class(ode_system_t), intent(inout) :: this
    real(wp), intent(in) :: t, y(:, :), h
    associate (unused_this => this, unused_t => t, unused_y => y, unused_h => h)
    end associate
  end subroutine ode_step_begin

  subroutine ode_step_accepted(this, t, y)
    class(ode_system_t), intent(inout) :: this
    real(wp), intent(in) :: t, y(:, :)
    associate (unused_this => this, unused_t => t, unused_y => y)
    end associate
  end subroutine ode_step_accepted

  subroutine ode_step_rejected(this)
    class(ode_system_t), intent(inout) :: this
    associate (unused_this => this)
    end associate
  end subroutine ode_step_rejected

  !> jac = df/dy at (t, y) by central differences of `derivative` (step
  !> cbrt(epsilon) max(1, |y_j|) per entry); evaluations: the 2n derivative calls it made.
  subroutine ode_jacobian(this, t, y, jac, evaluations, error)
    class(ode_system_t), intent(inout) :: this
    real(wp), intent(in) :: t
    real(wp), intent(in) :: y(:, :)
    real(wp), intent(out) :: jac(:, :)
    integer, intent(out) :: evaluations
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: yp(:, :), fp(:, :), fm(:, :)
    real(wp) :: eps, keep
    integer :: j, a, i
    allocate (yp, fp, fm, mold=y)
    yp = y
    evaluations = 0
    do j = 1, size(y)
      a = modulo(j - 1, size(y, 1)) + 1
      i = (j - 1)/size(y, 1) + 1
      keep = yp(a, i)
      eps = epsilon(1.0_wp)**(1.0_wp/3.0_wp)*max(1.0_wp, abs(keep))
      yp(a, i) = keep + eps
      call this%derivative(t, yp, fp, error)
      if (allocated(error)) return
      yp(a, i) = keep - eps
      call this%derivative(t, yp, fm, error)
      if (allocated(error)) return
      yp(a, i) = keep
      evaluations = evaluations + 2
      jac(:, j) = reshape(fp - fm, [size(y)])/(2.0_wp*eps)
    end do
  end subroutine ode_jacobian

end module kf_ode_system
