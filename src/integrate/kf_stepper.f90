!> The time steppers for y(3, N) (kf_ode_system): an abstract type with one `advance` and the
!> bookkeeping every method shares. The concrete methods are kf_stepper_rk4,
!> kf_stepper_dopri45 and kf_stepper_rosenbrock (ros34pw2, ros34pw3); kf_stepper_factory builds
!> one from the &integrator parameters and alone knows their names.
!>
!> Contract of `advance(sys, t, y, t_target, error, monitor)`: integrate y from t exactly to
!> t_target (t is updated); the last step is clipped to hit t_target, and the step size proposed
!> before the clip is kept for the next call. On failure (non-finite values, step size
!> underflow, max_steps, an error of the system) y and t are left at the last accepted state.
!> An optional monitor (kf_step_monitor) sees every accepted step; the system's hooks
!> (`step_begin`, `step_accepted`, `step_rejected`) are called as kf_ode_system describes.
!>
!> The statistics (accepted and rejected steps, derivative evaluations, smallest and largest
!> step used) and the current step size are read with accessor functions. The whole state of a
!> stepper (step size, statistics and whatever its method keeps between calls) is exported and
!> imported as two plain arrays with `get_state` / `set_state`, so a run written to a checkpoint
!> and resumed continues exactly as if it had not been interrupted (`shift_clock` moves the times
!> a method keeps when the continuation's clock starts at another time). Layout:
!>   reals = [dt, dt_min_used, dt_max_used, <method reals>]
!>   ints  = [state_version, steps, rejected, evaluations, <method ints>]
module kf_stepper
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_ode_system, only: ode_system_t
  use kf_step_monitor, only: step_monitor_t
  use kf_step_controller, only: step_controller_t
  implicit none
  private

  public :: check_target, all_finite, nonfinite_error, error_norm

  !> Non-finite trial steps in a row after which an adaptive method gives up.
  integer, parameter, public :: max_bad_trials = 10

  !> Version of the layout of `get_state` (first entry of ints).
  integer(i8), parameter, public :: stepper_state_version = 1
  !> Number of leading entries of the state arrays common to every method.
  integer, parameter, public :: n_common_reals = 3, n_common_ints = 4

  !> A time stepper: the current step size, statistics and limits. The components are private:
  !> read them with the accessors; the procedures under "for the methods" are meant for the
  !> concrete steppers only.
  type, abstract, public :: stepper_t
    private
    real(wp) :: dt_ = 1.0e-3_wp               !< current (proposed) step size
    integer(i8) :: max_steps_ = huge(1_i8)
    integer(i8) :: steps_ = 0                 !< accepted steps
    integer(i8) :: rejected_ = 0              !< rejected trial steps
    integer(i8) :: evaluations_ = 0           !< derivative evaluations
    real(wp) :: dt_min_used_ = huge(1.0_wp)
    real(wp) :: dt_max_used_ = 0.0_wp
  contains
    !> advance(sys, t, y, t_target, error[, monitor]): integrate exactly to t_target.
    procedure(advance_i), deferred :: advance
    !> The method's own state (after the common entries of get_state / set_state).
    procedure(get_method_state_i), deferred :: get_method_state
    procedure(set_method_state_i), deferred :: set_method_state
    ! accessors
    procedure, non_overridable :: dt => stepper_dt
    procedure, non_overridable :: steps => stepper_steps
    procedure, non_overridable :: rejected => stepper_rejected
    procedure, non_overridable :: evaluations => stepper_evaluations
    procedure, non_overridable :: dt_min_used => stepper_dt_min_used
    procedure, non_overridable :: dt_max_used => stepper_dt_max_used
    procedure, non_overridable :: max_steps => stepper_max_steps
    ! checkpoints
    procedure, non_overridable :: get_state
    procedure, non_overridable :: set_state
    procedure, non_overridable :: set_basic_state
    !> shift_clock(delta): the times the method keeps move by delta (a state continued on a
    !> clock that starts elsewhere); nothing for a method that keeps none.
    procedure :: shift_clock
    ! for the methods
    procedure, non_overridable :: reset_stepper
    procedure, non_overridable :: set_dt
    procedure, non_overridable :: add_evaluations
    procedure, non_overridable :: check_max_steps
    procedure, non_overridable :: accept_step
    procedure, non_overridable :: reject_step
    procedure, non_overridable :: finish_trial
  end type stepper_t

  abstract interface
    subroutine advance_i(this, sys, t, y, t_target, error, monitor)
      import :: stepper_t, ode_system_t, step_monitor_t, wp, error_t
      class(stepper_t), intent(inout) :: this
      class(ode_system_t), intent(inout) :: sys
      real(wp), intent(inout) :: t
      real(wp), intent(inout) :: y(:, :)
      real(wp), intent(in) :: t_target
      type(error_t), allocatable, intent(out) :: error
      class(step_monitor_t), intent(inout), optional :: monitor
    end subroutine advance_i

    !> The method's part of the state as plain arrays (possibly empty).
    subroutine get_method_state_i(this, reals, ints)
      import :: stepper_t, wp, i8
      class(stepper_t), intent(in) :: this
      real(wp), allocatable, intent(out) :: reals(:)
      integer(i8), allocatable, intent(out) :: ints(:)
    end subroutine get_method_state_i

    !> Restore the method's part of the state; on an error (sizes or values that this method
    !> cannot have written) the stepper is left unchanged.
    subroutine set_method_state_i(this, reals, ints, error)
      import :: stepper_t, wp, i8, error_t
      class(stepper_t), intent(inout) :: this
      real(wp), intent(in) :: reals(:)
      integer(i8), intent(in) :: ints(:)
      type(error_t), allocatable, intent(out) :: error
    end subroutine set_method_state_i
  end interface

contains

  ! ---------------------------------------------------------------- accessors

  !> The current step size: the size the next step will try (rk4: the fixed step).
  pure real(wp) function stepper_dt(this)
    class(stepper_t), intent(in) :: this
    stepper_dt = this%dt_
  end function stepper_dt

  !> Accepted steps since the start of the run.
  pure integer(i8) function stepper_steps(this)
    class(stepper_t), intent(in) :: this
    stepper_steps = this%steps_
  end function stepper_steps

  !> Rejected trial steps since the start of the run.
  pure integer(i8) function stepper_rejected(this)
    class(stepper_t), intent(in) :: this
    stepper_rejected = this%rejected_
  end function stepper_rejected

  !> Derivative evaluations since the start of the run.
  pure integer(i8) function stepper_evaluations(this)
    class(stepper_t), intent(in) :: this
    stepper_evaluations = this%evaluations_
  end function stepper_evaluations

  !> Smallest accepted step size (huge before the first step).
  pure real(wp) function stepper_dt_min_used(this)
    class(stepper_t), intent(in) :: this
    stepper_dt_min_used = this%dt_min_used_
  end function stepper_dt_min_used

  !> Largest accepted step size (0 before the first step).
  pure real(wp) function stepper_dt_max_used(this)
    class(stepper_t), intent(in) :: this
    stepper_dt_max_used = this%dt_max_used_
  end function stepper_dt_max_used

  !> The most accepted steps allowed.
  pure integer(i8) function stepper_max_steps(this)
    class(stepper_t), intent(in) :: this
    stepper_max_steps = this%max_steps_
  end function stepper_max_steps

  ! ---------------------------------------------------------------- checkpoints

  !> The whole state as plain arrays (layout in the module comment).
  subroutine get_state(this, reals, ints)
    class(stepper_t), intent(in) :: this
    real(wp), allocatable, intent(out) :: reals(:)
    integer(i8), allocatable, intent(out) :: ints(:)
    real(wp), allocatable :: method_reals(:)
    integer(i8), allocatable :: method_ints(:)
    call this%get_method_state(method_reals, method_ints)
    reals = [this%dt_, this%dt_min_used_, this%dt_max_used_, method_reals]
    ints = [stepper_state_version, this%steps_, this%rejected_, this%evaluations_, method_ints]
  end subroutine get_state

  !> Restore the whole state from arrays written by `get_state` of a stepper of the same
  !> method. Sizes and values are checked first: on an error the stepper is left unchanged.
  subroutine set_state(this, reals, ints, error)
    class(stepper_t), intent(inout) :: this
    real(wp), intent(in) :: reals(:)
    integer(i8), intent(in) :: ints(:)
    type(error_t), allocatable, intent(out) :: error
    if (size(reals) < n_common_reals .or. size(ints) < n_common_ints) then
      call fatal_error(error, 'stepper state: '//to_str(size(reals))//' reals and '//to_str(size(ints))// &
        ' integers (at least '//to_str(n_common_reals)//' and '//to_str(n_common_ints)//' expected)')
      return
    end if
    if (ints(1) /= stepper_state_version) then
      call fatal_error(error, 'stepper state: layout version '//to_str(ints(1))//' (this build reads '// &
        to_str(stepper_state_version)//')')
      return
    end if
    if (.not. all(ieee_is_finite(reals(1:n_common_reals)))) then
      call fatal_error(error, 'stepper state: non-finite step size or step statistics')
      return
    end if
    if (.not. reals(1) > 0.0_wp) then
      call fatal_error(error, 'stepper state: dt = '//to_str(reals(1), '(es10.3)')//' (must be > 0)')
      return
    end if
    if (any(ints(2:n_common_ints) < 0)) then
      call fatal_error(error, 'stepper state: negative step or evaluation counts')
      return
    end if
    call this%set_method_state(reals(n_common_reals + 1:), ints(n_common_ints + 1:), error)
    if (allocated(error)) return
    this%dt_ = reals(1)
    this%dt_min_used_ = reals(2)
    this%dt_max_used_ = reals(3)
    this%steps_ = ints(2)
    this%rejected_ = ints(3)
    this%evaluations_ = ints(4)
  end subroutine set_state

  !> Restore only the step size and the step counts (checkpoints written before the steppers
  !> saved their whole state): the rest keeps its initial value, so the continuation is close
  !> to, but not exactly, that of an uninterrupted run.
  subroutine set_basic_state(this, dt, steps, rejected, error)
    class(stepper_t), intent(inout) :: this
    real(wp), intent(in) :: dt
    integer(i8), intent(in) :: steps, rejected
    type(error_t), allocatable, intent(out) :: error
    if (.not. (ieee_is_finite(dt) .and. steps >= 0 .and. rejected >= 0)) then
      call fatal_error(error, 'stepper state: non-finite dt or negative step counts')
      return
    end if
    if (.not. dt > 0.0_wp) then
      call fatal_error(error, 'stepper state: dt = '//to_str(dt, '(es10.3)')//' (must be > 0)')
      return
    end if
    this%dt_ = dt
    this%steps_ = steps
    this%rejected_ = rejected
  end subroutine set_basic_state

  !> The default of `shift_clock`: a method whose state holds no time has nothing to move.
  subroutine shift_clock(this, delta)
    class(stepper_t), intent(inout) :: this
    real(wp), intent(in) :: delta
    associate (unused => this, unused_delta => delta)
    end associate
  end subroutine shift_clock

  ! ---------------------------------------------------------------- for the methods

  !> Start afresh with step size dt and at most max_steps accepted steps: statistics zeroed.
  subroutine reset_stepper(this, dt, max_steps)
    class(stepper_t), intent(inout) :: this
    real(wp), intent(in) :: dt
    integer(i8), intent(in) :: max_steps
    this%dt_ = dt
    this%max_steps_ = max_steps
    this%steps_ = 0
    this%rejected_ = 0
    this%evaluations_ = 0
    this%dt_min_used_ = huge(1.0_wp)
    this%dt_max_used_ = 0.0_wp
  end subroutine reset_stepper

  !> Set the step size the next step will try.
  subroutine set_dt(this, dt)
    class(stepper_t), intent(inout) :: this
    real(wp), intent(in) :: dt
    this%dt_ = dt
  end subroutine set_dt

  !> Count n derivative evaluations.
  subroutine add_evaluations(this, n)
    class(stepper_t), intent(inout) :: this
    integer, intent(in) :: n
    this%evaluations_ = this%evaluations_ + n
  end subroutine add_evaluations

  !> An error when max_steps accepted steps were taken (checked before every step at time t).
  subroutine check_max_steps(this, t, error)
    class(stepper_t), intent(in) :: this
    real(wp), intent(in) :: t
    type(error_t), allocatable, intent(out) :: error
    if (this%steps_ >= this%max_steps_) then
      call fatal_error(error, 'integrator: max_steps = '//to_str(this%max_steps_)//' reached at t = '// &
        to_str(t, '(es14.6)'))
    end if
  end subroutine check_max_steps

  !> Accept the step of size h from (t, y) to ynew: advance t (to t_target exactly on the last
  !> step), show the step to the monitor, take the new state, count the step and tell the system.
  subroutine accept_step(this, sys, t, y, ynew, h, last, t_target, monitor)
    class(stepper_t), intent(inout) :: this
    class(ode_system_t), intent(inout) :: sys
    real(wp), intent(inout) :: t
    real(wp), intent(inout) :: y(:, :)
    real(wp), intent(in) :: ynew(:, :)
    real(wp), intent(in) :: h, t_target
    logical, intent(in) :: last
    class(step_monitor_t), intent(inout), optional :: monitor
    real(wp) :: t_old
    t_old = t
    if (last) then
      t = t_target
    else
      t = t + h
    end if
    if (present(monitor)) call monitor%on_step(t_old, y, t, ynew)
    y = ynew
    this%steps_ = this%steps_ + 1
    this%dt_min_used_ = min(this%dt_min_used_, h)
    this%dt_max_used_ = max(this%dt_max_used_, h)
    call sys%step_accepted(t, y)
  end subroutine accept_step

  !> Count a rejected trial step and tell the system.
  subroutine reject_step(this, sys)
    class(stepper_t), intent(inout) :: this
    class(ode_system_t), intent(inout) :: sys
    this%rejected_ = this%rejected_ + 1
    call sys%step_rejected()
  end subroutine reject_step

  !> The end of one trial step of an adaptive method: h from t (the controller proposed
  !> dt_proposed; `last`: the step ends at t_target), the new state ynew and the error estimate
  !> err over the tolerance (`finite`: both usable). A non-finite trial is rejected and the step
  !> shrunk hard (an error after max_bad_trials in a row, counted in n_bad); err <= 1 accepts
  !> ynew (accept_step) and the controller proposes the next step; else the trial is rejected
  !> with a smaller step. Then the step-size underflow check. `accepted` tells the method to
  !> update its own state (e.g. dopri45's FSAL stage).
  subroutine finish_trial(this, controller, sys, t, y, ynew, h, dt_proposed, last, t_target, err, finite, &
                          n_bad, accepted, error, monitor)
    class(stepper_t), intent(inout) :: this
    type(step_controller_t), intent(inout) :: controller
    class(ode_system_t), intent(inout) :: sys
    real(wp), intent(inout) :: t
    real(wp), intent(inout) :: y(:, :)
    real(wp), intent(in) :: ynew(:, :)
    real(wp), intent(in) :: h, dt_proposed, t_target, err
    logical, intent(in) :: last, finite
    integer, intent(inout) :: n_bad
    logical, intent(out) :: accepted
    type(error_t), allocatable, intent(out) :: error
    class(step_monitor_t), intent(inout), optional :: monitor
    real(wp) :: dt_new
    accepted = .false.
    if (.not. finite) then
      n_bad = n_bad + 1
      call this%reject_step(sys)
      if (n_bad >= max_bad_trials) then
        call nonfinite_error(error, t)
        return
      end if
      call this%set_dt(controller%after_failure(h))
    else if (err <= 1.0_wp) then
      n_bad = 0
      call this%accept_step(sys, t, y, ynew, h, last, t_target, monitor)
      accepted = .true.
      call controller%after_accept(err, h, dt_proposed, last .and. h < dt_proposed, dt_new)
      call this%set_dt(dt_new)
    else
      call this%reject_step(sys)
      call this%set_dt(controller%after_rejection(err, h))
    end if
    if (t < t_target) call controller%check_underflow(this%dt(), t, error)
  end subroutine finish_trial

  ! ---------------------------------------------------------------- helpers

  !> The error of a trial step over the tolerance: the largest Euclidean norm over the columns
  !> (beads) of the estimate est, in `raw` (units of y) and divided by `tolerance` in `err`;
  !> `finite` (in: est usable) is false on return when err is not a finite number.
  pure subroutine error_norm(est, tolerance, finite, err, raw)
    real(wp), intent(in) :: est(:, :), tolerance
    logical, intent(inout) :: finite
    real(wp), intent(out) :: err
    real(wp), intent(inout) :: raw
    integer :: i
    err = 0.0_wp
    if (.not. finite) return
    do i = 1, size(est, 2)
      err = max(err, norm2(est(:, i)))
    end do
    raw = err
    err = err/tolerance
    finite = ieee_is_finite(err)
  end subroutine error_norm

  !> The check at the start of `advance`: t_target must not be before t.
  subroutine check_target(t, t_target, error)
    real(wp), intent(in) :: t, t_target
    type(error_t), allocatable, intent(out) :: error
    if (t_target < t) then
      call fatal_error(error, 'integrator: t_target = '//to_str(t_target, '(es14.6)')//' is before t = '// &
        to_str(t, '(es14.6)'))
    end if
  end subroutine check_target

  !> Are all entries finite? (No comparisons: quiet with FPE traps on.)
  pure logical function all_finite(a)
    real(wp), intent(in) :: a(:, :)
    all_finite = all(ieee_is_finite(a))
  end function all_finite

  !> The error for non-finite values in the solution near time t.
  subroutine nonfinite_error(error, t)
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in) :: t
    call fatal_error(error, 'integrator: non-finite values (NaN/Inf) in the solution near t = '//to_str(t, '(es14.6)'))
  end subroutine nonfinite_error

end module kf_stepper
