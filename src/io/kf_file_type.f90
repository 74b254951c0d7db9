!> The type and size of a file before it is opened (Linux statx, whose record has the same layout
!> on every architecture): readers refuse anything but a regular file (a FIFO would block the
!> open or the read forever, a device such as /dev/zero never ends, a directory is no input).
module kf_file_type
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char, c_int8_t, c_int16_t, &
    c_int64_t
  use kf_kinds, only: i8
  use kf_error, only: error_t, fatal_error
  implicit none
  private

  public :: check_regular_file, is_symbolic_link

  interface
    !> int statx(int dirfd, const char *path, int flags, unsigned mask, struct statx *buf)
    function c_statx(dirfd, path, flags, mask, buf) bind(c, name='statx') result(rc)
      import :: c_int, c_char, c_int8_t
      integer(c_int), value :: dirfd, flags, mask
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int8_t), intent(out) :: buf(*)
      integer(c_int) :: rc
    end function c_statx
  end interface

  integer(c_int), parameter :: at_fdcwd = -100, at_symlink_nofollow = 256
  integer(c_int), parameter :: statx_type = 1, statx_size = 512
  !> struct statx: 256 bytes; stx_mode (16 bits) at byte 28, stx_size (64 bits) at byte 40.
  integer, parameter :: statx_bytes = 256, mode_offset = 28, size_offset = 40
  integer, parameter :: s_ifmt = int(o'170000'), s_ifreg = int(o'100000'), &
    s_ifdir = int(o'040000'), s_ifchr = int(o'020000'), s_ifblk = int(o'060000'), &
    s_ififo = int(o'010000'), s_ifsock = int(o'140000')

contains

  !> An error unless `path` (symbolic links followed) is a regular file; `what` names the input
  !> in the message ("coordinate file", "scene", "case file"). `bytes` is its size.
  !> A file that does not exist is not refused here (the caller's open says so).
  subroutine check_regular_file(path, what, error, bytes)
    character(len=*), intent(in) :: path, what
    type(error_t), allocatable, intent(out) :: error
    integer(i8), intent(out), optional :: bytes
    integer(c_int8_t) :: buf(statx_bytes)
    integer(c_int16_t) :: mode16
    integer(c_int64_t) :: size64
    integer :: mode, kind
    character(len=:), allocatable :: type_name

    if (present(bytes)) bytes = -1_i8
    buf = 0_c_int8_t
    if (c_statx(at_fdcwd, trim(path)//c_null_char, 0_c_int, ior(statx_type, statx_size), buf) /= 0) &
      return
    mode16 = transfer(buf(mode_offset + 1:mode_offset + 2), mode16)
    size64 = transfer(buf(size_offset + 1:size_offset + 8), size64)
    mode = iand(int(mode16), 65535)
    kind = iand(mode, s_ifmt)
    if (present(bytes)) bytes = int(size64, i8)
    if (kind == s_ifreg) return
    select case (kind)
    case (s_ifdir)
      type_name = 'a directory'
    case (s_ififo)
      type_name = 'a FIFO (named pipe)'
    case (s_ifchr)
      type_name = 'a character device'
    case (s_ifblk)
      type_name = 'a block device'
    case (s_ifsock)
      type_name = 'a socket'
    case default
      type_name = 'not a regular file'
    end select
    call fatal_error(error, what//" '"//trim(path)//"' is "//type_name// &
      ": only a regular file is read")
  end subroutine check_regular_file

  !> Whether `path` itself is a symbolic link (statx with AT_SYMLINK_NOFOLLOW; false when it
  !> does not exist).
  logical function is_symbolic_link(path)
    character(len=*), intent(in) :: path
    integer(c_int8_t) :: buf(statx_bytes)
    integer(c_int16_t) :: mode16
    integer, parameter :: s_iflnk = int(o'120000')
    is_symbolic_link = .false.
    buf = 0_c_int8_t
    if (c_statx(at_fdcwd, trim(path)//c_null_char, at_symlink_nofollow, statx_type, buf) /= 0) return
    mode16 = transfer(buf(mode_offset + 1:mode_offset + 2), mode16)
    is_symbolic_link = iand(iand(int(mode16), 65535), s_ifmt) == s_iflnk
  end function is_symbolic_link

end module kf_file_type
