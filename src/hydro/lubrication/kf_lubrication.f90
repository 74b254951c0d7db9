!> Lubrication (two-body) corrections to the order-L multipole friction (MULTIPOLE.md 13.3,
!> PHYSICS.md 3.3): dzeta = zeta_exact(pair) - zeta_L(pair) and the strain-coupling difference,
!> in the Cartesian Jeffrey-Onishi/Kim-Karrila form, project units.
!>
!> The scalar corrections f_exact - f_L of the 22 two-sphere functions come from the generated
!> tables of kf_lubrication_data (regular remainders on a uniform grid in u = sqrt(xi),
!> xi = 2 (r - 1)) interpolated with a cubic spline (clamped, zero slope at contact, where the
!> remainder is even in u) plus the analytic singular part w(xi) (g1/xi + g2 ln(1/xi) +
!> g3 xi ln(1/xi)). The result is multiplied by a C2 taper that brings it to exactly zero at the
!> cutoff r_c(L).
!>
!> Overlaps: pairs at |d| <= 1 are evaluated at (1 + eps_lub) d/|d|. Two forms (init's
!> `literal_bwe`): the clamp (default; the overlap rules 'pair', 'separate', 'relax') keeps the
!> correction continuous by evaluating every pair at max(|d|, 1 + eps_lub); the literal BWE rule
!> ('bwe', PHYSICS.md 3.3) evaluates a pair at |d| when |d| > 1 and at 1 + eps_lub when |d| <= 1
!> (the correction jumps down at contact: it diverges as |d| -> 1+).
module kf_lubrication
  use kf_kinds, only: wp
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_two_sphere, only: n_functions, has_strain
  use kf_near_contact, only: singular_part, singular_weight, smoothstep
  use kf_pair_tensor, only: pair_tensors
  use kf_pair_geometry, only: pair_geometry_t
  use kf_pair_tensor, only: pair_tensors, pair_strain_stresslet
  use kf_strain_basis, only: strain_basis
  use kf_lubrication_data, only: lub_max_order, lub_cutoff, lub_n_grid, lubrication_table
  use kf_pair_blocks, only: pair_blocks_t
  use kf_hydro_limits, only: eps_lub_in_range, eps_lub_range_text
  implicit none
  private

  !> Fraction of (r_c - 1) over which the correction is tapered to zero before the cutoff.
  real(wp), parameter :: taper_fraction = 0.1_wp

  !> Pair lubrication corrections for multipole truncation order L.
  type, public :: lubrication_t
    private
    integer :: order = 0
    real(wp) :: eps_lub = 1.0e-4_wp
    logical :: literal_bwe = .false.    !< only pairs at r <= 1 are moved to 1 + eps_lub
    real(wp) :: r_cut = 1.0_wp          !< cutoff centre distance
    real(wp) :: r_taper = 1.0_wp        !< start of the taper
    real(wp) :: h = 1.0_wp              !< grid step in u
    integer :: n = 0                    !< grid points
    integer :: nf = n_functions         !< number of represented functions (10 for L = 1)
    real(wp), allocatable :: val(:, :)  !< tabulated remainders (n, 22)
    real(wp), allocatable :: d2(:, :)   !< spline second derivatives (n, 22)
  contains
    procedure :: init
    procedure :: cutoff
    procedure :: correction_functions
    procedure :: evaluation_distance
    procedure :: pair_correction
    procedure :: pair_blocks
    procedure :: stresslet_correction
  end type lubrication_t

contains

  !> Set up the corrections for truncation order `order` (1..6) and overlap shift eps_lub > 0;
  !> `literal_bwe` (default .false.): the literal BWE rule instead of the clamp (module header).
  subroutine init(this, order, eps_lub, error, literal_bwe)
    class(lubrication_t), intent(inout) :: this
    integer, intent(in) :: order
    real(wp), intent(in) :: eps_lub
    type(error_t), allocatable, intent(out) :: error
    logical, intent(in), optional :: literal_bwe
    integer :: k

    if (order < 1 .or. order > lub_max_order) then
      call fatal_error(error, 'lubrication: truncation order '//to_str(order)// &
        ' not tabulated (allowed 1..'//to_str(lub_max_order)//')')
      return
    end if
    if (.not. eps_lub_in_range(eps_lub)) then
      call fatal_error(error, 'lubrication: eps_lub = '//to_str(eps_lub, '(es12.4)')// &
        ' out of range '//eps_lub_range_text())
      return
    end if
    this%order = order
    this%eps_lub = eps_lub
    this%literal_bwe = .false.
    if (present(literal_bwe)) this%literal_bwe = literal_bwe
    this%r_cut = lub_cutoff(order)
    this%r_taper = this%r_cut - taper_fraction*(this%r_cut - 1.0_wp)
    this%n = lub_n_grid(order)
    this%h = sqrt(2.0_wp*(this%r_cut - 1.0_wp))/real(this%n - 1, wp)
    this%nf = merge(n_functions, 10, has_strain(order))
    call lubrication_table(order, this%val)
    if (allocated(this%d2)) deallocate (this%d2)
    allocate (this%d2(this%n, n_functions))
    do k = 1, n_functions
      call spline_second_derivatives(this%val(:, k), this%h, this%d2(:, k))
    end do
  end subroutine init

  !> Centre distance (units of d) at and beyond which the corrections vanish.
  pure real(wp) function cutoff(this)
    class(lubrication_t), intent(in) :: this
    cutoff = this%r_cut
  end function cutoff

  !> The centre distance at which the correction of a pair at distance r is evaluated: the
  !> clamp max(r, 1 + eps_lub), or with literal_bwe r itself unless r <= 1 (then 1 + eps_lub).
  pure real(wp) function evaluation_distance(this, r) result(re)
    class(lubrication_t), intent(in) :: this
    real(wp), intent(in) :: r
    if (this%literal_bwe) then
      re = merge(1.0_wp + this%eps_lub, r, r <= 1.0_wp)
    else
      re = max(r, 1.0_wp + this%eps_lub)
    end if
  end function evaluation_distance

  !> Corrections f_exact - f_L of the 22 resistance functions at centre distance r (r > 1),
  !> including the taper; zero for r >= cutoff. No overlap rule here (see pair_correction);
  !> gaps are clamped to xi >= 1e-12 so that r <= 1 cannot produce NaN or a division by 0.
  pure subroutine correction_functions(this, r, df)
    class(lubrication_t), intent(in) :: this
    real(wp), intent(in) :: r
    real(wp), intent(out) :: df(n_functions)
    real(wp) :: xi, u, t, sing(n_functions), w, taper
    integer :: i

    df = 0.0_wp
    if (r >= this%r_cut) return
    xi = max(2.0_wp*(r - 1.0_wp), 1.0e-12_wp)
    u = sqrt(xi)
    i = min(this%n - 1, int(u/this%h) + 1)
    t = u/this%h - real(i - 1, wp)
    df(1:this%nf) = (1.0_wp - t)*this%val(i, 1:this%nf) + t*this%val(i + 1, 1:this%nf) &
      + this%h**2/6.0_wp*(((1.0_wp - t)**3 - (1.0_wp - t))*this%d2(i, 1:this%nf) &
                          + (t**3 - t)*this%d2(i + 1, 1:this%nf))
    w = singular_weight(xi)
    if (w > 0.0_wp) then
      call singular_part(xi, sing)
      df(1:this%nf) = df(1:this%nf) + w*sing(1:this%nf)
    end if
    taper = 1.0_wp - smoothstep((r - this%r_taper)/(this%r_cut - this%r_taper))
    df = taper*df
  end subroutine correction_functions

  !> Pair correction for d = R_j - R_i: dzeta(12,12) (ordering [U_i, Omega_i, U_j, Omega_j] ->
  !> [F_i, T_i, F_j, T_j], symmetric) and dxe(12,3,3) (delta x_k = sum dxe(k,a,b) E(a,b)).
  !> Zero for |d| >= cutoff; overlapping pairs as evaluation_distance says.
  pure subroutine pair_correction(this, d, dzeta, dxe)
    class(lubrication_t), intent(in) :: this
    real(wp), intent(in) :: d(3)
    real(wp), intent(out) :: dzeta(12, 12)
    real(wp), intent(out) :: dxe(12, 3, 3)
    real(wp) :: r, dhat(3), df(n_functions)

    r = norm2(d)
    if (r >= this%r_cut) then
      dzeta = 0.0_wp
      dxe = 0.0_wp
      return
    end if
    if (r > 0.0_wp) then
      dhat = d/r
    else
      dhat = [0.0_wp, 0.0_wp, 1.0_wp]   ! coincident centres: no direction, take z
    end if
    call this%correction_functions(this%evaluation_distance(r), df)
    call pair_tensors(df, dhat, dzeta, dxe)
  end subroutine pair_correction

  !> The corrections of every pair of r(3, N) closer than the cutoff, as a list of pair blocks.
  !> The pairs come from `pairs` when that list covers r to the cutoff (kf_pair_geometry), else
  !> they are found here. With `rotation` Q the blocks are those of the rotated configuration
  !> Q r (each separation d becomes Q d).
  subroutine pair_blocks(this, r, blocks, pairs, rotation)
    class(lubrication_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :)
    type(pair_blocks_t), intent(inout) :: blocks
    type(pair_geometry_t), intent(in), optional :: pairs
    real(wp), intent(in), optional :: rotation(3, 3)
    type(pair_geometry_t) :: own
    logical :: given
    given = .false.
    if (present(pairs)) given = pairs%covers(r, this%r_cut)
    if (given) then
      call fill(pairs)
    else
      call own%build(r, this%r_cut)
      call fill(own)
    end if
  contains
    subroutine fill(list)
      type(pair_geometry_t), intent(in) :: list
      real(wp) :: d(3), q(3, 3), zeta(12, 12), xe(12, 3, 3)
      integer, allocatable :: near(:)
      integer :: i, j, k, m
      logical :: rotate
      ! The pairs closer than the cutoff, in the order of the list; then their blocks, each
      ! computed and stored by one thread (the same list, bit for bit, for any thread count).
      allocate (near(list%size()))
      m = 0
      do k = 1, list%size()
        if (list%distance(k) >= this%r_cut) cycle
        m = m + 1
        near(m) = k
      end do
      call blocks%resize(m)
      rotate = present(rotation)
      q = 0.0_wp
      if (rotate) q = rotation
      !$omp parallel do default(none) shared(this, list, blocks, near, m, rotate, q) &
      !$omp private(k, i, j, d, zeta, xe) schedule(static)
      do k = 1, m
        call list%pair(near(k), i, j)
        d = list%separation(near(k))
        if (rotate) d = matmul(q, d)
        call this%pair_correction(d, zeta, xe)
        call blocks%store(k, i, j, zeta, xe)
      end do
      !$omp end parallel do
    end subroutine fill
  end subroutine pair_blocks

  !> The correction of the strain-stresslet coupling summed over every pair of r(3, N) closer
  !> than the cutoff, as pairings sm(k, l) = B_k : (sum over pairs of dS_1 + dS_2 for the strain
  !> B_l) with B_k = strain_basis(k), project units (the M functions; overlap rule as in
  !> pair_correction). Zero at L = 1 (no strain functions).
  subroutine stresslet_correction(this, r, sm)
    class(lubrication_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: sm(5, 5)
    type(pair_geometry_t) :: close_pairs
    real(wp) :: dist, dhat(3), df(n_functions), b(3, 3, 5)
    integer :: p, k, l
    sm = 0.0_wp
    if (.not. has_strain(this%order)) return
    do k = 1, 5
      b(:, :, k) = strain_basis(k)
    end do
    call close_pairs%build(r, this%r_cut)
    do p = 1, close_pairs%size()
      dist = close_pairs%distance(p)
      if (dist > 0.0_wp) then
        dhat = close_pairs%separation(p)/dist
      else
        dhat = [0.0_wp, 0.0_wp, 1.0_wp]
      end if
      call this%correction_functions(this%evaluation_distance(dist), df)
      do l = 1, 5
        do k = 1, 5
          sm(k, l) = sm(k, l) + sum(b(:, :, k)*pair_strain_stresslet(df, dhat, b(:, :, l)))
        end do
      end do
    end do
  end subroutine stresslet_correction

  !> Second derivatives of the cubic spline through y on a uniform grid of step h, clamped with
  !> zero slope at the first point and natural at the last.
  pure subroutine spline_second_derivatives(y, h, m)
    real(wp), intent(in) :: y(:)
    real(wp), intent(in) :: h
    real(wp), intent(out) :: m(:)
    real(wp) :: c(size(y)), rhs(size(y)), piv
    integer :: i, n
    n = size(y)
    ! Row 1: 2 m1 + m2 = 6 (y2 - y1)/h^2; rows i: m(i-1) + 4 m(i) + m(i+1) = 6 (second diff)/h^2;
    ! row n: m(n) = 0. Thomas algorithm.
    c(1) = 0.5_wp
    rhs(1) = 3.0_wp*(y(2) - y(1))/h**2
    do i = 2, n - 1
      piv = 4.0_wp - c(i - 1)
      c(i) = 1.0_wp/piv
      rhs(i) = (6.0_wp*(y(i + 1) - 2.0_wp*y(i) + y(i - 1))/h**2 - rhs(i - 1))/piv
    end do
    m(n) = 0.0_wp
    do i = n - 1, 1, -1
      m(i) = rhs(i) - c(i)*m(i + 1)
    end do
  end subroutine spline_second_derivatives

end module kf_lubrication
