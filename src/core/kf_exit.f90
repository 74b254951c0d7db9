!> Ending a program with an exit status and no runtime backtrace (programs only).
module kf_exit
  use, intrinsic :: iso_c_binding, only: c_int
  use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
  implicit none
  private

  public :: exit_program

  interface
    subroutine c_exit(status) bind(c, name='exit')
      import :: c_int
      integer(c_int), value :: status
    end subroutine c_exit
  end interface

contains

  !> Flush the standard units and end the process with `code` (C exit: open units are closed).
  subroutine exit_program(code)
    integer, intent(in) :: code
    flush (output_unit)
    flush (error_unit)
    call c_exit(int(code, c_int))
  end subroutine exit_program

end module kf_exit
