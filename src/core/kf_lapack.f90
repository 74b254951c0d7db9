!> LAPACK wrapped once: assumed-shape wrappers that work out the sizes and turn `info` into errors.
module kf_lapack
  use kf_kinds, only: wp
  use kf_strings, only: to_str
  use kf_blas, only: dpotrf, dpotrs, dpotri, dsyev, dgetrf, dgetrs
  use kf_error, only: error_t, fatal_error
  implicit none
  private

  public :: cholesky_factor, cholesky_solve, cholesky_invert, symmetric_eigenvalues, lu_factor, lu_solve

  !> Solve A X = B (B a matrix or a vector) given the factor from cholesky_factor.
  interface cholesky_solve
    module procedure cholesky_solve_matrix, cholesky_solve_vector
  end interface cholesky_solve

contains

  !> Cholesky factorisation A = L L^T in place (lower triangle; the upper one is left untouched).
  subroutine cholesky_factor(a, error, what)
    real(wp), intent(inout) :: a(:, :)
    type(error_t), allocatable, intent(out) :: error
    character(len=*), intent(in) :: what   !< name of the matrix, for the message
    integer :: info
    call dpotrf('L', size(a, 1), a, size(a, 1), info)
    if (info /= 0) then
      if (info > 0) then
        call fatal_error(error, 'Cholesky factorisation of the '//what// &
          ' failed: matrix not positive definite (leading minor '//to_str(info)//')')
      else
        call fatal_error(error, 'dpotrf: illegal argument '//to_str(info)//' for the '//what)
      end if
    end if
  end subroutine cholesky_factor

  !> Eigenvalues w (ascending) of the symmetric matrix a, whose lower triangle is read; a is
  !> overwritten. For diagnostics (LAPACK dsyev: its last bits may depend on the BLAS threads).
  subroutine symmetric_eigenvalues(a, w, error, what)
    real(wp), intent(inout) :: a(:, :)
    real(wp), intent(out) :: w(:)
    type(error_t), allocatable, intent(out) :: error
    character(len=*), intent(in) :: what   !< name of the matrix, for the message
    real(wp) :: query(1)
    real(wp), allocatable :: work(:)
    integer :: info, n
    n = size(a, 1)
    call dsyev('N', 'L', n, a, n, w, query, -1, info)
    if (info == 0) then
      allocate (work(max(1, int(query(1)))))
      call dsyev('N', 'L', n, a, n, w, work, size(work), info)
    end if
    if (info /= 0) call fatal_error(error, 'dsyev: eigenvalues of the '//what//' failed (info '//to_str(info)//')')
  end subroutine symmetric_eigenvalues

  !> Solve A X = B given the factor from cholesky_factor; B is overwritten by X.
  subroutine cholesky_solve_matrix(factor, b)
    real(wp), intent(in) :: factor(:, :)
    real(wp), intent(inout) :: b(:, :)
    integer :: info
    call dpotrs('L', size(factor, 1), size(b, 2), factor, size(factor, 1), b, size(b, 1), info)
  end subroutine cholesky_solve_matrix

  !> The same for one right-hand side b.
  subroutine cholesky_solve_vector(factor, b)
    real(wp), intent(in) :: factor(:, :)
    real(wp), intent(inout) :: b(:)
    integer :: info
    call dpotrs('L', size(factor, 1), 1, factor, size(factor, 1), b, size(b), info)
  end subroutine cholesky_solve_vector

  !> Inverse of an SPD matrix from its Cholesky factor; returns the full symmetric inverse.
  subroutine cholesky_invert(a, error, what)
    real(wp), intent(inout) :: a(:, :)
    type(error_t), allocatable, intent(out) :: error
    character(len=*), intent(in) :: what
    integer :: info, i, n
    n = size(a, 1)
    call dpotri('L', n, a, n, info)
    if (info /= 0) then
      call fatal_error(error, 'inversion of the '//what//' failed (dpotri info = '//to_str(info)//')')
      return
    end if
    do i = 2, n
      a(1:i - 1, i) = a(i, 1:i - 1)
    end do
  end subroutine cholesky_invert

  !> LU factorisation with partial pivoting P A = L U of the square matrix a, in place (LAPACK
  !> dgetrf); ipiv(size(a, 1)) receives the pivots. A singular matrix is an error.
  subroutine lu_factor(a, ipiv, error, what)
    real(wp), intent(inout) :: a(:, :)
    integer, intent(out) :: ipiv(:)
    type(error_t), allocatable, intent(out) :: error
    character(len=*), intent(in) :: what   !< name of the matrix, for the message
    integer :: info
    call dgetrf(size(a, 1), size(a, 2), a, size(a, 1), ipiv, info)
    if (info > 0) then
      call fatal_error(error, 'LU factorisation of the '//what//' failed: matrix singular (pivot '//to_str(info)//')')
    else if (info < 0) then
      call fatal_error(error, 'dgetrf: illegal argument '//to_str(info)//' for the '//what)
    end if
  end subroutine lu_factor

  !> Solve A x = b for one right-hand side given the factors from lu_factor; b is overwritten by x.
  subroutine lu_solve(factor, ipiv, b)
    real(wp), intent(in) :: factor(:, :)
    integer, intent(in) :: ipiv(:)
    real(wp), intent(inout) :: b(:)
    integer :: info
    call dgetrs('N', size(factor, 1), 1, factor, size(factor, 1), ipiv, b, size(b), info)
  end subroutine lu_solve

end module kf_lapack
