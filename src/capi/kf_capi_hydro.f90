!> The C interface of the hydrodynamic models (docs/python-api.md). A model is an opaque handle made
!> by knotflow_model_create from a specification (model name, multipole order, lubrication,
!> eps_lub, overlap rule) through the library's factory (kf_hydro_factory, with the &hydro
!> group's validation and names) and freed by knotflow_model_free. Independent handles share
!> nothing, so different threads may use different handles at the same time; one handle must
!> not be used by two threads at once (a model keeps its factorisation).
!>
!> Arrays are plain C arrays of doubles: positions r[3N] (x1 y1 z1 x2 ...), the 3N x 3N mobility
!> in column-major order (element (3(i-1)+a, 3(j-1)+b), velocity component a of bead i for
!> force component b on bead j; the matrix is symmetric), 3 x 3 tensors in column-major order.
!> The mobility is that of knotflow-mobility: the same factory, prepare and mobility_matrix calls,
!> the multipole model with update 'stage' (an exact solve at every call).
module kf_capi_hydro
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_double, c_ptr, c_loc, c_f_pointer, c_associated, &
    c_null_ptr
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str, to_str_exact
  use kf_error, only: error_t, fatal_error
  use kf_capi_status, only: kf_ok, kf_invalid_argument, kf_failed, put_message, from_c_chars, check_positions, &
    elapsed_seconds
  use kf_scene_item, only: name_len
  use kf_scene_check, only: name_list, refuse, quoted
  use kf_scene_hydro, only: hydro_params_t, update_stage, overlap_names
  use kf_scene_flow, only: flow_params_t, flow_linear
  use kf_flow, only: flow_t
  use kf_hydro_model, only: hydro_model_t
  use kf_hydro_factory, only: make_hydro_model, make_overlap_rule, hydro_model_names, standalone_eps_lub
  use kf_overlap_rule, only: overlap_rule_t
  use kf_pair_geometry, only: pair_geometry_t
  use kf_hydro_limits, only: eps_lub_range_text
  implicit none
  private

  !> What a handle points to: the model, its overlap rule and an empty pair list (the rule
  !> finds its own pairs).
  type :: capi_model_t
    class(hydro_model_t), allocatable :: model
    class(overlap_rule_t), allocatable :: overlap
    type(pair_geometry_t) :: pairs
  end type capi_model_t

  public :: knotflow_model_create, knotflow_model_free, knotflow_model_label, knotflow_model_mobility, &
    knotflow_model_velocities, knotflow_model_disturbance, knotflow_model_stresslet

contains

  !> Create a model: `name`(name_length) one of the &hydro models (none, rpy, multipole);
  !> `order` the multipole order L; `lubrication` /= 0 for the lubrication corrections; `eps_lub`
  !> the BWE shift (0 < eps_lub < 0.5; knotflow_defaults gives knotflow-mobility's default);
  !> `overlap`(overlap_length) one of the overlap rules; `overlap_time` the relax rule's time
  !> (knotflow_defaults gives the &hydro default, the only value allowed with other rules).
  !> The values are checked by the &hydro group's own validation (kf_scene_hydro), and the
  !> multipole model is built with update 'stage' (exact at every call). On success *handle is
  !> the new model (free it with knotflow_model_free), else it is NULL and msg holds the reason.
  integer(c_int) function knotflow_model_create(name, name_length, order, lubrication, eps_lub, overlap, &
    overlap_length, overlap_time, handle, msg, msglen) bind(c, name='knotflow_model_create') result(status)
    integer(c_int), value, intent(in) :: name_length, overlap_length
    character(kind=c_char), intent(in) :: name(max(name_length, 0)), overlap(max(overlap_length, 0))
    integer(c_int), value, intent(in) :: order, lubrication
    real(c_double), value, intent(in) :: eps_lub, overlap_time
    type(c_ptr), intent(out) :: handle
    character(kind=c_char), intent(inout) :: msg(*)
    integer(c_int), value, intent(in) :: msglen
    type(capi_model_t), pointer :: m
    type(hydro_params_t) :: params
    type(error_t), allocatable :: error
    character(len=:), allocatable :: model_name, rule_name
    handle = c_null_ptr
    status = kf_invalid_argument
    model_name = from_c_chars(name, max(name_length, 0))
    rule_name = from_c_chars(overlap, max(overlap_length, 0))
    if (len(model_name) > name_len) &
      call refuse(error, '', 'hydro', 'model', quoted(model_name), 'one of '//name_list(hydro_model_names))
    if (.not. allocated(error) .and. len(rule_name) > name_len) &
      call refuse(error, '', 'hydro', 'overlap', quoted(rule_name), 'one of '//name_list(overlap_names))
    ! a negative eps_lub means "the integration tolerance" in a scene; here there is none
    if (.not. allocated(error) .and. .not. eps_lub > 0.0_c_double) &
      call refuse(error, '', 'hydro', 'eps_lub', to_str_exact(real(eps_lub, wp)), &
        'a number in '//eps_lub_range_text())
    if (allocated(error)) then
      call put_message(error%message, msg, msglen)
      return
    end if
    params%model = model_name
    params%order = order
    params%lubrication = lubrication /= 0
    params%eps_lub = eps_lub
    params%update = update_stage
    params%overlap = rule_name
    params%overlap_time = overlap_time
    allocate (m)
    call make_hydro_model(params, standalone_eps_lub, m%model, error)
    if (.not. allocated(error)) &
      call make_overlap_rule(params%overlap, params%eps_lub, params%overlap_time, m%overlap, error)
    if (allocated(error)) then
      deallocate (m)
      call put_message(error%message, msg, msglen)
      return
    end if
    handle = c_loc(m)
    status = kf_ok
  end function knotflow_model_create

  !> Free a model made by knotflow_model_create (NULL is ignored); *handle becomes NULL.
  subroutine knotflow_model_free(handle) bind(c, name='knotflow_model_free')
    type(c_ptr), intent(inout) :: handle
    type(capi_model_t), pointer :: m
    if (.not. c_associated(handle)) return
    call c_f_pointer(handle, m)
    deallocate (m)
    handle = c_null_ptr
  end subroutine knotflow_model_free

  !> The model's description (e.g. "multipole L=2 lubrication") into buf(buflen).
  integer(c_int) function knotflow_model_label(handle, buf, buflen) bind(c, name='knotflow_model_label') &
    result(status)
    type(c_ptr), value, intent(in) :: handle
    character(kind=c_char), intent(inout) :: buf(*)
    integer(c_int), value, intent(in) :: buflen
    type(capi_model_t), pointer :: m
    status = kf_invalid_argument
    if (.not. c_associated(handle)) then
      call put_message('knotflow_model_label: the model handle is NULL', buf, buflen)
      return
    end if
    call c_f_pointer(handle, m)
    call put_message(m%model%name(), buf, buflen)
    status = kf_ok
  end function knotflow_model_label

  !> mu[3N x 3N] = the translational mobility of the n beads at r[3N] (column-major); `seconds`:
  !> the wall time of the library's work (prepare and mobility_matrix).
  integer(c_int) function knotflow_model_mobility(handle, n, r, mu, seconds, msg, msglen) &
    bind(c, name='knotflow_model_mobility') result(status)
    type(c_ptr), value, intent(in) :: handle
    integer(c_int), value, intent(in) :: n
    real(c_double), intent(in) :: r(3, max(n, 0))
    real(c_double), intent(out) :: mu(3*max(n, 0), 3*max(n, 0))
    real(c_double), intent(out) :: seconds
    character(kind=c_char), intent(inout) :: msg(*)
    integer(c_int), value, intent(in) :: msglen
    type(capi_model_t), pointer :: m
    type(error_t), allocatable :: error
    real(wp), allocatable :: rh(:, :)
    integer(i8) :: start
    logical :: moved
    seconds = 0.0_c_double
    call get_model('knotflow_model_mobility', handle, n, r, m, status, msg, msglen)
    if (status /= kf_ok) return
    call system_clock(start)
    allocate (rh(3, n))
    call m%overlap%hydro_configuration(r, m%pairs, rh, moved, error)
    if (.not. allocated(error)) then
      if (moved) then
        call m%model%prepare(rh, error)
      else
        call m%model%prepare(r, error)
      end if
    end if
    if (.not. allocated(error)) then
      call m%model%mobility_matrix(mu)
      if (.not. all(ieee_is_finite(mu))) call fatal_error(error, 'the '//m%model%name()//' mobility holds '// &
        to_str(count(.not. ieee_is_finite(mu)))//' non-finite entries')
    end if
    seconds = elapsed_seconds(start)
    call finish(error, status, msg, msglen)
  end function knotflow_model_mobility

  !> u[3N] = G x + mu(x) f + C(x):E for forces f[3N] in the ambient linear flow v0 = G r with the
  !> traceless velocity gradient g[9] (column-major, G(i,j) = d v0_i / d r_j; E its symmetric part),
  !> where x is r or, under the overlap rules 'separate' and 'relax' while beads overlap, the
  !> configuration without overlaps; 'relax' adds its contact velocity. These are knotflow's bead
  !> velocities (kf_dynamics) for given forces.
  integer(c_int) function knotflow_model_velocities(handle, n, r, f, g, u, msg, msglen) &
    bind(c, name='knotflow_model_velocities') result(status)
    type(c_ptr), value, intent(in) :: handle
    integer(c_int), value, intent(in) :: n
    real(c_double), intent(in) :: r(3, max(n, 0)), f(3, max(n, 0)), g(3, 3)
    real(c_double), intent(out) :: u(3, max(n, 0))
    character(kind=c_char), intent(inout) :: msg(*)
    integer(c_int), value, intent(in) :: msglen
    type(capi_model_t), pointer :: m
    type(error_t), allocatable :: error
    type(flow_t) :: flow
    real(wp), allocatable :: rh(:, :), w(:, :)
    logical :: moved
    u = 0.0_c_double
    call get_model('knotflow_model_velocities', handle, n, r, m, status, msg, msglen)
    if (status /= kf_ok) return
    call check_values('knotflow_model_velocities: the forces', f, error)
    if (.not. allocated(error)) call check_values('knotflow_model_velocities: the velocity gradient', g, error)
    if (.not. allocated(error)) call flow%init(flow_params_t(flow_type=flow_linear, velocity_gradient=g), error)
    if (allocated(error)) then
      status = kf_invalid_argument
      call put_message(error%message, msg, msglen)
      return
    end if
    allocate (rh(3, n), w(3, n))
    call m%overlap%hydro_configuration(r, m%pairs, rh, moved, error)
    if (.not. allocated(error)) then
      if (moved) then
        call hydro_velocities(rh)
      else
        call hydro_velocities(r)
      end if
    end if
    if (.not. allocated(error)) call m%overlap%add_contact_velocity(r, rh, moved, u)
    call finish(error, status, msg, msglen)

  contains

    !> u = v0(x) + mu F + C:E with the hydrodynamics of configuration x (as kf_dynamics).
    subroutine hydro_velocities(x)
      real(wp), intent(in) :: x(:, :)
      if (flow%has_strain) then
        call m%model%velocities(x, f, w, error, flow%e)
      else
        call m%model%velocities(x, f, w, error)
      end if
      if (allocated(error)) return
      call flow%velocity(x, u)
      u = u + w
    end subroutine hydro_velocities
  end function knotflow_model_velocities

  !> u[3N] = C(r):E, the velocities of force-free, torque-free beads at r relative to the ambient
  !> flow, for the symmetric traceless rate of strain e[9] (knotflow-mobility --output shear
  !> with E_13 = E_31 = 1/2).
  integer(c_int) function knotflow_model_disturbance(handle, n, r, e, u, msg, msglen) &
    bind(c, name='knotflow_model_disturbance') result(status)
    type(c_ptr), value, intent(in) :: handle
    integer(c_int), value, intent(in) :: n
    real(c_double), intent(in) :: r(3, max(n, 0)), e(3, 3)
    real(c_double), intent(out) :: u(3, max(n, 0))
    character(kind=c_char), intent(inout) :: msg(*)
    integer(c_int), value, intent(in) :: msglen
    type(capi_model_t), pointer :: m
    type(error_t), allocatable :: error
    u = 0.0_c_double
    call get_model('knotflow_model_disturbance', handle, n, r, m, status, msg, msglen)
    if (status /= kf_ok) return
    call check_strain('knotflow_model_disturbance', e, error)
    if (allocated(error)) then
      status = kf_invalid_argument
      call put_message(error%message, msg, msglen)
      return
    end if
    call m%model%prepare(r, error)
    if (.not. allocated(error)) then
      call m%model%add_strain_disturbance(e, u)
      if (.not. all(ieee_is_finite(u))) call fatal_error(error, 'the '//m%model%name()// &
        ' disturbance holds non-finite values')
    end if
    call finish(error, status, msg, msglen)
  end function knotflow_model_disturbance

  !> s[9] = the sum of the beads' hydrodynamic stresslets (kf_hydro_model, units pi eta d^3) of
  !> beads at r carrying forces f in the symmetric traceless strain e[9] (column-major), at r
  !> itself (no overlap rule is applied).
  integer(c_int) function knotflow_model_stresslet(handle, n, r, f, e, s, msg, msglen) &
    bind(c, name='knotflow_model_stresslet') result(status)
    type(c_ptr), value, intent(in) :: handle
    integer(c_int), value, intent(in) :: n
    real(c_double), intent(in) :: r(3, max(n, 0)), f(3, max(n, 0)), e(3, 3)
    real(c_double), intent(out) :: s(3, 3)
    character(kind=c_char), intent(inout) :: msg(*)
    integer(c_int), value, intent(in) :: msglen
    type(capi_model_t), pointer :: m
    type(error_t), allocatable :: error
    s = 0.0_c_double
    call get_model('knotflow_model_stresslet', handle, n, r, m, status, msg, msglen)
    if (status /= kf_ok) return
    call check_values('knotflow_model_stresslet: the forces', f, error)
    if (.not. allocated(error)) call check_strain('knotflow_model_stresslet', e, error)
    if (allocated(error)) then
      status = kf_invalid_argument
      call put_message(error%message, msg, msglen)
      return
    end if
    call m%model%stresslet(r, f, e, s, error)
    call finish(error, status, msg, msglen)
  end function knotflow_model_stresslet

  !> The model of `handle` after checking the handle and the n >= 1 beads at r; status kf_ok or
  !> kf_invalid_argument (with the message in msg).
  subroutine get_model(what, handle, n, r, m, status, msg, msglen)
    character(len=*), intent(in) :: what
    type(c_ptr), intent(in) :: handle
    integer(c_int), intent(in) :: n
    real(c_double), intent(in) :: r(:, :)
    type(capi_model_t), pointer, intent(out) :: m
    integer(c_int), intent(out) :: status
    character(kind=c_char), intent(inout) :: msg(*)
    integer(c_int), intent(in) :: msglen
    type(error_t), allocatable :: error
    m => null()
    status = kf_invalid_argument
    if (.not. c_associated(handle)) then
      call put_message(what//': the model handle is NULL', msg, msglen)
      return
    end if
    call check_positions(what, n, 1, r, error)
    if (allocated(error)) then
      call put_message(error%message, msg, msglen)
      return
    end if
    call c_f_pointer(handle, m)
    status = kf_ok
  end subroutine get_model

  !> Refuse a non-finite value of v.
  subroutine check_values(what, v, error)
    character(len=*), intent(in) :: what
    real(c_double), intent(in) :: v(:, :)
    type(error_t), allocatable, intent(out) :: error
    if (.not. all(ieee_is_finite(v))) call fatal_error(error, what//' hold '// &
      to_str(count(.not. ieee_is_finite(v)))//' non-finite value(s)')
  end subroutine check_values

  !> Refuse a rate of strain that is not finite, symmetric and traceless (to 1e-12 of its size).
  subroutine check_strain(what, e, error)
    character(len=*), intent(in) :: what
    real(c_double), intent(in) :: e(3, 3)
    type(error_t), allocatable, intent(out) :: error
    real(wp), parameter :: rel = 1.0e-12_wp
    real(wp) :: size_e
    call check_values(what//': the rate of strain', e, error)
    if (allocated(error)) return
    size_e = maxval(abs(e))
    if (maxval(abs(e - transpose(e))) > rel*size_e .or. abs(e(1, 1) + e(2, 2) + e(3, 3)) > rel*size_e) &
      call fatal_error(error, what//': the rate of strain must be symmetric and traceless (trace '// &
        to_str(e(1, 1) + e(2, 2) + e(3, 3), '(es12.4)')//')')
  end subroutine check_strain

  !> status and msg from the library's error (kf_failed) or kf_ok.
  subroutine finish(error, status, msg, msglen)
    type(error_t), allocatable, intent(in) :: error
    integer(c_int), intent(out) :: status
    character(kind=c_char), intent(inout) :: msg(*)
    integer(c_int), intent(in) :: msglen
    status = kf_ok
    if (.not. allocated(error)) return
    status = kf_failed
    call put_message(error%message, msg, msglen)
  end subroutine finish

end module kf_capi_hydro
