!> Measurement kernels of the accuracy-versus-cost report (knotflow-accuracy, docs/accuracy.md):
!> the bead velocities relative to the ambient flow, their error norms against a reference,
!> the median wall time of one velocity evaluation, a short timed integration with its
!> statistics, the largest bead deviation between two states and a least-squares exponent in
!> log-log. The program decides what to measure; these routines only measure.
module kf_accuracy
  use, intrinsic :: iso_fortran_env, only: int64
  use kf_kinds, only: wp, i8
  use kf_vector_ops, only: sort_index
  use kf_error, only: error_t, fatal_error
  use kf_scene, only: scene_t
  use kf_dynamics, only: dynamics_t
  use kf_stepper, only: stepper_t
  use kf_stepper_factory, only: make_stepper
  implicit none
  private

  public :: wall_seconds, median, relative_velocity, velocity_error_norms, time_per_evaluation, &
            max_bead_deviation, loglog_slope, integrate_timed

  !> Cost and statistics of one timed integration.
  type, public :: run_stats_t
    real(wp) :: wall = 0.0_wp            !< wall seconds of the integration alone
    integer(i8) :: steps = 0             !< accepted steps
    integer(i8) :: rejected = 0
    integer(i8) :: evaluations = 0       !< right-hand-side evaluations
  end type run_stats_t

contains

  !> Wall-clock time in seconds (monotonic counter; only differences are meaningful).
  function wall_seconds() result(t)
    real(wp) :: t
    integer(int64) :: count, rate
    call system_clock(count, rate)
    t = real(count, wp)/real(rate, wp)
  end function wall_seconds

  !> Bead velocities relative to the ambient flow, u_i = dr_i/dt - v0(r_i): the force-driven
  !> part plus the disturbance of the flow (zero for a force-free bead in free draining).
  subroutine relative_velocity(dyn, r, u, error)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: u(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: v0(:, :)
    call dyn%velocity(r, u, error)
    if (allocated(error)) return
    allocate (v0(3, size(r, 2)))
    call dyn%flow_velocity(r, v0)
    u = u - v0
  end subroutine relative_velocity

  !> Errors of the bead velocities u(3, N) against u_ref(3, N):
  !> rms = sqrt(sum_i |u_i - u_ref,i|^2 / sum_i |u_ref,i|^2) and
  !> max = max_i |u_i - u_ref,i| / max_i |u_ref,i| (both 0 if u = u_ref; huge if u_ref = 0 /= u).
  pure subroutine velocity_error_norms(u, u_ref, rms, max_rel)
    real(wp), intent(in) :: u(:, :), u_ref(:, :)
    real(wp), intent(out) :: rms, max_rel
    real(wp) :: ref2, ref_max, diff2, diff_max
    integer :: i
    ref2 = 0.0_wp
    diff2 = 0.0_wp
    ref_max = 0.0_wp
    diff_max = 0.0_wp
    do i = 1, size(u, 2)
      ref2 = ref2 + sum(u_ref(:, i)**2)
      diff2 = diff2 + sum((u(:, i) - u_ref(:, i))**2)
      ref_max = max(ref_max, norm2(u_ref(:, i)))
      diff_max = max(diff_max, norm2(u(:, i) - u_ref(:, i)))
    end do
    if (diff2 == 0.0_wp) then
      rms = 0.0_wp
      max_rel = 0.0_wp
    else if (ref2 == 0.0_wp) then
      rms = huge(1.0_wp)
      max_rel = huge(1.0_wp)
    else
      rms = sqrt(diff2/ref2)
      max_rel = diff_max/ref_max
    end if
  end subroutine velocity_error_norms

  !> Median wall time of one velocity evaluation of `dyn` at r. A sample is the mean over a
  !> batch of evaluations lasting about 1 ms (one evaluation when that takes longer). Samples
  !> are taken until at least min_evals evaluations have been made and min_seconds have
  !> passed, or until max_seconds have passed (at least one sample is always taken).
  !> n_evals returns the number of timed evaluations.
  subroutine time_per_evaluation(dyn, r, min_evals, min_seconds, max_seconds, t_median, n_evals, error)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: r(:, :)
    integer, intent(in) :: min_evals
    real(wp), intent(in) :: min_seconds, max_seconds
    real(wp), intent(out) :: t_median
    integer, intent(out) :: n_evals
    type(error_t), allocatable, intent(out) :: error
    real(wp), parameter :: batch_seconds = 1.0e-3_wp
    real(wp), allocatable :: v(:, :), samples(:), grown(:)
    real(wp) :: start, t0, t1
    integer :: batch, k, n_samples
    allocate (v(3, size(r, 2)), samples(16))
    n_evals = 0
    n_samples = 0
    batch = 1
    start = wall_seconds()
    do
      t0 = wall_seconds()
      do k = 1, batch
        call dyn%velocity(r, v, error)
        if (allocated(error)) return
      end do
      t1 = wall_seconds()
      n_evals = n_evals + batch
      n_samples = n_samples + 1
      if (n_samples > size(samples)) then
        allocate (grown(2*size(samples)))
        grown(:size(samples)) = samples
        call move_alloc(grown, samples)
      end if
      samples(n_samples) = (t1 - t0)/batch
      if (t1 - start >= max_seconds) exit
      if (n_evals >= min_evals .and. t1 - start >= min_seconds) exit
      if (n_samples == 1 .and. samples(1) < batch_seconds) then
        ! The first sample calibrates the batch; it is dropped from the median.
        batch = min(100000, max(1, ceiling(batch_seconds/max(samples(1), 1.0e-9_wp))))
        n_samples = 0
      end if
    end do
    t_median = median(samples(:n_samples))
  end subroutine time_per_evaluation

  !> Median of a (copy of a) non-empty array (mean of the two middle values for an even size).
  pure function median(a) result(m)
    real(wp), intent(in) :: a(:)
    real(wp) :: m
    real(wp) :: s(size(a))
    integer :: n
    s = a(sort_index(a))
    n = size(s)
    if (mod(n, 2) == 1) then
      m = s((n + 1)/2)
    else
      m = 0.5_wp*(s(n/2) + s(n/2 + 1))
    end if
  end function median

  !> max_i |r_i - r_ref,i| over beads (Euclidean norm per bead).
  pure function max_bead_deviation(r, r_ref) result(d)
    real(wp), intent(in) :: r(:, :), r_ref(:, :)
    real(wp) :: d
    integer :: i
    d = 0.0_wp
    do i = 1, size(r, 2)
      d = max(d, norm2(r(:, i) - r_ref(:, i)))
    end do
  end function max_bead_deviation

  !> Slope of the least-squares line through (log x_i, log y_i): the exponent p of y ~ x^p.
  !> Needs at least two points with distinct x; all x, y > 0.
  subroutine loglog_slope(x, y, slope, error)
    real(wp), intent(in) :: x(:), y(:)
    real(wp), intent(out) :: slope
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: lx(size(x)), ly(size(y)), mx, my, sxx
    slope = 0.0_wp
    if (size(x) /= size(y) .or. size(x) < 2) then
      call fatal_error(error, 'loglog_slope: needs two arrays of the same size >= 2')
      return
    end if
    if (any(x <= 0.0_wp) .or. any(y <= 0.0_wp)) then
      call fatal_error(error, 'loglog_slope: all values must be > 0')
      return
    end if
    lx = log(x)
    ly = log(y)
    mx = sum(lx)/size(lx)
    my = sum(ly)/size(ly)
    sxx = sum((lx - mx)**2)
    if (sxx <= 0.0_wp) then
      call fatal_error(error, 'loglog_slope: all x are equal')
      return
    end if
    slope = sum((lx - mx)*(ly - my))/sxx
  end subroutine loglog_slope

  !> Integrate the scene's equations of motion from r (at t = 0) to t_end with the scene's
  !> integrator settings, timing the integration alone; r returns the state at t_end. With
  !> t_skip (0 < t_skip < t_end) the statistics cover only (t_skip, t_end]: the start-up of the
  !> step-size control is left out, as when a rate is to be extrapolated to a long run.
  subroutine integrate_timed(scene, r, t_end, stats, error, t_skip)
    type(scene_t), intent(in) :: scene
    real(wp), intent(inout) :: r(:, :)
    real(wp), intent(in) :: t_end
    type(run_stats_t), intent(out) :: stats
    type(error_t), allocatable, intent(out) :: error
    real(wp), intent(in), optional :: t_skip
    type(dynamics_t) :: dyn
    class(stepper_t), allocatable :: integ
    type(run_stats_t) :: skipped
    real(wp) :: t, t0
    call dyn%init(scene, size(r, 2), error)
    if (allocated(error)) return
    call make_stepper(scene%integrator, integ, error)
    if (allocated(error)) return
    t = 0.0_wp
    t0 = wall_seconds()
    if (present(t_skip)) then
      if (.not. (t_skip > 0.0_wp .and. t_skip < t_end)) then
        call fatal_error(error, 'integrate_timed: t_skip must be in (0, t_end)')
        return
      end if
      call integ%advance(dyn, t, r, t_skip, error)
      if (allocated(error)) return
      skipped%wall = wall_seconds() - t0
      skipped%steps = integ%steps()
      skipped%rejected = integ%rejected()
      skipped%evaluations = integ%evaluations()
    end if
    call integ%advance(dyn, t, r, t_end, error)
    stats%wall = wall_seconds() - t0 - skipped%wall
    stats%steps = integ%steps() - skipped%steps
    stats%rejected = integ%rejected() - skipped%rejected
    stats%evaluations = integ%evaluations() - skipped%evaluations
  end subroutine integrate_timed

end module kf_accuracy
