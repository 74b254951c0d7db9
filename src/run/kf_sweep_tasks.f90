!> The cases of a sweep as the tasks of the task farm (kf_task_farm): task k runs case k
!> (kf_case_runner), and every progress line goes to a unit chosen by the program, prefixed with
!> the rank ("[rank 1] case ...").
module kf_sweep_tasks
  use, intrinsic :: iso_fortran_env, only: output_unit
  use kf_strings, only: to_str
  use kf_scene, only: scene_t
  use kf_sweep, only: sweep_t
  use kf_case_runner, only: run_case, case_path, case_reporter_t, case_ok, case_skipped, case_stopped
  use kf_task_farm, only: task_worker_t, task_ok, task_failed, task_skipped, task_stopped
  use kf_signals, only: stop_signal, signal_name
  use kf_run_segment, only: run_launch_t
  implicit none
  private

  public :: status_word

  !> Writes each line to `unit` as "[rank <rank>] <line>" and flushes it.
  type, extends(case_reporter_t), public :: rank_reporter_t
    integer :: unit = output_unit
    integer :: rank = 0
  contains
    procedure :: line => rank_line
  end type rank_reporter_t

  !> The sweep's cases as tasks; `reporter` receives the lines of the cases this rank runs
  !> and one line per completed case; `launch` (ranks, BLAS threads) is recorded in each case
  !> file's /runs.
  type, extends(task_worker_t), public :: sweep_tasks_t
    type(sweep_t) :: sweep
    type(rank_reporter_t) :: reporter
    type(run_launch_t) :: launch
  contains
    procedure :: run => run_sweep_case
    procedure :: progress => case_done
  end type sweep_tasks_t

contains

  subroutine rank_line(this, line)
    class(rank_reporter_t), intent(inout) :: this
    character(len=*), intent(in) :: line
    write (this%unit, '(a)') '[rank '//to_str(this%rank)//'] '//line
    flush (this%unit)
  end subroutine rank_line

  !> One case of the sweep (none after a stop signal: kf_signals).
  subroutine run_sweep_case(this, itask, status, message)
    class(sweep_tasks_t), intent(inout) :: this
    integer, intent(in) :: itask
    integer, intent(out) :: status
    character(len=256), intent(out) :: message
    type(scene_t) :: sc
    character(len=:), allocatable :: name, msg
    if (stop_signal() /= 0) then
      status = task_stopped
      message = 'not started: stopped by '//signal_name(stop_signal())
      return
    end if
    call this%sweep%case_scene(itask, sc, name)
    call this%reporter%line('case '//name//': started ('//case_path(sc)//')')
    call run_case(sc, this%reporter, status, msg, this%launch)
    select case (status)
    case (case_ok)
      status = task_ok
    case (case_skipped)
      status = task_skipped
    case (case_stopped)
      status = task_stopped
    case default
      status = task_failed
    end select
    message = msg
  end subroutine run_sweep_case

  subroutine case_done(this, done, ntasks, itask, status, message)
    class(sweep_tasks_t), intent(inout) :: this
    integer, intent(in) :: done, ntasks, itask, status
    character(len=256), intent(in) :: message
    type(scene_t) :: sc
    character(len=:), allocatable :: name
    call this%sweep%case_scene(itask, sc, name)
    call this%reporter%line(to_str(done)//' of '//to_str(ntasks)//' cases done; case '//name//' '// &
                            status_word(status)//': '//trim(message))
  end subroutine case_done

  !> The word for a task's status in progress lines and summaries.
  pure function status_word(status) result(word)
    integer, intent(in) :: status
    character(len=:), allocatable :: word
    select case (status)
    case (task_ok)
      word = 'finished'
    case (task_skipped)
      word = 'skipped'
    case (task_failed)
      word = 'FAILED'
    case (task_stopped)
      word = 'stopped'
    case default
      word = 'not run'
    end select
  end function status_word

end module kf_sweep_tasks
