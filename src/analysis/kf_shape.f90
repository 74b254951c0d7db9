!> Shape observables of a chain (PHYSICS.md section 6).
module kf_shape
  use kf_kinds, only: wp
  use kf_error, only: error_t
  use kf_symmetric_eigen, only: symmetric_eigen
  implicit none
  private

  real(wp), parameter, public :: close_pair_distance = 1.05_wp

  !> Observables of one configuration.
  type, public :: shape_t
    real(wp) :: rg = 0.0_wp        !< radius of gyration
    real(wp) :: a = 0.0_wp, b = 0.0_wp, c = 0.0_wp !< semi-axes sqrt(3 lambda_k), a >= b >= c
    real(wp) :: theta = 0.0_wp     !< angle of the principal axis from the vorticity axis y
    real(wp) :: phi = 0.0_wp       !< angle of its projection on the xz-plane, measured from z
    integer :: close_pairs = 0     !< pairs |i-j| > 1 with |r_i - r_j| < close_pair_distance
  end type shape_t

  public :: compute_shape, count_close_pairs

contains

  !> Observables of the configuration r(3, N). The principal axis is signed so that the
  !> end-to-end vector has a non-negative projection on it (so theta is in [0, pi] and
  !> phi in (-pi, pi] vary continuously while the chain does not flip end over end).
  subroutine compute_shape(r, s, error)
    real(wp), intent(in) :: r(:, :)
    type(shape_t), intent(out) :: s
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: centre(3), t(3, 3), lam(3), e1(3), dr(3)
    integer :: n, i
    n = size(r, 2)
    centre = sum(r, dim=2)/n
    ! T_nm = (1/2N^2) sum_ij (r_i - r_j)_n (r_i - r_j)_m = (1/N) sum_i (r_i - c)_n (r_i - c)_m
    t = 0.0_wp
    do i = 1, n
      dr = r(:, i) - centre
      t = t + spread(dr, 2, 3)*spread(dr, 1, 3)
    end do
    t = t/n
    call symmetric_eigen(t, lam, error)
    if (allocated(error)) return
    lam = max(lam, 0.0_wp)              ! ascending: lam(3) is the largest
    s%rg = sqrt(sum(lam))
    s%a = sqrt(3.0_wp*lam(3))
    s%b = sqrt(3.0_wp*lam(2))
    s%c = sqrt(3.0_wp*lam(1))
    e1 = t(:, 3)
    if (dot_product(e1, r(:, n) - r(:, 1)) < 0.0_wp) e1 = -e1
    s%theta = acos(max(-1.0_wp, min(1.0_wp, e1(2))))
    s%phi = atan2(e1(1), e1(3))
    s%close_pairs = count_close_pairs(r)
  end subroutine compute_shape

  !> Number of pairs i < j with j - i > 1 and |r_i - r_j| < close_pair_distance.
  pure integer function count_close_pairs(r) result(np)
    real(wp), intent(in) :: r(:, :)
    integer :: i, j
    real(wp) :: d2
    np = 0
    do j = 3, size(r, 2)
      do i = 1, j - 2
        d2 = sum((r(:, i) - r(:, j))**2)
        if (d2 < close_pair_distance**2) np = np + 1
      end do
    end do
  end function count_close_pairs

end module kf_shape
