!> A stepper state file (the &chain stepper_state of a scene): the state of a run's time stepper
!> at one frame, taken from the newest checkpoint of its case file, so that another run can go
!> on from that frame exactly as the first one's own resume would (docs/case-file.md, "A
!> stepper state file"). knotflow-campaign plan writes it when it continues a case from the
!> case ledger; knotflow only reads it. Layout (HDF5):
!>   /time       float64 scalar: the model time of the state on the clock of the run it comes
!>               from (the clock of the times the method keeps, e.g. dopri45's FSAL stage)
!>   /positions  float64 (3, N) in Fortran order: the beads at that time
!>   /stepper/reals float64 (M,), /stepper/ints int64 (K,), attribute `name` of /stepper: the
!>               stepper's state as a checkpoint holds it (kf_stepper get_state)
module kf_stepper_state_file
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp
  use kf_error, only: error_t, fatal_error
  use kf_h5, only: h5_file_t, h5_open_file, h5_close_file, h5_exists, h5_attr_exists, h5_read
  use kf_case_checkpoint, only: stepper_checkpoint_t, read_stepper
  use kf_file_type, only: check_regular_file
  implicit none
  private

  public :: read_stepper_state

  !> The content of a stepper state file.
  type, public :: stepper_state_t
    real(wp) :: t = 0.0_wp
    real(wp), allocatable :: r(:, :)
    type(stepper_checkpoint_t) :: stepper
  end type stepper_state_t

contains

  !> Read the stepper state file `path`; the error says what is missing or wrong (without the
  !> file's name, which the caller adds with the scene variable that names it).
  subroutine read_stepper_state(path, st, error)
    character(len=*), intent(in) :: path
    type(stepper_state_t), intent(out) :: st
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t) :: file
    type(error_t), allocatable :: close_error
    character(len=*), parameter :: parts(4) = [character(len=14) :: '/time', '/positions', '/stepper/reals', &
                                               '/stepper/ints']
    integer :: k
    call check_regular_file(path, 'stepper state file', error)
    if (allocated(error)) return
    call h5_open_file(file, path, .false., error)
    if (allocated(error)) return
    do k = 1, size(parts)
      if (.not. h5_exists(file, trim(parts(k)))) then
        call fatal_error(error, 'no dataset '//trim(parts(k))//' (a stepper state file holds /time, /positions '// &
          'and /stepper)')
        exit
      end if
    end do
    if (.not. allocated(error)) then
      if (.not. h5_attr_exists(file, '/stepper', 'name')) call fatal_error(error, 'no attribute name of /stepper')
    end if
    if (.not. allocated(error)) call h5_read(file, '/time', st%t, error)
    if (.not. allocated(error)) call h5_read(file, '/positions', st%r, error)
    if (.not. allocated(error)) call read_stepper(file, '/stepper', st%stepper, error)
    call h5_close_file(file, close_error)
    if (allocated(error)) return
    if (allocated(close_error)) then
      call move_alloc(close_error, error)
      return
    end if
    if (.not. (ieee_is_finite(st%t) .and. st%t >= 0.0_wp)) then
      call fatal_error(error, '/time is not a finite time >= 0')
    else if (size(st%r, 1) /= 3) then
      call fatal_error(error, '/positions does not have 3 rows (x, y, z)')
    else if (.not. all(ieee_is_finite(st%r))) then
      call fatal_error(error, '/positions holds non-finite values')
    end if
  end subroutine read_stepper_state

end module kf_stepper_state_file
