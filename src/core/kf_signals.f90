!> Stopping a run cleanly on SIGTERM (a scheduler's time limit, `scancel`, `kill`) and SIGINT
!> (Ctrl-C): the program installs a handler (`catch_stop_signals`) that only records the signal;
!> the frame loop asks `stop_signal()` after each frame it has written, stops there (the frame and
!> its checkpoint are whole) and the program ends with `exit_resubmit`, the status the job
!> scripts take for "run the same command again" (docs/robustness.md). A second signal ends the
!> process at once, with the same status: the last checkpoint is whole whenever a process ends.
!> Under mpirun every rank receives the signal and stops at its own next frame.
!>
!> The received signal is the one piece of process-wide state of the library: a signal handler
!> can only reach module data (a `volatile` integer, written by the handler, read by the loop).
!> A process that does not install the handler (Python, through the C layer) asks for the same
!> stop with `request_stop` from another thread and clears it with `clear_stop` before a run.
module kf_signals
  use, intrinsic :: iso_c_binding, only: c_int, c_funptr, c_funloc
  implicit none
  private

  public :: catch_stop_signals, stop_signal, signal_name, request_stop, clear_stop

  !> Exit status of a run stopped by SIGTERM or SIGINT: resubmit (EX_TEMPFAIL of sysexits.h,
  !> "temporary failure, try again").
  integer, parameter, public :: exit_resubmit = 75
  integer(c_int), parameter :: sigint = 2, sigterm = 15

  !> The stop signal received (0: none yet).
  integer(c_int), volatile, save :: received = 0

  interface
    function c_signal(signum, handler) bind(c, name='signal') result(old)
      import :: c_int, c_funptr
      integer(c_int), value :: signum
      type(c_funptr), value :: handler
      type(c_funptr) :: old
    end function c_signal
    subroutine c_exit_now(status) bind(c, name='_exit')
      import :: c_int
      integer(c_int), value :: status
    end subroutine c_exit_now
  end interface

contains

  !> Record SIGTERM and SIGINT instead of dying at once (the program polls `stop_signal`).
  subroutine catch_stop_signals()
    type(c_funptr) :: old
    old = c_signal(sigterm, c_funloc(on_stop_signal))
    old = c_signal(sigint, c_funloc(on_stop_signal))
  end subroutine catch_stop_signals

  !> The handler: the first signal is recorded; a second one ends the process now (_exit is
  !> async-signal-safe; the case file's last checkpoint is whole at any moment).
  subroutine on_stop_signal(signum) bind(c)
    integer(c_int), value :: signum
    if (received /= 0) call c_exit_now(int(exit_resubmit, c_int))
    received = signum
  end subroutine on_stop_signal

  !> Stop as SIGINT would (the running case after its current frame, no case after it), without
  !> a signal: for a caller that runs the library in another thread of its own (Ctrl-C in Python).
  subroutine request_stop()
    received = sigint
  end subroutine request_stop

  !> Forget a stop asked for before (a caller's next run starts afresh).
  subroutine clear_stop()
    received = 0
  end subroutine clear_stop

  !> The stop signal received so far (SIGTERM 15, SIGINT 2), 0 if none.
  integer function stop_signal()
    stop_signal = int(received)
  end function stop_signal

  !> 'SIGTERM', 'SIGINT' or 'signal <n>'.
  pure function signal_name(signum) result(name)
    integer, intent(in) :: signum
    character(len=:), allocatable :: name
    character(len=12) :: buf
    select case (signum)
    case (sigterm)
      name = 'SIGTERM'
    case (sigint)
      name = 'SIGINT'
    case default
      write (buf, '(i0)') signum
      name = 'signal '//trim(buf)
    end select
  end function signal_name

end module kf_signals
