!> Initial chain shapes (PHYSICS.md section 5): the open trefoil (orientations a-e), the
!> candy-cane with a seeded random rotation or a tilt about x, straight and random chains, and
!> coordinate files; then, optionally, a seeded random displacement of every bead.
module kf_chain_shapes
  use kf_kinds, only: wp, i8
  use kf_constants, only: pi, two_pi
  use kf_error, only: error_t, fatal_error
  use kf_scene_chain, only: chain_params_t, shape_trefoil, shape_candycane, shape_straight, shape_random, &
                            shape_file, trefoil_points, candycane_beads, check_chain, resolve_chain, &
                            read_chain_file, rotation_tilt_x
  use kf_random, only: rng_t
  implicit none
  private

  public :: build_initial_chain, trefoil_closed_points, random_rotation, tilt_x_rotation, &
            perturb_positions

  integer, parameter :: candycane_arc_points = 62
  real(wp), parameter :: candycane_radius = 20.0_wp
  real(wp), parameter :: candycane_ds = 0.05105_wp
  real(wp), parameter :: candycane_rod_spacing = 1.02_wp
  !> The perturbation's stream: seeded with ieor(seed, this key), so that it is not the stream
  !> of the candy-cane's rotation or the random chain drawn from the same seed.
  integer(i8), parameter :: perturbation_stream_key = 7046029254386353131_i8

  ! 5-point Gauss-Legendre rule on [-1, 1].
  real(wp), parameter :: gl_x(5) = [-0.9061798459386640_wp, -0.5384693101056831_wp, 0.0_wp, &
                                    0.5384693101056831_wp, 0.9061798459386640_wp]
  real(wp), parameter :: gl_w(5) = [0.2369268850561891_wp, 0.4786286704993665_wp, &
                                    0.5688888888888889_wp, 0.4786286704993665_wp, 0.2369268850561891_wp]

contains

  !> Build the initial bead positions r(3, N) described by `params`, after checking them by the
  !> &chain group's own rules (kf_scene_chain: names, ranges, the bead count of the shape, the
  !> coordinate file). `rotation` is the random rotation applied to the candy-cane
  !> (r = rotation * r_unrotated), the identity otherwise. With perturbation p > 0 every bead is
  !> then displaced by p times an isotropic random unit vector (perturb_positions); p = 0 leaves
  !> the shape untouched (no random number is drawn).
  subroutine build_initial_chain(params, r, rotation, error)
    type(chain_params_t), intent(in) :: params
    real(wp), allocatable, intent(out) :: r(:, :)
    real(wp), intent(out) :: rotation(3, 3)
    type(error_t), allocatable, intent(out) :: error
    type(chain_params_t) :: p

    rotation = identity3()
    p = params
    call check_chain(p, '', error)
    if (allocated(error)) return
    if (p%shape == shape_file) then
      call read_chain_file(p%coordinate_file, r, error)
      if (allocated(error)) then
        error%message = '&chain: '//error%message
        return
      end if
    else
      call resolve_chain(p, '', error)
      if (allocated(error)) return
      select case (trim(p%shape))
      case (shape_trefoil)
        call build_trefoil(p, r)
      case (shape_candycane)
        call build_candycane(p, r, rotation)
      case (shape_straight)
        call build_straight(p, r)
      case (shape_random)
        call build_random(p, r, error)
        if (allocated(error)) return
      end select
    end if
    if (p%perturbation > 0.0_wp) call perturb_positions(r, p%perturbation, p%seed)
  end subroutine build_initial_chain

  !> Displace every bead by `amplitude` times a unit vector drawn uniformly on the sphere
  !> (cos(polar angle) uniform in [-1, 1), azimuth uniform in [0, 2 pi)), bead 1 first, from the
  !> stream seeded with ieor(seed, perturbation_stream_key): each displacement has length
  !> `amplitude` (to rounding), its components at most `amplitude` in size.
  subroutine perturb_positions(r, amplitude, seed)
    real(wp), intent(inout) :: r(:, :)
    real(wp), intent(in) :: amplitude
    integer(i8), intent(in) :: seed
    type(rng_t) :: rng
    real(wp) :: cz, sz, phi
    integer :: k
    call rng%init(ieor(seed, perturbation_stream_key))
    do k = 1, size(r, 2)
      cz = 2.0_wp*rng%uniform() - 1.0_wp
      phi = two_pi*rng%uniform()
      sz = sqrt(max(0.0_wp, 1.0_wp - cz*cz))
      r(:, k) = r(:, k) + amplitude*[sz*cos(phi), sz*sin(phi), cz]
    end do
  end subroutine perturb_positions

  pure function identity3() result(m)
    real(wp) :: m(3, 3)
    m = 0.0_wp
    m(1, 1) = 1.0_wp
    m(2, 2) = 1.0_wp
    m(3, 3) = 1.0_wp
  end function identity3

  !> The trefoil curve (sin s + 2 sin 2s, cos s - 2 cos 2s, -sin 3s) and its derivative.
  pure function trefoil_curve(s) result(c)
    real(wp), intent(in) :: s
    real(wp) :: c(3)
    c = [sin(s) + 2.0_wp*sin(2.0_wp*s), cos(s) - 2.0_wp*cos(2.0_wp*s), -sin(3.0_wp*s)]
  end function trefoil_curve

  pure function trefoil_speed(s) result(v)
    real(wp), intent(in) :: s
    real(wp) :: v
    v = norm2([cos(s) + 4.0_wp*cos(2.0_wp*s), -sin(s) + 4.0_wp*sin(2.0_wp*s), -3.0_wp*cos(3.0_wp*s)])
  end function trefoil_speed

  !> Arc length of the unscaled trefoil from 0 to s (composite 5-point Gauss-Legendre).
  pure function trefoil_arc(s) result(arc)
    real(wp), intent(in) :: s
    real(wp) :: arc, h, a
    integer :: m, k, q
    m = max(1, ceiling(abs(s)/0.02_wp))
    h = s/m
    arc = 0.0_wp
    do k = 1, m
      a = (k - 1)*h
      do q = 1, 5
        arc = arc + 0.5_wp*h*gl_w(q)*trefoil_speed(a + 0.5_wp*h*(gl_x(q) + 1.0_wp))
      end do
    end do
  end function trefoil_arc

  !> The 100 points of the closed trefoil, evenly spaced in arc length from s = 0 and scaled so
  !> that the arc spacing is `spacing`; `scale` returns the scale factor used.
  subroutine trefoil_closed_points(spacing, p, scale)
    real(wp), intent(in) :: spacing
    real(wp), intent(out) :: p(3, trefoil_points)
    real(wp), intent(out) :: scale
    real(wp) :: total, target, s
    integer :: k, it
    total = trefoil_arc(two_pi)
    scale = spacing*trefoil_points/total
    s = 0.0_wp
    do k = 1, trefoil_points
      target = (k - 1)*total/trefoil_points
      if (k > 1) s = s + (total/trefoil_points)/trefoil_speed(s)
      do it = 1, 50
        s = s - (trefoil_arc(s) - target)/trefoil_speed(s)
        if (abs(trefoil_arc(s) - target) < 1.0e-14_wp*total) exit
      end do
      p(:, k) = scale*trefoil_curve(s)
    end do
  end subroutine trefoil_closed_points

  !> The open trefoil: drop point `trefoil_removed_point` and start the chain after it.
  subroutine build_trefoil(params, r)
    type(chain_params_t), intent(in) :: params
    real(wp), allocatable, intent(out) :: r(:, :)
    real(wp) :: p(3, trefoil_points), rot(3, 3), scale
    integer :: k, m

    m = params%trefoil_removed_point
    rot = 0.0_wp
    select case (params%orientation)
    case ('a')
      rot = identity3()
    case ('b')   ! about x by pi/2: y -> z, z -> -y
      rot(1, 1) = 1.0_wp
      rot(3, 2) = 1.0_wp
      rot(2, 3) = -1.0_wp
    case ('c')   ! about x by pi
      rot(1, 1) = 1.0_wp
      rot(2, 2) = -1.0_wp
      rot(3, 3) = -1.0_wp
    case ('d')   ! about z by pi/2: x -> y, y -> -x
      rot(2, 1) = 1.0_wp
      rot(1, 2) = -1.0_wp
      rot(3, 3) = 1.0_wp
    case ('e')   ! about z by 3 pi/2: x -> -y, y -> x
      rot(2, 1) = -1.0_wp
      rot(1, 2) = 1.0_wp
      rot(3, 3) = 1.0_wp
    end select
    call trefoil_closed_points(params%bond_length, p, scale)
    allocate (r(3, trefoil_points - 1))
    do k = 1, trefoil_points - 1
      r(:, k) = matmul(rot, p(:, modulo(m + k - 1, trefoil_points) + 1))
    end do
  end subroutine build_trefoil

  !> The candy-cane: rod (-1.02 (91 - s), 0, 0), s = 1..90, then the semicircle
  !> (20 cos s, 20 sin s + 20, 0) from s = -pi/2 in steps 0.05105 (62 points); then a rotation
  !> about the origin: uniformly random drawn from `seed` (candycane_rotation = 'random'), or
  !> about the x axis by tilt_deg ('tilt_x'; the seed is not used).
  subroutine build_candycane(params, r, rotation)
    type(chain_params_t), intent(in) :: params
    real(wp), allocatable, intent(out) :: r(:, :)
    real(wp), intent(out) :: rotation(3, 3)
    type(rng_t) :: rng
    integer :: k, n_rod
    real(wp) :: s

    n_rod = candycane_beads - candycane_arc_points
    allocate (r(3, candycane_beads))
    do k = 1, n_rod
      r(:, k) = [-candycane_rod_spacing*(n_rod + 1 - k), 0.0_wp, 0.0_wp]
    end do
    do k = 0, candycane_arc_points - 1
      s = -0.5_wp*pi + k*candycane_ds
      r(:, n_rod + 1 + k) = [candycane_radius*cos(s), candycane_radius*sin(s) + candycane_radius, 0.0_wp]
    end do
    if (params%candycane_rotation == rotation_tilt_x) then
      rotation = tilt_x_rotation(params%tilt_deg)
    else
      call rng%init(params%seed)
      rotation = random_rotation(rng)
    end if
    r = matmul(rotation, r)
  end subroutine build_candycane

  !> The rotation about the x axis by `deg` degrees (y turns towards z). Multiples of 90 degrees
  !> take exact cosines and sines (0, 1, -1), so that e.g. 90 maps y onto z exactly.
  pure function tilt_x_rotation(deg) result(m)
    real(wp), intent(in) :: deg
    real(wp) :: m(3, 3)
    real(wp) :: c, s, q
    q = modulo(deg, 360.0_wp)
    if (q == 0.0_wp) then
      c = 1.0_wp; s = 0.0_wp
    else if (q == 90.0_wp) then
      c = 0.0_wp; s = 1.0_wp
    else if (q == 180.0_wp) then
      c = -1.0_wp; s = 0.0_wp
    else if (q == 270.0_wp) then
      c = 0.0_wp; s = -1.0_wp
    else
      c = cos(deg*pi/180.0_wp); s = sin(deg*pi/180.0_wp)
    end if
    m = 0.0_wp
    m(1, 1) = 1.0_wp
    m(2, 2) = c
    m(3, 2) = s
    m(2, 3) = -s
    m(3, 3) = c
  end function tilt_x_rotation

  !> A uniformly distributed rotation matrix (Shoemake's random unit quaternion, 1992).
  function random_rotation(rng) result(m)
    type(rng_t), intent(inout) :: rng
    real(wp) :: m(3, 3)
    real(wp) :: u1, u2, u3, w, x, y, z
    u1 = rng%uniform()
    u2 = rng%uniform()
    u3 = rng%uniform()
    x = sqrt(1.0_wp - u1)*sin(two_pi*u2)
    y = sqrt(1.0_wp - u1)*cos(two_pi*u2)
    z = sqrt(u1)*sin(two_pi*u3)
    w = sqrt(u1)*cos(two_pi*u3)
    m(1, :) = [1.0_wp - 2.0_wp*(y*y + z*z), 2.0_wp*(x*y - w*z), 2.0_wp*(x*z + w*y)]
    m(2, :) = [2.0_wp*(x*y + w*z), 1.0_wp - 2.0_wp*(x*x + z*z), 2.0_wp*(y*z - w*x)]
    m(3, :) = [2.0_wp*(x*z - w*y), 2.0_wp*(y*z + w*x), 1.0_wp - 2.0_wp*(x*x + y*y)]
  end function random_rotation

  !> n_beads along straight_direction with spacing bond_length, centred at the origin.
  subroutine build_straight(params, r)
    type(chain_params_t), intent(in) :: params
    real(wp), allocatable, intent(out) :: r(:, :)
    real(wp) :: u(3)
    integer :: k
    u = params%straight_direction/norm2(params%straight_direction)
    allocate (r(3, params%n_beads))
    do k = 1, params%n_beads
      r(:, k) = (k - 0.5_wp*(params%n_beads + 1))*params%bond_length*u
    end do
  end subroutine build_straight

  !> A random walk of n_beads with steps bond_length in uniformly random directions, keeping
  !> non-adjacent beads at least 1 apart (up to 1000 tries per bead, 100 restarts), centred
  !> at its centre of mass. Deterministic for a given seed.
  subroutine build_random(params, r, error)
    type(chain_params_t), intent(in) :: params
    real(wp), allocatable, intent(out) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    type(rng_t) :: rng
    real(wp) :: u(3), cz, phi, trial(3)
    integer :: n, i, j, attempt, restart
    logical :: ok
    n = params%n_beads
    allocate (r(3, n))
    call rng%init(params%seed)
    do restart = 1, 100
      r(:, 1) = 0.0_wp
      do i = 2, n
        ok = .false.
        do attempt = 1, 1000
          cz = 2.0_wp*rng%uniform() - 1.0_wp
          phi = two_pi*rng%uniform()
          u = [sqrt(1.0_wp - cz*cz)*cos(phi), sqrt(1.0_wp - cz*cz)*sin(phi), cz]
          trial = r(:, i - 1) + params%bond_length*u
          ok = .true.
          do j = 1, i - 2
            if (sum((trial - r(:, j))**2) < 1.0_wp) then
              ok = .false.
              exit
            end if
          end do
          if (ok) exit
        end do
        if (.not. ok) exit
        r(:, i) = trial
      end do
      if (ok) exit
    end do
    if (.not. ok) then
      call fatal_error(error, 'chain: could not grow a self-avoiding random chain (n_beads too large?)')
      return
    end if
    do j = 1, 3
      r(j, :) = r(j, :) - sum(r(j, :))/n
    end do
  end subroutine build_random

end module kf_chain_shapes
