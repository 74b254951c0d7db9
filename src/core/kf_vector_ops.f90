!> Small vector operations used across the library: the cross product of 3-vectors,
!> insertion sorts for short lists (a few to a few hundred entries, where they beat anything
!> more elaborate and keep equal keys in their order) and whether the distances of a
!> configuration can be computed at all.
module kf_vector_ops
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp
  use kf_strings, only: to_str
  implicit none
  private

  public :: cross, sort_index, sort_small, distances_representable, span_limit, too_far_apart

  !> Largest range of one coordinate over a configuration for which every squared distance
  !> |r_i - r_j|^2 (three squared differences added) is a finite number.
  real(wp), parameter :: span_limit = sqrt(huge(1.0_wp)/3.0_wp)

contains

  !> u × v.
  pure function cross(u, v) result(w)
    real(wp), intent(in) :: u(3), v(3)
    real(wp) :: w(3)
    w = [u(2)*v(3) - u(3)*v(2), u(3)*v(1) - u(1)*v(3), u(1)*v(2) - u(2)*v(1)]
  end function cross

  !> Indices that sort v ascending; equal values keep their order.
  pure function sort_index(v) result(idx)
    real(wp), intent(in) :: v(:)
    integer :: idx(size(v))
    integer :: i, j, key
    idx = [(i, i=1, size(v))]
    do i = 2, size(v)
      key = idx(i)
      j = i - 1
      do while (j >= 1)
        if (v(idx(j)) <= v(key)) exit
        idx(j + 1) = idx(j)
        j = j - 1
      end do
      idx(j + 1) = key
    end do
  end function sort_index

  !> Sort a few integers ascending, in place (through sort_index: integers of magnitude below
  !> 2**53 are exact in real(wp)).
  pure subroutine sort_small(v)
    integer, intent(inout) :: v(:)
    v = v(sort_index(real(v, wp)))
  end subroutine sort_small

  !> Whether every squared distance |r_i - r_j|^2 of the configuration r(3, n) is finite: each
  !> coordinate's range (largest minus smallest) below span_limit; false for a non-finite
  !> coordinate. Halves are compared, so the range itself cannot overflow.
  pure logical function distances_representable(r)
    real(wp), intent(in) :: r(:, :)
    integer :: k
    distances_representable = all(ieee_is_finite(r))
    if (.not. distances_representable .or. size(r, 2) < 1) return
    do k = 1, size(r, 1)
      if (.not. (0.5_wp*maxval(r(k, :)) - 0.5_wp*minval(r(k, :)) < 0.5_wp*span_limit)) &
        distances_representable = .false.
    end do
  end function distances_representable

  !> The refusal of a configuration that fails distances_representable, after the words that
  !> name it (`what`, e.g. "the beads of 'chain.txt'"), with the allowed span.
  function too_far_apart(what) result(s)
    character(len=*), intent(in) :: what
    character(len=:), allocatable :: s
    s = what//' are too far apart: their squared distances overflow (allowed: each coordinate '// &
      'ranging over less than '//trim(adjustl(to_str(span_limit, '(es10.3e3)')))//' d)'
  end function too_far_apart

end module kf_vector_ops
