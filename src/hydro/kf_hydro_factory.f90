!> The hydrodynamic-model factory: the scene's model name is resolved here, once. The names of
!> the models, their parameters' validation and the eps_lub rule are those of the &hydro group
!> (kf_scene_hydro, the one source the scene validation uses too); `hydro_model_names` passes
!> the names on.
module kf_hydro_factory
  use kf_kinds, only: wp
  use kf_error, only: error_t, fatal_error
  use kf_scene_hydro, only: hydro_params_t, hydro_model_names => model_names, model_none, model_rpy, &
                            model_multipole, check_hydro, effective_eps_lub, overlap_bwe, update_iterative
  use kf_hydro_model, only: hydro_model_t
  use kf_hydro_none, only: none_model_t
  use kf_hydro_rpy, only: rpy_model_t
  use kf_hydro_multipole, only: multipole_model_t
  use kf_hydro_multipole_iterative, only: multipole_iterative_t
  implicit none
  private

  public :: make_hydro_model, hydro_model_names

  !> eps_lub of a model made outside a scene when none is given (knotflow-mobility's --eps-lub
  !> default, the C interface's default); also the tolerance such a model is made with.
  real(wp), parameter, public :: standalone_eps_lub = 1.0e-4_wp

contains

  !> Allocate the model named by params%model (none | rpy | multipole) after checking the
  !> parameters. `tolerance` is the integration accuracy: the multipole model's reuse budget,
  !> and its eps_lub when params%eps_lub is not given (a resolved scene has it set already).
  subroutine make_hydro_model(params, tolerance, model, error)
    type(hydro_params_t), intent(in) :: params
    real(wp), intent(in) :: tolerance
    class(hydro_model_t), allocatable, intent(out) :: model
    type(error_t), allocatable, intent(out) :: error
    if (.not. tolerance > 0.0_wp) then
      call fatal_error(error, 'hydro: the integration tolerance must be > 0 (it sets the default eps_lub)')
      return
    end if
    call check_hydro(params, '', error)
    if (allocated(error)) return
    select case (trim(params%model))
    case (model_none)
      allocate (none_model_t :: model)
    case (model_rpy)
      allocate (rpy_model_t :: model)
    case (model_multipole)
      if (trim(params%update) == update_iterative) then
        block
          type(multipole_iterative_t), allocatable :: mi
          allocate (mi)
          call mi%setup(params%order, params%lubrication, effective_eps_lub(params, tolerance), error, &
                        literal_bwe=(params%overlap == overlap_bwe))
          if (allocated(error)) return
          call move_alloc(mi, model)
        end block
        return
      end if
      block
        type(multipole_model_t), allocatable :: mp
        allocate (mp)
        call mp%init(params%order, params%lubrication, effective_eps_lub(params, tolerance), error, &
                     update=trim(params%update), tolerance=tolerance, &
                     literal_bwe=(params%overlap == overlap_bwe))
        if (allocated(error)) return
        call move_alloc(mp, model)
      end block
    end select
  end subroutine make_hydro_model

end module kf_hydro_factory
