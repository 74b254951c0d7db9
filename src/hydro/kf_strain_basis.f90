!> The five basis strains of symmetric traceless 3 x 3 tensors used by the hydrodynamic models
!> (coefficients of a rate of strain, strain couplings stored per basis strain) and the way back
!> from the five pairings S:B_k to a symmetric traceless tensor S.
module kf_strain_basis
  use kf_kinds, only: wp
  implicit none
  private

  public :: strain_basis, strain_coefficients, tensor_from_pairings

contains

  !> Basis strain k = 1..5: xx-zz, yy-zz, xy+yx, xz+zx, yz+zy.
  pure function strain_basis(k) result(e)
    integer, intent(in) :: k
    real(wp) :: e(3, 3)
    e = 0.0_wp
    select case (k)
    case (1)
      e(1, 1) = 1.0_wp
      e(3, 3) = -1.0_wp
    case (2)
      e(2, 2) = 1.0_wp
      e(3, 3) = -1.0_wp
    case (3)
      e(1, 2) = 1.0_wp
      e(2, 1) = 1.0_wp
    case (4)
      e(1, 3) = 1.0_wp
      e(3, 1) = 1.0_wp
    case (5)
      e(2, 3) = 1.0_wp
      e(3, 2) = 1.0_wp
    end select
  end function strain_basis

  !> Coefficients of a symmetric traceless strain in the basis of `strain_basis`:
  !> e = sum_k c(k) strain_basis(k).
  pure function strain_coefficients(e) result(c)
    real(wp), intent(in) :: e(3, 3)
    real(wp) :: c(5)
    c = [e(1, 1), e(2, 2), 0.5_wp*(e(1, 2) + e(2, 1)), 0.5_wp*(e(1, 3) + e(3, 1)), &
         0.5_wp*(e(2, 3) + e(3, 2))]
  end function strain_coefficients

  !> The symmetric traceless tensor s with s : strain_basis(k) = m(k), k = 1..5
  !> (m = [s11 - s33, s22 - s33, 2 s12, 2 s13, 2 s23]).
  pure function tensor_from_pairings(m) result(s)
    real(wp), intent(in) :: m(5)
    real(wp) :: s(3, 3)
    s(3, 3) = -(m(1) + m(2))/3.0_wp
    s(1, 1) = m(1) + s(3, 3)
    s(2, 2) = m(2) + s(3, 3)
    s(1, 2) = 0.5_wp*m(3)
    s(2, 1) = s(1, 2)
    s(1, 3) = 0.5_wp*m(4)
    s(3, 1) = s(1, 3)
    s(2, 3) = 0.5_wp*m(5)
    s(3, 2) = s(2, 3)
  end function tensor_from_pairings

end module kf_strain_basis
