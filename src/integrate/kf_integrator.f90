!> Time integrators for y(3, N) (kf_ode_system):
!>  - `dopri45`: Dormand-Prince 5(4) (Dormand and Prince 1980), adaptive, FSAL. The error per
!>    step is the largest Euclidean norm over beads of the embedded error estimate (units of d),
!>    compared with `tolerance`; the 5th-order solution is propagated. Step-size control is the
!>    PI controller of Gustafsson (Hairer and Wanner, Solving ODEs II, IV.2):
!>    h_new = h * clip(safety * err^(-alpha) * err_prev^beta, fac_min, fac_max), with only
!>    shrinking after a rejection. Near the stability limit set by stiff springs this keeps the
!>    step size from oscillating and the rejections few.
!>  - `rk4`: classic fixed-step fourth-order Runge-Kutta with step dt_initial.
module kf_integrator
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_scene, only: integrator_params_t
  use kf_ode_system, only: ode_system_t
  use kf_step_monitor, only: step_monitor_t
  implicit none
  private

  integer, parameter :: method_dopri45 = 1, method_rk4 = 2

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

  !> Integrator settings, work space and statistics.
  type, public :: integrator_t
    integer :: method = method_dopri45
    real(wp) :: tolerance = 1.0e-4_wp
    real(wp) :: dt = 1.0e-3_wp            !< current (proposed) step size
    real(wp) :: dt_min = 1.0e-9_wp
    real(wp) :: dt_max = 0.5_wp
    integer(i8) :: max_steps = huge(1_i8)
    real(wp) :: safety = 0.9_wp
    real(wp) :: fac_min = 0.2_wp
    real(wp) :: fac_max = 5.0_wp
    real(wp) :: alpha = 0.7_wp/5.0_wp     !< PI controller exponents
    real(wp) :: beta = 0.4_wp/5.0_wp
    ! statistics
    integer(i8) :: steps = 0              !< accepted steps
    integer(i8) :: rejected = 0
    integer(i8) :: evaluations = 0        !< derivative evaluations
    real(wp) :: dt_min_used = huge(1.0_wp)
    real(wp) :: dt_max_used = 0.0_wp
    ! internal state
    real(wp), private :: err_prev = 1.0e-4_wp
    logical, private :: fsal_valid = .false.
    real(wp), private :: t_fsal = 0.0_wp
    real(wp), allocatable, private :: y_fsal(:, :), k1(:, :), k2(:, :), k3(:, :), k4(:, :), &
                                      k5(:, :), k6(:, :), k7(:, :), ytmp(:, :), ynew(:, :)
  contains
    procedure :: init => integrator_init
    procedure :: advance => integrator_advance
    procedure, private :: ensure_work
    procedure, private :: step_rk4
    procedure, private :: step_dopri
  end type integrator_t

contains

  !> Validate the &integrator parameters and reset the statistics.
  subroutine integrator_init(this, params, error)
    class(integrator_t), intent(out) :: this
    type(integrator_params_t), intent(in) :: params
    type(error_t), allocatable, intent(out) :: error
    select case (trim(params%method))
    case ('dopri45')
      this%method = method_dopri45
    case ('rk4')
      this%method = method_rk4
    case default
      call fatal_error(error, "integrator: method = '"//trim(params%method)// &
        "' is unknown (allowed: dopri45, rk4)")
      return
    end select
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
    this%tolerance = params%tolerance
    this%dt_min = params%dt_min
    this%dt_max = params%dt_max
    this%max_steps = params%max_steps
    if (this%method == method_rk4) then
      this%dt = params%dt_initial
    else
      this%dt = min(params%dt_initial, params%dt_max)
    end if
  end subroutine integrator_init

  subroutine ensure_work(this, y)
    class(integrator_t), intent(inout) :: this
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

  !> Integrate y from t exactly to t_target (t is updated). The last step is clipped to hit
  !> t_target; the step size proposed before the clip is kept for the next call. On failure
  !> (non-finite values, step size underflow, max_steps, an error of the system) y and t are
  !> left at the last accepted state. An optional `monitor` sees every accepted step
  !> (kf_step_monitor): its `on_step` gets the configurations before and after the step.
  subroutine integrator_advance(this, sys, t, y, t_target, error, monitor)
    class(integrator_t), intent(inout) :: this
    class(ode_system_t), intent(inout) :: sys
    real(wp), intent(inout) :: t
    real(wp), intent(inout) :: y(:, :)
    real(wp), intent(in) :: t_target
    type(error_t), allocatable, intent(out) :: error
    class(step_monitor_t), intent(inout), optional :: monitor
    if (t_target < t) then
      call fatal_error(error, 'integrator: t_target = '//to_str(t_target, '(es14.6)')//' is before t = '// &
        to_str(t, '(es14.6)'))
      return
    end if
    call this%ensure_work(y)
    if (this%method == method_rk4) then
      call this%step_rk4(sys, t, y, t_target, error, monitor)
    else
      call this%step_dopri(sys, t, y, t_target, error, monitor)
    end if
  end subroutine integrator_advance

  pure logical function all_finite(a)
    real(wp), intent(in) :: a(:, :)
    all_finite = all(ieee_is_finite(a))   ! no comparisons: quiet with FPE traps on
  end function all_finite

  subroutine nonfinite_error(error, t)
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in) :: t
    call fatal_error(error, 'integrator: non-finite values (NaN/Inf) in the solution near t = '//to_str(t, '(es14.6)'))
  end subroutine nonfinite_error

  subroutine max_steps_error(error, this, t)
    type(error_t), allocatable, intent(out) :: error
    class(integrator_t), intent(in) :: this
    real(wp), intent(in) :: t
    call fatal_error(error, 'integrator: max_steps = '//to_str(this%max_steps)//' reached at t = '// &
      to_str(t, '(es14.6)'))
  end subroutine max_steps_error

  !> Accept the step of size h to this%ynew: advance t (to t_target exactly on the last step),
  !> show the step to the monitor, take the new state and count the step.
  subroutine accept_step(this, t, y, h, last, t_target, monitor)
    class(integrator_t), intent(inout) :: this
    real(wp), intent(inout) :: t
    real(wp), intent(inout) :: y(:, :)
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
    if (present(monitor)) call monitor%on_step(t_old, y, t, this%ynew)
    y = this%ynew
    this%steps = this%steps + 1
    this%dt_min_used = min(this%dt_min_used, h)
    this%dt_max_used = max(this%dt_max_used, h)
  end subroutine accept_step

  !> Fixed-step classic RK4 with step this%dt (the last step clipped to t_target).
  subroutine step_rk4(this, sys, t, y, t_target, error, monitor)
    class(integrator_t), intent(inout) :: this
    class(ode_system_t), intent(inout) :: sys
    real(wp), intent(inout) :: t
    real(wp), intent(inout) :: y(:, :)
    real(wp), intent(in) :: t_target
    type(error_t), allocatable, intent(out) :: error
    class(step_monitor_t), intent(inout), optional :: monitor
    real(wp) :: h
    logical :: last
    do while (t < t_target)
      if (this%steps >= this%max_steps) then
        call max_steps_error(error, this, t)
        return
      end if
      h = this%dt
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
      this%evaluations = this%evaluations + 4
      this%ynew = y + (h/6.0_wp)*(this%k1 + 2.0_wp*(this%k2 + this%k3) + this%k4)
      if (.not. all_finite(this%ynew)) then
        call nonfinite_error(error, t)
        return
      end if
      call accept_step(this, t, y, h, last, t_target, monitor)
    end do
  end subroutine step_rk4

  !> Adaptive Dormand-Prince 5(4) with FSAL and PI step-size control.
  subroutine step_dopri(this, sys, t, y, t_target, error, monitor)
    class(integrator_t), intent(inout) :: this
    class(ode_system_t), intent(inout) :: sys
    real(wp), intent(inout) :: t
    real(wp), intent(inout) :: y(:, :)
    real(wp), intent(in) :: t_target
    type(error_t), allocatable, intent(out) :: error
    class(step_monitor_t), intent(inout), optional :: monitor
    real(wp) :: h, err, fac, dt_proposed
    integer :: i, n_bad
    logical :: last, finite

    ! FSAL: k1 is reusable if y and t are those it was evaluated at (the caller may change y).
    if (this%fsal_valid) then
      if (t /= this%t_fsal .or. any(y /= this%y_fsal)) this%fsal_valid = .false.
    end if
    n_bad = 0
    do while (t < t_target)
      if (this%steps >= this%max_steps) then
        call max_steps_error(error, this, t)
        return
      end if
      if (.not. this%fsal_valid) then
        call sys%derivative(t, y, this%k1, error)
        if (allocated(error)) return
        this%evaluations = this%evaluations + 1
        if (.not. all_finite(this%k1)) then
          call nonfinite_error(error, t)
          return
        end if
        this%fsal_valid = .true.
        this%t_fsal = t
        this%y_fsal = y
      end if
      dt_proposed = min(this%dt, this%dt_max)
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
      this%evaluations = this%evaluations + 6

      ! Error estimate (into ytmp): largest Euclidean norm over beads, relative to tolerance.
      this%ytmp = h*(e1*this%k1 + e3*this%k3 + e4*this%k4 + e5*this%k5 + e6*this%k6 + e7*this%k7)
      finite = all_finite(this%ytmp) .and. all_finite(this%ynew) .and. all_finite(this%k7)
      err = 0.0_wp
      if (finite) then
        do i = 1, size(y, 2)
          err = max(err, norm2(this%ytmp(:, i)))
        end do
        err = err/this%tolerance
        finite = ieee_is_finite(err)
      end if
      if (.not. finite) then
        ! Non-finite trial step: shrink hard; give up after repeated failures.
        n_bad = n_bad + 1
        this%rejected = this%rejected + 1
        if (n_bad >= 10) then
          call nonfinite_error(error, t)
          return
        end if
        this%dt = h*this%fac_min
      else if (err <= 1.0_wp) then
        n_bad = 0
        call accept_step(this, t, y, h, last, t_target, monitor)
        call sys%step_accepted(t, y)
        this%k1 = this%k7
        this%t_fsal = t
        this%y_fsal = y
        fac = this%safety*max(err, 1.0e-10_wp)**(-this%alpha)*this%err_prev**this%beta
        fac = min(this%fac_max, max(this%fac_min, fac))
        this%err_prev = max(err, 1.0e-4_wp)
        if (last .and. h < dt_proposed) then
          ! A clipped step says little about larger steps: keep the proposal unless told to shrink.
          if (fac >= 1.0_wp) then
            this%dt = max(dt_proposed, h*fac)
          else
            this%dt = min(dt_proposed, h*fac)
          end if
        else
          this%dt = h*fac
        end if
        this%dt = min(this%dt, this%dt_max)
      else
        this%rejected = this%rejected + 1
        call sys%step_rejected()
        fac = max(this%fac_min, this%safety*err**(-this%alpha))
        this%dt = h*min(1.0_wp, fac)
      end if
      if (this%dt < this%dt_min .and. t < t_target) then
        call fatal_error(error, 'integrator: step size underflow (dt = '//to_str(this%dt, '(es10.3)')// &
          ' < dt_min at t = '//to_str(t, '(es14.6)')//')')
        return
      end if
    end do
  end subroutine step_dopri

end module kf_integrator
