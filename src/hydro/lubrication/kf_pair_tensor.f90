!> Cartesian two-sphere friction tensors (Jeffrey-Onishi / Kim-Karrila form, MULTIPOLE.md 12.3)
!> built from the 22 scalar resistance functions, in project units (PHYSICS.md section 1).
!>
!> Ordering of the 12x12 friction: [U_1, Omega_1, U_2, Omega_2] -> [F_1, T_1, F_2, T_2], where
!> F, T are the applied force/torque (= force/torque the sphere exerts on the fluid). The strain
!> coupling xe(12,3,3) maps a symmetric traceless E to x = zeta_FE : E with
!> [F; T] = zeta [U - U_inf; Omega - Omega_inf] - x. Sphere 1 <-> i, sphere 2 <-> j and
!> dhat = (R_j - R_i)/|R_j - R_i|. The assembly is linear in the functions, so it applies equally
!> to function differences (lubrication corrections).
module kf_pair_tensor
  use kf_kinds, only: wp
  use kf_error, only: error_t
  use kf_lapack, only: cholesky_factor, cholesky_invert
  use kf_two_sphere, only: n_functions, two_sphere_resistance, i_xa11, i_ya11, i_yb11, i_xc11, i_yc11, i_xg11, i_yg11, &
    i_yh11, i_xm11, i_xm12, i_ym11, i_ym12, i_zm11, i_zm12
  implicit none
  private

  public :: pair_tensors, pair_mobility_functions, two_sphere_mobility, pair_strain_stresslet

contains

  !> Value of the function family starting at index i11 (the "11" member) for the sphere pair
  !> (alpha, beta); odd families (B, G) change sign for alpha = 2 (f22 = s f11, f21 = s f12).
  pure real(wp) function fam(f, i11, alpha, beta, odd)
    real(wp), intent(in) :: f(n_functions)
    integer, intent(in) :: i11, alpha, beta
    logical, intent(in) :: odd
    fam = f(i11 + merge(0, 1, alpha == beta))
    if (odd .and. alpha == 2) fam = -fam
  end function fam

  !> Levi-Civita symbol.
  pure real(wp) function levi(i, j, k)
    integer, intent(in) :: i, j, k
    levi = real((i - j)*(j - k)*(k - i), wp)/2.0_wp
  end function levi

  !> Friction (12x12, symmetric) and strain coupling (12,3,3) of the pair from the functions f.
  pure subroutine pair_tensors(f, dhat, zeta, xe)
    real(wp), intent(in) :: f(n_functions)   !< resistance functions (or their differences)
    real(wp), intent(in) :: dhat(3)          !< unit vector from sphere i to sphere j
    real(wp), intent(out) :: zeta(12, 12)    !< friction, project units
    real(wp), intent(out) :: xe(12, 3, 3)    !< strain coupling, project units
    integer :: alpha, beta, i, j, k, l, rf, rt, cu, co
    real(wp) :: delta(3, 3), xa, ya, yb, xc, yc, xg, yg, yh, bsum, hsum

    delta = 0.0_wp
    do i = 1, 3
      delta(i, i) = 1.0_wp
    end do
    zeta = 0.0_wp
    xe = 0.0_wp
    do alpha = 1, 2
      rf = 6*(alpha - 1)
      rt = rf + 3
      do beta = 1, 2
        cu = 6*(beta - 1)
        co = cu + 3
        xa = 3.0_wp*fam(f, i_xa11, alpha, beta, .false.)
        ya = 3.0_wp*fam(f, i_ya11, alpha, beta, .false.)
        xc = fam(f, i_xc11, alpha, beta, .false.)
        yc = fam(f, i_yc11, alpha, beta, .false.)
        do i = 1, 3
          do j = 1, 3
            ! A^{alpha beta}_ij and C^{alpha beta}_ij.
            zeta(rf + i, cu + j) = xa*dhat(i)*dhat(j) + ya*(delta(i, j) - dhat(i)*dhat(j))
            zeta(rt + i, co + j) = xc*dhat(i)*dhat(j) + yc*(delta(i, j) - dhat(i)*dhat(j))
            ! B^{alpha beta}_ij = Y^B_{alpha beta} eps_ijk d_k (torque alpha <- velocity beta).
            yb = fam(f, i_yb11, alpha, beta, .true.)
            bsum = 0.0_wp
            do k = 1, 3
              bsum = bsum + levi(i, j, k)*dhat(k)
            end do
            zeta(rt + i, cu + j) = yb*bsum
          end do
        end do
      end do
    end do
    ! Btilde^{alpha beta}_ij = B^{beta alpha}_ji: the force <- rotation blocks by symmetry.
    do alpha = 1, 2
      do beta = 1, 2
        do i = 1, 3
          do j = 1, 3
            zeta(6*(alpha - 1) + i, 6*(beta - 1) + 3 + j) = zeta(6*(beta - 1) + 3 + j, 6*(alpha - 1) + i)
          end do
        end do
      end do
    end do
    ! Strain coupling: x(F_alpha,i) = sum_beta G^{beta alpha}_{jki} E_jk,
    ! x(T_alpha,i) = sum_beta H^{beta alpha}_{jki} E_jk.
    do alpha = 1, 2
      rf = 6*(alpha - 1)
      rt = rf + 3
      do beta = 1, 2
        xg = fam(f, i_xg11, beta, alpha, .true.)
        yg = fam(f, i_yg11, beta, alpha, .true.)
        yh = fam(f, i_yh11, beta, alpha, .false.)
        do i = 1, 3
          do j = 1, 3
            do k = 1, 3
              xe(rf + i, j, k) = xe(rf + i, j, k) &
                + xg*(dhat(j)*dhat(k) - delta(j, k)/3.0_wp)*dhat(i) &
                + yg*(dhat(j)*delta(k, i) + dhat(k)*delta(j, i) - 2.0_wp*dhat(j)*dhat(k)*dhat(i))
              hsum = 0.0_wp
              do l = 1, 3
                hsum = hsum + levi(j, i, l)*dhat(l)*dhat(k) + levi(k, i, l)*dhat(l)*dhat(j)
              end do
              xe(rt + i, j, k) = xe(rt + i, j, k) + yh*hsum
            end do
          end do
        end do
      end do
    end do
  end subroutine pair_tensors

  !> The sum of the two spheres' stresslets S_1 + S_2 due to the strain E at rest (U = U_inf,
  !> Omega = Omega_inf) from the M functions of f (Kim & Karrila 11.3, Jeffrey 1992:
  !> S_alpha = (20/3) pi eta a^3 sum_beta M^{alpha beta} : E), project units pi eta d^3 (an
  !> isolated sphere has (5/6) E; f22 = f11, f21 = f12 for equal spheres). Per pair member,
  !> with Q = d.E.d and e = E.d, M : E = (3/2) X^M (d d - I/3) Q + Y^M (d e + e d - 2 d d Q)
  !> + Z^M (E + I Q/2 + d d Q/2 - d e - e d) for symmetric traceless E.
  pure function pair_strain_stresslet(f, dhat, e) result(s)
    real(wp), intent(in) :: f(n_functions)   !< resistance functions (or their differences)
    real(wp), intent(in) :: dhat(3)          !< unit vector along the line of centres
    real(wp), intent(in) :: e(3, 3)          !< symmetric traceless rate of strain
    real(wp) :: s(3, 3)
    real(wp) :: xm, ym, zm, q, ev(3), de(3, 3), dd(3, 3), eye(3, 3)
    integer :: i
    eye = 0.0_wp
    do i = 1, 3
      eye(i, i) = 1.0_wp
    end do
    xm = f(i_xm11) + f(i_xm12)
    ym = f(i_ym11) + f(i_ym12)
    zm = f(i_zm11) + f(i_zm12)
    ev = matmul(e, dhat)
    q = dot_product(dhat, ev)
    dd = spread(dhat, 2, 3)*spread(dhat, 1, 3)
    de = spread(dhat, 2, 3)*spread(ev, 1, 3)
    de = de + transpose(de)
    s = 1.5_wp*xm*(dd - eye/3.0_wp)*q + ym*(de - 2.0_wp*dd*q) + zm*(e + 0.5_wp*eye*q + 0.5_wp*dd*q - de)
    s = 2.0_wp*(5.0_wp/6.0_wp)*s
  end function pair_strain_stresslet

  !> Normalised mobility functions [x11a, x12a, y11a, y12a] of two torque-free spheres
  !> (3 mu_xx(1,1), 3 mu_xx(1,2), 3 mu_yy(1,1), 3 mu_yy(1,2); x along the line of centres)
  !> obtained by inverting the 12x12 pair friction built from the resistance functions f.
  subroutine pair_mobility_functions(f, mob, error)
    real(wp), intent(in) :: f(n_functions)
    real(wp), intent(out) :: mob(4)
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: zeta(12, 12), xe(12, 3, 3)
    call pair_tensors(f, [0.0_wp, 0.0_wp, 1.0_wp], zeta, xe)
    call cholesky_factor(zeta, error, 'two-sphere friction')
    if (.not. allocated(error)) call cholesky_invert(zeta, error, 'two-sphere friction')
    if (allocated(error)) then
      mob = 0.0_wp
      return
    end if
    mob = 3.0_wp*[zeta(3, 3), zeta(3, 9), zeta(1, 1), zeta(1, 7)]
  end subroutine pair_mobility_functions

  !> Mobility functions [x11a, x12a, y11a, y12a] of the pair at centre distance r (units of d),
  !> multipole truncated at `order` (the inverse of the order-L pair friction, i.e. the Schur
  !> complement of the multipole system onto forces and torques).
  subroutine two_sphere_mobility(r, order, mob, error)
    real(wp), intent(in) :: r
    integer, intent(in) :: order
    real(wp), intent(out) :: mob(4)
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: f(n_functions)
    mob = 0.0_wp
    call two_sphere_resistance(r, order, f, error)
    if (allocated(error)) return
    call pair_mobility_functions(f, mob, error)
  end subroutine two_sphere_mobility

end module kf_pair_tensor
