!> The status codes and messages of the C interface (src/capi, docs/python-api.md). Every bind(c)
!> function returns one of the codes; when it is not `kf_ok` it writes a one-line message (the
!> library's error message, or what was refused) into the caller's buffer `msg` of `msglen`
!> characters, NUL-terminated and truncated to fit. Nothing is kept between calls.
module kf_capi_status
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char, c_double
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_vector_ops, only: distances_representable, too_far_apart
  implicit none
  private

  !> Status codes: success, an argument refused before any work, a failure of the library.
  integer(c_int), parameter, public :: kf_ok = 0, kf_invalid_argument = 1, kf_failed = 2

  public :: put_message, from_c_chars, check_positions, elapsed_seconds

contains

  !> Write `message` into the C buffer buf(buflen), NUL-terminated (nothing when buflen < 1).
  subroutine put_message(message, buf, buflen)
    character(len=*), intent(in) :: message
    integer(c_int), intent(in) :: buflen
    character(kind=c_char), intent(inout) :: buf(*)
    integer :: k, m
    if (buflen < 1) return
    m = min(len(message), buflen - 1)
    do k = 1, m
      buf(k) = message(k:k)
    end do
    buf(m + 1) = c_null_char
  end subroutine put_message

  !> The Fortran string of the n characters chars(1:n) (a C string passed with its length).
  pure function from_c_chars(chars, n) result(s)
    integer(c_int), intent(in) :: n
    character(kind=c_char), intent(in) :: chars(n)
    character(len=:), allocatable :: s
    integer :: k
    allocate (character(len=n) :: s)
    do k = 1, n
      s(k:k) = chars(k)
    end do
  end function from_c_chars

  !> Refuse n < min_beads beads, a non-finite coordinate of r(3, n) or beads so far apart that
  !> their squared distances overflow; `what` names the call.
  subroutine check_positions(what, n, min_beads, r, error)
    character(len=*), intent(in) :: what
    integer(c_int), intent(in) :: n
    integer, intent(in) :: min_beads
    real(c_double), intent(in) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer :: i
    if (n < min_beads) then
      call fatal_error(error, what//': '//to_str(int(n))//' bead(s) given, at least '//to_str(min_beads)// &
        ' needed')
      return
    end if
    do i = 1, size(r, 2)
      if (.not. all(ieee_is_finite(r(:, i)))) then
        call fatal_error(error, what//': bead '//to_str(i)//' (1-based) has a non-finite coordinate')
        return
      end if
    end do
    if (.not. distances_representable(r)) call fatal_error(error, too_far_apart(what//': the beads'))
  end subroutine check_positions

  !> Seconds of wall time since the system_clock count `start` (64-bit counter).
  real(c_double) function elapsed_seconds(start) result(s)
    integer(i8), intent(in) :: start
    integer(i8) :: now, rate
    call system_clock(now, rate)
    s = real(now - start, c_double)/real(rate, c_double)
  end function elapsed_seconds

end module kf_capi_status
