!> Step-size control of the adaptive steppers: the PI controller of Gustafsson (Hairer and
!> Wanner, Solving ODEs II, IV.2). After an accepted step with scaled error err (error norm
!> over tolerance, accepted when err <= 1)
!>   h_new = h * clip(safety * err^(-alpha) * err_prev^beta, fac_min, fac_max),
!> with err_prev the scaled error of the previous accepted step (kept >= 1e-4); after a
!> rejection the step only shrinks: h_new = h * min(1, max(fac_min, safety * err^(-alpha))).
!> A step clipped onto the end of an interval says little about larger steps: after it the
!> proposal made before the clip is kept unless the controller asks for more (or less).
!> Every new step size is capped at dt_max; one below dt_min is an underflow (the run fails).
!> Near the stability limit set by stiff springs this keeps the step size from oscillating
!> and the rejections few.
module kf_step_controller
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  implicit none
  private

  !> PI step-size controller: settings and the memory of the last accepted error.
  type, public :: step_controller_t
    private
    real(wp) :: dt_min = 1.0e-9_wp
    real(wp) :: dt_max = 0.5_wp
    real(wp) :: safety = 0.9_wp
    real(wp) :: fac_min = 0.2_wp
    real(wp) :: fac_max = 5.0_wp
    real(wp) :: alpha = 0.7_wp/5.0_wp     !< PI exponents 0.7/(q + 1), 0.4/(q + 1) for an
    real(wp) :: beta = 0.4_wp/5.0_wp      !< error estimate ~ h^(q+1) (dopri45: q = 4)
    real(wp) :: err_prev = 1.0e-4_wp      !< scaled error of the last accepted step
  contains
    procedure :: init => controller_init
    procedure :: proposal
    procedure :: after_accept
    procedure :: after_rejection
    procedure :: after_failure
    procedure :: check_underflow
    procedure :: memory
    procedure :: set_memory
    procedure :: max_step
  end type step_controller_t

  !> Smallest remembered error (a near-zero error must not blow up the next step).
  real(wp), parameter :: err_floor = 1.0e-4_wp

contains

  !> Set the step-size limits and forget the error history; `order` (default 4, dopri45) is the
  !> order q of the lower solution of the embedded pair: the error estimate is ~ h^(q+1) and the
  !> PI exponents are 0.7/(q + 1) and 0.4/(q + 1).
  subroutine controller_init(this, dt_min, dt_max, order)
    class(step_controller_t), intent(out) :: this
    real(wp), intent(in) :: dt_min, dt_max
    integer, intent(in), optional :: order
    integer :: q
    q = 4
    if (present(order)) q = order
    this%dt_min = dt_min
    this%dt_max = dt_max
    this%alpha = 0.7_wp/real(q + 1, wp)
    this%beta = 0.4_wp/real(q + 1, wp)
  end subroutine controller_init

  !> The step size to try next given the current proposal dt (capped at dt_max).
  pure real(wp) function proposal(this, dt)
    class(step_controller_t), intent(in) :: this
    real(wp), intent(in) :: dt
    proposal = min(dt, this%dt_max)
  end function proposal

  !> New step size dt after an accepted step of size h with scaled error err (remembered for
  !> the next step); dt_proposed is the size proposed before the step was clipped onto the end
  !> of the interval (clipped true).
  subroutine after_accept(this, err, h, dt_proposed, clipped, dt)
    class(step_controller_t), intent(inout) :: this
    real(wp), intent(in) :: err, h, dt_proposed
    logical, intent(in) :: clipped
    real(wp), intent(out) :: dt
    real(wp) :: fac
    fac = this%safety*max(err, 1.0e-10_wp)**(-this%alpha)*this%err_prev**this%beta
    fac = min(this%fac_max, max(this%fac_min, fac))
    this%err_prev = max(err, err_floor)
    if (clipped) then
      if (fac >= 1.0_wp) then
        dt = max(dt_proposed, h*fac)
      else
        dt = min(dt_proposed, h*fac)
      end if
    else
      dt = h*fac
    end if
    dt = min(dt, this%dt_max)
  end subroutine after_accept

  !> New step size after a step of size h rejected with scaled error err > 1 (only shrinks).
  pure real(wp) function after_rejection(this, err, h) result(dt)
    class(step_controller_t), intent(in) :: this
    real(wp), intent(in) :: err, h
    real(wp) :: fac
    fac = max(this%fac_min, this%safety*err**(-this%alpha))
    dt = h*min(1.0_wp, fac)
  end function after_rejection

  !> New step size after a trial of size h that produced non-finite values: shrink hard.
  pure real(wp) function after_failure(this, h) result(dt)
    class(step_controller_t), intent(in) :: this
    real(wp), intent(in) :: h
    dt = h*this%fac_min
  end function after_failure

  !> An error when the step size dt (proposed at time t) is below dt_min.
  subroutine check_underflow(this, dt, t, error)
    class(step_controller_t), intent(in) :: this
    real(wp), intent(in) :: dt, t
    type(error_t), allocatable, intent(out) :: error
    if (dt < this%dt_min) then
      call fatal_error(error, 'integrator: step size underflow (dt = '//to_str(dt, '(es10.3)')// &
        ' < dt_min at t = '//to_str(t, '(es14.6)')//')')
    end if
  end subroutine check_underflow

  !> The controller's memory: the scaled error of the last accepted step.
  pure real(wp) function memory(this)
    class(step_controller_t), intent(in) :: this
    memory = this%err_prev
  end function memory

  !> Restore the memory (from `memory`, e.g. out of a checkpoint); it must be finite and >= the
  !> floor the controller keeps it above.
  subroutine set_memory(this, err_prev, error)
    class(step_controller_t), intent(inout) :: this
    real(wp), intent(in) :: err_prev
    type(error_t), allocatable, intent(out) :: error
    logical :: valid
    valid = ieee_is_finite(err_prev)      ! no comparison with a NaN: quiet with FPE traps on
    if (valid) valid = err_prev >= err_floor
    if (.not. valid) then
      call fatal_error(error, 'step controller: err_prev = '//to_str(err_prev, '(es10.3)')// &
        ' (must be finite and >= '//to_str(err_floor, '(es8.1)')//')')
      return
    end if
    this%err_prev = err_prev
  end subroutine set_memory

  !> The largest step size allowed (dt_max).
  pure real(wp) function max_step(this)
    class(step_controller_t), intent(in) :: this
    max_step = this%dt_max
  end function max_step

end module kf_step_controller
