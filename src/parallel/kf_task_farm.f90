!> Dynamic load balancing for parameter sweeps: tasks 1..ntasks are handed out one at a time
!> from a shared counter (MPI_Fetch_and_op on a window owned by rank 0, passive target), so
!> every rank computes (no idle master) and a rank that finishes early simply takes the next
!> task. Each task runs exactly once. A second counter counts completions, so the rank that
!> completes a task knows how many tasks are done in total (for "k of n cases done" lines).
!> At the end the status, message and rank of every task are combined over all ranks and
!> returned on every rank.
!>
!> All MPI goes through kf_comm. Collective: every rank of `comm` must call `run_task_farm`
!> with the same `ntasks`.
module kf_task_farm
  use kf_kinds, only: i8
  use kf_error, only: error_t, fatal_error
  use kf_comm, only: comm_t, shared_counter_t
  implicit none
  private

  public :: run_task_farm

  !> Task outcomes (set by the worker: task_stopped when a stop signal ended it or kept it from
  !> starting) and "never ran".
  integer, parameter, public :: task_ok = 0, task_failed = 1, task_skipped = 2, task_stopped = 3, &
    task_not_run = -1
  integer, parameter, public :: task_message_len = 256

  !> The outcome of one task.
  type, public :: task_result_t
    integer :: status = task_not_run               !< task_ok, task_failed, task_skipped, task_stopped
    integer :: rank = -1                           !< the rank that ran it
    character(len=task_message_len) :: message = '' !< the worker's message
  end type task_result_t

  !> What the farm runs: `run` does one task, `progress` hears of each completion (by default
  !> nothing). An object rather than procedure arguments, so the caller's state travels in it
  !> (an internal procedure passed as an argument needs a trampoline on an executable stack).
  type, abstract, public :: task_worker_t
  contains
    procedure(task_run_i), deferred :: run
    procedure :: progress => no_progress
  end type task_worker_t

  abstract interface
    !> Run task `itask` (1-based); status 0 ok, 1 failed, 2 skipped, 3 stopped; a one-line message.
    subroutine task_run_i(this, itask, status, message)
      import :: task_worker_t
      class(task_worker_t), intent(inout) :: this
      integer, intent(in) :: itask
      integer, intent(out) :: status
      character(len=256), intent(out) :: message
    end subroutine task_run_i
  end interface

  integer, parameter :: next_counter = 1, done_counter = 2

contains

  !> Called on the rank that just finished task `itask`: `done` tasks of `ntasks` are complete
  !> over all ranks (done counts every completion exactly once, 1..ntasks). This one does nothing.
  subroutine no_progress(this, done, ntasks, itask, status, message)
    class(task_worker_t), intent(inout) :: this
    integer, intent(in) :: done, ntasks, itask, status
    character(len=256), intent(in) :: message
  end subroutine no_progress

  !> Run `worker` on tasks 1..ntasks across all ranks of `comm`; results(ntasks) on every rank.
  subroutine run_task_farm(comm, ntasks, worker, results, error)
    type(comm_t), intent(in) :: comm
    integer, intent(in) :: ntasks
    class(task_worker_t), intent(inout) :: worker
    type(task_result_t), allocatable, intent(out) :: results(:)
    type(error_t), allocatable, intent(out) :: error
    type(shared_counter_t) :: counter
    type(error_t), allocatable :: free_error
    integer, allocatable :: status(:), owner(:)
    character(len=task_message_len), allocatable :: messages(:)
    character(len=task_message_len) :: message
    integer(i8) :: next, done
    integer :: itask, st, me, k
    if (ntasks < 0) then
      call fatal_error(error, 'run_task_farm: negative number of tasks')
      return
    end if
    allocate (results(ntasks), status(ntasks), owner(ntasks), messages(ntasks))
    status = task_not_run
    owner = task_not_run
    messages = repeat(achar(0), task_message_len)
    me = comm%rank()
    if (me < 0) then
      call fatal_error(error, 'run_task_farm: cannot get the rank of this process')
      return
    end if
    if (ntasks == 0) return

    call counter%create(comm, 2, error)
    if (allocated(error)) return
    do
      call counter%fetch_add(next_counter, 1_i8, next, error)
      if (allocated(error)) exit
      if (next >= ntasks) exit
      itask = int(next) + 1
      st = task_failed
      message = ''
      call worker%run(itask, st, message)
      status(itask) = st
      owner(itask) = me
      messages(itask) = message
      call counter%fetch_add(done_counter, 1_i8, done, error)
      if (allocated(error)) exit
      call worker%progress(int(done) + 1, ntasks, itask, st, message)
    end do
    ! An MPI failure above is fatal under the default error handler; with MPI_ERRORS_RETURN
    ! the ranks may disagree here, which the caller must treat as fatal (MPI_Abort).
    if (allocated(error)) return
    call counter%free(free_error)
    if (allocated(free_error)) then
      call move_alloc(free_error, error)
      return
    end if

    ! Combine: exactly one rank holds each task's entries, all others the neutral values.
    call comm%max(status, error)
    if (.not. allocated(error)) call comm%max(owner, error)
    if (.not. allocated(error)) call comm%merge_bytes(messages, error)
    if (allocated(error)) return
    do itask = 1, ntasks
      results(itask)%status = status(itask)
      results(itask)%rank = owner(itask)
      do k = 1, task_message_len
        if (messages(itask)(k:k) == achar(0)) messages(itask)(k:k) = ' '
      end do
      results(itask)%message = messages(itask)
    end do
  end subroutine run_task_farm

end module kf_task_farm
