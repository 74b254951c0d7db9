!> The one kinds module of knotflow.
module kf_kinds
  use, intrinsic :: iso_fortran_env, only: real32, real64, int32, int64
  implicit none
  private
  integer, parameter, public :: wp = real64   !< working precision
  integer, parameter, public :: sp = real32   !< single precision (copies that only precondition)
  integer, parameter, public :: i4 = int32
  integer, parameter, public :: i8 = int64
end module kf_kinds
