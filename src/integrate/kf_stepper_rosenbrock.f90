!> Linearly implicit Rosenbrock-W methods of 4 stages (kf_stepper), driven by a tableau chosen
!> once at set-up (kf_stepper_factory maps &integrator method to one of the tableau functions):
!> - `ros34pw2_tableau`: ROS34PW2, order 3 with an embedded solution of order 2, L-stable and
!>   stiffly accurate; a W-method, so its order holds for any approximation J of the Jacobian;
!> - `ros34pw3_tableau`: ROS34PW3, order 4 as a Rosenbrock method (the exact Jacobian), order 3
!>   as a W-method (any J), embedded solution of order 2, A-stable with |R(inf)| = 0.63;
!> both of Rang and Angermann, BIT Numer. Math. 45 (2005) 761-787 (ROS34PW2 is PETSc's
!> TSROSWRA34PW2).
!> In the notation of Hairer and Wanner (Solving ODEs II, IV.7), with gamma_ii = gamma:
!>   (I - h gamma J) k_i = h f(t + alpha_i h, y + sum_j<i alpha_ij k_j) + h J sum_j<i gamma_ij k_j,
!>   y_new = y + sum_i b_i k_i,   error estimate sum_i (b_i - bhat_i) k_i.
!> It is evaluated in the variables u_i = sum_j<=i gamma_ij k_j (Hairer-Wanner (7.25)), which
!> need no product with J: with G = (gamma_ij), a = (alpha_ij) G^-1, c = -G^-1 (off-diagonal),
!> m = b G^-1 and mhat = bhat G^-1,
!>   (I/(h gamma) - J) u_i = f(t + alpha_i h, y + sum_j<i a_ij u_j) + sum_j<i (c_ij/h) u_j,
!>   y_new = y + sum_i m_i u_i,   error = sum_i (m_i - mhat_i) u_i.
!> The time derivative df/dt is not used: that is the W-method with the approximate Jacobian
!> [[J, 0], [0, 0]] of the autonomous form (y, t), so the W order holds for time-dependent f too
!> (ROS34PW3's order 4 needs the exact Jacobian and an autonomous f).
!>
!> Error per step: the largest Euclidean norm over beads (columns of y) of the estimate, against
!> `tolerance`, as dopri45; the higher-order solution is propagated; the PI controller of
!> kf_step_controller with the exponents of the tableau's embedded order. Work per trial step:
!> one LU factorisation of I/(h gamma) - J (n = size(y)), 4 solves, 3 derivative evaluations
!> plus f(t, y), which a retry after a rejection reuses. The Jacobian comes from the system's
!> `jacobian` hook (kf_ode_system) at the start of every step (a retry reuses it); a system may
!> build it from parts it keeps between calls (the dynamics: the mobility, `&integrator
!> jacobian_steps`).
!>
!> Method part of the state (`get_state`, after the common entries), the same for every
!> tableau (a resume checks the method's name, kf_case_runner):
!>   reals = [err_prev],   ints = [jacobians]   (Jacobians made)
module kf_stepper_rosenbrock
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_lapack, only: lu_factor, lu_solve
  use kf_ode_system, only: ode_system_t
  use kf_step_monitor, only: step_monitor_t
  use kf_stepper, only: stepper_t, check_target, all_finite, nonfinite_error, error_norm
  use kf_step_controller, only: step_controller_t
  implicit none
  private

  integer, parameter :: s = 4

  !> A published tableau: gamma, alpha_ij and gamma_ij (i > j; the diagonal of gammas is gamma),
  !> b, bhat and the order of the embedded solution (the estimate is ~ h^(embedded_order + 1)).
  type, public :: rosenbrock_tableau_t
    real(wp) :: gamma = 0.0_wp
    real(wp) :: alpha(s, s) = 0.0_wp, gammas(s, s) = 0.0_wp, b(s) = 0.0_wp, bhat(s) = 0.0_wp
    integer :: embedded_order = 0
  end type rosenbrock_tableau_t

  public :: ros34pw2_tableau, ros34pw3_tableau

  !> The tableau in the variables u (module header), worked out once from the published one.
  type :: tableau_t
    real(wp) :: a(s, s) = 0.0_wp, c(s, s) = 0.0_wp, m(s) = 0.0_wp, e(s) = 0.0_wp, alpha(s) = 0.0_wp, gamma = 0.0_wp
  end type tableau_t

  !> An adaptive Rosenbrock-W method: its tableau, tolerance, controller and work space.
  type, extends(stepper_t), public :: rosenbrock_stepper_t
    private
    real(wp) :: tolerance = 1.0e-4_wp
    type(step_controller_t) :: controller
    type(tableau_t) :: tab
    real(wp) :: last_error = 0.0_wp
    integer(i8) :: jacobians_ = 0            !< Jacobians made
    real(wp), allocatable :: jac(:, :), w(:, :), u(:, :), rhs(:), f0(:, :), fk(:, :), ytmp(:, :), &
                             ynew(:, :), est(:, :)
    integer, allocatable :: ipiv(:)
  contains
    procedure :: init => ros_init
    procedure :: advance => ros_advance
    procedure :: error_estimate => ros_error_estimate
    procedure :: jacobians => ros_jacobians
    procedure :: get_method_state => ros_get_method_state
    procedure :: set_method_state => ros_set_method_state
  end type rosenbrock_stepper_t

contains

  !> The tableau (one of the tableau functions), tolerance per step (units of y), initial step
  !> size (capped at dt_max), step-size limits and at most max_steps accepted steps; validated by
  !> the factory.
  subroutine ros_init(this, tableau, tolerance, dt_initial, dt_min, dt_max, max_steps)
    class(rosenbrock_stepper_t), intent(out) :: this
    type(rosenbrock_tableau_t), intent(in) :: tableau
    real(wp), intent(in) :: tolerance, dt_initial, dt_min, dt_max
    integer(i8), intent(in) :: max_steps
    this%tolerance = tolerance
    this%tab = transformed_tableau(tableau)
    call this%controller%init(dt_min, dt_max, tableau%embedded_order)
    call this%reset_stepper(min(dt_initial, dt_max), max_steps)
  end subroutine ros_init

  !> ROS34PW2 (Rang and Angermann 2005, table of ROS34PW2): order 3(2), L-stable.
  pure function ros34pw2_tableau() result(t)
    type(rosenbrock_tableau_t) :: t
    t%gamma = 4.3586652150845900e-01_wp
    t%alpha(2, 1) = 8.7173304301691801e-01_wp
    t%alpha(3, 1:2) = [8.4457060015369423e-01_wp, -1.1299064236484185e-01_wp]
    t%alpha(4, 1:3) = [0.0_wp, 0.0_wp, 1.0_wp]
    t%gammas(2, 1) = -8.7173304301691801e-01_wp
    t%gammas(3, 1:2) = [-9.0338057013044082e-01_wp, 5.4180672388095326e-02_wp]
    t%gammas(4, 1:3) = [2.4212380706095346e-01_wp, -1.2232505839045147e+00_wp, 5.4526025533510214e-01_wp]
    t%b = [2.4212380706095346e-01_wp, -1.2232505839045147e+00_wp, 1.5452602553351020e+00_wp, &
           4.3586652150845900e-01_wp]
    t%bhat = [3.7810903145819369e-01_wp, -9.6042292212423178e-02_wp, 5.0000000000000000e-01_wp, &
              2.1793326075422950e-01_wp]
    t%embedded_order = 2
    call set_diagonal(t)
  end function ros34pw2_tableau

  !> ROS34PW3 (Rang and Angermann 2005, table of ROS34PW3): order 4 with the exact Jacobian, 3
  !> as a W-method, embedded order 2 (checked: tests/unit/test_rosenbrock.pf), A-stable.
  pure function ros34pw3_tableau() result(t)
    type(rosenbrock_tableau_t) :: t
    t%gamma = 1.0685790213016289_wp
    t%alpha(2, 1) = 2.5155456020628817_wp
    t%alpha(3, 1:2) = [0.50777280103144085_wp, 0.75_wp]
    t%alpha(4, 1:3) = [0.13959081404277204_wp, -0.33111001065419338_wp, 0.82040559712714178_wp]
    t%gammas(2, 1) = -2.5155456020628817_wp
    t%gammas(3, 1:2) = [-0.87991339217106512_wp, -0.96014187766190695_wp]
    t%gammas(4, 1:3) = [-0.41731389379448741_wp, 0.41091047035857703_wp, -1.3558873204765276_wp]
    t%b = [0.22047681286931747_wp, 0.0027828278331185935_wp, 0.0071844787635140066_wp, 0.76955588053404989_wp]
    t%bhat = [0.31300297285209688_wp, -0.28946895245112692_wp, 0.97646597959903003_wp, 0.0_wp]
    t%embedded_order = 2
    call set_diagonal(t)
  end function ros34pw3_tableau

  !> gamma_ii = gamma.
  pure subroutine set_diagonal(t)
    type(rosenbrock_tableau_t), intent(inout) :: t
    integer :: i
    do i = 1, s
      t%gammas(i, i) = t%gamma
    end do
  end subroutine set_diagonal

  !> a = alpha G^-1, c = -G^-1 below the diagonal, m = b G^-1, e = (b - bhat) G^-1, and the stage
  !> times alpha_i = sum_j alpha_ij, G = gamma_ij (lower triangular, inverted by substitution).
  pure function transformed_tableau(t) result(tab)
    type(rosenbrock_tableau_t), intent(in) :: t
    type(tableau_t) :: tab
    real(wp) :: ginv(s, s)
    integer :: i, j, k
    ginv = 0.0_wp
    do j = 1, s
      ginv(j, j) = 1.0_wp/t%gammas(j, j)
      do i = j + 1, s
        ginv(i, j) = -sum(t%gammas(i, j:i - 1)*ginv(j:i - 1, j))/t%gammas(i, i)
      end do
    end do
    tab%a = matmul(t%alpha, ginv)
    tab%c = 0.0_wp
    do i = 2, s
      do k = 1, i - 1
        tab%c(i, k) = -ginv(i, k)
      end do
    end do
    tab%m = matmul(t%b, ginv)
    tab%e = matmul(t%b - t%bhat, ginv)
    tab%alpha = sum(t%alpha, dim=2)
    tab%gamma = t%gamma
  end function transformed_tableau

  !> The embedded error estimate of the last trial step (units of y, not divided by the
  !> tolerance; the largest Euclidean norm over the columns); 0 before the first trial.
  pure real(wp) function ros_error_estimate(this)
    class(rosenbrock_stepper_t), intent(in) :: this
    ros_error_estimate = this%last_error
  end function ros_error_estimate

  !> Jacobians made since the start of the run.
  pure integer(i8) function ros_jacobians(this)
    class(rosenbrock_stepper_t), intent(in) :: this
    ros_jacobians = this%jacobians_
  end function ros_jacobians

  !> Work space for states shaped like y.
  subroutine ensure_work(this, y)
    type(rosenbrock_stepper_t), intent(inout) :: this
    real(wp), intent(in) :: y(:, :)
    integer :: n
    n = size(y)
    if (allocated(this%f0)) then
      if (all(shape(this%f0) == shape(y))) return
      deallocate (this%jac, this%w, this%u, this%rhs, this%f0, this%fk, this%ytmp, this%ynew, this%est, this%ipiv)
    end if
    allocate (this%jac(n, n), this%w(n, n), this%u(n, s), this%rhs(n), this%ipiv(n))
    allocate (this%f0, this%fk, this%ytmp, this%ynew, this%est, mold=y)
  end subroutine ensure_work

  !> Integrate exactly to t_target with adaptive steps (contract in kf_stepper).
  subroutine ros_advance(this, sys, t, y, t_target, error, monitor)
    class(rosenbrock_stepper_t), intent(inout) :: this
    class(ode_system_t), intent(inout) :: sys
    real(wp), intent(inout) :: t
    real(wp), intent(inout) :: y(:, :)
    real(wp), intent(in) :: t_target
    type(error_t), allocatable, intent(out) :: error
    class(step_monitor_t), intent(inout), optional :: monitor
    type(error_t), allocatable :: lu_error
    real(wp) :: h, err, dt_proposed
    integer :: i, j, n, n_bad, evals
    logical :: last, finite, fresh, accepted

    call check_target(t, t_target, error)
    if (allocated(error)) return
    call ensure_work(this, y)
    n = size(y)
    n_bad = 0
    fresh = .true.              ! a new start: f(t, y) and the Jacobian to make (kept over retries)
    do while (t < t_target)
      call this%check_max_steps(t, error)
      if (allocated(error)) return
      if (fresh) then
        call sys%derivative(t, y, this%f0, error)
        if (allocated(error)) return
        call this%add_evaluations(1)
        if (.not. all_finite(this%f0)) then
          call nonfinite_error(error, t)
          return
        end if
        call sys%jacobian(t, y, this%jac, evals, error)
        if (allocated(error)) return
        call this%add_evaluations(evals)
        if (.not. all(ieee_is_finite(this%jac))) then
          call nonfinite_error(error, t)
          return
        end if
        this%jacobians_ = this%jacobians_ + 1
        fresh = .false.
      end if
      dt_proposed = this%controller%proposal(this%dt())
      h = dt_proposed
      last = t + h*(1.0_wp + 1.0e-12_wp) >= t_target
      if (last) h = t_target - t
      call sys%step_begin(t, y, h)

      ! W = I/(h gamma) - J, factorised
      this%w = -this%jac
      do i = 1, n
        this%w(i, i) = this%w(i, i) + 1.0_wp/(h*this%tab%gamma)
      end do
      call lu_factor(this%w, this%ipiv, lu_error, 'Rosenbrock iteration matrix')
      finite = .not. allocated(lu_error)
      if (finite) then
        do i = 1, s
          if (i == 1) then
            this%rhs = reshape(this%f0, [n])
          else
            this%ytmp = y
            do j = 1, i - 1
              if (this%tab%a(i, j) /= 0.0_wp) &
                this%ytmp = this%ytmp + this%tab%a(i, j)*reshape(this%u(:, j), shape(y))
            end do
            call sys%derivative(t + this%tab%alpha(i)*h, this%ytmp, this%fk, error)
            if (allocated(error)) return
            call this%add_evaluations(1)
            this%rhs = reshape(this%fk, [n])
            do j = 1, i - 1
              this%rhs = this%rhs + (this%tab%c(i, j)/h)*this%u(:, j)
            end do
          end if
          call lu_solve(this%w, this%ipiv, this%rhs)
          this%u(:, i) = this%rhs
        end do
        this%ynew = y + reshape(matmul(this%u, this%tab%m), shape(y))
        this%est = reshape(matmul(this%u, this%tab%e), shape(y))
        finite = all_finite(this%ynew) .and. all_finite(this%est)
      end if
      call error_norm(this%est, this%tolerance, finite, err, this%last_error)
      call this%finish_trial(this%controller, sys, t, y, this%ynew, h, dt_proposed, last, t_target, err, finite, &
                             n_bad, accepted, error, monitor)
      if (allocated(error)) return
      ! a new start after an accepted step: f(t, y) and the Jacobian to make (kept over retries)
      if (accepted) fresh = .true.
    end do
  end subroutine ros_advance

  !> err_prev and the count of Jacobians (layout in the module header).
  subroutine ros_get_method_state(this, reals, ints)
    class(rosenbrock_stepper_t), intent(in) :: this
    real(wp), allocatable, intent(out) :: reals(:)
    integer(i8), allocatable, intent(out) :: ints(:)
    reals = [this%controller%memory()]
    ints = [this%jacobians_]
  end subroutine ros_get_method_state

  subroutine ros_set_method_state(this, reals, ints, error)
    class(rosenbrock_stepper_t), intent(inout) :: this
    real(wp), intent(in) :: reals(:)
    integer(i8), intent(in) :: ints(:)
    type(error_t), allocatable, intent(out) :: error
    type(step_controller_t) :: controller
    character(len=*), parameter :: what = 'Rosenbrock stepper state: '
    if (size(reals) /= 1 .or. size(ints) /= 1) then
      call fatal_error(error, what//to_str(size(reals))//' reals and '//to_str(size(ints))// &
        ' integers after the common entries (1 and 1 expected)')
      return
    end if
    if (ints(1) < 0) then
      call fatal_error(error, what//'jacobians = '//to_str(ints(1))//' (must be >= 0)')
      return
    end if
    controller = this%controller
    call controller%set_memory(reals(1), error)
    if (allocated(error)) then
      error%message = what//error%message
      return
    end if
    this%controller = controller
    this%jacobians_ = ints(1)
  end subroutine ros_set_method_state

end module kf_stepper_rosenbrock
