!> The C interface of the knot analysis (kf_knot_closure, docs/python-api.md): the knotted fraction
!> k_f, the spectrum and the dominant type of an open chain from stochastic closures, as
!> knotflow-analyze computes them for a coordinate file (the same call, stream 0).
module kf_capi_knots
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_double, c_int64_t
  use kf_kinds, only: i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_capi_status, only: kf_ok, kf_invalid_argument, kf_failed, put_message, check_positions, elapsed_seconds
  use kf_knot_invariants, only: n_knot_types
  use kf_knot_closure, only: knot_stats_t, analyse_closures
  implicit none
  private

  public :: knotflow_knots

contains

  !> Knots of the open chain of n >= 2 beads at r[3N] from `closures` closures drawn from the
  !> stream (seed, stream) (knotflow-analyze on a coordinate file: stream 0; on a case file,
  !> frame k uses stream k). Out: *kf, spectrum[n_knot_types] (the fraction of each type, in the
  !> order of knotflow_names(3)), *dominant (1-based index of the most frequent type), per_closure
  !> [closures] (the type index of each closure) and *seconds (the library's wall time).
  integer(c_int) function knotflow_knots(n, r, closures, seed, stream, kf, spectrum, dominant, per_closure, &
    seconds, msg, msglen) bind(c, name='knotflow_knots') result(status)
    integer(c_int), value, intent(in) :: n, closures
    real(c_double), intent(in) :: r(3, max(n, 0))
    integer(c_int64_t), value, intent(in) :: seed, stream
    real(c_double), intent(out) :: kf, spectrum(n_knot_types)
    integer(c_int), intent(out) :: dominant
    integer(c_int), intent(out) :: per_closure(max(closures, 0))
    real(c_double), intent(out) :: seconds
    character(kind=c_char), intent(inout) :: msg(*)
    integer(c_int), value, intent(in) :: msglen
    type(error_t), allocatable :: error
    type(knot_stats_t) :: st
    integer(i8) :: start
    kf = 0.0_c_double
    spectrum = 0.0_c_double
    dominant = 0
    per_closure = 0
    seconds = 0.0_c_double
    status = kf_invalid_argument
    ! the numbers of beads and closures are checked by analyse_closures (its limits, its message)
    call check_positions('knotflow_knots', n, 0, r, error)
    if (.not. allocated(error) .and. stream < 0) &
      call fatal_error(error, 'knotflow_knots: stream = '//to_str(int(stream, i8))//' (must be >= 0)')
    if (allocated(error)) then
      call put_message(error%message, msg, msglen)
      return
    end if
    call system_clock(start)
    call analyse_closures(r, closures, int(seed, i8), st, error, stream=int(stream, i8), per_closure=.true.)
    seconds = elapsed_seconds(start)
    if (allocated(error)) then
      status = kf_failed
      call put_message(error%message, msg, msglen)
      return
    end if
    kf = st%kf
    spectrum = st%spectrum
    dominant = st%dominant
    per_closure = st%per_closure
    status = kf_ok
  end function knotflow_knots

end module kf_capi_knots
