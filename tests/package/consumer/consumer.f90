!> Uses the installed library: its modules (kinds, errors, the LAPACK wrapper, the HDF5 layer,
!> the build information) and the libraries they link. Argument: the version CMake's
!> find_package(knotflow) reported. Prints "consumer: ok" when every check holds.
program consumer
  use kf_kinds, only: wp
  use kf_error, only: error_t
  use kf_lapack, only: cholesky_factor, cholesky_solve
  use kf_h5, only: h5_initialize, h5_finalize
  use kf_build_info, only: knotflow_version
  implicit none
  type(error_t), allocatable :: error
  real(wp) :: a(2, 2), x(2)
  character(len=64) :: expected

  call get_command_argument(1, expected)
  if (trim(expected) /= knotflow_version) error stop 'consumer: version of the modules differs from the package'
  ! [[4, 2], [2, 3]] x = [8, 7] has the solution x = [1.25, 1.5] (LAPACK's dpotrf and dpotrs)
  a = reshape([4.0_wp, 2.0_wp, 2.0_wp, 3.0_wp], [2, 2])
  call cholesky_factor(a, error, 'test matrix')
  if (allocated(error)) error stop 'consumer: cholesky_factor failed'
  x = [8.0_wp, 7.0_wp]
  call cholesky_solve(a, x)
  if (any(abs(x - [1.25_wp, 1.5_wp]) > 1.0e-12_wp)) error stop 'consumer: wrong solution'
  call h5_initialize(error)
  if (allocated(error)) error stop 'consumer: h5_initialize failed'
  call h5_finalize()
  print '(a)', 'consumer: ok (knotflow '//knotflow_version//')'
end program consumer
