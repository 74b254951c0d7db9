!> Small file-system helpers through the C library (POSIX): create directories, check that a
!> directory is writable, remove files.
module kf_fs
  use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char
  use kf_error, only: error_t, fatal_error
  implicit none
  private

  public :: make_directory, check_writable_directory, file_exists, remove_file

  interface
    function c_mkdir(path, mode) bind(c, name='mkdir') result(rc)
      import :: c_char, c_int
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int), value :: mode
      integer(c_int) :: rc
    end function c_mkdir
    function c_access(path, mode) bind(c, name='access') result(rc)
      import :: c_char, c_int
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int), value :: mode
      integer(c_int) :: rc
    end function c_access
  end interface

  integer(c_int), parameter :: w_ok = 2, x_ok = 1, f_ok = 0

contains

  !> Create `path` and its parents (like mkdir -p). Existing directories are fine.
  subroutine make_directory(path, error)
    character(len=*), intent(in) :: path
    type(error_t), allocatable, intent(out) :: error
    integer :: k, rc
    character(len=:), allocatable :: p
    p = trim(path)
    do k = 2, len(p) + 1
      if (k <= len(p)) then
        if (p(k:k) /= '/') cycle
      end if
      rc = c_mkdir(p(1:k - 1)//c_null_char, int(o'755', c_int))
    end do
    if (c_access(p//c_null_char, f_ok) /= 0) then
      call fatal_error(error, 'cannot create directory '''//p//'''')
    end if
  end subroutine make_directory

  !> Fails unless `path` is an existing directory where files can be created.
  subroutine check_writable_directory(path, error)
    character(len=*), intent(in) :: path
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: probe
    integer :: unit, ios
    if (c_access(trim(path)//c_null_char, ior(w_ok, x_ok)) /= 0) then
      call fatal_error(error, 'directory '''//trim(path)//''' is not writable')
      return
    end if
    probe = trim(path)//'/.knotflow_write_probe'
    open (newunit=unit, file=probe, status='replace', action='write', iostat=ios)
    if (ios /= 0) then
      call fatal_error(error, 'directory '''//trim(path)//''' is not writable')
      return
    end if
    close (unit, status='delete')
  end subroutine check_writable_directory

  !> Does a file (or directory) exist at `path`?
  logical function file_exists(path)
    character(len=*), intent(in) :: path
    file_exists = c_access(trim(path)//c_null_char, f_ok) == 0
  end function file_exists

  !> Remove a file if it exists.
  subroutine remove_file(path)
    character(len=*), intent(in) :: path
    integer :: unit, ios
    open (newunit=unit, file=trim(path), status='old', iostat=ios)
    if (ios == 0) close (unit, status='delete')
  end subroutine remove_file

end module kf_fs
