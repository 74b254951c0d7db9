!> The &hydro group: the hydrodynamic model. Owns the parameter type with its defaults, the
!> reading of the group, its part of the item catalogue, its validation, the names of the models,
!> the update modes (the default `update_default`) and the overlap rules (kf_hydro_factory builds
!> the types from them; the rules themselves are kf_overlap_rule) and the resolution of eps_lub.
module kf_scene_hydro
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str, to_str_exact
  use kf_error, only: error_t
  use kf_scene_item, only: scene_item_t, add_s, add_i, add_l, add_r, name_len
  use kf_scene_check, only: refuse, name_list, quoted, check_finite
  use kf_hydro_limits, only: eps_lub_max, order_max, lubrication_order_max, eps_lub_range_text, &
    order_range_text, solver_tolerance_default, solver_tolerance_min, solver_tolerance_max
  implicit none
  private

  character(len=*), parameter, public :: model_none = 'none', model_rpy = 'rpy', model_multipole = 'multipole'
  !> The valid values of &hydro model.
  character(len=*), parameter, public :: model_names(3) = [character(len=9) :: model_none, model_rpy, &
    model_multipole]
  character(len=*), parameter, public :: update_stage = 'stage', update_adaptive = 'adaptive', &
    update_iterative = 'iterative'
  !> The default update mode of the multipole model (the one place it is defined; programs that
  !> offer an update option take it from here).
  character(len=*), parameter, public :: update_default = update_adaptive
  !> The valid values of &hydro update (multipole).
  character(len=*), parameter, public :: update_names(3) = [character(len=9) :: update_stage, update_adaptive, &
    update_iterative]

  character(len=*), parameter, public :: overlap_pair = 'pair', overlap_separate = 'separate', &
    overlap_relax = 'relax', overlap_bwe = 'bwe'
  !> The valid values of &hydro overlap (multipole). 'bwe' is the reference study's rule as
  !> PHYSICS.md 3.3 words it; the others are the project's variants (kf_overlap_rule).
  character(len=*), parameter, public :: overlap_names(4) = [character(len=8) :: overlap_pair, overlap_separate, &
    overlap_relax, overlap_bwe]
  !> The default of &hydro overlap_time (in units of 1/shear rate; kf_overlap_rule says why).
  real(wp), parameter :: overlap_time_default = 0.1_wp

  ! The allowed values, in the words of the refusals and of the scene reference (the ranges
  ! from kf_hydro_limits: order_allowed, order_lubrication_allowed, eps_lub_allowed below).
  character(len=*), parameter :: overlap_time_allowed = 'a number > 0'
  character(len=*), parameter :: overlap_time_relax_allowed = "only with overlap = '"//overlap_relax//"'"
  !> The default of &hydro jacobian_order: the model's own order.
  integer, parameter :: jacobian_order_default = 0

  !> &hydro: the hydrodynamic model.
  type, public :: hydro_params_t
    character(len=name_len) :: model = model_rpy    !< none | rpy | multipole
    integer :: order = 2                            !< multipole order L
    logical :: lubrication = .true.                 !< multipole: lubrication corrections
    !> overlap shift (pairs evaluated at 1 + eps_lub); < 0 (the default): not given, resolve_hydro
    !> sets the integration tolerance
    real(wp) :: eps_lub = -1.0_wp
    !> The multipole update: adaptive (reuse, the default) | stage (exact every stage) |
    !> iterative (exact every stage to a solver tolerance, by preconditioned GMRES)
    character(len=name_len) :: update = update_default
    !> Overlap rule of the multipole model: pair (lubrication and multipole blocks of a pair
    !> clamped at 1 + eps_lub, the default), separate (the configuration without overlaps), relax
    !> (separate, and overlaps undone over overlap_time) or bwe (the study's rule: only the
    !> lubrication correction of a pair with r <= 1, at 1 + eps_lub)
    character(len=name_len) :: overlap = overlap_pair
    !> relax: the time over which an overlap is undone
    real(wp) :: overlap_time = overlap_time_default
    !> The multipole order of the mobility in a linearly implicit stepper's Jacobian where the
    !> model's own is not at hand (update adaptive or iterative); 0: the model's order
    integer :: jacobian_order = jacobian_order_default
    !> update iterative: the relative solver tolerance (largest change of a bead velocity per
    !> GMRES iteration over the largest bead velocity; kf_hydro_limits)
    real(wp) :: solver_tolerance = solver_tolerance_default
  end type hydro_params_t

  public :: read_hydro_group, hydro_items, check_hydro, resolve_hydro, effective_eps_lub

contains

  !> Read the namelist text of &hydro into `p` (the values `p` holds are the defaults).
  subroutine read_hydro_group(p, text, ios, msg)
    type(hydro_params_t), intent(inout) :: p
    character(len=*), intent(in) :: text
    integer, intent(out) :: ios
    character(len=*), intent(inout) :: msg
    character(len=name_len) :: model
    integer :: order
    logical :: lubrication
    real(wp) :: eps_lub
    character(len=name_len) :: update, overlap
    real(wp) :: overlap_time
    integer :: jacobian_order
    real(wp) :: solver_tolerance
    namelist /hydro/ model, order, lubrication, eps_lub, update, overlap, overlap_time, jacobian_order, &
      solver_tolerance
    model = p%model; order = p%order; lubrication = p%lubrication; eps_lub = p%eps_lub
    update = p%update; overlap = p%overlap; overlap_time = p%overlap_time; jacobian_order = p%jacobian_order
    solver_tolerance = p%solver_tolerance
    read (text, nml=hydro, iostat=ios, iomsg=msg)
    p%model = model; p%order = order; p%lubrication = lubrication; p%eps_lub = eps_lub
    p%update = update; p%overlap = overlap; p%overlap_time = overlap_time; p%jacobian_order = jacobian_order
    p%solver_tolerance = solver_tolerance
  end subroutine read_hydro_group

  !> The variables of &hydro, in namelist order, appended to `items`.
  subroutine hydro_items(p, items)
    type(hydro_params_t), intent(in) :: p
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    call add_s(items, 'hydro.model', p%model, 'one of '//name_list(model_names), &
      'the hydrodynamic model: none (free draining), rpy (Rotne-Prager-Yamakawa), multipole (the multipole '// &
      'method, with lubrication corrections; docs/multipole.md)')
    call add_i(items, 'hydro.order', int(p%order, i8), order_allowed()//'; '//order_lubrication_allowed(), &
      'multipole order L')
    call add_l(items, 'hydro.lubrication', p%lubrication, '.true. or .false.', 'multipole: lubrication corrections')
    call add_r(items, 'hydro.eps_lub', p%eps_lub, eps_lub_allowed(), &
      'multipole: overlapping pairs are evaluated at 1 + eps_lub (as the overlap rule says); -1 (not given): '// &
      'the &integrator tolerance')
    call add_s(items, 'hydro.update', p%update, 'one of '//name_list(update_names), &
      'multipole: adaptive (the many-body part reused between refreshes within an error budget from the '// &
      'tolerance, lubrication exact at every stage), stage (recomputed exactly at every Runge-Kutta stage: '// &
      'the reference) or iterative (the exact system at every stage, solved by GMRES preconditioned with an '// &
      'earlier factorisation, to the relative velocity tolerance solver_tolerance); ignored by none and rpy')
    call add_s(items, 'hydro.overlap', p%overlap, 'one of '//name_list(overlap_names)//'; '// &
      quoted(overlap_pair)//' unless model = '//quoted(model_multipole), &
      'multipole: how overlapping beads are treated. bwe: the study''s BWE rule, only the lubrication '// &
      'correction of a pair with r <= 1 taken at 1 + eps_lub, everything else at the real positions (a run '// &
      'stops with the Cholesky error where that many-body system is not positive definite; docs/stability.md); '// &
      'the others are variants of ours: pair, the pair''s multipole blocks and lubrication correction at '// &
      '1 + eps_lub along its line of centres (also for 1 < r < 1 + eps_lub); separate, the whole hydrodynamics '// &
      'of the nearest configuration without overlaps; relax, separate and overlaps undone kinematically over '// &
      'overlap_time (docs/limitations.md says why the study inputs use it)')
    call add_r(items, 'hydro.overlap_time', p%overlap_time, overlap_time_allowed//', '//overlap_time_relax_allowed, &
      'relax: the time, in units of 1/shear rate, over which an overlap is undone')
    call add_i(items, 'hydro.jacobian_order', int(p%jacobian_order, i8), jacobian_order_allowed(), &
      'multipole, update adaptive or iterative: the order L of the mobility in the Jacobian of a linearly '// &
      'implicit stepper (&integrator method ros34pw2, ros34pw3), made where the model''s own is not at hand '// &
      '(same lubrication and overlap treatment); 0: the model''s order. A W-method keeps its order with any '// &
      'Jacobian; 1 is much cheaper (docs/accuracy.md, "A cheaper Jacobian"); ignored by the other methods')
    call add_r(items, 'hydro.solver_tolerance', p%solver_tolerance, solver_tolerance_allowed(), &
      'multipole, update iterative: GMRES stops when no bead velocity changed by more than solver_tolerance '// &
      'times the largest bead velocity in the last iteration; looser is cheaper (fewer iterations and '// &
      'factorisations) and less exact: at 1e-4 the trefoil moved 1.2e-4 d and a compact candy-cane coil '// &
      '3.7e-3 d from the exact path in ten time units (docs/accuracy.md, "The solver tolerance and the '// &
      'preconditioner''s Jacobian")')
  end subroutine hydro_items

  !> Check &hydro (`file`: the scene file named in the messages, '' from code).
  subroutine check_hydro(p, file, error)
    type(hydro_params_t), intent(in) :: p
    character(len=*), intent(in) :: file
    type(error_t), allocatable, intent(out) :: error
    type(scene_item_t), allocatable :: items(:)
    allocate (items(0))
    call hydro_items(p, items)
    call check_finite(items, file, error)
    if (allocated(error)) return
    if (.not. any(model_names == p%model)) then
      call refuse(error, file, 'hydro', 'model', quoted(p%model), 'one of '//name_list(model_names)); return
    end if
    if (p%model == model_multipole) then
      if (p%order < 1 .or. p%order > order_max) then
        call refuse(error, file, 'hydro', 'order', to_str(p%order), order_allowed()); return
      end if
      if (p%lubrication .and. p%order > lubrication_order_max) then
        call refuse(error, file, 'hydro', 'order', to_str(p%order), order_lubrication_allowed()); return
      end if
    end if
    if (.not. (p%eps_lub < eps_lub_max .and. p%eps_lub /= 0.0_wp)) then
      call refuse(error, file, 'hydro', 'eps_lub', to_str_exact(p%eps_lub), eps_lub_allowed()); return
    end if
    if (.not. any(update_names == p%update)) then
      call refuse(error, file, 'hydro', 'update', quoted(p%update), 'one of '//name_list(update_names)); return
    end if
    if (.not. any(overlap_names == p%overlap)) then
      call refuse(error, file, 'hydro', 'overlap', quoted(p%overlap), 'one of '//name_list(overlap_names)); return
    end if
    if (p%overlap /= overlap_pair .and. p%model /= model_multipole) then
      call refuse(error, file, 'hydro', 'overlap', quoted(p%overlap), &
        quoted(overlap_pair)//' with model = '//quoted(p%model)//' (the rule is for the multipole model)'); return
    end if
    if (.not. (p%overlap_time > 0.0_wp)) then
      call refuse(error, file, 'hydro', 'overlap_time', to_str_exact(p%overlap_time), overlap_time_allowed); return
    end if
    if (p%overlap /= overlap_relax .and. p%overlap_time /= overlap_time_default) then
      call refuse(error, file, 'hydro', 'overlap_time', to_str_exact(p%overlap_time), &
        overlap_time_relax_allowed//' (it has no effect with overlap = '// &
        quoted(p%overlap)//')'); return
    end if
    if (p%jacobian_order /= jacobian_order_default) then
      if (p%model /= model_multipole .or. p%update == update_stage .or. p%jacobian_order < 0 .or. &
          p%jacobian_order > p%order) then
        call refuse(error, file, 'hydro', 'jacobian_order', to_str(p%jacobian_order), jacobian_order_allowed()); return
      end if
    end if
    if (p%solver_tolerance /= solver_tolerance_default) then
      if (p%model /= model_multipole .or. p%update /= update_iterative .or. &
          .not. (p%solver_tolerance >= solver_tolerance_min .and. p%solver_tolerance <= solver_tolerance_max)) then
        call refuse(error, file, 'hydro', 'solver_tolerance', to_str_exact(p%solver_tolerance), &
          solver_tolerance_allowed()); return
      end if
    end if
  end subroutine check_hydro

  !> The eps_lub a model uses: the given one, or the integration tolerance when not given (< 0).
  pure real(wp) function effective_eps_lub(p, tolerance) result(eps)
    type(hydro_params_t), intent(in) :: p
    real(wp), intent(in) :: tolerance
    eps = p%eps_lub
    if (eps < 0.0_wp) eps = tolerance
  end function effective_eps_lub

  !> Set eps_lub to its effective value (the integration tolerance when not given); a tolerance
  !> outside the range of eps_lub is refused, naming both.
  subroutine resolve_hydro(p, tolerance, file, error)
    type(hydro_params_t), intent(inout) :: p
    real(wp), intent(in) :: tolerance
    character(len=*), intent(in) :: file
    type(error_t), allocatable, intent(out) :: error
    if (p%eps_lub >= 0.0_wp) return
    if (.not. (tolerance > 0.0_wp .and. tolerance < eps_lub_max)) then
      call refuse(error, file, 'hydro', 'eps_lub', 'the &integrator tolerance = '//to_str_exact(tolerance), &
        'a number in '//eps_lub_range_text()//': give eps_lub, or a smaller tolerance'); return
    end if
    p%eps_lub = effective_eps_lub(p, tolerance)
  end subroutine resolve_hydro

  !> The allowed values of jacobian_order, in the words of the refusals and the reference.
  function jacobian_order_allowed() result(text)
    character(len=:), allocatable :: text
    text = 'an integer from 0 to the order; '//to_str(jacobian_order_default)//' unless model = '// &
      quoted(model_multipole)//' and update = '//quoted(update_adaptive)//' or '//quoted(update_iterative)// &
      ' (with '//quoted(update_stage)//' the exact mobility is at hand)'
  end function jacobian_order_allowed

  !> The allowed values of solver_tolerance, in the words of the refusals and the reference.
  function solver_tolerance_allowed() result(text)
    character(len=:), allocatable :: text
    text = 'a number from '//to_str_exact(solver_tolerance_min)//' to '//to_str_exact(solver_tolerance_max)// &
      '; '//to_str_exact(solver_tolerance_default)//' unless model = '//quoted(model_multipole)// &
      ' and update = '//quoted(update_iterative)
  end function solver_tolerance_allowed

  !> 'an integer from 1 to 8' (the allowed orders).
  function order_allowed() result(text)
    character(len=:), allocatable :: text
    text = 'an integer from '//order_range_text(.false.)
  end function order_allowed

  !> 'at most 6 with lubrication = .true. (tables exist for L = 1..6)'.
  function order_lubrication_allowed() result(text)
    character(len=:), allocatable :: text
    text = 'at most '//to_str(lubrication_order_max)//' with lubrication = .true. (tables exist for L = 1..'// &
      to_str(lubrication_order_max)//')'
  end function order_lubrication_allowed

  !> 'a number in (0, 0.5), or negative for the integration tolerance'.
  function eps_lub_allowed() result(text)
    character(len=:), allocatable :: text
    text = 'a number in '//eps_lub_range_text()//', or negative for the integration tolerance'
  end function eps_lub_allowed

end module kf_scene_hydro
