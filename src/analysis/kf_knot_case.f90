!> Analysis of a whole trajectory (the computations behind /analysis of a case file, without
!> any I/O): k_f and spectrum of selected frames (each frame with its own random stream
!> (seed, frame index), so the result does not depend on how frames are shared among ranks),
!> transitions, modes from the shape series and spectra of R_g, phi and the end-to-end vector.
module kf_knot_case
  use, intrinsic :: iso_fortran_env, only: int8
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t
  use kf_shape, only: shape_t, compute_shape
  use kf_knot_invariants, only: n_knot_types
  use kf_knot_closure, only: knot_stats_t, analyse_closures
  use kf_modes, only: frame_mode, case_mode
  use kf_spectra, only: power_spectrum, dominant_period, unwrap_phase, detrend
  implicit none
  private

  !> Knot statistics of a set of frames.
  type, public :: frame_knots_t
    integer(i8), allocatable :: frame_index(:)   !< 0-based frame numbers
    real(wp), allocatable :: time(:)
    real(wp), allocatable :: kf(:)
    real(wp), allocatable :: spectrum(:, :)      !< (n_knot_types, nk)
    integer, allocatable :: dominant(:)          !< type index of each frame
  end type frame_knots_t

  !> Modes and spectra of the shape series.
  type, public :: shape_analysis_t
    integer, allocatable :: mode(:)
    integer :: case_mode = 0
    real(wp), allocatable :: frequency(:), power_rg(:), power_phi(:), power_end_to_end(:)
    real(wp) :: period_rg = 0.0_wp, period_phi = 0.0_wp
  end type shape_analysis_t

  public :: select_frames, analyse_frame_knots, analyse_shapes, frame_stream, stored_positions, &
    merge_frame_knots, same_frames, frame_digests

contains

  !> Stream of frame k (0-based) for the whole-chain closures.
  elemental integer(i8) function frame_stream(k)
    integer(i8), intent(in) :: k
    frame_stream = k
  end function frame_stream

  !> Frames 0, stride, 2 stride, ... of nframes, plus the last frame.
  function select_frames(nframes, stride) result(idx)
    integer, intent(in) :: nframes, stride
    integer(i8), allocatable :: idx(:)
    integer :: k, n
    n = (nframes - 1)/stride + 1
    if (modulo(nframes - 1, stride) /= 0) n = n + 1
    allocate (idx(n))
    do k = 1, (nframes - 1)/stride + 1
      idx(k) = int((k - 1)*stride, i8)
    end do
    if (modulo(nframes - 1, stride) /= 0) idx(n) = int(nframes - 1, i8)
  end function select_frames

  !> k_f, spectrum and dominant type of the frames `todo` (0-based) of r(3, N, nframes); with
  !> part/nparts only every nparts-th of them (the others stay zero, to be summed over ranks).
  subroutine analyse_frame_knots(r, t, todo, closures, seed, res, error, part, nparts)
    real(wp), intent(in) :: r(:, :, :), t(:)
    integer(i8), intent(in) :: todo(:)
    integer, intent(in) :: closures
    integer(i8), intent(in) :: seed
    type(frame_knots_t), intent(out) :: res
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: part, nparts
    type(knot_stats_t) :: st
    integer :: k, nk, p, np
    p = 0
    np = 1
    if (present(part)) p = part
    if (present(nparts)) np = nparts
    nk = size(todo)
    allocate (res%frame_index(nk), res%time(nk), res%kf(nk), res%spectrum(n_knot_types, nk), res%dominant(nk))
    res%frame_index = todo
    res%kf = 0.0_wp
    res%spectrum = 0.0_wp
    res%dominant = 0
    do k = 1, nk
      res%time(k) = t(todo(k) + 1)
      if (modulo(k - 1, np) /= p) cycle
      call analyse_closures(r(:, :, todo(k) + 1), closures, seed, st, error, stream=frame_stream(todo(k)))
      if (allocated(error)) then
        error%message = 'frame '//to_str(todo(k))//': '//error%message
        return
      end if
      res%kf(k) = st%kf
      res%spectrum(:, k) = st%spectrum
      res%dominant(k) = st%dominant
    end do
  end subroutine analyse_frame_knots

  !> Modes and spectra from the shapes of all frames r(3, N, nframes) at times t (uniform).
  subroutine analyse_shapes(r, t, res, error)
    real(wp), intent(in) :: r(:, :, :), t(:)
    type(shape_analysis_t), intent(out) :: res
    type(error_t), allocatable, intent(out) :: error
    type(shape_t), allocatable :: s(:)
    real(wp), allocatable :: rg(:), phi(:), f(:), pw(:), e2e(:, :)
    integer :: k, nf, c
    nf = size(r, 3)
    allocate (s(nf), rg(nf), phi(nf), e2e(3, nf))
    do k = 1, nf
      call compute_shape(r(:, :, k), s(k), error)
      if (allocated(error)) return
      rg(k) = s(k)%rg
      phi(k) = s(k)%phi
      e2e(:, k) = r(:, size(r, 2), k) - r(:, 1, k)
    end do
    res%mode = frame_mode(s)
    res%case_mode = case_mode(res%mode, phi)
    if (nf < 4) then
      allocate (res%frequency(0), res%power_rg(0), res%power_phi(0), res%power_end_to_end(0))
      return
    end if
    call power_spectrum(rg, t(2) - t(1), res%frequency, res%power_rg, error)
    if (allocated(error)) return
    call power_spectrum(detrend(unwrap_phase(phi)), t(2) - t(1), f, res%power_phi, error)
    if (allocated(error)) return
    allocate (res%power_end_to_end(size(f)))
    res%power_end_to_end = 0.0_wp
    do c = 1, 3
      call power_spectrum(e2e(c, :), t(2) - t(1), f, pw, error)
      if (allocated(error)) return
      res%power_end_to_end = res%power_end_to_end + pw
    end do
    res%period_rg = dominant_period(res%frequency, res%power_rg)
    res%period_phi = dominant_period(res%frequency, res%power_phi)
  end subroutine analyse_shapes

  !> pos_of(k): the position of frame todo(k) among the frames `stored` (0 when it is not there).
  pure function stored_positions(todo, stored) result(pos_of)
    integer(i8), intent(in) :: todo(:), stored(:)
    integer :: pos_of(size(todo))
    integer :: k, m
    pos_of = 0
    do k = 1, size(todo)
      do m = 1, size(stored)
        if (stored(m) == todo(k)) pos_of(k) = m
      end do
    end do
  end function stored_positions

  !> keep(m): whether a result stored for frame old_index(m) (0-based) of the trajectory t_old,
  !> r_old(3, N, frames) holds for the trajectory t, r as well: that frame is in both, with the
  !> same time and the same positions, bit for bit (an earlier copy of a case file that has
  !> grown since, or a resumed run that rewrote its last frames: those differ).
  pure function same_frames(old_index, t_old, r_old, t, r) result(keep)
    integer(i8), intent(in) :: old_index(:)
    real(wp), intent(in) :: t_old(:), r_old(:, :, :), t(:), r(:, :, :)
    logical :: keep(size(old_index))
    integer(i8) :: k, last
    integer :: m
    keep = .false.
    if (size(r_old, 1) /= size(r, 1) .or. size(r_old, 2) /= size(r, 2)) return
    last = min(size(t_old), size(t), size(r_old, 3), size(r, 3))
    do m = 1, size(old_index)
      k = old_index(m) + 1
      if (k < 1 .or. k > last) cycle
      keep(m) = t_old(k) == t(k)
      if (keep(m)) keep(m) = all(r_old(:, :, k) == r(:, :, k))
    end do
  end function same_frames

  !> A digest of each frame index(m) (0-based) of the trajectory t, r(3, N, frames): its time and
  !> positions, bit for bit (two sums modulo a prime over their bytes, as the checkpoint digest).
  !> Stored with results per frame, so that a result is reused only while its frame is unchanged.
  pure function frame_digests(index, t, r) result(d)
    integer(i8), intent(in) :: index(:)
    real(wp), intent(in) :: t(:), r(:, :, :)
    integer(i8) :: d(size(index))
    integer(i8), parameter :: prime = 2147483629_i8
    integer(int8), allocatable :: bytes(:)
    integer(i8) :: a, b
    integer :: m, k
    do m = 1, size(index)
      bytes = transfer([t(index(m) + 1), reshape(r(:, :, index(m) + 1), [size(r, 1)*size(r, 2)])], [0_int8])
      a = 1
      b = 0
      do k = 1, size(bytes)
        a = mod(a + iand(int(bytes(k), i8), 255_i8), prime)
        b = mod(b + a, prime)
      end do
      d(m) = b*2147483648_i8 + a
    end do
  end function frame_digests

  !> The knots of the frames `todo` (0-based) of a trajectory with frame times t: frame todo(k)
  !> from the stored results (kf, spectrum(:, m) at m = pos_of(k) > 0) or, where pos_of(k) = 0,
  !> from `fresh` (which holds exactly those frames, in the order of todo); the dominant type of
  !> each frame from its spectrum (first in table order on a tie).
  pure subroutine merge_frame_knots(todo, t, pos_of, stored_kf, stored_spectrum, fresh, merged)
    integer(i8), intent(in) :: todo(:)
    real(wp), intent(in) :: t(:)
    integer, intent(in) :: pos_of(:)
    real(wp), intent(in) :: stored_kf(:), stored_spectrum(:, :)
    type(frame_knots_t), intent(in) :: fresh
    type(frame_knots_t), intent(out) :: merged
    integer :: k, m
    allocate (merged%kf(size(todo)), merged%spectrum(n_knot_types, size(todo)), merged%dominant(size(todo)))
    merged%frame_index = todo
    merged%time = t(todo + 1)
    m = 0
    do k = 1, size(todo)
      if (pos_of(k) > 0) then
        merged%kf(k) = stored_kf(pos_of(k))
        merged%spectrum(:, k) = stored_spectrum(:, pos_of(k))
      else
        m = m + 1
        merged%kf(k) = fresh%kf(m)
        merged%spectrum(:, k) = fresh%spectrum(:, m)
      end if
      merged%dominant(k) = maxloc(merged%spectrum(:, k), 1)
    end do
  end subroutine merge_frame_knots

end module kf_knot_case
