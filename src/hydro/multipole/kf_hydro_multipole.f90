!> The multipole hydrodynamic model (PHYSICS.md 3.3): N-sphere induced-force multipoles
!> truncated at order L, optionally with two-sphere lubrication corrections (HYDROLIB scheme,
!> MULTIPOLE.md 13.3) and an overlap treatment: by default (overlap rules 'pair', 'separate',
!> 'relax') a pair closer than 1 + eps_lub has its multipole blocks and its lubrication
!> correction evaluated at 1 + eps_lub; with `literal_bwe` (overlap = 'bwe', PHYSICS.md 3.3) the
!> many-body system is that of the real positions and only the lubrication correction of a pair
!> with r <= 1 is evaluated at 1 + eps_lub.
!>
!> In parts: the many-body system (kf_multipole_system: assembly, p-moment elimination,
!> Cholesky factorisation, then its friction zeta_L and strain coupling x_L), the lubrication
!> corrections as a list of 12 x 12 pair blocks (kf_pair_blocks), and the corrected friction
!> route zeta = zeta_L + sum dzeta, x = x_L + sum dx, U - U_inf = zeta^-1 (F + x:E).
!>
!> Two ways to get velocities, chosen once at set-up (`&hydro update`; the third, 'iterative',
!> is its own type extending this one, kf_hydro_multipole_iterative):
!> * 'stage': `prepare(r)` at every call does all of the above and caches the 3N x 3N mobility
!>   and the strain disturbances (also what `prepare`/`apply_mobility`/`mobility_matrix` do in
!>   either mode). The reference.
!> * 'adaptive' (docs/multipole.md): the many-body part zeta_L, x_L is computed exactly at a
!>   refresh and reused at later stages, while the lubrication corrections are exact at every
!>   call. The current configuration is rotated onto the reference by the best rigid rotation
!>   Q (kf_rigid_fit; Stokes flow is covariant, so rigid tumbling costs no accuracy), forces and
!>   strain with it, the velocities back. With earlier refreshes in the history the part is
!>   extrapolated in time by the polynomial through the last k + 1 refreshes (order k = 1:
!>   linear through the last two, k = 2: quadratic through the last three):
!>   zeta_L(ref) + w1 dzeta_1 + w2 dzeta_2, with dzeta_1 = zeta_ref - zeta_prev and dzeta_2 =
!>   zeta_prev - zeta_prev2 seen from the reference frame and the Newton weights of
!>   `extrapolation_weights`. The corrected system is solved by conjugate gradients
!>   preconditioned with the Cholesky factor at the refresh (re-factorised when CG needs more
!>   than `cg_refactor_iterations`), to a velocity error below cg_fraction of the budget.
!>   Refresh rule: the budget on the velocity error of a stage is
!>   budget_fraction * tolerance / h (h the stepper's trial step): it moves a bead by less than
!>   budget_fraction of the tolerance in one step. The error of order k is predicted as
!>   coef_k |t - t_ref| prod_j<=k |t - t_hist(j)| (the error of polynomial interpolation);
!>   every refresh after the first also computes the reused velocities of the two candidate
!>   orders (the highest the history allows and the one below) at the new configuration and
!>   compares them with the exact ones, which recalibrates their coefficients (max over
!>   beads, never below half the old value). A call uses the candidate with the smaller
!>   prediction, and refreshes when that exceeds the budget, when a candidate is not calibrated
!>   yet, when |t - t_ref| > 3 (t_ref - t_prev), when the deformation after the rigid fit
!>   exceeds max_deformation, or when CG does not converge.
!>   Without a step size or a time (calls outside a stepper) every call is exact.
!>
!> The stresslet (`stresslet`, MULTIPOLE.md 9, 11, 13.3) is exact at the configuration given,
!> in either update mode, and leaves the reuse state alone: a frame's stresslet costs one
!> assembly and factorisation (plus, with lubrication, one grand friction). With the grand
!> resistance (F, T, S) = Xi (U_inf - U, Omega_inf - Omega, E), symmetric (Xi_SU = Xi_FE^T), the
!> beads' total stresslet paired with a basis strain B_k is
!>   S : B_k = sum_l Xi_SE(k, l) c_l(E) - V . x_k,   V = zeta^-1 (F + x c(E)),
!> with x_k = Xi_FE : B_k. Without lubrication this is gram c - F . D_k (D the free-sphere
!> disturbance; kf_multipole_system `strain_disturbance`). With lubrication zeta, x are the
!> corrected ones and Xi_SE = gram + D^T x_L + the pair corrections of the M functions
!> (kf_lubrication `stresslet_correction`), as HYDROLIB corrects the whole grand resistance.
module kf_hydro_multipole
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str
  use kf_blas, only: dgemv, dsymv
  use kf_lapack, only: cholesky_factor, cholesky_solve, cholesky_invert
  use kf_error, only: error_t, fatal_error
  use kf_hydro_model, only: hydro_model_t, hydro_stats_t
  use kf_multipole_system, only: multipole_system_t
  use kf_strain_basis, only: strain_coefficients, strain_basis, tensor_from_pairings
  use kf_lubrication, only: lubrication_t
  use kf_pair_blocks, only: pair_blocks_t
  use kf_pair_geometry, only: pair_geometry_t
  use kf_rigid_fit, only: best_rotation, centroid
  use kf_scene_hydro, only: update_stage, update_adaptive, update_iterative
  use kf_hydro_limits, only: eps_lub_in_range, eps_lub_range_text
  implicit none
  private

  public :: extrapolation_weights, multipole_memory_bytes, largest_velocity

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

  !> Multipole model of order L with or without lubrication corrections.
  type, extends(hydro_model_t), public :: multipole_model_t
    integer :: order = 2
    logical :: lubrication = .false.
    logical :: adaptive = .false.         !< update = 'adaptive'
    logical :: literal_bwe = .false.      !< overlap = 'bwe': no clamp of the many-body system
    real(wp) :: eps_lub = 1.0e-4_wp      !< overlap shift: overlapping pairs are evaluated at 1 + eps_lub
    real(wp) :: tolerance = 1.0e-4_wp    !< integration tolerance (units of d), for the budget
    type(multipole_system_t), private :: sys
    type(lubrication_t) :: lub
    integer :: n_lub_pairs = 0           !< pairs corrected at the last prepare
    !> pairs whose many-body blocks were clamped to 1 + eps_lub at the last prepare (none with literal_bwe)
    integer :: n_overlaps = 0
    real(wp), private :: t_lubrication = 0.0_wp   !< seconds in the lubrication part of the last prepare
    type(pair_blocks_t), private :: pairs
    real(wp), allocatable, private :: mu(:, :)    !< 3N x 3N translational mobility
    real(wp), allocatable, private :: r_prepared(:, :) !< the positions mu belongs to (valid when n > 0)
    real(wp), allocatable, private :: dist(:, :)  !< 3N x 5 disturbance for the basis strains
    real(wp), allocatable, private :: zt(:, :), x6(:, :) !< 6N x 6N, 6N x 5 friction route work
    real(wp), allocatable, private :: v3(:), w3(:)       !< 3N work
    ! adaptive reuse
    logical, private :: has_ref = .false.
    real(wp), private :: c_ref(3) = 0.0_wp
    real(wp), private :: h = 0.0_wp               !< trial step size of the stepper (0: none)
    integer, private :: n_hist = 0                 !< earlier refreshes in the history (0..2)
    real(wp), private :: t_ref = 0.0_wp            !< time of the last refresh
    real(wp), private :: t_hist(2) = 0.0_wp        !< times of the two before it (t_prev, t_prev2)
    real(wp), private :: w(2) = 0.0_wp             !< extrapolation weights of the current solve
    !> error / growth (< 0: unknown) with 0, 1 and 2 earlier refreshes in the history
    real(wp), private :: coef(0:2) = -1.0_wp
    real(wp), allocatable, private :: r_ref(:, :) !< reference configuration
    real(wp), allocatable, private :: zl(:, :)    !< zeta_L(ref), full storage
    real(wp), allocatable, private :: xl(:, :)    !< x_L(ref), 6N x 5
    real(wp), allocatable, private :: zh(:, :), xh(:, :) !< their change since the previous refresh
    real(wp), allocatable, private :: zh2(:, :), xh2(:, :) !< the change before that (same frame)
    real(wp), allocatable, private :: pf(:, :)    !< Cholesky factor of the preconditioner
    real(wp), allocatable, private :: fp(:, :)    !< rotated forces
    real(wp), allocatable, private :: us(:, :, :) !< reused velocities of the candidate orders
    real(wp), allocatable, private :: b(:), x(:), rs(:), z(:), p(:), q(:), xs(:) !< 6N work
    type(hydro_stats_t), private :: stats
  contains
    procedure :: init => multipole_init
    procedure :: prepare => multipole_prepare
    procedure :: apply_mobility => multipole_apply
    procedure :: add_strain_disturbance => multipole_disturbance
    procedure :: name => multipole_name
    procedure :: mobility_matrix => multipole_mobility_matrix
    procedure :: mobility_at => multipole_mobility_at
    procedure :: mobility_cached => multipole_mobility_cached
    procedure :: mobility_reusable => multipole_mobility_reusable
    procedure :: friction_matrix => multipole_friction_matrix
    procedure :: velocities => multipole_velocities
    procedure :: pair_cutoff => multipole_pair_cutoff
    procedure :: step_begin => multipole_step_begin
    procedure :: statistics => multipole_statistics
    procedure :: reused_velocities => multipole_reused_velocities
    procedure :: stresslet => multipole_stresslet
    procedure :: prepare_seconds => multipole_prepare_seconds
    procedure :: many_body_spectrum => multipole_many_body_spectrum
  end type multipole_model_t

contains

  !> The model's dense arrays for n beads (bytes; a lower bound: the many-body system comes on
  !> top): the 3N x 3N mobility and 6N x 6N friction (360 N^2), four more 6N x 6N matrices with
  !> `adaptive` (1152 N^2: the reference, two differences, the preconditioner), one more
  !> (288 N^2) for the stresslet's grand friction with lubrication (`stresslet_lubrication`).
  pure integer(i8) function multipole_memory_bytes(n, adaptive, stresslet_lubrication) result(bytes)
    integer(i8), intent(in) :: n
    logical, intent(in) :: adaptive, stresslet_lubrication
    bytes = 360_i8*n*n
    if (adaptive) bytes = bytes + 1152_i8*n*n
    if (stresslet_lubrication) bytes = bytes + 288_i8*n*n
  end function multipole_memory_bytes

  !> Order L (1..max_multipole_order), lubrication on/off, overlap shift eps_lub (kf_hydro_limits), update mode
  !> ('stage', the default, or 'adaptive') and the integration tolerance (> 0, default 1e-4)
  !> that sets the reuse budget; `literal_bwe` (default .false.): the literal BWE rule (module
  !> header) instead of the clamp.
  subroutine multipole_init(this, order, lubrication, eps_lub, error, update, tolerance, literal_bwe)
    class(multipole_model_t), intent(inout) :: this
    integer, intent(in) :: order
    logical, intent(in) :: lubrication
    real(wp), intent(in) :: eps_lub
    type(error_t), allocatable, intent(out) :: error
    character(len=*), intent(in), optional :: update
    real(wp), intent(in), optional :: tolerance
    logical, intent(in), optional :: literal_bwe
    character(len=:), allocatable :: mode
    real(wp) :: tol

    if (.not. eps_lub_in_range(eps_lub)) then
      call fatal_error(error, 'multipole: eps_lub = '//to_str(eps_lub, '(es12.4)')// &
                       ' not allowed (outside '//eps_lub_range_text()//')')
      return
    end if
    mode = update_stage
    if (present(update)) mode = update
    tol = 1.0e-4_wp
    if (present(tolerance)) tol = tolerance
    if (.not. tol > 0.0_wp) then
      call fatal_error(error, 'multipole: tolerance = '//to_str(tol, '(es12.4)')//' not allowed (> 0)')
      return
    end if
    select case (mode)
    case (update_stage)
      this%adaptive = .false.
    case (update_adaptive)
      this%adaptive = .true.
    case default
      call fatal_error(error, "multipole: update = '"//mode//"' is not a mode of this type (allowed: '"// &
                       update_stage//"', '"//update_adaptive//"'; '"//update_iterative//"' is kf_hydro_multipole_iterative)")
      return
    end select
    this%literal_bwe = .false.
    if (present(literal_bwe)) this%literal_bwe = literal_bwe
    if (lubrication) then
      call this%lub%init(order, eps_lub, error, literal_bwe=this%literal_bwe)
      if (allocated(error)) return
    end if
    this%order = order
    this%lubrication = lubrication
    this%eps_lub = eps_lub
    this%tolerance = tol
    this%n = 0
    this%has_ref = .false.
    this%n_hist = 0
    this%coef = -1.0_wp
    this%stats = hydro_stats_t()
    ! min_distance 0: the many-body system of the real positions (no pair clamped)
    call this%sys%init(order, merge(0.0_wp, 1.0_wp + eps_lub, this%literal_bwe), error)
  end subroutine multipole_init

  !> Work arrays for nb beads.
  subroutine ensure_work(this, nb)
    class(multipole_model_t), intent(inout) :: this
    integer, intent(in) :: nb
    if (allocated(this%zt)) then
      if (size(this%zt, 1) == 6*nb) return
      deallocate (this%mu, this%dist, this%zt, this%x6, this%v3, this%w3)
      if (allocated(this%zl)) deallocate (this%zl, this%xl, this%zh, this%xh, this%zh2, this%xh2, this%pf, &
                                          this%r_ref, this%fp, this%us, &
                                          this%b, this%x, this%rs, this%z, this%p, this%q, this%xs)
    end if
    allocate (this%mu(3*nb, 3*nb), this%dist(3*nb, 5), this%zt(6*nb, 6*nb), this%x6(6*nb, 5), &
              this%v3(3*nb), this%w3(3*nb))
    if (this%adaptive) then
      allocate (this%zl(6*nb, 6*nb), this%xl(6*nb, 5), this%zh(6*nb, 6*nb), this%xh(6*nb, 5), &
                this%zh2(6*nb, 6*nb), this%xh2(6*nb, 5), this%pf(6*nb, 6*nb), this%r_ref(3, nb), &
                this%fp(3, nb), this%us(3, nb, 2))
      allocate (this%b(6*nb), this%x(6*nb), this%rs(6*nb), this%z(6*nb), this%p(6*nb), this%q(6*nb), &
                this%xs(6*nb))
    end if
    this%has_ref = .false.
    this%n_hist = 0
  end subroutine ensure_work

  !> Assemble and factorise for bead centres r(3, N); cache mu and the strain disturbances
  !> (exact at r, in either update mode).
  subroutine multipole_prepare(this, r, error, pairs)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    type(pair_geometry_t), intent(in), optional :: pairs
    integer :: nb, j, i

    nb = size(r, 2)
    call ensure_work(this, nb)
    this%n = 0
    call this%sys%factorise(r, error)
    if (allocated(error)) return
    this%n_overlaps = this%sys%n_clamped
    if (.not. this%lubrication) then
      ! Schur route: the mobility directly from the factorised system.
      call this%sys%translational_mobility(this%mu)
      call this%sys%strain_disturbance(this%x6)
      do j = 1, nb
        this%dist(3*j - 2:3*j, 1:5) = this%x6(6*j - 5:6*j - 3, 1:5)
      end do
      this%r_prepared = r
      this%n = nb
      return
    end if
    call corrected_system(this, r, this%zt, this%x6, error, pairs)
    if (allocated(error)) return
    ! zt -> zeta^-1 (full), x6 -> zeta^-1 x: the translational blocks are mu and dist.
    call cholesky_solve(this%zt, this%x6)
    call cholesky_invert(this%zt, error, 'lubrication-corrected friction')
    if (allocated(error)) return
    do j = 1, nb
      do i = 1, nb
        this%mu(3*i - 2:3*i, 3*j - 2:3*j) = this%zt(6*i - 5:6*i - 3, 6*j - 5:6*j - 3)
      end do
      this%dist(3*j - 2:3*j, 1:5) = this%x6(6*j - 5:6*j - 3, 1:5)
    end do
    this%r_prepared = r
    this%n = nb
  end subroutine multipole_prepare

  !> For a factorised system at r: zeta = zeta_L + sum dzeta (Cholesky-factorised in place,
  !> lower triangle) and x = x_L + sum dx for the basis strains; the pair list is left at r.
  subroutine corrected_system(this, r, zeta, x, error, pairs)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(inout) :: zeta(:, :), x(:, :)
    type(error_t), allocatable, intent(out) :: error
    type(pair_geometry_t), intent(in), optional :: pairs
    real(wp) :: bas(3, 3, 5)
    integer :: k
    integer(i8) :: c0, c1, crate

    call this%sys%friction_coupling(zeta, x, error)
    if (allocated(error)) return
    call system_clock(c0, crate)
    if (this%lubrication) then
      do k = 1, 5
        bas(:, :, k) = strain_basis(k)
      end do
      call this%lub%pair_blocks(r, this%pairs, pairs)
      call this%pairs%add_friction(zeta)
      call this%pairs%add_strain_basis(bas, x)
      this%n_lub_pairs = this%pairs%n_pairs()
    end if
    call system_clock(c1)
    this%t_lubrication = real(c1 - c0, wp)/real(crate, wp)
    call cholesky_factor(zeta, error, 'lubrication-corrected friction')
  end subroutine corrected_system

  !> The eigenvalues (ascending) of the many-body system the model factorises at r (scaled real
  !> form, kf_multipole_system `spectrum`: positive definite exactly when prepare's first
  !> Cholesky factorisation succeeds) and `n_overlapping`, its pairs at r <= 1. Leaves the model
  !> unprepared. For diagnostics (knotflow-mobility --output spectrum).
  subroutine multipole_many_body_spectrum(this, r, w, n_overlapping, error)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), allocatable, intent(out) :: w(:)
    integer, intent(out) :: n_overlapping
    type(error_t), allocatable, intent(out) :: error
    this%n = 0
    call this%sys%spectrum(r, w, error)
    n_overlapping = this%sys%n_overlapping
  end subroutine multipole_many_body_spectrum

  !> u = mu f.
  subroutine multipole_apply(this, f, u)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: f(:, :)
    real(wp), intent(out) :: u(:, :)
    integer :: n3
    n3 = 3*this%n
    this%v3 = reshape(f(:, 1:this%n), [n3])
    call dgemv('N', n3, n3, 1.0_wp, this%mu, n3, this%v3, 1, 0.0_wp, this%w3, 1)
    u(:, 1:this%n) = reshape(this%w3, [3, this%n])
  end subroutine multipole_apply

  !> u = u + C:E for the symmetric traceless rate of strain e.
  subroutine multipole_disturbance(this, e, u)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: e(3, 3)
    real(wp), intent(inout) :: u(:, :)
    real(wp) :: c(5)
    integer :: i
    c = strain_coefficients(e)
    do i = 1, this%n
      u(:, i) = u(:, i) + matmul(this%dist(3*i - 2:3*i, :), c)
    end do
  end subroutine multipole_disturbance

  !> "multipole L=<order>" plus " lubrication" when corrections are on.
  function multipole_name(this) result(label)
    class(multipole_model_t), intent(in) :: this
    character(len=:), allocatable :: label
    label = 'multipole L='//to_str(this%order)
    if (this%lubrication) label = label//' lubrication'
  end function multipole_name

  !> The cached 3N x 3N mobility.
  subroutine multipole_mobility_matrix(this, mu)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(out) :: mu(:, :)
    mu = this%mu
  end subroutine multipole_mobility_matrix

  !> The 3N x 3N mobility at r: the cached one when the last prepare was at exactly r (as after
  !> a 'stage' evaluation there), else prepare at r first.
  subroutine multipole_mobility_at(this, r, mu, error)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: mu(:, :)
    type(error_t), allocatable, intent(out) :: error
    if (.not. this%mobility_cached(r)) then
      call this%prepare(r, error)
      if (allocated(error)) return
    end if
    mu = this%mu
  end subroutine multipole_mobility_at

  !> Was the last prepare at exactly r (and is its mobility still held)?
  logical function multipole_mobility_cached(this, r) result(cached)
    class(multipole_model_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :)
    cached = this%n == size(r, 2) .and. allocated(this%r_prepared)
    if (cached) cached = all(shape(this%r_prepared) == shape(r))
    if (cached) cached = all(this%r_prepared == r)
  end function multipole_mobility_cached

  !> The adaptive reuse keeps work across calls and a new mobility costs a factorisation: an
  !> earlier one may be kept ('stage' prepares at every call, its mobility is at hand).
  pure logical function multipole_mobility_reusable(this) result(reusable)
    class(multipole_model_t), intent(in) :: this
    reusable = this%adaptive
  end function multipole_mobility_reusable

  !> The 6N x 6N generalised friction [F; T] = zeta [U; Omega] (project units, ordering
  !> [U_1, Omega_1, U_2, ...]) at the last prepare, including the lubrication corrections.
  subroutine multipole_friction_matrix(this, zeta, error)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(out) :: zeta(:, :)
    type(error_t), allocatable, intent(out) :: error
    call this%sys%grand_friction(zeta, error)
    if (allocated(error)) return
    if (this%lubrication) call this%pairs%add_friction(zeta)
  end subroutine multipole_friction_matrix

  !> The trial step size of the stepper, from which the reuse budget follows.
  subroutine multipole_step_begin(this, h)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: h
    this%h = h
  end subroutine multipole_step_begin

  !> Counters of the adaptive reuse (evaluations also in 'stage' mode).
  function multipole_statistics(this) result(s)
    class(multipole_model_t), intent(in) :: this
    type(hydro_stats_t) :: s
    s = this%stats
  end function multipole_statistics

  !> The lubrication cutoff when the corrections are on, else 0 (no pair list needed).
  pure real(wp) function multipole_pair_cutoff(this) result(c)
    class(multipole_model_t), intent(in) :: this
    c = 0.0_wp
    if (this%lubrication) c = this%lub%cutoff()
  end function multipole_pair_cutoff

  !> u = mu(r) f + C(r):e at time t, exact ('stage') or with the adaptive reuse of the
  !> many-body part (which needs t and a step size from step_begin; else exact).
  subroutine multipole_velocities(this, r, f, u, error, e, t, pairs)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :)
    real(wp), intent(out) :: u(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in), optional :: e(3, 3), t
    type(pair_geometry_t), intent(in), optional :: pairs
    real(wp) :: ez(3, 3)
    integer(i8) :: c0, c1, crate, refreshes

    this%stats%evaluations = this%stats%evaluations + 1
    ez = 0.0_wp
    if (present(e)) ez = e
    if (.not. this%adaptive) then
      call this%prepare(r, error, pairs)
      if (allocated(error)) return
      call this%apply_mobility(f, u)
      if (present(e)) call this%add_strain_disturbance(e, u)
      return
    end if
    call system_clock(c0, crate)
    refreshes = this%stats%refreshes
    call adaptive_velocities(this, r, f, ez, u, error, t, pairs)
    call system_clock(c1)
    if (this%stats%refreshes > refreshes) then
      this%stats%refresh_seconds = this%stats%refresh_seconds + real(c1 - c0, wp)/real(crate, wp)
    else
      this%stats%reused_seconds = this%stats%reused_seconds + real(c1 - c0, wp)/real(crate, wp)
    end if
  end subroutine multipole_velocities

  !> The adaptive path of multipole_velocities (ez: the rate of strain, zero without strain).
  subroutine adaptive_velocities(this, r, f, ez, u, error, t, pairs)
    class(multipole_model_t), intent(inout) :: this
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
        this%stats%reused = this%stats%reused + 1
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
        this%stats%max_error_ratio = max(this%stats%max_error_ratio, err/predicted)
      this%coef(k) = max(err/gk(k - lo + 1), 0.5_wp*this%coef(k))
    end do
  end subroutine adaptive_velocities

  !> u from the many-body part of the last refresh as it is (no extrapolation, no refresh):
  !> what the adaptive path returns when it reuses that part at r. For tests and measurements;
  !> needs a refresh first (an adaptive velocities call), else returns an error.
  subroutine multipole_reused_velocities(this, r, f, u, error, e)
    class(multipole_model_t), intent(inout) :: this
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
  end subroutine multipole_reused_velocities

  !> The growth factor of the reuse error at time t for extrapolation order k (0..n_hist):
  !> |t - t_ref| for a reused many-body part, times |t - t_prev| for one extrapolated from the
  !> last two refreshes and |t - t_prev2| from the last three (the error of polynomial
  !> interpolation through the refresh times).
  pure real(wp) function growth(this, t, k) result(g)
    class(multipole_model_t), intent(in) :: this
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
    class(multipole_model_t), intent(in) :: this
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

  !> Exact velocities at r, which becomes the reference: assemble and factorise the system,
  !> keep zeta_L and x_L (and, when there was a reference, their change since it, rotated into
  !> the new frame: the history for the extrapolation), factorise zeta_L + sum dzeta (the
  !> preconditioner) and solve; t is the time of r.
  subroutine refresh(this, r, f, e, t, u, error, pairs)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :), e(3, 3), t
    real(wp), intent(out) :: u(:, :)
    type(error_t), allocatable, intent(out) :: error
    type(pair_geometry_t), intent(in), optional :: pairs
    real(wp) :: qrot(3, 3)
    integer :: i
    call this%sys%factorise(r, error)
    if (allocated(error)) return
    this%n_overlaps = this%sys%n_clamped
    call this%sys%friction_coupling(this%zt, this%x6, error)
    if (allocated(error)) return
    if (this%has_ref .and. t /= this%t_ref) then
      ! history: the new part minus the old one seen from the new frame, and the old change
      ! seen from the new frame (two refreshes at the same time, e.g. the last two stages of
      ! a step, give none)
      call best_rotation(this%r_ref, r, qrot, error)
      if (allocated(error)) return
      if (this%n_hist > 0) then
        call rotate_friction(qrot, this%zh, this%zh2)
        call rotate_coupling(qrot, this%xh, this%xh2)
        this%t_hist(2) = this%t_hist(1)
      end if
      call rotate_friction(qrot, this%zl, this%zh)
      call rotate_coupling(qrot, this%xl, this%xh)
      this%zh = this%zt - this%zh
      this%xh = this%x6 - this%xh
      this%n_hist = min(this%n_hist + 1, 2)
      this%t_hist(1) = this%t_ref
    else
      this%n_hist = 0
    end if
    this%has_ref = .false.   ! until the new reference is complete
    this%t_ref = t
    this%zl = this%zt
    this%xl = this%x6
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
    this%stats%refreshes = this%stats%refreshes + 1
  end subroutine refresh

  !> zo = Q zi Q^T blockwise: the friction of a configuration rotated by q (every 3 x 3
  !> block of the 6N x 6N matrix, translations and rotations alike).
  subroutine rotate_friction(q, zi, zo)
    real(wp), intent(in) :: q(3, 3), zi(:, :)
    real(wp), intent(out) :: zo(:, :)
    integer :: a, b, nb3
    nb3 = size(zi, 1)/3
    do b = 1, nb3
      do a = 1, nb3
        zo(3*a - 2:3*a, 3*b - 2:3*b) = matmul(q, matmul(zi(3*a - 2:3*a, 3*b - 2:3*b), transpose(q)))
      end do
    end do
  end subroutine rotate_friction

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
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: rr(:, :), w(2)
    type(error_t), allocatable, intent(out) :: error
    type(pair_geometry_t), intent(in), optional :: pairs
    real(wp), intent(in), optional :: rotation(3, 3)
    this%pf = this%zl
    if (w(1) /= 0.0_wp) this%pf = this%pf + w(1)*this%zh
    if (w(2) /= 0.0_wp) this%pf = this%pf + w(2)*this%zh2
    if (this%lubrication) then
      call this%lub%pair_blocks(rr, this%pairs, pairs, rotation)
      call this%pairs%add_friction(this%pf)
      this%n_lub_pairs = this%pairs%n_pairs()
    end if
    call cholesky_factor(this%pf, error, 'lubrication-corrected friction')
  end subroutine factor_preconditioner

  !> b = [f_i; 0] + (x_L(ref) + w1 xh + w2 xh2) : e + sum dx : e (the pair list at the current
  !> configuration).
  subroutine right_hand_side(this, f, e, w)
    class(multipole_model_t), intent(inout) :: this
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
    if (this%lubrication) call this%pairs%add_strain(e, this%b)
  end subroutine right_hand_side

  !> Velocities from the reused many-body part (extrapolated with the weights w) at r seen in the
  !> reference frame (rotation qrot: the aligned configuration rp of `measure_deformation`): lubrication of the
  !> rotated pairs, conjugate gradients on (zeta_L(ref) + w1 zh + w2 zh2 + sum dzeta) U = b.
  !> `converged` is false when CG did not reach the stopping error. `pairs`: the close pairs
  !> of r if the caller has them.
  subroutine reused_solve(this, r, f, e, qrot, w, budget, u, converged, pairs)
    class(multipole_model_t), intent(inout) :: this
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
    if (this%lubrication) call this%lub%pair_blocks(r, this%pairs, pairs, qt)
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
    this%stats%cg_iterations = this%stats%cg_iterations + it
    if (.not. converged) return
    do i = 1, nb
      u(:, i) = matmul(qrot, this%x(6*i - 5:6*i - 3))
    end do
    if (it > cg_refactor_iterations) then
      call factor_preconditioner(this, r, w, error, pairs, qt)
      this%stats%preconditioners = this%stats%preconditioners + 1
      if (allocated(error)) this%has_ref = .false.   ! refresh at the next call
    end if
  end subroutine reused_solve

  !> y = (zeta_L(ref) + w1 zh + w2 zh2 + sum dzeta) x.
  subroutine operator_apply(this, xv, y)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: xv(:)
    real(wp), intent(out) :: y(:)
    integer :: n6
    n6 = size(xv)
    call dsymv('L', n6, 1.0_wp, this%zl, n6, xv, 1, 0.0_wp, y, 1)
    if (this%w(1) /= 0.0_wp) call dsymv('L', n6, this%w(1), this%zh, n6, xv, 1, 1.0_wp, y, 1)
    if (this%w(2) /= 0.0_wp) call dsymv('L', n6, this%w(2), this%zh2, n6, xv, 1, 1.0_wp, y, 1)
    if (this%lubrication) call this%pairs%apply(xv, y)
  end subroutine operator_apply

  !> s = the beads' total hydrodynamic stresslet at r for forces f in the ambient strain e
  !> (module header; exact at r, the reuse state and the cached mobility are not touched).
  subroutine multipole_stresslet(this, r, f, e, s, error)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :), e(3, 3)
    real(wp), intent(out) :: s(3, 3)
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: dfree(:, :), zeta(:, :), x(:, :), v(:)
    real(wp) :: gram(5, 5), se(5, 5), sm(5, 5), c(5), m(5), bas(3, 3, 5)
    type(pair_blocks_t) :: pairs
    integer :: nb, i, k

    s = 0.0_wp
    if (this%order < 2) then
      call fatal_error(error, 'multipole: the stresslet needs order L >= 2 (L = 1 has no stresslet moments)')
      return
    end if
    nb = size(r, 2)
    call this%sys%factorise(r, error)
    if (allocated(error)) return
    allocate (dfree(6*nb, 5))
    call this%sys%strain_disturbance(dfree, gram)
    c = strain_coefficients(e)
    if (.not. this%lubrication) then
      do k = 1, 5
        m(k) = dot_product(gram(k, :), c)
        do i = 1, nb
          m(k) = m(k) - dot_product(f(:, i), dfree(6*i - 5:6*i - 3, k))
        end do
      end do
      s = tensor_from_pairings(m)
      return
    end if
    allocate (zeta(6*nb, 6*nb), x(6*nb, 5), v(6*nb))
    call this%sys%friction_coupling(zeta, x, error)
    if (allocated(error)) return
    se = gram + matmul(transpose(dfree), x)
    call this%lub%stresslet_correction(r, sm)
    se = se + sm
    do k = 1, 5
      bas(:, :, k) = strain_basis(k)
    end do
    call this%lub%pair_blocks(r, pairs)
    call pairs%add_friction(zeta)
    call pairs%add_strain_basis(bas, x)
    call cholesky_factor(zeta, error, 'lubrication-corrected friction')
    if (allocated(error)) return
    v = 0.0_wp
    do i = 1, nb
      v(6*i - 5:6*i - 3) = f(:, i)
    end do
    v = v + matmul(x, c)
    call cholesky_solve(zeta, v)
    do k = 1, 5
      m(k) = dot_product(se(k, :), c) - dot_product(v, x(:, k))
    end do
    s = tensor_from_pairings(m)
  end subroutine multipole_stresslet

  !> Largest translational velocity norm over beads of a 6N vector.
  pure real(wp) function largest_velocity(v, nb) result(m)
    real(wp), intent(in) :: v(:)
    integer, intent(in) :: nb
    integer :: i
    m = 0.0_wp
    do i = 1, nb
      m = max(m, norm2(v(6*i - 5:6*i - 3)))
    end do
  end function largest_velocity

  !> Seconds of the last `prepare` spent in the assembly of the pair blocks, the factorisation
  !> (p-moment elimination and Cholesky) and the lubrication part (knotflow-bench-multipole).
  subroutine multipole_prepare_seconds(this, assembly, factor, lubrication)
    class(multipole_model_t), intent(in) :: this
    real(wp), intent(out) :: assembly, factor, lubrication
    call this%sys%seconds(assembly, factor)
    lubrication = this%t_lubrication
  end subroutine multipole_prepare_seconds

end module kf_hydro_multipole
