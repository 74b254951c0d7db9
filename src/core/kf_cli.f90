!> The command line of every knotflow program (programs only: it ends the process): the
!> arguments at their full length, the options every program answers the same way (--help or -h
!> prints the usage, --version the version line '<program> <version> (<git hash>)', both on
!> standard output with exit status 0, before any work or MPI start-up), and the end of a
!> program on an error: one line '<program>: error: <message>' on stderr and an exit status.
module kf_cli
  use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
  use kf_build_info, only: knotflow_version, knotflow_git_hash
  use kf_exit, only: exit_program
  implicit none
  private

  public :: standard_option, version_line, argument, die

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

  !> Command argument `k` (1-based) at its full length ('' when there is none).
  function argument(k) result(arg)
    integer, intent(in) :: k
    character(len=:), allocatable :: arg
    integer :: length
    call get_command_argument(k, length=length)
    allocate (character(len=length) :: arg)
    if (length > 0) call get_command_argument(k, arg)
  end function argument

  !> '<program>: error: <message>' on stderr (unless `show` is false: the ranks of a parallel
  !> program other than the one that reports) and the end of the program with exit status `code`.
  subroutine die(program, message, code, show)
    character(len=*), intent(in) :: program, message
    integer, intent(in) :: code
    logical, intent(in), optional :: show
    logical :: write_line
    write_line = .true.
    if (present(show)) write_line = show
    if (write_line) write (error_unit, '(a)') program//': error: '//message
    call exit_program(code)
  end subroutine die

end module kf_cli
