!> A scene's cases checked and run in one process: what the program knotflow checks before any
!> case runs (the resources and models of the cases, the case files already there), and a serial
!> run of every case of a scene file for a caller inside another program (the C interface,
!> src/capi/kf_capi_run: Python's knotflow.run_scene). The program knotflow farms the cases out
!> over MPI ranks itself; both run each case with kf_case_runner's run_case.
module kf_scene_run
  use kf_kinds, only: wp
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_scene, only: scene_t, path_len
  use kf_sweep, only: sweep_t, read_sweep
  use kf_resources, only: check_resources, physical_memory
  use kf_dynamics, only: dynamics_t
  use kf_stepper, only: stepper_t
  use kf_stepper_factory, only: make_stepper
  use kf_case_match, only: check_reusable
  use kf_chain_shapes, only: build_initial_chain
  use kf_scene_check, only: refuse, quoted
  use kf_stepper_start, only: start_from_state
  use kf_case_runner, only: run_case, case_path, case_reporter_t
  use kf_run_segment, only: run_launch_t
  use kf_fs, only: make_directory, check_writable_directory, lock_directory, lock_case, release_locks
  implicit none
  private

  public :: check_case_resources, check_existing_cases, read_scene_cases, run_scene_cases

contains

  !> The resources of one case (kf_resources), and the models built once for it (they refuse
  !> what they cannot compute): the listed parameters of a sweep (A, orientation, seed) change
  !> neither the number of beads nor the sizes, so case 1 stands for all.
  subroutine check_case_resources(scene_file, sw, error)
    character(len=*), intent(in) :: scene_file
    type(sweep_t), intent(in) :: sw
    type(error_t), allocatable, intent(out) :: error
    type(scene_t) :: sc
    type(dynamics_t) :: dyn
    class(stepper_t), allocatable :: integ
    character(len=:), allocatable :: name
    real(wp), allocatable :: r(:, :)
    real(wp) :: rotation(3, 3)
    integer :: n_beads
    call sw%case_scene(1, sc, name)
    n_beads = sc%chain%n_beads   ! resolved when the scene was read
    call check_resources(sc, n_beads, physical_memory(), error)
    if (allocated(error)) return
    ! What the models themselves reject is refused here too, not by every case at run time.
    call dyn%init(sc, n_beads, error)
    if (.not. allocated(error)) call make_stepper(sc%integrator, integ, error)
    if (allocated(error)) then
      error%message = trim(scene_file)//': the models reject the scene: '//error%message
      return
    end if
    ! A stepper state belongs to one run's chain and method: one case, and checked whole here.
    if (len_trim(sc%chain%stepper_state) > 0) then
      if (sw%n_cases() /= 1) then
        call refuse(error, trim(scene_file), 'chain', 'stepper_state', quoted(sc%chain%stepper_state), &
          "'' in a sweep of "//to_str(sw%n_cases())//' cases (a stepper state continues one run)')
        return
      end if
      call build_initial_chain(sc%chain, r, rotation, error)
      if (.not. allocated(error)) call start_from_state(sc, r, integ, error)
    end if
  end subroutine check_case_resources

  !> Every finished or interrupted case file of the sweep must hold the requested scene
  !> (kf_case_match): the first mismatch in full, the others by name.
  subroutine check_existing_cases(sw, error)
    type(sweep_t), intent(in) :: sw
    type(error_t), allocatable, intent(out) :: error
    type(error_t), allocatable :: mismatch
    type(scene_t) :: sc
    character(len=:), allocatable :: name, others
    integer :: k, nothers
    others = ''
    nothers = 0
    do k = 1, sw%n_cases()
      call sw%case_scene(k, sc, name)
      call check_reusable(case_path(sc), sc, mismatch)
      if (.not. allocated(mismatch)) cycle
      if (.not. allocated(error)) then
        call move_alloc(mismatch, error)
      else
        nothers = nothers + 1
        if (nothers <= 10) others = others//merge(', ', '  ', nothers > 1)//case_path(sc)
        if (nothers == 11) others = others//', ...'
      end if
    end do
    if (nothers > 0) error%message = error%message//' (and '//to_str(nothers)// &
      ' more case file(s) with another scene: '//trim(adjustl(others))//')'
  end subroutine check_existing_cases

  !> Read the scene file `scene_file` (with its optional &sweep) and check what knotflow checks
  !> before writing anything: the scene's values (read_sweep), the resources and the models.
  !> `output_directory`, when not empty, replaces &output directory (the case files then go
  !> there). Nothing is written.
  subroutine read_scene_cases(scene_file, output_directory, sw, error)
    character(len=*), intent(in) :: scene_file, output_directory
    type(sweep_t), intent(out) :: sw
    type(error_t), allocatable, intent(out) :: error
    call read_sweep(scene_file, sw, error)
    if (allocated(error)) return
    if (len(output_directory) > 0) then
      if (len(output_directory) > path_len .or. len_trim(output_directory) == 0) then
        call fatal_error(error, 'output directory '''//output_directory//''' refused: a non-blank name of at most '// &
          to_str(path_len)//' characters is allowed')
        return
      end if
      sw%base%output%directory = output_directory
    end if
    call check_case_resources(scene_file, sw, error)
  end subroutine read_scene_cases

  !> Run every case of the sweep `sw` (from `read_scene_cases`) in this process, one after the
  !> other, as knotflow does on one rank: the output directory made and locked (released at the
  !> end), the existing case files checked (refused when they hold another scene: nothing
  !> runs), then each case run, resumed or skipped (kf_case_runner). `statuses(k)` and
  !> `messages(k)` are case k's outcome (case_ok, case_failed, case_skipped, case_stopped) and
  !> message; `error` is set only when nothing ran.
  subroutine run_scene_cases(scene_file, sw, report, launch, statuses, messages, error)
    character(len=*), intent(in) :: scene_file
    type(sweep_t), intent(in) :: sw
    class(case_reporter_t), intent(inout) :: report
    type(run_launch_t), intent(in) :: launch
    integer, intent(out) :: statuses(:)
    character(len=*), intent(out) :: messages(:)
    type(error_t), allocatable, intent(out) :: error
    type(scene_t) :: sc
    character(len=:), allocatable :: name, directory, msg
    integer :: fds(2), k
    statuses = -1
    messages = ''
    if (size(statuses) /= sw%n_cases() .or. size(messages) /= sw%n_cases()) then
      call fatal_error(error, 'run_scene_cases: room for '//to_str(size(statuses))//' case(s), the scene has '// &
        to_str(sw%n_cases()))
      return
    end if
    fds = -1
    directory = trim(sw%base%output%directory)
    call make_directory(directory, error)
    if (.not. allocated(error)) call check_writable_directory(directory, error)
    if (.not. allocated(error)) then
      ! one case: other single cases may share the directory (kf_fs: lock_case)
      if (sw%n_cases() == 1) then
        call sw%case_scene(1, sc, name)
        call lock_case(directory, name, error, fds)
      else
        call lock_directory(directory, error, fds)
      end if
    end if
    if (allocated(error)) then
      error%message = trim(scene_file)//': &output: directory = '''//directory//''': '//error%message
      call release_locks(fds)
      return
    end if
    call check_existing_cases(sw, error)
    if (allocated(error)) then
      error%message = trim(scene_file)//': '//error%message
      call release_locks(fds)
      return
    end if
    do k = 1, sw%n_cases()
      call sw%case_scene(k, sc, name)
      call report%line('case '//name//': started ('//case_path(sc)//')')
      call run_case(sc, report, statuses(k), msg, launch)
      messages(k) = msg
    end do
    call release_locks(fds)
  end subroutine run_scene_cases

end module kf_scene_run
