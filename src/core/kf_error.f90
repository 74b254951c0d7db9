!> Errors are values: fallible routines take `type(error_t), allocatable, intent(out) :: error`
!> and the caller checks `if (allocated(error)) return`. Only programs print and stop.
module kf_error
  implicit none
  private

  !> An error with a one-line, user-facing message.
  type, public :: error_t
    character(len=:), allocatable :: message
  end type error_t

  public :: fatal_error

contains

  !> Create an error carrying `message`.
  subroutine fatal_error(error, message)
    type(error_t), allocatable, intent(out) :: error
    character(len=*), intent(in) :: message
    allocate (error)
    error%message = message
  end subroutine fatal_error

end module kf_error
