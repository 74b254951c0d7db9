!> Counting and packing the pairs i < j of N beads, in 64-bit integers: N(N-1) passes
!> huge(int32) from N = 46,342 on and the count N(N-1)/2 itself from N = 65,537, so any pair
!> count or packed pair index in default integers overflows for chains the scenes accept
!> (up to 100,000 beads). The one definition of these formulas for the run diagnostics
!> (kf_run_diagnostics), the RPY pair tables (kf_hydro_rpy) and the memory estimate
!> (kf_resources).
module kf_pairs
  use kf_kinds, only: i8
  implicit none
  private

  public :: pair_count, pair_row_offset

contains

  !> Number of pairs i < j of `n_beads` beads, N(N-1)/2 (0 for N < 2).
  pure integer(i8) function pair_count(n_beads)
    integer, intent(in) :: n_beads
    integer(i8) :: n
    n = max(0_i8, int(n_beads, i8))
    pair_count = n*max(0_i8, n - 1)/2
  end function pair_count

  !> Row-major packing of the pairs i < j of `n` beads (row i holds j = i+1..n, rows one after
  !> the other): pair (i, j) has index pair_row_offset(i, n) + j, from 1 for (1, 2) to
  !> pair_count(n) for (n-1, n).
  pure integer(i8) function pair_row_offset(i, n)
    integer, intent(in) :: i, n
    integer(i8) :: ii
    ii = int(i, i8)
    pair_row_offset = (ii - 1)*int(n, i8) - (ii*(ii - 1))/2 - ii
  end function pair_row_offset

end module kf_pairs
