!> The C interface of the chain forces (kf_forces, docs/python-api.md): springs, bending, excluded
!> volume and a constant external force, with the &forces group's parameters and validation.
module kf_capi_forces
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_double
  use kf_error, only: error_t
  use kf_capi_status, only: kf_ok, kf_invalid_argument, put_message, check_positions
  use kf_scene_forces, only: forces_params_t
  use kf_forces, only: forces_t
  implicit none
  private

  public :: knotflow_chain_forces, knotflow_forces_defaults

contains

  !> f[3N] = the total force on each of the n beads at r[3N] and *energy = the potential energy of
  !> the conservative terms, for a chain of rest bond length `bond_length`: springs (/= 0) with
  !> constant spring_k, bending (/= 0) with stiffness bending_a, excluded volume (/= 0) with
  !> ev_strength and ev_range, and the external force external[3] on every bead (the &forces
  !> group's variables and units, PHYSICS.md section 2).
  integer(c_int) function knotflow_chain_forces(n, r, bond_length, springs, spring_k, bending, bending_a, &
    excluded_volume, ev_strength, ev_range, external, f, energy, msg, msglen) &
    bind(c, name='knotflow_chain_forces') result(status)
    integer(c_int), value, intent(in) :: n
    real(c_double), intent(in) :: r(3, max(n, 0))
    real(c_double), value, intent(in) :: bond_length, spring_k, bending_a, ev_strength, ev_range
    integer(c_int), value, intent(in) :: springs, bending, excluded_volume
    real(c_double), intent(in) :: external(3)
    real(c_double), intent(out) :: f(3, max(n, 0))
    real(c_double), intent(out) :: energy
    character(kind=c_char), intent(inout) :: msg(*)
    integer(c_int), value, intent(in) :: msglen
    type(error_t), allocatable :: error
    type(forces_t) :: forces
    type(forces_params_t) :: params
    f = 0.0_c_double
    energy = 0.0_c_double
    status = kf_invalid_argument
    ! the number of beads and the parameters are checked by forces%init (the &forces validation)
    call check_positions('knotflow_chain_forces', n, 0, r, error)
    if (.not. allocated(error)) then
      params%springs = springs /= 0
      params%spring_k = spring_k
      params%bending = bending /= 0
      params%bending_a = bending_a
      params%excluded_volume = excluded_volume /= 0
      params%ev_strength = ev_strength
      params%ev_range = ev_range
      params%external_force = external
      call forces%init(params, n, bond_length, error)
    end if
    if (allocated(error)) then
      call put_message(error%message, msg, msglen)
      return
    end if
    call forces%compute(r, f)
    energy = forces%energy(r)
    status = kf_ok
  end function knotflow_chain_forces

  !> The &forces group's defaults: springs, bending and excluded_volume as 1/0, spring_k,
  !> bending_a, ev_strength and ev_range.
  subroutine knotflow_forces_defaults(springs, spring_k, bending, bending_a, excluded_volume, ev_strength, &
    ev_range) bind(c, name='knotflow_forces_defaults')
    integer(c_int), intent(out) :: springs, bending, excluded_volume
    real(c_double), intent(out) :: spring_k, bending_a, ev_strength, ev_range
    type(forces_params_t) :: p
    springs = merge(1, 0, p%springs)
    spring_k = p%spring_k
    bending = merge(1, 0, p%bending)
    bending_a = p%bending_a
    excluded_volume = merge(1, 0, p%excluded_volume)
    ev_strength = p%ev_strength
    ev_range = p%ev_range
  end subroutine knotflow_forces_defaults

end module kf_capi_forces
