!> The scene: everything one case needs, with the defaults of a reference-study trefoil run.
!> One module per namelist group owns its parameter type (kf_scene_chain, kf_scene_forces,
!> kf_scene_flow, kf_scene_hydro, kf_scene_integrator, kf_scene_output); `scene_t` is composed
!> of them, and this module passes their types on, so a user of the scene needs one `use`.
!> kf_scene_read reads, validates and resolves a scene.
module kf_scene
  use kf_scene_item, only: path_len, name_len
  use kf_scene_chain, only: chain_params_t
  use kf_scene_forces, only: forces_params_t
  use kf_scene_flow, only: flow_params_t
  use kf_scene_hydro, only: hydro_params_t
  use kf_scene_integrator, only: integrator_params_t
  use kf_scene_output, only: output_params_t
  implicit none
  private

  public :: path_len, name_len
  public :: chain_params_t, forces_params_t, flow_params_t, hydro_params_t, integrator_params_t, &
            output_params_t

  !> The whole scene of one case.
  type, public :: scene_t
    character(len=path_len) :: source_file = ''     !< where it was read from
    type(chain_params_t) :: chain
    type(forces_params_t) :: forces
    type(flow_params_t) :: flow
    type(hydro_params_t) :: hydro
    type(integrator_params_t) :: integrator
    type(output_params_t) :: output
  end type scene_t

end module kf_scene
