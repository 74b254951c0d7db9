!> The multipole model with `&hydro update = 'adaptive'` (docs/multipole.md): the many-body part
!> zeta_L, x_L of the exact model (kf_hydro_multipole) is computed exactly at a refresh and
!> reused at later stages, while the lubrication corrections are exact at every call.
!>
!> The current configuration is rotated onto the reference by the best rigid rotation Q
!> (kf_rigid_fit; Stokes flow is covariant, so rigid tumbling costs no accuracy), forces and
!> strain with it, the velocities back. With earlier refreshes in the history the part is
!> extrapolated in time by the polynomial through the last k + 1 refreshes (order k = 1: linear
!> through the last two, k = 2: quadratic through the last three):
!> zeta_L(ref) + w1 dzeta_1 + w2 dzeta_2, with dzeta_1 = zeta_ref - zeta_prev and dzeta_2 =
!> zeta_prev - zeta_prev2 seen from the reference frame and the Newton weights of
!> `extrapolation_weights`. The corrected system is solved by conjugate gradients preconditioned
!> with the Cholesky factor at the refresh (re-factorised when CG needs more than
!> `cg_refactor_iterations`), to a velocity error below cg_fraction of the budget.
!>
!> Refresh rule: the budget on the velocity error of a stage is budget_fraction * tolerance / h
!> (h the stepper's trial step): it moves a bead by less than budget_fraction of the tolerance
!> in one step. The error of order k is predicted as coef_k |t - t_ref| prod_j<=k |t - t_hist(j)|
!> (the error of polynomial interpolation); every refresh after the first also computes the
!> reused velocities of the two candidate orders (the highest the history allows and the one
!> below) at the new configuration and compares them with the exact ones, which recalibrates
!> their coefficients (max over beads, never below half the old value). A call uses the
!> candidate with the smaller prediction, and refreshes when that exceeds the budget, when a
!> candidate is not calibrated yet, when |t - t_ref| > 3 (t_ref - t_prev), when the deformation
!> after the rigid fit exceeds max_deformation, or when CG does not converge. Without a step
!> size or a time (calls outside a stepper) every call is exact.
!>
!> Everything else (`prepare`, `apply_mobility`, the stresslet, the friction matrix) is the exact
!> model's (the parent type), exact at the configuration given; it leaves the reuse state alone.
module kf_hydro_multipole_adaptive
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str
  use kf_blas, only: dgemv, dsymv
  use kf_lapack, only: cholesky_factor, cholesky_solve
  use kf_error, only: error_t, fatal_error
  use kf_hydro_model, only: hydro_stats_t
  use kf_hydro_multipole, only: multipole_model_t, multipole_memory_bytes, largest_velocity
  use kf_strain_basis, only: strain_coefficients, strain_basis
  use kf_pair_blocks, only: pair_blocks_t
  use kf_pair_geometry, only: pair_geometry_t
  use kf_rigid_fit, only: best_rotation, centroid, rotate_blocks
  implicit none
  private

  public :: extrapolation_weights, adaptive_memory_bytes

  !> Velocity error budget of a reused many-body part, as a fraction of tolerance / step size.
  real(wp), parameter :: budget_fraction = 0.25_wp
  !> Conjugate-gradient stopping error, as a fraction of the budget.
  real(wp), parameter :: cg_fraction = 0.05_wp
  !> Largest deformation D (units of d) over which a many-body part is reused.
  real(wp), parameter :: max_deformation = 0.5_wp
  !> Largest extrapolation ratio |t - t_ref| / (t_ref - t_prev).
  real(wp), parameter :: max_extrapolation = 3.0_wp
  integer, parameter :: cg_max_iterations = 60
  integer, parameter :: cg_refactor_iterations = 12

  !> Multipole model that reuses its many-body part across stages and steps within a budget.
  type, extends(multipole_model_t), public :: multipole_adaptive_t
    real(wp) :: tolerance = 0.0_wp               !< integration tolerance (units of d), for the budget
    logical, private :: has_ref = .false.
    real(wp), private :: c_ref(3) = 0.0_wp
    real(wp), private :: h = 0.0_wp               !< trial step size of the stepper (0: none)
    integer, private :: n_hist = 0                 !< earlier refreshes in the history (0..2)
    real(wp), private :: t_ref = 0.0_wp            !< time of the last refresh
    real(wp), private :: t_hist(2) = 0.0_wp        !< times of the two before it (t_prev, t_prev2)
    real(wp), private :: w(2) = 0.0_wp             !< extrapolation weights of the current solve
    !> error / growth (< 0: unknown) with 0, 1 and 2 earlier refreshes in the history
    real(wp), private :: coef(0:2) = -1.0_wp
    type(pair_blocks_t), private :: blocks        !< lubrication blocks of the current call
    real(wp), allocatable, private :: r_ref(:, :) !< reference configuration
    real(wp), allocatable, private :: zl(:, :)    !< zeta_L(ref), full storage
    real(wp), allocatable, private :: xl(:, :)    !< x_L(ref), 6N x 5
    real(wp), allocatable, private :: zh(:, :), xh(:, :) !< their change since the previous refresh
    real(wp), allocatable, private :: zh2(:, :), xh2(:, :) !< the change before that (same frame)
    real(wp), allocatable, private :: pf(:, :)    !< Cholesky factor of the preconditioner
    real(wp), allocatable, private :: fp(:, :)    !< rotated forces
    real(wp), allocatable, private :: us(:, :, :) !< reused velocities of the candidate orders
    real(wp), allocatable, private :: b(:), x(:), rs(:), z(:), p(:), q(:) !< 6N work
    type(hydro_stats_t), private :: rstats   !< the reuse's counters
  contains
    procedure :: setup => adaptive_setup
    procedure :: velocities => adaptive_velocities
    procedure :: step_begin => adaptive_step_begin
    procedure :: statistics => adaptive_statistics
    procedure :: reused_velocities => adaptive_reused_velocities
    procedure :: mobility_reusable => adaptive_mobility_reusable
  end type multipole_adaptive_t

contains

  !> The model's dense arrays for n beads (bytes; a lower bound): the exact model's and four
  !> more 6N x 6N matrices (1152 N^2: the reference, two differences, the preconditioner).
  pure integer(i8) function adaptive_memory_bytes(n, stresslet_lubrication) result(bytes)
    integer(i8), intent(in) :: n
    logical, intent(in) :: stresslet_lubrication
    bytes = multipole_memory_bytes(n, stresslet_lubrication) + 1152_i8*n*n
  end function adaptive_memory_bytes

  !> Order L, lubrication, overlap shift eps_lub and `literal_bwe` (as the exact model) and the
  !> integration tolerance (> 0) that sets the reuse budget.
  subroutine adaptive_setup(this, order, lubrication, eps_lub, tolerance, error, literal_bwe)
    class(multipole_adaptive_t), intent(inout) :: this
    integer, intent(in) :: order
    logical, intent(in) :: lubrication
    real(wp), intent(in) :: eps_lub, tolerance
    type(error_t), allocatable, intent(out) :: error
    logical, intent(in), optional :: literal_bwe
    if (.not. tolerance > 0.0_wp) then
      call fatal_error(error, 'multipole adaptive: tolerance = '//to_str(tolerance, '(es12.4)')//' not allowed (> 0)')
      return
    end if
    call this%multipole_model_t%init(order, lubrication, eps_lub, error, literal_bwe=literal_bwe)
    if (allocated(error)) return
    this%tolerance = tolerance
    this%has_ref = .false.
    this%n_hist = 0
    this%coef = -1.0_wp
    this%rstats = hydro_stats_t()
  end subroutine adaptive_setup

  !> Work arrays for nb beads (a new bead number starts without a reference).
  subroutine ensure_work(this, nb)
    class(multipole_adaptive_t), intent(inout) :: this
    integer, intent(in) :: nb
    if (allocated(this%zl)) then
      if (size(this%zl, 1) == 6*nb) return
      deallocate (this%zl, this%xl, this%zh, this%xh, this%zh2, this%xh2, this%pf, this%r_ref, this%fp, this%us, &
                  this%b, this%x, this%rs, this%z, this%p, this%q)
    end if
    allocate (this%zl(6*nb, 6*nb), this%xl(6*nb, 5), this%zh(6*nb, 6*nb), this%xh(6*nb, 5), &
              this%zh2(6*nb, 6*nb), this%xh2(6*nb, 5), this%pf(6*nb, 6*nb), this%r_ref(3, nb), &
              this%fp(3, nb), this%us(3, nb, 2))
    allocate (this%b(6*nb), this%x(6*nb), this%rs(6*nb), this%z(6*nb), this%p(6*nb), this%q(6*nb))
    this%has_ref = .false.
    this%n_hist = 0
  end subroutine ensure_work

  !> The trial step size of the stepper, from which the reuse budget follows.
  subroutine adaptive_step_begin(this, h)
    class(multipole_adaptive_t), intent(inout) :: this
    real(wp), intent(in) :: h
    this%h = h
  end subroutine adaptive_step_begin

  !> Counters of the reuse: evaluations, refreshes, reused evaluations, CG iterations,
  !> preconditioner factorisations, the largest measured error ratio and the wall times.
  function adaptive_statistics(this) result(s)
    class(multipole_adaptive_t), intent(in) :: this
    type(hydro_stats_t) :: s
    s = this%rstats
  end function adaptive_statistics

  !> u = mu(r) f + C(r):e at time t with the reuse of the many-body part (which needs t and a
  !> step size from step_begin; else exact).
  subroutine adaptive_velocities(this, r, f, u, error, e, t, pairs)
    class(multipole_adaptive_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :)
    real(wp), intent(out) :: u(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in), optional :: e(3, 3), t
    type(pair_geometry_t), intent(in), optional :: pairs
    real(wp) :: ez(3, 3)
    integer(i8) :: c0, c1, crate, refreshes

    this%rstats%evaluations = this%rstats%evaluations + 1
    ez = 0.0_wp
    if (present(e)) ez = e
    call system_clock(c0, crate)
    refreshes = this%rstats%refreshes
    call reuse_or_refresh(this, r, f, ez, u, error, t, pairs)
    call system_clock(c1)
    if (this%rstats%refreshes > refreshes) then
      this%rstats%refresh_seconds = this%rstats%refresh_seconds + real(c1 - c0, wp)/real(crate, wp)
    else
      this%rstats%reused_seconds = this%rstats%reused_seconds + real(c1 - c0, wp)/real(crate, wp)
    end if
  end subroutine adaptive_velocities

  !> The rule of the module header (ez: the rate of strain, zero without strain).
  subroutine reuse_or_refresh(this, r, f, ez, u, error, t, pairs)
    class(multipole_adaptive_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :), ez(3, 3)
    real(wp), intent(out) :: u(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in), optional :: t
    type(pair_geometry_t), intent(in), optional :: pairs
    real(wp) :: qrot(3, 3), deform, budget, err, predicted, w(2), ratio, gk(2)
    logical :: converged, ok(2)
    integer :: k, lo, hi, order

    call ensure_work(this, size(r, 2))
    budget = 0.0_wp
    if (this%h > 0.0_wp .and. present(t)) budget = budget_fraction*this%tolerance/this%h
    if (.not. this%has_ref .or. budget <= 0.0_wp) then
      this%has_ref = .false.   ! no history across an exact call
      if (present(t)) then
        call refresh(this, r, f, ez, t, u, error, pairs)
      else
        call refresh(this, r, f, ez, 0.0_wp, u, error, pairs)
      end if
      return
    end if
    call best_rotation(this%r_ref, r, qrot, error)
    if (allocated(error)) return
    call measure_deformation(this, r, qrot, deform)
    ! The candidate orders: the highest the history allows (n_hist) and the one below it; the
    ! one with the smaller predicted error is used (an order not calibrated yet forces a
    ! refresh, which calibrates it).
    lo = max(this%n_hist - 1, 0)
    hi = this%n_hist
    ratio = 0.0_wp
    if (hi > 0) ratio = abs(t - this%t_ref)/(this%t_ref - this%t_hist(1))
    predicted = huge(1.0_wp)
    order = -1
    do k = lo, hi
      gk(k - lo + 1) = growth(this, t, k)
      if (this%coef(k) >= 0.0_wp .and. this%coef(k)*gk(k - lo + 1) < predicted) then
        predicted = this%coef(k)*gk(k - lo + 1)
        order = k
      end if
    end do
    if (any(this%coef(lo:hi) < 0.0_wp)) order = -1
    if (order >= 0 .and. predicted <= budget .and. deform <= max_deformation .and. &
        ratio <= max_extrapolation) then
      w = extrapolation_weights(t, this%t_ref, this%t_hist, order)
      call reused_solve(this, r, f, ez, qrot, w, budget, u, converged, pairs)
      if (converged) then
        this%rstats%reused = this%rstats%reused + 1
        return
      end if
      call refresh(this, r, f, ez, t, u, error, pairs)
      return
    end if
    ! Refresh; measure first the error of the reused part of each candidate order here, to
    ! calibrate the rule.
    do k = lo, hi
      w = extrapolation_weights(t, this%t_ref, this%t_hist, k)
      call reused_solve(this, r, f, ez, qrot, w, budget, this%us(:, :, k - lo + 1), ok(k - lo + 1), pairs)
    end do
    call refresh(this, r, f, ez, t, u, error, pairs)
    if (allocated(error)) return
    do k = lo, hi
      if (.not. ok(k - lo + 1) .or. gk(k - lo + 1) <= 0.0_wp) cycle
      err = maxval(norm2(this%us(:, :, k - lo + 1) - u, dim=1))
      if (k == order .and. predicted > 0.0_wp) &
        this%rstats%max_error_ratio = max(this%rstats%max_error_ratio, err/predicted)
      this%coef(k) = max(err/gk(k - lo + 1), 0.5_wp*this%coef(k))
    end do
  end subroutine reuse_or_refresh

  !> u from the many-body part of the last refresh as it is (no extrapolation, no refresh):
  !> what the adaptive path returns when it reuses that part at r. For tests and measurements;
  !> needs a refresh first (a velocities call), else returns an error.
  subroutine adaptive_reused_velocities(this, r, f, u, error, e)
    class(multipole_adaptive_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :)
    real(wp), intent(out) :: u(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in), optional :: e(3, 3)
    real(wp) :: ez(3, 3), qrot(3, 3), deform
    logical :: converged
    if (.not. this%has_ref) then
      call fatal_error(error, 'multipole: no reference to reuse (update = adaptive, after a velocities call)')
      return
    end if
    if (size(r, 2) /= size(this%r_ref, 2)) then
      call fatal_error(error, 'multipole: reused_velocities for another number of beads')
      return
    end if
    ez = 0.0_wp
    if (present(e)) ez = e
    call best_rotation(this%r_ref, r, qrot, error)
    if (allocated(error)) return
    call measure_deformation(this, r, qrot, deform)
    call reused_solve(this, r, f, ez, qrot, [0.0_wp, 0.0_wp], 1.0e-3_wp*this%tolerance, u, converged)
    if (.not. converged) call fatal_error(error, 'multipole: conjugate gradients did not converge')
  end subroutine adaptive_reused_velocities

  !> The growth factor of the reuse error at time t for extrapolation order k (0..n_hist):
  !> |t - t_ref| for a reused many-body part, times |t - t_prev| for one extrapolated from the
  !> last two refreshes and |t - t_prev2| from the last three (the error of polynomial
  !> interpolation through the refresh times).
  pure real(wp) function growth(this, t, k) result(g)
    class(multipole_adaptive_t), intent(in) :: this
    real(wp), intent(in) :: t
    integer, intent(in) :: k
    g = abs(t - this%t_ref)*product(abs(t - this%t_hist(1:k)))
  end function growth

  !> Newton weights of the extrapolation in time through the last refresh (t_ref) and the
  !> n_hist (0..2) before it (t_hist(1) = t_prev, t_hist(2) = t_prev2): a quantity z known at
  !> those times is z(t) = z_ref + w(1) (z_ref - z_prev) + w(2) (z_prev - z_prev2), exactly
  !> for a polynomial in t of degree n_hist. Times must differ.
  pure function extrapolation_weights(t, t_ref, t_hist, n_hist) result(w)
    real(wp), intent(in) :: t, t_ref, t_hist(2)
    integer, intent(in) :: n_hist
    real(wp) :: w(2), d1, d2
    w = 0.0_wp
    if (n_hist < 1) return
    d1 = t_ref - t_hist(1)
    w(1) = (t - t_ref)/d1
    if (n_hist < 2) return
    d2 = (t - t_ref)*(t - t_hist(1))/(t_ref - t_hist(2))
    w(1) = w(1) + d2/d1
    w(2) = -d2/(t_hist(1) - t_hist(2))
  end function extrapolation_weights

  !> The deformation D = max_i |rp_i - r_ref,i| of r since the reference, with
  !> rp = Q^T (r - c) + c_ref the configuration r rotated onto the reference.
  subroutine measure_deformation(this, r, qrot, deform)
    class(multipole_adaptive_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :), qrot(3, 3)
    real(wp), intent(out) :: deform
    real(wp) :: c(3), qt(3, 3)
    integer :: i
    c = centroid(r)
    qt = transpose(qrot)
    deform = 0.0_wp
    do i = 1, size(r, 2)
      deform = max(deform, norm2(matmul(qt, r(:, i) - c) + this%c_ref - this%r_ref(:, i)))
    end do
  end subroutine measure_deformation

  !> Exact velocities at r, which becomes the reference: the exact model's many-body part
  !> zeta_L, x_L at r (and, when there was a reference, its change since it, the old part
  !> rotated into the new frame: the history for the extrapolation), factorise
  !> zeta_L + sum dzeta (the preconditioner) and solve; t is the time of r.
  subroutine refresh(this, r, f, e, t, u, error, pairs)
    class(multipole_adaptive_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :), e(3, 3), t
    real(wp), intent(out) :: u(:, :)
    type(error_t), allocatable, intent(out) :: error
    type(pair_geometry_t), intent(in), optional :: pairs
    real(wp) :: qrot(3, 3)
    logical :: history
    integer :: i
    ! history: the new part minus the old one seen from the new frame, and the old change seen
    ! from the new frame (two refreshes at the same time, e.g. the last two stages of a step,
    ! give none). The old part is rotated into zh, xh before the new one replaces it.
    history = this%has_ref .and. t /= this%t_ref
    if (history) then
      call best_rotation(this%r_ref, r, qrot, error)
      if (allocated(error)) return
      if (this%n_hist > 0) then
        call rotate_blocks(qrot, this%zh, this%zh2)
        call rotate_coupling(qrot, this%xh, this%xh2)
        this%t_hist(2) = this%t_hist(1)
      end if
      call rotate_blocks(qrot, this%zl, this%zh)
      call rotate_coupling(qrot, this%xl, this%xh)
      this%n_hist = min(this%n_hist + 1, 2)
      this%t_hist(1) = this%t_ref
    else
      this%n_hist = 0
    end if
    this%has_ref = .false.   ! until the new reference is complete
    call this%many_body_part(r, this%zl, this%xl, error)
    if (allocated(error)) return
    if (history) then
      this%zh = this%zl - this%zh
      this%xh = this%xl - this%xh
    end if
    this%t_ref = t
    this%r_ref = r
    this%c_ref = centroid(r)
    call factor_preconditioner(this, r, [0.0_wp, 0.0_wp], error, pairs)
    if (allocated(error)) return
    call right_hand_side(this, f, e, [0.0_wp, 0.0_wp])
    this%x = this%b
    call cholesky_solve(this%pf, this%x)
    do i = 1, size(r, 2)
      u(:, i) = this%x(6*i - 5:6*i - 3)
    end do
    this%has_ref = .true.
    this%rstats%refreshes = this%rstats%refreshes + 1
  end subroutine refresh

  !> xo = the strain coupling (6N x 5, basis strains) of a configuration rotated by q:
  !> x(Q r)[E] = Q x(r)[Q^T E Q] blockwise.
  subroutine rotate_coupling(q, xi, xo)
    real(wp), intent(in) :: q(3, 3), xi(:, :)
    real(wp), intent(out) :: xo(:, :)
    real(wp) :: m(5, 5), t(size(xi, 1), 5)
    integer :: k, a
    do k = 1, 5
      m(:, k) = strain_coefficients(matmul(transpose(q), matmul(strain_basis(k), q)))
    end do
    t = matmul(xi, m)
    do a = 1, size(xi, 1)/3
      xo(3*a - 2:3*a, :) = matmul(q, t(3*a - 2:3*a, :))
    end do
  end subroutine rotate_coupling

  !> pf = Cholesky factor of zeta_L(ref) + w1 zh + w2 zh2 + sum dzeta(Q rr), Q = rotation or 1;
  !> the pair list is left at Q rr. `pairs`: the close pairs of rr if the caller has them.
  subroutine factor_preconditioner(this, rr, w, error, pairs, rotation)
    class(multipole_adaptive_t), intent(inout) :: this
    real(wp), intent(in) :: rr(:, :), w(2)
    type(error_t), allocatable, intent(out) :: error
    type(pair_geometry_t), intent(in), optional :: pairs
    real(wp), intent(in), optional :: rotation(3, 3)
    this%pf = this%zl
    if (w(1) /= 0.0_wp) this%pf = this%pf + w(1)*this%zh
    if (w(2) /= 0.0_wp) this%pf = this%pf + w(2)*this%zh2
    if (this%lubrication) then
      call this%lub%pair_blocks(rr, this%blocks, pairs, rotation)
      call this%blocks%add_friction(this%pf)
      this%n_lub_pairs = this%blocks%n_pairs()
    end if
    call cholesky_factor(this%pf, error, 'lubrication-corrected friction')
  end subroutine factor_preconditioner

  !> b = [f_i; 0] + (x_L(ref) + w1 xh + w2 xh2) : e + sum dx : e (the pair list at the current
  !> configuration).
  subroutine right_hand_side(this, f, e, w)
    class(multipole_adaptive_t), intent(inout) :: this
    real(wp), intent(in) :: f(:, :), e(3, 3), w(2)
    real(wp) :: c(5)
    integer :: i, nb
    nb = size(f, 2)
    do i = 1, nb
      this%b(6*i - 5:6*i - 3) = f(:, i)
      this%b(6*i - 2:6*i) = 0.0_wp
    end do
    c = strain_coefficients(e)
    call dgemv('N', 6*nb, 5, 1.0_wp, this%xl, 6*nb, c, 1, 1.0_wp, this%b, 1)
    if (w(1) /= 0.0_wp) call dgemv('N', 6*nb, 5, w(1), this%xh, 6*nb, c, 1, 1.0_wp, this%b, 1)
    if (w(2) /= 0.0_wp) call dgemv('N', 6*nb, 5, w(2), this%xh2, 6*nb, c, 1, 1.0_wp, this%b, 1)
    if (this%lubrication) call this%blocks%add_strain(e, this%b)
  end subroutine right_hand_side

  !> Velocities from the reused many-body part (extrapolated with the weights w) at r seen in the
  !> reference frame (rotation qrot: the aligned configuration rp of `measure_deformation`):
  !> lubrication of the rotated pairs, conjugate gradients on
  !> (zeta_L(ref) + w1 zh + w2 zh2 + sum dzeta) U = b. `converged` is false when CG did not reach
  !> the stopping error. `pairs`: the close pairs of r if the caller has them.
  subroutine reused_solve(this, r, f, e, qrot, w, budget, u, converged, pairs)
    class(multipole_adaptive_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :), e(3, 3), qrot(3, 3), w(2), budget
    real(wp), intent(inout) :: u(:, :)
    logical, intent(out) :: converged
    type(pair_geometry_t), intent(in), optional :: pairs
    type(error_t), allocatable :: error
    real(wp) :: qt(3, 3), rz, rz_new, alpha
    integer :: i, nb, it

    nb = size(f, 2)
    qt = transpose(qrot)
    do i = 1, nb
      this%fp(:, i) = matmul(qt, f(:, i))
    end do
    if (this%lubrication) call this%lub%pair_blocks(r, this%blocks, pairs, qt)
    call right_hand_side(this, this%fp, matmul(qt, matmul(e, qrot)), w)
    this%w = w
    ! Preconditioned CG from x = P^-1 b.
    this%x = this%b
    call cholesky_solve(this%pf, this%x)
    call operator_apply(this, this%x, this%q)
    this%rs = this%b - this%q
    this%z = this%rs
    call cholesky_solve(this%pf, this%z)
    converged = largest_velocity(this%z, nb) <= cg_fraction*budget
    this%p = this%z
    rz = dot_product(this%rs, this%z)
    it = 0
    do while (.not. converged .and. it < cg_max_iterations)
      it = it + 1
      call operator_apply(this, this%p, this%q)
      alpha = rz/dot_product(this%p, this%q)
      this%x = this%x + alpha*this%p
      this%rs = this%rs - alpha*this%q
      this%z = this%rs
      call cholesky_solve(this%pf, this%z)
      converged = largest_velocity(this%z, nb) <= cg_fraction*budget
      rz_new = dot_product(this%rs, this%z)
      this%p = this%z + (rz_new/rz)*this%p
      rz = rz_new
    end do
    this%rstats%cg_iterations = this%rstats%cg_iterations + it
    if (.not. converged) return
    do i = 1, nb
      u(:, i) = matmul(qrot, this%x(6*i - 5:6*i - 3))
    end do
    if (it > cg_refactor_iterations) then
      call factor_preconditioner(this, r, w, error, pairs, qt)
      this%rstats%preconditioners = this%rstats%preconditioners + 1
      if (allocated(error)) this%has_ref = .false.   ! refresh at the next call
    end if
  end subroutine reused_solve

  !> y = (zeta_L(ref) + w1 zh + w2 zh2 + sum dzeta) x.
  subroutine operator_apply(this, xv, y)
    class(multipole_adaptive_t), intent(inout) :: this
    real(wp), intent(in) :: xv(:)
    real(wp), intent(out) :: y(:)
    integer :: n6
    n6 = size(xv)
    call dsymv('L', n6, 1.0_wp, this%zl, n6, xv, 1, 0.0_wp, y, 1)
    if (this%w(1) /= 0.0_wp) call dsymv('L', n6, this%w(1), this%zh, n6, xv, 1, 1.0_wp, y, 1)
    if (this%w(2) /= 0.0_wp) call dsymv('L', n6, this%w(2), this%zh2, n6, xv, 1, 1.0_wp, y, 1)
    if (this%lubrication) call this%blocks%apply(xv, y)
  end subroutine operator_apply

  !> It reuses work across calls and a new mobility costs a factorisation: a user of the
  !> mobility (the dynamics' Jacobian) may keep an earlier one.
  pure logical function adaptive_mobility_reusable(this) result(reusable)
    class(multipole_adaptive_t), intent(in) :: this
    reusable = .true.
    associate (unused_this => this)
    end associate
  end function adaptive_mobility_reusable

end module kf_hydro_multipole_adaptive
