!> Explicit interfaces of the external BLAS and LAPACK routines the project calls, declared
!> once. Code that wants errors as values should use the wrappers in kf_lapack instead.
module kf_blas
  use kf_kinds, only: wp, sp
  implicit none
  private

  public :: dpotrf, dpotrs, dpotri, dsyev, dtrsm, dtrsv, stpsv, dgemm, dsyrk, dgemv, dsymv, dgetrf, dgetrs
  public :: sgemv, ssymv

  interface
    subroutine dpotrf(uplo, n, a, lda, info)
      import :: wp
      character(len=1), intent(in) :: uplo
      integer, intent(in) :: n, lda
      real(wp), intent(inout) :: a(lda, *)
      integer, intent(out) :: info
    end subroutine dpotrf
    subroutine dpotrs(uplo, n, nrhs, a, lda, b, ldb, info)
      import :: wp
      character(len=1), intent(in) :: uplo
      integer, intent(in) :: n, nrhs, lda, ldb
      real(wp), intent(in) :: a(lda, *)
      real(wp), intent(inout) :: b(ldb, *)
      integer, intent(out) :: info
    end subroutine dpotrs
    subroutine dpotri(uplo, n, a, lda, info)
      import :: wp
      character(len=1), intent(in) :: uplo
      integer, intent(in) :: n, lda
      real(wp), intent(inout) :: a(lda, *)
      integer, intent(out) :: info
    end subroutine dpotri
    subroutine dsyev(jobz, uplo, n, a, lda, w, work, lwork, info)
      import :: wp
      character(len=1), intent(in) :: jobz, uplo
      integer, intent(in) :: n, lda, lwork
      real(wp), intent(inout) :: a(lda, *)
      real(wp), intent(out) :: w(*)
      real(wp), intent(inout) :: work(*)
      integer, intent(out) :: info
    end subroutine dsyev
    subroutine dtrsm(side, uplo, transa, diag, m, n, alpha, a, lda, b, ldb)
      import :: wp
      character(len=1), intent(in) :: side, uplo, transa, diag
      integer, intent(in) :: m, n, lda, ldb
      real(wp), intent(in) :: alpha
      real(wp), intent(in) :: a(lda, *)
      real(wp), intent(inout) :: b(ldb, *)
    end subroutine dtrsm
    subroutine dtrsv(uplo, trans, diag, n, a, lda, x, incx)
      import :: wp
      character(len=1), intent(in) :: uplo, trans, diag
      integer, intent(in) :: n, lda, incx
      real(wp), intent(in) :: a(lda, *)
      real(wp), intent(inout) :: x(*)
    end subroutine dtrsv
    subroutine stpsv(uplo, trans, diag, n, ap, x, incx)
      import :: sp
      character(len=1), intent(in) :: uplo, trans, diag
      integer, intent(in) :: n, incx
      real(sp), intent(in) :: ap(*)
      real(sp), intent(inout) :: x(*)
    end subroutine stpsv
    subroutine dgemm(transa, transb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc)
      import :: wp
      character(len=1), intent(in) :: transa, transb
      integer, intent(in) :: m, n, k, lda, ldb, ldc
      real(wp), intent(in) :: alpha, beta
      real(wp), intent(in) :: a(lda, *), b(ldb, *)
      real(wp), intent(inout) :: c(ldc, *)
    end subroutine dgemm
    subroutine dsyrk(uplo, trans, n, k, alpha, a, lda, beta, c, ldc)
      import :: wp
      character(len=1), intent(in) :: uplo, trans
      integer, intent(in) :: n, k, lda, ldc
      real(wp), intent(in) :: alpha, beta
      real(wp), intent(in) :: a(lda, *)
      real(wp), intent(inout) :: c(ldc, *)
    end subroutine dsyrk
    subroutine dgemv(trans, m, n, alpha, a, lda, x, incx, beta, y, incy)
      import :: wp
      character(len=1), intent(in) :: trans
      integer, intent(in) :: m, n, lda, incx, incy
      real(wp), intent(in) :: alpha, beta
      real(wp), intent(in) :: a(lda, *), x(*)
      real(wp), intent(inout) :: y(*)
    end subroutine dgemv
    subroutine dsymv(uplo, n, alpha, a, lda, x, incx, beta, y, incy)
      import :: wp
      character(len=1), intent(in) :: uplo
      integer, intent(in) :: n, lda, incx, incy
      real(wp), intent(in) :: alpha, beta, a(lda, *), x(*)
      real(wp), intent(inout) :: y(*)
    end subroutine dsymv
    subroutine sgemv(trans, m, n, alpha, a, lda, x, incx, beta, y, incy)
      import :: sp
      character(len=1), intent(in) :: trans
      integer, intent(in) :: m, n, lda, incx, incy
      real(sp), intent(in) :: alpha, beta
      real(sp), intent(in) :: a(lda, *), x(*)
      real(sp), intent(inout) :: y(*)
    end subroutine sgemv
    subroutine ssymv(uplo, n, alpha, a, lda, x, incx, beta, y, incy)
      import :: sp
      character(len=1), intent(in) :: uplo
      integer, intent(in) :: n, lda, incx, incy
      real(sp), intent(in) :: alpha, beta, a(lda, *), x(*)
      real(sp), intent(inout) :: y(*)
    end subroutine ssymv
    subroutine dgetrf(m, n, a, lda, ipiv, info)
      import :: wp
      integer, intent(in) :: m, n, lda
      real(wp), intent(inout) :: a(lda, *)
      integer, intent(out) :: ipiv(*)
      integer, intent(out) :: info
    end subroutine dgetrf
    subroutine dgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
      import :: wp
      character(len=1), intent(in) :: trans
      integer, intent(in) :: n, nrhs, lda, ldb
      real(wp), intent(in) :: a(lda, *)
      integer, intent(in) :: ipiv(*)
      real(wp), intent(inout) :: b(ldb, *)
      integer, intent(out) :: info
    end subroutine dgetrs
  end interface

end module kf_blas
