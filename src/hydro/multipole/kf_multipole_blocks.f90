!> Building blocks of the induced-force multipole method for equal spheres of diameter 1
!> (radius a = 1/2, viscosity 1): the per-sphere layout of the unknowns, the diagonal scaling,
!> the single-sphere operator and the closed-form translation (pair) blocks of MULTIPOLE.md
!> sections 5-7.
!>
!> Per sphere there are 3L(L+2) unknowns: ranks n = 1..L, families phi, chi, p, components
!> q = 0..2n. Local index (1-based) t = 3(n^2-1) + s(2n+1) + q + 1 with s = 0, 1, 2 for
!> phi, chi, p. Complex form: q = m + n. Real form: q = 0 <-> m = 0, q = 2m-1 <-> sqrt2 Re F_m,
!> q = 2m <-> sqrt2 Im F_m. Everything is scaled by sigma (section 5.2) so that the self block is
!> the identity plus -c_n between (phi,n,m) and (p,n,m).
module kf_multipole_blocks
  use kf_kinds, only: wp
  use kf_constants, only: pi
  implicit none
  private

  integer, parameter, public :: fam_phi = 0, fam_chi = 1, fam_p = 2
  real(wp), parameter, public :: sphere_radius = 0.5_wp

  !> Layout of the unknowns of one sphere at truncation order L, with scaling and real-form maps.
  type, public :: multipole_layout_t
    integer :: order = 0              !< truncation L
    integer :: nb = 0                 !< unknowns per sphere, 3L(L+2)
    integer, allocatable :: rank_n(:) !< rank n of local index t
    integer, allocatable :: fam(:)    !< family of local index t
    integer, allocatable :: m_of(:)   !< order m of complex local index t
    real(wp), allocatable :: sigma(:) !< scale sigma of complex local index t
    real(wp), allocatable :: sigma_real(:) !< scale sigma of real local index t
    real(wp), allocatable :: cn(:)    !< self coupling c_n, n = 1..L
    integer, allocatable :: widx(:, :)      !< real row p = sum_k wval(k,p) * complex row widx(k,p)
    complex(wp), allocatable :: wval(:, :)
  contains
    procedure :: init => layout_init
    procedure :: index => layout_index
  end type multipole_layout_t

  public :: pair_block_complex, pair_block_real, z0_inverse

contains

  !> Set up the layout for truncation order L >= 1.
  subroutine layout_init(this, order)
    class(multipole_layout_t), intent(inout) :: this
    integer, intent(in) :: order
    integer :: n, s, q, m, t, tp, tm
    real(wp) :: kappa, lognu, rt2

    this%order = order
    this%nb = 3*order*(order + 2)
    if (allocated(this%rank_n)) deallocate (this%rank_n, this%fam, this%m_of, this%sigma, &
                                            this%sigma_real, this%cn, this%widx, this%wval)
    allocate (this%rank_n(this%nb), this%fam(this%nb), this%m_of(this%nb), this%sigma(this%nb))
    allocate (this%sigma_real(this%nb))
    allocate (this%cn(order), this%widx(2, this%nb), this%wval(2, this%nb))
    rt2 = sqrt(2.0_wp)
    do n = 1, order
      this%cn(n) = sqrt(real((2*n - 1)*(2*n + 3), wp))/real(2*n + 1, wp)
      do s = fam_phi, fam_p
        select case (s)
        case (fam_phi)
          kappa = sqrt(16.0_wp*pi*n*(2*n - 1)/real((n + 1)*(2*n + 1), wp))*sphere_radius**(n - 0.5_wp)
        case (fam_chi)
          kappa = sqrt(4.0_wp*pi*n*(n + 1))*sphere_radius**(n + 0.5_wp)
        case default
          kappa = sqrt(4.0_wp*pi*n/real((n + 1)*(2*n + 1)*(2*n + 3), wp))*sphere_radius**(n + 1.5_wp)
        end select
        do q = 0, 2*n
          t = this%index(n, s, q)
          m = q - n
          this%rank_n(t) = n
          this%fam(t) = s
          this%m_of(t) = m
          lognu = log_gamma(real(n + m + 1, wp)) + log_gamma(real(n - m + 1, wp))
          this%sigma(t) = kappa*exp(-0.5_wp*lognu)
        end do
        do q = 0, 2*n
          this%sigma_real(this%index(n, s, q)) = this%sigma(this%index(n, s, n + (q + 1)/2))
        end do
        ! Real form rows (section 7): x_0 = F_0, x_{2m-1} = (F_m + (-1)^m F_-m)/sqrt2,
        ! x_{2m} = (F_m - (-1)^m F_-m)/(i sqrt2).
        t = this%index(n, s, 0)
        this%widx(:, t) = this%index(n, s, n)
        this%wval(1, t) = (1.0_wp, 0.0_wp)
        this%wval(2, t) = (0.0_wp, 0.0_wp)
        do m = 1, n
          tp = this%index(n, s, n + m)
          tm = this%index(n, s, n - m)
          t = this%index(n, s, 2*m - 1)
          this%widx(:, t) = [tp, tm]
          this%wval(:, t) = [cmplx(1.0_wp/rt2, 0.0_wp, wp), cmplx((-1)**m/rt2, 0.0_wp, wp)]
          t = this%index(n, s, 2*m)
          this%widx(:, t) = [tp, tm]
          this%wval(:, t) = [cmplx(0.0_wp, -1.0_wp/rt2, wp), cmplx(0.0_wp, (-1)**m/rt2, wp)]
        end do
      end do
    end do
  end subroutine layout_init

  !> Local (1-based) index of rank n, family s, component q.
  pure integer function layout_index(this, n, s, q) result(t)
    class(multipole_layout_t), intent(in) :: this
    integer, intent(in) :: n, s, q
    t = 3*(n*n - 1) + s*(2*n + 1) + q + 1
  end function layout_index

  !> Unscaled single-sphere inverse operator Z0^-1 at rank n, order m, radius a (section 5.1):
  !> zinv = [phi-phi, phi-p, p-p, chi-chi].
  pure function z0_inverse(n, m, a) result(zinv)
    integer, intent(in) :: n, m
    real(wp), intent(in) :: a
    real(wp) :: zinv(4)
    real(wp) :: nu
    nu = gamma(real(n + m + 1, wp))*gamma(real(n - m + 1, wp))
    zinv(1) = nu*(n + 1)*(2*n + 1)/(16.0_wp*pi*n*(2*n - 1)*a**(2*n - 1))
    zinv(2) = -nu*(n + 1)*(2*n + 3)/(8.0_wp*pi*n*a**(2*n + 1))
    zinv(3) = nu*(n + 1)*(2*n + 1)*(2*n + 3)/(4.0_wp*pi*n*a**(2*n + 3))
    zinv(4) = nu/(4.0_wp*pi*n*(n + 1)*a**(2*n + 1))
  end function z0_inverse

  !> Scaled complex translation block g = sigma G sigma (section 6.1) for the displacement
  !> d = R_receiver - R_source; rows: receiver unknowns, columns: source unknowns (complex form).
  !> ih is work space of shape (0:2L, -2L:2L) holding the irregular harmonics of d on input.
  pure subroutine pair_block_complex(lay, d, ih, g)
    type(multipole_layout_t), intent(in) :: lay
    real(wp), intent(in) :: d(3)
    complex(wp), intent(in) :: ih(0:, -2*lay%order:)
    complex(wp), intent(out) :: g(:, :)
    integer :: tr, tc, k, l, n, m, sr, sc, lam, mu, knl
    real(wp) :: d2, sgn, alam, bq, qq, pref
    complex(wp) :: j0, j2
    real(wp), parameter :: c4pi = 1.0_wp/(4.0_wp*pi)

    d2 = sum(d**2)
    do tc = 1, lay%nb
      n = lay%rank_n(tc)
      m = lay%m_of(tc)
      sc = lay%fam(tc)
      do tr = 1, lay%nb
        k = lay%rank_n(tr)
        l = lay%m_of(tr)
        sr = lay%fam(tr)
        lam = n + k
        mu = m - l
        sgn = real(1 - 2*modulo(k + l, 2), wp)
        pref = lay%sigma(tr)*lay%sigma(tc)*c4pi
        select case (3*sr + sc)
        case (3*fam_p + fam_phi, 3*fam_phi + fam_p)
          g(tr, tc) = pref*jt(0)
        case (3*fam_chi + fam_chi)
          g(tr, tc) = -pref*jt(0)/real((n + 1)*(k + 1), wp)
        case (3*fam_phi + fam_chi)
          knl = n*l + k*m
          g(tr, tc) = pref*cmplx(0.0_wp, real(knl, wp), wp)*jt(1)/real(k*n*(n + 1), wp)
        case (3*fam_chi + fam_phi)
          knl = n*l + k*m
          g(tr, tc) = pref*cmplx(0.0_wp, real(knl, wp), wp)*jt(1)/real(n*k*(k + 1), wp)
        case (3*fam_phi + fam_phi)
          knl = k*m + n*l
          alam = -1.0_wp/real(2*(2*lam - 1), wp)
          qq = real(2*knl*knl - (m + l)*knl - (lam - 1)*(n*k + l*m), wp)
          bq = -real(n*k - 2*n - 2*k + 1, wp)*qq/real(n*k*(2*n - 1)*(2*k - 1)*(2*lam - 1), wp)
          j0 = jt(0)
          j2 = jt(2)
          g(tr, tc) = pref*(alam*d2*j0 + bq*j2)
        case default
          g(tr, tc) = (0.0_wp, 0.0_wp)
        end select
      end do
    end do

  contains

    pure complex(wp) function jt(t)
      integer, intent(in) :: t
      if (abs(mu) > lam - t) then
        jt = (0.0_wp, 0.0_wp)
      else
        jt = sgn*ih(lam - t, mu)
      end if
    end function jt

  end subroutine pair_block_complex

  !> Scaled real translation block (section 7): gr = Re(W g W^dagger) of the complex block g.
  !> x is complex work space of the same shape as g.
  pure subroutine pair_block_real(lay, g, x, gr)
    type(multipole_layout_t), intent(in) :: lay
    complex(wp), intent(in) :: g(:, :)
    complex(wp), intent(out) :: x(:, :)
    real(wp), intent(out) :: gr(:, :)
    integer :: p, q
    do q = 1, lay%nb
      do p = 1, lay%nb
        x(p, q) = lay%wval(1, p)*g(lay%widx(1, p), q) + lay%wval(2, p)*g(lay%widx(2, p), q)
      end do
    end do
    do q = 1, lay%nb
      do p = 1, lay%nb
        gr(p, q) = real(x(p, lay%widx(1, q))*conjg(lay%wval(1, q)) &
                        + x(p, lay%widx(2, q))*conjg(lay%wval(2, q)), wp)
      end do
    end do
  end subroutine pair_block_real

end module kf_multipole_blocks
