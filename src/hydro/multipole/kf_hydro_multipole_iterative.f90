!> The multipole model with `&hydro update = 'iterative'` (docs/multipole.md): the exact
!> lubrication-corrected velocities at every call, by an iterative solve of the assembled
!> many-body system preconditioned with an earlier factorisation.
!>
!> The corrected friction route of kf_hydro_multipole, (zeta_L + dzeta) U = F + (x_L + dx) : E
!> with zeta_L = the inverse of the Schur complement of K onto the force/torque moments P, is
!> one linear system in the moments m (the nr unknowns of K, p-moments eliminated) and the
!> Cartesian velocities U (6N, [U_1, Omega_1, U_2, ...]):
!>   K m - E S^-1 U = [rhs_Q(E); 0]            (the multipole system, K = K0 - B B^T)
!>   S^-1 m_P / pi + dzeta U = F + dx : E       (force balance with the lubrication blocks)
!> with E the injection of the P rows, S = diag(s_c) the moment scales of kf_multipole_system
!> and rhs_Q the ambient strain's coefficients. Eliminating m gives the friction route exactly.
!> At every call the system is assembled (K0 and B, no p-moment update, no factorisation) at
!> the configuration rotated onto the reference (best rigid rotation Q, kf_rigid_fit; Stokes
!> flow is covariant), with the lubrication blocks of the rotated pairs, forces and strain
!> rotated with it and the velocities back. It is solved by flexible GMRES, right-preconditioned
!> with the inverse of the same system at the reference (the Cholesky factor of K_ref and of
!> zeta_L(ref) + dzeta_f, dzeta_f the lubrication blocks of the call that last factorised it):
!> one triangular-solve pair with K_ref and one with the 6N factor per iteration. The solves
!> with K_ref use a single-precision copy of its factor (half the memory traffic of the
!> iteration's largest part); flexible GMRES keeps the preconditioned basis, so the operator,
!> applied in double to it, alone decides the solution: the preconditioner's rounding costs at
!> most iterations, not accuracy (a left-preconditioned GMRES would stall at the single
!> precision's level).
!> Start (docs/multipole.md, "An extrapolated warm start"): the right-hand sides b_j and
!> solutions x_j of the last warm_history calls since the last factorisation (setup argument,
!> default warm_history_default = 6; the moments and velocities of every call are in the
!> reference frame) give x0 = sum_j c_j x_j with the affine weights (sum c_j = 1) that fit the
!> call's b best, sum_j c_j b_j (affine_weights: least squares in the differences to the newest,
!> nearly dependent ones dropped, sum |c_j| bounded by weight_bound); x0 = 0 when that has the
!> smaller residual. Since A_j x_j = b_j, b - A x0 = (b - sum c_j b_j) - sum c_j (A - A_j) x_j:
!> the stiff forces change faster than the operator. warm_history = 1: the last call's
!> solution. A factorisation or a change of bead number starts the history anew.
!> Single-precision products in the Krylov loop (`single_products`, default .true.): the
!> start's residual r0 = b - A x0 is always computed with the double operator; the loop then
!> computes only a correction d with A d = r0. With the loop's products those of A + E (K's
!> products from single copies of K0 and B, kf_multipole_system `apply_single`; the 6N rows,
!> the coupling and the lubrication blocks stay double), flexible GMRES solves (A + E) d' = r0,
!> so the solution moves by d' - d = -A^-1 E d' and, with |E| <= eta |A| (eta about the single
!> rounding u = 2^-24 = 6.0e-8 times the sums' growth) and d' close to d = A^-1 r0,
!>   |d' - d| / |x| <= kappa eta |d| / |x| <= kappa^2 eta |r0| / |b|,
!> kappa the condition number that maps a residual of K's rows onto the velocities. A call uses
!> the single products when its start is warm and close:
!>   |r0| < |b|  and  |r0| <= theta |b|,  theta = solver_tolerance / (single_margin u),
!> single_margin = 100 standing for kappa^2 times the growth (theta = 0.17 at the default 1e-6;
!> measured along dopri45 runs against 'stage', docs/multipole.md, "Single-precision products
!> in the Krylov loop": with 99 % of the iterations in single the largest velocity error is
!> that of the double products, 2.4e-7). A cold start (x0 = 0, so |r0| = |b|: the first call,
!> after a factorisation or when zero is the better start) and small tolerances (theta = 1.7e-5
!> at 1e-10, below the warm starts of the tests) use the double products. The single copies
!> are made by the assembly (each sphere's columns from cache, about 1 ms at N = 99; 1.6-2.1 ms
!> as a separate conversion) when the last call's start satisfied the rule, and used when this
!> call's does too. Only chains of at least `single_min_beads` beads (component, default
!> single_min_beads_default = 90) use them: the copies cost about as much as the cheaper products
!> save below that (K in cache; measured, docs/multipole.md). Counters: `statistics`
!> (single_solves, single_iterations).
!> The whole operator in single at loose tolerances: with solver_tolerance >=
!> single_operator_tolerance (component, default single_operator_tolerance_default = 1e-5), at
!> least single_operator_min_beads beads (component, default single_operator_min_beads_default =
!> 60: no copies are made, so single_min_beads' reason does not apply; measured faster at 60
!> beads, docs/multipole.md, and not measured below) and `single_products`, the assembly writes
!> K0 only in single (kf_multipole_system `assemble` with `only_single`: no double K0 written nor
!> read, half the bytes of K0 moved) and every product with K, the start's residual too, uses
!> the single copies; the solution is then that of A + E (|E| <= eta |A|, module header),
!> off by at most kappa eta relative. Measured along dopri45 (every stage against 'stage', solver
!> tolerance 1e-8 so the rounding shows, docs/multipole.md): relative RMS velocity error at most
!> 3.8e-7 to 6.2e-7 (trefoil, a random chain of 60 beads, the compact coil of 152; largest bead
!> 1.0e-6 to 1.3e-6) against 1.3e-9 with the double residual (trefoil); at solver_tolerance 1e-5
!> the iteration's own largest error is five to nine times that.
!> GMRES, not CG: the system is symmetric but indefinite (its Schur complement onto U is
!> negative definite). One system, not nested solves (CG on the 6N friction, each product an
!> inner solve with K preconditioned by K_ref): an inner solve alone needs as many iterations,
!> each of the same cost, as the whole one-system solve (docs/multipole.md).
!>
!> 6N friction factor rule: a call refactorises the 6N factor with its own blocks dzeta when
!> they differ from dzeta_f by more than friction_change (setup argument, default
!> friction_change_default = 0.05) in the largest entry scaled by the factor's diagonal,
!>   max over the pairs of either list and (a, b) of |dzeta - dzeta_f|_ab / sqrt(d_a d_b),
!> d the diagonal of zeta_L(ref) + dzeta_f (a pair in one list only counts with its whole
!> block; kf_pair_blocks `largest_scaled_change`, about 0.07 ms at N = 99 with 1328 pairs);
!> otherwise it keeps the factor (about 2 ms of dpotrf and copy saved). The operator always
!> holds the call's own blocks, so a kept factor costs iterations, never accuracy. A pair
!> entering or leaving the list at the cutoff (tapered to zero there) changes little and keeps
!> the factor; an approaching pair's squeeze block (about 1/(4 gap)) refactorises it. Each
!> factorisation (the reference's too) makes the call's blocks dzeta_f. Measured on the study's
!> case path, docs/multipole.md ("The 6N friction factor kept"). Counter: `preconditioners`.
!>
!> Stopping rule: the largest change of a bead's velocity between two iterations is at most
!> solver_tolerance times the largest bead velocity (at least two iterations). Refactorisation
!> rule: a call that needs more than refactor_iterations iterations makes the next call
!> factorise at its configuration (the new reference); a call that does not converge in
!> max_iterations factorises at once. The first call and a change of bead number factorise.
!> A factorising call solves directly with the double factors (the exact inverse there).
!>
!> Memory (besides the parent's arrays): zeta_L(ref) and the 6N factor (6N x 6N each, in the
!> permuted order of `ordering`), the Jacobian's 3N x 3N mobility blocks, the factor's diagonal
!> scale (6N), two lists of lubrication blocks (the call's and the factor's), an N x N integer
!> map for the rule's pair matching, the two many-body systems (the reference factor with its
!> single-precision copy, and the assembled one with the single copies of K0 and B, 5 nr^2 bytes
!> (K0 full, 4 nr^2; B, nr^2): 12.5 MB at N = 99, made at the first call that uses them), the
!> Krylov bases and the start's history (2 warm_history vectors of the system's size).
!>
!> Jacobian mobility (`mobility_at`, for a linearly implicit stepper): at the model's order, the
!> translational part of the inverse of the preconditioner's 6N friction, rotated onto the
!> configuration (no factorisation of K; exact at the reference and its rigid motions); a lower
!> jacobian_order keeps the exact model's route (docs/accuracy.md, "The solver tolerance and the
!> preconditioner's Jacobian"). The 6N friction and its factor are kept with the rotations first
!> and the translations last (`ordering`), so that part is the inverse of the factor's trailing
!> 3N x 3N block times its transpose (one dpotri of size 3N). The unrotated blocks are kept until
!> the 6N factor changes, so a Jacobian between two factorisations of it costs a rotation
!> (counter `mobilities`: those made from a factor).
!>
!> Checkpoint: the reference and the history of solutions are not in the checkpoint; the
!> reference is rebuilt (a direct solve) at the first call after a resume, so a resumed run
!> agrees with an uninterrupted one to the solver tolerance (not bit for bit). Frames, the stresslet and
!> `prepare` use the exact model's routes (the parent type).
module kf_hydro_multipole_iterative
  use kf_kinds, only: wp, sp, i8
  use kf_strings, only: to_str
  use kf_constants, only: pi
  use kf_lapack, only: cholesky_factor
  use kf_blas, only: dtrsv, dpotri
  use kf_error, only: error_t, fatal_error
  use kf_hydro_model, only: hydro_stats_t
  use kf_hydro_multipole, only: multipole_model_t, multipole_memory_bytes, largest_velocity
  use kf_multipole_system, only: multipole_system_t
  use kf_strain_basis, only: strain_coefficients
  use kf_pair_blocks, only: pair_blocks_t
  use kf_pair_geometry, only: pair_geometry_t
  use kf_rigid_fit, only: best_rotation, centroid, rotate_blocks
  use kf_hydro_limits, only: solver_tolerance_default, solver_tolerance_min, solver_tolerance_max
  implicit none
  private

  !> The default number of iterations above which the next call refactorises.
  integer, parameter, public :: refactor_iterations_default = 6
  !> GMRES iterations before a call gives up and factorises (no restart).
  integer, parameter, public :: max_iterations = 30
  !> The default largest scaled change of the lubrication blocks for which a call keeps the 6N
  !> friction factor of an earlier call.
  real(wp), parameter, public :: friction_change_default = 0.05_wp
  !> The default number of earlier calls (since the last factorisation) whose right-hand
  !> sides and solutions make GMRES's start (1: the last call's solution).
  integer, parameter, public :: warm_history_default = 6
  !> The largest allowed warm_history.
  integer, parameter, public :: warm_history_max = 8
  !> The largest sum of |weights| of an extrapolated start; larger weights are shrunk towards
  !> the newest call's (a convex combination of the extrapolation and the newest solution).
  real(wp), parameter, public :: weight_bound = 4.0_wp
  !> A stored difference whose part orthogonal to the newer ones is at most this fraction of
  !> its length does not take part in the fit (repeated or collinear configurations).
  real(wp), parameter, public :: drop_tolerance = 1.0e-6_wp
  !> The rule's margin for single-precision products (module header): a call uses them when
  !> |r0| <= solver_tolerance / (single_margin u) |b|, u the single rounding unit.
  real(wp), parameter, public :: single_margin = 100.0_wp
  !> The fewest beads for single-precision products (module header): below, the single copies
  !> cost about as much as the products save (docs/multipole.md).
  integer, parameter, public :: single_min_beads_default = 90
  !> The fewest beads for the whole operator in single (module header): the smallest chain it
  !> was measured on (docs/multipole.md).
  integer, parameter, public :: single_operator_min_beads_default = 60
  !> The default smallest solver tolerance at which the whole operator is in single (module
  !> header).
  real(wp), parameter, public :: single_operator_tolerance_default = 1.0e-5_wp

  public :: iterative_memory_bytes, affine_weights

  !> Multipole model, exact at every call by preconditioned GMRES on the assembled system.
  type, extends(multipole_model_t), public :: multipole_iterative_t
    real(wp) :: solver_tolerance = solver_tolerance_default
    integer :: refactor_iterations = refactor_iterations_default
    type(multipole_system_t), private :: cur   !< assembled at the current (rotated) configuration
    type(multipole_system_t), private :: ref   !< factorised at the reference
    type(pair_blocks_t), private :: blocks(2)  !< lubrication blocks: of the call, of the 6N factor
    integer, private :: ib = 1                 !< blocks(ib): the current call's
    integer, private :: fb = 1                 !< blocks(fb): those in the 6N factor pre
    real(wp) :: friction_change = friction_change_default
    !> .false.: the Krylov loop's products always in double (module header).
    logical :: single_products = .true.
    !> The fewest beads for them (module header).
    integer :: single_min_beads = single_min_beads_default
    !> The fewest beads for the whole operator in single (module header).
    integer :: single_operator_min_beads = single_operator_min_beads_default
    !> The smallest solver tolerance at which the whole operator is in single (module header).
    real(wp) :: single_operator_tolerance = single_operator_tolerance_default
    !> The last GMRES call's start satisfied the rule: the next assembly makes the single copies.
    logical, private :: single_next = .false.
    logical, private :: ready = .false.
    logical, private :: refactor_next = .false.
    integer :: warm_history = warm_history_default  !< calls kept for the start (1: the last solution)
    integer, private :: hn = 0                 !< calls in the history (newest last)
    integer, private :: nr = 0                 !< unknowns of K
    real(wp), private :: cen_ref(3) = 0.0_wp
    real(wp), allocatable, private :: pos_ref(:, :), rp(:, :), frot(:, :)
    !> The 6N friction's permuted order (`ordering`): position k holds unknown perm(k) of the
    !> order [U_1, Omega_1, U_2, ...]; pos is the inverse map.
    integer, allocatable, private :: perm(:), pos(:)
    real(wp), allocatable, private :: zref(:, :)    !< zeta_L(ref), full storage, permuted order
    real(wp), allocatable, private :: pre(:, :)     !< Cholesky factor of zeta_L(ref) + dzeta_f, permuted order
    real(wp), allocatable, private :: pscale(:)     !< 1/sqrt of the diagonal of zeta_L(ref) + dzeta_f
    real(wp), allocatable, private :: s6p(:)        !< 6N work in the permuted order
    !> The translational blocks of the inverse of the 6N friction in `pre` (3N x 3N; the Jacobian
    !> mobility at the reference; sized by ensure_work), made by the first `mobility_at` after each
    !> factorisation of pre.
    real(wp), allocatable, private :: mref(:, :)
    logical, private :: mref_valid = .false.
    integer, allocatable, private :: slot(:, :)     !< (N, N) work of largest_scaled_change
    real(wp), allocatable, private :: v(:, :)      !< Krylov basis
    real(wp), allocatable, private :: hm(:, :)     !< Hessenberg matrix (Givens-rotated)
    real(wp), allocatable, private :: rhs(:), wk(:), m0(:), s6(:), uk(:), uprev(:), u0(:)
    real(wp), allocatable, private :: zb(:, :)     !< preconditioned basis (flexible GMRES)
    real(wp), allocatable, private :: xs(:)        !< the start, then the solution (reference frame)
    real(wp), allocatable, private :: hb(:, :)     !< (nt, warm_history) the history's right-hand sides
    real(wp), allocatable, private :: hx(:, :)     !< (nt, warm_history) their solutions
    real(sp), allocatable, private :: zs(:), ms(:) !< single-precision work of the preconditioner
    type(hydro_stats_t), private :: istats
  contains
    procedure :: setup => iterative_setup
    procedure :: velocities => iterative_velocities
    procedure :: statistics => iterative_statistics
    procedure :: mobility_reusable => iterative_mobility_reusable
    procedure :: mobility_at => iterative_mobility_at
  end type multipole_iterative_t

contains

  !> The model's dense arrays for n beads (bytes; a lower bound): the exact model's, one more
  !> 6N x 6N matrix (288 N^2), the preconditioner's friction factor, the N x N integer map of its
  !> rule (4 N^2) and the Jacobian's 3N x 3N mobility blocks (72 N^2); its two many-body systems
  !> (the reference factor with its single-precision copy, and the assembled one with the single
  !> copies of its products) and the Krylov bases come on top.
  pure integer(i8) function iterative_memory_bytes(n, stresslet_lubrication) result(bytes)
    integer(i8), intent(in) :: n
    logical, intent(in) :: stresslet_lubrication
    bytes = multipole_memory_bytes(n, stresslet_lubrication) + 364_i8*n*n
  end function iterative_memory_bytes

  !> Order L, lubrication, overlap shift eps_lub and `literal_bwe` (as the exact model), the
  !> relative solver tolerance (solver_tolerance_min..solver_tolerance_max, default
  !> solver_tolerance_default), the refactorisation threshold (>= 1 iterations, default
  !> refactor_iterations_default), the 6N friction factor's threshold friction_change
  !> (>= 0, default friction_change_default; 0: refactorised at every call whose blocks
  !> changed at all) and the number of earlier solutions of the start, warm_history (1 to
  !> warm_history_max, default warm_history_default; 1: the last call's solution).
  subroutine iterative_setup(this, order, lubrication, eps_lub, error, solver_tolerance, refactor_iterations, &
                             literal_bwe, friction_change, warm_history)
    class(multipole_iterative_t), intent(inout) :: this
    integer, intent(in) :: order
    logical, intent(in) :: lubrication
    real(wp), intent(in) :: eps_lub
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in), optional :: solver_tolerance
    integer, intent(in), optional :: refactor_iterations
    logical, intent(in), optional :: literal_bwe
    real(wp), intent(in), optional :: friction_change
    integer, intent(in), optional :: warm_history
    real(wp) :: min_distance
    this%solver_tolerance = solver_tolerance_default
    if (present(solver_tolerance)) this%solver_tolerance = solver_tolerance
    if (.not. (this%solver_tolerance >= solver_tolerance_min .and. this%solver_tolerance <= solver_tolerance_max)) then
      call fatal_error(error, 'multipole iterative: solver tolerance = '//to_str(this%solver_tolerance, '(es12.4)')// &
                       ' not allowed ('//to_str(solver_tolerance_min, '(es8.1)')//' to '// &
                       to_str(solver_tolerance_max, '(es8.1)')//')')
      return
    end if
    this%refactor_iterations = refactor_iterations_default
    if (present(refactor_iterations)) this%refactor_iterations = refactor_iterations
    if (this%refactor_iterations < 1) then
      call fatal_error(error, 'multipole iterative: refactor_iterations = '//to_str(this%refactor_iterations)// &
                       ' not allowed (>= 1)')
      return
    end if
    this%friction_change = friction_change_default
    if (present(friction_change)) this%friction_change = friction_change
    if (.not. (this%friction_change >= 0.0_wp)) then
      call fatal_error(error, 'multipole iterative: friction_change = '//to_str(this%friction_change, '(es12.4)')// &
                       ' not allowed (>= 0)')
      return
    end if
    this%warm_history = warm_history_default
    if (present(warm_history)) this%warm_history = warm_history
    if (this%warm_history < 1 .or. this%warm_history > warm_history_max) then
      call fatal_error(error, 'multipole iterative: warm_history = '//to_str(this%warm_history)// &
                       ' not allowed (1 to '//to_str(warm_history_max)//')')
      return
    end if
    call this%multipole_model_t%init(order, lubrication, eps_lub, error, literal_bwe=literal_bwe)
    if (allocated(error)) return
    ! the systems' overlap treatment as the exact model's (0: the real positions, 'bwe')
    min_distance = merge(0.0_wp, 1.0_wp + eps_lub, this%literal_bwe)
    call this%cur%init(order, min_distance, error)
    if (allocated(error)) return
    call this%ref%init(order, min_distance, error, single_copy=.true.)
    if (allocated(error)) return
    this%ready = .false.
    this%hn = 0
    this%refactor_next = .false.
    this%mref_valid = .false.
    this%istats = hydro_stats_t()
    this%single_next = .true.
  end subroutine iterative_setup

  !> The work counters, evaluations, refreshes (factorisations), reused (iterative solves),
  !> cg_iterations (their GMRES iterations), single_solves and single_iterations (the GMRES
  !> calls whose loop used the single-precision products, and their iterations), preconditioners (the iterative solves that
  !> refactorised the 6N friction factor), mobilities (Jacobian mobilities made from a 6N factor,
  !> not served from the kept ones) and the wall time of both kinds.
  function iterative_statistics(this) result(s)
    class(multipole_iterative_t), intent(in) :: this
    type(hydro_stats_t) :: s
    s = this%istats
  end function iterative_statistics

  !> u = mu(r) f + C(r):e, exact to the solver tolerance (t and pairs as for the exact model).
  subroutine iterative_velocities(this, r, f, u, error, e, t, pairs)
    class(multipole_iterative_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :)
    real(wp), intent(out) :: u(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in), optional :: e(3, 3), t
    type(pair_geometry_t), intent(in), optional :: pairs
    real(wp) :: ez(3, 3), q(3, 3), qt(3, 3), c(3)
    integer(i8) :: c0, c1, crate
    integer :: nb, i, its
    logical :: converged

    this%istats%evaluations = this%istats%evaluations + 1
    nb = size(r, 2)
    ez = 0.0_wp
    if (present(e)) ez = e
    call system_clock(c0, crate)
    if (allocated(this%pos_ref)) then
      if (size(this%pos_ref, 2) /= nb) this%ready = .false.
    end if
    if (.not. this%ready .or. this%refactor_next) then
      call refresh(this, r, f, ez, u, error, pairs)
      call system_clock(c1)
      this%istats%refresh_seconds = this%istats%refresh_seconds + real(c1 - c0, wp)/real(crate, wp)
      return
    end if
    call best_rotation(this%pos_ref, r, q, error)
    if (allocated(error)) return
    qt = transpose(q)
    c = centroid(r)
    do i = 1, nb
      this%rp(:, i) = matmul(qt, r(:, i) - c) + this%cen_ref
      this%frot(:, i) = matmul(qt, f(:, i))
    end do
    call this%cur%assemble(this%rp, error, single=this%single_products .and. this%single_next, &
                           only_single=this%single_products .and. nb >= this%single_operator_min_beads .and. &
                                       this%solver_tolerance >= this%single_operator_tolerance)
    if (allocated(error)) return
    this%n_overlaps = this%cur%n_clamped
    if (this%lubrication) then
      this%ib = 3 - this%fb
      call this%lub%pair_blocks(r, this%blocks(this%ib), pairs, qt)
      this%n_lub_pairs = this%blocks(this%ib)%n_pairs()
      if (this%blocks(this%ib)%largest_scaled_change(this%blocks(this%fb), this%pscale, this%slot) > &
          this%friction_change) then
        call factor_friction(this, error)
        if (allocated(error)) return
        this%istats%preconditioners = this%istats%preconditioners + 1
      end if
    end if
    call right_hand_side(this, this%frot, matmul(qt, matmul(ez, q)))
    call gmres(this, its, converged)
    this%istats%cg_iterations = this%istats%cg_iterations + its
    if (.not. converged) then
      call refresh(this, r, f, ez, u, error, pairs)
      call system_clock(c1)
      this%istats%refresh_seconds = this%istats%refresh_seconds + real(c1 - c0, wp)/real(crate, wp)
      return
    end if
    call history_push(this)
    do i = 1, nb
      u(:, i) = matmul(q, this%uk(6*i - 5:6*i - 3))
    end do
    this%refactor_next = its > this%refactor_iterations
    this%istats%reused = this%istats%reused + 1
    call system_clock(c1)
    this%istats%reused_seconds = this%istats%reused_seconds + real(c1 - c0, wp)/real(crate, wp)
  end subroutine iterative_velocities

  !> Factorise at r (the new reference: K_ref and zeta_L(ref) + dzeta(ref)) and solve there
  !> directly.
  subroutine refresh(this, r, f, e, u, error, pairs)
    class(multipole_iterative_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :), e(3, 3)
    real(wp), intent(out) :: u(:, :)
    type(error_t), allocatable, intent(out) :: error
    type(pair_geometry_t), intent(in), optional :: pairs
    integer :: nb, i
    nb = size(r, 2)
    this%ready = .false.
    this%hn = 0
    call this%ref%factorise(r, error)
    if (allocated(error)) return
    this%n_overlaps = this%ref%n_clamped
    call ensure_work(this, nb)
    call this%ref%grand_friction(this%pre, error)
    if (allocated(error)) return
    this%zref = this%pre(this%perm, this%perm)
    if (this%lubrication) then
      this%ib = 3 - this%fb
      call this%lub%pair_blocks(r, this%blocks(this%ib), pairs)
      this%n_lub_pairs = this%blocks(this%ib)%n_pairs()
    end if
    call factor_friction(this, error)
    if (allocated(error)) return
    this%pos_ref = r
    this%cen_ref = centroid(r)
    call right_hand_side(this, f, e)
    call precondition(this, this%rhs, this%xs, exact=.true.)
    call history_push(this)
    do i = 1, nb
      u(:, i) = this%xs(this%nr + 6*i - 5:this%nr + 6*i - 3)
    end do
    this%ready = .true.
    this%refactor_next = .false.
    this%istats%refreshes = this%istats%refreshes + 1
  end subroutine refresh

  !> pre = the Cholesky factor of zeta_L(ref) + the current call's lubrication blocks (the 6N
  !> friction factor of the preconditioner), pscale = 1/sqrt of that matrix's diagonal; the
  !> current blocks become the factor's (fb = ib).
  subroutine factor_friction(this, error)
    class(multipole_iterative_t), intent(inout) :: this
    type(error_t), allocatable, intent(out) :: error
    integer :: a
    this%pre = this%zref
    if (this%lubrication) call this%blocks(this%ib)%add_friction(this%pre, this%pos)
    do a = 1, size(this%pscale)
      this%pscale(a) = 1.0_wp/sqrt(this%pre(this%pos(a), this%pos(a)))
    end do
    this%mref_valid = .false.
    call cholesky_factor(this%pre, error, 'lubrication-corrected friction')
    if (allocated(error)) return
    this%fb = this%ib
  end subroutine factor_friction

  !> Work arrays for nb beads (after a factorisation, which sizes the system).
  subroutine ensure_work(this, nb)
    class(multipole_iterative_t), intent(inout) :: this
    integer, intent(in) :: nb
    integer :: nt
    this%nr = this%ref%unknowns()
    nt = this%nr + 6*nb
    if (allocated(this%rhs)) then
      if (size(this%rhs) == nt .and. size(this%rp, 2) == nb) return
      deallocate (this%pos_ref, this%rp, this%frot, this%pre, this%pscale, this%slot, this%zref, this%perm, this%pos, &
                  this%s6p, this%mref, this%v, this%hm, this%rhs, this%wk, &
                  this%m0, this%s6, this%uk, this%uprev, this%u0, this%zb, this%xs, this%zs, this%ms)
    end if
    allocate (this%pos_ref(3, nb), this%rp(3, nb), this%frot(3, nb), this%pre(6*nb, 6*nb), this%pscale(6*nb), &
              this%slot(nb, nb), this%zref(6*nb, 6*nb), this%s6p(6*nb), this%perm(6*nb), this%pos(6*nb), &
              this%mref(3*nb, 3*nb))
    call ordering(nb, this%perm, this%pos)
    this%slot = 0
    allocate (this%v(nt, max_iterations + 1), this%hm(max_iterations + 1, max_iterations + 2))
    allocate (this%rhs(nt), this%wk(nt), this%m0(6*nb), this%s6(6*nb), this%uk(6*nb), this%uprev(6*nb), &
              this%u0(6*nb), this%zb(nt, max_iterations), this%xs(nt), this%zs(this%nr), this%ms(6*nb))
  end subroutine ensure_work

  !> The order of the preconditioner's 6N friction and its factor: the rotations of all beads
  !> first, then the translations ([Omega_1, ..., Omega_N, U_1, ..., U_N], each bead's three
  !> components together), so that the translational block of the inverse comes from the
  !> factor's trailing 3N x 3N block alone (`mobility_at`). perm(k): the unknown of the order
  !> [U_1, Omega_1, U_2, ...] at position k; pos: the inverse map.
  pure subroutine ordering(nb, perm, pos)
    integer, intent(in) :: nb
    integer, intent(out) :: perm(:), pos(:)
    integer :: i, c
    do i = 1, nb
      do c = 1, 3
        perm(3*(i - 1) + c) = 6*(i - 1) + 3 + c
        perm(3*nb + 3*(i - 1) + c) = 6*(i - 1) + c
      end do
    end do
    pos(perm) = [(i, i = 1, 6*nb)]
  end subroutine ordering

  !> b = [rhs_Q(e); 0; f, torques 0, + dx : e] (lubrication blocks of the current call).
  subroutine right_hand_side(this, f, e)
    class(multipole_iterative_t), intent(inout) :: this
    real(wp), intent(in) :: f(:, :), e(3, 3)
    integer :: i, nr
    nr = this%nr
    this%rhs = 0.0_wp
    call this%ref%add_strain_rhs(strain_coefficients(e), this%rhs(1:nr))
    do i = 1, size(f, 2)
      this%rhs(nr + 6*i - 5:nr + 6*i - 3) = f(:, i)
    end do
    if (this%lubrication) call this%blocks(this%ib)%add_strain(e, this%rhs(nr + 1:))
  end subroutine right_hand_side

  !> y = A x, the system at the current configuration (module header); `single` (optional,
  !> default .false.): K's products from the single copies (after copy_products_single); always
  !> so when the assembly wrote K0 in single alone.
  subroutine operator_apply(this, x, y, single)
    class(multipole_iterative_t), intent(inout) :: this
    real(wp), intent(in), contiguous :: x(:)
    real(wp), intent(out), contiguous :: y(:)
    logical, intent(in), optional :: single
    integer :: nr, i, c, k, j
    real(wp) :: s
    logical :: use_single
    nr = this%nr
    use_single = .not. this%cur%has_double_products()
    if (present(single)) use_single = use_single .or. single
    if (use_single) then
      call this%cur%apply_single(x(1:nr), y(1:nr))
    else
      call this%cur%apply(x(1:nr), y(1:nr))
    end if
    do i = 1, size(this%rp, 2)
      do c = 1, 6
        k = this%ref%p_row(i, c)
        j = nr + 6*(i - 1) + c
        s = this%ref%moment_scale(c)
        y(k) = y(k) - x(j)/s
        y(j) = x(k)/(pi*s)
      end do
    end do
    if (this%lubrication) call this%blocks(this%ib)%apply(x(nr + 1:), y(nr + 1:))
  end subroutine operator_apply

  !> z = P^-1 g, the inverse of the system at the reference (`exact`: with the double factor;
  !> otherwise its single-precision copy), with one forward and one backward solve of
  !> K_ref = L L^T (P last, so L^-1 E v = [0; L_PP^-1 v] and
  !> (K_ref^-1 g)_P = L_PP^-T (L^-1 g)_P):
  !>   y = L^-1 g_m, U = (zeta_L(ref) + dzeta)^-1 (g_U - S^-1 L_PP^-T y_P / pi),
  !>   m = L^-T (y + [0; L_PP^-1 S^-1 U]) = K_ref^-1 (g_m + E S^-1 U).
  subroutine precondition(this, g, z, exact)
    class(multipole_iterative_t), intent(inout) :: this
    real(wp), intent(in) :: g(:)
    real(wp), intent(out), contiguous :: z(:)
    logical, intent(in) :: exact
    integer :: nr, nq, i, c, j, n6
    nr = this%nr
    nq = nr - size(this%s6)
    if (exact) then
      z(1:nr) = g(1:nr)
      call this%ref%forward(z(1:nr))
      this%m0 = z(nq + 1:nr)
      call this%ref%backward_p(this%m0)
    else
      this%zs = real(g(1:nr), sp)
      call this%ref%forward_single(this%zs)
      this%ms = this%zs(nq + 1:nr)
      call this%ref%backward_p_single(this%ms)
      this%m0 = real(this%ms, wp)
    end if
    do i = 1, size(this%rp, 2)
      do c = 1, 6
        j = 6*(i - 1) + c
        this%s6(j) = g(nr + j) - this%m0(this%ref%p_row(i, c) - nq)/(pi*this%ref%moment_scale(c))
      end do
    end do
    n6 = size(this%s6)
    this%s6p = this%s6(this%perm)
    call dtrsv('L', 'N', 'N', n6, this%pre, n6, this%s6p, 1)
    call dtrsv('L', 'T', 'N', n6, this%pre, n6, this%s6p, 1)
    this%s6(this%perm) = this%s6p
    do i = 1, size(this%rp, 2)
      do c = 1, 6
        this%m0(this%ref%p_row(i, c) - nq) = this%s6(6*(i - 1) + c)/this%ref%moment_scale(c)
      end do
    end do
    if (exact) then
      call this%ref%forward_p(this%m0)
      z(nq + 1:nr) = z(nq + 1:nr) + this%m0
      call this%ref%backward(z(1:nr))
    else
      this%ms = real(this%m0, sp)
      call this%ref%forward_p_single(this%ms)
      this%zs(nq + 1:nr) = this%zs(nq + 1:nr) + this%ms
      call this%ref%backward_single(this%zs)
      z(1:nr) = real(this%zs, wp)
    end if
    z(nr + 1:) = this%s6
  end subroutine precondition

  !> Flexible GMRES (right-preconditioned, the preconditioned basis kept) on A x = b from the
  !> start of warm_start (the extrapolated history, or zero; no restart, at
  !> most max_iterations); uk = the velocity part of the last iterate, `its` the iterations
  !> done, `converged` by the stopping rule of the module header; xs = the solution when
  !> converged. With the basis z_k = P^-1 v_k kept, A Z_k = V_k+1 H_k holds with the double
  !> operator whatever rounding the single-precision preconditioner adds, so the iterates
  !> converge to the exact solution.
  subroutine gmres(this, its, converged)
    class(multipole_iterative_t), intent(inout) :: this
    integer, intent(out) :: its
    logical, intent(out) :: converged
    real(wp) :: beta, cs(max_iterations), sn(max_iterations), gv(max_iterations + 1), y(max_iterations)
    real(wp) :: tmp, den, change, scale, bnorm
    integer :: k, j, nr, nt, nb
    logical :: single, close

    nr = this%nr
    nt = size(this%rhs)
    nb = size(this%rp, 2)
    converged = .false.
    its = 0
    call warm_start(this)
    beta = norm2(this%v(:, 1))
    this%u0 = this%xs(nr + 1:nt)
    this%uk = this%u0
    if (beta == 0.0_wp) then
      converged = .true.
      return
    end if
    ! the loop's products in single when the rule of the module header allows
    ! (the copies come from the assembly when the last call's start satisfied the rule too)
    bnorm = norm2(this%rhs)
    close = beta < bnorm .and. beta <= this%solver_tolerance/(single_margin*0.5_wp*epsilon(1.0_sp))*bnorm &
            .and. nb >= this%single_min_beads
    single = this%cur%has_single_products() .and. (close .or. .not. this%cur%has_double_products())
    this%single_next = close
    if (single) this%istats%single_solves = this%istats%single_solves + 1
    this%v(:, 1) = this%v(:, 1)/beta
    gv = 0.0_wp
    gv(1) = beta
    do k = 1, max_iterations
      its = k
      call precondition(this, this%v(:, k), this%zb(:, k), exact=.false.)
      call operator_apply(this, this%zb(:, k), this%v(:, k + 1), single)
      if (single) this%istats%single_iterations = this%istats%single_iterations + 1
      ! modified Gram-Schmidt
      do j = 1, k
        this%hm(j, k) = dot_product(this%v(:, j), this%v(:, k + 1))
        this%v(:, k + 1) = this%v(:, k + 1) - this%hm(j, k)*this%v(:, j)
      end do
      this%hm(k + 1, k) = norm2(this%v(:, k + 1))
      if (this%hm(k + 1, k) > 0.0_wp) this%v(:, k + 1) = this%v(:, k + 1)/this%hm(k + 1, k)
      ! the earlier Givens rotations, then a new one that zeroes hm(k + 1, k)
      do j = 1, k - 1
        tmp = cs(j)*this%hm(j, k) + sn(j)*this%hm(j + 1, k)
        this%hm(j + 1, k) = -sn(j)*this%hm(j, k) + cs(j)*this%hm(j + 1, k)
        this%hm(j, k) = tmp
      end do
      den = hypot(this%hm(k, k), this%hm(k + 1, k))
      cs(k) = this%hm(k, k)/den
      sn(k) = this%hm(k + 1, k)/den
      this%hm(k, k) = den
      this%hm(k + 1, k) = 0.0_wp
      gv(k + 1) = -sn(k)*gv(k)
      gv(k) = cs(k)*gv(k)
      ! y = R^-1 g, and the velocity part of the iterate x0 + Z y
      do j = k, 1, -1
        y(j) = (gv(j) - dot_product(this%hm(j, j + 1:k), y(j + 1:k)))/this%hm(j, j)
      end do
      this%uprev = this%uk
      this%uk = this%u0 + matmul(this%zb(nr + 1:nt, 1:k), y(1:k))
      if (gv(k + 1) == 0.0_wp) then
        converged = .true.
        exit
      end if
      if (k >= 2) then
        change = largest_velocity(this%uk - this%uprev, nb)
        scale = largest_velocity(this%uk, nb)
        if (change <= this%solver_tolerance*scale) then
          converged = .true.
          exit
        end if
      end if
    end do
    if (.not. converged) return
    this%xs = this%xs + matmul(this%zb(:, 1:its), y(1:its))
  end subroutine gmres

  !> GMRES's start xs and its residual v(:, 1) = b - A xs: the combination sum_j c_j x_j of the
  !> history's solutions with the affine weights c of the call's right-hand side b in theirs
  !> (affine_weights), or zero (v(:, 1) = b) when that has the smaller residual or the history
  !> is empty. x_j solves A_j x_j = b_j, so b - A sum_j c_j x_j = (b - sum_j c_j b_j) -
  !> sum_j c_j (A - A_j) x_j: the fit makes the first term small; the operator changes little
  !> between calls.
  subroutine warm_start(this)
    class(multipole_iterative_t), intent(inout) :: this
    real(wp) :: c(warm_history_max)
    integer :: m
    m = this%hn
    this%v(:, 1) = this%rhs
    if (m == 0) then
      this%xs = 0.0_wp
      return
    end if
    call affine_weights(this%hb(:, 1:m), this%rhs, c(1:m))
    this%xs = matmul(this%hx(:, 1:m), c(1:m))
    call operator_apply(this, this%xs, this%wk)
    this%wk = this%rhs - this%wk
    if (norm2(this%wk) < norm2(this%rhs)) then
      this%v(:, 1) = this%wk
    else
      this%xs = 0.0_wp
    end if
  end subroutine warm_start

  !> The converged call (its right-hand side and solution xs) becomes the history's newest
  !> entry (the oldest dropped when warm_history are stored; the public component taken within
  !> 1..warm_history_max).
  subroutine history_push(this)
    class(multipole_iterative_t), intent(inout) :: this
    integer :: nt, k
    nt = size(this%xs)
    k = max(1, min(this%warm_history, warm_history_max))
    if (allocated(this%hx)) then
      if (size(this%hx, 1) /= nt .or. size(this%hx, 2) /= k) deallocate (this%hb, this%hx)
    end if
    if (.not. allocated(this%hx)) then
      allocate (this%hb(nt, k), this%hx(nt, k))
      this%hn = 0
    end if
    if (this%hn == k) then
      this%hb(:, 1:k - 1) = this%hb(:, 2:k)
      this%hx(:, 1:k - 1) = this%hx(:, 2:k)
    else
      this%hn = this%hn + 1
    end if
    this%hb(:, this%hn) = this%rhs
    this%hx(:, this%hn) = this%xs
  end subroutine history_push

  !> Affine weights c (sum c = 1) of the target y in the points p(:, 1:m) (the newest last):
  !> c minimises |y - sum_j c_j p_j| (least squares in the differences p_j - p_m, newest first;
  !> a difference nearly in the span of the newer ones is dropped, drop_tolerance, its weight
  !> 0), then shrunk towards the newest point, c = (1 - s) e_m + s c, so that sum |c| is at
  !> most weight_bound.
  pure subroutine affine_weights(p, y, c)
    real(wp), intent(in) :: p(:, :), y(:)
    real(wp), intent(out) :: c(:)
    real(wp) :: d(size(p, 1), size(p, 2) - 1), a(size(p, 2) - 1), total, s
    integer :: m, j
    m = size(p, 2)
    c = 0.0_wp
    c(m) = 1.0_wp
    if (m == 1) return
    do j = 1, m - 1
      d(:, j) = p(:, m - j) - p(:, m)
    end do
    call least_squares(d, y - p(:, m), a)
    do j = 1, m - 1
      c(m - j) = a(j)
    end do
    c(m) = 1.0_wp - sum(a)
    total = sum(abs(c))
    if (total > weight_bound) then
      s = (weight_bound - 1.0_wp)/(total - 1.0_wp)
      c = s*c
      c(m) = c(m) + (1.0_wp - s)
    end if
  end subroutine affine_weights

  !> w minimising |y - a w| by modified Gram-Schmidt (twice) over the columns in their order;
  !> a column whose part orthogonal to the kept ones is at most drop_tolerance times its
  !> length (or zero) gets the weight 0.
  pure subroutine least_squares(a, y, w)
    real(wp), intent(in) :: a(:, :), y(:)
    real(wp), intent(out) :: w(:)
    real(wp) :: q(size(a, 1), size(a, 2)), rr(size(a, 2), size(a, 2)), z(size(a, 2)), b(size(a, 2))
    real(wp) :: res(size(a, 1)), col, h
    integer :: keep(size(a, 2)), nk, j, i, pass
    w = 0.0_wp
    nk = 0
    res = y
    rr = 0.0_wp
    do j = 1, size(a, 2)
      col = norm2(a(:, j))
      if (col == 0.0_wp) cycle
      q(:, nk + 1) = a(:, j)
      rr(:, nk + 1) = 0.0_wp
      do pass = 1, 2
        do i = 1, nk
          h = dot_product(q(:, i), q(:, nk + 1))
          rr(i, nk + 1) = rr(i, nk + 1) + h
          q(:, nk + 1) = q(:, nk + 1) - h*q(:, i)
        end do
      end do
      rr(nk + 1, nk + 1) = norm2(q(:, nk + 1))
      if (rr(nk + 1, nk + 1) <= drop_tolerance*col) cycle
      nk = nk + 1
      q(:, nk) = q(:, nk)/rr(nk, nk)
      keep(nk) = j
      z(nk) = dot_product(q(:, nk), res)
      res = res - z(nk)*q(:, nk)
    end do
    do i = nk, 1, -1
      b(i) = (z(i) - dot_product(rr(i, i + 1:nk), b(i + 1:nk)))/rr(i, i)
    end do
    w(keep(1:nk)) = b(1:nk)
  end subroutine least_squares

  !> The 3N x 3N mobility for a linearly implicit stepper's Jacobian at r. At the model's own
  !> order (jacobian_order = the order, the default) and once a reference exists: the inverse of
  !> the preconditioner's 6N friction, zeta_L(ref) + dzeta_f (the model's order, lubrication
  !> included, at the reference; dzeta_f the blocks of the call that last factorised it), its
  !> translational blocks rotated onto r by the best rigid rotation Q of the reference onto r,
  !> mu_ij(r) = Q mu_ij(ref) Q^T (Stokes flow is covariant): exact at the reference and at its
  !> rigid motions, otherwise the mobility of a nearby configuration (a W-method keeps its order
  !> with any Jacobian). The first call after a factorisation of the 6N factor costs one dpotri
  !> of size 3N with the factor's trailing block (the translations, `ordering`), no factorisation
  !> of K; the blocks mu(ref) are kept, so later calls with the same factor cost the rotation (the
  !> same numbers as made anew). Otherwise (a lower jacobian_order, or no reference yet) the exact
  !> model's (kf_hydro_multipole `mobility_at`).
  subroutine iterative_mobility_at(this, r, mu, error)
    class(multipole_iterative_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: mu(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: q(3, 3)
    integer :: nb, j, n3, n6, info
    logical :: own
    nb = size(r, 2)
    own = this%ready .and. this%jacobian_order == this%order
    if (own) own = size(this%pos_ref, 2) == nb
    if (.not. own) then
      call this%multipole_model_t%mobility_at(r, mu, error)
      return
    end if
    call best_rotation(this%pos_ref, r, q, error)
    if (allocated(error)) return
    n3 = 3*nb
    if (.not. this%mref_valid) then
      ! the translations are the trailing 3N unknowns of the factor Z = L L^T (`ordering`), so
      ! the translational block of Z^-1 is (L_TT L_TT^T)^-1, L_TT the trailing 3N x 3N block of L
      ! (L^-1 is block lower triangular): one dpotri of size 3N
      n6 = 6*nb
      this%mref = this%pre(n3 + 1:n6, n3 + 1:n6)
      call dpotri('L', n3, this%mref, n3, info)
      if (info /= 0) then
        call fatal_error(error, 'multipole iterative: the Jacobian mobility''s inverse failed (dpotri info = '// &
                         to_str(info)//')')
        return
      end if
      do j = 1, n3
        this%mref(j, j + 1:n3) = this%mref(j + 1:n3, j)
      end do
      this%mref_valid = .true.
      this%istats%mobilities = this%istats%mobilities + 1
    end if
    call rotate_blocks(q, this%mref, mu)
  end subroutine iterative_mobility_at

  !> Its calls never prepare, so a mobility costs solves with the 6N factor (or, of a lower
  !> jacobian_order, a factorisation); its reference is rebuilt after a resume anyway: an earlier
  !> mobility may be kept.
  pure logical function iterative_mobility_reusable(this) result(reusable)
    class(multipole_iterative_t), intent(in) :: this
    reusable = .true.
    associate (unused_this => this)
    end associate
  end function iterative_mobility_reusable

end module kf_hydro_multipole_iterative
