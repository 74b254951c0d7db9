!> Program knotflow: run a scene or a sweep of scenes over MPI ranks.
!>   mpirun -n P knotflow SCENE.nml [--dry-run | --write-scenes DIR]
!>   knotflow --scene-reference      (every scene variable as Markdown: docs/scenes.md)
!> Every rank computes; cases are handed out dynamically. Built without MPI
!> (-DKNOTFLOW_WITH_MPI=OFF), `knotflow SCENE.nml` runs every case in one process. Finished
!> cases are skipped and interrupted ones resume from their checkpoint when the same command is
!> run again.
!> Exit status: 0 all cases finished, 2 bad input (nothing written), 3 some cases failed, 75
!> stopped by SIGTERM or SIGINT (each running case at its last written frame: run the same
!> command again; kf_signals, docs/robustness.md).
program knotflow
  use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
  use kf_strings, only: to_str
  use kf_memory, only: keep_freed_heap
  use kf_error, only: error_t
  use kf_scene, only: scene_t
  use kf_scene_items, only: scene_text
  use kf_sweep, only: sweep_t, read_sweep
  use kf_fs, only: make_directory, check_writable_directory, check_directory_creatable, lock_directory, lock_case, &
                   write_file_atomic, ignore_file_size_signal
  use kf_h5, only: h5_initialize, h5_finalize
  use kf_case_runner, only: case_path
  use kf_scene_run, only: check_case_resources, check_existing_cases
  use kf_comm, only: comm_t, comm_init, comm_finalize
  use kf_task_farm, only: run_task_farm, task_result_t, task_ok, task_failed, task_skipped, task_stopped
  use kf_signals, only: catch_stop_signals, stop_signal, signal_name, exit_resubmit
  use kf_sweep_tasks, only: sweep_tasks_t, status_word
  use kf_exit, only: exit_program_now
  use kf_cli, only: standard_option, argument, version_line, die
  use kf_blas_threads, only: allowed_cpus, blas_threads_for, set_blas_threads, blas_threads_in_use, blas_library, &
    set_openmp_threads, openmp_threads_in_use
  use kf_platform, only: load_average
  use kf_kinds, only: wp
  use kf_scene_reference, only: scene_reference
  implicit none

  character(len=*), parameter :: program_name = 'knotflow'
  character(len=*), parameter :: usage = 'usage: mpirun -n P knotflow SCENE.nml [--dry-run | --write-scenes DIR]'// &
    new_line('a')//'  Runs every case of the scene''s &sweep (or the single scene).'// &
    new_line('a')//'  --dry-run            validate the input and list the cases without running them'// &
    new_line('a')//'  --write-scenes DIR   as --dry-run, and write each case''s scene, a single-case input that'// &
    new_line('a')//'                       runs (or resumes, or skips) that case alone, to DIR/<case>.nml'// &
    new_line('a')//'  --version            print the version'// &
    new_line('a')//'  --scene-reference    print every scene variable (default, allowed values, meaning) as'// &
    new_line('a')//'                       Markdown (docs/scenes.md) and exit'

  type(comm_t) :: comm
  type(error_t), allocatable :: error
  type(sweep_t) :: sw
  type(sweep_tasks_t) :: tasks
  type(task_result_t), allocatable :: results(:)
  character(len=:), allocatable :: scene_file, directory, scenes_dir
  logical :: dry_run
  logical :: summary_failed = .false.
  integer :: me = 0, nfailed, nstopped, threads, k
  logical :: threads_set, omp_set
  real(wp) :: load

  ! --help and --version before MPI start-up (kf_cli), and the scene reference.
  do k = 1, command_argument_count()
    call standard_option(program_name, argument(k), usage)
  end do
  if (command_argument_count() == 1) then
    if (argument(1) == '--scene-reference') call print_scene_reference()
  end if
  call comm_init(comm, error)
  if (allocated(error)) call die(program_name, error%message, 2)
  call keep_freed_heap()   ! after MPI start-up, which sets its own allocator options
  call catch_stop_signals()   ! SIGTERM/SIGINT: each case stops after its current frame
  call ignore_file_size_signal()   ! a write past `ulimit -f` fails (EFBIG) and is reported
  me = comm%rank()
  if (me < 0) call die(program_name, 'cannot get the rank of this process (MPI)', 2)
  call parse_arguments(scene_file, dry_run, scenes_dir)
  call h5_initialize(error)
  if (allocated(error)) call stop_all(error%message, 2)

  ! Every rank reads and validates the same input; errors stop before anything is written.
  call read_sweep(scene_file, sw, error)
  if (allocated(error)) call stop_all(error%message, 2)
  ! What a case needs (memory, frames): refuse what cannot fit before anything is written.
  if (me == 0) call check_case_resources(scene_file, sw, error)
  call agree(error)
  if (allocated(error)) call stop_all(error%message, 2)
  directory = trim(sw%base%output%directory)
  if (me == 0 .and. dry_run) then
    ! A dry run writes nothing but the scenes asked for: it only checks that the directory
    ! could be made.
    call check_directory_creatable(directory, error)
  else if (me == 0) then
    call make_directory(directory, error)
    if (.not. allocated(error)) call check_writable_directory(directory, error)
    if (.not. allocated(error)) then
      ! One case: other single cases may share the directory (kf_fs: lock_case).
      if (sw%n_cases() == 1) then
        call lock_case(directory, single_case_name(), error)
      else
        call lock_directory(directory, error)
      end if
    end if
  end if
  call agree(error)
  if (allocated(error)) call stop_all(trim(scene_file)//': &output: directory = '''//directory// &
                                 ''': '//error%message, 2)
  ! Existing case files are reused only when they hold the requested scene: refuse otherwise,
  ! before any case runs.
  if (me == 0) call check_existing_cases(sw, error)
  call agree(error)
  if (allocated(error)) call stop_all(trim(scene_file)//': '//error%message, 2)

  if (me == 0) then
    write (output_unit, '(a)') version_line(program_name)//': '// &
      to_str(sw%n_cases())//' case(s) from '//trim(scene_file)//' on '//to_str(comm%size())// &
      ' rank(s), output in '//directory
    call list_cases()
    flush (output_unit)
  end if
  if (dry_run) then
    if (len(scenes_dir) > 0 .and. me == 0) call write_case_scenes(error)
    call agree(error)
    if (allocated(error)) call stop_all(error%message, 2)
    call h5_finalize()
    call comm_finalize(error)
    stop
  end if

  ! Idle CPUs for the BLAS and the OpenMP pair loops of a run with one rank on its node
  ! (kf_blas_threads).
  call load_average(load, error)
  if (allocated(error)) then   ! not known: taken as an idle machine
    load = 0.0_wp
    deallocate (error)
  end if
  threads = blas_threads_for(allowed_cpus(), comm%ranks_on_node(), real(load))
  call set_blas_threads(threads, threads_set)
  call set_openmp_threads(threads, omp_set)
  tasks%sweep = sw
  tasks%reporter%rank = me
  tasks%launch%ranks = comm%size()
  tasks%launch%threads = blas_threads_in_use()
  tasks%launch%blas = blas_library()
  if (me == 0) then
    ! The kernels decide the speed (scripts/blas_env.sh); each case's /runs records them too.
    if (tasks%launch%threads > 0 .and. threads_set) then
      write (output_unit, '(a)') 'knotflow: BLAS '//tasks%launch%blas//', '// &
        to_str(tasks%launch%threads)//' thread(s) per rank'
    else if (tasks%launch%threads > 0) then
      write (output_unit, '(a)') 'knotflow: BLAS '//tasks%launch%blas//', '// &
        to_str(tasks%launch%threads)//' thread(s) per rank (OPENBLAS_NUM_THREADS)'
    else
      write (output_unit, '(a)') 'knotflow: BLAS '//tasks%launch%blas
    end if
    if (openmp_threads_in_use() > 0 .and. omp_set) then
      write (output_unit, '(a)') 'knotflow: OpenMP '//to_str(openmp_threads_in_use())//' thread(s) per rank'
    else if (openmp_threads_in_use() > 0) then
      write (output_unit, '(a)') 'knotflow: OpenMP '//to_str(openmp_threads_in_use())// &
        ' thread(s) per rank (OMP_NUM_THREADS)'
    end if
    flush (output_unit)
  end if
  call run_task_farm(comm, sw%n_cases(), tasks, results, error)
  if (allocated(error)) call stop_all(error%message, 1)
  nfailed = count(results%status /= task_ok .and. results%status /= task_skipped .and. results%status /= task_stopped)
  nstopped = count(results%status == task_stopped)
  if (me == 0) call write_summary()
  if (me == 0 .and. nstopped > 0) call stopped_line()
  call h5_finalize()
  call comm_finalize(error)
  ! Every file is closed and MPI finalised: end without the libraries' exit handlers, because
  ! after a write that failed (full disk) HDF5 1.10's handler crashes on the file whose close
  ! failed, which would turn a reported failure into a segmentation fault.
  if (nstopped > 0) call exit_program_now(exit_resubmit)
  call exit_program_now(merge(3, 0, nfailed > 0 .or. summary_failed))

contains

  subroutine list_cases()
    type(scene_t) :: sc
    character(len=:), allocatable :: name
    integer :: k
    do k = 1, sw%n_cases()
      call sw%case_scene(k, sc, name)
      write (output_unit, '(a)') '  case '//to_str(k)//': '//name//'  (A = '//to_str(sc%forces%bending_a, '(g0.6)')// &
        ', shape '//trim(sc%chain%shape)//', orientation '//sc%chain%orientation//', hydro '// &
        trim(sc%hydro%model)//', t_end = '//to_str(sc%integrator%t_end, '(g0.6)')//')'
    end do
  end subroutine list_cases

  !> Each case's scene as a single-case input, DIR/<case>.nml (kf_scene_items: scene_text, the
  !> text that reads back to the same scene; its output directory and case name are the sweep's,
  !> so it runs, resumes or skips the very file the sweep would). Each is written whole or not
  !> at all (kf_fs: write_file_atomic: a new temporary file, every write checked, renamed), so a
  !> scene file is complete or as it was; a failed write stops with the path and the reason.
  subroutine write_case_scenes(err)
    type(error_t), allocatable, intent(out) :: err
    type(scene_t) :: sc
    character(len=:), allocatable :: name, path
    integer :: k
    call make_directory(scenes_dir, err)
    if (.not. allocated(err)) call check_writable_directory(scenes_dir, err)
    if (allocated(err)) then
      err%message = '--write-scenes '''//scenes_dir//''': '//err%message
      return
    end if
    do k = 1, sw%n_cases()
      call sw%case_scene(k, sc, name)
      path = scenes_dir//'/'//name//'.nml'
      call write_file_atomic(path, '! case '//name//' of '//scene_file//' (knotflow --write-scenes)'// &
                             new_line('a')//scene_text(sc), err)
      if (allocated(err)) then
        err%message = '--write-scenes: '//err%message
        return
      end if
    end do
    write (output_unit, '(a)') 'knotflow: '//to_str(sw%n_cases())//' scene(s) written to '//scenes_dir
  end subroutine write_case_scenes

  !> The name of case 1: the case of a scene without &sweep.
  function single_case_name() result(name)
    character(len=:), allocatable :: name
    type(scene_t) :: sc
    call sw%case_scene(1, sc, name)
  end function single_case_name

  !> summary.txt (one line per case) and summary.json in the output directory, each written
  !> whole or not at all (kf_fs: write_file_atomic: a new temporary file of a unique name, every
  !> write, the fsync and the close checked, then renamed over the old one), so a summary is
  !> either complete or the previous one, and never written through a planted link. A summary
  !> that cannot be written is reported on stderr with its path and the operating system's
  !> reason and counts as a failure (exit status 3).
  subroutine write_summary()
    type(scene_t) :: sc
    character(len=:), allocatable :: name, line, txt, json
    character(len=1), parameter :: nl = new_line('a')
    type(error_t), allocatable :: err
    integer :: k
    txt = '# case  bending_a  orientation  status  rank  file  message'//nl
    json = '{"scene": "'//json_escape(scene_file)//'", "cases": ['//nl
    do k = 1, size(results)
      call sw%case_scene(k, sc, name)
      txt = txt//name//'  '//to_str(sc%forces%bending_a, '(g0.6)')//'  '//sc%chain%orientation//'  '// &
        status_word(results(k)%status)//'  '//to_str(results(k)%rank)//'  '//case_path(sc)//'  '// &
        trim(results(k)%message)//nl
      json = json//'  {"case": "'//name//'", "bending_a": '// &
        to_str(sc%forces%bending_a, '(g0.6)')//', "orientation": "'//sc%chain%orientation//'", "status": "'// &
        status_word(results(k)%status)//'", "rank": '//to_str(results(k)%rank)//', "file": "'// &
        json_escape(case_path(sc))//'", "message": "'//json_escape(trim(results(k)%message))//'"}'// &
        merge(',', ' ', k < size(results))//nl
    end do
    json = json//']}'//nl
    call write_file_atomic(directory//'/summary.txt', txt, err)
    if (.not. allocated(err)) call write_file_atomic(directory//'/summary.json', json, err)
    if (allocated(err)) then
      write (error_unit, '(a)') 'knotflow: error: the summary: '//err%message//' (the case files hold the results)'
      summary_failed = .true.
    end if
    line = 'knotflow: '//to_str(count(results%status == task_ok))//' finished, '// &
      to_str(count(results%status == task_skipped))//' skipped (already finished), '//to_str(nfailed)//' failed'
    if (nstopped > 0) line = line//', '//to_str(nstopped)//' stopped'
    if (.not. summary_failed) line = line//'; summary in '//directory//'/summary.txt'
    write (output_unit, '(a)') line
    do k = 1, size(results)
      if (results(k)%status == task_failed) then
        call sw%case_scene(k, sc, name)
        write (output_unit, '(a)') '  FAILED '//name//': '//trim(results(k)%message)
      end if
    end do
  end subroutine write_summary

  !> The closing line of a run a stop signal ended (rank 0; the signal reached every rank under
  !> mpirun, or another rank alone).
  subroutine stopped_line()
    character(len=:), allocatable :: why
    integer :: nrunning
    why = 'a stop signal'
    if (stop_signal() /= 0) why = signal_name(stop_signal())
    nrunning = count(results%status == task_stopped .and. index(results%message, 'not started') /= 1)
    write (output_unit, '(a)') 'knotflow: stopped by '//why//': '//to_str(nrunning)// &
      ' case(s) stopped after their last frame (checkpoint written), '//to_str(nstopped - nrunning)// &
      ' not started; run the same command again to go on (exit status '//to_str(exit_resubmit)//')'
  end subroutine stopped_line

  function json_escape(s) result(t)
    character(len=*), intent(in) :: s
    character(len=:), allocatable :: t
    integer :: k
    t = ''
    do k = 1, len(s)
      select case (s(k:k))
      case ('"', '\')
        t = t//'\'//s(k:k)
      case default
        if (iachar(s(k:k)) >= 32) t = t//s(k:k)
      end select
    end do
  end function json_escape

  !> Make an error on rank 0 known to every rank.
  subroutine agree(err)
    type(error_t), allocatable, intent(inout) :: err
    character(len=:), allocatable :: msg
    type(error_t), allocatable :: comm_error
    msg = ''
    if (allocated(err)) msg = err%message
    call comm%bcast(msg, comm_error)
    if (len(msg) > 0 .and. .not. allocated(err)) then
      allocate (err)
      err%message = msg
    end if
  end subroutine agree

  subroutine parse_arguments(path, dry, scenes)
    character(len=:), allocatable, intent(out) :: path, scenes
    logical, intent(out) :: dry
    integer :: k
    character(len=:), allocatable :: arg
    dry = .false.
    path = ''
    scenes = ''
    k = 0
    do while (k < command_argument_count())
      k = k + 1
      arg = argument(k)
      if (arg == '--dry-run') then
        dry = .true.
      else if (arg == '--write-scenes') then
        if (k == command_argument_count()) call stop_all('--write-scenes needs a directory (--write-scenes DIR)', 2)
        k = k + 1
        scenes = argument(k)
        if (len(scenes) == 0) call stop_all('--write-scenes needs a directory, not an empty name', 2)
        dry = .true.
      else if (index(arg, '-') == 1) then
        call stop_all('unknown option '''//arg//''' (allowed: --dry-run, --write-scenes DIR, --scene-reference, '// &
          '--help, --version)', 2)
      else if (len(path) > 0) then
        call stop_all('more than one scene file given ('''//path//''' and '''//arg//''')', 2)
      else
        path = arg
      end if
    end do
    if (len(path) == 0) call stop_all('no scene file given (usage: knotflow SCENE.nml [--dry-run | --write-scenes DIR])', 2)
  end subroutine parse_arguments

  !> Print the scene reference (kf_scene_reference) and end, before MPI start-up.
  subroutine print_scene_reference()
    character(len=:), allocatable :: text
    call scene_reference(text, error)
    if (allocated(error)) call die(program_name, error%message, 1)
    write (output_unit, '(a)', advance='no') text
    call exit_program_now(0)
  end subroutine print_scene_reference

  !> MPI finalised on every rank, then one error line on stderr (from rank 0) and a non-zero
  !> exit on every rank (kf_cli).
  subroutine stop_all(message, code)
    character(len=*), intent(in) :: message
    integer, intent(in) :: code
    type(error_t), allocatable :: ignored
    call comm_finalize(ignored)
    call die(program_name, message, code, show=me == 0)
  end subroutine stop_all

end program knotflow
