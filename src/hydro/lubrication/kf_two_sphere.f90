!> Two equal spheres on the z axis: the m-decoupled multipole system (MULTIPOLE.md sections 6.4, 12).
!>
!> Sphere 1 sits at the origin and sphere 2 at D z (D = centre distance over the radius a, i.e.
!> D = 2 r with r in bead diameters). With the line of centres along z the induced-force-multipole
!> system splits into independent blocks m = 0, 1, 2, ...; each block is made real symmetric
!> (chi unknowns multiplied by i, chi equations by -i), scaled so that its diagonal is 1, and
!> solved by Cholesky. The 22 Jeffrey-Onishi/Jeffrey resistance functions (normalised as in
!> Kim & Karrila section 11.3, see MULTIPOLE.md 12.3) come from the m = 0, 1, 2 blocks.
!> Factorials enter through log-gamma, so truncation orders up to L ~ 1000 work in double precision.
module kf_two_sphere
  use kf_kinds, only: wp
  use kf_constants, only: pi
  use kf_error, only: error_t, fatal_error
  use kf_lapack, only: cholesky_factor, cholesky_solve
  implicit none
  private

  public :: two_sphere_resistance, two_sphere_block, block_index, has_strain

  !> Number of two-sphere resistance functions.
  integer, parameter, public :: n_functions = 22
  !> Indices of the functions in every array of 22 values (order of MULTIPOLE.md 13.1).
  integer, parameter, public :: i_xa11 = 1, i_xa12 = 2, i_ya11 = 3, i_ya12 = 4, i_yb11 = 5, &
    i_yb12 = 6, i_xc11 = 7, i_xc12 = 8, i_yc11 = 9, i_yc12 = 10, i_xg11 = 11, i_xg12 = 12, &
    i_yg11 = 13, i_yg12 = 14, i_yh11 = 15, i_yh12 = 16, i_xm11 = 17, i_xm12 = 18, i_ym11 = 19, &
    i_ym12 = 20, i_zm11 = 21, i_zm12 = 22
  !> Names of the functions, for reports and the generated table.
  character(len=4), parameter, public :: function_names(n_functions) = [ &
    'XA11', 'XA12', 'YA11', 'YA12', 'YB11', 'YB12', 'XC11', 'XC12', 'YC11', 'YC12', 'XG11', &
    'XG12', 'YG11', 'YG12', 'YH11', 'YH12', 'XM11', 'XM12', 'YM11', 'YM12', 'ZM11', 'ZM12']
  !> Isolated-sphere limits (1 for the diagonal A, C, M functions, 0 otherwise).
  real(wp), parameter, public :: isolated_limit(n_functions) = [ &
    1.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, &
    0.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 1.0_wp, 0.0_wp, 1.0_wp, 0.0_wp]

  integer, parameter :: fam_phi = 1, fam_chi = 2, fam_p = 3

contains

  !> True when truncation order `order` represents the strain (stresslet) moments (L >= 2).
  pure logical function has_strain(order)
    integer, intent(in) :: order
    has_strain = order >= 2
  end function has_strain

  !> Position of unknown (sphere, rank n, family) in the block of order m (families 1 = phi,
  !> 2 = chi, 3 = p; spheres 1, 2).
  pure integer function block_index(order, m, sphere, n, family)
    integer, intent(in) :: order, m, sphere, n, family
    integer :: n0, nb
    n0 = max(1, m)
    nb = 3*(order - n0 + 1)
    block_index = (sphere - 1)*nb + 3*(n - n0) + family
  end function block_index

  !> ln(nu_nm) = ln((n+m)! (n-m)!).
  pure real(wp) function log_nu(n, m)
    integer, intent(in) :: n, m
    log_nu = log_gamma(real(n + m + 1, wp)) + log_gamma(real(n - m + 1, wp))
  end function log_nu

  !> Scaled, real symmetric matrix of block m (size 6 (order - max(1,m) + 1)) at centre
  !> distance `dist` = D/a. Both off-diagonal sphere blocks are computed from the closed form
  !> (the symmetry is a check of the formulas, not imposed).
  pure subroutine two_sphere_block(dist, order, m, mat)
    real(wp), intent(in) :: dist          !< centre distance over the radius (>= 2 without overlap)
    integer, intent(in) :: order          !< truncation order L >= 1
    integer, intent(in) :: m              !< azimuthal order m >= 0
    real(wp), intent(out) :: mat(:, :)    !< the block matrix
    integer :: n0, n, k, s, sr, sc
    real(wp) :: kf(order), kc(order), kp(order), lnu(order), rm, rlam, amp, bmp, q, sd, sgn
    real(wp) :: ph0p, ph1, ph0m, ph2, ld, x1, x2, four_pi
    integer :: ip_k, ic_k, ix_k, ip_n, ic_n, ix_n, lam

    four_pi = 4.0_wp*pi
    n0 = max(1, m)
    rm = real(m, wp)
    ld = log(dist)
    do n = n0, order
      kf(n) = sqrt(16.0_wp*pi*n*(2*n - 1)/real((n + 1)*(2*n + 1), wp))
      kp(n) = sqrt(4.0_wp*pi*n/(real(n + 1, wp)*(2*n + 1)*(2*n + 3)))
      kc(n) = sqrt(4.0_wp*pi*n*(n + 1))
      lnu(n) = log_nu(n, m)
    end do
    mat = 0.0_wp
    ! Self blocks: 1 on the diagonal, -c_n between phi and p of equal rank.
    do s = 1, 2
      do n = n0, order
        ip_n = block_index(order, m, s, n, fam_phi)
        ix_n = block_index(order, m, s, n, fam_p)
        ic_n = block_index(order, m, s, n, fam_chi)
        mat(ip_n, ip_n) = 1.0_wp
        mat(ic_n, ic_n) = 1.0_wp
        mat(ix_n, ix_n) = 1.0_wp
        mat(ip_n, ix_n) = -sqrt(real((2*n - 1)*(2*n + 3), wp))/real(2*n + 1, wp)
        mat(ix_n, ip_n) = mat(ip_n, ix_n)
      end do
    end do
    ! Pair blocks: receiver sphere sr (rank k), source sphere sc (rank n); d = R_sr - R_sc.
    do sr = 1, 2
      sc = 3 - sr
      sd = merge(1.0_wp, -1.0_wp, sr == 2)
      do n = n0, order
        ip_n = block_index(order, m, sc, n, fam_phi)
        ic_n = block_index(order, m, sc, n, fam_chi)
        ix_n = block_index(order, m, sc, n, fam_p)
        do k = n0, order
          ip_k = block_index(order, m, sr, k, fam_phi)
          ic_k = block_index(order, m, sr, k, fam_chi)
          ix_k = block_index(order, m, sr, k, fam_p)
          lam = n + k
          rlam = real(lam, wp)
          sgn = merge(1.0_wp, -1.0_wp, mod(k + m, 2) == 0)
          ph0p = phi_t(0, lam + 1)
          ph1 = phi_t(1, lam)
          ph0m = phi_t(0, lam - 1)
          ph2 = phi_t(2, lam - 1)
          amp = -1.0_wp/(2.0_wp*(2.0_wp*rlam - 1.0_wp))
          q = (rlam - 1.0_wp)*(rm*rm*(2.0_wp*rlam - 1.0_wp) - real(n, wp)*k)
          bmp = -(real(n, wp)*k - 2.0_wp*n - 2.0_wp*k + 1.0_wp)*q/ &
                (real(n, wp)*k*(2.0_wp*n - 1.0_wp)*(2.0_wp*k - 1.0_wp)*(2.0_wp*rlam - 1.0_wp))
          mat(ix_k, ip_n) = kp(k)*kf(n)*ph0p/four_pi
          mat(ip_k, ix_n) = kf(k)*kp(n)*ph0p/four_pi
          mat(ic_k, ic_n) = -kc(k)*kc(n)*ph0p/(four_pi*(n + 1)*(k + 1))
          x1 = rm*rlam*kf(k)*kc(n)*ph1/(four_pi*k*n*(n + 1))
          x2 = rm*rlam*kc(k)*kf(n)*ph1/(four_pi*n*k*(k + 1))
          ! i x1 (phi <- chi) and i x2 (chi <- phi) become -x1 and +x2 in the real form.
          mat(ip_k, ic_n) = -x1
          mat(ic_k, ip_n) = x2
          mat(ip_k, ip_n) = kf(k)*kf(n)*(amp*ph0m + bmp*ph2)/four_pi
        end do
      end do
    end do

  contains

    !> Phi_t(q) of MULTIPOLE.md 6.4 for the current (k, n, m, s_d), a = 1.
    pure real(wp) function phi_t(t, qq)
      integer, intent(in) :: t, qq
      integer :: lt
      lt = lam - t
      if (lt < 0) then
        phi_t = 0.0_wp
        return
      end if
      phi_t = sgn*merge(1.0_wp, sd, mod(lt, 2) == 0)* &
              exp(log_gamma(real(lt + 1, wp)) - 0.5_wp*(lnu(k) + lnu(n)) - qq*ld)
    end function phi_t

  end subroutine two_sphere_block

  !> The 22 resistance functions of two equal spheres at centre distance `r` (in bead diameters),
  !> multipole method truncated at order `order` (MULTIPOLE.md 12.4 recipes).
  !> For order = 1 the strain functions (G, H, M) are not represented and are returned as 0.
  subroutine two_sphere_resistance(r, order, f, error)
    real(wp), intent(in) :: r                 !< centre distance in units of d (>= 1)
    integer, intent(in) :: order              !< truncation order L >= 1
    real(wp), intent(out) :: f(n_functions)   !< resistance functions (index constants i_*)
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: mat(:, :), rhs(:, :)
    real(wp) :: dist, sig1, sig2, sc1, sc2
    integer :: m, nrow, beta, j1, j2, jc, c1, c2
    real(wp), parameter :: m_norm = 20.0_wp*pi/3.0_wp

    f = 0.0_wp
    if (order < 1) then
      call fatal_error(error, 'two_sphere_resistance: truncation order must be >= 1')
      return
    end if
    if (.not. (r >= 1.0_wp)) then
      call fatal_error(error, 'two_sphere_resistance: centre distance must be >= 1 (no overlap)')
      return
    end if
    dist = 2.0_wp*r
    do m = 0, min(2, order)
      nrow = 6*(order - max(1, m) + 1)
      allocate (mat(nrow, nrow), rhs(nrow, 6))
      call two_sphere_block(dist, order, m, mat)
      call cholesky_factor(mat, error, 'two-sphere multipole block')
      if (allocated(error)) return
      rhs = 0.0_wp
      select case (m)
      case (0)
        sig1 = sigma(fam_phi, 1, 0)
        do beta = 1, 2
          ! U_beta = z: b(phi,1,0) = 1.
          rhs(block_index(order, 0, beta, 1, fam_phi), beta) = sig1
          ! Omega_beta = z: b(chi,1,0) = 1.
          rhs(block_index(order, 0, beta, 1, fam_chi), 2 + beta) = sigma(fam_chi, 1, 0)
          ! E_beta = zz - I/3: b(phi,2,0) = -2/3.
          if (order >= 2) rhs(block_index(order, 0, beta, 2, fam_phi), 4 + beta) = &
            -2.0_wp/3.0_wp*sigma(fam_phi, 2, 0)
        end do
        call cholesky_solve(mat, rhs)
        j1 = block_index(order, 0, 1, 1, fam_phi)
        jc = block_index(order, 0, 1, 1, fam_chi)
        do beta = 1, 2
          f(i_xa11 + beta - 1) = sig1*rhs(j1, beta)/(6.0_wp*pi)
          f(i_xc11 + beta - 1) = sigma(fam_chi, 1, 0)*rhs(jc, 2 + beta)/(8.0_wp*pi)
          if (order >= 2) then
            j2 = block_index(order, 0, 1, 2, fam_phi)
            sig2 = sigma(fam_phi, 2, 0)
            f(i_xg11 + beta - 1) = sig2*rhs(j2, beta)/(4.0_wp*pi)
            f(i_xm11 + beta - 1) = -sig2*rhs(j2, 4 + beta)/m_norm
          end if
        end do
      case (1)
        sc1 = sigma(fam_chi, 1, 1)
        sig1 = sigma(fam_phi, 1, 1)
        do beta = 1, 2
          ! U_beta = x: b(phi,1,1) = -1 (real).
          rhs(block_index(order, 1, beta, 1, fam_phi), beta) = -sig1
          ! Omega_beta = x: b(chi,1,1) = -1, i.e. +i in the real form; solved with +1,
          ! the true solution is i times this one.
          rhs(block_index(order, 1, beta, 1, fam_chi), 2 + beta) = sc1
          ! E_beta = xz + zx: b(phi,2,1) = 1.
          if (order >= 2) rhs(block_index(order, 1, beta, 2, fam_phi), 4 + beta) = &
            sigma(fam_phi, 2, 1)
        end do
        call cholesky_solve(mat, rhs)
        j1 = block_index(order, 1, 1, 1, fam_phi)
        c1 = block_index(order, 1, 1, 1, fam_chi)
        do beta = 1, 2
          f(i_ya11 + beta - 1) = -2.0_wp*sig1*rhs(j1, beta)/(6.0_wp*pi)
          f(i_yb11 + beta - 1) = -2.0_wp*sc1*rhs(c1, beta)/(4.0_wp*pi)
          f(i_yc11 + beta - 1) = 2.0_wp*sc1*rhs(c1, 2 + beta)/(8.0_wp*pi)
          if (order >= 2) then
            j2 = block_index(order, 1, 1, 2, fam_phi)
            sig2 = sigma(fam_phi, 2, 1)
            f(i_yg11 + beta - 1) = -sig2*rhs(j2, beta)/(4.0_wp*pi)
            f(i_yh11 + beta - 1) = -sig2*rhs(j2, 2 + beta)/(8.0_wp*pi)
            f(i_ym11 + beta - 1) = sig2*rhs(j2, 4 + beta)/m_norm
          end if
        end do
      case (2)
        sc2 = sigma(fam_phi, 2, 2)
        do beta = 1, 2
          ! E_beta = xx - yy: b(phi,2,2) = -2.
          rhs(block_index(order, 2, beta, 2, fam_phi), beta) = -2.0_wp*sc2
        end do
        call cholesky_solve(mat, rhs(:, 1:2))
        c2 = block_index(order, 2, 1, 2, fam_phi)
        do beta = 1, 2
          f(i_zm11 + beta - 1) = -2.0_wp*sc2*rhs(c2, beta)/m_norm
        end do
      end select
      deallocate (mat, rhs)
    end do

  contains

    !> sigma^family_{n m} (a = 1).
    pure real(wp) function sigma(family, n, mm)
      integer, intent(in) :: family, n, mm
      select case (family)
      case (fam_phi)
        sigma = sqrt(16.0_wp*pi*n*(2*n - 1)/real((n + 1)*(2*n + 1), wp))
      case (fam_chi)
        sigma = sqrt(4.0_wp*pi*n*(n + 1))
      case default
        sigma = sqrt(4.0_wp*pi*n/(real(n + 1, wp)*(2*n + 1)*(2*n + 3)))
      end select
      sigma = sigma*exp(-0.5_wp*log_nu(n, mm))
    end function sigma

  end subroutine two_sphere_resistance

end module kf_two_sphere
