!> Rotne-Prager-Yamakawa mobility with the overlapping-sphere form (Wajnryb, Mizerski, Zuk,
!> Szymczak, J. Fluid Mech. 731, R3 (2013)) and the matching shear disturbance C:E
!> (PHYSICS.md 3.2). Units: d = 1, isolated-bead mobility 1/3; r_hat = (r_i - r_j)/r.
!>   r >= 1: mu_ij = 1/(8r) [ (1 + 1/(6r^2)) I + (1 - 1/(2r^2)) r_hat r_hat ]
!>   r <  1: mu_ij = 1/3 [ (1 - 9r/16) I + (3r/16) r_hat r_hat ]
!>   r >= 1: C_ij:E = -1/(12 r^4) E r_hat - 5/(16 r^2) (1 - 2/(3r^2)) (r_hat.E.r_hat) r_hat
!>   r <  1: C_ij:E = (5r^2/12 - r/2) E r_hat - (5r^2/48) (r_hat.E.r_hat) r_hat
!> prepare() only copies the positions (structure of arrays); apply_mobility and
!> add_strain_disturbance are single pair loops over i < j that use the symmetry of the pair
!> (mu_ji = mu_ij, C_ji:E = -C_ij:E) and allocate nothing. This is faster than assembling the
!> 3N x 3N matrix and applying it with DSYMV (measured with knotflow-bench, see the README).
module kf_hydro_rpy
  use kf_kinds, only: wp
  use kf_error, only: error_t
  use kf_hydro_model, only: hydro_model_t
  implicit none
  private

  public :: rpy_pair_coefficients, rpy_strain_coefficients

  !> RPY model; holds the bead positions of the last prepare.
  type, extends(hydro_model_t), public :: rpy_model_t
    real(wp), allocatable :: x(:), y(:), z(:)
  contains
    procedure :: prepare => rpy_prepare
    procedure :: apply_mobility => rpy_apply
    procedure :: add_strain_disturbance => rpy_disturb
    procedure :: name => rpy_name
    procedure :: mobility_matrix => rpy_mobility_matrix
  end type rpy_model_t

  real(wp), parameter :: third = 1.0_wp/3.0_wp

contains

  !> For a separation vector d with |d|^2 = r2 > 0: mu_ij = a I + bb d d^T.
  elemental subroutine rpy_pair_coefficients(r2, a, bb)
    real(wp), intent(in) :: r2
    real(wp), intent(out) :: a, bb
    real(wp) :: rinv, rinv2, r
    rinv = 1.0_wp/sqrt(r2)
    rinv2 = rinv*rinv
    if (r2 >= 1.0_wp) then
      a = 0.125_wp*rinv*(1.0_wp + rinv2/6.0_wp)
      bb = 0.125_wp*rinv*rinv2*(1.0_wp - 0.5_wp*rinv2)
    else
      r = r2*rinv
      a = third*(1.0_wp - 0.5625_wp*r)
      bb = rinv/16.0_wp
    end if
  end subroutine rpy_pair_coefficients

  !> For a separation vector d with |d|^2 = r2 > 0: C_ij:E = c1 E d + c2 (d.E.d) d.
  elemental subroutine rpy_strain_coefficients(r2, c1, c2)
    real(wp), intent(in) :: r2
    real(wp), intent(out) :: c1, c2
    real(wp) :: rinv, rinv2, rinv5, r
    rinv = 1.0_wp/sqrt(r2)
    rinv2 = rinv*rinv
    if (r2 >= 1.0_wp) then
      rinv5 = rinv2*rinv2*rinv
      c1 = -rinv5/12.0_wp
      c2 = -(5.0_wp/16.0_wp)*rinv5*(1.0_wp - (2.0_wp/3.0_wp)*rinv2)
    else
      r = r2*rinv
      c1 = (5.0_wp/12.0_wp)*r - 0.5_wp
      c2 = -(5.0_wp/48.0_wp)*rinv
    end if
  end subroutine rpy_strain_coefficients

  subroutine rpy_prepare(this, r, error)
    class(rpy_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer :: n
    n = size(r, 2)
    if (.not. allocated(this%x)) then
      allocate (this%x(n), this%y(n), this%z(n))
    else if (size(this%x) /= n) then
      deallocate (this%x, this%y, this%z)
      allocate (this%x(n), this%y(n), this%z(n))
    end if
    this%n = n
    this%x = r(1, :)
    this%y = r(2, :)
    this%z = r(3, :)
  end subroutine rpy_prepare

  !> u = mu f. Coincident beads (r = 0) take the limit mu_ij = I/3.
  subroutine rpy_apply(this, f, u)
    class(rpy_model_t), intent(inout) :: this
    real(wp), intent(in) :: f(:, :)
    real(wp), intent(out) :: u(:, :)
    integer :: i, j, n
    real(wp) :: xi, yi, zi, fxi, fyi, fzi, uxi, uyi, uzi, dx, dy, dz, r2, a, bb, rinv, rinv2, r
    real(wp) :: df_j, df_i
    n = this%n
    u = f*third
    do i = 1, n - 1
      xi = this%x(i)
      yi = this%y(i)
      zi = this%z(i)
      fxi = f(1, i)
      fyi = f(2, i)
      fzi = f(3, i)
      uxi = 0.0_wp
      uyi = 0.0_wp
      uzi = 0.0_wp
      do j = i + 1, n
        dx = xi - this%x(j)
        dy = yi - this%y(j)
        dz = zi - this%z(j)
        r2 = dx*dx + dy*dy + dz*dz
        if (r2 >= 1.0_wp) then
          rinv = 1.0_wp/sqrt(r2)
          rinv2 = rinv*rinv
          a = 0.125_wp*rinv*(1.0_wp + rinv2*(1.0_wp/6.0_wp))
          bb = 0.125_wp*rinv*rinv2*(1.0_wp - 0.5_wp*rinv2)
        else if (r2 > 0.0_wp) then
          rinv = 1.0_wp/sqrt(r2)
          r = r2*rinv
          a = third*(1.0_wp - 0.5625_wp*r)
          bb = 0.0625_wp*rinv
        else
          a = third
          bb = 0.0_wp
        end if
        df_j = bb*(dx*f(1, j) + dy*f(2, j) + dz*f(3, j))
        df_i = bb*(dx*fxi + dy*fyi + dz*fzi)
        uxi = uxi + a*f(1, j) + df_j*dx
        uyi = uyi + a*f(2, j) + df_j*dy
        uzi = uzi + a*f(3, j) + df_j*dz
        u(1, j) = u(1, j) + a*fxi + df_i*dx
        u(2, j) = u(2, j) + a*fyi + df_i*dy
        u(3, j) = u(3, j) + a*fzi + df_i*dz
      end do
      u(1, i) = u(1, i) + uxi
      u(2, i) = u(2, i) + uyi
      u(3, i) = u(3, i) + uzi
    end do
  end subroutine rpy_apply

  !> u = u + C:E (coincident beads add nothing).
  subroutine rpy_disturb(this, e, u)
    class(rpy_model_t), intent(inout) :: this
    real(wp), intent(in) :: e(3, 3)
    real(wp), intent(inout) :: u(:, :)
    integer :: i, j, n
    real(wp) :: xi, yi, zi, dx, dy, dz, r2, c1, c2, rinv, rinv2, rinv5, r
    real(wp) :: ed(3), ded, w(3), uxi, uyi, uzi
    real(wp) :: e11, e12, e13, e22, e23, e33
    n = this%n
    e11 = e(1, 1)
    e12 = 0.5_wp*(e(1, 2) + e(2, 1))
    e13 = 0.5_wp*(e(1, 3) + e(3, 1))
    e22 = e(2, 2)
    e23 = 0.5_wp*(e(2, 3) + e(3, 2))
    e33 = e(3, 3)
    do i = 1, n - 1
      xi = this%x(i)
      yi = this%y(i)
      zi = this%z(i)
      uxi = 0.0_wp
      uyi = 0.0_wp
      uzi = 0.0_wp
      do j = i + 1, n
        dx = xi - this%x(j)
        dy = yi - this%y(j)
        dz = zi - this%z(j)
        r2 = dx*dx + dy*dy + dz*dz
        if (r2 >= 1.0_wp) then
          rinv = 1.0_wp/sqrt(r2)
          rinv2 = rinv*rinv
          rinv5 = rinv2*rinv2*rinv
          c1 = -rinv5*(1.0_wp/12.0_wp)
          c2 = -(5.0_wp/16.0_wp)*rinv5*(1.0_wp - (2.0_wp/3.0_wp)*rinv2)
        else if (r2 > 0.0_wp) then
          rinv = 1.0_wp/sqrt(r2)
          r = r2*rinv
          c1 = (5.0_wp/12.0_wp)*r - 0.5_wp
          c2 = -(5.0_wp/48.0_wp)*rinv
        else
          c1 = 0.0_wp
          c2 = 0.0_wp
        end if
        ed(1) = e11*dx + e12*dy + e13*dz
        ed(2) = e12*dx + e22*dy + e23*dz
        ed(3) = e13*dx + e23*dy + e33*dz
        ded = dx*ed(1) + dy*ed(2) + dz*ed(3)
        w(1) = c1*ed(1) + c2*ded*dx
        w(2) = c1*ed(2) + c2*ded*dy
        w(3) = c1*ed(3) + c2*ded*dz
        uxi = uxi + w(1)
        uyi = uyi + w(2)
        uzi = uzi + w(3)
        u(1, j) = u(1, j) - w(1)
        u(2, j) = u(2, j) - w(2)
        u(3, j) = u(3, j) - w(3)
      end do
      u(1, i) = u(1, i) + uxi
      u(2, i) = u(2, i) + uyi
      u(3, i) = u(3, i) + uzi
    end do
  end subroutine rpy_disturb

  function rpy_name(this) result(label)
    class(rpy_model_t), intent(in) :: this
    character(len=:), allocatable :: label
    label = 'rpy'
  end function rpy_name

  !> The full 3N x 3N mobility, built pair by pair (after prepare).
  subroutine rpy_mobility_matrix(this, mu)
    class(rpy_model_t), intent(inout) :: this
    real(wp), intent(out) :: mu(:, :)
    integer :: i, j, p, q
    real(wp) :: d(3), r2, a, bb, blk(3, 3)
    mu = 0.0_wp
    do i = 1, this%n
      do p = 1, 3
        mu(3*(i - 1) + p, 3*(i - 1) + p) = third
      end do
      do j = i + 1, this%n
        d = [this%x(i) - this%x(j), this%y(i) - this%y(j), this%z(i) - this%z(j)]
        r2 = sum(d**2)
        if (r2 > 0.0_wp) then
          call rpy_pair_coefficients(r2, a, bb)
        else
          a = third
          bb = 0.0_wp
        end if
        do q = 1, 3
          do p = 1, 3
            blk(p, q) = bb*(d(p)*d(q))
          end do
          blk(q, q) = blk(q, q) + a
        end do
        mu(3*(i - 1) + 1:3*i, 3*(j - 1) + 1:3*j) = blk
        mu(3*(j - 1) + 1:3*j, 3*(i - 1) + 1:3*i) = blk
      end do
    end do
  end subroutine rpy_mobility_matrix

end module kf_hydro_rpy
