!> Free draining (PHYSICS.md 3.1): mu_ij = delta_ij I/3, no strain disturbance.
module kf_hydro_none
  use kf_kinds, only: wp
  use kf_pair_geometry, only: pair_geometry_t
  use kf_error, only: error_t
  use kf_hydro_model, only: hydro_model_t
  implicit none
  private

  !> Isolated beads: each moves with F/3 relative to the ambient flow.
  type, extends(hydro_model_t), public :: none_model_t
  contains
    procedure :: prepare => none_prepare
    procedure :: apply_mobility => none_apply
    procedure :: add_strain_disturbance => none_disturb
    procedure :: name => none_name
  end type none_model_t

contains

  subroutine none_prepare(this, r, error, pairs)
    class(none_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    type(pair_geometry_t), intent(in), optional :: pairs
    this%n = size(r, 2)
  end subroutine none_prepare

  subroutine none_apply(this, f, u)
    class(none_model_t), intent(inout) :: this
    real(wp), intent(in) :: f(:, :)
    real(wp), intent(out) :: u(:, :)
    u = f/3.0_wp
  end subroutine none_apply

  !> Point-like beads do not disturb each other: nothing to add.
  subroutine none_disturb(this, e, u)
    class(none_model_t), intent(inout) :: this
    real(wp), intent(in) :: e(3, 3)
    real(wp), intent(inout) :: u(:, :)
  end subroutine none_disturb

  function none_name(this) result(label)
    class(none_model_t), intent(in) :: this
    character(len=:), allocatable :: label
    label = 'none'
  end function none_name

end module kf_hydro_none
