!> The &flow group: the ambient linear flow. Owns the parameter type with its defaults, the
!> reading of the group, its part of the item catalogue, its validation and the names of the
!> flows (kf_flow builds from them).
module kf_scene_flow
  use kf_kinds, only: wp
  use kf_strings, only: to_str_exact
  use kf_error, only: error_t
  use kf_scene_item, only: scene_item_t, add_s, add_r, add_a, name_len
  use kf_scene_check, only: refuse, name_list, quoted, check_finite
  implicit none
  private

  character(len=*), parameter, public :: flow_shear = 'shear', flow_linear = 'linear', &
    flow_quiescent = 'quiescent'
  !> The valid values of &flow flow_type.
  character(len=*), parameter, public :: flow_names(3) = [character(len=9) :: flow_shear, flow_linear, &
    flow_quiescent]

  ! The allowed values, in the words of the refusals and of the scene reference.
  character(len=*), parameter :: shear_rate_allowed = 'a finite number'
  character(len=*), parameter :: gradient_allowed = 'a traceless matrix (incompressible flow)'

  !> &flow: the ambient linear flow v0 = G r.
  type, public :: flow_params_t
    character(len=name_len) :: flow_type = flow_shear !< shear | linear | quiescent
    real(wp) :: shear_rate = 1.0_wp                 !< shear: v0 = (shear_rate z, 0, 0)
    real(wp) :: velocity_gradient(3, 3) = 0.0_wp    !< linear: G(i,j) = d v0_i / d r_j, traceless
  end type flow_params_t

  public :: read_flow_group, flow_items, check_flow

contains

  !> Read the namelist text of &flow into `p` (the values `p` holds are the defaults).
  subroutine read_flow_group(p, text, ios, msg)
    type(flow_params_t), intent(inout) :: p
    character(len=*), intent(in) :: text
    integer, intent(out) :: ios
    character(len=*), intent(inout) :: msg
    character(len=name_len) :: flow_type
    real(wp) :: shear_rate, velocity_gradient(3, 3)
    namelist /flow/ flow_type, shear_rate, velocity_gradient
    flow_type = p%flow_type; shear_rate = p%shear_rate; velocity_gradient = p%velocity_gradient
    read (text, nml=flow, iostat=ios, iomsg=msg)
    p%flow_type = flow_type; p%shear_rate = shear_rate; p%velocity_gradient = velocity_gradient
  end subroutine read_flow_group

  !> The variables of &flow, in namelist order, appended to `items`.
  subroutine flow_items(p, items)
    type(flow_params_t), intent(in) :: p
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    call add_s(items, 'flow.flow_type', p%flow_type, 'one of '//name_list(flow_names), &
      'the ambient flow: shear, v0 = (shear_rate z, 0, 0); linear, v0 = G r; quiescent, no flow')
    call add_r(items, 'flow.shear_rate', p%shear_rate, shear_rate_allowed, 'gamma_dot of the shear flow')
    call add_a(items, 'flow.velocity_gradient', reshape(p%velocity_gradient, [9]), [3, 3], gradient_allowed, &
      "G(i,j) = d v0_i / d r_j of flow_type = 'linear' (9 values, or one component as velocity_gradient(i,j) = x)")
  end subroutine flow_items

  !> Check &flow (`file`: the scene file named in the messages, '' from code).
  subroutine check_flow(p, file, error)
    type(flow_params_t), intent(in) :: p
    character(len=*), intent(in) :: file
    type(error_t), allocatable, intent(out) :: error
    type(scene_item_t), allocatable :: items(:)
    real(wp) :: tr
    allocate (items(0))
    call flow_items(p, items)
    call check_finite(items, file, error)
    if (allocated(error)) return
    if (.not. any(flow_names == p%flow_type)) then
      call refuse(error, file, 'flow', 'flow_type', quoted(p%flow_type), 'one of '//name_list(flow_names)); return
    end if
    if (.not. (abs(p%shear_rate) < 1.0e6_wp)) then
      call refuse(error, file, 'flow', 'shear_rate', to_str_exact(p%shear_rate), shear_rate_allowed); return
    end if
    if (p%flow_type == flow_linear) then
      associate (g => p%velocity_gradient)
        if (.not. all(abs(g) < 1.0e6_wp)) then
          call refuse(error, file, 'flow', 'velocity_gradient', 'non-finite', 'finite numbers'); return
        end if
        tr = g(1, 1) + g(2, 2) + g(3, 3)
        if (abs(tr) > 1.0e-12_wp*max(1.0_wp, maxval(abs(g)))) then
          call refuse(error, file, 'flow', 'velocity_gradient', 'trace '//to_str_exact(tr), &
            gradient_allowed); return
        end if
      end associate
    end if
  end subroutine check_flow

end module kf_scene_flow
