!> Dormand-Prince 5(4) (Dormand and Prince 1980), adaptive, first same as last (kf_stepper). The
!> error per step is the largest Euclidean norm over beads (columns of y) of the embedded error
!> estimate, compared with `tolerance`; the 5th-order solution is propagated. The step size is
!> chosen by the PI controller of kf_step_controller.
!>
!> Method part of the state (`get_state`, after the common entries):
!>   reals = [err_prev, t_fsal, k1(:), y_fsal(:)]   (k1 and y_fsal only when fsal_valid = 1)
!>   ints  = [fsal_valid, rows, cols]               (shape of k1 and y_fsal; 0, 0 when not valid)
!> where k1 = f(t_fsal, y_fsal) is the first stage of the next step (reused when `advance` is
!> called again with t = t_fsal and y = y_fsal) and err_prev the controller's memory.
module kf_stepper_dopri45
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_ode_system, only: ode_system_t
  use kf_step_monitor, only: step_monitor_t
  use kf_stepper, only: stepper_t, check_target, all_finite, nonfinite_error, error_norm
  use kf_step_controller, only: step_controller_t
  implicit none
  private

  ! Dormand-Prince 5(4) tableau.
  real(wp), parameter :: c2 = 1.0_wp/5, c3 = 3.0_wp/10, c4 = 4.0_wp/5, c5 = 8.0_wp/9
  real(wp), parameter :: a21 = 1.0_wp/5
  real(wp), parameter :: a31 = 3.0_wp/40, a32 = 9.0_wp/40
  real(wp), parameter :: a41 = 44.0_wp/45, a42 = -56.0_wp/15, a43 = 32.0_wp/9
  real(wp), parameter :: a51 = 19372.0_wp/6561, a52 = -25360.0_wp/2187, a53 = 64448.0_wp/6561, &
                         a54 = -212.0_wp/729
  real(wp), parameter :: a61 = 9017.0_wp/3168, a62 = -355.0_wp/33, a63 = 46732.0_wp/5247, &
                         a64 = 49.0_wp/176, a65 = -5103.0_wp/18656
  real(wp), parameter :: a71 = 35.0_wp/384, a73 = 500.0_wp/1113, a74 = 125.0_wp/192, &
                         a75 = -2187.0_wp/6784, a76 = 11.0_wp/84
  real(wp), parameter :: e1 = 71.0_wp/57600, e3 = -71.0_wp/16695, e4 = 71.0_wp/1920, &
                         e5 = -17253.0_wp/339200, e6 = 22.0_wp/525, e7 = -1.0_wp/40

  !> Trials in a row with non-finite values after which the step fails.

  !> Adaptive Dormand-Prince 5(4): tolerance, controller, FSAL stage and work space.
  type, extends(stepper_t), public :: dopri45_stepper_t
    private
    real(wp) :: tolerance = 1.0e-4_wp
    type(step_controller_t) :: controller
    real(wp) :: last_error = 0.0_wp          !< error norm of the last trial step (units of y)
    logical :: fsal_valid = .false.
    real(wp) :: t_fsal = 0.0_wp
    real(wp), allocatable :: y_fsal(:, :), k1(:, :), k2(:, :), k3(:, :), k4(:, :), &
                             k5(:, :), k6(:, :), k7(:, :), ytmp(:, :), ynew(:, :)
  contains
    procedure :: init => dopri45_init
    procedure :: advance => dopri45_advance
    procedure :: error_estimate
    procedure :: get_method_state => dopri45_get_method_state
    procedure :: set_method_state => dopri45_set_method_state
    procedure :: shift_clock => dopri45_shift_clock
  end type dopri45_stepper_t

contains

  !> Tolerance per step (units of y), initial step size (capped at dt_max), step-size limits
  !> and at most max_steps accepted steps; all validated by the factory.
  subroutine dopri45_init(this, tolerance, dt_initial, dt_min, dt_max, max_steps)
    class(dopri45_stepper_t), intent(out) :: this
    real(wp), intent(in) :: tolerance, dt_initial, dt_min, dt_max
    integer(i8), intent(in) :: max_steps
    this%tolerance = tolerance
    call this%controller%init(dt_min, dt_max)
    call this%reset_stepper(min(dt_initial, dt_max), max_steps)
  end subroutine dopri45_init

  !> The embedded error estimate of the last trial step: the largest Euclidean norm over the
  !> columns of y (units of y, not divided by the tolerance); 0 before the first trial.
  pure real(wp) function error_estimate(this)
    class(dopri45_stepper_t), intent(in) :: this
    error_estimate = this%last_error
  end function error_estimate

  subroutine ensure_work(this, y)
    type(dopri45_stepper_t), intent(inout) :: this
    real(wp), intent(in) :: y(:, :)
    if (allocated(this%k1)) then
      if (all(shape(this%k1) == shape(y))) return
      deallocate (this%y_fsal, this%k1, this%k2, this%k3, this%k4, this%k5, this%k6, this%k7, &
                  this%ytmp, this%ynew)
    end if
    allocate (this%y_fsal, this%k1, this%k2, this%k3, this%k4, this%k5, this%k6, this%k7, &
              this%ytmp, this%ynew, mold=y)
    this%fsal_valid = .false.
  end subroutine ensure_work

  !> Integrate exactly to t_target with adaptive steps (contract in kf_stepper).
  subroutine dopri45_advance(this, sys, t, y, t_target, error, monitor)
    class(dopri45_stepper_t), intent(inout) :: this
    class(ode_system_t), intent(inout) :: sys
    real(wp), intent(inout) :: t
    real(wp), intent(inout) :: y(:, :)
    real(wp), intent(in) :: t_target
    type(error_t), allocatable, intent(out) :: error
    class(step_monitor_t), intent(inout), optional :: monitor
    real(wp) :: h, err, dt_proposed
    integer :: n_bad
    logical :: last, finite, accepted

    call check_target(t, t_target, error)
    if (allocated(error)) return
    call ensure_work(this, y)
    ! FSAL: k1 is reusable if y and t are those it was evaluated at (the caller may change y).
    if (this%fsal_valid) then
      if (t /= this%t_fsal .or. any(y /= this%y_fsal)) this%fsal_valid = .false.
    end if
    n_bad = 0
    do while (t < t_target)
      call this%check_max_steps(t, error)
      if (allocated(error)) return
      if (.not. this%fsal_valid) then
        call sys%derivative(t, y, this%k1, error)
        if (allocated(error)) return
        call this%add_evaluations(1)
        if (.not. all_finite(this%k1)) then
          call nonfinite_error(error, t)
          return
        end if
        this%fsal_valid = .true.
        this%t_fsal = t
        this%y_fsal = y
      end if
      dt_proposed = this%controller%proposal(this%dt())
      h = dt_proposed
      last = t + h*(1.0_wp + 1.0e-12_wp) >= t_target
      if (last) h = t_target - t
      call sys%step_begin(t, y, h)

      this%ytmp = y + h*a21*this%k1
      call sys%derivative(t + c2*h, this%ytmp, this%k2, error)
      if (allocated(error)) return
      this%ytmp = y + h*(a31*this%k1 + a32*this%k2)
      call sys%derivative(t + c3*h, this%ytmp, this%k3, error)
      if (allocated(error)) return
      this%ytmp = y + h*(a41*this%k1 + a42*this%k2 + a43*this%k3)
      call sys%derivative(t + c4*h, this%ytmp, this%k4, error)
      if (allocated(error)) return
      this%ytmp = y + h*(a51*this%k1 + a52*this%k2 + a53*this%k3 + a54*this%k4)
      call sys%derivative(t + c5*h, this%ytmp, this%k5, error)
      if (allocated(error)) return
      this%ytmp = y + h*(a61*this%k1 + a62*this%k2 + a63*this%k3 + a64*this%k4 + a65*this%k5)
      call sys%derivative(t + h, this%ytmp, this%k6, error)
      if (allocated(error)) return
      this%ynew = y + h*(a71*this%k1 + a73*this%k3 + a74*this%k4 + a75*this%k5 + a76*this%k6)
      call sys%derivative(t + h, this%ynew, this%k7, error)
      if (allocated(error)) return
      call this%add_evaluations(6)

      ! Error estimate (into ytmp): largest Euclidean norm over beads, relative to tolerance.
      this%ytmp = h*(e1*this%k1 + e3*this%k3 + e4*this%k4 + e5*this%k5 + e6*this%k6 + e7*this%k7)
      finite = all_finite(this%ytmp) .and. all_finite(this%ynew) .and. all_finite(this%k7)
      call error_norm(this%ytmp, this%tolerance, finite, err, this%last_error)
      call this%finish_trial(this%controller, sys, t, y, this%ynew, h, dt_proposed, last, t_target, err, finite, &
                             n_bad, accepted, error, monitor)
      if (allocated(error)) return
      if (accepted) then
        this%k1 = this%k7
        this%t_fsal = t
        this%y_fsal = y
      end if
    end do
  end subroutine dopri45_advance

  !> err_prev, and the FSAL stage with the (t, y) it belongs to (layout in the module comment).
  subroutine dopri45_get_method_state(this, reals, ints)
    class(dopri45_stepper_t), intent(in) :: this
    real(wp), allocatable, intent(out) :: reals(:)
    integer(i8), allocatable, intent(out) :: ints(:)
    if (this%fsal_valid) then
      reals = [this%controller%memory(), this%t_fsal, reshape(this%k1, [size(this%k1)]), &
               reshape(this%y_fsal, [size(this%y_fsal)])]
      ints = [1_i8, int(size(this%k1, 1), i8), int(size(this%k1, 2), i8)]
    else
      reals = [this%controller%memory(), this%t_fsal]
      ints = [0_i8, 0_i8, 0_i8]
    end if
  end subroutine dopri45_get_method_state

  subroutine dopri45_set_method_state(this, reals, ints, error)
    class(dopri45_stepper_t), intent(inout) :: this
    real(wp), intent(in) :: reals(:)
    integer(i8), intent(in) :: ints(:)
    type(error_t), allocatable, intent(out) :: error
    type(step_controller_t) :: controller
    integer(i8) :: n
    character(len=*), parameter :: what = 'dopri45 stepper state: '
    if (size(ints) /= 3) then
      call fatal_error(error, what//to_str(size(ints))//' integers after the common entries (3 expected)')
      return
    end if
    if (ints(1) /= 0 .and. ints(1) /= 1) then
      call fatal_error(error, what//'fsal_valid = '//to_str(ints(1))//' (must be 0 or 1)')
      return
    end if
    if (ints(1) == 1 .and. .not. (ints(2) >= 1 .and. ints(3) >= 1 .and. ints(2) <= huge(1)/max(1_i8, ints(3)))) then
      call fatal_error(error, what//'FSAL stage shape ('//to_str(ints(2))//', '//to_str(ints(3))//') is not valid')
      return
    end if
    n = 0
    if (ints(1) == 1) n = ints(2)*ints(3)
    if (size(reals, kind=i8) /= 2 + 2*n) then
      call fatal_error(error, what//to_str(size(reals))//' reals after the common entries ('// &
        to_str(2 + 2*n)//' expected for the FSAL stage shape ('//to_str(ints(2))//', '//to_str(ints(3))//'))')
      return
    end if
    if (.not. all(ieee_is_finite(reals))) then
      call fatal_error(error, what//'non-finite values')
      return
    end if
    controller = this%controller
    call controller%set_memory(reals(1), error)
    if (allocated(error)) then
      error%message = what//error%message
      return
    end if
    this%controller = controller
    this%t_fsal = reals(2)
    this%fsal_valid = ints(1) == 1
    if (this%fsal_valid) then
      call ensure_work(this, reshape(reals(3:2 + n), [int(ints(2)), int(ints(3))]))
      this%fsal_valid = .true.            ! ensure_work forgets it for a new shape
      this%k1 = reshape(reals(3:2 + n), [int(ints(2)), int(ints(3))])
      this%y_fsal = reshape(reals(3 + n:2 + 2*n), [int(ints(2)), int(ints(3))])
    end if
  end subroutine dopri45_set_method_state

  !> The FSAL stage's time moves with the clock (a state at t = t0 continued from t = t0 + delta).
  subroutine dopri45_shift_clock(this, delta)
    class(dopri45_stepper_t), intent(inout) :: this
    real(wp), intent(in) :: delta
    this%t_fsal = this%t_fsal + delta
  end subroutine dopri45_shift_clock

end module kf_stepper_dopri45
