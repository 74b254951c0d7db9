!> The /analysis group of a case file (the schema of docs/analysis.md): reading what a previous
!> run left (for resuming), removing it and writing the new one. Only /analysis is ever touched;
!> /frames, /checkpoint and the root attributes are read-only here. HDF5 goes through kf_h5.
module kf_knot_store
  use kf_kinds, only: wp, i4, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_h5, only: h5_file_t, h5_open_file, h5_close_file, h5_create_group, h5_exists, &
    h5_attr_exists, h5_write_attr, h5_read_attr, h5_write, h5_read, h5_delete
  use kf_knot_invariants, only: n_knot_types, knot_type_names
  use kf_knot_case, only: frame_knots_t, shape_analysis_t
  use kf_transitions, only: event_names
  implicit none
  private

  character(len=*), parameter, public :: analysis_tool = 'knotflow-analyze'

  !> One knot matrix to store.
  type, public :: stored_matrix_t
    integer(i8) :: frame = 0
    real(wp) :: time = 0.0_wp
    real(wp), allocatable :: k(:, :)   !< K(i+1, j+1) for the 0-based subchain i..j
  end type stored_matrix_t

  public :: read_previous_knots, read_previous_matrix, remove_analysis, write_analysis

contains

  !> The frame knots of a previous run with the same closures and seed (nk = 0 if none).
  subroutine read_previous_knots(path, closures, seed, prev, error)
    character(len=*), intent(in) :: path
    integer, intent(in) :: closures
    integer(i8), intent(in) :: seed
    type(frame_knots_t), intent(out) :: prev
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t) :: file
    integer(i8) :: c, s
    integer :: k
    logical :: stored
    allocate (prev%frame_index(0), prev%time(0), prev%kf(0), prev%spectrum(n_knot_types, 0), prev%dominant(0))
    call h5_open_file(file, path, .false., error)
    if (allocated(error)) return
    ! one query after the other (in one expression, the compiler may skip evaluating one)
    stored = h5_exists(file, '/analysis/knots/kf')
    if (stored) stored = h5_attr_exists(file, '/analysis/knots', 'closures')
    if (stored) stored = h5_attr_exists(file, '/analysis/knots', 'seed')
    if (stored) then
      call h5_read_attr(file, '/analysis/knots', 'closures', c, error)
      if (.not. allocated(error)) call h5_read_attr(file, '/analysis/knots', 'seed', s, error)
      if (.not. allocated(error) .and. c == closures .and. s == seed) then
        deallocate (prev%frame_index, prev%time, prev%kf, prev%spectrum, prev%dominant)
        call h5_read(file, '/analysis/knots/frame_index', prev%frame_index, error)
        if (.not. allocated(error)) call h5_read(file, '/analysis/knots/time', prev%time, error)
        if (.not. allocated(error)) call h5_read(file, '/analysis/knots/kf', prev%kf, error)
        if (.not. allocated(error)) call h5_read(file, '/analysis/knots/spectrum', prev%spectrum, error)
        if (.not. allocated(error)) then
          allocate (prev%dominant(size(prev%kf)))
          do k = 1, size(prev%kf)
            prev%dominant(k) = maxloc(prev%spectrum(:, k), 1)
          end do
        end if
      end if
    end if
    call h5_close_file(file)
  end subroutine read_previous_knots

  !> A previous knot matrix of `frame` with the same closures and min_length, if any.
  subroutine read_previous_matrix(path, frame, closures, min_length, m, found, error)
    character(len=*), intent(in) :: path
    integer(i8), intent(in) :: frame
    integer, intent(in) :: closures, min_length
    type(stored_matrix_t), intent(out) :: m
    logical, intent(out) :: found
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t) :: file
    integer(i8) :: c, l
    real(wp), allocatable :: kt(:, :)
    character(len=:), allocatable :: name
    found = .false.
    name = '/analysis/knot_matrix/frame_'//to_str(frame)
    call h5_open_file(file, path, .false., error)
    if (allocated(error)) return
    if (h5_exists(file, name)) then
      call h5_read_attr(file, name, 'closures', c, error)
      if (.not. allocated(error)) call h5_read_attr(file, name, 'min_length', l, error)
      if (.not. allocated(error) .and. c == closures .and. l == min_length) then
        call h5_read(file, name, kt, error)
        if (.not. allocated(error)) call h5_read_attr(file, name, 'time', m%time, error)
        if (.not. allocated(error)) then
          m%frame = frame
          m%k = transpose(kt)
          found = .true.
        end if
      end if
    end if
    call h5_close_file(file)
  end subroutine read_previous_matrix

  !> Delete the group /analysis (and everything in it) if it exists.
  subroutine remove_analysis(path, error)
    character(len=*), intent(in) :: path
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t) :: file
    type(error_t), allocatable :: h5_error, close_error
    call h5_open_file(file, path, .true., h5_error)
    if (allocated(h5_error)) then
      call fatal_error(error, "case file '"//path//"': cannot open for writing")
      return
    end if
    call h5_delete(file, '/analysis', h5_error)
    call h5_close_file(file, close_error)
    if (allocated(h5_error) .or. allocated(close_error)) &
      call fatal_error(error, "case file '"//path//"': cannot remove /analysis")
  end subroutine remove_analysis

  !> Replace /analysis by the given results. On failure /analysis is removed again, so that no
  !> partial group is left behind.
  subroutine write_analysis(path, knots, closures, seed, ev_kind, ev_frame, ev_time, low, high, &
                            mats, mat_closures, min_length, shapes, error)
    character(len=*), intent(in) :: path
    type(frame_knots_t), intent(in) :: knots
    integer, intent(in) :: closures, mat_closures, min_length
    integer(i8), intent(in) :: seed
    integer, intent(in) :: ev_kind(:)
    integer(i8), intent(in) :: ev_frame(:)
    real(wp), intent(in) :: ev_time(:), low, high
    type(stored_matrix_t), intent(in) :: mats(:)
    type(shape_analysis_t), intent(in) :: shapes
    type(error_t), allocatable, intent(out) :: error
    type(error_t), allocatable :: cleanup
    call remove_analysis(path, error)
    if (allocated(error)) return
    call write_all(error)
    if (allocated(error)) call remove_analysis(path, cleanup)

  contains

    subroutine write_all(error)
      type(error_t), allocatable, intent(out) :: error
      type(h5_file_t) :: file
      character(len=5), allocatable :: dom(:)
      character(len=6), allocatable :: kinds(:)
      character(len=:), allocatable :: name
      integer :: k
      call h5_open_file(file, path, .true., error)
      if (allocated(error)) return
      call h5_create_group(file, '/analysis/knots', error)
      if (allocated(error)) goto 100
      call h5_write_attr(file, '/analysis/knots', 'closures', int(closures, i8), error)
      if (allocated(error)) goto 100
      call h5_write_attr(file, '/analysis/knots', 'seed', seed, error)
      if (allocated(error)) goto 100
      call h5_write_attr(file, '/analysis/knots', 'tool', analysis_tool, error)
      if (allocated(error)) goto 100
      call h5_write(file, '/analysis/knots/frame_index', knots%frame_index, error)
      if (allocated(error)) goto 100
      call h5_write(file, '/analysis/knots/time', knots%time, error)
      if (allocated(error)) goto 100
      call h5_write(file, '/analysis/knots/kf', knots%kf, error)
      if (allocated(error)) goto 100
      call h5_write(file, '/analysis/knots/spectrum', knots%spectrum, error)
      if (allocated(error)) goto 100
      call h5_write_attr(file, '/analysis/knots/spectrum', 'types', knot_type_names, error)
      if (allocated(error)) goto 100
      allocate (dom(size(knots%dominant)))
      do k = 1, size(dom)
        dom(k) = knot_type_names(knots%dominant(k))
      end do
      call h5_write(file, '/analysis/knots/dominant', dom, error)
      if (allocated(error)) goto 100
      ! events
      call h5_create_group(file, '/analysis/events', error)
      if (allocated(error)) goto 100
      call h5_write_attr(file, '/analysis/events', 'low', low, error)
      if (allocated(error)) goto 100
      call h5_write_attr(file, '/analysis/events', 'high', high, error)
      if (allocated(error)) goto 100
      allocate (kinds(size(ev_kind)))
      do k = 1, size(ev_kind)
        kinds(k) = event_names(ev_kind(k))
      end do
      call h5_write(file, '/analysis/events/kind', kinds, error)
      if (allocated(error)) goto 100
      call h5_write(file, '/analysis/events/time', ev_time, error)
      if (allocated(error)) goto 100
      call h5_write(file, '/analysis/events/frame_index', ev_frame, error)
      if (allocated(error)) goto 100
      ! knot matrices (transposed so that h5py sees K[i, j])
      if (size(mats) > 0) then
        call h5_create_group(file, '/analysis/knot_matrix', error)
        if (allocated(error)) goto 100
      end if
      do k = 1, size(mats)
        name = '/analysis/knot_matrix/frame_'//to_str(mats(k)%frame)
        call h5_write(file, name, transpose(mats(k)%k), error)
        if (allocated(error)) goto 100
        call h5_write_attr(file, name, 'closures', int(mat_closures, i8), error)
        if (allocated(error)) goto 100
        call h5_write_attr(file, name, 'min_length', int(min_length, i8), error)
        if (allocated(error)) goto 100
        call h5_write_attr(file, name, 'time', mats(k)%time, error)
        if (allocated(error)) goto 100
      end do
      ! modes and spectra
      call h5_create_group(file, '/analysis/shape', error)
      if (allocated(error)) goto 100
      call h5_write(file, '/analysis/shape/mode', int(shapes%mode, i4), error)
      if (allocated(error)) goto 100
      call h5_write_attr(file, '/analysis/shape', 'case_mode', int(shapes%case_mode, i8), error)
      if (allocated(error)) goto 100
      call h5_create_group(file, '/analysis/spectra', error)
      if (allocated(error)) goto 100
      call h5_write(file, '/analysis/spectra/frequency', shapes%frequency, error)
      if (allocated(error)) goto 100
      call h5_write(file, '/analysis/spectra/power_rg', shapes%power_rg, error)
      if (allocated(error)) goto 100
      call h5_write(file, '/analysis/spectra/power_phi', shapes%power_phi, error)
      if (allocated(error)) goto 100
      call h5_write(file, '/analysis/spectra/power_end_to_end', shapes%power_end_to_end, error)
      if (allocated(error)) goto 100
      call h5_write_attr(file, '/analysis/spectra', 'dominant_period_rg', shapes%period_rg, error)
      if (allocated(error)) goto 100
      call h5_write_attr(file, '/analysis/spectra', 'dominant_period_phi', shapes%period_phi, error)
100   call h5_close_file(file)
    end subroutine write_all

  end subroutine write_analysis

end module kf_knot_store
