!> The hydrodynamic-model factory: the scene's model name, update mode and overlap rule are
!> resolved here, once. The names of the models, update modes and overlap rules, their
!> parameters' validation and the eps_lub rule are those of the &hydro group (kf_scene_hydro, the
!> one source the scene validation uses too); `hydro_model_names` passes the names on. The
!> concrete types (kf_hydro_none, kf_hydro_rpy, the multipole types, kf_overlap_rule) take plain
!> values.
module kf_hydro_factory
  use kf_kinds, only: wp, i8
  use kf_error, only: error_t, fatal_error
  use kf_scene_check, only: name_list
  use kf_scene_hydro, only: hydro_params_t, hydro_model_names => model_names, model_none, model_rpy, &
                            model_multipole, check_hydro, effective_eps_lub, overlap_bwe, update_stage, &
                            update_adaptive, update_iterative, overlap_pair, overlap_separate, overlap_relax, &
                            overlap_names
  use kf_overlap_rule, only: overlap_rule_t, pair_rule, separate_rule, relax_rule
  use kf_hydro_model, only: hydro_model_t
  use kf_hydro_none, only: none_model_t
  use kf_hydro_rpy, only: rpy_model_t, rpy_memory_bytes
  use kf_hydro_multipole, only: multipole_model_t, multipole_memory_bytes
  use kf_hydro_multipole_adaptive, only: multipole_adaptive_t, adaptive_memory_bytes
  use kf_hydro_multipole_iterative, only: multipole_iterative_t, iterative_memory_bytes
  implicit none
  private

  public :: make_hydro_model, make_overlap_rule, hydro_model_names, hydro_memory_bytes

  !> eps_lub of a model made outside a scene when none is given (knotflow-mobility's --eps-lub
  !> default, the C interface's default); also the tolerance such a model is made with.
  real(wp), parameter, public :: standalone_eps_lub = 1.0e-4_wp

contains

  !> The memory the model named by params%model keeps for `n_beads` beads (bytes), as each model
  !> module states it (`rpy_memory_bytes`, `multipole_memory_bytes`, `adaptive_memory_bytes`,
  !> `iterative_memory_bytes`, plus a model of a lower &hydro jacobian_order;
  !> 'none' keeps nothing); `stresslet`: the case records the stresslet. A model name this
  !> factory cannot build gives -1 (kf_resources refuses it), never a silent 0.
  pure integer(i8) function hydro_memory_bytes(params, n_beads, stresslet) result(bytes)
    type(hydro_params_t), intent(in) :: params
    integer, intent(in) :: n_beads
    logical, intent(in) :: stresslet
    integer(i8) :: n
    n = max(0_i8, int(n_beads, i8))
    select case (trim(params%model))
    case (model_none)
      bytes = 0
    case (model_rpy)
      bytes = rpy_memory_bytes(n)
    case (model_multipole)
      select case (trim(params%update))
      case (update_stage)
        bytes = multipole_memory_bytes(n, stresslet .and. params%lubrication)
      case (update_adaptive)
        bytes = adaptive_memory_bytes(n, stresslet .and. params%lubrication)
      case (update_iterative)
        bytes = iterative_memory_bytes(n, stresslet .and. params%lubrication)
      case default
        bytes = -1
      end select
      ! a lower jacobian_order: one more multipole model (without a stresslet)
      if (bytes >= 0 .and. params%jacobian_order > 0 .and. params%jacobian_order < params%order) &
        bytes = bytes + multipole_memory_bytes(n, .false.)
    case default
      bytes = -1
    end select
  end function hydro_memory_bytes

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
      call make_multipole(params, tolerance, model, error)
    end select
  end subroutine make_hydro_model

  !> The multipole model of the update mode params%update (checked): the exact one ('stage'),
  !> its adaptive reuse ('adaptive', whose budget the integration tolerance sets) or its
  !> iterative solve ('iterative'), each from plain values.
  subroutine make_multipole(params, tolerance, model, error)
    type(hydro_params_t), intent(in) :: params
    real(wp), intent(in) :: tolerance
    class(hydro_model_t), allocatable, intent(out) :: model
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: eps_lub
    logical :: literal_bwe
    eps_lub = effective_eps_lub(params, tolerance)
    literal_bwe = params%overlap == overlap_bwe
    select case (trim(params%update))
    case (update_stage)
      block
        type(multipole_model_t), allocatable :: mp
        allocate (mp)
        call mp%init(params%order, params%lubrication, eps_lub, error, literal_bwe=literal_bwe)
        if (allocated(error)) return
        call move_alloc(mp, model)
      end block
    case (update_adaptive)
      block
        type(multipole_adaptive_t), allocatable :: ma
        allocate (ma)
        call ma%setup(params%order, params%lubrication, eps_lub, tolerance, error, literal_bwe=literal_bwe)
        if (allocated(error)) return
        if (params%jacobian_order > 0) call ma%set_jacobian_order(params%jacobian_order, error)
        if (allocated(error)) return
        call move_alloc(ma, model)
      end block
    case (update_iterative)
      block
        type(multipole_iterative_t), allocatable :: mi
        allocate (mi)
        call mi%setup(params%order, params%lubrication, eps_lub, error, literal_bwe=literal_bwe, &
                      solver_tolerance=params%solver_tolerance)
        if (allocated(error)) return
        if (params%jacobian_order > 0) call mi%set_jacobian_order(params%jacobian_order, error)
        if (allocated(error)) return
        call move_alloc(mi, model)
      end block
    case default
      call fatal_error(error, "hydro: update = '"//trim(params%update)//"' has no multipole type")
    end select
  end subroutine make_multipole

  !> The overlap rule `name` (one of kf_scene_hydro's overlap_names) for the overlap shift
  !> eps_lub > 0; `overlap_time` (> 0) is used by 'relax' only.
  subroutine make_overlap_rule(name, eps_lub, overlap_time, rule, error)
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: eps_lub, overlap_time
    class(overlap_rule_t), allocatable, intent(out) :: rule
    type(error_t), allocatable, intent(out) :: error
    select case (trim(name))
    case (overlap_pair)
      call pair_rule(.false., rule)
    case (overlap_bwe)
      call pair_rule(.true., rule)
    case (overlap_separate)
      call separate_rule(eps_lub, rule, error)
    case (overlap_relax)
      call relax_rule(eps_lub, overlap_time, rule, error)
    case default
      call fatal_error(error, 'overlap rule "'//trim(name)//'" unknown (one of '// &
        name_list(overlap_names)//')')
    end select
  end subroutine make_overlap_rule

end module kf_hydro_factory
