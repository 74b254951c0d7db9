!> The equations of motion (PHYSICS.md section 3): dr_i/dt = G r_i + sum_j mu_ij F_j(r)
!> + sum_j C_ij : E, assembled from a forces_t, a hydrodynamic model and a flow_t that are
!> all built once from the scene. As an ode_system_t the state y is r(3, N).
!> One pair-geometry pass per evaluation (kf_pair_geometry, to the largest range the forces and
!> the model need) serves the excluded volume and the lubrication corrections; the run
!> diagnostics use it too when it was built at the configuration they look at (`pairs`).
!> The overlap rule (kf_overlap_rule) says at which configuration the hydrodynamics is evaluated:
!> the positions themselves, or, under 'separate' and only while beads overlap, the nearest
!> configuration without overlaps, whose velocities (ambient flow included) the beads then take;
!> under 'relax' the beads also move towards that configuration (its kinematic contact velocity).
!> The parts (forces, model, flow) are private: run/ and the programs reach them through the
!> operations below (`compute_forces`, `flow_velocity`, `force_velocity`, `reused_velocity`,
!> `hydro_statistics`, `stresslet`).
module kf_dynamics
  use kf_kinds, only: wp, i8
  use kf_error, only: error_t
  use kf_scene, only: scene_t
  use kf_forces, only: forces_t
  use kf_flow, only: flow_t
  use kf_hydro_model, only: hydro_model_t, hydro_stats_t
  use kf_hydro_factory, only: make_hydro_model, make_overlap_rule
  use kf_overlap_rule, only: overlap_rule_t
  use kf_scene_hydro, only: effective_eps_lub
  use kf_ode_system, only: ode_system_t
  use kf_blas, only: dgemm
  use kf_pair_geometry, only: pair_geometry_t
  use kf_rheology, only: fibre_stresslet_t, elastic_stresslet, shear_observables
  implicit none
  private

  !> Forces, hydrodynamics and ambient flow of one case.
  type, extends(ode_system_t), public :: dynamics_t
    type(forces_t), private :: forces
    class(hydro_model_t), allocatable, private :: model
    type(flow_t), private :: flow
    integer :: n = 0                     !< number of beads
    integer(i8) :: evaluations = 0       !< calls of velocity
    real(wp) :: pair_cutoff = 0.0_wp     !< range of the pair list (0: none is built)
    type(pair_geometry_t) :: pairs       !< close pairs of the last evaluation's positions
    class(overlap_rule_t), allocatable, private :: overlap !< where the hydrodynamics is evaluated
    type(pair_geometry_t), private :: hydro_pairs !< close pairs of the separated configuration
    real(wp), allocatable, private :: f(:, :)     !< work: forces of the last evaluation
    real(wp), allocatable, private :: u(:, :)     !< work: mu F + C:E of the last evaluation
    real(wp), allocatable, private :: rh(:, :)    !< work: the separated configuration
    integer, private :: mobility_steps = 1        !< Jacobians a kept mobility serves (&integrator jacobian_steps)
    integer, private :: mobility_uses = 0         !< Jacobians the kept mobility has served
    real(wp), allocatable, private :: mu(:, :)    !< the mobility of the Jacobian
  contains
    procedure :: init => dynamics_init
    procedure :: velocity => dynamics_velocity
    procedure :: need_pairs
    procedure :: derivative => dynamics_derivative
    procedure :: step_begin => dynamics_step_begin
    procedure :: step_accepted => dynamics_step_accepted
    procedure :: step_rejected => dynamics_step_rejected
    procedure :: jacobian => dynamics_jacobian
    procedure :: stresslet => dynamics_stresslet
    procedure :: compute_forces => dynamics_compute_forces
    procedure :: flow_velocity => dynamics_flow_velocity
    procedure :: force_velocity => dynamics_force_velocity
    procedure :: reused_velocity => dynamics_reused_velocity
    procedure :: hydro_statistics => dynamics_hydro_statistics
  end type dynamics_t

contains

  !> Build forces, hydrodynamic model and flow from the scene for a chain of n_beads. `model`
  !> (optional, allocated): a hydrodynamic model the caller built from scene%hydro (e.g. the
  !> factory's with a setup value changed, for a benchmark), taken over instead of the factory's.
  subroutine dynamics_init(this, scene, n_beads, error, model)
    class(dynamics_t), intent(out) :: this
    type(scene_t), intent(in) :: scene
    integer, intent(in) :: n_beads
    type(error_t), allocatable, intent(out) :: error
    class(hydro_model_t), allocatable, intent(inout), optional :: model
    call this%forces%init(scene%forces, n_beads, scene%chain%bond_length, error)
    if (allocated(error)) return
    call this%flow%init(scene%flow, error)
    if (allocated(error)) return
    if (present(model)) then
      if (allocated(model)) call move_alloc(model, this%model)
    end if
    if (.not. allocated(this%model)) call make_hydro_model(scene%hydro, scene%integrator%tolerance, this%model, error)
    if (allocated(error)) return
    call make_overlap_rule(scene%hydro%overlap, &
      effective_eps_lub(scene%hydro, scene%integrator%tolerance), scene%hydro%overlap_time, this%overlap, error)
    if (allocated(error)) return
    this%n = n_beads
    this%mobility_steps = scene%integrator%jacobian_steps
    this%mobility_uses = 0
    this%pair_cutoff = max(this%forces%pair_range(), this%model%pair_cutoff())
    allocate (this%f(3, n_beads), this%u(3, n_beads), this%rh(3, n_beads))
  end subroutine dynamics_init

  !> Build the pair list of every evaluation to at least `cutoff` (for a monitor that shares it).
  subroutine need_pairs(this, cutoff)
    class(dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: cutoff
    this%pair_cutoff = max(this%pair_cutoff, cutoff)
  end subroutine need_pairs
  !> The fibre's stresslet at r(3, N) (kf_rheology): the hydrodynamic part from the model (exact
  !> at r), the elastic part from the forces, and, in simple shear (v0 = (G_13 z, 0, 0)), the
  !> viscosity and normal-stress coefficients (left 0 in other flows).
  subroutine dynamics_stresslet(this, r, st, error)
    class(dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    type(fibre_stresslet_t), intent(out) :: st
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: g(3, 3)
    logical :: moved
    call this%forces%compute(r, this%f)
    call this%overlap%hydro_configuration(r, this%pairs, this%rh, moved, error)
    if (allocated(error)) return
    if (moved) then
      call this%model%stresslet(this%rh, this%f, this%flow%e, st%hydrodynamic, error)
    else
      call this%model%stresslet(r, this%f, this%flow%e, st%hydrodynamic, error)
    end if
    if (allocated(error)) return
    st%elastic = elastic_stresslet(r, this%f)
    g = this%flow%g
    g(1, 3) = 0.0_wp
    if (this%flow%g(1, 3) /= 0.0_wp .and. all(g == 0.0_wp)) &
      call shear_observables(st, size(r, 2), this%flow%g(1, 3))
  end subroutine dynamics_stresslet

  !> Bead velocities v(3, N) at positions r(3, N), at time t of an integration (optional; a
  !> hydrodynamic model that reuses work between the stages needs it).
  subroutine dynamics_velocity(this, r, v, error, t)
    class(dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: v(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in), optional :: t
    logical :: moved
    this%evaluations = this%evaluations + 1
    if (this%pair_cutoff > 0.0_wp) call this%pairs%build(r, this%pair_cutoff)
    call this%forces%compute(r, this%f, this%pairs)
    call this%overlap%hydro_configuration(r, this%pairs, this%rh, moved, error)
    if (allocated(error)) return
    if (moved) then
      call this%hydro_pairs%build(this%rh, this%pair_cutoff)
      call hydro_velocities(this%rh, this%hydro_pairs)
    else
      call hydro_velocities(r, this%pairs)
    end if
    if (allocated(error)) return
    call this%overlap%add_contact_velocity(r, this%rh, moved, v)

  contains

    !> v = v0(x) + mu F + C:E with the hydrodynamics of configuration x.
    subroutine hydro_velocities(x, x_pairs)
      real(wp), intent(in) :: x(:, :)
      type(pair_geometry_t), intent(in) :: x_pairs
      if (this%flow%has_strain) then
        call this%model%velocities(x, this%f, this%u, error, this%flow%e, t, x_pairs)
      else
        call this%model%velocities(x, this%f, this%u, error, t=t, pairs=x_pairs)
      end if
      if (allocated(error)) return
      call this%flow%velocity(x, v)
      v = v + this%u
    end subroutine hydro_velocities
  end subroutine dynamics_velocity

  !> The bead forces f(3, N) at r(3, N) (kf_forces; no shared pair list).
  subroutine dynamics_compute_forces(this, r, f)
    class(dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: f(:, :)
    call this%forces%compute(r, f)
  end subroutine dynamics_compute_forces

  !> The ambient flow's velocities v0(3, N) at r(3, N) (kf_flow).
  subroutine dynamics_flow_velocity(this, r, v0)
    class(dynamics_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: v0(:, :)
    call this%flow%velocity(r, v0)
  end subroutine dynamics_flow_velocity

  !> The force-driven part uf = mu(r) F(r) of the velocities, exact at r (the model prepared at
  !> r itself, whatever it reuses and whatever the overlap rule; no ambient flow, no strain).
  subroutine dynamics_force_velocity(this, r, uf, error)
    class(dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: uf(:, :)
    type(error_t), allocatable, intent(out) :: error
    call this%forces%compute(r, this%f)
    call this%model%prepare(r, error)
    if (allocated(error)) return
    call this%model%apply_mobility(this%f, uf)
  end subroutine dynamics_force_velocity

  !> The velocities v(3, N) at r from the part the model reuses, as it is (`reused_velocities`
  !> of the model: no refresh), plus the ambient flow; an error when the model reuses nothing.
  subroutine dynamics_reused_velocity(this, r, v, error)
    class(dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: v(:, :)
    type(error_t), allocatable, intent(out) :: error
    call this%forces%compute(r, this%f)
    call this%model%reused_velocities(r, this%f, this%u, error, this%flow%e)
    if (allocated(error)) return
    call this%flow%velocity(r, v)
    v = v + this%u
  end subroutine dynamics_reused_velocity

  !> The hydrodynamic model's work counters (kf_hydro_model `statistics`).
  function dynamics_hydro_statistics(this) result(s)
    class(dynamics_t), intent(in) :: this
    type(hydro_stats_t) :: s
    s = this%model%statistics()
  end function dynamics_hydro_statistics

  !> The ode_system_t interface: dydt = velocity(y) (the system is autonomous).
  subroutine dynamics_derivative(this, t, y, dydt, error)
    class(dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: t
    real(wp), intent(in) :: y(:, :)
    real(wp), intent(out) :: dydt(:, :)
    type(error_t), allocatable, intent(out) :: error
    call this%velocity(y, dydt, error, t)
  end subroutine dynamics_derivative

  !> The Jacobian the linearly implicit steppers use (kf_ode_system `jacobian`):
  !>   J = G (x) I + mu dF/dr (y),
  !> the ambient flow's gradient on every bead (exact: v0 is linear) and the forces' Jacobian at y
  !> (kf_forces `jacobian`) times a mobility: the model's at y (`mobility_at`: free after a
  !> 'stage' evaluation at y), or, where the model allows it (`mobility_reusable`: 'adaptive',
  !> whose new mobility costs a factorisation, and 'iterative', solves with its 6N factor) and
  !> it is not at hand, the one of an
  !> earlier call, kept for &integrator jacobian_steps calls in all. Left out: the change of mu
  !> and of the strain disturbance C:E with y, and the overlap rule's configuration (exact where
  !> the forces vanish, no strain acts and no pair overlaps); a W-method keeps its order with
  !> any J. No velocity evaluation is spent (evaluations = 0).
  subroutine dynamics_jacobian(this, t, y, jac, evaluations, error)
    class(dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: t
    real(wp), intent(in) :: y(:, :)
    real(wp), intent(out) :: jac(:, :)
    integer, intent(out) :: evaluations
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: k(:, :)
    integer :: n3, i
    logical :: renew
    evaluations = 0
    n3 = size(y)
    renew = .not. allocated(this%mu)
    if (.not. renew) renew = size(this%mu, 1) /= n3
    if (.not. renew) renew = this%mobility_uses >= this%mobility_steps .or. .not. this%model%mobility_reusable() &
                             .or. this%model%mobility_cached(y)
    if (renew) then
      if (allocated(this%mu)) deallocate (this%mu)
      allocate (this%mu(n3, n3))
      call this%model%mobility_at(y, this%mu, error)
      if (allocated(error)) then
        deallocate (this%mu)
        return
      end if
      this%mobility_uses = 0
    end if
    this%mobility_uses = this%mobility_uses + 1
    allocate (k(n3, n3))
    call this%forces%jacobian(y, k)
    call mobility_times(this%mu, k, jac)
    do i = 1, size(y, 2)
      jac(3*i - 2:3*i, 3*i - 2:3*i) = jac(3*i - 2:3*i, 3*i - 2:3*i) + this%flow%g
    end do
  end subroutine dynamics_jacobian

  !> The stepper's hooks go to the hydrodynamic model (the one part that reuses work).
  subroutine dynamics_step_begin(this, t, y, h)
    class(dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: t, y(:, :), h
    call this%model%step_begin(h)
  end subroutine dynamics_step_begin

  subroutine dynamics_step_accepted(this, t, y)
    class(dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: t, y(:, :)
    call this%model%step_accepted()
  end subroutine dynamics_step_accepted

  subroutine dynamics_step_rejected(this)
    class(dynamics_t), intent(inout) :: this
    call this%model%step_rejected()
  end subroutine dynamics_step_rejected

  !> jac = mu k. The forces' Jacobian k of a chain is banded (bonds and bending couple beads at
  !> most two apart; a few excluded-volume pairs add entries): with at most an eighth of its
  !> entries nonzero, each column of jac is the sum over that column's nonzero entries of
  !> k(i, j) mu(:, i) (the same sum as the dense product without its zero terms; about 15 of
  !> 3N terms per column for a chain), else one dense product (dgemm).
  subroutine mobility_times(mu, k, jac)
    real(wp), intent(in) :: mu(:, :), k(:, :)
    real(wp), intent(out) :: jac(:, :)
    integer :: n3, i, j
    n3 = size(k, 1)
    if (count(k /= 0.0_wp) > size(k)/8) then
      call dgemm('N', 'N', n3, n3, n3, 1.0_wp, mu, n3, k, n3, 0.0_wp, jac, n3)
      return
    end if
    do j = 1, n3
      jac(:, j) = 0.0_wp
      do i = 1, n3
        if (k(i, j) /= 0.0_wp) jac(:, j) = jac(:, j) + k(i, j)*mu(:, i)
      end do
    end do
  end subroutine mobility_times

end module kf_dynamics
