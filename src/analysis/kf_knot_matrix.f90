!> The knot matrix K(i, j) (0-based beads, i < j): k_f of the subchain i..j with the closure
!> sphere of that subchain (its own centre of mass and R_g), each subchain with its own random
!> stream (seed, i*65536 + j + 1), so that the result does not depend on how the subchains are
!> shared among ranks. Knot core: the shortest subchain with K >= 0.5 (the lowest i on a tie).
!> Slipknot: a subchain with K >= 0.5 while the whole chain has k_f < 0.1.
module kf_knot_matrix
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_nan
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_knot_closure, only: knot_stats_t, analyse_closures
  implicit none
  private

  real(wp), parameter, public :: knotted_threshold = 0.5_wp
  real(wp), parameter, public :: slipknot_whole_max = 0.1_wp
  integer, parameter, public :: default_min_length = 10
  integer, parameter, public :: default_matrix_closures = 100

  public :: knot_matrix, knot_core, is_slipknot, subchain_stream, n_subchains, for_max_merge, after_max_merge

  !> Stands for NaN (not computed here, or shorter than min_length) in a merge by maximum.
  real(wp), parameter :: not_computed = -huge(1.0_wp)

contains

  !> Stream number of the subchain i..j (0-based).
  elemental integer(i8) function subchain_stream(i, j)
    integer, intent(in) :: i, j
    subchain_stream = int(i, i8)*65536_i8 + int(j, i8) + 1_i8
  end function subchain_stream

  !> Number of subchains i < j of an N-bead chain with at least min_length beads.
  pure integer function n_subchains(n, min_length)
    integer, intent(in) :: n, min_length
    integer :: l
    n_subchains = 0
    do l = max(2, min_length), n
      n_subchains = n_subchains + (n - l + 1)
    end do
  end function n_subchains

  !> K(N, N) for r(3, N); K(i+1, j+1) holds the subchain i..j. Entries not computed are NaN.
  !> With part/nparts only the subchains number part, part+nparts, ... (0-based, in the order
  !> i ascending, then j ascending) are computed: the others are NaN (for parallel farming).
  !> With stride > 1 only the subchains with i and j on the grid 0, stride, 2 stride, ... (and
  !> j = N - 1) are computed (the others NaN); each computed entry equals the full matrix's, its
  !> stream being the subchain's own.
  subroutine knot_matrix(r, closures, seed, min_length, kmat, error, part, nparts, stride)
    real(wp), intent(in) :: r(:, :)
    integer, intent(in) :: closures
    integer(i8), intent(in) :: seed
    integer, intent(in) :: min_length
    real(wp), intent(out) :: kmat(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: part, nparts, stride
    type(knot_stats_t) :: st
    integer :: n, i, j, idx, p, np, step
    n = size(r, 2)
    p = 0
    np = 1
    step = 1
    if (present(part)) p = part
    if (present(nparts)) np = nparts
    if (present(stride)) step = stride
    kmat = ieee_value(0.0_wp, ieee_quiet_nan)
    if (min_length < 2) then
      call fatal_error(error, 'knot matrix: min_length must be >= 2, got '//to_str(min_length))
      return
    end if
    if (step < 1) then
      call fatal_error(error, 'knot matrix: stride must be >= 1, got '//to_str(step))
      return
    end if
    if (size(kmat, 1) /= n .or. size(kmat, 2) /= n) then
      call fatal_error(error, 'knot matrix: the matrix must be N x N')
      return
    end if
    idx = -1
    do i = 0, n - 2
      do j = i + 1, n - 1
        if (j - i + 1 < min_length) cycle
        if (modulo(i, step) /= 0 .or. (modulo(j, step) /= 0 .and. j /= n - 1)) cycle
        idx = idx + 1
        if (modulo(idx, np) /= p) cycle
        call analyse_closures(r(:, i + 1:j + 1), closures, seed, st, error, stream=subchain_stream(i, j))
        if (allocated(error)) return
        kmat(i + 1, j + 1) = st%kf
      end do
    end do
  end subroutine knot_matrix

  !> The knot core: the shortest subchain with K >= 0.5, as 0-based [i, j]; found = .false. if none.
  subroutine knot_core(kmat, core, found)
    real(wp), intent(in) :: kmat(:, :)
    integer, intent(out) :: core(2)
    logical, intent(out) :: found
    integer :: i, j, best
    found = .false.
    core = -1
    best = huge(best)
    do i = 1, size(kmat, 1)
      do j = i + 1, size(kmat, 2)
        if (ieee_is_nan(kmat(i, j))) cycle
        if (kmat(i, j) >= knotted_threshold .and. j - i < best) then
          best = j - i
          core = [i - 1, j - 1]
          found = .true.
        end if
      end do
    end do
  end subroutine knot_core

  !> A slipknot: some subchain has K >= 0.5 while the whole chain has k_f < 0.1.
  logical function is_slipknot(kmat, kf_whole)
    real(wp), intent(in) :: kmat(:, :)
    real(wp), intent(in) :: kf_whole
    integer :: core(2)
    logical :: found
    call knot_core(kmat, core, found)
    is_slipknot = found .and. kf_whole < slipknot_whole_max
  end function is_slipknot

  !> Partial knot matrices (each with NaN where its part did not compute) merge by an element-wise
  !> maximum of their `for_max_merge` values (e.g. an MPI maximum over ranks) followed by
  !> `after_max_merge`: NaN becomes -huge, below every k_f, and back.
  elemental real(wp) function for_max_merge(k)
    real(wp), intent(in) :: k
    for_max_merge = merge(not_computed, k, ieee_is_nan(k))
  end function for_max_merge

  !> The inverse of `for_max_merge` after the maximum.
  elemental real(wp) function after_max_merge(k)
    real(wp), intent(in) :: k
    after_max_merge = k
    if (k == not_computed) after_max_merge = ieee_value(0.0_wp, ieee_quiet_nan)
  end function after_max_merge

end module kf_knot_matrix
