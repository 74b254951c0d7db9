!> Numerical diagnostics of a run, updated at every accepted integrator step (a step monitor,
!> kf_step_monitor): strand passages, overlapping beads and bond strain.
!>
!> - Strand passages: `count_strand_passages(y_old, y_new, passage_tolerance)` per accepted
!>   step (kf_strand_passage; beads move linearly within a step), summed over the run; the
!>   time of the first one is the end time of the step in which it happened.
!> - Overlaps: a pair i < j (any |i - j|) overlaps when |r_i - r_j| < 1 (= d). An episode of a
!>   pair starts at the first accepted step (or the initial configuration) where it overlaps and
!>   ends at the first accepted step where it does not; its duration is the difference of these
!>   two step times, so durations are resolved to one step. Kept: episodes started (completed +
!>   ongoing), mean and maximum duration of the completed ones, the current and the largest
!>   number of overlapping pairs, the smallest distance over pairs with |i - j| > 1.
!> - The largest relative bond strain |l - l0|/l0 over the run.
!> The initial configuration (`start`) counts as a step of the run for overlaps, distances and
!> strain. The state can be saved and restored (`get_state` / `set_state`) so a resumed run
!> continues the counters, ongoing episodes included.
!> Cost per step: beads: one pass over the close pairs (kf_pair_geometry, pairs closer than
!> `diag_pair_cutoff`; the dynamics' own list of the step's end when it was built there with at
!> least that cutoff, see `share_pairs`); the overlapping pairs are kept as a sorted list, so
!> memory is O(N + overlapping pairs), not O(N^2). The smallest non-bonded distance comes from
!> the list (a full scan only when no non-bonded pair is in it). Bonds: during the step every point
!> of bond k stays within rho_k = l_k/2 + (largest displacement of its two beads) of the bond's
!> midpoint at the start, so bonds i, j can only touch when their midpoints are closer than
!> rho_i + rho_j + tolerance; only those pairs go through the exact test `segments_pass` of
!> kf_strand_passage (the count is the same as `count_strand_passages`).
module kf_run_diagnostics
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_step_monitor, only: step_monitor_t
  use kf_pairs, only: pair_count
  use kf_strand_passage, only: segments_pass
  use kf_pair_geometry, only: pair_geometry_t
  use kf_vector_ops, only: sort_index
  implicit none
  private

  public :: configuration_diagnostics, prefiltered_passages, diagnostics_memory

  !> Sizes of the saved state (`get_state` / `set_state`).
  integer, parameter, public :: diag_n_counters = 5, diag_n_values = 5
  !> Range of the pair list the diagnostics look at: every overlapping pair (< 1) and, on any
  !> chain with bond strain below 20 %, the pairs (i, i + 2) (<= 2 l0 (1 + strain)), so the
  !> smallest non-bonded distance is found in the list.
  real(wp), parameter, public :: diag_pair_cutoff = 2.5_wp

  !> Diagnostics of one run; `init` before use, `start` with the initial configuration.
  type, extends(step_monitor_t), public :: run_diagnostics_t
    real(wp) :: bond_length = 1.02_wp            !< l0 of the strain
    real(wp) :: passage_tolerance = 1.0e-6_wp    !< contact distance of the passage test (units of d)
    integer :: n_beads = 0
    integer(i8) :: strand_passages = 0           !< cumulative since t = 0
    real(wp) :: first_passage_time = -1.0_wp     !< -1 while there is none
    integer(i8) :: overlap_episodes = 0          !< episodes started (completed + ongoing)
    integer(i8) :: completed_episodes = 0
    real(wp) :: duration_sum = 0.0_wp            !< over completed episodes
    real(wp) :: duration_max = 0.0_wp            !< over completed episodes
    integer :: overlapping_pairs = 0             !< now (after the last step seen)
    integer :: max_overlapping_pairs = 0
    real(wp) :: min_distance2 = huge(1.0_wp)     !< smallest squared distance, |i - j| > 1
    real(wp) :: max_bond_strain = 0.0_wp
    integer, private :: n_over = 0                      !< ongoing episodes (overlapping pairs)
    integer(i8), allocatable, private :: over_key(:)    !< their pair keys (pair_key), ascending
    real(wp), allocatable, private :: over_start(:)     !< and the starts of their episodes
    integer(i8), allocatable, private :: new_key(:)     !< work: the overlapping pairs now
    real(wp), allocatable, private :: new_start(:)
    real(wp), allocatable, private :: work(:, :)       !< (N, 4) work space
    type(pair_geometry_t), private :: own              !< the list when none is shared
    type(pair_geometry_t), pointer, private :: shared => null()
  contains
    procedure :: init => diagnostics_init
    procedure :: share_pairs
    procedure :: start => diagnostics_start
    procedure :: on_step => diagnostics_on_step
    procedure :: min_distance => diagnostics_min_distance
    procedure :: mean_duration => diagnostics_mean_duration
    procedure :: get_state => diagnostics_get_state
    procedure :: set_state => diagnostics_set_state
    procedure, private :: observe
  end type run_diagnostics_t

contains

  !> Bytes the run diagnostics of `n_beads` beads allocate, for the memory estimate at set-up:
  !> four work columns and the pair list's search arrays per bead (11 words), and the close pairs
  !> of a chain no denser than close packing (at most 46 per bead within diag_pair_cutoff, each
  !> 48 bytes), of which at most 6 per bead overlap (16 bytes each, twice).
  pure integer(i8) function diagnostics_memory(n_beads) result(bytes)
    integer, intent(in) :: n_beads
    bytes = int(max(1, n_beads), i8)*(11_i8*8_i8 + 46_i8*48_i8 + 6_i8*32_i8)
  end function diagnostics_memory

  !> Reset for a chain of `n_beads` beads with rest length `bond_length`; `passage_tolerance`
  !> (default 1e-6) is the contact distance of the strand-passage test.
  subroutine diagnostics_init(this, n_beads, bond_length, passage_tolerance)
    class(run_diagnostics_t), intent(out) :: this
    integer, intent(in) :: n_beads
    real(wp), intent(in) :: bond_length
    real(wp), intent(in), optional :: passage_tolerance
    this%n_beads = n_beads
    this%bond_length = bond_length
    if (present(passage_tolerance)) this%passage_tolerance = passage_tolerance
    allocate (this%work(max(n_beads, 1), 4), this%over_key(16), this%over_start(16), &
              this%new_key(16), this%new_start(16))
  end subroutine diagnostics_init

  !> Look at `pairs` (the dynamics' close pairs of its last evaluation) instead of finding the
  !> pairs again whenever that list was built at the configuration of a step's end with a
  !> cutoff of at least diag_pair_cutoff (a dopri45 step ends with an evaluation there).
  !> `pairs` must outlive this object.
  subroutine share_pairs(this, pairs)
    class(run_diagnostics_t), intent(inout) :: this
    type(pair_geometry_t), intent(in), target :: pairs
    this%shared => pairs
  end subroutine share_pairs

  !> Take the initial configuration r(3, N) at time t: overlaps present now start episodes at t.
  subroutine diagnostics_start(this, t, r)
    class(run_diagnostics_t), intent(inout) :: this
    real(wp), intent(in) :: t
    real(wp), intent(in) :: r(:, :)
    call this%observe(t, r)
  end subroutine diagnostics_start

  !> One accepted step (kf_step_monitor).
  subroutine diagnostics_on_step(this, t_old, y_old, t_new, y_new)
    class(run_diagnostics_t), intent(inout) :: this
    real(wp), intent(in) :: t_old
    real(wp), intent(in) :: y_old(:, :)
    real(wp), intent(in) :: t_new
    real(wp), intent(in) :: y_new(:, :)
    integer :: passages
    passages = prefiltered_passages(y_old, y_new, this%passage_tolerance, this%work)
    if (passages > 0) then
      if (this%strand_passages == 0) this%first_passage_time = t_new
      this%strand_passages = this%strand_passages + passages
    end if
    call this%observe(t_new, y_new)
  end subroutine diagnostics_on_step

  !> Overlap bookkeeping, distances and strain of configuration r at time t.
  subroutine observe(this, t, r)
    class(run_diagnostics_t), intent(inout) :: this
    real(wp), intent(in) :: t
    real(wp), intent(in) :: r(:, :)
    logical :: use_shared
    use_shared = .false.
    if (associated(this%shared)) use_shared = this%shared%covers(r, diag_pair_cutoff)
    if (use_shared) then
      call observe_pairs(this, t, r, this%shared)
    else
      call this%own%build(r, diag_pair_cutoff)
      call observe_pairs(this, t, r, this%own)
    end if
  end subroutine observe

  !> `observe` with the close pairs g of r: the overlapping pairs now (sorted by key) merged with
  !> the ongoing episodes (sorted): new ones start at t, vanished ones end at t.
  subroutine observe_pairs(this, t, r, g)
    class(run_diagnostics_t), intent(inout) :: this
    real(wp), intent(in) :: t
    real(wp), intent(in) :: r(:, :)
    type(pair_geometry_t), intent(in) :: g
    integer :: i, j, k, n, now, a, b
    integer(i8) :: key, old_key
    real(wp) :: dmin2, duration
    logical :: found
    n = min(this%n_beads, size(r, 2))
    now = 0
    dmin2 = huge(1.0_wp)
    found = .false.
    do k = 1, g%size()
      call g%pair(k, i, j)
      if (j > n) cycle
      if (j - i > 1) then
        dmin2 = min(dmin2, g%distance(k)**2)
        found = .true.
      end if
      if (g%distance(k) >= 1.0_wp) cycle
      now = now + 1
      call grow(this%new_key, this%new_start, now)
      this%new_key(now) = pair_key(i, j, n)
    end do
    if (.not. found) dmin2 = full_scan_min_distance2(r(:, 1:n), this%work)
    this%min_distance2 = min(this%min_distance2, dmin2)
    ! merge the two sorted key lists
    a = 1
    b = 1
    do while (a <= this%n_over .or. b <= now)
      old_key = huge(1_i8)
      if (a <= this%n_over) old_key = this%over_key(a)
      key = huge(1_i8)
      if (b <= now) key = this%new_key(b)
      if (old_key < key) then
        ! an ongoing episode ended
        duration = t - this%over_start(a)
        this%completed_episodes = this%completed_episodes + 1
        this%duration_sum = this%duration_sum + duration
        this%duration_max = max(this%duration_max, duration)
        a = a + 1
      else if (old_key == key) then
        this%new_start(b) = this%over_start(a)   ! continues
        a = a + 1
        b = b + 1
      else
        this%new_start(b) = t                    ! starts now
        this%overlap_episodes = this%overlap_episodes + 1
        b = b + 1
      end if
    end do
    call grow(this%over_key, this%over_start, now)
    this%over_key(1:now) = this%new_key(1:now)
    this%over_start(1:now) = this%new_start(1:now)
    this%n_over = now
    this%overlapping_pairs = now
    this%max_overlapping_pairs = max(this%max_overlapping_pairs, now)
    this%max_bond_strain = max(this%max_bond_strain, max_strain(r(:, 1:n), this%bond_length))
  end subroutine observe_pairs

  !> Key of pair i < j of n beads, ascending in the (i, j) order of kf_pair_geometry's lists.
  pure integer(i8) function pair_key(i, j, n)
    integer, intent(in) :: i, j, n
    pair_key = int(i - 1, i8)*int(n, i8) + int(j, i8)
  end function pair_key

  !> Beads i < j of the pair with key `key` (the inverse of pair_key).
  pure subroutine pair_of_key(key, n, i, j)
    integer(i8), intent(in) :: key
    integer, intent(in) :: n
    integer, intent(out) :: i, j
    i = int((key - 1)/n) + 1
    j = int(key - int(i - 1, i8)*n)
  end subroutine pair_of_key

  !> Room for m entries in a key list and its start times (contents kept).
  subroutine grow(key, start, m)
    integer(i8), allocatable, intent(inout) :: key(:)
    real(wp), allocatable, intent(inout) :: start(:)
    integer, intent(in) :: m
    integer(i8), allocatable :: k2(:)
    real(wp), allocatable :: s2(:)
    integer :: cap
    if (size(key) >= m) return
    cap = max(2*size(key), m)
    allocate (k2(cap), s2(cap))
    k2(1:size(key)) = key
    s2(1:size(start)) = start
    call move_alloc(k2, key)
    call move_alloc(s2, start)
  end subroutine grow

  !> Smallest squared distance over pairs with |i - j| > 1 of r(3, N) by a full (vectorised)
  !> scan; huge when N < 3. `work` has at least N rows and 4 columns.
  function full_scan_min_distance2(r, work) result(dmin2)
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(inout) :: work(:, :)
    real(wp) :: dmin2
    integer :: j, n
    n = size(r, 2)
    dmin2 = huge(1.0_wp)
    associate (x => work(:, 1), y => work(:, 2), z => work(:, 3), d2 => work(:, 4))
      x(1:n) = r(1, 1:n)
      y(1:n) = r(2, 1:n)
      z(1:n) = r(3, 1:n)
      do j = 3, n
        d2(1:j - 2) = (x(1:j - 2) - x(j))**2 + (y(1:j - 2) - y(j))**2 + (z(1:j - 2) - z(j))**2
        dmin2 = min(dmin2, minval(d2(1:j - 2)))
      end do
    end associate
  end function full_scan_min_distance2

  !> Smallest distance over pairs with |i - j| > 1 seen so far (-1 when there is none: N < 3).
  pure real(wp) function diagnostics_min_distance(this) result(d)
    class(run_diagnostics_t), intent(in) :: this
    if (this%min_distance2 < huge(1.0_wp)) then
      d = sqrt(this%min_distance2)
    else
      d = -1.0_wp
    end if
  end function diagnostics_min_distance

  !> Mean duration of the completed overlap episodes (0 when none is completed).
  pure real(wp) function diagnostics_mean_duration(this) result(d)
    class(run_diagnostics_t), intent(in) :: this
    if (this%completed_episodes > 0) then
      d = this%duration_sum/real(this%completed_episodes, wp)
    else
      d = 0.0_wp
    end if
  end function diagnostics_mean_duration

  !> The state for a checkpoint: counters(diag_n_counters) = [strand passages, episodes started,
  !> episodes completed, max overlapping pairs, ongoing episodes n_on];
  !> values(diag_n_values) = [first passage time, sum and max of completed durations, smallest
  !> squared distance (|i - j| > 1; huge when none), max bond strain];
  !> ongoing(3, max(1, n_on)) = (i, j, start time) of every ongoing episode (one unused column
  !> of zeros when there is none, so the array is never empty).
  subroutine diagnostics_get_state(this, counters, values, ongoing)
    class(run_diagnostics_t), intent(in) :: this
    integer(i8), intent(out) :: counters(diag_n_counters)
    real(wp), intent(out) :: values(diag_n_values)
    real(wp), allocatable, intent(out) :: ongoing(:, :)
    integer :: m, i, j
    counters = [this%strand_passages, this%overlap_episodes, this%completed_episodes, &
                int(this%max_overlapping_pairs, i8), int(this%n_over, i8)]
    values = [this%first_passage_time, this%duration_sum, this%duration_max, this%min_distance2, &
              this%max_bond_strain]
    allocate (ongoing(3, max(1, this%n_over)))
    ongoing = 0.0_wp
    do m = 1, this%n_over
      call pair_of_key(this%over_key(m), this%n_beads, i, j)
      ongoing(:, m) = [real(i, wp), real(j, wp), this%over_start(m)]
    end do
  end subroutine diagnostics_get_state

  !> Restore a state written by `get_state` (after `init` with the same number of beads).
  subroutine diagnostics_set_state(this, counters, values, ongoing, error)
    class(run_diagnostics_t), intent(inout) :: this
    integer(i8), intent(in) :: counters(:)
    real(wp), intent(in) :: values(:)
    real(wp), intent(in) :: ongoing(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer :: i, j, m, n_on
    integer(i8), allocatable :: keys(:)
    integer, allocatable :: order(:)
    if (size(counters) /= diag_n_counters .or. size(values) /= diag_n_values .or. size(ongoing, 1) /= 3) then
      call fatal_error(error, 'diagnostics state: wrong sizes (counters '//to_str(size(counters))// &
        ', values '//to_str(size(values))//', ongoing rows '//to_str(size(ongoing, 1))//')')
      return
    end if
    n_on = int(counters(5))
    if (n_on < 0 .or. n_on > size(ongoing, 2) .or. int(n_on, i8) > pair_count(this%n_beads)) then
      call fatal_error(error, 'diagnostics state: '//to_str(n_on)//' ongoing episodes do not fit')
      return
    end if
    allocate (keys(n_on))
    do m = 1, n_on
      i = nint(ongoing(1, m))
      j = nint(ongoing(2, m))
      if (i < 1 .or. i >= j .or. j > this%n_beads) then
        call fatal_error(error, 'diagnostics state: ongoing episode of pair ('//to_str(i)//', '// &
          to_str(j)//') is not a pair of '//to_str(this%n_beads)//' beads')
        return
      end if
      keys(m) = pair_key(i, j, this%n_beads)
    end do
    ! in key order (files before the sorted list stored them column by column); keys < N^2 are
    ! exact in real(wp)
    order = sort_index(real(keys, wp))
    do m = 2, n_on
      if (keys(order(m)) == keys(order(m - 1))) then
        call pair_of_key(keys(order(m)), this%n_beads, i, j)
        call fatal_error(error, 'diagnostics state: pair ('//to_str(i)//', '//to_str(j)// &
          ') has two ongoing episodes')
        return
      end if
    end do
    call grow(this%over_key, this%over_start, n_on)
    this%over_key(1:n_on) = keys(order)
    this%over_start(1:n_on) = ongoing(3, order)
    this%n_over = n_on
    this%strand_passages = counters(1)
    this%overlap_episodes = counters(2)
    this%completed_episodes = counters(3)
    this%max_overlapping_pairs = int(counters(4))
    this%overlapping_pairs = n_on
    this%first_passage_time = values(1)
    this%duration_sum = values(2)
    this%duration_max = values(3)
    this%min_distance2 = values(4)
    this%max_bond_strain = values(5)
  end subroutine diagnostics_set_state

  !> Number of pairs of non-adjacent bonds passing through each other while the chain moves
  !> linearly from r0(3, N) to r1(3, N): the count of `count_strand_passages` (kf_strand_passage),
  !> with the midpoint-sphere prefilter described at the top of this module. `work` has at least
  !> N rows and 4 columns.
  integer function prefiltered_passages(r0, r1, tolerance, work) result(count)
    real(wp), intent(in) :: r0(:, :), r1(:, :)
    real(wp), intent(in) :: tolerance
    real(wp), intent(inout) :: work(:, :)
    integer :: n, i, j
    real(wp) :: shift(size(r0, 2))
    count = 0
    n = size(r0, 2)
    if (n < 4) return
    shift = sqrt(sum((r1 - r0)**2, dim=1))
    associate (cx => work(:, 1), cy => work(:, 2), cz => work(:, 3), rho => work(:, 4))
      cx(1:n - 1) = 0.5_wp*(r0(1, 1:n - 1) + r0(1, 2:n))
      cy(1:n - 1) = 0.5_wp*(r0(2, 1:n - 1) + r0(2, 2:n))
      cz(1:n - 1) = 0.5_wp*(r0(3, 1:n - 1) + r0(3, 2:n))
      rho(1:n - 1) = 0.5_wp*sqrt(sum((r0(:, 2:n) - r0(:, 1:n - 1))**2, dim=1)) + &
                     max(shift(1:n - 1), shift(2:n)) + 0.5_wp*tolerance
      do j = 3, n - 1
        if (all((cx(1:j - 2) - cx(j))**2 + (cy(1:j - 2) - cy(j))**2 + (cz(1:j - 2) - cz(j))**2 > &
                (rho(1:j - 2) + rho(j))**2)) cycle
        do i = 1, j - 2
          if ((cx(i) - cx(j))**2 + (cy(i) - cy(j))**2 + (cz(i) - cz(j))**2 > (rho(i) + rho(j))**2) cycle
          if (segments_pass(r0(:, i), r0(:, i + 1), r0(:, j), r0(:, j + 1), &
                            r1(:, i), r1(:, i + 1), r1(:, j), r1(:, j + 1), tolerance)) count = count + 1
        end do
      end do
    end associate
  end function prefiltered_passages

  !> Largest |l - l0|/l0 over the bonds of r(3, N).
  pure real(wp) function max_strain(r, l0) result(s)
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(in) :: l0
    integer :: i
    s = 0.0_wp
    do i = 1, size(r, 2) - 1
      s = max(s, abs(norm2(r(:, i + 1) - r(:, i)) - l0))
    end do
    s = s/l0
  end function max_strain

  !> Per-configuration diagnostics of r(3, N): pairs i < j closer than 1, the smallest distance
  !> over pairs with |i - j| > 1 (-1 when N < 3) and the largest relative bond strain.
  pure subroutine configuration_diagnostics(r, bond_length, overlapping_pairs, min_distance, max_bond_strain)
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(in) :: bond_length
    integer, intent(out) :: overlapping_pairs
    real(wp), intent(out) :: min_distance, max_bond_strain
    integer :: i, j
    real(wp) :: d2, dmin2
    overlapping_pairs = 0
    dmin2 = huge(1.0_wp)
    do j = 2, size(r, 2)
      do i = 1, j - 1
        d2 = sum((r(:, i) - r(:, j))**2)
        if (d2 < 1.0_wp) overlapping_pairs = overlapping_pairs + 1
        if (j - i > 1) dmin2 = min(dmin2, d2)
      end do
    end do
    if (dmin2 < huge(1.0_wp)) then
      min_distance = sqrt(dmin2)
    else
      min_distance = -1.0_wp
    end if
    max_bond_strain = max_strain(r, bond_length)
  end subroutine configuration_diagnostics

end module kf_run_diagnostics
