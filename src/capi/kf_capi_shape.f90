!> The C interface of the shape observables (kf_shape, PHYSICS.md section 6, docs/python-api.md):
!> what knotflow records for every frame (/frames/observables).
module kf_capi_shape
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_double
  use kf_error, only: error_t
  use kf_capi_status, only: kf_ok, kf_invalid_argument, kf_failed, put_message, check_positions
  use kf_shape, only: shape_t, compute_shape
  implicit none
  private

  public :: knotflow_shape

contains

  !> Shape of the chain of n >= 2 beads at r[3N]: values[6] = (R_g, a, b, c, theta, phi) and
  !> *close_pairs (pairs |i - j| > 1 closer than 1.05).
  integer(c_int) function knotflow_shape(n, r, values, close_pairs, msg, msglen) bind(c, name='knotflow_shape') &
    result(status)
    integer(c_int), value, intent(in) :: n
    real(c_double), intent(in) :: r(3, max(n, 0))
    real(c_double), intent(out) :: values(6)
    integer(c_int), intent(out) :: close_pairs
    character(kind=c_char), intent(inout) :: msg(*)
    integer(c_int), value, intent(in) :: msglen
    type(error_t), allocatable :: error
    type(shape_t) :: s
    values = 0.0_c_double
    close_pairs = 0
    status = kf_invalid_argument
    call check_positions('knotflow_shape', n, 2, r, error)
    if (allocated(error)) then
      call put_message(error%message, msg, msglen)
      return
    end if
    call compute_shape(r, s, error)
    if (allocated(error)) then
      status = kf_failed
      call put_message(error%message, msg, msglen)
      return
    end if
    values = [s%rg, s%a, s%b, s%c, s%theta, s%phi]
    close_pairs = s%close_pairs
    status = kf_ok
  end function knotflow_shape

end module kf_capi_shape
