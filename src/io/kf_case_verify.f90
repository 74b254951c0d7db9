!> Reading a case file back: its status (`case_file_status`), its complete frames
!> (`read_frames`, `read_open_frames`: what every reader of positions takes) and the
!> verification of a finished run (`verify_case_file`: every /frames dataset of the frame table
!> (kf_case_frames), the checkpoint (kf_case_checkpoint) and /runs (kf_case_runs)).
!> Readers refuse bad frames instead of computing from them; every message names the file.
module kf_case_verify
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp, i4, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_file_type, only: check_regular_file
  use kf_vector_ops, only: distances_representable, too_far_apart
  use kf_h5, only: h5_file_t, h5_open_file, h5_close_file, h5_exists, h5_attr_exists, h5_read_attr, h5_read
  use kf_case_frames, only: frames_time, frames_positions, file_frame_template, check_frames
  use kf_case_checkpoint, only: checkpoint_t, latest_checkpoint, checkpoint_frames
  use kf_case_runs, only: check_runs
  implicit none
  private

  public :: case_file_status, verify_case_file, read_frames, read_open_frames, read_observables

contains

  !> Status of the case file `path`: 'missing' (no file), the status attribute ('running',
  !> 'finished', 'failed: <reason>'), or 'corrupt: <reason>' when the file exists but cannot be
  !> opened as HDF5 or has no status attribute (the caller reports it and recreates the case).
  !> `error` is set only for an invalid request (an empty path), not for a bad file.
  subroutine case_file_status(path, status, error)
    character(len=*), intent(in) :: path
    character(len=:), allocatable, intent(out) :: status
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t) :: file
    type(error_t), allocatable :: err
    logical :: exists, is_directory
    if (len_trim(path) == 0) then
      call fatal_error(error, 'case_file_status: empty path')
      status = 'missing'
      return
    end if
    inquire (file=path, exist=exists)
    if (.not. exists) then
      status = 'missing'
      return
    end if
    ! A FIFO, device or socket under the case file's name is no damaged case file: it is refused
    ! (not moved aside, not opened: a FIFO would block HDF5's open for ever).
    inquire (file=path//'/.', exist=is_directory)
    if (.not. is_directory) then
      call check_regular_file(path, 'case file', error)
      if (allocated(error)) then
        status = 'not a regular file'
        return
      end if
    end if
    call h5_open_file(file, path, .false., err)
    if (allocated(err)) then
      status = 'corrupt: '//err%message
      return
    end if
    if (.not. h5_attr_exists(file, '/', 'status')) then
      status = 'corrupt: no status attribute'
    else
      call h5_read_attr(file, '/', 'status', status, err)
      if (allocated(err)) status = 'corrupt: '//err%message
    end if
    call h5_close_file(file)
  end subroutine case_file_status

  !> Read the case file `path` back and check what a finished run must hold: every /frames
  !> dataset has the checkpoint's frame count and reads without a checksum error; the times
  !> start at 0, increase strictly and end at `t_end`; every position is finite; the checkpoint
  !> is the last frame. The message names the file, dataset and frame of the first problem.
  subroutine verify_case_file(path, t_end, error)
    character(len=*), intent(in) :: path
    real(wp), intent(in) :: t_end
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t) :: file
    real(wp), allocatable :: t(:), r(:, :, :)
    type(checkpoint_t) :: ck
    integer(i8) :: nframes
    integer(i4) :: n_beads
    integer :: k, bad
    call h5_open_file(file, path, .false., error)
    if (allocated(error)) return
    call check()
    call h5_close_file(file)
    if (allocated(error)) then
      k = index(error%message, "case file '"//path//"'")
      if (k == 1) error%message = error%message(len("case file '"//path//"'") + 1:)
      if (k == 1 .and. error%message(1:1) == ':') error%message = adjustl(error%message(2:))
      error%message = "case file '"//path//"' fails verification: "//error%message
    end if

  contains

    subroutine check()
      call h5_read_attr(file, '/', 'n_beads', n_beads, error)
      if (allocated(error)) return
      ! the newest whole checkpoint, which must be the last frame
      call latest_checkpoint(file, int(n_beads), ck, error)
      if (allocated(error)) return
      nframes = ck%nframes
      call h5_read(file, frames_time, t, error)
      if (allocated(error)) return
      if (size(t, kind=i8) /= nframes .or. nframes < 1) then
        call fatal_error(error, frames_time//' has '//to_str(size(t, kind=i8))//' frames, the newest whole '// &
          'checkpoint '//to_str(nframes))
        return
      end if
      if (t(1) /= 0.0_wp) then
        call fatal_error(error, 'frame 0 is not at t = 0')
        return
      end if
      do k = 1, size(t)
        if (.not. ieee_is_finite(t(k))) then
          call fatal_error(error, 'frame '//to_str(int(k - 1, i8))//' has a non-finite time')
          return
        end if
      end do
      do k = 2, size(t)
        if (.not. t(k) > t(k - 1)) then
          call fatal_error(error, 'frame '//to_str(int(k - 1, i8))//': time does not increase')
          return
        end if
      end do
      if (.not. abs(t(size(t)) - t_end) <= 1.0e-9_wp*max(1.0_wp, abs(t_end))) then
        call fatal_error(error, 'the last frame is not at t_end')
        return
      end if
      call h5_read(file, frames_positions, r, error)
      if (allocated(error)) return
      if (size(r, 1) /= 3 .or. size(r, 2) /= n_beads .or. size(r, 3, kind=i8) /= nframes) then
        call fatal_error(error, frames_positions//' does not have shape (nframes, n_beads, 3)')
        return
      end if
      do k = 1, size(r, 3)
        bad = count(.not. ieee_is_finite(r(:, :, k)))
        if (bad > 0) then
          call fatal_error(error, 'frame '//to_str(int(k - 1, i8))//' (t = '//to_str(t(k), '(g0.6)')//') holds '// &
            to_str(int(bad, i8))//' non-finite coordinates')
          return
        end if
      end do
      ! every /frames dataset (of the parts the file has): its length, and it reads back
      call check_frames(file, file_frame_template(file, int(n_beads)), nframes, error)
      if (allocated(error)) return
      call check_runs(file, error)
    end subroutine check


  end subroutine verify_case_file

  !> Read the complete frames of a case file: times t(nframes) and positions r(3, N, nframes).
  !> A file with a checkpoint is read up to the frames its newest checkpoint counts (a frame
  !> beyond it was being written when the run stopped). Refused with an error naming the file
  !> and the problem: no /frames group, /frames/time or /frames/positions missing, not numbers
  !> or unreadable (checksums), positions not of shape (frames, beads, 3), fewer than 2 beads,
  !> time and positions of different lengths (without a checkpoint), no frame, a non-finite time
  !> or coordinate, times that do not increase.
  subroutine read_frames(path, t, r, error)
    character(len=*), intent(in) :: path
    real(wp), allocatable, intent(out) :: t(:)
    real(wp), allocatable, intent(out) :: r(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t) :: file
    call h5_open_file(file, path, .false., error)
    if (allocated(error)) return
    call read_open_frames(file, t, r, error)
    call h5_close_file(file)
  end subroutine read_frames

  !> `read_frames` of a case file that is already open.
  subroutine read_open_frames(file, t, r, error)
    type(h5_file_t), intent(in) :: file
    real(wp), allocatable, intent(out) :: t(:)
    real(wp), allocatable, intent(out) :: r(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: path
    integer(i8) :: counted
    integer :: n, k
    path = file%name()
    if (.not. h5_exists(file, '/frames')) then
      call fatal_error(error, "case file '"//path//"': no /frames group (not a knotflow case file)")
    else
      call h5_read(file, frames_time, t, error)
      if (.not. allocated(error)) call h5_read(file, frames_positions, r, error)
      if (.not. allocated(error)) call checkpoint_frames(file, counted, error)
    end if
    if (allocated(error)) return
    if (size(r, 1) /= 3) then
      call fatal_error(error, "case file '"//path//"': /frames/positions has shape ("//to_str(size(r, 3))//', '// &
        to_str(size(r, 2))//', '//to_str(size(r, 1))//'), expected (frames, beads, 3)')
      return
    end if
    if (size(r, 2) < 2) then
      call fatal_error(error, "case file '"//path//"': /frames/positions holds "//to_str(size(r, 2))// &
        ' bead(s) per frame, a chain needs at least 2')
      return
    end if
    if (counted >= 0) then
      n = int(min(int(min(size(t), size(r, 3)), i8), counted))
    else if (size(r, 3) /= size(t)) then
      call fatal_error(error, "case file '"//path//"': /frames/time and /frames/positions have different "// &
        'lengths ('//to_str(size(t))//' and '//to_str(size(r, 3))//' frames)')
      return
    else
      n = size(t)
    end if
    if (n < 1) then
      call fatal_error(error, "case file '"//path//"': no complete frame (/frames is empty)")
      return
    end if
    if (n < size(t)) t = t(1:n)
    if (n < size(r, 3)) r = r(:, :, 1:n)
    call check_finite_frames(path, t, r, error)
    if (allocated(error)) return
    do k = 2, n
      if (.not. t(k) > t(k - 1)) then
        call fatal_error(error, "case file '"//path//"': frame "//to_str(k - 1)//' (t = '//to_str(t(k), '(g0.6)')// &
          ') is not after frame '//to_str(k - 2)//' (t = '//to_str(t(k - 1), '(g0.6)')//'): times must increase')
        return
      end if
    end do
  end subroutine read_open_frames

  !> Every frame time and coordinate must be finite: the error names the file, the first bad
  !> frame (0-based), its time and the number of non-finite coordinates.
  subroutine check_finite_frames(path, t, r, error)
    character(len=*), intent(in) :: path
    real(wp), intent(in) :: t(:), r(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    integer :: k, bad
    do k = 1, size(t)
      bad = count(.not. ieee_is_finite(r(:, :, k)))
      if (bad > 0 .or. .not. ieee_is_finite(t(k))) then
        call fatal_error(error, "case file '"//path//"': frame "//to_str(k - 1)//' (t = '// &
          to_str(t(k), '(g0.6)')//') holds '//to_str(bad)//' non-finite coordinates'// &
          merge(' and a non-finite time', '                      ', .not. ieee_is_finite(t(k))))
        error%message = trim(error%message)
        return
      end if
      if (.not. distances_representable(r(:, :, k))) then
        call fatal_error(error, too_far_apart("case file '"//path//"': frame "//to_str(k - 1)//' (t = '// &
          to_str(t(k), '(g0.6)')//'): the beads'))
        return
      end if
    end do
  end subroutine check_finite_frames

  !> Read the shape observables of the first `nframes` frames of the case file `path`
  !> (/frames/observables: as many frames as `read_frames` returns): values(nframes, 6) holds
  !> rg, a, b, c, theta, phi (in this order, one column each) and close_pairs(nframes).
  !> Refused with an error naming the file and the dataset: missing, unreadable, or shorter than
  !> `nframes`.
  subroutine read_observables(path, nframes, values, close_pairs, error)
    character(len=*), intent(in) :: path
    integer, intent(in) :: nframes
    real(wp), allocatable, intent(out) :: values(:, :)
    integer(i4), allocatable, intent(out) :: close_pairs(:)
    type(error_t), allocatable, intent(out) :: error
    character(len=*), parameter :: names(6) = [character(len=5) :: 'rg', 'a', 'b', 'c', 'theta', 'phi']
    type(h5_file_t) :: file
    real(wp), allocatable :: column(:)
    integer(i4), allocatable :: counts(:)
    integer :: k
    allocate (values(nframes, 6), close_pairs(nframes))
    call h5_open_file(file, path, .false., error)
    if (allocated(error)) return
    do k = 1, size(names)
      call read_column('/frames/observables/'//trim(names(k)))
      if (allocated(error)) exit
      values(:, k) = column(1:nframes)
    end do
    if (.not. allocated(error)) then
      if (.not. h5_exists(file, '/frames/observables/close_pairs')) then
        call fatal_error(error, '/frames/observables/close_pairs missing (not a knotflow case file)')
      else
        call h5_read(file, '/frames/observables/close_pairs', counts, error)
      end if
      if (.not. allocated(error) .and. size(counts) < nframes) call too_short('/frames/observables/close_pairs', &
                                                                             size(counts))
      if (.not. allocated(error)) close_pairs = counts(1:nframes)
    end if
    call h5_close_file(file)
    if (allocated(error)) error%message = "case file '"//path//"': "//error%message

  contains

    subroutine read_column(name)
      character(len=*), intent(in) :: name
      if (.not. h5_exists(file, name)) then
        call fatal_error(error, name//' missing (not a knotflow case file)')
        return
      end if
      call h5_read(file, name, column, error)
      if (.not. allocated(error) .and. size(column) < nframes) call too_short(name, size(column))
    end subroutine read_column

    subroutine too_short(name, length)
      character(len=*), intent(in) :: name
      integer, intent(in) :: length
      call fatal_error(error, name//' holds '//to_str(length)//' frame(s), fewer than the '//to_str(nframes)// &
        ' of /frames/positions')
    end subroutine too_short

  end subroutine read_observables

end module kf_case_verify
