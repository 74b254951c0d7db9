!> Knotting and unknotting events from a k_f(t) series with hysteresis: the state becomes
!> 'knotted' when k_f > high and 'unknotted' when k_f < low and is unchanged in between; the
!> initial state is that of the first frame outside the band; an event is a change of state,
!> recorded at the first frame of the new state ('unknot': knotted -> unknotted, 'knot' the reverse).
module kf_transitions
  use kf_kinds, only: wp
  implicit none
  private

  real(wp), parameter, public :: default_low = 0.1_wp, default_high = 0.9_wp
  integer, parameter, public :: event_unknot = 1, event_knot = 2
  character(len=6), parameter, public :: event_names(2) = ['unknot', 'knot  ']

  public :: detect_transitions

contains

  !> Events of kf(:): their kinds (event_unknot/event_knot) and 1-based frame positions.
  subroutine detect_transitions(kf, low, high, kinds, frames)
    real(wp), intent(in) :: kf(:)
    real(wp), intent(in) :: low, high
    integer, allocatable, intent(out) :: kinds(:), frames(:)
    integer :: k, state, ne, new
    integer :: tk(size(kf)), tf(size(kf))
    state = 0                  ! 0 undetermined, 1 unknotted, 2 knotted
    ne = 0
    do k = 1, size(kf)
      new = state
      if (kf(k) > high) new = 2
      if (kf(k) < low) new = 1
      if (state /= 0 .and. new /= state) then
        ne = ne + 1
        tk(ne) = merge(event_knot, event_unknot, new == 2)
        tf(ne) = k
      end if
      state = new
    end do
    kinds = tk(1:ne)
    frames = tf(1:ne)
  end subroutine detect_transitions

end module kf_transitions
