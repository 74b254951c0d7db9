!> Dynamical modes of a chain in shear (PHYSICS.md 6, the reference study's Table 1: mode I,
!> a >> b >~ c, theta near 0 or pi, phi increasing (rolling about the vorticity), many close
!> pairs; mode II, a >> b >> c, theta near pi/2, phi near pi/2 (flow direction, tumbling), few
!> close pairs) from the shape series. The one mode rule of knotflow (docs/analysis.md); the
!> Python tools read its result from /analysis/shape. Per frame:
!>   mode I  (1): a >= 3 b, |cos theta| >= 0.7 and at least 3 close pairs;
!>   mode II (2): a >= 3 b, b >= 2 c, |cos theta| <= 0.5, |sin phi| >= 0.7 and fewer than 3
!>               close pairs;
!>   else 0 (unclassified).
!> Per case, over the second half of the frames (the long-time state): 0 unless at least half
!> of them (and at least one) are classified; else the more frequent of modes I and II (I on a
!> tie), and mode I only if phi, unwrapped, ends higher than it starts (the chain rolls).
module kf_modes
  use kf_kinds, only: wp
  use kf_shape, only: shape_t
  use kf_spectra, only: unwrap_phase
  implicit none
  private

  real(wp), parameter, public :: mode_elongation = 3.0_wp      !< a/b threshold (both modes)
  real(wp), parameter, public :: mode_flatness = 2.0_wp        !< b/c threshold (mode II)
  real(wp), parameter, public :: mode1_cos_theta = 0.7_wp      !< |cos theta| at least (mode I)
  real(wp), parameter, public :: mode2_cos_theta = 0.5_wp      !< |cos theta| at most (mode II)
  real(wp), parameter, public :: mode2_sin_phi = 0.7_wp        !< |sin phi| at least (mode II)
  integer, parameter, public :: mode_many_close_pairs = 3      !< mode I at least, mode II fewer
  integer, parameter, public :: mode_none = 0, mode_one = 1, mode_two = 2

  public :: frame_mode, case_mode, long_time_start

contains

  !> Mode of one frame; `elongation` replaces the a/b threshold mode_elongation (both modes), to
  !> measure how a verdict depends on reading "a >> b" (knotflow-analyze ROWS.csv --elongation).
  elemental integer function frame_mode(s, elongation) result(mode)
    type(shape_t), intent(in) :: s
    real(wp), intent(in), optional :: elongation
    real(wp) :: ct, ab
    mode = mode_none
    ab = mode_elongation
    if (present(elongation)) ab = elongation
    if (s%a <= 0.0_wp .or. s%a < ab*s%b) return
    ct = abs(cos(s%theta))
    if (ct >= mode1_cos_theta .and. s%close_pairs >= mode_many_close_pairs) then
      mode = mode_one
    else if (s%b >= mode_flatness*s%c .and. ct <= mode2_cos_theta .and. abs(sin(s%phi)) >= mode2_sin_phi &
             .and. s%close_pairs < mode_many_close_pairs) then
      mode = mode_two
    end if
  end function frame_mode

  !> Mode of a case from the per-frame modes and phi of every frame (the rule above).
  pure integer function case_mode(modes, phi) result(mode)
    integer, intent(in) :: modes(:)
    real(wp), intent(in) :: phi(:)
    real(wp), allocatable :: rolled(:)
    integer :: first, nhalf, n1, n2
    mode = mode_none
    first = long_time_start(size(modes))
    nhalf = size(modes) - first + 1
    n1 = count(modes(first:) == mode_one)
    n2 = count(modes(first:) == mode_two)
    if (nhalf == 0 .or. n1 + n2 < max(1, nhalf/2)) return
    mode = merge(mode_one, mode_two, n1 >= n2)
    if (mode == mode_one .and. size(phi) >= 4) then
      rolled = unwrap_phase(phi(long_time_start(size(phi)):))
      if (rolled(size(rolled)) <= rolled(1)) mode = mode_none
    end if
  end function case_mode

  !> The first of n frames (in time order) of the long-time state that case_mode classifies:
  !> the second half.
  pure integer function long_time_start(n)
    integer, intent(in) :: n
    long_time_start = n/2 + 1
  end function long_time_start

end module kf_modes
