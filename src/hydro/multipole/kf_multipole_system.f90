!> The N-sphere multipole system (MULTIPOLE.md sections 7-11) for equal spheres of diameter 1,
!> in the real scaled form. Structure used:
!> * the p-moments of different spheres do not interact (no p<-p translation) and their scaled
!>   self block is the identity, and they couple only to phi-moments: they are eliminated
!>   first, exactly, by one product K_phiphi -= B B^T (B = the phi<-p couplings, DSYRK/DGEMM);
!> * the remaining (phi, chi) system K is factorised by one dense Cholesky with the
!>   force/torque moments (set P) ordered last: the trailing factor L_PP satisfies
!>   L_PP L_PP^T = the Schur complement onto P (the grand mobility in moment form), and L_PQ,
!>   L_QQ give the shear disturbance of free spheres by one triangular solve and one product.
!> Global order of K: [phi n>=2 (all spheres), chi n>=2, phi n=1, chi n=1].
!>
!> Results are in project units (PHYSICS.md section 1): an isolated sphere has translational
!> mobility 1/3 and rotational mobility 1; Cartesian ordering per sphere [U(3), Omega(3)].
!>
!> Overlapping spheres: with min_distance > 0 (the clamp of the overlap rules 'pair', 'separate'
!> and 'relax', min_distance = 1 + eps_lub) the pair blocks of a pair with centre distance
!> r < min_distance are evaluated at r = min_distance along the line of centres (the plain system
!> is not positive definite for deeply overlapping spheres); this is the distance at which
!> kf_lubrication's clamp evaluates that pair's correction, so the pair part of the corrected
!> friction is continuous. With min_distance <= 0 (the literal BWE rule, 'bwe') nothing is
!> clamped: the system of the real positions, whose loss of positive definiteness is reported.
!>
!> Single-precision copy (init's `single_copy`): `factorise` also keeps the factor's lower
!> triangle in single precision, packed by columns (half the bytes of the double lower triangle),
!> for the approximate triangular solves `forward_single` ... `backward_p_single` (single
!> arithmetic, BLAS stpsv) of a preconditioner; the exact solves keep the double factor.
!>
!> Single-precision products (`apply_single`, after `copy_products_single` or an `assemble` with
!> `single`, which converts each sphere's columns right after writing them, from cache; or with
!> `only_single`, which writes K0's columns in single alone, each through a double column in
!> cache, so `apply` is not available until the next assemble without it):
!> the single copies of K0's lower triangle (full storage, nr^2 4 bytes, the upper part not
!> touched) and of B (its size in 4 bytes) give y = K x in single arithmetic (BLAS ssymv and
!> sgemv, x rounded to single, y returned in double) from half the bytes of `apply`. Each
!> entry of K0 and B is rounded once (relative u = 2^-24) and the sums accumulate in single,
!> so |y_single - K x| <= (nr + 3) u (|K0| |x| + |B| |B^T| |x|) + O(u^2) componentwise (nr the
!> longest sum; Higham, Accuracy and Stability of Numerical Algorithms, section 3.5).
!> kf_hydro_multipole_iterative uses them inside its Krylov loop only where its rule bounds
!> their effect on the solution (its header).
module kf_multipole_system
  use kf_kinds, only: wp, sp
  use kf_strings, only: to_str
  use kf_blas, only: dpotrf, dpotri, dtrsm, dtrsv, stpsv, dgemm, dsyrk, dgemv, dsymv, sgemv, ssymv
  use kf_lapack, only: symmetric_eigenvalues
  use kf_constants, only: pi
  use kf_error, only: error_t, fatal_error
  use kf_multipole_blocks, only: multipole_layout_t, pair_entries, fam_phi, fam_p
  use kf_multipole_index, only: multipole_index_t
  use kf_strain_basis, only: strain_basis, strain_coefficients
  implicit none
  private

  !> The highest truncation order L the system takes (the scene allows less: kf_scene_hydro).
  integer, parameter, public :: max_multipole_order = 20
  !> Pairs per chunk in `assemble`: their entries are computed at once (loops over the chunk
  !> innermost, whole cache lines of the owner's table).
  integer, parameter :: assembly_chunk = 16
  !> Columns of B per panel in `apply` (a panel of 16 N rows: 200 kB at N = 99, L = 2).
  integer, parameter :: apply_panel = 32

  !> The factorised N-sphere system.
  !> Work arrays and sizes are private; `n_clamped` and `seconds` report on the last factorise.
  type, public :: multipole_system_t
    private
    type(multipole_layout_t) :: lay
    type(multipole_index_t) :: idx   !< where the unknowns sit in K, B and P
    real(wp) :: min_distance = 1.0_wp   !< pairs with |d| < min_distance are evaluated there
    logical :: single_copy = .false.    !< factorise keeps k32 (module header)
    integer :: n = 0        !< number of spheres
    integer :: nr = 0       !< size of K (phi and chi unknowns), 2 N L(L+2)
    integer :: nqt = 0      !< unknowns of K outside P (they come first)
    integer :: n6 = 0       !< 6N
    integer, public :: n_clamped = 0 !< pairs closer than min_distance at the last factorise
    integer, public :: n_overlapping = 0 !< pairs at r <= 1 at the last factorise (clamped or not)
    real(wp) :: scal(6) = 0.0_wp !< moment_hat = scal(c) * Cartesian force/torque component c
    real(wp), allocatable :: k(:, :)     !< K, then its Cholesky factor (lower triangle)
    real(sp), allocatable :: k32(:)      !< the factor in single precision, packed by columns
    real(sp), allocatable :: k0s(:, :)   !< K0's lower triangle in single (copy_products_single)
    real(sp), allocatable :: bps(:, :)   !< B in single (copy_products_single)
    real(sp), allocatable :: xw(:), yw(:), tw(:) !< single work of apply_single
    logical :: single_current = .false. !< k0s and bps hold the last assembly's K0 and B
    logical :: double_current = .false. !< k and bp hold the last assembly's K0 and B (`apply`)
    real(wp), allocatable :: bp(:, :)    !< phi <- p couplings (rows phi, columns p)
    real(wp), allocatable :: w6(:, :)    !< 6N x 6N work
    real(wp), allocatable :: bq(:, :)    !< nqt x 5 work
    real(wp), allocatable :: d6(:, :)    !< 6N x 5 work
    !> Seconds spent in the last assembly of the pair blocks and in the factorisation
    !> (p-moment elimination and Cholesky).
    real(wp) :: t_assembly = 0.0_wp, t_factor = 0.0_wp
    !> Element G(p, q) (grouped local row p, column q) of a pair block is elem_sgn(p, q) times
    !> entry elem_src(p, q) of `pair_entries` (0: no terms, zero in every block).
    integer, allocatable :: elem_src(:, :)
    real(wp), allocatable :: elem_sgn(:, :)
  contains
    procedure :: init => system_init
    procedure :: assemble => system_assemble
    procedure :: factorise => system_factorise
    procedure :: spectrum => system_spectrum
    procedure :: apply => system_apply
    procedure :: copy_products_single => system_copy_products_single
    procedure :: apply_single => system_apply_single
    procedure :: has_single_products => system_has_single_products
    procedure :: has_double_products => system_has_double_products
    procedure :: forward => system_forward
    procedure :: backward => system_backward
    procedure :: forward_p => system_forward_p
    procedure :: backward_p => system_backward_p
    procedure :: forward_single => system_forward_single
    procedure :: backward_single => system_backward_single
    procedure :: forward_p_single => system_forward_p_single
    procedure :: backward_p_single => system_backward_p_single
    procedure :: unknowns => system_unknowns
    procedure :: p_row => system_p_row
    procedure :: moment_scale => system_moment_scale
    procedure :: add_strain_rhs => system_add_strain_rhs
    procedure :: grand_mobility => system_grand_mobility
    procedure :: translational_mobility => system_translational_mobility
    procedure :: grand_friction => system_grand_friction
    procedure :: strain_disturbance => system_strain_disturbance
    procedure :: friction_coupling => system_friction_coupling
    procedure :: pindex => system_pindex
    procedure :: seconds => system_seconds
  end type multipole_system_t

contains

  !> Truncation order L (1..max_multipole_order) and the distance min_distance (1 + eps_lub) at which closer
  !> (overlapping) pairs are evaluated; min_distance <= 0 disables the overlap treatment.
  !> `single_copy` (default .false.): factorise keeps the single-precision copy of the factor
  !> (module header).
  subroutine system_init(this, order, min_distance, error, single_copy)
    class(multipole_system_t), intent(inout) :: this
    integer, intent(in) :: order
    real(wp), intent(in) :: min_distance
    type(error_t), allocatable, intent(out) :: error
    logical, intent(in), optional :: single_copy
    integer :: c, s

    if (order < 1 .or. order > max_multipole_order) then
      call fatal_error(error, 'multipole order L = '//to_str(order)//' not allowed (1 <= L <= '// &
                       to_str(max_multipole_order)//')')
      return
    end if
    call this%lay%init(order)
    call build_elements(this)
    this%min_distance = min_distance
    this%single_copy = .false.
    if (present(single_copy)) this%single_copy = single_copy
    this%n = 0
    associate (lay => this%lay)
      do s = 0, 1
        c = 3*s
        this%scal(c + 1) = -1.0_wp/(sqrt(2.0_wp)*lay%sigma_real(lay%index(1, s, 1)))
        this%scal(c + 2) = 1.0_wp/(sqrt(2.0_wp)*lay%sigma_real(lay%index(1, s, 2)))
        this%scal(c + 3) = 1.0_wp/lay%sigma_real(lay%index(1, s, 0))
      end do
    end associate
  end subroutine system_init

  !> Index in P (1..6N) of Cartesian component c (1..3 force, 4..6 torque) of sphere i.
  pure integer function system_pindex(this, i, c) result(p)
    class(multipole_system_t), intent(in) :: this
    integer, intent(in) :: i, c
    p = this%idx%p_index(i, c)
  end function system_pindex

  !> The eigenvalues w (ascending) of the matrix that factorise(r) factorises (the scaled real
  !> system after the p-moment elimination; positive definite exactly when its Cholesky
  !> factorisation succeeds). Leaves the system unfactorised. For diagnostics.
  subroutine system_spectrum(this, r, w, error)
    class(multipole_system_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    real(wp), allocatable, intent(out) :: w(:)
    type(error_t), allocatable, intent(out) :: error
    call system_factorise(this, r, error, w)
  end subroutine system_spectrum

  !> Assemble the scaled real system for centres r(3, N) without factorising: the (phi, chi)
  !> block K0 (lower triangle) and the phi <- p couplings B, so that K = K0 - B B^T (`apply`).
  !> `single` (optional, default .false.): also the single copies of `copy_products_single`,
  !> each sphere's columns converted right after they are written (from cache). `only_single`
  !> (optional, default .false.): K0 in single alone (the copies; B in double and single), no
  !> double K0, so `apply` is not available (`has_double_products`) until the next assembly
  !> without it.
  subroutine system_assemble(this, r, error, single, only_single)
    class(multipole_system_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    logical, intent(in), optional :: single, only_single
    integer :: nsph, h, i, x, yr, n, q, t, s, t0, nt, pc, n_over, n_clamp
    integer :: lo(5), hi(5), ks(4), bs(4), ps
    integer, allocatable :: first_coincident(:)
    integer(8) :: c0, c1, crate
    real(wp) :: d(3), dist, dd(3, assembly_chunk)
    real(wp), allocatable :: yw(:, :), vt(:, :), wcol(:)
    logical :: conv, alone

    nsph = size(r, 2)
    if (nsph < 1) then
      call fatal_error(error, 'multipole system: no spheres')
      return
    end if
    if (this%lay%order < 1) then
      call fatal_error(error, 'multipole system: init was not called')
      return
    end if
    call system_clock(c0, crate)
    h = this%lay%h
    if (nsph /= this%n .or. .not. allocated(this%k)) then
      this%n = nsph
      call this%idx%init(h, nsph)
      this%nr = this%idx%nr()
      this%nqt = this%idx%nqt()
      this%n6 = this%idx%n6()
      if (allocated(this%k)) deallocate (this%k, this%bp, this%w6, this%bq, this%d6)
      allocate (this%k(this%nr, this%nr), this%bp(this%idx%b_rows(), this%idx%p_unknowns()), &
                this%w6(this%n6, this%n6))
      allocate (this%bq(max(1, this%nqt), 5), this%d6(this%n6, 5))
    end if
    conv = .false.
    if (present(single)) conv = single
    alone = .false.
    if (present(only_single)) alone = only_single
    conv = conv .or. alone
    this%single_current = .false.
    this%double_current = .false.
    if (conv) call allocate_single(this)
    associate (idx => this%idx)
      lo = idx%lo
      hi = idx%hi

      allocate (first_coincident(nsph))
      do i = 1, nsph
        call starts(i, ks, bs, ps)
        do x = 1, 4
          do yr = x, 4
            this%k(ks(yr):ks(yr) + hi(yr) - lo(yr), ks(x):ks(x) + hi(x) - lo(x)) = 0.0_wp
          end do
        end do
        do t = 1, 2*h
          pc = idx%k_row(t, i)
          this%k(pc, pc) = 1.0_wp
        end do
        this%bp(bs(1):bs(1) + hi(1) - lo(1), ps:ps + h - 1) = 0.0_wp
        this%bp(bs(3):bs(3) + 2, ps:ps + h - 1) = 0.0_wp
        do n = 1, this%lay%order
          do q = 0, 2*n
            t = this%lay%grp(this%lay%index(n, fam_phi, q))
            pc = this%lay%grp(this%lay%index(n, fam_p, q))
            this%bp(idx%b_row(t, i), ps + pc - lo(5)) = -this%lay%cn(n)
          end do
        end do
      end do

      ! The pair blocks, by the sphere s that owns the columns: the columns of s in the lower
      ! triangle of K (rows of the spheres t > s in its runs, and of every t /= s in the later
      ! runs) and its p columns of B (phi rows of every t /= s) are written whole, each column
      ! from top to bottom, by one thread; the entries of every pair (s, t) are computed first
      ! (`pair_entries` of the pair (min(s,t), max(s,t)), so twice per pair: once for each
      ! owner) into vt(t, :). K and B are the same, bit for bit, for any number of OpenMP
      ! threads (kf_blas_threads sets the count); the counters are integer sums over t > s.
      n_over = 0
      n_clamp = 0
      first_coincident = 0
      !$omp parallel default(none) shared(this, r, nsph, first_coincident, conv, alone) &
      !$omp private(s, t, t0, nt, d, dist, dd, yw, vt, wcol) reduction(+:n_over, n_clamp)
      allocate (yw(assembly_chunk, 2*this%lay%nslot), vt(nsph, 0:this%lay%nhalf), wcol(this%nr))
      vt(:, 0) = 0.0_wp
      !$omp do schedule(dynamic)
      do s = 1, nsph
        ! the spheres t by chunks, the entries of a chunk's pairs at once (t = s, not read, and
        ! coincident spheres, an error below: a stand-in displacement)
        do t0 = 1, nsph, assembly_chunk
          nt = min(assembly_chunk, nsph - t0 + 1)
          do t = t0, t0 + nt - 1
            dd(:, t - t0 + 1) = [0.0_wp, 0.0_wp, 1.0_wp]
            if (t == s) cycle
            ! the pair (i, j) = (min(s, t), max(s, t)): receiver j (rows), source i (columns)
            if (t > s) then
              d = r(:, t) - r(:, s)
            else
              d = r(:, s) - r(:, t)
            end if
            dist = norm2(d)
            if (dist <= 0.0_wp) then
              if (t > s .and. first_coincident(s) == 0) first_coincident(s) = t
              cycle
            end if
            if (t > s .and. dist <= 1.0_wp) n_over = n_over + 1
            if (dist < this%min_distance) then
              d = d*(this%min_distance/dist)
              if (t > s) n_clamp = n_clamp + 1
            end if
            dd(:, t - t0 + 1) = d
          end do
          call pair_entries(this%lay, nt, dd, yw, vt(t0:t0 + nt - 1, 1:))
        end do
        if (alone) then
          call write_columns(s, vt, wcol)
          call single_columns(this, s, only_b=.true.)
        else
          call write_columns(s, vt)
          if (conv) call single_columns(this, s)
        end if
      end do
      !$omp end do
      deallocate (yw, vt, wcol)
      !$omp end parallel
      this%n_overlapping = n_over
      this%n_clamped = n_clamp
      do i = 1, nsph
        if (first_coincident(i) > 0) then
          call fatal_error(error, 'multipole system: spheres '//to_str(i)//' and '// &
                           to_str(first_coincident(i))//' coincide')
          this%n = 0
          return
        end if
      end do
    end associate
    this%single_current = conv
    this%double_current = .not. alone
    call system_clock(c1)
    this%t_assembly = real(c1 - c0, wp)/real(crate, wp)

  contains

    !> The columns of sphere so in K (lower triangle, its own diagonal blocks excepted) and
    !> in B from the entries vt(t, :) of the pairs (so, t). Row t of a run holds element
    !> G(row of t, column of so) of the block with receiver t and source so: for t > so the
    !> pair's element (row, column), for t < so (the pair (t, so)) its element (column, row).
    !> With `wcol` (`only_single`): K0's columns in single alone (k0s, from the diagonal down),
    !> each written first into the double column wcol (in cache; the runs fill every row but
    !> those of its own sphere, set to the self block's zero and diagonal 1), then rounded.
    subroutine write_columns(so, vt, wcol)
      integer, intent(in) :: so
      real(wp), intent(in) :: vt(:, 0:)
      real(wp), intent(inout), optional :: wcol(:)
      integer :: rc, rr, b, c, col
      associate (idx => this%idx)
        do rc = 1, 4
          do b = 0, idx%hi(rc) - idx%lo(rc)
            c = idx%lo(rc) + b
            col = idx%k_start(rc, so) + b
            if (present(wcol)) then
              ! the runs write every row from col down but those of so itself: zero them
              do rr = rc, 4
                wcol(max(col, idx%k_start(rr, so)):idx%k_start(rr, so) + idx%hi(rr) - idx%lo(rr)) = 0.0_wp
                call write_run(so, vt, wcol, idx%k_start(rr, 1), rr, c, rr /= rc)
              end do
              wcol(col) = 1.0_wp
              this%k0s(col:, col) = real(wcol(col:), sp)
            else
              do rr = rc, 4
                call write_run(so, vt, this%k(:, col), idx%k_start(rr, 1), rr, c, rr /= rc)
              end do
            end if
          end do
        end do
        do b = 0, h - 1
          c = idx%lo(5) + b
          do rr = 1, 3, 2
            call write_run(so, vt, this%bp(:, idx%p_start(so) + b), idx%b_start(rr, 1), rr, c, .true.)
          end do
        end do
      end associate
    end subroutine write_columns

    !> Into column dst, the run of group rr (rows k0 + ln (t - 1) + a, a = 0..ln-1) of every
    !> sphere t > so from element (row, c) of the pair entries vt(t, :) of (so, t), and with
    !> `below` also of every t < so from element (c, row) of those of (t, so).
    subroutine write_run(so, vt, dst, k0, rr, c, below)
      integer, intent(in) :: so
      real(wp), intent(in) :: vt(:, 0:)
      real(wp), intent(inout) :: dst(:)
      integer, intent(in) :: k0, rr, c
      logical, intent(in) :: below
      integer :: ln, a, g, e, tt
      real(wp) :: sg
      ln = this%idx%hi(rr) - this%idx%lo(rr) + 1
      do a = 0, ln - 1
        g = this%idx%lo(rr) + a
        e = this%elem_src(g, c)
        sg = this%elem_sgn(g, c)
        do tt = so + 1, nsph
          dst(k0 + ln*(tt - 1) + a) = sg*vt(tt, e)
        end do
        if (.not. below) cycle
        e = this%elem_src(c, g)
        sg = this%elem_sgn(c, g)
        do tt = 1, so - 1
          dst(k0 + ln*(tt - 1) + a) = sg*vt(tt, e)
        end do
      end do
    end subroutine write_run

    !> Starts of the runs of sphere s in K (ksv), in the rows of B (bsv) and its p column (psv).
    pure subroutine starts(s, ksv, bsv, psv)
      integer, intent(in) :: s
      integer, intent(out) :: ksv(4), bsv(4), psv
      integer :: rr
      do rr = 1, 4
        ksv(rr) = this%idx%k_start(rr, s)
      end do
      bsv = 0
      bsv(1) = this%idx%b_start(1, s)
      bsv(3) = this%idx%b_start(3, s)
      psv = this%idx%p_start(s)
    end subroutine starts

  end subroutine system_assemble

  !> elem_src, elem_sgn (type components) from the layout's entries and mirrors.
  subroutine build_elements(this)
    class(multipole_system_t), intent(inout) :: this
    integer :: u, m
    associate (lay => this%lay)
      if (allocated(this%elem_src)) deallocate (this%elem_src, this%elem_sgn)
      allocate (this%elem_src(lay%nb, lay%nb), this%elem_sgn(lay%nb, lay%nb))
      this%elem_src = 0
      this%elem_sgn = 1.0_wp
      do u = 1, lay%nhalf
        this%elem_src(lay%fast_row(u), lay%fast_col(u)) = u
      end do
      do m = 1, lay%nmirror
        u = lay%fast_mirror(m)
        this%elem_src(lay%fast_col(u), lay%fast_row(u)) = u
        this%elem_sgn(lay%fast_col(u), lay%fast_row(u)) = lay%fast_msign(m)
      end do
    end associate
  end subroutine build_elements

  !> Assemble the scaled real system for centres r(3, N), eliminate the p-moments and
  !> factorise (Cholesky), with the single-precision copy when init asked for it; with
  !> `spectrum`: its eigenvalues instead of the factorisation.
  subroutine system_factorise(this, r, error, spectrum)
    class(multipole_system_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable, intent(out), optional :: spectrum(:)
    integer :: info, na, nc, nphi, np, b3, k3
    integer(8) :: c1, c2, crate

    call this%assemble(r, error)
    if (allocated(error)) return
    this%double_current = .false.   ! K0 becomes the eliminated system and its factor
    call system_clock(c1, crate)
    ! The offsets are the index map's (kf_multipole_index): rows of B in run 1 (na, from row 1
    ! of K) and in run 3 (nc, from row b3 of B and row k3 of K), all rows and columns of B.
    na = this%idx%b_run_rows(1)
    nc = this%idx%b_run_rows(3)
    nphi = this%idx%b_rows()
    np = this%idx%p_unknowns()
    b3 = this%idx%b_start(3, 1)
    k3 = this%idx%k_start(3, 1)
    ! Exact elimination of the p-moments (their block is the identity): K_phiphi -= B B^T.
    if (na > 0) then
      call dsyrk('L', 'N', na, np, -1.0_wp, this%bp, nphi, 1.0_wp, this%k, this%nr)
      call dgemm('N', 'T', nc, na, np, -1.0_wp, this%bp(b3, 1), nphi, this%bp, nphi, 1.0_wp, &
                 this%k(k3, 1), this%nr)
    end if
    call dsyrk('L', 'N', nc, np, -1.0_wp, this%bp(b3, 1), nphi, 1.0_wp, this%k(k3, k3), this%nr)

    if (present(spectrum)) then
      allocate (spectrum(this%nr))
      call symmetric_eigenvalues(this%k, spectrum, error, 'multipole system')
      this%n = 0
      return
    end if
    call dpotrf('L', this%nr, this%k, this%nr, info)
    if (info == 0 .and. this%single_copy) call copy_single(this)
    call system_clock(c2)
    this%t_factor = real(c2 - c1, wp)/real(crate, wp)
    if (info /= 0) then
      if (info > 0) then
        if (this%min_distance > 0.0_wp) then
          ! with the clamp: the message of the rules 'pair', 'separate' and 'relax', unchanged
          call fatal_error(error, 'Cholesky factorisation of the multipole system failed: matrix not '// &
                           'positive definite (leading minor '//to_str(info)//'); '//to_str(this%n_clamped)// &
                           ' overlapping pairs (mutually overlapping spheres are not supported)')
        else
          call fatal_error(error, 'Cholesky factorisation of the multipole system failed: matrix not '// &
                           'positive definite (leading minor '//to_str(info)//'); '//to_str(this%n_overlapping)// &
                           ' overlapping pairs (r <= 1), none clamped: the many-body system of the real '// &
                           'positions is not positive definite there')
        end if
      else
        call fatal_error(error, 'dpotrf: illegal argument '//to_str(info)//' for the multipole system')
      end if
      this%n = 0
    end if
  end subroutine system_factorise

  !> y = K x for the assembled, not factorised system (after `assemble` without `only_single`:
  !> `has_double_products`): K0 x - B (B^T x),
  !> the p-moments eliminated by products instead of the dense update of `factorise`.
  !> x, y: the nr unknowns of K (`unknowns`), in its global order.
  subroutine system_apply(this, x, y)
    class(multipole_system_t), intent(inout) :: this
    real(wp), intent(in), contiguous :: x(:)
    real(wp), intent(out), contiguous :: y(:)
    integer :: na, nc, nphi, np, cs, c0, w
    real(wp) :: t(this%lay%h*this%n)
    na = (this%lay%h - 3)*this%n
    nc = 3*this%n
    nphi = this%lay%h*this%n
    np = nphi
    cs = 2*na + 1
    call dsymv('L', this%nr, 1.0_wp, this%k, this%nr, x, 1, 0.0_wp, y, 1)
    ! t = B^T x_phi; y_phi -= B t (rows of B: run 1 of K, then run 3 from cs), by panels of
    ! apply_panel columns of B: a panel's part of t needs only its own columns, so each panel
    ! is read from memory once and again from cache for its share of B t.
    do c0 = 1, np, apply_panel
      w = min(apply_panel, np - c0 + 1)
      call dgemv('T', nc, w, 1.0_wp, this%bp(na + 1, c0), nphi, x(cs:), 1, 0.0_wp, t(c0), 1)
      if (na > 0) call dgemv('T', na, w, 1.0_wp, this%bp(1, c0), nphi, x, 1, 1.0_wp, t(c0), 1)
      call dgemv('N', nc, w, -1.0_wp, this%bp(na + 1, c0), nphi, t(c0), 1, 1.0_wp, y(cs:), 1)
      if (na > 0) call dgemv('N', na, w, -1.0_wp, this%bp(1, c0), nphi, t(c0), 1, 1.0_wp, y, 1)
    end do
  end subroutine system_apply

  !> The single-precision copies of K0 (lower triangle) and B of the last `assemble` for
  !> `apply_single` (module header); to be called after each `assemble` that they should follow
  !> (nothing when the double ones are not held: `has_double_products`).
  subroutine system_copy_products_single(this)
    class(multipole_system_t), intent(inout) :: this
    integer :: so
    if (.not. this%double_current) return
    call allocate_single(this)
    do so = 1, this%n
      call single_columns(this, so)
    end do
    this%single_current = .true.
  end subroutine system_copy_products_single

  !> The columns of sphere so in K0 (lower triangle from the diagonal) and in B, in single
  !> (what the single copies hold; `assemble` calls it per sphere from cache); `only_b`: B's.
  subroutine single_columns(this, so, only_b)
    class(multipole_system_t), intent(inout) :: this
    integer, intent(in) :: so
    logical, intent(in), optional :: only_b
    integer :: rc, b, c, nr
    logical :: k0
    nr = this%nr
    k0 = .true.
    if (present(only_b)) k0 = .not. only_b
    associate (idx => this%idx)
      if (k0) then
        do rc = 1, 4
          do b = 0, idx%hi(rc) - idx%lo(rc)
            c = idx%k_start(rc, so) + b
            this%k0s(c:nr, c) = real(this%k(c:nr, c), sp)
          end do
        end do
      end if
      do b = 0, this%lay%h - 1
        c = idx%p_start(so) + b
        this%bps(:, c) = real(this%bp(:, c), sp)
      end do
    end associate
  end subroutine single_columns

  !> True when the single copies hold the last assembly (assemble with `single`, or
  !> copy_products_single after it).
  pure logical function system_has_single_products(this) result(yes)
    class(multipole_system_t), intent(in) :: this
    yes = this%single_current
  end function system_has_single_products

  !> True when K0 and B of the last assembly are held in double (`apply`): not after an
  !> assemble with `only_single`, nor after a factorisation.
  pure logical function system_has_double_products(this) result(yes)
    class(multipole_system_t), intent(in) :: this
    yes = this%double_current
  end function system_has_double_products

  !> The single copies and work of apply_single, sized for the current system.
  subroutine allocate_single(this)
    class(multipole_system_t), intent(inout) :: this
    integer :: nr
    nr = this%nr
    if (allocated(this%k0s)) then
      if (size(this%k0s, 1) /= nr .or. any(shape(this%bps) /= shape(this%bp))) &
        deallocate (this%k0s, this%bps, this%xw, this%yw, this%tw)
    end if
    if (.not. allocated(this%k0s)) then
      allocate (this%k0s(nr, nr), this%bps(size(this%bp, 1), size(this%bp, 2)), this%xw(nr), this%yw(nr), &
                this%tw(size(this%bp, 2)))
    end if
  end subroutine allocate_single

  !> y = K x as `apply`, in single arithmetic with the copies of `copy_products_single` (x
  !> rounded to single, y returned in double; the error bound in the module header).
  subroutine system_apply_single(this, x, y)
    class(multipole_system_t), intent(inout) :: this
    real(wp), intent(in), contiguous :: x(:)
    real(wp), intent(out), contiguous :: y(:)
    integer :: na, nc, nphi, np, cs, c0, w
    na = (this%lay%h - 3)*this%n
    nc = 3*this%n
    nphi = this%lay%h*this%n
    np = nphi
    cs = 2*na + 1
    this%xw = real(x(1:this%nr), sp)
    call ssymv('L', this%nr, 1.0_sp, this%k0s, this%nr, this%xw, 1, 0.0_sp, this%yw, 1)
    do c0 = 1, np, apply_panel
      w = min(apply_panel, np - c0 + 1)
      call sgemv('T', nc, w, 1.0_sp, this%bps(na + 1, c0), nphi, this%xw(cs:), 1, 0.0_sp, this%tw(c0), 1)
      if (na > 0) call sgemv('T', na, w, 1.0_sp, this%bps(1, c0), nphi, this%xw, 1, 1.0_sp, this%tw(c0), 1)
      call sgemv('N', nc, w, -1.0_sp, this%bps(na + 1, c0), nphi, this%tw(c0), 1, 1.0_sp, this%yw(cs:), 1)
      if (na > 0) call sgemv('N', na, w, -1.0_sp, this%bps(1, c0), nphi, this%tw(c0), 1, 1.0_sp, this%yw, 1)
    end do
    y(1:this%nr) = real(this%yw, wp)
  end subroutine system_apply_single

  !> x = L^-1 x with the Cholesky factor K = L L^T of the last `factorise` (nr unknowns).
  subroutine system_forward(this, x)
    class(multipole_system_t), intent(in) :: this
    real(wp), intent(inout), contiguous :: x(:)
    call dtrsv('L', 'N', 'N', this%nr, this%k, this%nr, x, 1)
  end subroutine system_forward

  !> x = L^-T x (nr unknowns); `forward` then `backward` is `solve`.
  subroutine system_backward(this, x)
    class(multipole_system_t), intent(in) :: this
    real(wp), intent(inout), contiguous :: x(:)
    call dtrsv('L', 'T', 'N', this%nr, this%k, this%nr, x, 1)
  end subroutine system_backward

  !> v = L_PP^-1 v for the 6N unknowns of P (rows p_row - (nr - 6N) of the trailing block):
  !> P comes last, so L^-1 [0; v] = [0; L_PP^-1 v].
  subroutine system_forward_p(this, v)
    class(multipole_system_t), intent(in) :: this
    real(wp), intent(inout), contiguous :: v(:)
    call dtrsv('L', 'N', 'N', this%n6, this%k(this%nqt + 1, this%nqt + 1), this%nr, v, 1)
  end subroutine system_forward_p

  !> v = L_PP^-T v: the P part of L^-T x is L_PP^-T x_P, so (K^-1 g)_P = L_PP^-T (L^-1 g)_P.
  subroutine system_backward_p(this, v)
    class(multipole_system_t), intent(in) :: this
    real(wp), intent(inout), contiguous :: v(:)
    call dtrsv('L', 'T', 'N', this%n6, this%k(this%nqt + 1, this%nqt + 1), this%nr, v, 1)
  end subroutine system_backward_p

  !> k32 = the factor's lower triangle in single precision, packed by columns.
  subroutine copy_single(this)
    class(multipole_system_t), intent(inout) :: this
    integer :: j, off, nr
    nr = this%nr
    if (allocated(this%k32)) then
      if (size(this%k32) /= nr*(nr + 1)/2) deallocate (this%k32)
    end if
    if (.not. allocated(this%k32)) allocate (this%k32(nr*(nr + 1)/2))
    off = 0
    do j = 1, nr
      this%k32(off + 1:off + nr - j + 1) = real(this%k(j:nr, j), sp)
      off = off + nr - j + 1
    end do
  end subroutine copy_single

  !> Position in k32 of the diagonal element of column j: the columns before hold
  !> nr + (nr - 1) + ... + (nr - j + 2) values.
  pure integer function packed_start(this, j) result(p)
    class(multipole_system_t), intent(in) :: this
    integer, intent(in) :: j
    p = (j - 1)*(this%nr + 1) - ((j - 1)*j)/2 + 1
  end function packed_start

  !> `forward` in single precision with the copy of the factor (init's `single_copy`).
  subroutine system_forward_single(this, x)
    class(multipole_system_t), intent(in) :: this
    real(sp), intent(inout), contiguous :: x(:)
    call stpsv('L', 'N', 'N', this%nr, this%k32, x, 1)
  end subroutine system_forward_single

  !> `backward` in single precision with the copy of the factor.
  subroutine system_backward_single(this, x)
    class(multipole_system_t), intent(in) :: this
    real(sp), intent(inout), contiguous :: x(:)
    call stpsv('L', 'T', 'N', this%nr, this%k32, x, 1)
  end subroutine system_backward_single

  !> `forward_p` in single precision: the trailing columns of a packed lower triangle are the
  !> packed trailing block, so L_PP starts at the diagonal element of column nqt + 1.
  subroutine system_forward_p_single(this, v)
    class(multipole_system_t), intent(in) :: this
    real(sp), intent(inout), contiguous :: v(:)
    call stpsv('L', 'N', 'N', this%n6, this%k32(packed_start(this, this%nqt + 1)), v, 1)
  end subroutine system_forward_p_single

  !> `backward_p` in single precision.
  subroutine system_backward_p_single(this, v)
    class(multipole_system_t), intent(in) :: this
    real(sp), intent(inout), contiguous :: v(:)
    call stpsv('L', 'T', 'N', this%n6, this%k32(packed_start(this, this%nqt + 1)), v, 1)
  end subroutine system_backward_p_single

  !> The number nr of (phi, chi) unknowns of K (2 N L(L+2)) at the last assembly.
  pure integer function system_unknowns(this) result(nr)
    class(multipole_system_t), intent(in) :: this
    nr = this%nr
  end function system_unknowns

  !> Row of K (1..nr) of Cartesian component c (1..3 force, 4..6 torque) of sphere i: the P
  !> unknowns come last.
  pure integer function system_p_row(this, i, c) result(k)
    class(multipole_system_t), intent(in) :: this
    integer, intent(in) :: i, c
    k = this%nqt + this%idx%p_index(i, c)
  end function system_p_row

  !> The scale s of Cartesian component c (1..6): a force or torque moment of K is
  !> pi s F_c and the matching velocity unknown U_c / s (project units), so that the grand
  !> mobility is pi s_c s_c' (Schur complement onto P) and the friction its inverse.
  pure real(wp) function system_moment_scale(this, c) result(s)
    class(multipole_system_t), intent(in) :: this
    integer, intent(in) :: c
    s = this%scal(c)
  end function system_moment_scale

  !> v = v + the right-hand side of K on the rows outside P for the ambient strain with the
  !> basis coefficients c(5) (kf_strain_basis): K [m_Q; m_P] = [rhs_Q; U_P / s] gives free
  !> spheres (m_P = 0) the disturbance velocities of `strain_disturbance`.
  subroutine system_add_strain_rhs(this, c, v)
    class(multipole_system_t), intent(in) :: this
    real(wp), intent(in) :: c(5)
    real(wp), intent(inout) :: v(:)
    real(wp) :: y(5, 5)
    integer :: i, q, t, row
    if (this%lay%order < 2) return
    y = strain_coefficients_real()
    do i = 1, this%n
      do q = 0, 4
        t = this%lay%index(2, fam_phi, q)
        row = this%idx%strain_row(i, q)
        v(row) = v(row) - this%lay%sigma_real(t)*dot_product(y(q + 1, :), c)
      end do
    end do
  end subroutine system_add_strain_rhs

  !> Real-form strain coefficients y(q, k) (MULTIPOLE.md section 7) of basis strain k.
  pure function strain_coefficients_real() result(y)
    real(wp) :: y(5, 5), rt2
    rt2 = sqrt(2.0_wp)
    y(:, 1) = [-1.0_wp, 0.0_wp, 0.0_wp, rt2, 0.0_wp]
    y(:, 2) = [-1.0_wp, 0.0_wp, 0.0_wp, -rt2, 0.0_wp]
    y(:, 3) = [0.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, -2.0_wp*rt2]
    y(:, 4) = [0.0_wp, -rt2, 0.0_wp, 0.0_wp, 0.0_wp]
    y(:, 5) = [0.0_wp, 0.0_wp, rt2, 0.0_wp, 0.0_wp]
  end function strain_coefficients_real

  !> Copy L_PP (lower, upper part zeroed) into w6.
  subroutine copy_lpp(this)
    class(multipole_system_t), intent(inout) :: this
    integer :: j
    do j = 1, this%n6
      this%w6(1:j - 1, j) = 0.0_wp
      this%w6(j:this%n6, j) = this%k(this%nqt + j:this%nr, this%nqt + j)
    end do
  end subroutine copy_lpp

  !> The 6N x 6N grand mobility (velocities and angular velocities from applied forces and
  !> torques), project units, ordering [U_1, Omega_1, U_2, ...].
  subroutine system_grand_mobility(this, mob)
    class(multipole_system_t), intent(inout) :: this
    real(wp), intent(out) :: mob(:, :)
    real(wp), allocatable :: s(:, :)
    integer :: i, j, c, cc, n6

    n6 = this%n6
    call copy_lpp(this)
    allocate (s(n6, n6))
    call dsyrk('L', 'N', n6, n6, 1.0_wp, this%w6, n6, 0.0_wp, s, n6)
    do j = 1, n6
      s(j, j + 1:n6) = s(j + 1:n6, j)
    end do
    do j = 1, this%n
      do cc = 1, 6
        do i = 1, this%n
          do c = 1, 6
            mob(6*(i - 1) + c, 6*(j - 1) + cc) = pi*this%scal(c)*this%scal(cc)* &
              s(this%pindex(i, c), this%pindex(j, cc))
          end do
        end do
      end do
    end do
  end subroutine system_grand_mobility

  !> The 3N x 3N translational mobility of torque-free spheres (project units). The force
  !> moments come first in P and L_PP is lower triangular, so mu_tt = L_tt L_tt^T.
  subroutine system_translational_mobility(this, mu)
    class(multipole_system_t), intent(inout) :: this
    real(wp), intent(out) :: mu(:, :)
    integer :: i, j, c, cc, n3
    n3 = 3*this%n
    call copy_lpp(this)
    call dsyrk('L', 'N', n3, n3, 1.0_wp, this%w6, this%n6, 0.0_wp, this%w6(1, n3 + 1), this%n6)
    ! the lower triangle of w6(1:n3, n3+1:2*n3) now holds S_tt
    do j = 1, this%n
      do cc = 1, 3
        do i = 1, this%n
          do c = 1, 3
            mu(3*(i - 1) + c, 3*(j - 1) + cc) = pi*this%scal(c)*this%scal(cc)* &
              stt(this%pindex(i, c), this%pindex(j, cc))
          end do
        end do
      end do
    end do
  contains
    pure real(wp) function stt(p, q)
      integer, intent(in) :: p, q
      stt = this%w6(max(p, q), n3 + min(p, q))
    end function stt
  end subroutine system_translational_mobility

  !> The 6N x 6N generalised friction (inverse of the grand mobility), project units:
  !> [F; T] = zeta [U; Omega] for applied forces and torques in a quiescent fluid.
  subroutine system_grand_friction(this, zeta, error)
    class(multipole_system_t), intent(inout) :: this
    real(wp), intent(out) :: zeta(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer :: i, j, c, cc, n6, info

    n6 = this%n6
    call copy_lpp(this)
    call dpotri('L', n6, this%w6, n6, info)
    if (info /= 0) then
      call fatal_error(error, 'inversion of the multipole grand mobility failed (dpotri info = '// &
                       to_str(info)//')')
      return
    end if
    do j = 1, n6
      this%w6(j, j + 1:n6) = this%w6(j + 1:n6, j)
    end do
    ! a copy with a permutation, O(N^2): the columns of sphere j by one thread (no sums)
    !$omp parallel do default(none) shared(this, zeta) private(i, c, cc) schedule(static)
    do j = 1, this%n
      do cc = 1, 6
        do i = 1, this%n
          do c = 1, 6
            zeta(6*(i - 1) + c, 6*(j - 1) + cc) = this%w6(this%pindex(i, c), &
              this%pindex(j, cc))/(pi*this%scal(c)*this%scal(cc))
          end do
        end do
      end do
    end do
    !$omp end parallel do
  end subroutine system_grand_friction

  !> Disturbance [U - U_inf; Omega - Omega_inf] (6N) of force-free, torque-free spheres for the
  !> five basis strains of `strain_basis` (columns). Zero at L = 1 (no strain coupling).
  !> `gram` (optional): the pairings gram(k, l) = B_k : (sum over the spheres of their
  !> stresslets, Batchelor's sign, when force- and torque-free in the strain B_l), project units
  !> pi eta d^3. With the scaled strain right-hand sides b_l (= sigma c(B_l)) and
  !> K_QQ = L_QQ L_QQ^T, the moments are F_Q = -sigma K_QQ^-1 b_l (MULTIPOLE.md 11), their pairing
  !> with c(B_k) is the fluid's E:S^fl (4.3) and S = -S^fl: gram = (L^-1 b_k).(L^-1 b_l)/pi
  !> (force unit pi eta d^2 with eta = d = 1).
  subroutine system_strain_disturbance(this, dist, gram)
    class(multipole_system_t), intent(inout) :: this
    real(wp), intent(out) :: dist(:, :)
    real(wp), intent(out), optional :: gram(5, 5)
    real(wp) :: y(5, 5)
    integer :: i, k, q, t, c

    dist(1:this%n6, 1:5) = 0.0_wp
    if (present(gram)) gram = 0.0_wp
    if (this%lay%order < 2) return
    y = strain_coefficients_real()
    this%bq = 0.0_wp
    do i = 1, this%n
      do q = 0, 4
        t = this%lay%index(2, fam_phi, q)
        this%bq(this%idx%strain_row(i, q), :) = this%lay%sigma_real(t)*y(q + 1, :)
      end do
    end do
    call dtrsm('L', 'L', 'N', 'N', this%nqt, 5, 1.0_wp, this%k, this%nr, this%bq, this%nqt)
    if (present(gram)) gram = matmul(transpose(this%bq), this%bq)/pi
    call dgemm('N', 'N', this%n6, 5, this%nqt, -1.0_wp, this%k(this%nqt + 1, 1), this%nr, &
               this%bq, this%nqt, 0.0_wp, this%d6, this%n6)
    do k = 1, 5
      do i = 1, this%n
        do c = 1, 6
          dist(6*(i - 1) + c, k) = this%scal(c)*this%d6(this%pindex(i, c), k)
        end do
      end do
    end do
  end subroutine system_strain_disturbance

  !> The many-body friction of the system and its strain coupling (MULTIPOLE.md 13.3), project
  !> units, ordering [U_1, Omega_1, U_2, ...]: zeta (6N x 6N, full storage) = grand friction,
  !> x (6N x 5) = zeta (U - U_inf) of free spheres for the five basis strains, so that
  !> [F; T] = zeta [U - U_inf; Omega - Omega_inf] - x : E.
  subroutine system_friction_coupling(this, zeta, x, error)
    class(multipole_system_t), intent(inout) :: this
    real(wp), intent(out) :: zeta(:, :), x(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: free(:, :)
    integer :: n6
    n6 = this%n6
    call this%grand_friction(zeta, error)
    if (allocated(error)) return
    allocate (free(n6, 5))
    call this%strain_disturbance(free)
    call dgemm('N', 'N', n6, 5, n6, 1.0_wp, zeta, n6, free, n6, 0.0_wp, x, n6)
  end subroutine system_friction_coupling

  !> Seconds spent in the last assembly of the pair blocks and in the last factorisation.
  subroutine system_seconds(this, assembly, factor)
    class(multipole_system_t), intent(in) :: this
    real(wp), intent(out) :: assembly, factor
    assembly = this%t_assembly
    factor = this%t_factor
  end subroutine system_seconds

end module kf_multipole_system
