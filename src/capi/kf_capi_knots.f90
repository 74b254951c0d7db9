!> The C interface of the knot analysis (kf_knot_closure, docs/python-api.md): the knotted fraction
!> k_f, the spectrum and the dominant type of an open chain from stochastic closures, as
!> knotflow-analyze computes them for a coordinate file (the same call, stream 0), at closure
!> points given, and the knot matrix (kf_knot_matrix) with its knot core and slipknot test.
!> Nothing is kept between calls: independent calls may run in parallel threads.
module kf_capi_knots
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_double, c_int64_t
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_capi_status, only: kf_ok, kf_invalid_argument, kf_failed, put_message, check_positions, elapsed_seconds
  use kf_knot_invariants, only: n_knot_types
  use kf_knot_closure, only: knot_stats_t, analyse_closures
  use kf_knot_matrix, only: knot_matrix, knot_core, is_slipknot, default_matrix_closures, default_min_length
  implicit none
  private

  public :: knotflow_knots, knotflow_knots_at_points, knotflow_knot_matrix, knotflow_knot_core, &
    knotflow_matrix_defaults

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
    call clear_knot_outputs(kf, spectrum, dominant, per_closure, seconds)
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

  !> Knots of the open chain of n >= 2 beads at r[3N] closed through the npoints >= 1 given
  !> points[3 npoints] (absolute coordinates, in order; knotflow-analyze --closure-points); `seed`
  !> draws the projections. Out: as knotflow_knots, per_closure[npoints].
  integer(c_int) function knotflow_knots_at_points(n, r, npoints, points, seed, kf, spectrum, dominant, &
    per_closure, seconds, msg, msglen) bind(c, name='knotflow_knots_at_points') result(status)
    integer(c_int), value, intent(in) :: n, npoints
    real(c_double), intent(in) :: r(3, max(n, 0)), points(3, max(npoints, 0))
    integer(c_int64_t), value, intent(in) :: seed
    real(c_double), intent(out) :: kf, spectrum(n_knot_types)
    integer(c_int), intent(out) :: dominant
    integer(c_int), intent(out) :: per_closure(max(npoints, 0))
    real(c_double), intent(out) :: seconds
    character(kind=c_char), intent(inout) :: msg(*)
    integer(c_int), value, intent(in) :: msglen
    type(error_t), allocatable :: error
    type(knot_stats_t) :: st
    integer(i8) :: start
    call clear_knot_outputs(kf, spectrum, dominant, per_closure, seconds)
    status = kf_invalid_argument
    call check_positions('knotflow_knots_at_points', n, 2, r, error)
    if (.not. allocated(error) .and. npoints < 1) &
      call fatal_error(error, 'knotflow_knots_at_points: '//to_str(int(npoints))//' closure point(s) given, '// &
        'at least 1 needed')
    if (.not. allocated(error)) then
      if (.not. all(ieee_is_finite(points))) &
        call fatal_error(error, 'knotflow_knots_at_points: a closure point has a non-finite coordinate')
    end if
    if (allocated(error)) then
      call put_message(error%message, msg, msglen)
      return
    end if
    call system_clock(start)
    call analyse_closures(r, npoints, int(seed, i8), st, error, points=points, per_closure=.true.)
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
  end function knotflow_knots_at_points

  !> The outputs of knotflow_knots and knotflow_knots_at_points before anything is computed
  !> (what a refused call leaves).
  subroutine clear_knot_outputs(kf, spectrum, dominant, per_closure, seconds)
    real(c_double), intent(out) :: kf, spectrum(:), seconds
    integer(c_int), intent(out) :: dominant, per_closure(:)
    kf = 0.0_c_double
    spectrum = 0.0_c_double
    dominant = 0
    per_closure = 0
    seconds = 0.0_c_double
  end subroutine clear_knot_outputs

  !> The knot matrix of the chain of n >= 2 beads at r[3N] (knotflow-analyze --matrix): kmat
  !> [N*N], column-major (Fortran order: kmat[i + N j] is K(i, j), 0-based), K(i, j) the k_f of
  !> the subchain i..j (i < j, at least min_length >= 2 beads) from `closures` closures of its
  !> own stream (seed, i*65536 + j + 1); NaN elsewhere, and off the grid of `stride` (i and j
  !> multiples of stride, or j = N - 1). Out: core[2] (the knot core, 0-based, -1 -1 when
  !> *found = 0), *slipknot (1: a knot core while kf_whole < 0.1; 0 also when kf_whole is not
  !> finite, i.e. not given) and *seconds.
  integer(c_int) function knotflow_knot_matrix(n, r, closures, seed, min_length, stride, kf_whole, kmat, core, &
    found, slipknot, seconds, msg, msglen) bind(c, name='knotflow_knot_matrix') result(status)
    integer(c_int), value, intent(in) :: n, closures, min_length, stride
    real(c_double), intent(in) :: r(3, max(n, 0))
    integer(c_int64_t), value, intent(in) :: seed
    real(c_double), value, intent(in) :: kf_whole
    real(c_double), intent(out) :: kmat(max(n, 0), max(n, 0))
    integer(c_int), intent(out) :: core(2), found, slipknot
    real(c_double), intent(out) :: seconds
    character(kind=c_char), intent(inout) :: msg(*)
    integer(c_int), value, intent(in) :: msglen
    type(error_t), allocatable :: error
    integer(i8) :: start
    integer :: c(2)
    logical :: has_core
    core = -1
    found = 0
    slipknot = 0
    seconds = 0.0_c_double
    status = kf_invalid_argument
    call check_positions('knotflow_knot_matrix', n, 2, r, error)
    if (.not. allocated(error) .and. closures < 1) &
      call fatal_error(error, 'knotflow_knot_matrix: closures = '//to_str(int(closures))//' (must be >= 1)')
    if (allocated(error)) then
      call put_message(error%message, msg, msglen)
      return
    end if
    call system_clock(start)
    ! min_length and stride are checked by knot_matrix (its limits, its message)
    call knot_matrix(r, int(closures), int(seed, i8), int(min_length), kmat, error, stride=int(stride))
    seconds = elapsed_seconds(start)
    if (allocated(error)) then
      status = kf_failed
      call put_message(error%message, msg, msglen)
      return
    end if
    call knot_core(kmat, c, has_core)
    core = c
    found = merge(1, 0, has_core)
    if (ieee_is_finite(kf_whole)) slipknot = merge(1, 0, is_slipknot(kmat, kf_whole))
    status = kf_ok
  end function knotflow_knot_matrix

  !> The knot core of a knot matrix kmat[N*N] (column-major as knotflow_knot_matrix writes it;
  !> NaN entries are skipped, only i < j is looked at): core[2] the shortest subchain with
  !> K >= 0.5, the lowest i on a tie (0-based), *found = 1; -1 -1 and 0 when there is none.
  integer(c_int) function knotflow_knot_core(n, kmat, core, found, msg, msglen) bind(c, name='knotflow_knot_core') &
    result(status)
    integer(c_int), value, intent(in) :: n
    real(c_double), intent(in) :: kmat(max(n, 0), max(n, 0))
    integer(c_int), intent(out) :: core(2), found
    character(kind=c_char), intent(inout) :: msg(*)
    integer(c_int), value, intent(in) :: msglen
    integer :: c(2)
    logical :: has_core
    core = -1
    found = 0
    if (n < 0) then
      status = kf_invalid_argument
      call put_message('knotflow_knot_core: n = '//to_str(int(n))//' (must be >= 0)', msg, msglen)
      return
    end if
    call knot_core(kmat, c, has_core)
    core = c
    found = merge(1, 0, has_core)
    status = kf_ok
  end function knotflow_knot_core

  !> knotflow-analyze's defaults of the knot matrix: closures per subchain and shortest subchain.
  subroutine knotflow_matrix_defaults(closures, min_length) bind(c, name='knotflow_matrix_defaults')
    integer(c_int), intent(out) :: closures, min_length
    closures = default_matrix_closures
    min_length = default_min_length
  end subroutine knotflow_matrix_defaults

end module kf_capi_knots
