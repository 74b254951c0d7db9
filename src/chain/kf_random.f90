!> A small, seedable, deterministic pseudo-random generator: xoshiro256** (Blackman and Vigna,
!> 2018) seeded through splitmix64 (Steele, Lea, Flood 2014). The 256-bit state lives in an
!> `rng_t` value, so every case owns its own stream and the state can be checkpointed.
!> Integer arithmetic wraps modulo 2^64 (this file is compiled with -fwrapv).
module kf_random
  use kf_kinds, only: wp, i8
  implicit none
  private

  !> xoshiro256** state; `s` may be saved and restored to continue a stream.
  type, public :: rng_t
    integer(i8) :: s(4) = 0_i8
  contains
    procedure :: init => rng_init
    procedure :: next_int => rng_next_int
    procedure :: uniform => rng_uniform
  end type rng_t

  ! splitmix64 constants 0x9E3779B97F4A7C15, 0xBF58476D1CE4E5B9, 0x94D049BB133111EB as signed int64.
  integer(i8), parameter :: golden = -7046029254386353131_i8
  integer(i8), parameter :: mix1 = -4658895280553007687_i8
  integer(i8), parameter :: mix2 = -7723592293110705685_i8

contains

  !> Seed the generator: the four state words are successive splitmix64 outputs of `seed`.
  subroutine rng_init(this, seed)
    class(rng_t), intent(out) :: this
    integer(i8), intent(in) :: seed
    integer(i8) :: x
    integer :: k
    x = seed
    do k = 1, 4
      x = x + golden
      this%s(k) = splitmix_mix(x)
    end do
  end subroutine rng_init

  !> The splitmix64 output function.
  pure function splitmix_mix(x) result(z)
    integer(i8), intent(in) :: x
    integer(i8) :: z
    z = x
    z = ieor(z, ishft(z, -30))*mix1
    z = ieor(z, ishft(z, -27))*mix2
    z = ieor(z, ishft(z, -31))
  end function splitmix_mix

  !> The next 64 random bits (as a signed 64-bit integer).
  function rng_next_int(this) result(res)
    class(rng_t), intent(inout) :: this
    integer(i8) :: res
    integer(i8) :: t
    res = ishftc(this%s(2)*5_i8, 7)*9_i8
    t = ishft(this%s(2), 17)
    this%s(3) = ieor(this%s(3), this%s(1))
    this%s(4) = ieor(this%s(4), this%s(2))
    this%s(2) = ieor(this%s(2), this%s(3))
    this%s(1) = ieor(this%s(1), this%s(4))
    this%s(3) = ieor(this%s(3), t)
    this%s(4) = ishftc(this%s(4), 45)
  end function rng_next_int

  !> A uniform deviate in [0, 1) with 53 random bits.
  function rng_uniform(this) result(u)
    class(rng_t), intent(inout) :: this
    real(wp) :: u
    u = real(ishft(this%next_int(), -11), wp)*2.0_wp**(-53)
  end function rng_uniform

end module kf_random
