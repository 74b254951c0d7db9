!> Checking the adaptive reuse of the hydrodynamic model along a real run: an ODE system that
!> integrates with one dynamics (the adaptive one, or another update such as 'iterative', which
!> sees the stepper's hooks) and, at
!> every stage, computes also the velocities of a second dynamics (the exact one) at the
!> same positions, and accumulates the relative errors of the velocities relative to the
!> ambient flow (kf_accuracy's velocity_error_norms: RMS over beads and max over beads, both
!> relative to the exact velocities).
module kf_reuse_check
  use kf_kinds, only: wp, i8
  use kf_error, only: error_t
  use kf_scene, only: scene_t
  use kf_scene_hydro, only: update_stage, update_adaptive
  use kf_hydro_limits, only: solver_tolerance_default
  use kf_dynamics, only: dynamics_t
  use kf_hydro_model, only: hydro_model_t
  use kf_ode_system, only: ode_system_t
  use kf_accuracy, only: velocity_error_norms
  implicit none
  private

  !> The adaptive dynamics, checked against the exact one at every stage.
  type, extends(ode_system_t), public :: checked_dynamics_t
    type(dynamics_t) :: fast                !< integrates (update = 'adaptive')
    type(dynamics_t) :: exact               !< update = 'stage'
    integer(i8) :: checks = 0               !< stages compared
    real(wp) :: max_rms = 0.0_wp            !< largest relative RMS error of a stage
    real(wp) :: max_max = 0.0_wp            !< largest relative max error of a stage
    real(wp) :: sum_rms = 0.0_wp            !< sum of the relative RMS errors
    integer :: every = 1                    !< compare every k-th stage only
    integer(i8), private :: calls = 0
    real(wp), allocatable, private :: v(:, :), v0(:, :)
  contains
    procedure :: init => checked_init
    procedure :: derivative => checked_derivative
    procedure :: step_begin => checked_step_begin
    procedure :: step_accepted => checked_step_accepted
    procedure :: step_rejected => checked_step_rejected
  end type checked_dynamics_t

contains

  !> The scene with update = 'adaptive' (or fast_update, e.g. 'iterative') integrates, the same
  !> with 'stage' is the reference; `fast_model` (optional): the integrating path's model, made
  !> by the caller (kf_dynamics `init`'s `model`).
  subroutine checked_init(this, scene, n_beads, error, every, fast_update, fast_model)
    class(checked_dynamics_t), intent(inout) :: this
    type(scene_t), intent(in) :: scene
    integer, intent(in) :: n_beads
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: every
    character(len=*), intent(in), optional :: fast_update
    class(hydro_model_t), allocatable, intent(inout), optional :: fast_model
    type(scene_t) :: sc
    sc = scene
    sc%hydro%update = update_adaptive
    if (present(fast_update)) sc%hydro%update = fast_update
    call this%fast%init(sc, n_beads, error, fast_model)
    if (allocated(error)) return
    sc%hydro%update = update_stage
    sc%hydro%solver_tolerance = solver_tolerance_default   ! the fast path's setting only
    call this%exact%init(sc, n_beads, error)
    if (allocated(error)) return
    allocate (this%v(3, n_beads), this%v0(3, n_beads))
    this%every = 1
    if (present(every)) this%every = max(1, every)
  end subroutine checked_init

  subroutine checked_derivative(this, t, y, dydt, error)
    class(checked_dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: t
    real(wp), intent(in) :: y(:, :)
    real(wp), intent(out) :: dydt(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: rms, mx
    call this%fast%derivative(t, y, dydt, error)
    if (allocated(error)) return
    this%calls = this%calls + 1
    if (mod(this%calls - 1, int(this%every, i8)) /= 0) return
    call this%exact%velocity(y, this%v, error)
    if (allocated(error)) return
    call this%exact%flow_velocity(y, this%v0)
    call velocity_error_norms(dydt - this%v0, this%v - this%v0, rms, mx)
    this%checks = this%checks + 1
    this%max_rms = max(this%max_rms, rms)
    this%max_max = max(this%max_max, mx)
    this%sum_rms = this%sum_rms + rms
  end subroutine checked_derivative

  subroutine checked_step_begin(this, t, y, h)
    class(checked_dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: t, y(:, :), h
    call this%fast%step_begin(t, y, h)
  end subroutine checked_step_begin

  subroutine checked_step_accepted(this, t, y)
    class(checked_dynamics_t), intent(inout) :: this
    real(wp), intent(in) :: t, y(:, :)
    call this%fast%step_accepted(t, y)
  end subroutine checked_step_accepted

  subroutine checked_step_rejected(this)
    class(checked_dynamics_t), intent(inout) :: this
    call this%fast%step_rejected()
  end subroutine checked_step_rejected

end module kf_reuse_check
