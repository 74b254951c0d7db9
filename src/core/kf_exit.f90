!> Ending a program with an exit status and no runtime backtrace (programs only).
module kf_exit
  use, intrinsic :: iso_c_binding, only: c_int
  use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
  implicit none
  private

  public :: exit_program, exit_program_now

  interface
    subroutine c_exit(status) bind(c, name='exit')
      import :: c_int
      integer(c_int), value :: status
    end subroutine c_exit
    subroutine c_exit_now(status) bind(c, name='_exit')
      import :: c_int
      integer(c_int), value :: status
    end subroutine c_exit_now
  end interface

contains

  !> Flush the standard units and end the process with `code` (C exit: open units are closed).
  subroutine exit_program(code)
    integer, intent(in) :: code
    flush (output_unit)
    flush (error_unit)
    call c_exit(int(code, c_int))
  end subroutine exit_program

  !> Like `exit_program`, but without the exit handlers of the libraries (C _exit): for a
  !> program whose HDF5 library could not close cleanly (a file whose last writes failed), where
  !> HDF5's own exit handler would crash. Every file the program wrote must be closed already.
  subroutine exit_program_now(code)
    integer, intent(in) :: code
    flush (output_unit)
    flush (error_unit)
    call c_exit_now(int(code, c_int))
  end subroutine exit_program_now

end module kf_exit
