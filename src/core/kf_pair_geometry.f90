!> The close pairs of one configuration: every pair of beads i < j with |r_j - r_i| < cutoff,
!> with its separation d = r_j - r_i and distance, in the order of the double loop (i, then j).
!> One pass per configuration serves everything that looks at close pairs: the excluded volume
!> (kf_forces), the lubrication corrections (kf_lubrication) and the run diagnostics
!> (kf_run_diagnostics). A consumer asks `covers(r, cutoff)` whether the list was built for
!> exactly these positions with a cutoff at least as large as it needs, and builds its own
!> otherwise.
!>
!> The search uses a cell list (cells of edge >= cutoff over the bounding box, at most about
!> 2N cells), so the cost is O(N + pairs) for a chain of bounded density; the pairs are then put
!> in (i, j) order by two stable counting sorts. Memory O(N + pairs).
module kf_pair_geometry
  use kf_kinds, only: wp, i8
  implicit none
  private

  type, public :: pair_geometry_t
    private
    integer :: n_beads = -1             !< beads of the configuration (-1: never built)
    integer :: n_pairs = 0
    real(wp) :: cutoff_ = 0.0_wp
    integer, allocatable :: i_(:), j_(:)
    real(wp), allocatable :: d_(:, :)   !< (3, pair): r_j - r_i
    real(wp), allocatable :: dist_(:)
    real(wp), allocatable :: r_ref(:, :) !< the configuration the list was built for
    ! work space of the search, kept between builds
    integer, allocatable :: cell_of(:), cell_start(:), order(:), ti(:), tj(:), counts(:)
  contains
    procedure :: build
    procedure :: covers
    procedure :: size => pair_total
    procedure :: cutoff
    procedure :: pair
    procedure :: distance
    procedure :: separation
  end type pair_geometry_t

  integer, parameter :: min_capacity = 64

contains

  !> Find every pair i < j of r(3, N) closer than `cutoff` (cutoff <= 0: no pairs).
  subroutine build(this, r, cutoff)
    class(pair_geometry_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(in) :: cutoff
    integer :: n, nc(3), c(3), lo(3), hi(3), cx, cy, cz, cell, i, j, k, p
    real(wp) :: rmin(3), rmax(3), edge, cut2, d(3), d2
    integer(i8) :: n_cells

    n = size(r, 2)
    this%n_beads = n
    this%cutoff_ = max(cutoff, 0.0_wp)
    this%n_pairs = 0
    if (allocated(this%r_ref)) then
      if (size(this%r_ref, 2) /= n) deallocate (this%r_ref)
    end if
    if (.not. allocated(this%r_ref)) allocate (this%r_ref(3, n))
    this%r_ref = r
    if (n < 2 .or. this%cutoff_ <= 0.0_wp) return
    if (.not. all(r == r)) return   ! NaN positions: no geometry (the caller's checks report them)

    ! cells of edge >= cutoff; at most about 2N cells (then larger cells)
    rmin = minval(r, dim=2)
    rmax = maxval(r, dim=2)
    edge = this%cutoff_
    do
      nc = max(1, int(min((rmax - rmin)/edge, 1.0e6_wp)))
      n_cells = int(nc(1), i8)*nc(2)*nc(3)
      if (n_cells <= 2_i8*n + 8_i8) exit
      edge = 2.0_wp*edge
    end do
    call ensure_int(this%cell_of, n)
    call ensure_int(this%order, n)
    call ensure_int(this%cell_start, int(n_cells) + 1)
    this%cell_start = 0
    do i = 1, n
      c = cell_index(r(:, i))
      cell = flat(c)
      this%cell_of(i) = cell
      this%cell_start(cell + 1) = this%cell_start(cell + 1) + 1
    end do
    do cell = 2, int(n_cells) + 1
      this%cell_start(cell) = this%cell_start(cell) + this%cell_start(cell - 1)
    end do
    ! beads of cell k: order(cell_start(k)+1 : cell_start(k+1)), ascending
    block
      integer, allocatable :: fill(:)
      fill = this%cell_start(1:int(n_cells))
      do i = 1, n
        fill(this%cell_of(i)) = fill(this%cell_of(i)) + 1
        this%order(fill(this%cell_of(i))) = i
      end do
    end block

    cut2 = this%cutoff_**2
    p = 0
    do i = 1, n
      c = cell_index(r(:, i))
      lo = max(c - 1, 1)
      hi = min(c + 1, nc)
      do cz = lo(3), hi(3)
        do cy = lo(2), hi(2)
          do cx = lo(1), hi(1)
            cell = flat([cx, cy, cz])
            do k = this%cell_start(cell) + 1, this%cell_start(cell + 1)
              j = this%order(k)
              if (j <= i) cycle
              d = r(:, j) - r(:, i)
              d2 = d(1)**2 + d(2)**2 + d(3)**2
              if (d2 >= cut2) cycle
              p = p + 1
              call ensure_pairs(this, p)
              this%i_(p) = i
              this%j_(p) = j
            end do
          end do
        end do
      end do
    end do
    this%n_pairs = p
    call sort_pairs(this, n)
    do k = 1, p
      this%d_(:, k) = r(:, this%j_(k)) - r(:, this%i_(k))
      this%dist_(k) = norm2(this%d_(:, k))
    end do

  contains

    pure function cell_index(x) result(ci)
      real(wp), intent(in) :: x(3)
      integer :: ci(3)
      ci = min(nc, 1 + int((x - rmin)/edge))
    end function cell_index

    pure integer function flat(ci)
      integer, intent(in) :: ci(3)
      flat = ci(1) + nc(1)*((ci(2) - 1) + nc(2)*(ci(3) - 1))
    end function flat

  end subroutine build

  !> True when the list was built for exactly the positions r and a cutoff >= `cutoff`.
  pure logical function covers(this, r, cutoff)
    class(pair_geometry_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(in) :: cutoff
    covers = .false.
    if (this%n_beads /= size(r, 2) .or. this%n_beads < 0) return
    if (this%cutoff_ < cutoff) return
    if (size(r, 1) /= 3) return
    covers = all(this%r_ref == r)
  end function covers

  !> Number of pairs in the list.
  pure integer function pair_total(this)
    class(pair_geometry_t), intent(in) :: this
    pair_total = this%n_pairs
  end function pair_total

  !> The cutoff of the last build.
  pure real(wp) function cutoff(this)
    class(pair_geometry_t), intent(in) :: this
    cutoff = this%cutoff_
  end function cutoff

  !> Beads i < j of pair k (1 <= k <= size()).
  pure subroutine pair(this, k, i, j)
    class(pair_geometry_t), intent(in) :: this
    integer, intent(in) :: k
    integer, intent(out) :: i, j
    i = this%i_(k)
    j = this%j_(k)
  end subroutine pair

  !> |r_j - r_i| of pair k.
  pure real(wp) function distance(this, k)
    class(pair_geometry_t), intent(in) :: this
    integer, intent(in) :: k
    distance = this%dist_(k)
  end function distance

  !> r_j - r_i of pair k.
  pure function separation(this, k) result(d)
    class(pair_geometry_t), intent(in) :: this
    integer, intent(in) :: k
    real(wp) :: d(3)
    d = this%d_(:, k)
  end function separation

  !> Put the pairs in (i, j) order: a stable counting sort by j, then one by i.
  subroutine sort_pairs(this, n)
    type(pair_geometry_t), intent(inout) :: this
    integer, intent(in) :: n
    integer :: p
    p = this%n_pairs
    if (p < 2) return
    call ensure_int(this%ti, p)
    call ensure_int(this%tj, p)
    call ensure_int(this%counts, n + 1)
    call counting_pass(this%j_(1:p), this%i_(1:p), this%tj(1:p), this%ti(1:p))
    call counting_pass(this%ti(1:p), this%tj(1:p), this%i_(1:p), this%j_(1:p))
  contains
    !> Stable sort of the pairs (key, other) by key into (key_out, other_out).
    subroutine counting_pass(key, other, key_out, other_out)
      integer, intent(in) :: key(:), other(:)
      integer, intent(out) :: key_out(:), other_out(:)
      integer :: k, v, pos
      this%counts(1:n + 1) = 0
      do k = 1, size(key)
        this%counts(key(k) + 1) = this%counts(key(k) + 1) + 1
      end do
      do v = 2, n + 1
        this%counts(v) = this%counts(v) + this%counts(v - 1)
      end do
      ! counts(v) = number of keys < v
      do k = 1, size(key)
        v = key(k)
        this%counts(v) = this%counts(v) + 1
        pos = this%counts(v)
        key_out(pos) = v
        other_out(pos) = other(k)
      end do
    end subroutine counting_pass
  end subroutine sort_pairs

  !> Room for p pairs (the arrays grow by doubling and keep their contents).
  subroutine ensure_pairs(this, p)
    type(pair_geometry_t), intent(inout) :: this
    integer, intent(in) :: p
    integer :: cap
    integer, allocatable :: ti(:), tj(:)
    if (allocated(this%i_)) then
      if (size(this%i_) >= p) return
      cap = max(2*size(this%i_), p)
      allocate (ti(cap), tj(cap))
      ti(1:p - 1) = this%i_(1:p - 1)
      tj(1:p - 1) = this%j_(1:p - 1)
      call move_alloc(ti, this%i_)
      call move_alloc(tj, this%j_)
      deallocate (this%d_, this%dist_)
    else
      cap = max(min_capacity, p)
      allocate (this%i_(cap), this%j_(cap))
    end if
    allocate (this%d_(3, cap), this%dist_(cap))
  end subroutine ensure_pairs

  !> An integer work array of at least n elements.
  subroutine ensure_int(a, n)
    integer, allocatable, intent(inout) :: a(:)
    integer, intent(in) :: n
    if (allocated(a)) then
      if (size(a) >= n) return
      deallocate (a)
    end if
    allocate (a(max(n, 1)))
  end subroutine ensure_int

end module kf_pair_geometry
