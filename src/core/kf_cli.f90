!> The options every knotflow program answers the same way (programs only: it ends the
!> process): --help (or -h) prints the usage, --version the version line '<program> <version>
!> (<git hash>)', both on standard output with exit status 0, before any work or MPI start-up.
module kf_cli
  use, intrinsic :: iso_fortran_env, only: output_unit
  use kf_build_info, only: knotflow_version, knotflow_git_hash
  use kf_exit, only: exit_program
  implicit none
  private

  public :: standard_option, version_line

contains

  !> '<program> <version> (<git hash>)'.
  function version_line(program) result(line)
    character(len=*), intent(in) :: program
    character(len=:), allocatable :: line
    line = program//' '//knotflow_version//' ('//knotflow_git_hash//')'
  end function version_line

  !> When `arg` is --help, -h or --version: print `usage` (its lines joined with new_line) or
  !> the version line and end the program with exit status 0; otherwise return.
  subroutine standard_option(program, arg, usage)
    character(len=*), intent(in) :: program, arg, usage
    select case (trim(arg))
    case ('-h', '--help')
      write (output_unit, '(a)') usage
      call exit_program(0)
    case ('--version')
      write (output_unit, '(a)') version_line(program)
      call exit_program(0)
    end select
  end subroutine standard_option

end module kf_cli
