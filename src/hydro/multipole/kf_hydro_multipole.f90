!> The exact multipole hydrodynamic model (PHYSICS.md 3.3, `&hydro update = 'stage'`): N-sphere
!> induced-force multipoles truncated at order L, optionally with two-sphere lubrication
!> corrections (HYDROLIB scheme, MULTIPOLE.md 13.3) and an overlap treatment: by default (overlap
!> rules 'pair', 'separate', 'relax') a pair closer than 1 + eps_lub has its multipole blocks and
!> its lubrication correction evaluated at 1 + eps_lub; with `literal_bwe` (overlap = 'bwe',
!> PHYSICS.md 3.3) the many-body system is that of the real positions and only the lubrication
!> correction of a pair with r <= 1 is evaluated at 1 + eps_lub.
!>
!> In parts: the many-body system (kf_multipole_system: assembly, p-moment elimination,
!> Cholesky factorisation, then its friction zeta_L and strain coupling x_L), the lubrication
!> corrections as a list of 12 x 12 pair blocks (kf_pair_blocks), and the corrected friction
!> route zeta = zeta_L + sum dzeta, x = x_L + sum dx, U - U_inf = zeta^-1 (F + x:E).
!>
!> `prepare(r)` at every call does all of the above and caches the 3N x 3N mobility and the
!> strain disturbances; `velocities` prepares at every call: the exact reference. The two other
!> update modes are their own types extending this one, beside it: 'adaptive'
!> (kf_hydro_multipole_adaptive: reuses the many-body part `many_body_part` across stages and
!> steps) and 'iterative' (kf_hydro_multipole_iterative: an exact iterative solve at every call).
!>
!> The stresslet (`stresslet`, MULTIPOLE.md 9, 11, 13.3) is exact at the configuration given,
!> in every update mode, and leaves the reuse state of an extension alone: a frame's stresslet
!> costs one assembly and factorisation (plus, with lubrication, one grand friction). With the grand
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
  use kf_blas, only: dgemv
  use kf_lapack, only: cholesky_factor, cholesky_solve, cholesky_invert
  use kf_error, only: error_t, fatal_error
  use kf_hydro_model, only: hydro_model_t, hydro_stats_t
  use kf_multipole_system, only: multipole_system_t
  use kf_strain_basis, only: strain_coefficients, strain_basis, tensor_from_pairings
  use kf_lubrication, only: lubrication_t
  use kf_pair_blocks, only: pair_blocks_t
  use kf_pair_geometry, only: pair_geometry_t
  use kf_hydro_limits, only: eps_lub_in_range, eps_lub_range_text
  implicit none
  private

  public :: multipole_memory_bytes, largest_velocity

  !> Multipole model of order L with or without lubrication corrections.
  type, extends(hydro_model_t), public :: multipole_model_t
    integer :: order = 0                 !< multipole order L (init sets it)
    logical :: lubrication = .false.
    logical :: literal_bwe = .false.      !< overlap = 'bwe': no clamp of the many-body system
    real(wp) :: eps_lub = 0.0_wp         !< overlap shift (init sets it): overlapping pairs are evaluated at 1 + eps_lub
    !> The order of the mobility `mobility_at` makes when it is not at hand (`set_jacobian_order`;
    !> the model's own order unless a lower one was set)
    integer :: jacobian_order = 0
    !> the model of that order when it is lower (the same lubrication, eps_lub and overlap treatment)
    class(hydro_model_t), allocatable, private :: jmodel
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
    procedure :: set_jacobian_order => multipole_set_jacobian_order
    procedure :: friction_matrix => multipole_friction_matrix
    procedure :: velocities => multipole_velocities
    procedure :: pair_cutoff => multipole_pair_cutoff
    procedure :: statistics => multipole_statistics
    procedure :: many_body_part => multipole_many_body_part
    procedure :: stresslet => multipole_stresslet
    procedure :: prepare_seconds => multipole_prepare_seconds
    procedure :: many_body_spectrum => multipole_many_body_spectrum
  end type multipole_model_t

contains

  !> The model's dense arrays for n beads (bytes; a lower bound: the many-body system comes on
  !> top): the 3N x 3N mobility and 6N x 6N friction (360 N^2), one more (288 N^2) for the
  !> stresslet's grand friction with lubrication (`stresslet_lubrication`).
  pure integer(i8) function multipole_memory_bytes(n, stresslet_lubrication) result(bytes)
    integer(i8), intent(in) :: n
    logical, intent(in) :: stresslet_lubrication
    bytes = 360_i8*n*n
    if (stresslet_lubrication) bytes = bytes + 288_i8*n*n
  end function multipole_memory_bytes

  !> Order L (1..max_multipole_order), lubrication on/off, overlap shift eps_lub (kf_hydro_limits);
  !> `literal_bwe` (default .false.): the literal BWE rule (module header) instead of the clamp.
  subroutine multipole_init(this, order, lubrication, eps_lub, error, literal_bwe)
    class(multipole_model_t), intent(inout) :: this
    integer, intent(in) :: order
    logical, intent(in) :: lubrication
    real(wp), intent(in) :: eps_lub
    type(error_t), allocatable, intent(out) :: error
    logical, intent(in), optional :: literal_bwe

    if (.not. eps_lub_in_range(eps_lub)) then
      call fatal_error(error, 'multipole: eps_lub = '//to_str(eps_lub, '(es12.4)')// &
                       ' not allowed (outside '//eps_lub_range_text()//')')
      return
    end if
    this%literal_bwe = .false.
    if (present(literal_bwe)) this%literal_bwe = literal_bwe
    if (lubrication) then
      call this%lub%init(order, eps_lub, error, literal_bwe=this%literal_bwe)
      if (allocated(error)) return
    end if
    this%order = order
    this%jacobian_order = order
    if (allocated(this%jmodel)) deallocate (this%jmodel)
    this%lubrication = lubrication
    this%eps_lub = eps_lub
    this%n = 0
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
    end if
    allocate (this%mu(3*nb, 3*nb), this%dist(3*nb, 5), this%zt(6*nb, 6*nb), this%x6(6*nb, 5), &
              this%v3(3*nb), this%w3(3*nb))
  end subroutine ensure_work

  !> The many-body part at r, without lubrication: assemble and factorise the many-body system,
  !> zeta (6N x 6N, full storage) = its friction zeta_L and x (6N x 5) = its strain coupling x_L
  !> for the basis strains (kf_multipole_system `friction_coupling`); counts the clamped pairs.
  !> What a model that reuses the part (kf_hydro_multipole_adaptive) refreshes with; leaves the
  !> cached mobility alone.
  subroutine multipole_many_body_part(this, r, zeta, x, error)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: zeta(:, :), x(:, :)
    type(error_t), allocatable, intent(out) :: error
    call this%sys%factorise(r, error)
    if (allocated(error)) return
    this%n_overlaps = this%sys%n_clamped
    call this%sys%friction_coupling(zeta, x, error)
  end subroutine multipole_many_body_part

  !> Assemble and factorise for bead centres r(3, N); cache mu and the strain disturbances
  !> (exact at r, in every update mode).
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
  !> a 'stage' evaluation there); else, with a lower `jacobian_order`, the mobility of the model of
  !> that order at r (for a linearly implicit stepper's Jacobian: cheaper, not this model's);
  !> else prepare at r first.
  subroutine multipole_mobility_at(this, r, mu, error)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: mu(:, :)
    type(error_t), allocatable, intent(out) :: error
    if (.not. this%mobility_cached(r)) then
      if (allocated(this%jmodel)) then
        call this%jmodel%mobility_at(r, mu, error)
        return
      end if
      call this%prepare(r, error)
      if (allocated(error)) return
    end if
    mu = this%mu
  end subroutine multipole_mobility_at

  !> The order (1..order) of the mobility `mobility_at` makes where this model's is not at hand
  !> (after init: the model's order). A lower order builds a multipole model of that order with the
  !> same lubrication, eps_lub and overlap treatment.
  subroutine multipole_set_jacobian_order(this, jorder, error)
    class(multipole_model_t), intent(inout) :: this
    integer, intent(in) :: jorder
    type(error_t), allocatable, intent(out) :: error
    if (jorder < 1 .or. jorder > this%order) then
      call fatal_error(error, 'multipole: jacobian order = '//to_str(jorder)//' not allowed (1 to the order L = '// &
                       to_str(this%order)//')')
      return
    end if
    if (allocated(this%jmodel)) deallocate (this%jmodel)
    this%jacobian_order = jorder
    if (jorder == this%order) return
    block
      type(multipole_model_t), allocatable :: low
      allocate (low)
      call low%init(jorder, this%lubrication, this%eps_lub, error, literal_bwe=this%literal_bwe)
      if (allocated(error)) return
      call move_alloc(low, this%jmodel)
    end block
  end subroutine multipole_set_jacobian_order

  !> Was the last prepare at exactly r (and is its mobility still held)?
  logical function multipole_mobility_cached(this, r) result(cached)
    class(multipole_model_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :)
    cached = this%n == size(r, 2) .and. allocated(this%r_prepared)
    if (cached) cached = all(shape(this%r_prepared) == shape(r))
    if (cached) cached = all(this%r_prepared == r)
  end function multipole_mobility_cached

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

  !> Work counters: the evaluations (`velocities` calls; nothing is reused).
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

  !> u = mu(r) f + C(r):e, exact: prepare at r and apply (t is not needed).
  subroutine multipole_velocities(this, r, f, u, error, e, t, pairs)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :)
    real(wp), intent(out) :: u(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in), optional :: e(3, 3), t
    type(pair_geometry_t), intent(in), optional :: pairs

    this%stats%evaluations = this%stats%evaluations + 1
    call this%prepare(r, error, pairs)
    if (allocated(error)) return
    call this%apply_mobility(f, u)
    if (present(e)) call this%add_strain_disturbance(e, u)
  end subroutine multipole_velocities

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
