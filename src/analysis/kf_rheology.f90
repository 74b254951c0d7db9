!> The fibre's stresslet and its rheological observables in simple shear (docs/case-file.md, the stresslet).
!>
!> A dilute suspension of fibres at number density n adds n <S> to the fluid's stress, S the
!> fibre's stresslet: the sum of the beads' hydrodynamic stresslets (about their own centres,
!> from the hydrodynamic model, kf_hydro_model `stresslet`) plus the elastic (Kramers-Kirkwood)
!> part, the symmetric traceless part of -sum_i (r_i - r_c) F_i with F_i the non-hydrodynamic
!> force on bead i (which the bead passes on to the fluid) and r_c the centroid (the isotropic
!> part is a pressure and does not enter S). Batchelor's sign: an isolated rigid sphere in the
!> strain E has S = (20/3) pi eta a^3 E. Units pi eta d^3 gamma_dot.
!>
!> Observables for simple shear v0 = (gamma_dot z, 0, 0) (x flow, z gradient, y vorticity), in
!> intrinsic-viscosity form normalised by the beads' total volume V = N pi d^3 / 6:
!>   viscosity = S_xz / (eta gamma_dot V) = 6 S_xz / (N gamma_dot)   (free far-apart beads: 5/2)
!>   psi1 = (S_xx - S_zz) / (eta gamma_dot^2 V) = 6 (S_xx - S_zz) / (N gamma_dot^2)
!>   psi2 = (S_zz - S_yy) / (eta gamma_dot^2 V) = 6 (S_zz - S_yy) / (N gamma_dot^2)
!> (the suspension's eta_p = eta phi viscosity, Psi_1 = eta phi psi1 with phi = n V).
module kf_rheology
  use kf_kinds, only: wp
  implicit none
  private

  public :: elastic_stresslet, shear_observables, symmetric_traceless

  !> The fibre's stresslet at one frame and its observables.
  type, public :: fibre_stresslet_t
    real(wp) :: hydrodynamic(3, 3) = 0.0_wp !< sum of the beads' hydrodynamic stresslets
    real(wp) :: elastic(3, 3) = 0.0_wp      !< Kramers-Kirkwood part
    real(wp) :: viscosity = 0.0_wp          !< intrinsic-viscosity form (see the module header)
    real(wp) :: psi1 = 0.0_wp               !< first normal-stress-difference coefficient
    real(wp) :: psi2 = 0.0_wp               !< second normal-stress-difference coefficient
  end type fibre_stresslet_t

contains

  !> The symmetric traceless part of a 3 x 3 tensor.
  pure function symmetric_traceless(a) result(s)
    real(wp), intent(in) :: a(3, 3)
    real(wp) :: s(3, 3)
    integer :: i
    s = 0.5_wp*(a + transpose(a))
    do i = 1, 3
      s(i, i) = s(i, i) - (a(1, 1) + a(2, 2) + a(3, 3))/3.0_wp
    end do
  end function symmetric_traceless

  !> Elastic (Kramers-Kirkwood) stresslet of beads at r(3, N) with non-hydrodynamic forces
  !> f(3, N): the symmetric traceless part of -sum_i (r_i - r_c) f_i^T, r_c the centroid.
  pure function elastic_stresslet(r, f) result(s)
    real(wp), intent(in) :: r(:, :), f(:, :)
    real(wp) :: s(3, 3)
    real(wp) :: a(3, 3), c(3)
    integer :: i, j
    c = sum(r, dim=2)/real(size(r, 2), wp)
    a = 0.0_wp
    do i = 1, size(r, 2)
      do j = 1, 3
        a(:, j) = a(:, j) - (r(:, i) - c)*f(j, i)
      end do
    end do
    s = symmetric_traceless(a)
  end function elastic_stresslet

  !> Viscosity and normal-stress coefficients of `st` (both parts) for N beads in simple shear
  !> of rate gamma_dot /= 0 (module header).
  pure subroutine shear_observables(st, n_beads, gamma_dot)
    type(fibre_stresslet_t), intent(inout) :: st
    integer, intent(in) :: n_beads
    real(wp), intent(in) :: gamma_dot
    real(wp) :: s(3, 3), scale
    s = st%hydrodynamic + st%elastic
    scale = 6.0_wp/(real(n_beads, wp)*gamma_dot)
    st%viscosity = scale*s(1, 3)
    st%psi1 = scale*(s(1, 1) - s(3, 3))/gamma_dot
    st%psi2 = scale*(s(3, 3) - s(2, 2))/gamma_dot
  end subroutine shear_observables

end module kf_rheology
