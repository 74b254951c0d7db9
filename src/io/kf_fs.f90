!> Small file-system helpers through the C library (POSIX): create directories, check that a
!> directory is writable, remove files, lock a directory against a second writer, write a text
!> file whole or not at all (never through a planted symbolic link), and tell whether another
!> process holds a file open (HDF5's file lock) or its mode forbids writing it.
module kf_fs
  use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char, c_ptr, c_f_pointer, &
    c_funptr, c_intptr_t, c_size_t
  use kf_error, only: error_t, fatal_error
  use kf_strings, only: c_string, to_str
  implicit none
  private

  public :: make_directory, check_writable_directory, check_directory_creatable, parent_directory
  public :: file_exists, remove_file, lock_directory, lock_case, release_locks
  public :: rename_file, move_aside, clear_os_error, os_error_text, ignore_file_size_signal
  public :: write_file_atomic, file_in_use, file_not_writable, copy_file_exclusive, replace_file

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
    function c_write(fd, buf, count) bind(c, name='write') result(n)
      import :: c_int, c_char, c_size_t, c_intptr_t
      integer(c_int), value :: fd
      character(kind=c_char), intent(in) :: buf(*)
      integer(c_size_t), value :: count
      integer(c_intptr_t) :: n
    end function c_write
    function c_read(fd, buf, count) bind(c, name='read') result(n)
      import :: c_int, c_char, c_size_t, c_intptr_t
      integer(c_int), value :: fd
      character(kind=c_char), intent(out) :: buf(*)
      integer(c_size_t), value :: count
      integer(c_intptr_t) :: n
    end function c_read
    function c_fsync(fd) bind(c, name='fsync') result(rc)
      import :: c_int
      integer(c_int), value :: fd
      integer(c_int) :: rc
    end function c_fsync
    function c_close(fd) bind(c, name='close') result(rc)
      import :: c_int
      integer(c_int), value :: fd
      integer(c_int) :: rc
    end function c_close
    function c_unlink(path) bind(c, name='unlink') result(rc)
      import :: c_char, c_int
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int) :: rc
    end function c_unlink
    function c_getpid() bind(c, name='getpid') result(pid)
      import :: c_int
      integer(c_int) :: pid
    end function c_getpid
  end interface

  integer(c_int), parameter :: w_ok = 2, x_ok = 1, f_ok = 0
  ! open(2) and flock(2) constants of Linux (the same on every Linux architecture knotflow
  ! builds on, and in the BSDs for these values). O_CREAT with O_EXCL never opens an existing
  ! file and never follows a symbolic link, whatever it points to.
  integer(c_int), parameter :: o_rdonly = 0, o_wronly = 1, o_rdwr = 2, o_creat = 64, o_excl = 128, &
    o_nonblock = 2048, lock_sh = 1, lock_ex = 2, lock_nb = 4
  !> errno values of Linux: interrupted call, file exists, operation would block.
  integer(c_int), parameter :: eintr = 4, eexist = 17, ewouldblock = 11
  !> Tries at a unique temporary name before giving up (another process would have to create
  !> that many names of this process id first).
  integer, parameter :: max_temp_tries = 1000
  !> Longest part of the target's name kept in a temporary name (NAME_MAX is 255 bytes).
  integer, parameter :: temp_stem_len = 120

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
    integer(c_int) :: fd, rc
    if (c_access(trim(path)//c_null_char, ior(w_ok, x_ok)) /= 0) then
      call fatal_error(error, 'directory '''//trim(path)//''' is not writable')
      return
    end if
    ! a probe of a new, unique name (an existing file or link of that name is never opened)
    call create_temporary(trim(path)//'/.knotflow_write_probe', probe, fd, error)
    if (allocated(error)) then
      error%message = 'directory '''//trim(path)//''' is not writable: '//error%message
      return
    end if
    rc = c_close(fd)
    rc = c_unlink(probe//c_null_char)
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

  !> Remove a file if it exists (unlink(2): a symbolic link is removed, not what it points to).
  subroutine remove_file(path)
    character(len=*), intent(in) :: path
    integer(c_int) :: rc
    rc = c_unlink(trim(path)//c_null_char)
  end subroutine remove_file

  !> Create a new file '<dir>/.<name>.<pid>-<k>.tmp' for writing, exclusively (O_CREAT|O_EXCL:
  !> never an existing file, never through a symbolic link), beside `target` ('<dir>/<name>'):
  !> `tmp` is its name, `fd` its descriptor (mode 0666 less the umask).
  subroutine create_temporary(target, tmp, fd, error)
    character(len=*), intent(in) :: target
    character(len=:), allocatable, intent(out) :: tmp
    integer(c_int), intent(out) :: fd
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: dir, stem
    integer :: k, slash
    integer(c_int), pointer :: e
    slash = index(target, '/', back=.true.)
    dir = parent_directory(target)
    stem = target(slash + 1:)
    if (len(stem) > temp_stem_len) stem = stem(1:temp_stem_len)
    call c_f_pointer(c_errno_location(), e)
    do k = 1, max_temp_tries
      tmp = dir//'/.'//stem//'.'//to_str(int(c_getpid()))//'-'//to_str(k)//'.tmp'
      if (dir == '/') tmp = tmp(2:)
      call clear_os_error()
      fd = c_open(tmp//c_null_char, ior(o_wronly, ior(o_creat, o_excl)), int(o'666', c_int))
      if (fd >= 0) return
      if (e /= eexist) exit
    end do
    call fatal_error(error, "cannot create a temporary file beside '"//target//"' ("//tmp//'): '// &
      os_error_text())
  end subroutine create_temporary

  !> Write `text` as the whole content of the file `path`, so that the write cannot be
  !> redirected and leaves `path` whole or as it was: `text` goes into a new temporary file
  !> created exclusively in the directory of `path` (`create_temporary`), every write(2), the
  !> fsync(2) and the close(2) are checked, and only then is it renamed over `path` (a symbolic
  !> link at `path` is replaced by the file; what it pointed to is not touched). On failure the
  !> temporary is removed, `path` is left as it was and `error` names the path and the
  !> operating system's reason (e.g. 'No space left on device').
  subroutine write_file_atomic(path, text, error)
    character(len=*), intent(in) :: path, text
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: tmp, reason
    integer(c_int) :: fd, rc
    integer(c_intptr_t) :: n
    integer :: pos, chunk
    integer(c_int), pointer :: e
    call create_temporary(path, tmp, fd, error)
    if (allocated(error)) return
    call c_f_pointer(c_errno_location(), e)
    reason = ''
    pos = 1
    do while (pos <= len(text))
      chunk = min(len(text) - pos + 1, 1048576)
      call clear_os_error()
      n = c_write(fd, text(pos:pos + chunk - 1), int(chunk, c_size_t))
      if (n < 0 .and. e == eintr) cycle
      if (n <= 0) then
        reason = os_error_text()
        if (len(reason) == 0) reason = 'nothing written'
        exit
      end if
      pos = pos + int(n)
    end do
    if (len(reason) == 0) then
      call clear_os_error()
      if (c_fsync(fd) /= 0) reason = os_error_text()
    end if
    call clear_os_error()
    rc = c_close(fd)
    if (rc /= 0 .and. len(reason) == 0) reason = os_error_text()
    if (len(reason) == 0) then
      call clear_os_error()
      if (c_rename(tmp//c_null_char, path//c_null_char) /= 0) reason = os_error_text()
    end if
    if (len(reason) > 0) then
      rc = c_unlink(tmp//c_null_char)
      call fatal_error(error, "cannot write '"//path//"': "//reason)
      return
    end if
    call sync_directory(parent_directory(path))
  end subroutine write_file_atomic

  !> Copy the file `source` to `copy`, a new file created exclusively (an old file or link of
  !> that name is removed first, never followed or written through), with every read, write,
  !> the fsync and the close checked. For a file that is changed as a copy and then put in
  !> place by `replace_file`, so that a kill or a failed write never touches `source`. On
  !> failure `copy` is removed and `error` names the path and the operating system's reason.
  subroutine copy_file_exclusive(source, copy, error)
    character(len=*), intent(in) :: source, copy
    type(error_t), allocatable, intent(out) :: error
    integer, parameter :: block = 1048576
    character(kind=c_char, len=:), allocatable :: buf
    character(len=:), allocatable :: reason
    integer(c_int) :: in, out, rc
    integer(c_intptr_t) :: got, n, done
    integer(c_int), pointer :: e
    allocate (character(kind=c_char, len=block) :: buf)
    call c_f_pointer(c_errno_location(), e)
    call clear_os_error()
    in = c_open(source//c_null_char, ior(o_rdonly, o_nonblock), 0_c_int)
    if (in < 0) then
      call fatal_error(error, "cannot read '"//source//"': "//os_error_text())
      return
    end if
    rc = c_unlink(copy//c_null_char)
    call clear_os_error()
    out = c_open(copy//c_null_char, ior(o_wronly, ior(o_creat, o_excl)), int(o'666', c_int))
    if (out < 0) then
      call fatal_error(error, "cannot create '"//copy//"': "//os_error_text())
      rc = c_close(in)
      return
    end if
    reason = ''
    do
      call clear_os_error()
      got = c_read(in, buf, int(block, c_size_t))
      if (got < 0 .and. e == eintr) cycle
      if (got < 0) reason = "cannot read '"//source//"': "//os_error_text()
      if (got <= 0) exit
      done = 0
      do while (done < got)
        call clear_os_error()
        n = c_write(out, buf(done + 1:got), int(got - done, c_size_t))
        if (n < 0 .and. e == eintr) cycle
        if (n <= 0) then
          reason = "cannot write '"//copy//"': "//os_error_text()
          exit
        end if
        done = done + n
      end do
      if (len(reason) > 0) exit
    end do
    rc = c_close(in)
    if (len(reason) == 0) then
      call clear_os_error()
      if (c_fsync(out) /= 0) reason = "cannot write '"//copy//"': "//os_error_text()
    end if
    call clear_os_error()
    rc = c_close(out)
    if (rc /= 0 .and. len(reason) == 0) reason = "cannot write '"//copy//"': "//os_error_text()
    if (len(reason) > 0) then
      rc = c_unlink(copy//c_null_char)
      call fatal_error(error, reason)
    end if
  end subroutine copy_file_exclusive

  !> Put the complete file `tmp` (closed by its writer) in the place of `path`: fsync(2) it,
  !> then rename(2) it over `path` (atomic: `path` is the old file or the new one, whatever
  !> moment a kill comes). On failure `tmp` is removed and `path` is left as it was.
  subroutine replace_file(tmp, path, error)
    character(len=*), intent(in) :: tmp, path
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: reason
    integer(c_int) :: fd, rc
    reason = ''
    call clear_os_error()
    fd = c_open(tmp//c_null_char, o_rdonly, 0_c_int)
    if (fd < 0) then
      reason = os_error_text()
    else
      if (c_fsync(fd) /= 0) reason = os_error_text()
      rc = c_close(fd)
    end if
    if (len(reason) == 0) then
      call clear_os_error()
      if (c_rename(tmp//c_null_char, path//c_null_char) /= 0) reason = os_error_text()
    end if
    if (len(reason) > 0) then
      rc = c_unlink(tmp//c_null_char)
      call fatal_error(error, "cannot replace '"//path//"' by its new version '"//tmp//"': "//reason)
      return
    end if
    call sync_directory(parent_directory(path))
  end subroutine replace_file

  !> fsync(2) a directory, so that a rename in it lasts a crash (best effort: some file systems
  !> refuse to sync a directory, and the file itself is synced already).
  subroutine sync_directory(dir)
    character(len=*), intent(in) :: dir
    integer(c_int) :: fd, rc
    fd = c_open(dir//c_null_char, o_rdonly, 0_c_int)
    if (fd < 0) return
    rc = c_fsync(fd)
    rc = c_close(fd)
  end subroutine sync_directory

  !> Whether another process holds the file `path` open with a lock (HDF5 locks every file it
  !> opens: shared for reading, exclusive for writing; h5py, HDFView and ParaView hold it while
  !> the file is open in them): with `for_writing`, any lock of another process counts (a writer
  !> needs the file alone), else only an exclusive one (a reader can share). `in_use` is false
  !> for a file that cannot be opened or locked for another reason (the caller's open says why).
  logical function file_in_use(path, for_writing) result(in_use)
    character(len=*), intent(in) :: path
    logical, intent(in) :: for_writing
    integer(c_int) :: fd, rc
    integer(c_int), pointer :: e
    in_use = .false.
    ! O_NONBLOCK: a FIFO of that name must not block the probe
    fd = c_open(trim(path)//c_null_char, ior(o_rdonly, o_nonblock), 0_c_int)
    if (fd < 0) return
    call c_f_pointer(c_errno_location(), e)
    call clear_os_error()
    rc = c_flock(fd, ior(merge(lock_ex, lock_sh, for_writing), lock_nb))
    in_use = rc /= 0 .and. e == ewouldblock
    rc = c_close(fd)   ! releases the probe's own lock
  end function file_in_use

  !> The operating system's reason why the existing file `path` cannot be opened for writing
  !> by this process because of its mode or its file system (e.g. 'Permission denied',
  !> 'Read-only file system'), '' when it can.
  function file_not_writable(path) result(reason)
    character(len=*), intent(in) :: path
    character(len=:), allocatable :: reason
    reason = ''
    call clear_os_error()
    if (c_access(trim(path)//c_null_char, w_ok) /= 0) reason = os_error_text()
  end function file_not_writable

  !> Take an exclusive lock on `<dir>/.knotflow.lock` for the rest of the process: a second
  !> run writing into the same directory would otherwise find the case files open (HDF5 file
  !> locking) and take them for corrupt ones. The kernel releases the lock when the process ends,
  !> however it ends (kill -9 included), so a killed run never leaves a stale lock.
  !> `fds` (optional) receives the lock's descriptor (and -1), for `release_locks` by a caller
  !> that goes on after the run (the C interface: a Python process runs several scenes).
  subroutine lock_directory(dir, error, fds)
    character(len=*), intent(in) :: dir
    type(error_t), allocatable, intent(out) :: error
    integer(c_int), intent(out), optional :: fds(2)
    integer(c_int) :: fd
    call take_lock(trim(dir)//'/.knotflow.lock', lock_ex, 'another knotflow run is writing into this directory', &
      error, fd)
    if (present(fds)) fds = [fd, -1_c_int]
  end subroutine lock_directory

  !> The locks of a run of one case (a scene without &sweep, e.g. from knotflow --write-scenes),
  !> held for the rest of the process: `<dir>/.knotflow.lock` shared, so that runs of other
  !> single cases may write into the directory at the same time while a sweep or an analysis of
  !> it (which lock it exclusively) may not, and `<dir>/.knotflow.<case>.lock` exclusive, so
  !> that the same case is not run twice at once.
  !> `fds` (optional) receives the two descriptors (-1 where none was opened), for `release_locks`.
  subroutine lock_case(dir, case_name, error, fds)
    character(len=*), intent(in) :: dir, case_name
    type(error_t), allocatable, intent(out) :: error
    integer(c_int), intent(out), optional :: fds(2)
    integer(c_int) :: fd(2)
    fd = -1
    call take_lock(trim(dir)//'/.knotflow.lock', lock_sh, 'a knotflow sweep or analysis is using this directory', &
      error, fd(1))
    if (.not. allocated(error)) call take_lock(trim(dir)//'/.knotflow.'//trim(case_name)//'.lock', lock_ex, &
                                               'another knotflow run is computing case '//trim(case_name)//' here', &
                                               error, fd(2))
    if (present(fds)) fds = fd
  end subroutine lock_case

  !> Release the locks of `lock_directory` or `lock_case` (close their descriptors; -1 is skipped).
  subroutine release_locks(fds)
    integer(c_int), intent(in) :: fds(2)
    integer(c_int) :: rc
    integer :: k
    do k = 1, 2
      if (fds(k) >= 0) rc = c_close(fds(k))
    end do
  end subroutine release_locks

  !> flock(2) `operation` (without blocking) on `path`, created if missing; the descriptor
  !> stays open on purpose: closing it would release the lock.
  !> `fd` is the descriptor holding the lock (-1 when none is held: it is closed on failure).
  subroutine take_lock(path, operation, held_by, error, fd)
    character(len=*), intent(in) :: path, held_by
    integer(c_int), intent(in) :: operation
    type(error_t), allocatable, intent(out) :: error
    integer(c_int), intent(out) :: fd
    integer(c_int) :: rc
    integer :: try
    ! An existing lock file is opened as it is; a missing one is created exclusively
    ! (O_CREAT|O_EXCL), so a dangling link planted under its name never creates a file elsewhere.
    fd = -1
    do try = 1, 3
      fd = c_open(path//c_null_char, o_rdwr, 0_c_int)
      if (fd >= 0) exit
      fd = c_open(path//c_null_char, ior(o_rdwr, ior(o_creat, o_excl)), int(o'644', c_int))
      if (fd >= 0) exit
    end do
    if (fd < 0) then
      call fatal_error(error, "cannot create the lock file '"//path//"'")
      return
    end if
    if (c_flock(fd, ior(operation, lock_nb)) /= 0) then
      call fatal_error(error, held_by//' (it holds '''//path//'''): wait for it to end, or choose another output directory')
      rc = c_close(fd)
      fd = -1
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
