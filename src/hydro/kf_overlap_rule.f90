!> How the hydrodynamics treats overlapping beads (&hydro overlap; docs/limitations.md).
!>
!> 'bwe' is the reference study's rule, as PHYSICS.md 3.3 words it: a pair with r <= 1 has its
!> lubrication correction evaluated at (1 + eps_lub) r^, and everything else is left as it is -
!> the many-body multipole friction and every other pair's correction at the real positions, the
!> dynamics of the real positions. Its part lives in the model (kf_hydro_factory passes
!> `literal_bwe` to the multipole model: kf_lubrication evaluates such a pair at 1 + eps_lub,
!> kf_multipole_system clamps nothing); here it leaves the configuration alone, as 'pair' does.
!> Where the many-body system is not positive definite at overlapping positions, the run stops
!> with the Cholesky error (docs/stability.md "The literal BWE rule").
!>
!> 'pair' (the default; a variant of ours, not BWE): an overlapping pair's lubrication
!> correction and also its multipole pair blocks (docs/multipole.md) are evaluated at
!> (1 + eps_lub) times its unit separation, for every pair closer than 1 + eps_lub
!> (kf_lubrication and kf_multipole_system clamp each pair's distance). The pair's ambient
!> velocity difference G (r_j - r_i) is then that of the overlapping geometry while its hydrodynamic coupling to the
!> strain is that of a pair at contact; the mismatch, about (1 + eps_lub - r) G r^, is not
!> resisted, so in the compressional quadrant of the shear a pressed pair approaches at a rate
!> that grows with its overlap (measured: an A = 1 trefoil's pair went from 0.9995 d at t = 24 to
!> 0.717 d at t = 39, then the friction matrix lost positive definiteness).
!>
!> 'separate' evaluates the whole hydrodynamic problem (many-body multipole, lubrication and the
!> ambient flow at the beads) at the nearest configuration without overlaps: every pair at least
!> 1 + eps_lub apart, found by moving the two beads of each overlapping pair apart along their
!> line of centres by equal amounts (which keeps every pair's midpoint, so the centre of the
!> chain) until none is left; the beads then move with those velocities. For one isolated pair
!> this is the shift to 1 + eps_lub applied to the geometry as a whole (a variant of ours, not
!> BWE), so its relative motion is that of a lubricated pair at the gap eps_lub. Forces are
!> always those of the real positions.
!>
!> 'relax' is 'separate' plus a kinematic contact rule: while beads overlap, every bead also moves
!> towards its place in that configuration without overlaps, at the velocity (rh - r)/overlap_time
!> (an isolated pair at r < 1 + eps_lub separates at (1 + eps_lub - r)/overlap_time). Why it is
!> needed: under 'separate' a pair pressed by a net force F creeps into overlap at about
!> 4 eps_lub F per unit time (the squeeze mobility of the gap eps_lub), and no force can push it
!> back, because the same lubrication resists the way out; in a compact tangle the overlaps then
!> grow for hundreds of time units (measured: a trefoil, A = 0.8, orientation b, from 0.92 d at
!> t = 400 to 0.05 d and 39 strand passages at t = 800). The rule is continuous in the positions,
!> vanishes without overlap and holds an overlap at about (creep rate) x overlap_time; the default
!> 0.1 (in units of 1/shear rate) is fast against the shear and slow against the springs
!> (relaxation rate 2k/3 = 333), so the integrator's step size is not affected.
module kf_overlap_rule
  use kf_kinds, only: wp
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_pair_geometry, only: pair_geometry_t
  use kf_hydro_limits, only: eps_lub_in_range, eps_lub_range_text
  implicit none
  private

  public :: pair_rule, separate_rule, relax_rule

  !> The configuration at which the hydrodynamics of positions r is evaluated.
  type, abstract, public :: overlap_rule_t
  contains
    procedure(hydro_configuration_i), deferred :: hydro_configuration
    !> Add the rule's kinematic contact velocity to the bead velocities (default: none).
    procedure :: add_contact_velocity => no_contact_velocity
  end type overlap_rule_t

  abstract interface
    !> Set rh(3, N) to the configuration whose hydrodynamics the beads at r(3, N) get and
    !> `moved` to .true., or leave rh alone and set `moved` to .false. when it is r itself.
    !> `pairs` is a pair list of some configuration; a rule uses it only when it covers r.
    subroutine hydro_configuration_i(this, r, pairs, rh, moved, error)
      import :: overlap_rule_t, wp, pair_geometry_t, error_t
      class(overlap_rule_t), intent(inout) :: this
      real(wp), intent(in) :: r(:, :)
      type(pair_geometry_t), intent(in) :: pairs
      real(wp), intent(inout) :: rh(:, :)
      logical, intent(out) :: moved
      type(error_t), allocatable, intent(out) :: error
    end subroutine hydro_configuration_i
  end interface

  !> 'pair': the hydrodynamics of the real positions (the lubrication clamps each pair).
  type, extends(overlap_rule_t) :: overlap_pair_t
  contains
    procedure :: hydro_configuration => pair_configuration
  end type overlap_pair_t

  !> 'bwe': the hydrodynamics of the real positions as well (the model applies the rule).
  type, extends(overlap_pair_t) :: overlap_bwe_t
  end type overlap_bwe_t

  !> 'separate': the hydrodynamics of the nearest configuration with all pairs >= 1 + eps_lub.
  type, extends(overlap_rule_t) :: overlap_separate_t
    private
    real(wp) :: target = 1.0_wp          !< 1 + eps_lub
    type(pair_geometry_t) :: work        !< close pairs of the configuration being separated
  contains
    procedure :: hydro_configuration => separate_configuration
  end type overlap_separate_t

  !> 'relax': 'separate', and overlapping beads move towards that configuration over `time`.
  type, extends(overlap_separate_t) :: overlap_relax_t
    private
    real(wp) :: time = 0.0_wp            !< overlap_time (> 0; relax_rule sets it)
  contains
    procedure :: add_contact_velocity => relax_contact_velocity
  end type overlap_relax_t

  !> Pairs closer than target - slack overlap, so that sweeps end after finitely many steps (a
  !> moved pair ends at target; the lubrication clamps distances below target to target anyway,
  !> and the far-field part changes by O(slack)). Candidates: the pairs within target + margin, which
  !> includes those a sweep's moves may push together.
  real(wp), parameter :: slack = 1.0e-10_wp, margin = 0.1_wp
  integer, parameter :: max_rounds = 20, max_sweeps = 10000

contains

  !> 'pair', or with `literal_bwe` 'bwe': the hydrodynamics of the real positions.
  subroutine pair_rule(literal_bwe, rule)
    logical, intent(in) :: literal_bwe
    class(overlap_rule_t), allocatable, intent(out) :: rule
    if (literal_bwe) then
      allocate (overlap_bwe_t :: rule)
    else
      allocate (overlap_pair_t :: rule)
    end if
  end subroutine pair_rule

  !> 'separate' for the overlap shift eps_lub (kf_hydro_limits' range).
  subroutine separate_rule(eps_lub, rule, error)
    real(wp), intent(in) :: eps_lub
    class(overlap_rule_t), allocatable, intent(out) :: rule
    type(error_t), allocatable, intent(out) :: error
    if (.not. eps_lub_in_range(eps_lub)) then
      call fatal_error(error, 'overlap rule separate: eps_lub = '//to_str(eps_lub, '(es12.4)')// &
        ' out of range '//eps_lub_range_text())
      return
    end if
    allocate (rule, source=overlap_separate_t(target=1.0_wp + eps_lub))
  end subroutine separate_rule

  !> 'relax' for the overlap shift eps_lub (kf_hydro_limits' range) and the time overlap_time
  !> (> 0) over which an overlap is undone.
  subroutine relax_rule(eps_lub, overlap_time, rule, error)
    real(wp), intent(in) :: eps_lub, overlap_time
    class(overlap_rule_t), allocatable, intent(out) :: rule
    type(error_t), allocatable, intent(out) :: error
    if (.not. eps_lub_in_range(eps_lub)) then
      call fatal_error(error, 'overlap rule relax: eps_lub = '//to_str(eps_lub, '(es12.4)')// &
        ' out of range '//eps_lub_range_text())
      return
    end if
    if (.not. (overlap_time > 0.0_wp)) then
      call fatal_error(error, 'overlap rule relax: overlap_time = '//to_str(overlap_time, '(es12.4)')// &
        ' (must be > 0)')
      return
    end if
    allocate (rule, source=overlap_relax_t(target=1.0_wp + eps_lub, time=overlap_time))
  end subroutine relax_rule

  subroutine pair_configuration(this, r, pairs, rh, moved, error)
    class(overlap_pair_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    type(pair_geometry_t), intent(in) :: pairs
    real(wp), intent(inout) :: rh(:, :)
    logical, intent(out) :: moved
    type(error_t), allocatable, intent(out) :: error
    moved = .false.
  end subroutine pair_configuration

  !> Rounds of: find the pairs of rh closer than target + margin (cell list), then sweep over
  !> them moving the beads of each overlapping one apart (Gauss-Seidel, in the pair list's order,
  !> so the result is deterministic) until none overlaps; a round that finds no overlap ends it.
  subroutine separate_configuration(this, r, pairs, rh, moved, error)
    class(overlap_separate_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    type(pair_geometry_t), intent(in) :: pairs
    real(wp), intent(inout) :: rh(:, :)
    logical, intent(out) :: moved
    type(error_t), allocatable, intent(out) :: error
    integer :: round, sweep, k, i, j
    real(wp) :: d(3), dist, shift, worst, limit

    moved = .false.
    limit = this%target - slack
    ! the usual case: the caller's list of r shows no overlap, nothing to do
    if (pairs%covers(r, this%target)) then
      if (count_overlaps(pairs, limit) == 0) return
    end if
    rh = r
    do round = 1, max_rounds
      call this%work%build(rh, this%target + margin)
      if (count_overlaps(this%work, limit) == 0) return
      moved = .true.
      do sweep = 1, max_sweeps
        worst = 0.0_wp
        do k = 1, this%work%size()
          call this%work%pair(k, i, j)
          d = rh(:, j) - rh(:, i)
          dist = norm2(d)
          if (dist >= limit) cycle
          if (.not. dist > 0.0_wp) then
            call fatal_error(error, 'overlap rule separate: beads '//to_str(i)//' and '// &
              to_str(j)//' coincide, their line of centres is undefined')
            return
          end if
          shift = 0.5_wp*(this%target - dist)/dist
          rh(:, i) = rh(:, i) - shift*d
          rh(:, j) = rh(:, j) + shift*d
          worst = max(worst, this%target - dist)
        end do
        if (worst == 0.0_wp) exit
      end do
    end do
    call fatal_error(error, 'overlap rule separate: the overlaps could not be removed in '// &
      to_str(max_rounds)//' rounds of '//to_str(max_sweeps)//' sweeps')
  end subroutine separate_configuration

  !> v(3, N) += the kinematic contact velocity for beads at r; rh and `moved` as
  !> hydro_configuration returned them for r. The default rules have none.
  subroutine no_contact_velocity(this, r, rh, moved, v)
    class(overlap_rule_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :), rh(:, :)
    logical, intent(in) :: moved
    real(wp), intent(inout) :: v(:, :)
    associate (unused_this => this, unused_r => r, unused_rh => rh, unused_moved => moved, unused_v => v)
    end associate
  end subroutine no_contact_velocity

  !> 'relax': while beads overlap (moved), v += (rh - r)/time.
  subroutine relax_contact_velocity(this, r, rh, moved, v)
    class(overlap_relax_t), intent(in) :: this
    real(wp), intent(in) :: r(:, :), rh(:, :)
    logical, intent(in) :: moved
    real(wp), intent(inout) :: v(:, :)
    if (moved) v = v + (rh - r)/this%time
  end subroutine relax_contact_velocity

  !> Pairs of the list closer than `limit`.
  integer function count_overlaps(pairs, limit) result(m)
    type(pair_geometry_t), intent(in) :: pairs
    real(wp), intent(in) :: limit
    integer :: k
    m = 0
    do k = 1, pairs%size()
      if (pairs%distance(k) < limit) m = m + 1
    end do
  end function count_overlaps

end module kf_overlap_rule
