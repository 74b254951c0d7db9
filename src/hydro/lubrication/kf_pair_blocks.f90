!> Pairwise friction terms as a list of pair blocks: for pairs (i, j) a 12 x 12 friction block
!> (ordering [U_i, Omega_i, U_j, Omega_j] -> [F_i, T_i, F_j, T_j]) and a strain coupling
!> xe(12, 3, 3) (delta x = xe : E), e.g. the lubrication corrections of one configuration
!> (kf_lubrication's `pair_blocks`). The sum over pairs acts on 6N vectors ordered
!> [U_1, Omega_1, U_2, ...]: as an operator (`apply`), added into a dense friction
!> (`add_friction`), or as the strain right-hand side (`add_strain`, `add_strain_basis`).
!> Never a dense 6N x 6N matrix of its own.
module kf_pair_blocks
  use kf_kinds, only: wp
  implicit none
  private

  !> A list of pair blocks.
  type, public :: pair_blocks_t
    private
    integer :: count = 0                     !< pairs in the list
    integer, allocatable :: ij(:, :)         !< (2, capacity): the beads i < j
    real(wp), allocatable :: zeta(:, :, :)   !< (12, 12, capacity)
    real(wp), allocatable :: xe(:, :, :, :)  !< (12, 3, 3, capacity)
  contains
    procedure :: clear
    procedure :: next_slot
    procedure :: resize
    procedure :: store
    procedure :: n_pairs
    procedure :: pair
    procedure :: apply
    procedure :: add_friction
    procedure :: add_strain
    procedure :: add_strain_basis
    procedure :: largest_scaled_change
  end type pair_blocks_t

contains

  !> Empty the list (the storage is kept).
  subroutine clear(this)
    class(pair_blocks_t), intent(inout) :: this
    this%count = 0
  end subroutine clear

  !> Append pair (i, j) and return its slot k: the caller fills block(k) and coupling(k)
  !> through the pointers zeta and xe.
  subroutine next_slot(this, i, j, zeta, xe)
    class(pair_blocks_t), intent(inout), target :: this
    integer, intent(in) :: i, j
    real(wp), pointer, intent(out) :: zeta(:, :), xe(:, :, :)
    if (.not. allocated(this%ij)) call grow(this, 64)
    if (this%count == size(this%ij, 2)) call grow(this, 2*size(this%ij, 2))
    this%count = this%count + 1
    this%ij(:, this%count) = [i, j]
    zeta => this%zeta(:, :, this%count)
    xe => this%xe(:, :, :, this%count)
  end subroutine next_slot

  !> Make the list hold `n` pairs whose contents `store` sets next, slot by slot (the storage
  !> grows when needed; what it held is not kept).
  subroutine resize(this, n)
    class(pair_blocks_t), intent(inout) :: this
    integer, intent(in) :: n
    this%count = 0
    if (.not. allocated(this%ij)) then
      call grow(this, max(64, n))
    else if (size(this%ij, 2) < n) then
      call grow(this, max(n, 2*size(this%ij, 2)))
    end if
    this%count = n
  end subroutine resize

  !> Set slot k (1..n_pairs) to pair (i, j) with block zeta and coupling xe. Different slots
  !> may be stored by different threads at the same time.
  subroutine store(this, k, i, j, zeta, xe)
    class(pair_blocks_t), intent(inout) :: this
    integer, intent(in) :: k, i, j
    real(wp), intent(in) :: zeta(12, 12), xe(12, 3, 3)
    this%ij(:, k) = [i, j]
    this%zeta(:, :, k) = zeta
    this%xe(:, :, :, k) = xe
  end subroutine store

  !> Enlarge the storage to `capacity` pairs, keeping the pairs held.
  subroutine grow(this, capacity)
    type(pair_blocks_t), intent(inout) :: this
    integer, intent(in) :: capacity
    integer, allocatable :: ij(:, :)
    real(wp), allocatable :: zeta(:, :, :), xe(:, :, :, :)
    allocate (ij(2, capacity), zeta(12, 12, capacity), xe(12, 3, 3, capacity))
    if (this%count > 0) then
      ij(:, 1:this%count) = this%ij(:, 1:this%count)
      zeta(:, :, 1:this%count) = this%zeta(:, :, 1:this%count)
      xe(:, :, :, 1:this%count) = this%xe(:, :, :, 1:this%count)
    end if
    call move_alloc(ij, this%ij)
    call move_alloc(zeta, this%zeta)
    call move_alloc(xe, this%xe)
  end subroutine grow

  !> Number of pairs in the list.
  pure integer function n_pairs(this)
    class(pair_blocks_t), intent(in) :: this
    n_pairs = this%count
  end function n_pairs

  !> The beads (i, j) of pair k.
  pure function pair(this, k) result(ij)
    class(pair_blocks_t), intent(in) :: this
    integer, intent(in) :: k
    integer :: ij(2)
    ij = this%ij(:, k)
  end function pair

  !> The 12 rows (or columns) of pair k in a 6N vector.
  pure function rows(this, k) result(ii)
    class(pair_blocks_t), intent(in) :: this
    integer, intent(in) :: k
    integer :: ii(12), c
    do c = 1, 6
      ii(c) = 6*(this%ij(1, k) - 1) + c
      ii(6 + c) = 6*(this%ij(2, k) - 1) + c
    end do
  end function rows

  !> y = y + (sum of the pair blocks) x for 6N vectors x, y.
  !> Each block by columns into a local 12-vector (no vector-subscript temporaries).
  subroutine apply(this, x, y)
    class(pair_blocks_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp), intent(inout) :: y(:)
    integer :: k, c, i0, j0
    real(wp) :: xl(12), yl(12)
    do k = 1, this%count
      i0 = 6*(this%ij(1, k) - 1)
      j0 = 6*(this%ij(2, k) - 1)
      xl(1:6) = x(i0 + 1:i0 + 6)
      xl(7:12) = x(j0 + 1:j0 + 6)
      yl = 0.0_wp
      do c = 1, 12
        yl = yl + this%zeta(:, c, k)*xl(c)
      end do
      y(i0 + 1:i0 + 6) = y(i0 + 1:i0 + 6) + yl(1:6)
      y(j0 + 1:j0 + 6) = y(j0 + 1:j0 + 6) + yl(7:12)
    end do
  end subroutine apply

  !> zeta = zeta + the pair blocks, for a dense 6N x 6N friction (full storage); with `position`
  !> the friction's rows and columns are permuted: entry (a, b) of the 6N ordering
  !> [U_1, Omega_1, U_2, ...] is stored at (position(a), position(b)).
  subroutine add_friction(this, zeta, position)
    class(pair_blocks_t), intent(in) :: this
    real(wp), intent(inout) :: zeta(:, :)
    integer, intent(in), optional :: position(:)
    integer :: k, ii(12)
    do k = 1, this%count
      ii = rows(this, k)
      if (present(position)) ii = position(ii)
      zeta(ii, ii) = zeta(ii, ii) + this%zeta(:, :, k)
    end do
  end subroutine add_friction

  !> b = b + (sum of the pair couplings) : e for the symmetric traceless rate of strain e.
  subroutine add_strain(this, e, b)
    class(pair_blocks_t), intent(in) :: this
    real(wp), intent(in) :: e(3, 3)
    real(wp), intent(inout) :: b(:)
    integer :: k, ii(12), a, c
    real(wp) :: x(12)
    do k = 1, this%count
      ii = rows(this, k)
      x = 0.0_wp
      do c = 1, 3
        do a = 1, 3
          x = x + this%xe(:, a, c, k)*e(a, c)
        end do
      end do
      b(ii) = b(ii) + x
    end do
  end subroutine add_strain

  !> x(6N, 5) = x + the pair couplings for the five basis strains of the rows of `basis`
  !> (basis(:, :, k), k = 1..5).
  subroutine add_strain_basis(this, basis, x)
    class(pair_blocks_t), intent(in) :: this
    real(wp), intent(in) :: basis(:, :, :)
    real(wp), intent(inout) :: x(:, :)
    integer :: k
    do k = 1, size(x, 2)
      call this%add_strain(basis(:, :, k), x(:, k))
    end do
  end subroutine add_strain_basis

  !> The largest scaled entry of the difference of two lists' friction blocks: the maximum over
  !> the pairs of either list and the entries (a, b) of their 12 x 12 blocks of
  !> |zeta_this(a, b) - zeta_other(a, b)| s_a s_b, a pair missing from one list having a zero
  !> block there. s: a 6N scale vector; slot(N, N): integer work, zero on entry and on return.
  !> The blocks are symmetric (friction), so their lower triangles are compared; the couplings
  !> xe are not.
  function largest_scaled_change(this, other, s, slot) result(delta)
    class(pair_blocks_t), intent(in) :: this
    type(pair_blocks_t), intent(in) :: other
    real(wp), intent(in) :: s(:)
    integer, intent(inout) :: slot(:, :)
    real(wp) :: delta
    integer :: k, m, i, j
    delta = 0.0_wp
    do k = 1, other%count
      slot(other%ij(1, k), other%ij(2, k)) = k
    end do
    do k = 1, this%count
      i = this%ij(1, k)
      j = this%ij(2, k)
      m = slot(i, j)
      if (m > 0) then
        delta = max(delta, scaled_max(this%zeta(:, :, k), scales(this, k, s), other%zeta(:, :, m)))
        slot(i, j) = -m
      else
        delta = max(delta, scaled_max(this%zeta(:, :, k), scales(this, k, s)))
      end if
    end do
    do k = 1, other%count
      i = other%ij(1, k)
      j = other%ij(2, k)
      if (slot(i, j) > 0) delta = max(delta, scaled_max(other%zeta(:, :, k), scales(other, k, s)))
      slot(i, j) = 0
    end do
  end function largest_scaled_change

  !> The entries of a 6N scale vector s at the 12 rows of pair k.
  pure function scales(this, k, s) result(sl)
    type(pair_blocks_t), intent(in) :: this
    integer, intent(in) :: k
    real(wp), intent(in) :: s(:)
    real(wp) :: sl(12)
    integer :: i0, j0
    i0 = 6*(this%ij(1, k) - 1)
    j0 = 6*(this%ij(2, k) - 1)
    sl(1:6) = s(i0 + 1:i0 + 6)
    sl(7:12) = s(j0 + 1:j0 + 6)
  end function scales

  !> max over a >= b of |z(a, b) - y(a, b)| sl(a) sl(b) (y absent: zero), for symmetric z, y.
  pure real(wp) function scaled_max(z, sl, y)
    real(wp), intent(in) :: z(12, 12), sl(12)
    real(wp), intent(in), optional :: y(12, 12)
    real(wp) :: col
    integer :: a, b
    scaled_max = 0.0_wp
    do b = 1, 12
      col = 0.0_wp
      if (present(y)) then
        do a = b, 12
          col = max(col, abs(z(a, b) - y(a, b))*sl(a))
        end do
      else
        do a = b, 12
          col = max(col, abs(z(a, b))*sl(a))
        end do
      end if
      scaled_max = max(scaled_max, col*sl(b))
    end do
  end function scaled_max

end module kf_pair_blocks
