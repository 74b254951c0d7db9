!> The C interface of runs and case files (docs/python-api.md): the cases of a scene file, a run
!> of all of them in this process (kf_scene_run: the checks of the program knotflow, then each
!> case run, resumed or skipped by kf_case_runner), and a case file read back with the library's
!> reader (kf_case_verify: frames, shape observables, status). Strings come as (chars, length)
!> pairs. These calls use HDF5, which they initialise (never close: the process may go on using
!> it); the HDF5 library is not thread-safe, so calls of this module must not run at the same
!> time in several threads (the Python package serialises them). Nothing else is kept between
!> calls.
module kf_capi_run
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_double
  use, intrinsic :: iso_fortran_env, only: output_unit
  use kf_kinds, only: wp, i4
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_capi_status, only: kf_ok, kf_invalid_argument, kf_failed, put_message, from_c_chars
  use kf_h5, only: h5_initialize
  use kf_scene, only: scene_t
  use kf_sweep, only: sweep_t
  use kf_scene_run, only: read_scene_cases, run_scene_cases
  use kf_case_runner, only: case_path, case_reporter_t, case_failed
  use kf_run_segment, only: run_launch_t
  use kf_blas_threads, only: blas_threads_in_use, blas_library
  use kf_signals, only: request_stop, clear_stop
  use kf_case_verify, only: case_file_status, read_frames, read_observables
  implicit none
  private

  !> The longest message of one case kept in knotflow_run_scene's `messages`.
  integer, parameter :: case_message_len = 512

  !> Progress lines of a run: written to standard output when `echo`, else dropped.
  type, extends(case_reporter_t) :: echo_reporter_t
    logical :: echo = .false.
  contains
    procedure :: line => echo_line
  end type echo_reporter_t

  public :: knotflow_scene_cases, knotflow_run_scene, knotflow_case_size, knotflow_read_case

contains

  subroutine echo_line(this, line)
    class(echo_reporter_t), intent(inout) :: this
    character(len=*), intent(in) :: line
    if (.not. this%echo) return
    write (output_unit, '(a)') 'knotflow: '//line
    flush (output_unit)
  end subroutine echo_line

  !> The scene file path[pathlen] read and checked as the program knotflow checks it before it
  !> writes anything (the values, naming file, group, variable and value; the resources; the
  !> models), with &output directory replaced by outdir[outdirlen] when outdirlen > 0. Out:
  !> *ncases, and files[fileslen] the case files' paths, one a line (NUL-terminated); *needed is
  !> the length files needs (kf_invalid_argument when fileslen is shorter). Nothing is written.
  integer(c_int) function knotflow_scene_cases(path, pathlen, outdir, outdirlen, ncases, files, fileslen, needed, &
    msg, msglen) bind(c, name='knotflow_scene_cases') result(status)
    integer(c_int), value, intent(in) :: pathlen, outdirlen, fileslen, msglen
    character(kind=c_char), intent(in) :: path(max(pathlen, 0)), outdir(max(outdirlen, 0))
    integer(c_int), intent(out) :: ncases, needed
    character(kind=c_char), intent(inout) :: files(*), msg(*)
    type(error_t), allocatable :: error
    type(sweep_t) :: sw
    character(len=:), allocatable :: list
    ncases = 0
    needed = 0
    call read_scene(path, pathlen, outdir, outdirlen, sw, error)
    if (allocated(error)) then
      status = kf_invalid_argument
      call put_message(error%message, msg, msglen)
      return
    end if
    list = case_list(sw)
    ncases = sw%n_cases()
    needed = len(list) + 1
    if (fileslen < needed) then
      status = kf_invalid_argument
      call put_message('knotflow_scene_cases: a buffer of '//to_str(len(list) + 1)//' characters is needed', msg, &
                       msglen)
      return
    end if
    call put_message(list, files, fileslen)
    status = kf_ok
  end function knotflow_scene_cases

  !> The length to which knotflow_run_scene cuts each case's message (its buffer needs this plus
  !> one character per case).
  integer(c_int) function knotflow_case_message_length() bind(c, name='knotflow_case_message_length') result(n)
    n = case_message_len
  end function knotflow_case_message_length

  !> Ask a knotflow_run_scene running in another thread to stop as on SIGINT: the running case
  !> after the frame it is computing (written with its checkpoint, status 3 'stopped'), the cases
  !> after it not started. The request lasts until knotflow_clear_stop.
  subroutine knotflow_request_stop() bind(c, name='knotflow_request_stop')
    call request_stop()
  end subroutine knotflow_request_stop

  !> Forget a stop asked for by knotflow_request_stop (call it before a run).
  subroutine knotflow_clear_stop() bind(c, name='knotflow_clear_stop')
    call clear_stop()
  end subroutine knotflow_clear_stop

  !> Run every case of the scene file path[pathlen] (outdir as in knotflow_scene_cases) in this
  !> process, as `knotflow SCENE` on one rank does: the scene checked (a bad scene: nothing is
  !> written), the output directory made and locked for the run, case files already there
  !> checked (refused when they hold another scene), then each case run, resumed from its
  !> checkpoint, or skipped when finished. Progress lines go to standard output when echo /= 0.
  !> ncases must be the number knotflow_scene_cases gives. Out: statuses[ncases] (0 finished,
  !> 1 failed, 2 skipped: already finished, 3 stopped) and messages[messageslen] (each case's
  !> message, one a line, each cut to 512 characters). Returns kf_failed when a case failed
  !> (the message names the first), kf_invalid_argument when nothing ran.
  integer(c_int) function knotflow_run_scene(path, pathlen, outdir, outdirlen, echo, ncases, statuses, messages, &
    messageslen, msg, msglen) bind(c, name='knotflow_run_scene') result(status)
    integer(c_int), value, intent(in) :: pathlen, outdirlen, echo, ncases, messageslen, msglen
    character(kind=c_char), intent(in) :: path(max(pathlen, 0)), outdir(max(outdirlen, 0))
    integer(c_int), intent(out) :: statuses(max(ncases, 0))
    character(kind=c_char), intent(inout) :: messages(*), msg(*)
    type(error_t), allocatable :: error
    type(sweep_t) :: sw
    type(echo_reporter_t) :: report
    type(run_launch_t) :: launch
    type(scene_t) :: sc
    integer, allocatable :: outcome(:)
    character(len=case_message_len), allocatable :: texts(:)
    character(len=:), allocatable :: joined, name
    integer :: k
    statuses = -1
    status = kf_invalid_argument
    call put_message('', messages, messageslen)
    call read_scene(path, pathlen, outdir, outdirlen, sw, error)
    if (.not. allocated(error) .and. ncases /= sw%n_cases()) call fatal_error(error, 'knotflow_run_scene: ncases = '// &
      to_str(int(ncases))//', the scene has '//to_str(sw%n_cases())//' case(s)')
    if (allocated(error)) then
      call put_message(error%message, msg, msglen)
      return
    end if
    report%echo = echo /= 0
    launch%ranks = 1
    launch%threads = blas_threads_in_use()
    launch%blas = blas_library()
    allocate (outcome(ncases), texts(ncases))
    call run_scene_cases(from_c_chars(path, pathlen), sw, report, launch, outcome, texts, error)
    if (allocated(error)) then
      call put_message(error%message, msg, msglen)
      return
    end if
    statuses = outcome
    joined = ''
    do k = 1, ncases
      joined = joined//trim(texts(k))//merge(new_line('a'), ' ', k < ncases)
    end do
    call put_message(trim(joined), messages, messageslen)
    status = kf_ok
    do k = 1, ncases
      if (outcome(k) /= case_failed) cycle
      call sw%case_scene(k, sc, name)
      status = kf_failed
      call put_message('case '//name//' failed ('//case_path(sc)//'): '//trim(texts(k)), msg, msglen)
      exit
    end do
  end function knotflow_run_scene

  !> The number of complete frames and of beads of the case file path[pathlen] (as
  !> knotflow_read_case reads it); a missing or unreadable file is refused with its reason.
  integer(c_int) function knotflow_case_size(path, pathlen, nframes, nbeads, msg, msglen) &
    bind(c, name='knotflow_case_size') result(status)
    integer(c_int), value, intent(in) :: pathlen, msglen
    character(kind=c_char), intent(in) :: path(max(pathlen, 0))
    integer(c_int), intent(out) :: nframes, nbeads
    character(kind=c_char), intent(inout) :: msg(*)
    type(error_t), allocatable :: error
    real(wp), allocatable :: t(:), r(:, :, :)
    character(len=:), allocatable :: state
    nframes = 0
    nbeads = 0
    call open_case(from_c_chars(path, max(pathlen, 0)), state, t, r, error)
    if (allocated(error)) then
      status = kf_invalid_argument
      call put_message(error%message, msg, msglen)
      return
    end if
    nframes = size(t)
    nbeads = size(r, 2)
    status = kf_ok
  end function knotflow_case_size

  !> Read the case file path[pathlen] with the library's reader: t[nframes] the frame times,
  !> r[3 nbeads nframes] the positions (frame-major: r[3 (nbeads f + i) + k]), observables
  !> [6 nframes] (six rows of nframes: rg, a, b, c, theta, phi), close_pairs[nframes] and state
  !> [statelen] the file's status ('finished', 'running', 'failed: ...'). nframes and nbeads
  !> must be knotflow_case_size's (else the file changed: refused).
  integer(c_int) function knotflow_read_case(path, pathlen, nframes, nbeads, t, r, observables, close_pairs, state, &
    statelen, msg, msglen) bind(c, name='knotflow_read_case') result(status)
    integer(c_int), value, intent(in) :: pathlen, nframes, nbeads, statelen, msglen
    character(kind=c_char), intent(in) :: path(max(pathlen, 0))
    real(c_double), intent(out) :: t(max(nframes, 0)), r(3, max(nbeads, 0), max(nframes, 0))
    real(c_double), intent(out) :: observables(max(nframes, 0), 6)
    integer(c_int), intent(out) :: close_pairs(max(nframes, 0))
    character(kind=c_char), intent(inout) :: state(*), msg(*)
    type(error_t), allocatable :: error
    real(wp), allocatable :: tf(:), rf(:, :, :), values(:, :)
    integer(i4), allocatable :: pairs(:)
    character(len=:), allocatable :: file_state, p
    t = 0.0_c_double
    r = 0.0_c_double
    observables = 0.0_c_double
    close_pairs = 0
    call put_message('', state, statelen)
    status = kf_invalid_argument
    p = from_c_chars(path, max(pathlen, 0))
    call open_case(p, file_state, tf, rf, error)
    if (.not. allocated(error)) then
      if (size(tf) /= nframes .or. size(rf, 2) /= nbeads) call fatal_error(error, "case file '"//p//"': holds "// &
        to_str(size(tf))//' frame(s) of '//to_str(size(rf, 2))//' beads, not the '//to_str(int(nframes))// &
        ' of '//to_str(int(nbeads))//' asked for (did it change?)')
    end if
    if (.not. allocated(error)) call read_observables(p, size(tf), values, pairs, error)
    if (allocated(error)) then
      call put_message(error%message, msg, msglen)
      return
    end if
    t = tf
    r = rf
    observables = values
    close_pairs = pairs
    call put_message(file_state, state, statelen)
    status = kf_ok
  end function knotflow_read_case

  !> The scene of path[pathlen], with outdir[outdirlen] as its output directory when given.
  subroutine read_scene(path, pathlen, outdir, outdirlen, sw, error)
    integer(c_int), intent(in) :: pathlen, outdirlen
    character(kind=c_char), intent(in) :: path(max(pathlen, 0)), outdir(max(outdirlen, 0))
    type(sweep_t), intent(out) :: sw
    type(error_t), allocatable, intent(out) :: error
    call h5_initialize(error)
    if (allocated(error)) return
    if (pathlen < 1) then
      call fatal_error(error, 'no scene file given (an empty path)')
      return
    end if
    call read_scene_cases(from_c_chars(path, pathlen), from_c_chars(outdir, max(outdirlen, 0)), sw, error)
  end subroutine read_scene

  !> The case files of the sweep's cases, one a line.
  function case_list(sw) result(list)
    type(sweep_t), intent(in) :: sw
    character(len=:), allocatable :: list
    type(scene_t) :: sc
    character(len=:), allocatable :: name
    integer :: k
    list = ''
    do k = 1, sw%n_cases()
      call sw%case_scene(k, sc, name)
      list = list//case_path(sc)//merge(new_line('a'), ' ', k < sw%n_cases())
    end do
    list = trim(list)
  end function case_list

  !> The status, times and positions of the case file `path`; a missing, damaged or non-case
  !> file is refused, naming it.
  subroutine open_case(path, state, t, r, error)
    character(len=*), intent(in) :: path
    character(len=:), allocatable, intent(out) :: state
    real(wp), allocatable, intent(out) :: t(:), r(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    call h5_initialize(error)
    if (allocated(error)) return
    if (len(path) == 0) then
      call fatal_error(error, 'no case file given (an empty path)')
      return
    end if
    call case_file_status(path, state, error)
    if (allocated(error)) return
    if (state == 'missing') then
      call fatal_error(error, "case file '"//path//"': not found")
    else if (state == 'not a regular file' .or. index(state, 'corrupt: ') == 1) then
      call fatal_error(error, "case file '"//path//"': "//state)
    else
      call read_frames(path, t, r, error)
    end if
  end subroutine open_case

end module kf_capi_run
