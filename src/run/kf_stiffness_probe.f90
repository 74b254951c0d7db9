!> Which limit sets the time step along a real run: an ODE system that integrates with one
!> dynamics (the scene's, which sees the stepper's hooks) and, at the start of every trial step
!> (t, y, h), estimates the stiffest eigenvalue lambda of mu(y) dF/dr (y) -- the exact mobility
!> of a second, exact ('stage') copy of the scene's hydrodynamic model at y, and the Jacobian of
!> the forces (springs, bending, excluded volume) by central differences -- and records lambda*h,
!> the stepper's error estimate of that trial and whether it was accepted.
!>
!> mu dF/dr is similar to the symmetric mu^(1/2) dF/dr mu^(1/2), so its eigenvalues are real;
!> those of the stiff bond modes are negative. The estimate is a Lanczos iteration (probe_stiffest)
!> warm-started from the previous step's Ritz vector; a Ritz value is a lower bound of the
!> magnitude, exact for an exact eigenvector. dopri45's
!> stability interval on the negative real axis ends at lambda*h = -3.31 (stability_boundary).
module kf_stiffness_probe
  use kf_kinds, only: wp, i8
  use kf_error, only: error_t
  use kf_scene, only: scene_t
  use kf_scene_hydro, only: update_stage
  use kf_dynamics, only: dynamics_t
  use kf_ode_system, only: ode_system_t
  use kf_hydro_model, only: hydro_model_t
  use kf_hydro_factory, only: make_hydro_model
  use kf_stepper, only: stepper_t
  use kf_stepper_dopri45, only: dopri45_stepper_t
  use kf_symmetric_eigen, only: symmetric_eigen
  implicit none
  private

  !> |lambda h| at the end of the real stability interval of the Dormand-Prince 5(4) method
  !> (the root of |R(z)| = 1 on the negative real axis, R its stability polynomial of degree 6).
  real(wp), parameter, public :: stability_boundary = 3.3066_wp

  !> One trial step: where it started, its size, the estimate and its outcome.
  type, public :: trial_record_t
    real(wp) :: t = 0.0_wp           !< start of the trial step
    real(wp) :: h = 0.0_wp           !< its size
    real(wp) :: lambda = 0.0_wp      !< stiffest eigenvalue of mu dF/dr at the start
    real(wp) :: error = 0.0_wp       !< the stepper's error estimate (units of y; -1: none)
    integer :: iterations = 0        !< Lanczos iterations spent
    logical :: accepted = .false.
  end type trial_record_t

  !> The scene's dynamics with the stiffness recorded at every trial step.
  type, extends(ode_system_t), public :: stiffness_probe_t
    type(dynamics_t) :: dyn                          !< integrates (the scene as given)
    class(stepper_t), pointer :: stepper => null()   !< its error estimate (dopri45), if set
    type(trial_record_t), allocatable :: trials(:)   !< records(1:n_trials)
    integer :: n_trials = 0
    integer :: max_iterations = 40                   !< Lanczos iterations per trial at most
    real(wp) :: rel_tol = 1.0e-4_wp                  !< stop when lambda changes less
    class(hydro_model_t), allocatable, private :: exact
    real(wp), allocatable, private :: f(:, :), u(:, :), g(:, :), rp(:, :), fp(:, :), fm(:, :)
    real(wp), private :: t_last = -huge(1.0_wp), lambda_last = 0.0_wp
    integer, private :: iterations_last = 0
  contains
    procedure :: init => probe_init
    procedure :: derivative => probe_derivative
    procedure :: step_begin => probe_step_begin
    procedure :: step_accepted => probe_step_accepted
    procedure :: step_rejected => probe_step_rejected
    procedure :: stiffest => probe_stiffest
  end type stiffness_probe_t

contains

  !> The scene integrates; an exact copy of its hydrodynamic model gives mu.
  subroutine probe_init(this, scene, n_beads, error)
    class(stiffness_probe_t), intent(inout) :: this
    type(scene_t), intent(in) :: scene
    integer, intent(in) :: n_beads
    type(error_t), allocatable, intent(out) :: error
    type(scene_t) :: sc
    integer :: i
    call this%dyn%init(scene, n_beads, error)
    if (allocated(error)) return
    sc = scene
    sc%hydro%update = update_stage
    call make_hydro_model(sc%hydro, sc%integrator%tolerance, this%exact, error)
    if (allocated(error)) return
    allocate (this%f(3, n_beads), this%u(3, n_beads), this%g(3, n_beads), this%rp(3, n_beads), &
              this%fp(3, n_beads), this%fm(3, n_beads), this%trials(1024))
    do i = 1, n_beads   ! a start vector with every mode in it
      this%f(:, i) = [sin(1.3_wp*i), cos(2.9_wp*i), sin(5.3_wp*i + 0.4_wp)]
    end do
    this%n_trials = 0
    this%t_last = -huge(1.0_wp)
  end subroutine probe_init

  subroutine probe_derivative(this, t, y, dydt, error)
    class(stiffness_probe_t), intent(inout) :: this
    real(wp), intent(in) :: t
    real(wp), intent(in) :: y(:, :)
    real(wp), intent(out) :: dydt(:, :)
    type(error_t), allocatable, intent(out) :: error
    call this%dyn%derivative(t, y, dydt, error)
  end subroutine probe_derivative

  !> The stiffest eigenvalue lambda (largest in magnitude) of mu(r) dF/dr(r) and the Lanczos
  !> iterations it took, started from the last call's Ritz vector. The exact model is prepared
  !> at r. K = dF/dr mu acts on forces and is self-adjoint in <a, b> = a.mu b (mu symmetric,
  !> dF/dr symmetric); Lanczos in that inner product with full reorthogonalisation (the inner
  !> products with the stored u_i = mu q_i are cheap), one mobility product and two force
  !> evaluations per iteration; stops when the extreme Ritz value changes by less than rel_tol.
  subroutine probe_stiffest(this, r, lambda, iterations, error)
    class(stiffness_probe_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: lambda
    integer, intent(out) :: iterations
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: q(:, :, :), u(:, :, :), t(:, :), y(:)
    real(wp) :: previous, beta, eps, c
    integer :: m, k, i, n, pick
    m = this%max_iterations
    n = size(r, 2)
    call this%exact%prepare(r, error)
    if (allocated(error)) return
    allocate (q(3, n, m + 1), u(3, n, m + 1), t(m, m), y(m))
    t = 0.0_wp
    lambda = 0.0_wp
    iterations = 0
    call this%exact%apply_mobility(this%f, this%u)
    beta = sqrt(sum(this%f*this%u))
    q(:, :, 1) = this%f/beta
    u(:, :, 1) = this%u/beta
    do k = 1, m
      previous = lambda
      ! g = dF/dr u_k by central differences, displacements of at most 1e-5 d
      eps = 1.0e-5_wp/max(maxval(abs(u(:, :, k))), tiny(1.0_wp))
      this%rp = r + eps*u(:, :, k)
      call this%dyn%compute_forces(this%rp, this%fp)
      this%rp = r - eps*u(:, :, k)
      call this%dyn%compute_forces(this%rp, this%fm)
      this%g = (this%fp - this%fm)/(2.0_wp*eps)
      t(k, k) = sum(this%g*u(:, :, k))
      do i = 1, k    ! full reorthogonalisation in the mu inner product
        c = sum(this%g*u(:, :, i))
        this%g = this%g - c*q(:, :, i)
      end do
      iterations = k
      call ritz(t, k, lambda, y, pick, error)
      if (allocated(error)) return
      call this%exact%apply_mobility(this%g, this%u)
      beta = sqrt(max(sum(this%g*this%u), 0.0_wp))
      if (k == m .or. beta <= 1.0e-12_wp*abs(lambda) .or. &
          (k >= 5 .and. abs(lambda - previous) <= this%rel_tol*abs(lambda))) exit
      q(:, :, k + 1) = this%g/beta
      u(:, :, k + 1) = this%u/beta
      t(k + 1, k) = beta
      t(k, k + 1) = beta
    end do
    ! the next call starts from this Ritz vector
    this%f = 0.0_wp
    do i = 1, iterations
      this%f = this%f + y(i)*q(:, :, i)
    end do
    this%f = this%f/norm2(this%f)
  end subroutine probe_stiffest

  !> The Ritz value of largest magnitude of the k x k Lanczos matrix t(1:k, 1:k), its vector
  !> y(1:k) and its index in ascending order.
  subroutine ritz(t, k, lambda, y, pick, error)
    real(wp), intent(in) :: t(:, :)
    integer, intent(in) :: k
    real(wp), intent(out) :: lambda, y(:)
    integer, intent(out) :: pick
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: a(k, k), w(k)
    a = t(1:k, 1:k)
    call symmetric_eigen(a, w, error)
    if (allocated(error)) return
    pick = 1
    if (abs(w(k)) > abs(w(1))) pick = k
    lambda = w(pick)
    y = 0.0_wp
    y(1:k) = a(:, pick)
  end subroutine ritz

  !> A trial step begins: estimate (once per start time) and open its record.
  subroutine probe_step_begin(this, t, y, h)
    class(stiffness_probe_t), intent(inout) :: this
    real(wp), intent(in) :: t, y(:, :), h
    type(error_t), allocatable :: error
    type(trial_record_t), allocatable :: grown(:)
    if (t /= this%t_last) then
      call this%stiffest(y, this%lambda_last, this%iterations_last, error)
      if (allocated(error)) this%lambda_last = ieee_nan()
      this%t_last = t
    end if
    if (this%n_trials == size(this%trials)) then
      allocate (grown(2*size(this%trials)))
      grown(1:this%n_trials) = this%trials
      call move_alloc(grown, this%trials)
    end if
    this%n_trials = this%n_trials + 1
    this%trials(this%n_trials) = trial_record_t(t=t, h=h, lambda=this%lambda_last, error=-1.0_wp, &
                                                iterations=this%iterations_last, accepted=.false.)
    call this%dyn%step_begin(t, y, h)
  end subroutine probe_step_begin

  subroutine probe_step_accepted(this, t, y)
    class(stiffness_probe_t), intent(inout) :: this
    real(wp), intent(in) :: t, y(:, :)
    call close_trial(this, .true.)
    call this%dyn%step_accepted(t, y)
  end subroutine probe_step_accepted

  subroutine probe_step_rejected(this)
    class(stiffness_probe_t), intent(inout) :: this
    call close_trial(this, .false.)
    call this%dyn%step_rejected()
  end subroutine probe_step_rejected

  !> The outcome and the stepper's error estimate of the open trial.
  subroutine close_trial(this, accepted)
    type(stiffness_probe_t), intent(inout) :: this
    logical, intent(in) :: accepted
    if (this%n_trials < 1) return
    this%trials(this%n_trials)%accepted = accepted
    if (associated(this%stepper)) then
      select type (s => this%stepper)
      type is (dopri45_stepper_t)
        this%trials(this%n_trials)%error = s%error_estimate()
      end select
    end if
  end subroutine close_trial

  pure real(wp) function ieee_nan()
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    ieee_nan = ieee_value(1.0_wp, ieee_quiet_nan)
  end function ieee_nan

end module kf_stiffness_probe
