!> The ambient linear flow v0 = G r (PHYSICS.md section 1): simple shear (G(1,3) = shear_rate),
!> a general traceless linear flow, or quiescent fluid.
module kf_flow
  use kf_kinds, only: wp
  use kf_error, only: error_t
  use kf_scene_flow, only: flow_params_t, flow_shear, flow_linear, flow_quiescent, check_flow
  implicit none
  private

  !> Velocity gradient G(i,j) = d v0_i / d r_j, rate of strain E = (G + G^T)/2 and the angular
  !> velocity Omega0 = curl(v0)/2 of the ambient flow.
  type, public :: flow_t
    real(wp) :: g(3, 3) = 0.0_wp
    real(wp) :: e(3, 3) = 0.0_wp
    real(wp) :: omega(3) = 0.0_wp
    logical :: has_strain = .false.
  contains
    procedure :: init => flow_init
    procedure :: velocity => flow_velocity
  end type flow_t

contains

  !> Set up the flow from the &flow parameters, checked by the &flow group's own rules
  !> (kf_scene_flow: the names, a traceless linear flow).
  subroutine flow_init(this, params, error)
    class(flow_t), intent(out) :: this
    type(flow_params_t), intent(in) :: params
    type(error_t), allocatable, intent(out) :: error
    call check_flow(params, '', error)
    if (allocated(error)) return
    this%g = 0.0_wp
    select case (trim(params%flow_type))
    case (flow_shear)
      this%g(1, 3) = params%shear_rate
    case (flow_linear)
      this%g = params%velocity_gradient
    case (flow_quiescent)
    end select
    this%e = 0.5_wp*(this%g + transpose(this%g))
    this%omega = 0.5_wp*[this%g(3, 2) - this%g(2, 3), this%g(1, 3) - this%g(3, 1), this%g(2, 1) - this%g(1, 2)]
    this%has_strain = any(this%e /= 0.0_wp)
  end subroutine flow_init

  !> v(:, i) = G r(:, i) for every bead (v is overwritten).
  pure subroutine flow_velocity(this, r, v)
    class(flow_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: v(:, :)
    integer :: i
    do i = 1, size(r, 2)
      v(1, i) = this%g(1, 1)*r(1, i) + this%g(1, 2)*r(2, i) + this%g(1, 3)*r(3, i)
      v(2, i) = this%g(2, 1)*r(1, i) + this%g(2, 2)*r(2, i) + this%g(2, 3)*r(3, i)
      v(3, i) = this%g(3, 1)*r(1, i) + this%g(3, 2)*r(2, i) + this%g(3, 3)*r(3, i)
    end do
  end subroutine flow_velocity

end module kf_flow
