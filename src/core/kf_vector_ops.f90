!> Small vector operations used across the library: the cross product of 3-vectors and
!> insertion sorts for short lists (a few to a few hundred entries, where they beat anything
!> more elaborate and keep equal keys in their order).
module kf_vector_ops
  use kf_kinds, only: wp
  implicit none
  private

  public :: cross, sort_index, sort_small

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

end module kf_vector_ops
