!> Dynamical modes of a chain in shear (PHYSICS.md 6, the reference study's Table 1) from the
!> shape series. Per frame, with the thresholds below:
!>   mode I  (1): a >= 1.5 b (elongated), |cos theta| >= cos 30 deg (principal axis within 30 deg
!>               of the vorticity axis) and at least 3 close pairs (compact, many contacts);
!>   mode II (2): a >= 1.5 b, b >= 1.5 c (flat), |cos theta| <= cos 60 deg (axis within 30 deg
!>               of the flow-gradient plane) and at most 2 close pairs;
!>   else 0 (unclassified).
!> Per case: the mode of more than half of all frames, else 0.
module kf_modes
  use kf_kinds, only: wp
  use kf_shape, only: shape_t
  implicit none
  private

  real(wp), parameter, public :: mode_elongation = 1.5_wp       !< a/b threshold (both modes)
  real(wp), parameter, public :: mode_flatness = 1.5_wp         !< b/c threshold (mode II)
  real(wp), parameter, public :: mode1_cos_theta = 0.8660254037844386_wp !< cos 30 deg
  real(wp), parameter, public :: mode2_cos_theta = 0.5_wp       !< cos 60 deg
  integer, parameter, public :: mode1_min_close_pairs = 3
  integer, parameter, public :: mode2_max_close_pairs = 2
  integer, parameter, public :: mode_none = 0, mode_one = 1, mode_two = 2

  public :: frame_mode, case_mode

contains

  !> Mode of one frame.
  elemental integer function frame_mode(s) result(mode)
    type(shape_t), intent(in) :: s
    real(wp) :: ct
    mode = mode_none
    ct = abs(cos(s%theta))
    if (s%a < mode_elongation*s%b) return
    if (ct >= mode1_cos_theta .and. s%close_pairs >= mode1_min_close_pairs) then
      mode = mode_one
    else if (ct <= mode2_cos_theta .and. s%b >= mode_flatness*s%c .and. &
             s%close_pairs <= mode2_max_close_pairs) then
      mode = mode_two
    end if
  end function frame_mode

  !> Mode of a case: the per-frame mode held by more than half of the frames, else 0.
  pure integer function case_mode(modes) result(mode)
    integer, intent(in) :: modes(:)
    mode = mode_none
    if (size(modes) == 0) return
    if (2*count(modes == mode_one) > size(modes)) mode = mode_one
    if (2*count(modes == mode_two) > size(modes)) mode = mode_two
  end function case_mode

end module kf_modes
