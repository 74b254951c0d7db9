!> Triangle reduction of a closed polygon (Taylor, Nature 406, 916 (2000); Koniaris and
!> Muthukumar, PRL 66, 2211 (1991)): a vertex is deleted when no other segment of the closed
!> polygon meets the triangle it forms with its two neighbours, an isotopy that never changes the
!> knot type. The test is conservative: near-degenerate configurations (segments within a relative
!> tolerance of the triangle, coplanar neighbours) count as piercing, so the vertex is kept.
module kf_knot_reduce
  use kf_kinds, only: wp
  use kf_vector_ops, only: cross
  implicit none
  private

  public :: reduce_polygon

contains

  !> Reduce the closed polygon p(:, 1:m) (the segment p(:, m) -> p(:, 1) closes it) in place;
  !> on return p(:, 1:m) holds the remaining vertices in their original cyclic order.
  subroutine reduce_polygon(p, m)
    real(wp), intent(inout) :: p(:, :)
    integer, intent(inout) :: m
    integer, allocatable :: nxt(:), prv(:)
    integer :: i, a, c, k, since, live, j
    real(wp) :: extent, eps
    real(wp), allocatable :: q(:, :)
    if (m <= 3) return
    allocate (nxt(m), prv(m))
    do i = 1, m
      nxt(i) = merge(1, i + 1, i == m)
      prv(i) = merge(m, i - 1, i == 1)
    end do
    extent = 0.0_wp
    do k = 1, 3
      extent = max(extent, maxval(p(k, 1:m)) - minval(p(k, 1:m)))
    end do
    if (extent <= 0.0_wp) return
    eps = 1.0e-12_wp*extent**3
    live = m
    i = 1
    since = 0              ! vertices visited since the last deletion
    do while (live > 3 .and. since < live)
      a = prv(i)
      c = nxt(i)
      if (removable(a, i, c)) then
        nxt(a) = c
        prv(c) = a
        live = live - 1
        since = 0
        i = c
      else
        since = since + 1
        i = c
      end if
    end do
    allocate (q(3, live))
    k = i
    do j = 1, live
      q(:, j) = p(:, k)
      k = nxt(k)
    end do
    p(:, 1:live) = q
    m = live

  contains

    !> True when no other segment meets the triangle (p_a, p_b, p_c).
    logical function removable(ia, ib, ic)
      integer, intent(in) :: ia, ib, ic
      real(wp) :: ta(3), tb(3), tc(3), nrm(3), lo(3), hi(3)
      integer :: s, e
      ta = p(:, ia)
      tb = p(:, ib)
      tc = p(:, ic)
      nrm = cross(tb - ta, tc - ta)
      lo = min(ta, tb, tc) - 1.0e-9_wp*extent
      hi = max(ta, tb, tc) + 1.0e-9_wp*extent
      removable = .true.
      ! b on the straight segment a-c (including b coinciding with a or c): deleting it does
      ! not move the curve at all
      if (norm2(nrm) <= 1.0e-12_wp*extent**2 .and. dot_product(tb - ta, tc - tb) >= 0.0_wp) return
      if (norm2(tb - ta) <= 1.0e-12_wp*extent .or. norm2(tc - tb) <= 1.0e-12_wp*extent) return
      removable = .false.
      ! the neighbouring segments touch the triangle at a vertex: they block the move only
      ! when their far end lies in the triangle's plane
      if (abs(dot_product(nrm, p(:, prv(ia)) - ta)) <= eps .and. prv(ia) /= ic) return
      if (abs(dot_product(nrm, p(:, nxt(ic)) - ta)) <= eps .and. nxt(ic) /= ia) return
      s = nxt(ic)
      do while (nxt(s) /= ia .and. s /= ia)
        e = nxt(s)
        if (all(max(p(:, s), p(:, e)) >= lo) .and. all(min(p(:, s), p(:, e)) <= hi)) then
          if (pierces(ta, tb, tc, nrm, p(:, s), p(:, e))) return
        end if
        s = e
      end do
      removable = .true.
    end function removable

    !> Conservative segment (x, y) / triangle (ta, tb, tc) intersection test.
    logical function pierces(ta, tb, tc, nrm, x, y)
      real(wp), intent(in) :: ta(3), tb(3), tc(3), nrm(3), x(3), y(3)
      real(wp) :: v1, v2, w1, w2, w3, d(3)
      pierces = .false.
      v1 = dot_product(nrm, x - ta)
      v2 = dot_product(nrm, y - ta)
      if ((v1 > eps .and. v2 > eps) .or. (v1 < -eps .and. v2 < -eps)) return
      d = y - x
      w1 = dot_product(d, cross(ta - x, tb - x))
      w2 = dot_product(d, cross(tb - x, tc - x))
      w3 = dot_product(d, cross(tc - x, ta - x))
      pierces = (w1 >= -eps .and. w2 >= -eps .and. w3 >= -eps) .or. &
                (w1 <= eps .and. w2 <= eps .and. w3 <= eps)
    end function pierces

  end subroutine reduce_polygon

end module kf_knot_reduce
