!> Mathematical constants.
module kf_constants
  use kf_kinds, only: wp
  implicit none
  private
  real(wp), parameter, public :: pi = 3.141592653589793238462643383279502884_wp
  real(wp), parameter, public :: two_pi = 2.0_wp*pi
end module kf_constants
