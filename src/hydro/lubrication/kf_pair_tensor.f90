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

  !> Friction (12x12, symmetric) and strain coupling (12,3,3) of the pair from the functions f.
  !> The direction's tensors are formed once per pair: dd = d d, ed_ij = eps_ijk d_k and the three
  !> strain-coupling forms t1..t3 (below); each block is then a combination of them with the
  !> pair's functions.
  pure subroutine pair_tensors(f, dhat, zeta, xe)
    real(wp), intent(in) :: f(n_functions)   !< resistance functions (or their differences)
    real(wp), intent(in) :: dhat(3)          !< unit vector from sphere i to sphere j
    real(wp), intent(out) :: zeta(12, 12)    !< friction, project units
    real(wp), intent(out) :: xe(12, 3, 3)    !< strain coupling, project units
    integer :: alpha, beta, i, j, k, rf, rt, cu, co
    real(wp) :: delta(3, 3), dd(3, 3), ed(3, 3), t1(3, 3, 3), t2(3, 3, 3), t3(3, 3, 3)
    real(wp) :: xa, ya, yb, xc, yc, xg, yg, yh

    delta = 0.0_wp
    do i = 1, 3
      delta(i, i) = 1.0_wp
    end do
    do j = 1, 3
      dd(:, j) = dhat*dhat(j)
    end do
    ! ed_ij = sum_k eps_ijk d_k
    ed = reshape([0.0_wp, -dhat(3), dhat(2), dhat(3), 0.0_wp, -dhat(1), -dhat(2), dhat(1), 0.0_wp], [3, 3])
    ! t1 = (d_j d_k - delta_jk / 3) d_i (X^G), t2 = d_j delta_ki + d_k delta_ji - 2 d_i d_j d_k
    ! (Y^G), t3 = sum_l (eps_jil d_l d_k + eps_kil d_l d_j) = ed_ji d_k + ed_ki d_j (Y^H)
    do k = 1, 3
      do j = 1, 3
        do i = 1, 3
          t1(i, j, k) = (dd(j, k) - delta(j, k)/3.0_wp)*dhat(i)
          t2(i, j, k) = dhat(j)*delta(k, i) + dhat(k)*delta(j, i) - 2.0_wp*dhat(i)*dd(j, k)
          t3(i, j, k) = ed(j, i)*dhat(k) + ed(k, i)*dhat(j)
        end do
      end do
    end do
    zeta = 0.0_wp
    xe = 0.0_wp
    do alpha = 1, 2
      rf = 6*(alpha - 1)
      rt = rf + 3
      do beta = 1, 2
        cu = 6*(beta - 1)
        co = cu + 3
        ! A^{alpha beta}, C^{alpha beta}, and B^{alpha beta}_ij = Y^B eps_ijk d_k (torque alpha <-
        ! velocity beta)
        xa = 3.0_wp*fam(f, i_xa11, alpha, beta, .false.)
        ya = 3.0_wp*fam(f, i_ya11, alpha, beta, .false.)
        xc = fam(f, i_xc11, alpha, beta, .false.)
        yc = fam(f, i_yc11, alpha, beta, .false.)
        yb = fam(f, i_yb11, alpha, beta, .true.)
        zeta(rf + 1:rf + 3, cu + 1:cu + 3) = xa*dd + ya*(delta - dd)
        zeta(rt + 1:rt + 3, co + 1:co + 3) = xc*dd + yc*(delta - dd)
        zeta(rt + 1:rt + 3, cu + 1:cu + 3) = yb*ed
        ! strain coupling: x(F_alpha,i) = sum_beta G^{beta alpha}_{jki} E_jk,
        ! x(T_alpha,i) = sum_beta H^{beta alpha}_{jki} E_jk
        xg = fam(f, i_xg11, beta, alpha, .true.)
        yg = fam(f, i_yg11, beta, alpha, .true.)
        yh = fam(f, i_yh11, beta, alpha, .false.)
        xe(rf + 1:rf + 3, :, :) = xe(rf + 1:rf + 3, :, :) + xg*t1 + yg*t2
        xe(rt + 1:rt + 3, :, :) = xe(rt + 1:rt + 3, :, :) + yh*t3
      end do
    end do
    ! Btilde^{alpha beta}_ij = B^{beta alpha}_ji: the force <- rotation blocks by symmetry.
    do alpha = 1, 2
      do beta = 1, 2
        zeta(6*(alpha - 1) + 1:6*(alpha - 1) + 3, 6*(beta - 1) + 4:6*(beta - 1) + 6) = &
          transpose(zeta(6*(beta - 1) + 4:6*(beta - 1) + 6, 6*(alpha - 1) + 1:6*(alpha - 1) + 3))
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
