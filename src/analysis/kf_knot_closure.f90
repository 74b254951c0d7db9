!> Stochastic closure of an open chain (PHYSICS.md 7): a uniformly random point on the sphere
!> centred at the chain's centre of mass with radius 10 R_g (Marsaglia 1972) is joined to both
!> ends by straight segments and the closed polygon is classified; k_f is the fraction of
!> non-trivial closures, the spectrum the fraction of each type, the dominant type the most
!> frequent one (the first in table order on a tie).
module kf_knot_closure
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_knot_rng, only: knot_rng_t, rng_init, rng_sphere_point
  use kf_knot_invariants, only: n_knot_types, type_unknot, classify_polygon
  implicit none
  private

  real(wp), parameter, public :: closure_radius_factor = 10.0_wp
  integer, parameter, public :: default_closures = 1000
  integer(i8), parameter, public :: default_knot_seed = 1972_i8
  integer(i8), parameter :: projection_stream_offset = 2_i8**40

  !> The result of the closures of one chain.
  type, public :: knot_stats_t
    integer :: closures = 0                   !< number of closures
    integer(i8) :: seed = 0                   !< seed of the closure points
    real(wp) :: kf = 0.0_wp                   !< fraction of non-trivial closures
    real(wp) :: spectrum(n_knot_types) = 0.0_wp !< fraction of each type
    integer :: dominant = type_unknot         !< most frequent type
    integer, allocatable :: per_closure(:)    !< type of each closure (when requested)
  end type knot_stats_t

  public :: analyse_closures, closure_sphere

contains

  !> Centre and radius (10 R_g) of the closure sphere of r(3, N).
  subroutine closure_sphere(r, centre, radius)
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: centre(3), radius
    integer :: i
    centre = sum(r, dim=2)/size(r, 2)
    radius = 0.0_wp
    do i = 1, size(r, 2)
      radius = radius + sum((r(:, i) - centre)**2)
    end do
    radius = closure_radius_factor*sqrt(radius/size(r, 2))
  end subroutine closure_sphere

  !> Classify `closures` closures of the open chain r(3, N). Closure points come from the seeded
  !> stream (seed, stream) unless `points(3, C)` is given (then closures = C and the points are
  !> used in order). `reduce = .false.` skips the triangle reduction (for checks).
  subroutine analyse_closures(r, closures, seed, stats, error, stream, points, reduce, per_closure)
    real(wp), intent(in) :: r(:, :)
    integer, intent(in) :: closures
    integer(i8), intent(in) :: seed
    type(knot_stats_t), intent(out) :: stats
    type(error_t), allocatable, intent(out) :: error
    integer(i8), intent(in), optional :: stream
    real(wp), intent(in), optional :: points(:, :)
    logical, intent(in), optional :: reduce
    logical, intent(in), optional :: per_closure
    type(knot_rng_t) :: rng, rng_projection
    integer(i8) :: st
    real(wp), allocatable :: poly(:, :)
    real(wp) :: centre(3), radius
    integer, allocatable :: types(:)
    integer :: n, nc, k, counts(n_knot_types)
    n = size(r, 2)
    nc = closures
    if (present(points)) nc = size(points, 2)
    if (nc < 1) then
      call fatal_error(error, 'knot closures: the number of closures must be >= 1, got '//to_str(nc))
      return
    end if
    if (n < 2) then
      call fatal_error(error, 'knot closures: the chain has '//to_str(n)//' bead(s), at least 2 are needed')
      return
    end if
    st = 0_i8
    if (present(stream)) st = stream
    ! closure points and projection directions come from separate streams, so that the points
    ! depend only on (seed, stream) and not on how many projections were tried
    call rng_init(rng, seed, st)
    call rng_init(rng_projection, seed, st + projection_stream_offset)
    stats%closures = nc
    stats%seed = seed
    allocate (types(nc))
    call closure_sphere(r, centre, radius)
    allocate (poly(3, n + 1))
    if (n > 0) poly(:, 1:n) = r
    do k = 1, nc
      if (present(points)) then
        poly(:, n + 1) = points(:, k)
      else
        poly(:, n + 1) = centre + radius*rng_sphere_point(rng)
      end if
      if (n + 1 <= 5 .or. radius <= 0.0_wp) then
        types(k) = type_unknot        ! at most 5 sticks (or a single point): always unknotted
        cycle
      end if
      call classify_polygon(poly, rng_projection, types(k), error, reduce=reduce)
      if (allocated(error)) return
    end do
    do k = 1, n_knot_types
      counts(k) = count(types == k)
    end do
    stats%spectrum = real(counts, wp)/nc
    stats%kf = real(nc - counts(type_unknot), wp)/nc
    stats%dominant = maxloc(counts, 1)
    if (present(per_closure)) then
      if (per_closure) call move_alloc(types, stats%per_closure)
    end if
  end subroutine analyse_closures

end module kf_knot_closure
