!> Small file-system helpers through the C library (POSIX): create directories, check that a
!> directory is writable, remove files, and lock a directory against a second writer.
module kf_fs
  use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char, c_ptr, c_f_pointer, &
    c_funptr, c_intptr_t
  use kf_error, only: error_t, fatal_error
  use kf_strings, only: c_string
  implicit none
  private

  public :: make_directory, check_writable_directory, check_directory_creatable, parent_directory
  public :: file_exists, remove_file, lock_directory, lock_case
  public :: rename_file, move_aside, clear_os_error, os_error_text, ignore_file_size_signal

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
    function c_open(path, flags, mode) bind(c, name='open') result(fd)
      import :: c_char, c_int
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int), value :: flags, mode
      integer(c_int) :: fd
    end function c_open
    function c_flock(fd, operation) bind(c, name='flock') result(rc)
      import :: c_int
      integer(c_int), value :: fd, operation
      integer(c_int) :: rc
    end function c_flock
    function c_rename(old, new) bind(c, name='rename') result(rc)
      import :: c_char, c_int
      character(kind=c_char), intent(in) :: old(*), new(*)
      integer(c_int) :: rc
    end function c_rename
    !> glibc's (and musl's) address of the calling thread's errno.
    function c_errno_location() bind(c, name='__errno_location') result(p)
      import :: c_ptr
      type(c_ptr) :: p
    end function c_errno_location
    function c_signal(signum, handler) bind(c, name='signal') result(old)
      import :: c_int, c_funptr
      integer(c_int), value :: signum
      type(c_funptr), value :: handler
      type(c_funptr) :: old
    end function c_signal
    function c_strerror(errnum) bind(c, name='strerror') result(p)
      import :: c_int, c_ptr
      integer(c_int), value :: errnum
      type(c_ptr) :: p
    end function c_strerror
  end interface

  integer(c_int), parameter :: w_ok = 2, x_ok = 1, f_ok = 0
  ! open(2) and flock(2) constants of Linux (and the BSDs for these values).
  integer(c_int), parameter :: o_rdwr = 2, o_creat = 64, lock_sh = 1, lock_ex = 2, lock_nb = 4

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

  !> Fails unless `path` is a writable directory or could be created as one: its nearest
  !> existing ancestor is a writable directory. Creates nothing (for runs that must not write,
  !> e.g. a dry run); `make_directory` and `check_writable_directory` still decide at the run.
  subroutine check_directory_creatable(path, error)
    character(len=*), intent(in) :: path
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: p, existing
    p = trim(path)
    do while (len(p) > 1)
      if (p(len(p):len(p)) /= '/') exit
      p = p(1:len(p) - 1)
    end do
    existing = p
    do while (c_access(existing//c_null_char, f_ok) /= 0)
      if (existing == '.' .or. existing == '/') exit
      existing = parent_directory(existing)
    end do
    ! "name/." exists only when name is a directory (or a link to one).
    if (c_access(existing//'/.'//c_null_char, f_ok) /= 0) then
      if (existing == p) then
        call fatal_error(error, ''''//p//''' is not a directory')
      else
        call fatal_error(error, 'cannot create directory '''//p//''': '''//existing//''' is not a directory')
      end if
    else if (c_access(existing//c_null_char, ior(w_ok, x_ok)) /= 0) then
      call fatal_error(error, 'directory '''//existing//''' is not writable')
    end if
  end subroutine check_directory_creatable

  !> The directory part of `path`: '.' for a bare name, '/' for a name in the root.
  pure function parent_directory(path) result(dir)
    character(len=*), intent(in) :: path
    character(len=:), allocatable :: dir
    integer :: k
    k = index(trim(path), '/', back=.true.)
    if (k == 0) then
      dir = '.'
    else if (k == 1) then
      dir = '/'
    else
      dir = path(1:k - 1)
    end if
  end function parent_directory

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

  !> Take an exclusive lock on `<dir>/.knotflow.lock` for the rest of the process: a second
  !> run writing into the same directory would otherwise find the case files open (HDF5 file
  !> locking) and take them for corrupt ones. The kernel releases the lock when the process ends,
  !> however it ends (kill -9 included), so a killed run never leaves a stale lock.
  subroutine lock_directory(dir, error)
    character(len=*), intent(in) :: dir
    type(error_t), allocatable, intent(out) :: error
    call take_lock(trim(dir)//'/.knotflow.lock', lock_ex, 'another knotflow run is writing into this directory', &
      error)
  end subroutine lock_directory

  !> The locks of a run of one case (a scene without &sweep, e.g. from knotflow --write-scenes),
  !> held for the rest of the process: `<dir>/.knotflow.lock` shared, so that runs of other
  !> single cases may write into the directory at the same time while a sweep or an analysis of
  !> it (which lock it exclusively) may not, and `<dir>/.knotflow.<case>.lock` exclusive, so
  !> that the same case is not run twice at once.
  subroutine lock_case(dir, case_name, error)
    character(len=*), intent(in) :: dir, case_name
    type(error_t), allocatable, intent(out) :: error
    call take_lock(trim(dir)//'/.knotflow.lock', lock_sh, 'a knotflow sweep or analysis is using this directory', &
      error)
    if (.not. allocated(error)) call take_lock(trim(dir)//'/.knotflow.'//trim(case_name)//'.lock', lock_ex, &
                                               'another knotflow run is computing case '//trim(case_name)//' here', error)
  end subroutine lock_case

  !> flock(2) `operation` (without blocking) on `path`, created if missing; the descriptor
  !> stays open on purpose: closing it would release the lock.
  subroutine take_lock(path, operation, held_by, error)
    character(len=*), intent(in) :: path, held_by
    integer(c_int), intent(in) :: operation
    type(error_t), allocatable, intent(out) :: error
    integer(c_int) :: fd
    fd = c_open(path//c_null_char, ior(o_rdwr, o_creat), int(o'644', c_int))
    if (fd < 0) then
      call fatal_error(error, "cannot create the lock file '"//path//"'")
      return
    end if
    if (c_flock(fd, ior(operation, lock_nb)) /= 0) then
      call fatal_error(error, held_by//' (it holds '''//path//'''): wait for it to end, or choose another output directory')
    end if
  end subroutine take_lock

  !> Ignore SIGXFSZ (Linux: 25), which the kernel sends when a write passes the file size limit
  !> (`ulimit -f`) and which otherwise kills the program (the Fortran runtime even installs a
  !> backtrace handler for it): the write then fails with EFBIG ('File too large') and the
  !> program reports it like a full disk. Called once by programs that write case files.
  subroutine ignore_file_size_signal()
    integer(c_int), parameter :: sigxfsz = 25
    integer(c_intptr_t), parameter :: sig_ign = 1
    type(c_funptr) :: old
    old = c_signal(sigxfsz, transfer(sig_ign, old))
  end subroutine ignore_file_size_signal

  !> Set the C library's errno to 0, before an operation whose failure `os_error_text` explains.
  subroutine clear_os_error()
    integer(c_int), pointer :: e
    call c_f_pointer(c_errno_location(), e)
    e = 0
  end subroutine clear_os_error

  !> The operating system's reason for the last failed system call (strerror(errno), e.g.
  !> 'No space left on device', 'File too large'), '' when errno is 0.
  function os_error_text() result(text)
    character(len=:), allocatable :: text
    integer(c_int), pointer :: e
    text = ''
    call c_f_pointer(c_errno_location(), e)
    if (e == 0) return
    text = c_string(c_strerror(e))
  end function os_error_text

  !> Rename `old` to `new` (rename(2): atomic within one file system, replaces `new`).
  subroutine rename_file(old, new, error)
    character(len=*), intent(in) :: old, new
    type(error_t), allocatable, intent(out) :: error
    call clear_os_error()
    if (c_rename(old//c_null_char, new//c_null_char) /= 0) then
      call fatal_error(error, 'cannot rename '''//old//''' to '''//new//''': '//os_error_text())
    end if
  end subroutine rename_file

  !> Move the file `path` aside, never deleting it: renamed to '<path>.damaged', or
  !> '<path>.damaged.<k>' (k = 2, 3, ...) when that exists. `moved_to` is the new name.
  subroutine move_aside(path, moved_to, error)
    character(len=*), intent(in) :: path
    character(len=:), allocatable, intent(out) :: moved_to
    type(error_t), allocatable, intent(out) :: error
    character(len=16) :: suffix
    integer :: k
    moved_to = path//'.damaged'
    k = 1
    do while (file_exists(moved_to))
      k = k + 1
      write (suffix, '(i0)') k
      moved_to = path//'.damaged.'//trim(suffix)
    end do
    call rename_file(path, moved_to, error)
  end subroutine move_aside

end module kf_fs
