!> The abstract hydrodynamic model. Bead velocities are
!>   dr_i/dt = v0(r_i) + sum_j mu_ij F_j + sum_j C_ij : E,
!> with mu (3N x 3N) the translational mobility of torque-free beads and C:E the disturbance
!> of force-free, torque-free beads in the ambient rate of strain E.
!> Units of PHYSICS.md section 1: an isolated bead has mobility 1/3.
!>
!> `stresslet(r, f, e, s, error)`: the sum over the beads of their hydrodynamic stresslets
!> (Batchelor's sign: the symmetric traceless first moment of the traction the fluid exerts on
!> each bead, about the bead's centre; an isolated bead in the strain E has (20/3) pi eta a^3 E)
!> for beads at r that carry the forces f in the ambient strain e, exact at r whatever a model
!> reuses. Units pi eta d^3 (rate of strain in the time unit): an isolated bead gives (5/6) E.
!> The default is exact for any model whose grand mobility is symmetric, by the reciprocal
!> theorem: the stresslet due to the forces satisfies S_F : E' = - sum_j F_j . (C:E')_j, so it
!> follows from the model's own disturbance C; to it add N (5/6) E (every bead's own) and the
!> model's strain-strain pair couplings (`add_pair_strain_stresslet`, none by default).
!>
!> The expensive work depends only on positions: `prepare(r)` (assemble, factorise), then any
!> number of cheap `apply_mobility(f, u)` / `add_strain_disturbance(e, u)` calls.
!>
!> The dynamics asks for `velocities(r, f, u, error, e, t)` instead: by default the same three
!> calls, but a model may reuse work across the stages and steps of the time integration,
!> within an error budget. The time stepper's hooks reach the model through `step_begin`
!> (with the trial step size, from which such a budget follows), `step_accepted` and
!> `step_rejected`; `statistics` reports the work done, and a model that reuses work answers
!> `reused_velocities` (the velocities from its reused part as it is, for measurements; the
!> default: an error, nothing is reused).
module kf_hydro_model
  use kf_kinds, only: wp, i8
  use kf_error, only: error_t, fatal_error
  use kf_pair_geometry, only: pair_geometry_t
  use kf_strain_basis, only: strain_basis, tensor_from_pairings
  implicit none
  private

  !> Work counters of a model (all zero for a model that reuses nothing).
  type, public :: hydro_stats_t
    integer(i8) :: evaluations = 0     !< calls of velocities
    integer(i8) :: refreshes = 0       !< exact computations of the many-body part
    integer(i8) :: reused = 0          !< evaluations that reused an earlier many-body part
    integer(i8) :: cg_iterations = 0   !< conjugate-gradient iterations of the reused evaluations
    integer(i8) :: preconditioners = 0 !< factorisations of the preconditioner between refreshes
    integer(i8) :: single_solves = 0   !< reused evaluations whose iterations used single-precision products
    integer(i8) :: single_iterations = 0 !< their iterations (part of cg_iterations)
    integer(i8) :: mobilities = 0      !< Jacobian mobilities made from a factor (not from one kept since it)
    real(wp) :: max_error_ratio = 0.0_wp !< largest measured reuse error / error budget
    real(wp) :: refresh_seconds = 0.0_wp !< wall time of the evaluations that refreshed
    real(wp) :: reused_seconds = 0.0_wp  !< wall time of the evaluations that reused
  end type hydro_stats_t

  type, abstract, public :: hydro_model_t
    integer :: n = 0   !< number of beads at the last prepare
  contains
    procedure(prepare_i), deferred :: prepare
    procedure(apply_i), deferred :: apply_mobility
    procedure(disturb_i), deferred :: add_strain_disturbance
    procedure(name_i), deferred :: name
    procedure :: mobility_matrix
    procedure :: mobility_at
    procedure :: mobility_cached
    procedure :: mobility_reusable
    procedure :: velocities
    procedure :: step_begin
    procedure :: step_accepted
    procedure :: step_rejected
    procedure :: statistics
    procedure :: reused_velocities
    procedure :: pair_cutoff
    procedure :: stresslet
    procedure :: add_pair_strain_stresslet
  end type hydro_model_t

  !> Stresslet of an isolated bead per unit rate of strain, (20/3) pi eta a^3 with a = d/2, in
  !> units of pi eta d^3.
  real(wp), parameter, public :: single_bead_stresslet = 5.0_wp/6.0_wp

  abstract interface
    !> Set up for bead centres r(3, N); `pairs`: the close pairs of r if the caller has them
    !> (kf_pair_geometry; a model that needs them to pair_cutoff() and finds them not covering
    !> r finds its own).
    subroutine prepare_i(this, r, error, pairs)
      import :: hydro_model_t, wp, error_t, pair_geometry_t
      class(hydro_model_t), intent(inout) :: this
      real(wp), intent(in) :: r(:, :)
      type(error_t), allocatable, intent(out) :: error
      type(pair_geometry_t), intent(in), optional :: pairs
    end subroutine prepare_i
    !> u = mu f for forces f(3, N) (u is overwritten).
    subroutine apply_i(this, f, u)
      import :: hydro_model_t, wp
      class(hydro_model_t), intent(inout) :: this
      real(wp), intent(in) :: f(:, :)
      real(wp), intent(out) :: u(:, :)
    end subroutine apply_i
    !> u = u + C:E for the symmetric traceless rate of strain e(3, 3).
    subroutine disturb_i(this, e, u)
      import :: hydro_model_t, wp
      class(hydro_model_t), intent(inout) :: this
      real(wp), intent(in) :: e(3, 3)
      real(wp), intent(inout) :: u(:, :)
    end subroutine disturb_i
    !> A short description of the model, e.g. "rpy" or "multipole L=2 lubrication".
    function name_i(this) result(label)
      import :: hydro_model_t
      class(hydro_model_t), intent(in) :: this
      character(len=:), allocatable :: label
    end function name_i
  end interface

contains

  !> The full 3N x 3N mobility, row 3(i-1)+a, column 3(j-1)+b (after prepare).
  !> Models that hold the matrix override this; the default applies mu to unit forces.
  subroutine mobility_matrix(this, mu)
    class(hydro_model_t), intent(inout) :: this
    real(wp), intent(out) :: mu(:, :)
    real(wp), allocatable :: f(:, :), u(:, :)
    integer :: j, b
    allocate (f(3, this%n), u(3, this%n))
    do j = 1, this%n
      do b = 1, 3
        f = 0.0_wp
        f(b, j) = 1.0_wp
        call this%apply_mobility(f, u)
        mu(:, 3*(j - 1) + b) = reshape(u, [3*this%n])
      end do
    end do
  end subroutine mobility_matrix

  !> The full 3N x 3N mobility at r (layout as mobility_matrix), exact at r whatever the model
  !> reuses in `velocities`. The default prepares at r; a model that knows it is prepared at r
  !> already may skip that (the linearly implicit stepper asks right after an evaluation at r).
  subroutine mobility_at(this, r, mu, error)
    class(hydro_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: mu(:, :)
    type(error_t), allocatable, intent(out) :: error
    call this%prepare(r, error)
    if (allocated(error)) return
    call this%mobility_matrix(mu)
  end subroutine mobility_at

  !> Is the mobility at r at hand already (`mobility_at` then costs a copy)? Default: no.
  logical function mobility_cached(this, r)
    class(hydro_model_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :)
    mobility_cached = .false.
    associate (unused_this => this, unused_r => r)
    end associate
  end function mobility_cached

  !> May a user of the mobility (the dynamics' Jacobian) keep an earlier one instead of asking
  !> `mobility_at` at every configuration? Only where that costs a factorisation and the model
  !> reuses work across calls itself (so that a resumed run is not bitwise the uninterrupted one
  !> anyway); default: no.
  pure logical function mobility_reusable(this)
    class(hydro_model_t), intent(in) :: this
    mobility_reusable = .false.
    associate (unused_this => this)
    end associate
  end function mobility_reusable

  !> u = mu(r) f + C(r) : e (u is overwritten; no strain term when e is absent) at time t of
  !> the integration (optional: a model that reuses work needs it). The default prepares at r
  !> and applies: exact at every call. `pairs` as for prepare.
  subroutine velocities(this, r, f, u, error, e, t, pairs)
    class(hydro_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :)
    real(wp), intent(out) :: u(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in), optional :: e(3, 3), t
    type(pair_geometry_t), intent(in), optional :: pairs
    call this%prepare(r, error, pairs)
    if (allocated(error)) return
    call this%apply_mobility(f, u)
    if (present(e)) call this%add_strain_disturbance(e, u)
  end subroutine velocities

  !> A trial step of size h begins (the default ignores it).
  subroutine step_begin(this, h)
    class(hydro_model_t), intent(inout) :: this
    real(wp), intent(in) :: h
  end subroutine step_begin

  !> The step was accepted (the default ignores it).
  subroutine step_accepted(this)
    class(hydro_model_t), intent(inout) :: this
  end subroutine step_accepted

  !> The trial step was rejected (the default ignores it).
  subroutine step_rejected(this)
    class(hydro_model_t), intent(inout) :: this
  end subroutine step_rejected

  !> Work counters; zero for a model that reuses nothing.
  function statistics(this) result(s)
    class(hydro_model_t), intent(in) :: this
    type(hydro_stats_t) :: s
    s = hydro_stats_t()
  end function statistics

  !> u from the part of an earlier evaluation that the model reuses, as it is at r (no refresh),
  !> for forces f and the strain e: what a reusing model returns when it reuses that part at r
  !> (for tests and measurements). The default: an error, the model reuses nothing.
  subroutine reused_velocities(this, r, f, u, error, e)
    class(hydro_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :)
    real(wp), intent(out) :: u(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in), optional :: e(3, 3)
    u = 0.0_wp
    call fatal_error(error, 'the hydrodynamic model '//this%name()//' reuses nothing (reused_velocities: '// &
                     "&hydro update = 'adaptive')")
  end subroutine reused_velocities

  !> The largest centre distance at which the model treats pairs apart (lubrication); 0 when it
  !> needs no pair list.
  pure real(wp) function pair_cutoff(this)
    class(hydro_model_t), intent(in) :: this
    pair_cutoff = 0.0_wp
  end function pair_cutoff
  !> s = the sum of the beads' hydrodynamic stresslets (see the module header) for beads at
  !> r(3, N) carrying the forces f(3, N) (torque-free) in the ambient symmetric traceless
  !> strain e: prepares the model at r, so a model's cached state is that of r afterwards.
  subroutine stresslet(this, r, f, e, s, error)
    class(hydro_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), f(:, :), e(3, 3)
    real(wp), intent(out) :: s(3, 3)
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: u(:, :)
    real(wp) :: m(5)
    integer :: k
    s = 0.0_wp
    call this%prepare(r, error)
    if (allocated(error)) return
    allocate (u(3, size(r, 2)))
    do k = 1, 5
      u = 0.0_wp
      call this%add_strain_disturbance(strain_basis(k), u)
      m(k) = -sum(f*u)
    end do
    s = real(size(r, 2), wp)*single_bead_stresslet*e + tensor_from_pairings(m)
    call this%add_pair_strain_stresslet(r, e, s)
  end subroutine stresslet

  !> s = s + the stresslets that the beads' own strain stresslets induce on each other (after
  !> prepare at r). The default adds nothing: beads that do not disturb each other's strain.
  subroutine add_pair_strain_stresslet(this, r, e, s)
    class(hydro_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), e(3, 3)
    real(wp), intent(inout) :: s(3, 3)
  end subroutine add_pair_strain_stresslet

end module kf_hydro_model
