!> Uses the installed library: its modules (kinds, errors, the LAPACK wrapper, the HDF5 layer,
!> the build information) and the libraries they link. Argument: the version CMake's
!> find_package(knotflow) reported. Prints "consumer: ok" when every check holds.
program consumer
  use kf_kinds, only: wp
  use kf_error, only: error_t
  use kf_lapack, only: symmetric_eigen
  use kf_h5, only: h5_initialize, h5_finalize
  use kf_build_info, only: knotflow_version
  implicit none
  type(error_t), allocatable :: error
  real(wp) :: a(2, 2), w(2)
  character(len=64) :: expected

  call get_command_argument(1, expected)
  if (trim(expected) /= knotflow_version) error stop 'consumer: version of the modules differs from the package'
  ! [[2, 1], [1, 2]] has the eigenvalues 1 and 3 (ascending, as LAPACK's dsyev returns them)
  a = reshape([2.0_wp, 1.0_wp, 1.0_wp, 2.0_wp], [2, 2])
  call symmetric_eigen(a, w, error)
  if (allocated(error)) error stop 'consumer: symmetric_eigen failed'
  if (any(abs(w - [1.0_wp, 3.0_wp]) > 1.0e-12_wp)) error stop 'consumer: wrong eigenvalues'
  call h5_initialize(error)
  if (allocated(error)) error stop 'consumer: h5_initialize failed'
  call h5_finalize()
  print '(a)', 'consumer: ok (knotflow '//knotflow_version//')'
end program consumer
