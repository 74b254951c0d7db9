!> The C interface's name lists and defaults, taken from the library's own definitions (one
!> source): the hydrodynamic models and overlap rules of the &hydro group, the knot types of
!> kf_knot_invariants, the outcomes of a case of kf_case_runner, and the defaults of the
!> closures and of eps_lub.
module kf_capi_names
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_double, c_int64_t
  use kf_capi_status, only: kf_ok, kf_invalid_argument, put_message
  use kf_strings, only: to_str
  use kf_hydro_factory, only: hydro_model_names, standalone_eps_lub
  use kf_scene_hydro, only: hydro_params_t, overlap_names
  use kf_knot_invariants, only: n_knot_types, knot_type_names
  use kf_knot_closure, only: default_closures, default_knot_seed
  use kf_case_runner, only: case_outcome_names
  implicit none
  private

  !> The list kinds of knotflow_names.
  integer(c_int), parameter :: list_models = 1, list_overlap_rules = 2, list_knot_types = 3, &
    list_case_statuses = 4

  public :: knotflow_names, knotflow_defaults

contains

  !> Write the names of list `kind` (1: hydrodynamic models, 2: overlap rules, 3: knot types in
  !> the order of the spectrum, 4: the case statuses of knotflow_run_scene from 0), separated
  !> by single blanks, into buf(buflen). Returns kf_ok, or
  !> kf_invalid_argument for an unknown kind or a buffer too short (the message is then in buf).
  integer(c_int) function knotflow_names(kind, buf, buflen) bind(c, name='knotflow_names') result(status)
    integer(c_int), value, intent(in) :: kind
    character(kind=c_char), intent(inout) :: buf(*)
    integer(c_int), value, intent(in) :: buflen
    character(len=:), allocatable :: list
    select case (kind)
    case (list_models)
      list = joined(hydro_model_names)
    case (list_overlap_rules)
      list = joined(overlap_names)
    case (list_knot_types)
      list = joined(knot_type_names)
    case (list_case_statuses)
      list = joined(case_outcome_names)
    case default
      call put_message('knotflow_names: list '//to_str(int(kind))//' unknown (allowed: 1 models, '// &
        '2 overlap rules, 3 knot types, 4 case statuses)', buf, buflen)
      status = kf_invalid_argument
      return
    end select
    if (len(list) + 1 > buflen) then
      call put_message('knotflow_names: a buffer of '//to_str(len(list) + 1)//' characters is needed', buf, buflen)
      status = kf_invalid_argument
      return
    end if
    call put_message(list, buf, buflen)
    status = kf_ok
  end function knotflow_names

  !> The defaults: closures and seed of knotflow-analyze's knot analysis, eps_lub of
  !> knotflow-mobility, the &hydro group's overlap_time and the number of knot types (the
  !> length of a spectrum).
  subroutine knotflow_defaults(closures, seed, eps_lub, overlap_time, knot_types) bind(c, name='knotflow_defaults')
    integer(c_int), intent(out) :: closures
    integer(c_int64_t), intent(out) :: seed
    real(c_double), intent(out) :: eps_lub, overlap_time
    integer(c_int), intent(out) :: knot_types
    type(hydro_params_t) :: hydro
    closures = default_closures
    seed = default_knot_seed
    eps_lub = standalone_eps_lub
    overlap_time = hydro%overlap_time
    knot_types = n_knot_types
  end subroutine knotflow_defaults

  !> The trimmed names joined by single blanks.
  pure function joined(names) result(list)
    character(len=*), intent(in) :: names(:)
    character(len=:), allocatable :: list
    integer :: k
    list = trim(names(1))
    do k = 2, size(names)
      list = list//' '//trim(names(k))
    end do
  end function joined

end module kf_capi_names
