!> Eigenvalues and eigenvectors of a small real symmetric matrix (the 3 x 3 gyration tensor of
!> kf_shape, the 4 x 4 quaternion matrix of kf_rigid_fit) by the cyclic Jacobi method.
!>
!> Written here rather than taken from LAPACK's dsyev because a threaded BLAS (OpenBLAS) makes
!> dsyev's last bits depend on the number of BLAS threads, which knotflow chooses from the
!> machine's load at start-up: the recorded shape of a case resumed with another thread count
!> would then differ from the uninterrupted run. Jacobi rotations touch the matrix in a fixed
!> order, so the result is the same bit for bit on every run of one binary, and it is accurate to
!> a few units in the last place of the largest eigenvalue (the rotations are orthogonal).
module kf_symmetric_eigen
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp
  use kf_error, only: error_t, fatal_error
  use kf_strings, only: to_str
  use kf_vector_ops, only: sort_index
  implicit none
  private

  public :: symmetric_eigen

  integer, parameter :: max_sweeps = 60   !< quadratic convergence: a few sweeps suffice

contains

  !> Eigenvalues w (ascending) of the symmetric matrix a (its lower triangle is read) and, in
  !> the columns of a, orthonormal eigenvectors in the same order.
  subroutine symmetric_eigen(a, w, error)
    real(wp), intent(inout) :: a(:, :)
    real(wp), intent(out) :: w(:)
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: v(:, :)
    real(wp) :: negligible
    integer :: n, i, j, sweep, order(size(w))
    logical :: rotated

    n = size(a, 1)
    if (size(a, 2) /= n .or. size(w) /= n) then
      call fatal_error(error, 'symmetric_eigen: a must be square and w of its order (a is '// &
        to_str(size(a, 1))//' x '//to_str(size(a, 2))//', w has '//to_str(size(w))//')')
      return
    end if
    do j = 1, n
      if (.not. all(ieee_is_finite(a(j:n, j)))) then
        call fatal_error(error, 'symmetric_eigen: the matrix has a non-finite entry in column '// &
          to_str(j))
        return
      end if
    end do
    do j = 2, n
      a(1:j - 1, j) = a(j, 1:j - 1)
    end do
    allocate (v(n, n))
    v = 0.0_wp
    do i = 1, n
      v(i, i) = 1.0_wp
    end do
    ! below this, an off-diagonal entry moves no eigenvalue by more than eps**2 |A|
    negligible = epsilon(1.0_wp)**2*sqrt(sum(a**2))
    do sweep = 1, max_sweeps
      rotated = .false.
      do j = 2, n
        do i = 1, j - 1
          if (abs(a(i, j)) <= negligible) cycle
          if (abs(a(i, j)) <= epsilon(1.0_wp)*sqrt(abs(a(i, i))*abs(a(j, j)))) cycle
          call rotate(a, v, i, j)
          rotated = .true.
        end do
      end do
      if (.not. rotated) exit
    end do
    if (rotated) then   ! not seen: Jacobi converges quadratically for finite entries
      call fatal_error(error, 'symmetric_eigen: Jacobi rotations did not converge in '// &
        to_str(max_sweeps)//' sweeps')
      return
    end if
    do i = 1, n
      w(i) = a(i, i)
    end do
    order = sort_index(w)
    w = w(order)
    a = v(:, order)
  end subroutine symmetric_eigen

  !> The Jacobi rotation in the (p, q) plane that zeroes a(p, q): a <- J^T a J, v <- v J.
  pure subroutine rotate(a, v, p, q)
    real(wp), intent(inout) :: a(:, :), v(:, :)
    integer, intent(in) :: p, q
    real(wp) :: theta, t, c, s, apq, col_p(size(a, 1)), col_q(size(a, 1))
    apq = a(p, q)
    theta = (a(q, q) - a(p, p))/(2.0_wp*apq)
    ! t = tan of the rotation angle, the smaller root of t^2 + 2 theta t - 1 = 0
    if (abs(theta) > 1.0e150_wp) then
      t = 0.5_wp/theta
    else
      t = sign(1.0_wp, theta)/(abs(theta) + sqrt(theta**2 + 1.0_wp))
    end if
    c = 1.0_wp/sqrt(t**2 + 1.0_wp)
    s = t*c
    col_p = a(:, p)
    col_q = a(:, q)
    a(:, p) = c*col_p - s*col_q
    a(:, q) = s*col_p + c*col_q
    a(p, :) = a(:, p)
    a(q, :) = a(:, q)
    a(p, p) = col_p(p) - t*apq
    a(q, q) = col_q(q) + t*apq
    a(p, q) = 0.0_wp
    a(q, p) = 0.0_wp
    col_p = v(:, p)
    col_q = v(:, q)
    v(:, p) = c*col_p - s*col_q
    v(:, q) = s*col_p + c*col_q
  end subroutine rotate

end module kf_symmetric_eigen
