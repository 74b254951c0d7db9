!> The analysis store of one case file: the file opened once for all of a case's analysis reads
!> (the frames, what a previous run left in /analysis for resuming); the new /analysis group (the
!> schema of docs/analysis.md) is then written into a copy that replaces the file (`write`). It takes and
!> returns plain records and computes nothing; /frames, /checkpoint and the root attributes are
!> read-only here.
module kf_analysis_store
  use kf_kinds, only: wp, i4, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_h5, only: h5_file_t, h5_open_file, h5_close_file, h5_flush, h5_create_group, h5_exists, &
    h5_attr_exists, h5_write_attr, h5_read_attr, h5_write, h5_read, h5_delete, h5_move, h5_raise_end
  use kf_case_verify, only: read_open_frames
  use kf_fs, only: copy_file_exclusive, replace_file, remove_file, parent_directory
  implicit none
  private

  !> Value of the `tool` attribute of /analysis/knots: the one writer of /analysis.
  character(len=*), parameter, public :: analysis_tool = 'knotflow-analyze'
  !> The group of the results, and the prefix of a damaged one that could only be moved aside.
  character(len=*), parameter :: analysis_group = '/analysis', discarded_prefix = '/analysis_discarded_'

  !> k_f and knot spectrum of the analysed frames (/analysis/knots).
  type, public :: knots_record_t
    integer(i8) :: closures = 0, seed = 0
    integer(i8), allocatable :: frame_index(:)      !< 0-based frames
    real(wp), allocatable :: time(:), kf(:)
    real(wp), allocatable :: spectrum(:, :)          !< (size(type_names), frames)
    character(len=:), allocatable :: type_names(:)  !< names of the rows of `spectrum`
    character(len=:), allocatable :: dominant(:)    !< type name of each frame
    !> digest of each frame's time and positions (kf_knot_case: frame_digests); absent in files
    !> analysed before it existed
    integer(i8), allocatable :: frame_digest(:)
  end type knots_record_t

  !> Knot transitions (/analysis/events).
  type, public :: events_record_t
    character(len=:), allocatable :: kind(:)
    integer(i8), allocatable :: frame_index(:)
    real(wp), allocatable :: time(:)
    real(wp) :: low = 0.0_wp, high = 0.0_wp          !< hysteresis thresholds
  end type events_record_t

  !> One knot matrix (/analysis/knot_matrix/frame_<frame>).
  type, public :: matrix_record_t
    integer(i8) :: frame = 0, closures = 0, min_length = 0
    real(wp) :: time = 0.0_wp
    real(wp), allocatable :: k(:, :)                 !< K(i+1, j+1) for the 0-based subchain i..j
  end type matrix_record_t

  !> Modes and spectra of the shape series (/analysis/shape, /analysis/spectra).
  type, public :: shape_record_t
    integer(i4), allocatable :: mode(:)              !< per frame
    integer :: case_mode = 0
    real(wp), allocatable :: frequency(:), power_rg(:), power_phi(:), power_end_to_end(:)
    real(wp) :: period_rg = 0.0_wp, period_phi = 0.0_wp
  end type shape_record_t

  !> One case file, open for its analysis.
  type, public :: analysis_store_t
    private
    type(h5_file_t) :: file
  contains
    procedure :: open => store_open
    procedure :: close => store_close
    procedure :: read_frames => store_read_frames
    procedure :: read_knots
    procedure :: read_matrix
    procedure :: write => store_write
  end type analysis_store_t

contains

  !> Open the case file `path` for the reads (read-only: a file that turns out not to be a case
  !> file is left exactly as it was; HDF5 would write a superblock into an empty file opened for
  !> writing). `write` closes it, writes a copy that replaces it, and opens the new file.
  subroutine store_open(this, path, error)
    class(analysis_store_t), intent(inout) :: this
    character(len=*), intent(in) :: path
    type(error_t), allocatable, intent(out) :: error
    call h5_open_file(this%file, path, .false., error)
  end subroutine store_open

  !> Close the file (a store that is not open is left alone).
  subroutine store_close(this, error)
    class(analysis_store_t), intent(inout) :: this
    type(error_t), allocatable, intent(out), optional :: error
    call h5_close_file(this%file, error)
  end subroutine store_close

  !> The complete frames: times t(nframes) and positions r(3, N, nframes).
  subroutine store_read_frames(this, t, r, error)
    class(analysis_store_t), intent(in) :: this
    real(wp), allocatable, intent(out) :: t(:), r(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    call read_open_frames(this%file, t, r, error)
  end subroutine store_read_frames

  !> The stored frame knots if they were computed with the same closures and seed (`found`);
  !> otherwise `rec` holds no frame.
  subroutine read_knots(this, closures, seed, rec, found, error)
    class(analysis_store_t), intent(in) :: this
    integer(i8), intent(in) :: closures, seed
    type(knots_record_t), intent(out) :: rec
    logical, intent(out) :: found
    type(error_t), allocatable, intent(out) :: error
    character(len=*), parameter :: group = analysis_group//'/knots'
    allocate (rec%frame_index(0), rec%time(0), rec%kf(0), rec%spectrum(0, 0))
    rec%closures = closures
    rec%seed = seed
    ! one query after the other (in one expression, the compiler may skip evaluating one)
    found = h5_exists(this%file, group//'/kf')
    if (found) found = h5_attr_exists(this%file, group, 'closures')
    if (found) found = h5_attr_exists(this%file, group, 'seed')
    if (found) call h5_read_attr(this%file, group, 'closures', rec%closures, error)
    if (found .and. .not. allocated(error)) call h5_read_attr(this%file, group, 'seed', rec%seed, error)
    if (allocated(error)) found = .false.
    if (found) found = rec%closures == closures .and. rec%seed == seed
    if (.not. found) return
    call h5_read(this%file, group//'/frame_index', rec%frame_index, error)
    if (.not. allocated(error)) call h5_read(this%file, group//'/time', rec%time, error)
    if (.not. allocated(error)) call h5_read(this%file, group//'/kf', rec%kf, error)
    if (.not. allocated(error)) call h5_read(this%file, group//'/spectrum', rec%spectrum, error)
    if (.not. allocated(error)) then
      if (h5_exists(this%file, group//'/frame_digest')) &
        call h5_read(this%file, group//'/frame_digest', rec%frame_digest, error)
    end if
    if (allocated(error)) found = .false.
  end subroutine read_knots

  !> The stored knot matrix of `frame` if it was computed with the same closures and min_length.
  subroutine read_matrix(this, frame, closures, min_length, rec, found, error)
    class(analysis_store_t), intent(in) :: this
    integer(i8), intent(in) :: frame, closures, min_length
    type(matrix_record_t), intent(out) :: rec
    logical, intent(out) :: found
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: kt(:, :)
    character(len=:), allocatable :: name
    name = matrix_name(frame)
    rec%frame = frame
    found = h5_exists(this%file, name)
    if (.not. found) return
    call h5_read_attr(this%file, name, 'closures', rec%closures, error)
    if (.not. allocated(error)) call h5_read_attr(this%file, name, 'min_length', rec%min_length, error)
    found = .not. allocated(error)
    if (found) found = rec%closures == closures .and. rec%min_length == min_length
    if (.not. found) return
    call h5_read(this%file, name, kt, error)
    if (.not. allocated(error)) call h5_read_attr(this%file, name, 'time', rec%time, error)
    found = .not. allocated(error)
    if (found) rec%k = transpose(kt)
  end subroutine read_matrix

  pure function matrix_name(frame, root) result(name)
    integer(i8), intent(in) :: frame
    character(len=*), intent(in), optional :: root   !< the group written ('/analysis' if absent)
    character(len=:), allocatable :: name
    if (present(root)) then
      name = root//'/knot_matrix/frame_'//to_str(frame)
    else
      name = analysis_group//'/knot_matrix/frame_'//to_str(frame)
    end if
  end function matrix_name

  !> Replace /analysis by the given results so that a kill (or a failed write, a full disk) at
  !> any moment leaves the case file as it was or with the whole new /analysis, never a file a
  !> later run cannot analyse: the case file is copied to '<dir>/.<name>.analysis.tmp' (created
  !> exclusively; a leftover of a killed run is replaced), /analysis is replaced in the copy, the
  !> copy is flushed, closed, synced and renamed over the case file (kf_fs: copy_file_exclusive,
  !> replace_file). HDF5 changes metadata in place, so a kill while it rewrites a group can
  !> damage the file itself: only the copy is ever changed. An /analysis a kill of an older
  !> version damaged is removed in the copy (`discard`), so a rerun always recovers.
  subroutine store_write(this, knots, events, mats, shapes, error)
    class(analysis_store_t), intent(inout) :: this
    type(knots_record_t), intent(in) :: knots
    type(events_record_t), intent(in) :: events
    type(matrix_record_t), intent(in) :: mats(:)
    type(shape_record_t), intent(in) :: shapes
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t) :: copy
    type(error_t), allocatable :: ignored
    character(len=:), allocatable :: path, tmp
    integer(i8) :: old_end, new_end
    logical :: raised
    path = this%file%name()
    tmp = parent_directory(path)//'/.'//base_name(path)//'.analysis.tmp'
    ! (the reads are done: the original is closed before it is replaced)
    call h5_close_file(this%file)
    call copy_file_exclusive(path, tmp, error)
    if (allocated(error)) then
      error%message = "case file '"//path//"': cannot copy it to write /analysis: "//error%message
      return
    end if
    ! objects a killed writer left beyond the end the superblock records become readable
    call h5_raise_end(tmp, raised, old_end, new_end, error)
    if (.not. allocated(error)) call h5_open_file(copy, tmp, .true., error)
    if (.not. allocated(error)) call discard(copy, analysis_group, error)
    if (.not. allocated(error)) call write_knots(copy, analysis_group, knots, error)
    if (.not. allocated(error)) call write_events(copy, analysis_group, events, error)
    if (.not. allocated(error)) call write_matrices(copy, analysis_group, mats, error)
    if (.not. allocated(error)) call write_shapes(copy, analysis_group, shapes, error)
    if (.not. allocated(error)) call h5_flush(copy, error)
    if (allocated(error)) then
      call h5_close_file(copy, ignored)
    else
      call h5_close_file(copy, error)
    end if
    if (.not. allocated(error)) call replace_file(tmp, path, error)
    if (allocated(error)) then
      call remove_file(tmp)
      error%message = "case file '"//path//"': /analysis not written, the file is as it was: "//error%message
      return
    end if
    ! the store reads the new file from here on
    call h5_open_file(this%file, path, .false., error)
  end subroutine store_write

  !> The last part of a path ('c.h5' of 'results/c.h5').
  pure function base_name(path) result(name)
    character(len=*), intent(in) :: path
    character(len=:), allocatable :: name
    name = path(index(path, '/', back=.true.) + 1:)
  end function base_name

  !> Remove the group `name` if it exists; when it cannot be deleted (a kill of an older
  !> version while it was written damaged its structure), move its link aside to
  !> '/analysis_discarded_<k>' (the first free k; a link move reads nothing of the object), so
  !> that `name` is free again. Readers use /analysis only.
  subroutine discard(file, name, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    type(error_t), allocatable, intent(out) :: error
    type(error_t), allocatable :: not_deleted
    integer :: k
    if (.not. h5_exists(file, name)) return
    call h5_delete(file, name, not_deleted)
    if (.not. allocated(not_deleted)) return
    k = 1
    do while (h5_exists(file, discarded_prefix//to_str(k)))
      k = k + 1
    end do
    call h5_move(file, name, discarded_prefix//to_str(k), error)
    if (allocated(error)) error%message = 'cannot remove '//name//' ('//not_deleted%message// &
      ') nor move it aside: '//error%message
  end subroutine discard

  subroutine write_knots(file, root, rec, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: root
    type(knots_record_t), intent(in) :: rec
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: group
    group = root//'/knots'
    call h5_create_group(file, group, error)
    if (.not. allocated(error)) call h5_write_attr(file, group, 'closures', rec%closures, error)
    if (.not. allocated(error)) call h5_write_attr(file, group, 'seed', rec%seed, error)
    if (.not. allocated(error)) call h5_write_attr(file, group, 'tool', analysis_tool, error)
    if (.not. allocated(error)) call h5_write(file, group//'/frame_index', rec%frame_index, error)
    if (.not. allocated(error)) call h5_write(file, group//'/time', rec%time, error)
    if (.not. allocated(error)) call h5_write(file, group//'/kf', rec%kf, error)
    if (.not. allocated(error)) call h5_write(file, group//'/spectrum', rec%spectrum, error)
    if (.not. allocated(error)) call h5_write_attr(file, group//'/spectrum', 'types', rec%type_names, error)
    if (.not. allocated(error)) call h5_write(file, group//'/dominant', rec%dominant, error)
    if (.not. allocated(error) .and. allocated(rec%frame_digest)) &
      call h5_write(file, group//'/frame_digest', rec%frame_digest, error)
  end subroutine write_knots

  subroutine write_events(file, root, rec, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: root
    type(events_record_t), intent(in) :: rec
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: group
    group = root//'/events'
    call h5_create_group(file, group, error)
    if (.not. allocated(error)) call h5_write_attr(file, group, 'low', rec%low, error)
    if (.not. allocated(error)) call h5_write_attr(file, group, 'high', rec%high, error)
    if (.not. allocated(error)) call h5_write(file, group//'/kind', rec%kind, error)
    if (.not. allocated(error)) call h5_write(file, group//'/time', rec%time, error)
    if (.not. allocated(error)) call h5_write(file, group//'/frame_index', rec%frame_index, error)
  end subroutine write_events

  !> Knot matrices, transposed so that h5py sees K[i, j].
  subroutine write_matrices(file, root, mats, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: root
    type(matrix_record_t), intent(in) :: mats(:)
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: name
    integer :: k
    if (size(mats) > 0) call h5_create_group(file, root//'/knot_matrix', error)
    do k = 1, size(mats)
      if (allocated(error)) return
      name = matrix_name(mats(k)%frame, root)
      call h5_write(file, name, transpose(mats(k)%k), error)
      if (.not. allocated(error)) call h5_write_attr(file, name, 'closures', mats(k)%closures, error)
      if (.not. allocated(error)) call h5_write_attr(file, name, 'min_length', mats(k)%min_length, error)
      if (.not. allocated(error)) call h5_write_attr(file, name, 'time', mats(k)%time, error)
    end do
  end subroutine write_matrices

  subroutine write_shapes(file, root, rec, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: root
    type(shape_record_t), intent(in) :: rec
    type(error_t), allocatable, intent(out) :: error
    call h5_create_group(file, root//'/shape', error)
    if (.not. allocated(error)) call h5_write(file, root//'/shape/mode', rec%mode, error)
    if (.not. allocated(error)) call h5_write_attr(file, root//'/shape', 'case_mode', int(rec%case_mode, i8), error)
    if (.not. allocated(error)) call h5_create_group(file, root//'/spectra', error)
    if (.not. allocated(error)) call h5_write(file, root//'/spectra/frequency', rec%frequency, error)
    if (.not. allocated(error)) call h5_write(file, root//'/spectra/power_rg', rec%power_rg, error)
    if (.not. allocated(error)) call h5_write(file, root//'/spectra/power_phi', rec%power_phi, error)
    if (.not. allocated(error)) call h5_write(file, root//'/spectra/power_end_to_end', rec%power_end_to_end, error)
    if (.not. allocated(error)) &
      call h5_write_attr(file, root//'/spectra', 'dominant_period_rg', rec%period_rg, error)
    if (.not. allocated(error)) &
      call h5_write_attr(file, root//'/spectra', 'dominant_period_phi', rec%period_phi, error)
  end subroutine write_shapes

end module kf_analysis_store
