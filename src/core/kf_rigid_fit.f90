!> The rigid motion that best maps one point set onto another (least squares, Horn 1987:
!> "Closed-form solution of absolute orientation using unit quaternions", J. Opt. Soc. Am. A 4,
!> 629). For points a_i, b_i with centroids ca, cb the rotation Q minimises
!> sum_i |Q (a_i - ca) - (b_i - cb)|^2; it is the rotation of the unit quaternion that is the
!> eigenvector of the largest eigenvalue of Horn's symmetric 4 x 4 matrix. A proper rotation
!> always (no reflection), also for collinear or planar sets (then one of the best ones).
module kf_rigid_fit
  use kf_kinds, only: wp
  use kf_error, only: error_t
  use kf_symmetric_eigen, only: symmetric_eigen
  implicit none
  private

  public :: best_rotation, centroid, rotate_blocks

contains

  !> Mean of the columns of p(3, N).
  pure function centroid(p) result(c)
    real(wp), intent(in) :: p(:, :)
    real(wp) :: c(3)
    c = sum(p, dim=2)/real(max(1, size(p, 2)), wp)
  end function centroid

  !> Rotation q (3 x 3) with b_i - cb ~ q (a_i - ca), ca and cb the centroids of a and b (3, N).
  subroutine best_rotation(a, b, q, error)
    real(wp), intent(in) :: a(:, :), b(:, :)
    real(wp), intent(out) :: q(3, 3)
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: ca(3), cb(3), s(3, 3), hm(4, 4), w(4), e(4)
    integer :: i
    ca = centroid(a)
    cb = centroid(b)
    s = 0.0_wp
    do i = 1, size(a, 2)
      s = s + spread(a(:, i) - ca, 2, 3)*spread(b(:, i) - cb, 1, 3)
    end do
    ! s(x, y) = sum a_x b_y; Horn's matrix.
    hm(1, :) = [s(1, 1) + s(2, 2) + s(3, 3), s(2, 3) - s(3, 2), s(3, 1) - s(1, 3), s(1, 2) - s(2, 1)]
    hm(2, :) = [s(2, 3) - s(3, 2), s(1, 1) - s(2, 2) - s(3, 3), s(1, 2) + s(2, 1), s(3, 1) + s(1, 3)]
    hm(3, :) = [s(3, 1) - s(1, 3), s(1, 2) + s(2, 1), -s(1, 1) + s(2, 2) - s(3, 3), s(2, 3) + s(3, 2)]
    hm(4, :) = [s(1, 2) - s(2, 1), s(3, 1) + s(1, 3), s(2, 3) + s(3, 2), -s(1, 1) - s(2, 2) + s(3, 3)]
    call symmetric_eigen(hm, w, error)
    if (allocated(error)) return
    e = hm(:, 4)/norm2(hm(:, 4))
    q(1, :) = [e(1)**2 + e(2)**2 - e(3)**2 - e(4)**2, 2*(e(2)*e(3) - e(1)*e(4)), 2*(e(2)*e(4) + e(1)*e(3))]
    q(2, :) = [2*(e(3)*e(2) + e(1)*e(4)), e(1)**2 - e(2)**2 + e(3)**2 - e(4)**2, 2*(e(3)*e(4) - e(1)*e(2))]
    q(3, :) = [2*(e(4)*e(2) - e(1)*e(3)), 2*(e(4)*e(3) + e(1)*e(2)), e(1)**2 - e(2)**2 - e(3)**2 + e(4)**2]
  end subroutine best_rotation

  !> zo = Q zi Q^T for every 3 x 3 block of zi (square, of size a multiple of 3): a matrix that
  !> maps per-point 3-vectors onto per-point 3-vectors (a mobility, a friction with translations
  !> and rotations alike) for the point set rotated by q.
  pure subroutine rotate_blocks(q, zi, zo)
    real(wp), intent(in) :: q(3, 3), zi(:, :)
    real(wp), intent(out) :: zo(:, :)
    integer :: a, b, nb3
    nb3 = size(zi, 1)/3
    do b = 1, nb3
      do a = 1, nb3
        zo(3*a - 2:3*a, 3*b - 2:3*b) = matmul(q, matmul(zi(3*a - 2:3*a, 3*b - 2:3*b), transpose(q)))
      end do
    end do
  end subroutine rotate_blocks

end module kf_rigid_fit
