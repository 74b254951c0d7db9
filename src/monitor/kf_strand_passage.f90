!> Strand-passage detection between two configurations of a chain.
!> Between accepted steps every bead is taken to move on a straight line, r_k(s) = r0_k + s (r1_k - r0_k),
!> s in [0, 1]. Two non-adjacent bonds pass through each other when, at some s, their four end
!> points are coplanar and the two segments intersect. The coplanarity condition is a cubic in s
!> (the triple product of the moving vectors); its roots in [0, 1] are found by bracketing between
!> the cubic's turning points and bisection, and at each root the segments are tested for contact.
!> A swept bounding-box test discards distant pairs first.
module kf_strand_passage
  use kf_kinds, only: wp
  use kf_vector_ops, only: cross
  implicit none
  private

  public :: count_strand_passages, segments_pass

contains

  !> Number of pairs of non-adjacent bonds (|i - j| > 1) that pass through each other while the
  !> chain moves linearly from r0(3, N) to r1(3, N). `tolerance` is the contact distance
  !> (units of d) below which segments count as intersecting at a coplanarity root.
  integer function count_strand_passages(r0, r1, tolerance) result(count)
    real(wp), intent(in) :: r0(:, :), r1(:, :)
    real(wp), intent(in) :: tolerance
    real(wp), allocatable :: lo(:, :), hi(:, :)
    integer :: n, i, j
    n = size(r0, 2)
    count = 0
    if (n < 4) return
    allocate (lo(3, n - 1), hi(3, n - 1))
    do i = 1, n - 1
      lo(:, i) = min(r0(:, i), r0(:, i + 1), r1(:, i), r1(:, i + 1)) - tolerance
      hi(:, i) = max(r0(:, i), r0(:, i + 1), r1(:, i), r1(:, i + 1)) + tolerance
    end do
    do j = 3, n - 1
      do i = 1, j - 2
        if (any(lo(:, i) > hi(:, j)) .or. any(lo(:, j) > hi(:, i))) cycle
        if (segments_pass(r0(:, i), r0(:, i + 1), r0(:, j), r0(:, j + 1), &
                          r1(:, i), r1(:, i + 1), r1(:, j), r1(:, j + 1), tolerance)) count = count + 1
      end do
    end do
  end function count_strand_passages

  !> Do segments a = [a1, a2] and b = [b1, b2], moving linearly from the "0" to the "1" positions,
  !> intersect at some intermediate time (excluding contacts present at both ends)?
  logical function segments_pass(a1_0, a2_0, b1_0, b2_0, a1_1, a2_1, b1_1, b2_1, tolerance) result(pass)
    real(wp), intent(in) :: a1_0(3), a2_0(3), b1_0(3), b2_0(3), a1_1(3), a2_1(3), b1_1(3), b2_1(3)
    real(wp), intent(in) :: tolerance
    real(wp) :: c(0:3), brk(4), s_lo, s_hi, f_lo, f_hi, s, disc, s1, s2, q
    integer :: nb, k, it

    pass = .false.
    ! Coefficients of the cubic f(s) from its values at s = 0, 1/3, 2/3, 1 (exact for a cubic).
    block
      real(wp) :: f0, f1, f2, f3
      f0 = triple(0.0_wp)
      f1 = triple(1.0_wp/3.0_wp)
      f2 = triple(2.0_wp/3.0_wp)
      f3 = triple(1.0_wp)
      c(0) = f0
      c(1) = (-11.0_wp*f0 + 18.0_wp*f1 - 9.0_wp*f2 + 2.0_wp*f3)/2.0_wp
      c(2) = (18.0_wp*f0 - 45.0_wp*f1 + 36.0_wp*f2 - 9.0_wp*f3)/2.0_wp
      c(3) = (-9.0_wp*f0 + 27.0_wp*f1 - 27.0_wp*f2 + 9.0_wp*f3)/2.0_wp
    end block
    ! Brackets: [0, 1] split at the turning points of the cubic (roots of 3 c3 s^2 + 2 c2 s + c1).
    nb = 1
    brk(1) = 0.0_wp
    disc = c(2)**2 - 3.0_wp*c(3)*c(1)
    if (abs(c(3)) > 0.0_wp .and. disc > 0.0_wp) then
      q = -(c(2) + sign(sqrt(disc), c(2)))
      s1 = q/(3.0_wp*c(3))
      s2 = merge(c(1)/q, s1, q /= 0.0_wp)
      call add_break(min(s1, s2))
      call add_break(max(s1, s2))
    else if (abs(c(3)) == 0.0_wp .and. abs(c(2)) > 0.0_wp) then
      call add_break(-c(1)/(2.0_wp*c(2)))
    end if
    nb = nb + 1
    brk(nb) = 1.0_wp
    do k = 1, nb - 1
      s_lo = brk(k)
      s_hi = brk(k + 1)
      f_lo = cubic(s_lo)
      f_hi = cubic(s_hi)
      if (f_lo*f_hi > 0.0_wp) then
        ! no sign change: a touching root only if |f| is tiny at the ends of the bracket
        s = merge(s_lo, s_hi, abs(f_lo) < abs(f_hi))
        if (abs(cubic(s)) <= tiny(1.0_wp)) then
          if (contact(s)) pass = .true.
        end if
        cycle
      end if
      do it = 1, 200
        s = 0.5_wp*(s_lo + s_hi)
        if (s_hi - s_lo < 1.0e-14_wp) exit
        if (cubic(s)*f_lo <= 0.0_wp) then
          s_hi = s
        else
          s_lo = s
          f_lo = cubic(s_lo)
        end if
      end do
      if (contact(s)) pass = .true.
      if (pass) return
    end do

  contains

    subroutine add_break(x)
      real(wp), intent(in) :: x
      if (x > brk(nb) .and. x < 1.0_wp) then
        nb = nb + 1
        brk(nb) = x
      end if
    end subroutine add_break

    real(wp) function cubic(x)
      real(wp), intent(in) :: x
      cubic = c(0) + x*(c(1) + x*(c(2) + x*c(3)))
    end function cubic

    real(wp) function triple(x)
      real(wp), intent(in) :: x
      real(wp) :: a1(3), a2(3), b1(3), b2(3)
      call positions(x, a1, a2, b1, b2)
      triple = dot_product(b1 - a1, cross(a2 - a1, b2 - b1))
    end function triple

    !> Are the segments within `tolerance` of each other at time x?
    logical function contact(x)
      real(wp), intent(in) :: x
      real(wp) :: a1(3), a2(3), b1(3), b2(3)
      call positions(x, a1, a2, b1, b2)
      contact = segment_distance(a1, a2, b1, b2) <= tolerance
    end function contact

    subroutine positions(x, a1, a2, b1, b2)
      real(wp), intent(in) :: x
      real(wp), intent(out) :: a1(3), a2(3), b1(3), b2(3)
      a1 = a1_0 + x*(a1_1 - a1_0)
      a2 = a2_0 + x*(a2_1 - a2_0)
      b1 = b1_0 + x*(b1_1 - b1_0)
      b2 = b2_0 + x*(b2_1 - b2_0)
    end subroutine positions

  end function segments_pass

  !> Shortest distance between segments [p1, p2] and [q1, q2].
  pure real(wp) function segment_distance(p1, p2, q1, q2) result(dist)
    real(wp), intent(in) :: p1(3), p2(3), q1(3), q2(3)
    real(wp) :: d1(3), d2(3), r(3), a, e, f, b, c, denom, s, t
    d1 = p2 - p1
    d2 = q2 - q1
    r = p1 - q1
    a = dot_product(d1, d1)
    e = dot_product(d2, d2)
    f = dot_product(d2, r)
    c = dot_product(d1, r)
    b = dot_product(d1, d2)
    denom = a*e - b*b
    if (denom > 1.0e-14_wp*a*e) then
      s = min(1.0_wp, max(0.0_wp, (b*f - c*e)/denom))
    else
      s = 0.0_wp
    end if
    t = (b*s + f)/max(e, tiny(1.0_wp))
    if (t < 0.0_wp) then
      t = 0.0_wp
      s = min(1.0_wp, max(0.0_wp, -c/max(a, tiny(1.0_wp))))
    else if (t > 1.0_wp) then
      t = 1.0_wp
      s = min(1.0_wp, max(0.0_wp, (b - c)/max(a, tiny(1.0_wp))))
    end if
    dist = norm2(p1 + s*d1 - (q1 + t*d2))
  end function segment_distance

end module kf_strand_passage
