!> The random numbers of the knot analysis: L'Ecuyer's MRG32k3a combined multiple recursive
!> generator (Operations Research 47, 159 (1999)) in 64-bit integer arithmetic (no overflow),
!> seeded from a 64-bit seed and a stream number, so that every subchain of a knot matrix has
!> its own reproducible stream whatever the partition over ranks.
module kf_knot_rng
  use kf_kinds, only: wp, i8
  implicit none
  private

  integer(i8), parameter :: m1 = 4294967087_i8, m2 = 4294944443_i8
  integer(i8), parameter :: a12 = 1403580_i8, a13n = 810728_i8
  integer(i8), parameter :: a21 = 527612_i8, a23n = 1370589_i8
  real(wp), parameter :: norm = 1.0_wp/(real(m1, wp) + 1.0_wp)

  !> Generator state (six integers, none of the two triples all zero).
  type, public :: knot_rng_t
    integer(i8) :: s(6) = [12345_i8, 12345_i8, 12345_i8, 12345_i8, 12345_i8, 12345_i8]
  end type knot_rng_t

  public :: rng_init, rng_uniform, rng_sphere_point

contains

  !> Seed the generator from `seed` (any value) and `stream` (>= 0).
  subroutine rng_init(rng, seed, stream)
    type(knot_rng_t), intent(out) :: rng
    integer(i8), intent(in) :: seed
    integer(i8), intent(in) :: stream
    real(wp) :: u
    integer :: k
    rng%s(1) = 1_i8 + modulo(seed, m1 - 1_i8)
    rng%s(2) = 1_i8 + modulo(seed/(m1 - 1_i8) + 7_i8, m1 - 1_i8)
    rng%s(3) = 1_i8 + modulo(stream, m1 - 1_i8)
    rng%s(4) = 1_i8 + modulo(stream/(m2 - 1_i8) + 12345_i8, m2 - 1_i8)
    rng%s(5) = 1_i8 + modulo(seed + 69069_i8, m2 - 1_i8)
    rng%s(6) = 1_i8 + modulo(modulo(stream, 1000003_i8)*4093_i8 + 1_i8, m2 - 1_i8)
    do k = 1, 40          ! decorrelate nearby seeds and streams
      u = rng_uniform(rng)
    end do
  end subroutine rng_init

  !> A uniform number in (0, 1).
  real(wp) function rng_uniform(rng) result(u)
    type(knot_rng_t), intent(inout) :: rng
    integer(i8) :: p1, p2
    p1 = modulo(a12*rng%s(2) - a13n*rng%s(1), m1)
    rng%s(1:2) = rng%s(2:3)
    rng%s(3) = p1
    p2 = modulo(a21*rng%s(6) - a23n*rng%s(4), m2)
    rng%s(4:5) = rng%s(5:6)
    rng%s(6) = p2
    if (p1 > p2) then
      u = real(p1 - p2, wp)*norm
    else
      u = real(p1 - p2 + m1, wp)*norm
    end if
  end function rng_uniform

  !> A uniformly distributed point on the unit sphere (Marsaglia, Ann. Math. Stat. 43, 645 (1972)).
  function rng_sphere_point(rng) result(x)
    type(knot_rng_t), intent(inout) :: rng
    real(wp) :: x(3)
    real(wp) :: u, v, s
    do
      u = 2.0_wp*rng_uniform(rng) - 1.0_wp
      v = 2.0_wp*rng_uniform(rng) - 1.0_wp
      s = u*u + v*v
      if (s < 1.0_wp) exit
    end do
    x = [2.0_wp*u*sqrt(1.0_wp - s), 2.0_wp*v*sqrt(1.0_wp - s), 1.0_wp - 2.0_wp*s]
  end function rng_sphere_point

end module kf_knot_rng
