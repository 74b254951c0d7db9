!> The hydrodynamic-model factory: the scene's model name is resolved here, once.
module kf_hydro_factory
  use kf_kinds, only: wp
  use kf_error, only: error_t, fatal_error
  use kf_scene, only: hydro_params_t
  use kf_hydro_model, only: hydro_model_t
  use kf_hydro_none, only: none_model_t
  use kf_hydro_rpy, only: rpy_model_t
  use kf_hydro_multipole, only: multipole_model_t
  implicit none
  private

  public :: make_hydro_model

contains

  !> Allocate the model named by params%model (none | rpy | multipole). `tolerance` is the
  !> integration accuracy: the multipole model uses it as eps_lub when params%eps_lub < 0
  !> (none and rpy ignore it).
  subroutine make_hydro_model(params, tolerance, model, error)
    type(hydro_params_t), intent(in) :: params
    real(wp), intent(in) :: tolerance
    class(hydro_model_t), allocatable, intent(out) :: model
    type(error_t), allocatable, intent(out) :: error
    if (.not. tolerance > 0.0_wp) then
      call fatal_error(error, 'hydro: the integration tolerance must be > 0 (it sets the default eps_lub)')
      return
    end if
    select case (trim(params%model))
    case ('none')
      allocate (none_model_t :: model)
    case ('rpy')
      allocate (rpy_model_t :: model)
    case ('multipole')
      block
        type(multipole_model_t), allocatable :: mp
        real(wp) :: eps_lub
        allocate (mp)
        eps_lub = params%eps_lub
        if (eps_lub < 0.0_wp) eps_lub = tolerance
        call mp%init(params%order, params%lubrication, eps_lub, error, update=trim(params%update), &
                     tolerance=tolerance)
        if (allocated(error)) return
        call move_alloc(mp, model)
      end block
    case default
      call fatal_error(error, "hydro: model = '"//trim(params%model)// &
        "' is unknown (allowed: none, rpy, multipole)")
    end select
  end subroutine make_hydro_model

end module kf_hydro_factory
