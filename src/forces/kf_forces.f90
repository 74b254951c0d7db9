!> Conservative forces on the beads (PHYSICS.md section 2), each term only if the scene enables it:
!>  - springs   U_s = (k/2) sum_i (l_i - l0)^2 over the N-1 bonds;
!>  - bending   U_b = (A/(2 l0)) sum_i beta_i^2 over the N-2 inner beads, cos beta_i = b_{i-1}.b_i;
!>  - excluded volume (our choice): U_ev = (ev_strength/2) (ev_range - r_ij)^2 for every
!>    non-bonded pair |i - j| > 1 closer than ev_range (a soft, linear repulsion F = ev_strength
!>    (ev_range - r) along the line of centres);
!>  - a constant external force on every bead (no potential is reported for it).
!> Units: force F0 = pi eta d^2 gamma_dot, k per pi eta d gamma_dot, A per pi eta d^4 gamma_dot.
module kf_forces
  use kf_kinds, only: wp
  use kf_vector_ops, only: cross
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_scene_forces, only: forces_params_t, check_forces
  use kf_pair_geometry, only: pair_geometry_t
  implicit none
  private

  !> The enabled force terms and their constants (resolved at init).
  type, public :: forces_t
    integer :: n = 0                  !< number of beads
    logical :: springs = .false.
    logical :: bending = .false.
    logical :: excluded_volume = .false.
    logical :: external = .false.
    real(wp) :: k = 0.0_wp            !< spring constant
    real(wp) :: l0 = 0.0_wp           !< rest bond length
    real(wp) :: a_over_l0 = 0.0_wp    !< bending stiffness A / l0
    real(wp) :: ev_strength = 0.0_wp
    real(wp) :: ev_range = 0.0_wp
    real(wp) :: f_ext(3) = 0.0_wp
  contains
    procedure :: init => forces_init
    procedure :: compute => forces_compute
    procedure :: energy => forces_energy
    procedure :: jacobian => forces_jacobian
    procedure :: pair_range
  end type forces_t

contains

  !> Validate the parameters (the &forces group's own rules, kf_scene_forces) and set up the enabled terms for a chain of n_beads.
  subroutine forces_init(this, params, n_beads, bond_length, error)
    class(forces_t), intent(out) :: this
    type(forces_params_t), intent(in) :: params
    integer, intent(in) :: n_beads
    real(wp), intent(in) :: bond_length
    type(error_t), allocatable, intent(out) :: error
    if (n_beads < 1) then
      call fatal_error(error, 'forces: number of beads = '//to_str(n_beads)//' (must be >= 1)')
      return
    end if
    if (.not. bond_length > 0.0_wp) then
      call fatal_error(error, 'forces: bond_length = '//to_str(bond_length)//' (must be > 0)')
      return
    end if
    call check_forces(params, '', error)
    if (allocated(error)) return
    this%n = n_beads
    this%l0 = bond_length
    this%springs = params%springs
    this%k = params%spring_k
    this%bending = params%bending
    this%a_over_l0 = params%bending_a/bond_length
    this%excluded_volume = params%excluded_volume
    this%ev_strength = params%ev_strength
    this%ev_range = params%ev_range
    this%f_ext = params%external_force
    this%external = any(params%external_force /= 0.0_wp)
  end subroutine forces_init

  !> Total force f(3, N) on each bead at positions r(3, N). The excluded volume takes its pairs
  !> from `pairs` when that list covers r to pair_range() (kf_pair_geometry), else finds them.
  subroutine forces_compute(this, r, f, pairs)
    class(forces_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: f(:, :)
    type(pair_geometry_t), intent(in), optional :: pairs
    type(pair_geometry_t) :: own
    logical :: given
    integer :: n, i
    n = size(r, 2)
    f = 0.0_wp
    if (this%springs) call add_springs(this%k, this%l0, r, f)
    if (this%bending .and. n >= 3) call add_bending(this%a_over_l0, r, f)
    if (this%excluded_volume) then
      given = .false.
      if (present(pairs)) given = pairs%covers(r, this%ev_range)
      if (given) then
        call add_excluded_volume(this%ev_strength, this%ev_range, pairs, f)
      else
        call own%build(r, this%ev_range)
        call add_excluded_volume(this%ev_strength, this%ev_range, own, f)
      end if
    end if
    if (this%external) then
      do i = 1, n
        f(:, i) = f(:, i) + this%f_ext
      end do
    end if
  end subroutine forces_compute

  !> k = dF/dr at r(3, N) as a dense 3N x 3N matrix (entry (3(i-1)+a, 3(j-1)+b) = dF_i,a/dr_j,b).
  !> Springs and bending by central differences (displacements jacobian_step, units of d) with
  !> beads five apart moved together: a bead's bonded force depends on the beads at most two
  !> away, so each force change has one moved bead as its source (30 force evaluations of the
  !> bonded terms); the excluded volume exactly, pair by pair: for x = r_i - r_j, d = |x| <
  !> ev_range, the force on i, s (ev_range - d) x/d, has the derivative
  !>   E = s [(ev_range/d - 1)(I - x x^T/d^2) - x x^T/d^2]
  !> (+E on the diagonal blocks of i and j, -E on the two off-diagonal ones). The external force
  !> drops out. Symmetric up to the differencing error (the forces derive from a potential).
  subroutine forces_jacobian(this, r, k)
    class(forces_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: k(:, :)
    real(wp), parameter :: jacobian_step = 1.0e-5_wp
    integer, parameter :: stride = 5
    type(forces_t) :: bonded
    type(pair_geometry_t) :: pairs
    real(wp), allocatable :: rp(:, :), fp(:, :), fm(:, :)
    real(wp) :: x(3), d, e(3, 3), xx(3, 3)
    integer :: c, a, j, m, n, p, i, b
    n = size(r, 2)
    k = 0.0_wp
    bonded = this
    bonded%excluded_volume = .false.
    bonded%external = .false.
    allocate (rp, fp, fm, mold=r)
    do c = 1, min(stride, n)
      do a = 1, 3
        rp = r
        rp(a, c:n:stride) = r(a, c:n:stride) + jacobian_step
        call bonded%compute(rp, fp)
        rp(a, c:n:stride) = r(a, c:n:stride) - jacobian_step
        call bonded%compute(rp, fm)
        fp = (fp - fm)/(2.0_wp*jacobian_step)
        do j = c, n, stride
          do m = max(1, j - 2), min(n, j + 2)
            k(3*m - 2:3*m, 3*(j - 1) + a) = fp(:, m)
          end do
        end do
      end do
    end do
    if (.not. this%excluded_volume) return
    call pairs%build(r, this%ev_range)
    do p = 1, pairs%size()
      call pairs%pair(p, i, j)
      if (abs(j - i) < 2) cycle
      d = pairs%distance(p)
      if (.not. (d < this%ev_range .and. d > 0.0_wp)) cycle
      x = -pairs%separation(p)/d            ! unit vector from j to i
      do b = 1, 3
        xx(:, b) = x*x(b)
      end do
      e = -this%ev_strength*xx
      do b = 1, 3
        e(:, b) = e(:, b) - this%ev_strength*(this%ev_range/d - 1.0_wp)*xx(:, b)
        e(b, b) = e(b, b) + this%ev_strength*(this%ev_range/d - 1.0_wp)
      end do
      k(3*i - 2:3*i, 3*i - 2:3*i) = k(3*i - 2:3*i, 3*i - 2:3*i) + e
      k(3*j - 2:3*j, 3*j - 2:3*j) = k(3*j - 2:3*j, 3*j - 2:3*j) + e
      k(3*i - 2:3*i, 3*j - 2:3*j) = k(3*i - 2:3*i, 3*j - 2:3*j) - e
      k(3*j - 2:3*j, 3*i - 2:3*i) = k(3*j - 2:3*j, 3*i - 2:3*i) - e
    end do
  end subroutine forces_jacobian

  !> The largest centre distance at which a pair force acts (0 when none is enabled).
  pure real(wp) function pair_range(this)
    class(forces_t), intent(in) :: this
    pair_range = 0.0_wp
    if (this%excluded_volume) pair_range = this%ev_range
  end function pair_range

  !> Potential energy of the enabled conservative terms (the external force is not included).
  function forces_energy(this, r) result(u)
    class(forces_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp) :: u
    real(wp) :: b1(3), b2(3), c, s, dist
    integer :: n, i, j
    n = size(r, 2)
    u = 0.0_wp
    if (this%springs) then
      do i = 1, n - 1
        u = u + 0.5_wp*this%k*(norm2(r(:, i + 1) - r(:, i)) - this%l0)**2
      end do
    end if
    if (this%bending) then
      do i = 2, n - 1
        b1 = r(:, i) - r(:, i - 1)
        b2 = r(:, i + 1) - r(:, i)
        b1 = b1/norm2(b1)
        b2 = b2/norm2(b2)
        c = dot_product(b1, b2)
        s = norm2(cross(b1, b2))
        u = u + 0.5_wp*this%a_over_l0*atan2(s, c)**2
      end do
    end if
    if (this%excluded_volume) then
      do i = 1, n - 2
        do j = i + 2, n
          dist = norm2(r(:, i) - r(:, j))
          if (dist < this%ev_range) u = u + 0.5_wp*this%ev_strength*(this%ev_range - dist)**2
        end do
      end do
    end if
  end function forces_energy

  !> Harmonic springs between consecutive beads.
  pure subroutine add_springs(k, l0, r, f)
    real(wp), intent(in) :: k, l0
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(inout) :: f(:, :)
    real(wp) :: b(3), l, fb(3)
    integer :: i
    do i = 1, size(r, 2) - 1
      b = r(:, i + 1) - r(:, i)
      l = sqrt(b(1)**2 + b(2)**2 + b(3)**2)
      fb = (k*(l - l0)/l)*b
      f(:, i) = f(:, i) + fb
      f(:, i + 1) = f(:, i + 1) - fb
    end do
  end subroutine add_springs

  !> Discrete-elastica bending. With w+ = b1 - c b2 and w- = b2 - c b1 (b1, b2 the unit bonds
  !> before and after bead i, c = cos beta, |w+| = |w-| = sin beta):
  !>   F_{i+1} = (A/l0) beta w+ / (|w+| l_i),  F_{i-1} = -(A/l0) beta w- / (|w-| l_{i-1}),
  !>   F_i = -(F_{i-1} + F_{i+1}).
  !> Using w/|w| avoids dividing by sin beta: the force stays bounded (|F| <= A beta / (l0 l))
  !> as beta -> pi and vanishes smoothly as beta -> 0; an exactly degenerate w gives zero.
  pure subroutine add_bending(a_over_l0, r, f)
    real(wp), intent(in) :: a_over_l0
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(inout) :: f(:, :)
    real(wp) :: b1(3), b2(3), l1, l2, c, s, beta, wp_(3), wm(3), np, nm, fp(3), fm(3)
    integer :: i
    do i = 2, size(r, 2) - 1
      b1 = r(:, i) - r(:, i - 1)
      b2 = r(:, i + 1) - r(:, i)
      l1 = sqrt(b1(1)**2 + b1(2)**2 + b1(3)**2)
      l2 = sqrt(b2(1)**2 + b2(2)**2 + b2(3)**2)
      b1 = b1/l1
      b2 = b2/l2
      c = b1(1)*b2(1) + b1(2)*b2(2) + b1(3)*b2(3)
      wp_ = b1 - c*b2
      wm = b2 - c*b1
      np = sqrt(wp_(1)**2 + wp_(2)**2 + wp_(3)**2)
      nm = sqrt(wm(1)**2 + wm(2)**2 + wm(3)**2)
      s = 0.5_wp*(np + nm)
      beta = atan2(s, c)
      if (np > 0.0_wp) then
        fp = (a_over_l0*beta/(np*l2))*wp_
      else
        fp = 0.0_wp
      end if
      if (nm > 0.0_wp) then
        fm = -(a_over_l0*beta/(nm*l1))*wm
      else
        fm = 0.0_wp
      end if
      f(:, i + 1) = f(:, i + 1) + fp
      f(:, i - 1) = f(:, i - 1) + fm
      f(:, i) = f(:, i) - fp - fm
    end do
  end subroutine add_bending

  !> Linear repulsion between non-bonded pairs (|i - j| > 1) closer than `range`; `pairs` holds
  !> (at least) every pair closer than `range`.
  pure subroutine add_excluded_volume(strength, range, pairs, f)
    real(wp), intent(in) :: strength, range
    type(pair_geometry_t), intent(in) :: pairs
    real(wp), intent(inout) :: f(:, :)
    real(wp) :: dist, fij(3)
    integer :: i, j, k
    do k = 1, pairs%size()
      call pairs%pair(k, i, j)
      if (j - i < 2) cycle
      dist = pairs%distance(k)
      if (dist < range .and. dist > 0.0_wp) then
        ! repulsion along r_i - r_j = -(separation)
        fij = (-strength*(range - dist)/dist)*pairs%separation(k)
        f(:, i) = f(:, i) + fij
        f(:, j) = f(:, j) - fij
      end if
    end do
  end subroutine add_excluded_volume

end module kf_forces
