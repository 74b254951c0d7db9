!> Rotne-Prager-Yamakawa mobility with the overlapping-sphere form (Wajnryb, Mizerski, Zuk,
!> Szymczak, J. Fluid Mech. 731, R3 (2013)) and the matching shear disturbance C:E
!> (PHYSICS.md 3.2). Units: d = 1, isolated-bead mobility 1/3; r_hat = (r_i - r_j)/r.
!>   r >= 1: mu_ij = 1/(8r) [ (1 + 1/(6r^2)) I + (1 - 1/(2r^2)) r_hat r_hat ]
!>   r <  1: mu_ij = 1/3 [ (1 - 9r/16) I + (3r/16) r_hat r_hat ]
!>   r >= 1: C_ij:E = -1/(12 r^4) E r_hat - 5/(16 r^2) (1 - 2/(3r^2)) (r_hat.E.r_hat) r_hat
!>   r <  1: C_ij:E = (5r^2/12 - r/2) E r_hat - (5r^2/48) (r_hat.E.r_hat) r_hat
!> The stresslet (kf_hydro_model `stresslet`): every bead's own (5/6) E, the stresslets due to
!> the forces from the reciprocal theorem (the transpose of C above, overlaps included), and the
!> generalised-RPY strain-strain pair coupling (the same superposition that gives C: the
!> Faxen-corrected strain, (1 + a^2/10 lap), at bead i of the field (1 + a^2/10 lap) u_S of bead
!> j's stresslet S0 = (20/3) pi eta a^3 E; Wajnryb et al. 2013 above, and Batchelor & Green,
!> J. Fluid Mech. 56, 401 (1972) for the single-sphere fields). With a = 1/2, n = r_hat,
!> Q = n.E.n, e = E.n, per pair (both beads) in units pi eta d^3:
!>   S_pair = (5/3) E'(r),  E'(r) = -(5/16) { [e n + n e + Q I - 5 Q n n]/r^3
!>            + [(4/5) E - 4 (e n + n e) - 2 Q I + 14 Q n n]/(4 r^5) }.
!> For overlapping beads (r < 1) this coupling is taken at r = 1 (the overlapping-sphere form of
!> the strain-strain coupling is not implemented; an approximation used only while beads overlap).
!> prepare() tabulates per pair i < j the separation and the scalar coefficients (one sqrt
!> per pair, branch-free, vectorised); apply_mobility and add_strain_disturbance are then
!> single pair loops that use the symmetry of the pair (mu_ji = mu_ij, C_ji:E = -C_ij:E) and
!> allocate nothing (work arrays are allocated when N changes).
module kf_hydro_rpy
  use kf_kinds, only: wp, i8
  use kf_pair_geometry, only: pair_geometry_t
  use kf_pairs, only: pair_count, pair_row_offset
  use kf_error, only: error_t
  use kf_hydro_model, only: hydro_model_t
  implicit none
  private

  public :: rpy_pair_coefficients, rpy_memory_bytes

  !> RPY model; holds the bead positions of the last prepare.
  type, extends(hydro_model_t), public :: rpy_model_t
    private
    real(wp), allocatable :: x(:), y(:), z(:)                 !< positions (structure of arrays)
    real(wp), allocatable :: dx(:), dy(:), dz(:)              !< pair separations r_i - r_j, i < j
    real(wp), allocatable :: a(:), bb(:), c1(:), c2(:)        !< pair coefficients (see prepare)
    real(wp), allocatable :: ux(:), uy(:), uz(:), fx(:), fy(:), fz(:)   !< work
  contains
    procedure :: prepare => rpy_prepare
    procedure :: apply_mobility => rpy_apply
    procedure :: add_strain_disturbance => rpy_disturb
    procedure :: name => rpy_name
    procedure :: mobility_matrix => rpy_mobility_matrix
    procedure :: add_pair_strain_stresslet => rpy_pair_strain_stresslet
  end type rpy_model_t

  real(wp), parameter :: third = 1.0_wp/3.0_wp

contains

  !> The model's arrays for n beads (bytes; kf_resources adds the rest of a case): 7 float64
  !> pair tables (56 bytes per pair) and 9 float64 per bead.
  pure integer(i8) function rpy_memory_bytes(n) result(bytes)
    integer(i8), intent(in) :: n
    bytes = 56_i8*(n*(n - 1_i8)/2_i8) + 72_i8*n
  end function rpy_memory_bytes

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

  !> Copy the positions and tabulate, for every pair i < j (packed index), the separation
  !> d = r_i - r_j and the coefficients mu_ij = a I + bb d d^T, C_ij:E = c1 E d + c2 (d.E.d) d.
  !> The loops are branch-free so that they vectorise; coincident beads (r = 0) get the limits
  !> mu_ij = I/3 and C_ij:E = 0.
  subroutine rpy_prepare(this, r, error, pairs)
    class(rpy_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    type(pair_geometry_t), intent(in), optional :: pairs
    integer :: n
    n = size(r, 2)
    if (n /= this%n .or. .not. allocated(this%x)) call allocate_work(this, n)
    this%x = r(1, :)
    this%y = r(2, :)
    this%z = r(3, :)
    call tabulate_pairs(n, pair_count(n), this%x, this%y, this%z, this%dx, this%dy, this%dz, this%a, this%bb, &
                        this%c1, this%c2)
  end subroutine rpy_prepare

  !> The pair table of rpy_prepare (explicit-shape arrays: no aliasing, the j loop vectorises;
  !> np = pair_count(n) and the packed indices are 64-bit, kf_pairs).
  pure subroutine tabulate_pairs(n, np, x, y, z, dx, dy, dz, a, bb, c1, c2)
    integer, intent(in) :: n
    integer(i8), intent(in) :: np
    real(wp), intent(in) :: x(n), y(n), z(n)
    real(wp), intent(out) :: dx(np), dy(np), dz(np), a(np), bb(np), c1(np), c2(np)
    integer :: i, j
    integer(i8) :: off
    real(wp) :: xi, yi, zi, r2, r2s, rinv, rf, rf2, rf5, wf, wn
    do i = 1, n - 1
      off = pair_row_offset(i, n)
      xi = x(i)
      yi = y(i)
      zi = z(i)
      do j = i + 1, n
        dx(off + j) = xi - x(j)
        dy(off + j) = yi - y(j)
        dz(off + j) = zi - z(j)
        r2 = dx(off + j)**2 + dy(off + j)**2 + dz(off + j)**2
        ! Branch-free blend: wf = 1 for r >= 1, 0 otherwise; both forms are finite everywhere.
        wf = 0.5_wp + sign(0.5_wp, r2 - 1.0_wp)
        wn = 1.0_wp - wf
        r2s = r2 + 1.0e-200_wp
        rinv = 1.0_wp/sqrt(r2s)
        rf = wf*rinv + wn                ! 1/r where r >= 1, 1 elsewhere
        rf2 = rf*rf
        rf5 = rf2*rf2*rf
        a(off + j) = wf*(0.125_wp*rf*(1.0_wp + rf2*(1.0_wp/6.0_wp))) &
                     + wn*(third*(1.0_wp - 0.5625_wp*r2s*rinv))
        bb(off + j) = wf*(0.125_wp*rf*rf2*(1.0_wp - 0.5_wp*rf2)) + wn*(0.0625_wp*rinv)
        c1(off + j) = wf*(-rf5*(1.0_wp/12.0_wp)) + wn*((5.0_wp/12.0_wp)*r2s*rinv - 0.5_wp)
        c2(off + j) = wf*(-(5.0_wp/16.0_wp)*rf5*(1.0_wp - (2.0_wp/3.0_wp)*rf2)) &
                      + wn*(-(5.0_wp/48.0_wp)*rinv)
      end do
    end do
  end subroutine tabulate_pairs

  subroutine allocate_work(this, n)
    class(rpy_model_t), intent(inout) :: this
    integer, intent(in) :: n
    integer(i8) :: np
    if (allocated(this%x)) deallocate (this%x, this%y, this%z, this%ux, this%uy, this%uz, &
                                       this%fx, this%fy, this%fz, this%dx, this%dy, this%dz, &
                                       this%a, this%bb, this%c1, this%c2)
    np = max(1_i8, pair_count(n))
    allocate (this%x(n), this%y(n), this%z(n), this%ux(n), this%uy(n), this%uz(n), &
              this%fx(n), this%fy(n), this%fz(n))
    allocate (this%dx(np), this%dy(np), this%dz(np), this%a(np), this%bb(np), this%c1(np), this%c2(np))
    this%n = n
  end subroutine allocate_work

  !> u = mu f.
  subroutine rpy_apply(this, f, u)
    class(rpy_model_t), intent(inout) :: this
    real(wp), intent(in) :: f(:, :)
    real(wp), intent(out) :: u(:, :)
    integer :: n
    n = this%n
    this%fx = f(1, :)
    this%fy = f(2, :)
    this%fz = f(3, :)
    this%ux = third*this%fx
    this%uy = third*this%fy
    this%uz = third*this%fz
    call mobility_pairs(n, pair_count(n), this%dx, this%dy, this%dz, this%a, this%bb, this%fx, this%fy, this%fz, &
                        this%ux, this%uy, this%uz)
    u(1, :) = this%ux
    u(2, :) = this%uy
    u(3, :) = this%uz
  end subroutine rpy_apply

  !> Pair loop of rpy_apply: u += sum over pairs of mu_ij f_j and mu_ji f_i.
  pure subroutine mobility_pairs(n, np, pdx, pdy, pdz, pa, pbb, fx, fy, fz, ux, uy, uz)
    integer, intent(in) :: n
    integer(i8), intent(in) :: np
    real(wp), intent(in) :: pdx(np), pdy(np), pdz(np), pa(np), pbb(np), fx(n), fy(n), fz(n)
    real(wp), intent(inout) :: ux(n), uy(n), uz(n)
    integer :: i, j
    integer(i8) :: off
    real(wp) :: fxi, fyi, fzi, uxi, uyi, uzi, df_j, df_i, a, dx, dy, dz
    do i = 1, n - 1
      off = pair_row_offset(i, n)
      fxi = fx(i)
      fyi = fy(i)
      fzi = fz(i)
      uxi = 0.0_wp
      uyi = 0.0_wp
      uzi = 0.0_wp
      !$omp simd reduction(+:uxi, uyi, uzi)
      do j = i + 1, n
        dx = pdx(off + j)
        dy = pdy(off + j)
        dz = pdz(off + j)
        a = pa(off + j)
        df_j = pbb(off + j)*(dx*fx(j) + dy*fy(j) + dz*fz(j))
        df_i = pbb(off + j)*(dx*fxi + dy*fyi + dz*fzi)
        uxi = uxi + a*fx(j) + df_j*dx
        uyi = uyi + a*fy(j) + df_j*dy
        uzi = uzi + a*fz(j) + df_j*dz
        ux(j) = ux(j) + a*fxi + df_i*dx
        uy(j) = uy(j) + a*fyi + df_i*dy
        uz(j) = uz(j) + a*fzi + df_i*dz
      end do
      ux(i) = ux(i) + uxi
      uy(i) = uy(i) + uyi
      uz(i) = uz(i) + uzi
    end do
  end subroutine mobility_pairs

  !> u = u + C:E.
  subroutine rpy_disturb(this, e, u)
    class(rpy_model_t), intent(inout) :: this
    real(wp), intent(in) :: e(3, 3)
    real(wp), intent(inout) :: u(:, :)
    integer :: n
    real(wp) :: e11, e12, e13, e22, e23, e33
    n = this%n
    e11 = e(1, 1)
    e12 = 0.5_wp*(e(1, 2) + e(2, 1))
    e13 = 0.5_wp*(e(1, 3) + e(3, 1))
    e22 = e(2, 2)
    e23 = 0.5_wp*(e(2, 3) + e(3, 2))
    e33 = e(3, 3)
    this%ux = 0.0_wp
    this%uy = 0.0_wp
    this%uz = 0.0_wp
    call strain_pairs(n, pair_count(n), this%dx, this%dy, this%dz, this%c1, this%c2, [e11, e12, e13, e22, e23, e33], &
                      this%ux, this%uy, this%uz)
    u(1, :) = u(1, :) + this%ux
    u(2, :) = u(2, :) + this%uy
    u(3, :) = u(3, :) + this%uz
  end subroutine rpy_disturb

  !> Pair loop of rpy_disturb; es = (E11, E12, E13, E22, E23, E33).
  pure subroutine strain_pairs(n, np, pdx, pdy, pdz, pc1, pc2, es, ux, uy, uz)
    integer, intent(in) :: n
    integer(i8), intent(in) :: np
    real(wp), intent(in) :: pdx(np), pdy(np), pdz(np), pc1(np), pc2(np), es(6)
    real(wp), intent(inout) :: ux(n), uy(n), uz(n)
    integer :: i, j
    integer(i8) :: off
    real(wp) :: dx, dy, dz, edx, edy, edz, ded, c1, c2, wx, wy, wz, uxi, uyi, uzi
    real(wp) :: e11, e12, e13, e22, e23, e33
    e11 = es(1)
    e12 = es(2)
    e13 = es(3)
    e22 = es(4)
    e23 = es(5)
    e33 = es(6)
    do i = 1, n - 1
      off = pair_row_offset(i, n)
      uxi = 0.0_wp
      uyi = 0.0_wp
      uzi = 0.0_wp
      !$omp simd reduction(+:uxi, uyi, uzi)
      do j = i + 1, n
        dx = pdx(off + j)
        dy = pdy(off + j)
        dz = pdz(off + j)
        c1 = pc1(off + j)
        c2 = pc2(off + j)
        edx = e11*dx + e12*dy + e13*dz
        edy = e12*dx + e22*dy + e23*dz
        edz = e13*dx + e23*dy + e33*dz
        ded = c2*(dx*edx + dy*edy + dz*edz)
        wx = c1*edx + ded*dx
        wy = c1*edy + ded*dy
        wz = c1*edz + ded*dz
        uxi = uxi + wx
        uyi = uyi + wy
        uzi = uzi + wz
        ux(j) = ux(j) - wx
        uy(j) = uy(j) - wy
        uz(j) = uz(j) - wz
      end do
      ux(i) = ux(i) + uxi
      uy(i) = uy(i) + uyi
      uz(i) = uz(i) + uzi
    end do
  end subroutine strain_pairs

  !> s = s + the strain-strain pair stresslets of every pair (module header), after prepare.
  subroutine rpy_pair_strain_stresslet(this, r, e, s)
    class(rpy_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :), e(3, 3)
    real(wp), intent(inout) :: s(3, 3)
    integer :: k
    real(wp) :: d(3), rr, nv(3), ev(3), q, en(3, 3), nn(3, 3), acc(3, 3), eye(3, 3)
    eye = 0.0_wp
    eye(1, 1) = 1.0_wp
    eye(2, 2) = 1.0_wp
    eye(3, 3) = 1.0_wp
    acc = 0.0_wp
    do k = 1, this%n*(this%n - 1)/2
      d = [this%dx(k), this%dy(k), this%dz(k)]
      rr = norm2(d)
      if (.not. rr > 0.0_wp) cycle   ! coincident beads: no direction, no coupling
      nv = d/rr
      rr = max(rr, 1.0_wp)
      ev = matmul(e, nv)
      q = dot_product(nv, ev)
      en = spread(ev, 2, 3)*spread(nv, 1, 3)
      en = en + transpose(en)
      nn = spread(nv, 2, 3)*spread(nv, 1, 3)
      acc = acc + (en + q*eye - 5.0_wp*q*nn)/rr**3 &
        + (0.8_wp*e - 4.0_wp*en - 2.0_wp*q*eye + 14.0_wp*q*nn)/(4.0_wp*rr**5)
    end do
    s = s - (5.0_wp/3.0_wp)*(5.0_wp/16.0_wp)*acc
  end subroutine rpy_pair_strain_stresslet

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
