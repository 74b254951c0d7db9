!> Exact knot invariants of a closed polygon: |Delta(-1)| and the odd part of |Delta(-2)| of the
!> Alexander polynomial (Alexander 1928), from the Alexander matrix of a generic projection.
!> The minor's determinant is computed modulo four primes near 2^31 and rebuilt exactly by the
!> Chinese remainder theorem in 128-bit integers whenever the Hadamard bound is below 2^122
!> (about 60 crossings); above that the residues are matched against the table (all primes must
!> agree with +-2^k times a table value), which decides the table types exactly up to a
!> collision with probability below 1e-30, and everything else is 'other'.
module kf_knot_invariants
  use kf_kinds, only: wp, i8
  use kf_vector_ops, only: cross, sort_index
  use kf_error, only: error_t, fatal_error
  use kf_knot_rng, only: knot_rng_t, rng_sphere_point
  use kf_knot_reduce, only: reduce_polygon
  implicit none
  private

  integer, parameter :: i16 = selected_int_kind(38)

  !> Number of knot types and their names (the last one, 'other', collects everything else).
  integer, parameter, public :: n_knot_types = 10
  character(len=5), parameter, public :: knot_type_names(n_knot_types) = &
    [character(len=5) :: '0_1', '3_1', '4_1', '5_1', '5_2', '6_1', '6_2', '6_3', '7_1', 'other']
  !> |Delta(-1)| and the odd part of |Delta(-2)| of the tabulated types 1..9.
  integer(i8), parameter, public :: table_det1(n_knot_types - 1) = &
    [1_i8, 3_i8, 5_i8, 5_i8, 7_i8, 9_i8, 11_i8, 13_i8, 7_i8]
  integer(i8), parameter, public :: table_det2(n_knot_types - 1) = &
    [1_i8, 7_i8, 11_i8, 31_i8, 1_i8, 5_i8, 59_i8, 67_i8, 127_i8]
  integer, parameter, public :: type_unknot = 1, type_other = n_knot_types

  integer(i8), parameter :: primes(4) = [2147483647_i8, 2147483629_i8, 2147483587_i8, 2147483579_i8]
  integer, parameter :: max_projections = 64

  public :: classify_polygon, alexander_values, type_from_values, knot_type_index

contains

  !> Knot type index (1..n_knot_types) of the closed polygon p(3, m); the polygon is
  !> triangle-reduced first unless `reduce` is false. `rng` chooses the projection direction.
  subroutine classify_polygon(p, rng, itype, error, reduce, det1, det2)
    real(wp), intent(in) :: p(:, :)
    type(knot_rng_t), intent(inout) :: rng
    integer, intent(out) :: itype
    type(error_t), allocatable, intent(out) :: error
    logical, intent(in), optional :: reduce
    integer(i8), intent(out), optional :: det1   !< |Delta(-1)| (-1 if not rebuilt exactly)
    integer(i8), intent(out), optional :: det2   !< odd part of |Delta(-2)| (-1 if not rebuilt)
    real(wp), allocatable :: q(:, :)
    integer :: m
    integer(i8) :: d1, d2
    logical :: exact
    allocate (q, source=p)
    m = size(p, 2)
    if (present(reduce)) then
      if (reduce) call reduce_polygon(q, m)
    else
      call reduce_polygon(q, m)
    end if
    call alexander_values(q(:, 1:m), rng, d1, d2, exact, itype, error)
    if (allocated(error)) return
    if (present(det1)) det1 = d1
    if (present(det2)) det2 = d2
  end subroutine classify_polygon

  !> Type index of the invariant pair (|Delta(-1)|, odd part of |Delta(-2)|).
  pure integer function type_from_values(d1, d2) result(itype)
    integer(i8), intent(in) :: d1, d2
    integer :: k
    itype = type_other
    do k = 1, n_knot_types - 1
      if (d1 == table_det1(k) .and. d2 == table_det2(k)) itype = k
    end do
  end function type_from_values

  !> Index of a type name, 0 if unknown.
  pure integer function knot_type_index(name) result(k)
    character(len=*), intent(in) :: name
    do k = 1, n_knot_types
      if (trim(knot_type_names(k)) == trim(name)) return
    end do
    k = 0
  end function knot_type_index

  !> Invariants of the closed polygon p(3, m) (no reduction here). With `exact` the values d1
  !> and d2 are exact; otherwise (very large diagrams) only `itype` is meaningful, d1 = d2 = -1.
  subroutine alexander_values(p, rng, d1, d2, exact, itype, error)
    real(wp), intent(in) :: p(:, :)
    type(knot_rng_t), intent(inout) :: rng
    integer(i8), intent(out) :: d1, d2
    logical, intent(out) :: exact
    integer, intent(out) :: itype
    type(error_t), allocatable, intent(out) :: error
    integer, allocatable :: over_arc(:), in_arc(:), out_arc(:), sgn(:)
    integer :: nc, attempt
    logical :: ok
    d1 = 1
    d2 = 1
    exact = .true.
    itype = type_unknot
    if (size(p, 2) <= 5) return           ! stick number of every non-trivial knot is >= 6
    do attempt = 1, max_projections
      call diagram(p, rng_sphere_point(rng), nc, over_arc, in_arc, out_arc, sgn, ok)
      if (ok) exit
    end do
    if (.not. ok) then
      call fatal_error(error, 'knot classification: no generic projection found (the closed '// &
        'polygon intersects itself or is degenerate)')
      return
    end if
    if (nc <= 2) return                   ! fewer than 3 crossings: unknot
    call determinants(nc, over_arc, in_arc, out_arc, sgn, d1, d2, exact, itype)
  end subroutine alexander_values

  !> Crossings of the projection of p along `dir`: for each crossing the over arc, the incoming
  !> and outgoing under arcs (0-based) and the sign. ok = .false. for a degenerate projection.
  subroutine diagram(p, dir, nc, over_arc, in_arc, out_arc, sgn, ok)
    real(wp), intent(in) :: p(:, :), dir(3)
    integer, intent(out) :: nc
    integer, allocatable, intent(out) :: over_arc(:), in_arc(:), out_arc(:), sgn(:)
    logical, intent(out) :: ok
    real(wp), allocatable :: x(:), y(:), h(:), over_pos(:), under_pos(:)
    integer, allocatable :: csign(:), order(:), rank(:)
    real(wp) :: e1(3), e2(3), ax(3), rx, ry, sx, sy, qx, qy, den, t, u, ha, hb, lr, ls
    real(wp) :: extent, tol
    integer :: m, a, b, a1, b1, cap, k, j
    m = size(p, 2)
    nc = 0
    ok = .false.
    ax = [1.0_wp, 0.0_wp, 0.0_wp]
    if (abs(dir(1)) > 0.6_wp) ax = [0.0_wp, 1.0_wp, 0.0_wp]
    e1 = cross(dir, ax)
    e1 = e1/norm2(e1)
    e2 = cross(dir, e1)
    allocate (x(m), y(m), h(m))
    do k = 1, m
      x(k) = dot_product(p(:, k), e1)
      y(k) = dot_product(p(:, k), e2)
      h(k) = dot_product(p(:, k), dir)
    end do
    extent = max(maxval(x) - minval(x), maxval(y) - minval(y), maxval(h) - minval(h))
    if (extent <= 0.0_wp) then
      ok = .true.
      allocate (over_arc(0), in_arc(0), out_arc(0), sgn(0))
      return
    end if
    tol = 1.0e-10_wp
    cap = 16
    allocate (over_pos(cap), under_pos(cap), csign(cap))
    do a = 1, m
      a1 = merge(1, a + 1, a == m)
      rx = x(a1) - x(a)
      ry = y(a1) - y(a)
      lr = hypot(rx, ry)
      do b = a + 1, m
        b1 = merge(1, b + 1, b == m)
        sx = x(b1) - x(b)
        sy = y(b1) - y(b)
        ls = hypot(sx, sy)
        if (b == a1 .or. a == b1) then
          ! adjacent segments: degenerate only if they fold back onto each other
          if (abs(rx*sy - ry*sx) <= tol*lr*ls .and. rx*sx + ry*sy < 0.0_wp) return
          cycle
        end if
        if (max(x(a), x(a1)) < min(x(b), x(b1)) - tol*extent) cycle
        if (min(x(a), x(a1)) > max(x(b), x(b1)) + tol*extent) cycle
        if (max(y(a), y(a1)) < min(y(b), y(b1)) - tol*extent) cycle
        if (min(y(a), y(a1)) > max(y(b), y(b1)) + tol*extent) cycle
        qx = x(b) - x(a)
        qy = y(b) - y(a)
        den = rx*sy - ry*sx
        if (abs(den) <= tol*max(lr*ls, tol*extent**2)) then
          ! (near) parallel: no crossing unless the two lie on one line and overlap
          if (abs(qx*ry - qy*rx) > tol*extent*max(lr, tol*extent) .or. &
              abs(qx*sy - qy*sx) > tol*extent*max(ls, tol*extent)) cycle
          return
        end if
        t = (qx*sy - qy*sx)/den
        u = (qx*ry - qy*rx)/den
        if (t < -tol .or. t > 1.0_wp + tol .or. u < -tol .or. u > 1.0_wp + tol) cycle
        if (t < tol .or. t > 1.0_wp - tol .or. u < tol .or. u > 1.0_wp - tol) return
        ha = h(a) + t*(h(a1) - h(a))
        hb = h(b) + u*(h(b1) - h(b))
        if (abs(ha - hb) <= tol*extent) return
        nc = nc + 1
        if (nc > cap) then
          cap = 2*cap
          call grow(over_pos, cap)
          call grow(under_pos, cap)
          call grow_int(csign, cap)
        end if
        if (ha > hb) then          ! a passes over b
          over_pos(nc) = (a - 1) + t
          under_pos(nc) = (b - 1) + u
          csign(nc) = merge(1, -1, rx*sy - ry*sx > 0.0_wp)
        else
          over_pos(nc) = (b - 1) + u
          under_pos(nc) = (a - 1) + t
          csign(nc) = merge(1, -1, sx*ry - sy*rx > 0.0_wp)
        end if
      end do
    end do
    ok = .true.
    allocate (over_arc(nc), in_arc(nc), out_arc(nc), sgn(nc), order(nc), rank(nc))
    if (nc == 0) return
    order = sort_index(under_pos(1:nc))
    do k = 1, nc
      rank(order(k)) = k - 1
    end do
    do k = 1, nc
      in_arc(k) = rank(k)
      out_arc(k) = modulo(rank(k) + 1, nc)
      j = count(under_pos(1:nc) < over_pos(k))
      over_arc(k) = modulo(j, nc)
      sgn(k) = csign(k)
    end do
  end subroutine diagram

  !> Determinants of the Alexander minor at t = -1 and t = -2 and the resulting type.
  subroutine determinants(nc, over_arc, in_arc, out_arc, sgn, d1, d2, exact, itype)
    integer, intent(in) :: nc, over_arc(:), in_arc(:), out_arc(:), sgn(:)
    integer(i8), intent(out) :: d1, d2
    logical, intent(out) :: exact
    integer, intent(out) :: itype
    integer(i8), allocatable :: a(:, :)
    integer(i8) :: res(4, 2), tval
    integer(i16) :: v(2)
    real(wp) :: log2_bound(2)
    integer :: it, ip, k, n, kk, k2
    logical :: match1, match2
    n = nc - 1
    allocate (a(nc, nc))
    do it = 1, 2
      tval = -int(it, i8)
      a = 0
      do k = 1, nc
        a(k, over_arc(k) + 1) = a(k, over_arc(k) + 1) + (1_i8 - tval)
        if (sgn(k) > 0) then
          a(k, in_arc(k) + 1) = a(k, in_arc(k) + 1) + tval
          a(k, out_arc(k) + 1) = a(k, out_arc(k) + 1) - 1_i8
        else
          a(k, in_arc(k) + 1) = a(k, in_arc(k) + 1) - 1_i8
          a(k, out_arc(k) + 1) = a(k, out_arc(k) + 1) + tval
        end if
      end do
      log2_bound(it) = 0.0_wp
      do k = 1, n
        log2_bound(it) = log2_bound(it) + 0.5_wp*log(max(1.0_wp, real(sum(a(k, 1:n)**2), wp)))/log(2.0_wp)
      end do
      do ip = 1, 4
        res(ip, it) = det_mod(a(1:n, 1:n), primes(ip))
      end do
    end do
    if (maxval(log2_bound) < 122.0_wp) then
      exact = .true.
      do it = 1, 2
        v(it) = abs(crt(res(:, it)))
      end do
      do while (v(2) > 0 .and. modulo(v(2), 2_i16) == 0)
        v(2) = v(2)/2
      end do
      d1 = int(min(v(1), int(huge(d1), i16)), i8)
      d2 = int(min(v(2), int(huge(d2), i16)), i8)
      itype = type_from_values(d1, d2)
      return
    end if
    exact = .false.
    d1 = -1
    d2 = -1
    itype = type_other
    do kk = 1, n_knot_types - 1
      match1 = all(matches(res(:, 1), table_det1(kk), 0))
      match2 = .false.
      do k2 = 0, nc + 64
        if (all(matches(res(:, 2), table_det2(kk), k2))) then
          match2 = .true.
          exit
        end if
      end do
      if (match1 .and. match2) then
        itype = kk
        return
      end if
    end do

  contains

    !> Whether residues equal +-2^k * value modulo each prime.
    function matches(r, value, k) result(ok)
      integer(i8), intent(in) :: r(4), value
      integer, intent(in) :: k
      logical :: ok(4)
      integer(i8) :: w
      integer :: q
      do q = 1, 4
        w = mulmod(modulo(value, primes(q)), powmod(2_i8, int(k, i8), primes(q)), primes(q))
        ok(q) = r(q) == w .or. r(q) == modulo(-w, primes(q))
      end do
    end function matches

    !> Symmetric CRT reconstruction from the four residues (Garner's algorithm).
    function crt(r) result(x)
      integer(i8), intent(in) :: r(4)
      integer(i16) :: x, mprod
      integer(i8) :: c(4), t
      integer :: i, j
      do i = 1, 4
        t = r(i)
        do j = 1, i - 1
          t = mulmod(modulo(t - c(j), primes(i)), powmod(modulo(primes(j), primes(i)), primes(i) - 2_i8, primes(i)), primes(i))
        end do
        c(i) = t
      end do
      x = 0
      mprod = 1
      do i = 1, 4
        x = x + int(c(i), i16)*mprod
        mprod = mprod*int(primes(i), i16)
      end do
      if (x > mprod/2) x = x - mprod
    end function crt

  end subroutine determinants

  !> Determinant of the integer matrix a modulo the prime q (Gaussian elimination).
  function det_mod(a, q) result(det)
    integer(i8), intent(in) :: a(:, :), q
    integer(i8) :: det
    integer(i8), allocatable :: b(:, :), row(:)
    integer(i8) :: inv, f
    integer :: n, i, k, piv
    n = size(a, 1)
    det = 1
    if (n == 0) return
    b = modulo(a, q)
    do k = 1, n
      piv = 0
      do i = k, n
        if (b(i, k) /= 0) then
          piv = i
          exit
        end if
      end do
      if (piv == 0) then
        det = 0
        return
      end if
      if (piv /= k) then
        row = b(k, :)
        b(k, :) = b(piv, :)
        b(piv, :) = row
        det = modulo(-det, q)
      end if
      det = mulmod(det, b(k, k), q)
      inv = powmod(b(k, k), q - 2_i8, q)
      do i = k + 1, n
        if (b(i, k) == 0) cycle
        f = mulmod(b(i, k), inv, q)
        b(i, k:n) = modulo(b(i, k:n) - modulo(f*b(k, k:n), q), q)
      end do
    end do
  end function det_mod

  elemental integer(i8) function mulmod(x, y, q)
    integer(i8), intent(in) :: x, y, q
    mulmod = modulo(x*y, q)          ! x, y < q < 2^31: the product fits in 63 bits
  end function mulmod

  pure integer(i8) function powmod(x, e, q) result(r)
    integer(i8), intent(in) :: x, e, q
    integer(i8) :: b, k
    r = 1
    b = modulo(x, q)
    k = e
    do while (k > 0)
      if (modulo(k, 2_i8) == 1) r = mulmod(r, b, q)
      b = mulmod(b, b, q)
      k = k/2
    end do
  end function powmod

  subroutine grow(v, cap)
    real(wp), allocatable, intent(inout) :: v(:)
    integer, intent(in) :: cap
    real(wp), allocatable :: w(:)
    allocate (w(cap))
    w(1:size(v)) = v
    call move_alloc(w, v)
  end subroutine grow

  subroutine grow_int(v, cap)
    integer, allocatable, intent(inout) :: v(:)
    integer, intent(in) :: cap
    integer, allocatable :: w(:)
    allocate (w(cap))
    w(1:size(v)) = v
    call move_alloc(w, v)
  end subroutine grow_int

end module kf_knot_invariants
