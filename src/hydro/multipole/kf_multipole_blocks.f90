!> Building blocks of the induced-force multipole method for equal spheres of diameter 1
!> (radius a = 1/2, viscosity 1): the per-sphere layout of the unknowns, the diagonal scaling,
!> the single-sphere operator and the closed-form translation (pair) blocks of MULTIPOLE.md
!> sections 5-7.
!>
!> Per sphere there are 3L(L+2) unknowns: ranks n = 1..L, families phi, chi, p, components
!> q = 0..2n. Local index (1-based) t = 3(n^2-1) + s(2n+1) + q + 1 with s = 0, 1, 2 for
!> phi, chi, p. Complex form: q = m + n. Real form: q = 0 <-> m = 0, q = 2m-1 <-> sqrt2 Re F_m,
!> q = 2m <-> sqrt2 Im F_m. Everything is scaled by sigma (section 5.2) so that the self block is
!> the identity plus -c_n between (phi,n,m) and (p,n,m).
module kf_multipole_blocks
  use kf_kinds, only: wp
  use kf_vector_ops, only: sort_small
  use kf_constants, only: pi
  use kf_solid_harmonics, only: irregular_harmonics_real
  implicit none
  private

  integer, parameter, public :: fam_phi = 0, fam_chi = 1, fam_p = 2
  real(wp), parameter, public :: sphere_radius = 0.5_wp

  !> Layout of the unknowns of one sphere at truncation order L, with scaling and real-form maps.
  type, public :: multipole_layout_t
    integer :: order = 0              !< truncation L
    integer :: nb = 0                 !< unknowns per sphere, 3L(L+2)
    integer, allocatable :: rank_n(:) !< rank n of local index t
    integer, allocatable :: fam(:)    !< family of local index t
    integer, allocatable :: m_of(:)   !< order m of complex local index t
    real(wp), allocatable :: sigma(:) !< scale sigma of complex local index t
    real(wp), allocatable :: sigma_real(:) !< scale sigma of real local index t
    real(wp), allocatable :: cn(:)    !< self coupling c_n, n = 1..L
    integer, allocatable :: widx(:, :)      !< real row p = sum_k wval(k,p) * complex row widx(k,p)
    complex(wp), allocatable :: wval(:, :)
    !> Translation element coefficients (see element_coefficients), nb x nb each.
    complex(wp), allocatable :: c1(:, :), c1d(:, :), c2(:, :)
    integer, allocatable :: k1(:, :), k2(:, :)
    !> Grouped local order [phi n>=2, chi n>=2, phi n=1, chi n=1, p all] of real local index t.
    integer, allocatable :: grp(:)
    integer :: h = 0        !< L(L+2), unknowns per family and sphere
    integer :: nslot = 0    !< real harmonic slots: Re/Im of I_lambda^mu, mu >= 0, lambda <= 2L
    !> Sparse real translation elements in grouped order (column-major element e = p + nb(q-1)):
    !> terms term_ptr(e) .. term_ptr(e+1)-1, value = sum coef * y(slot), y = [x, |d|^2 x].
    integer, allocatable :: term_ptr(:), term_slot(:)
    real(wp), allocatable :: term_coef(:)
    !> The terms evaluated per pair (`pair_entries`): entry u = 1..nhalf is element
    !> (half_row(u), half_col(u)) with terms half_ptr(u) .. half_ptr(u+1)-1 (those of term_ptr,
    !> same order); with half_sign(u) = +-1 the mirror element (half_col(u), half_row(u)) is
    !> half_sign(u) times it (K is symmetric and I_lambda^mu(-d) = (-1)^lambda I_lambda^mu(d),
    !> so the block of -d is the transpose: each entry of the lower triangle gives its mirror).
    integer :: nhalf = 0
    integer, allocatable :: half_row(:), half_col(:), half_ptr(:), half_slot(:)
    real(wp), allocatable :: half_coef(:), half_sign(:)
    !> The same entries as evaluated (`pair_entries`), ordered by their number of terms c
    !> so that each inner sum has a fixed length: entries fast_first(c) .. fast_first(c+1)-1
    !> have c terms each, entry u's terms at fast_tfirst(c) + c (u - fast_first(c)) + 0..c-1
    !> (slots fast_slot, coefficients fast_coef, in the order of half_*); fast_row/fast_col as
    !> half_row/half_col; the entries with a mirror are fast_mirror(1..nmirror), signs fast_msign.
    integer :: nterm_max = 0, nmirror = 0
    integer, allocatable :: fast_first(:), fast_tfirst(:), fast_row(:), fast_col(:), fast_slot(:)
    integer, allocatable :: fast_mirror(:)
    real(wp), allocatable :: fast_coef(:), fast_msign(:)
  contains
    procedure :: init => layout_init
    procedure :: index => layout_index
  end type multipole_layout_t

  public :: pair_block_complex, pair_block_real, pair_entries, z0_inverse

contains

  !> Set up the layout for truncation order L >= 1.
  subroutine layout_init(this, order)
    class(multipole_layout_t), intent(inout) :: this
    integer, intent(in) :: order
    integer :: n, s, q, m, t, tp, tm
    real(wp) :: kappa, lognu, rt2

    this%order = order
    this%nb = 3*order*(order + 2)
    if (allocated(this%rank_n)) deallocate (this%rank_n, this%fam, this%m_of, this%sigma, &
                                            this%sigma_real, this%cn, this%widx, this%wval, &
                                            this%c1, this%c1d, this%c2, this%k1, this%k2, &
                                            this%grp, this%term_ptr, this%term_slot, this%term_coef, &
                                            this%half_row, this%half_col, this%half_ptr, this%half_slot, &
                                            this%half_coef, this%half_sign, this%fast_first, this%fast_tfirst, &
                                            this%fast_row, this%fast_col, this%fast_slot, this%fast_mirror, &
                                            this%fast_coef, this%fast_msign)
    allocate (this%rank_n(this%nb), this%fam(this%nb), this%m_of(this%nb), this%sigma(this%nb))
    allocate (this%sigma_real(this%nb))
    allocate (this%cn(order), this%widx(2, this%nb), this%wval(2, this%nb))
    rt2 = sqrt(2.0_wp)
    do n = 1, order
      this%cn(n) = sqrt(real((2*n - 1)*(2*n + 3), wp))/real(2*n + 1, wp)
      do s = fam_phi, fam_p
        select case (s)
        case (fam_phi)
          kappa = sqrt(16.0_wp*pi*n*(2*n - 1)/real((n + 1)*(2*n + 1), wp))*sphere_radius**(n - 0.5_wp)
        case (fam_chi)
          kappa = sqrt(4.0_wp*pi*n*(n + 1))*sphere_radius**(n + 0.5_wp)
        case default
          kappa = sqrt(4.0_wp*pi*n/real((n + 1)*(2*n + 1)*(2*n + 3), wp))*sphere_radius**(n + 1.5_wp)
        end select
        do q = 0, 2*n
          t = this%index(n, s, q)
          m = q - n
          this%rank_n(t) = n
          this%fam(t) = s
          this%m_of(t) = m
          lognu = log_gamma(real(n + m + 1, wp)) + log_gamma(real(n - m + 1, wp))
          this%sigma(t) = kappa*exp(-0.5_wp*lognu)
        end do
        do q = 0, 2*n
          this%sigma_real(this%index(n, s, q)) = this%sigma(this%index(n, s, n + q/2 + mod(q, 2)))   ! m = ceiling(q/2)
        end do
        ! Real form rows (section 7): x_0 = F_0, x_{2m-1} = (F_m + (-1)^m F_-m)/sqrt2,
        ! x_{2m} = (F_m - (-1)^m F_-m)/(i sqrt2).
        t = this%index(n, s, 0)
        this%widx(:, t) = this%index(n, s, n)
        this%wval(1, t) = (1.0_wp, 0.0_wp)
        this%wval(2, t) = (0.0_wp, 0.0_wp)
        do m = 1, n
          tp = this%index(n, s, n + m)
          tm = this%index(n, s, n - m)
          t = this%index(n, s, 2*m - 1)
          this%widx(:, t) = [tp, tm]
          this%wval(:, t) = [cmplx(1.0_wp/rt2, 0.0_wp, wp), cmplx((-1)**m/rt2, 0.0_wp, wp)]
          t = this%index(n, s, 2*m)
          this%widx(:, t) = [tp, tm]
          this%wval(:, t) = [cmplx(0.0_wp, -1.0_wp/rt2, wp), cmplx(0.0_wp, (-1)**m/rt2, wp)]
        end do
      end do
    end do
    allocate (this%c1(this%nb, this%nb), this%c1d(this%nb, this%nb), this%c2(this%nb, this%nb))
    allocate (this%k1(this%nb, this%nb), this%k2(this%nb, this%nb))
    do tp = 1, this%nb
      do t = 1, this%nb
        call element_coefficients(this, t, tp, this%c1(t, tp), this%c1d(t, tp), this%k1(t, tp), &
                                  this%c2(t, tp), this%k2(t, tp))
      end do
    end do
    call build_grouped(this)
    call build_real_terms(this)
    call build_half_terms(this)
    call build_fast_terms(this)
  end subroutine layout_init

  !> Local (1-based) index of rank n, family s, component q.
  pure integer function layout_index(this, n, s, q) result(t)
    class(multipole_layout_t), intent(in) :: this
    integer, intent(in) :: n, s, q
    t = 3*(n*n - 1) + s*(2*n + 1) + q + 1
  end function layout_index

  !> The grouped local order of the real unknowns of one sphere.
  subroutine build_grouped(this)
    class(multipole_layout_t), intent(inout) :: this
    integer :: n, q, ia, ib, ic, id, ip, t
    this%h = this%order*(this%order + 2)
    allocate (this%grp(this%nb))
    ia = 0
    ib = this%h - 3
    ic = 2*(this%h - 3)
    id = ic + 3
    ip = 2*this%h
    do n = 1, this%order
      do q = 0, 2*n
        t = this%index(n, fam_phi, q)
        if (n == 1) then
          ic = ic + 1
          this%grp(t) = ic
        else
          ia = ia + 1
          this%grp(t) = ia
        end if
        t = this%index(n, fam_chi, q)
        if (n == 1) then
          id = id + 1
          this%grp(t) = id
        else
          ib = ib + 1
          this%grp(t) = ib
        end if
        ip = ip + 1
        this%grp(this%index(n, fam_p, q)) = ip
      end do
    end do
  end subroutine build_grouped

  !> Slot of Re (part = 0) or Im (part = 1) of I_lambda^mu, mu >= 0.
  pure integer function slot_of(lambda, mu, part)
    integer, intent(in) :: lambda, mu, part
    slot_of = 2*(lambda*(lambda + 1)/2 + mu) + part + 1
  end function slot_of

  !> Sparse real-form coefficients of every translation element (grouped order), derived from
  !> the complex coefficients and the unitary map W of section 7:
  !> gr(p, q) = Re sum_{a,b} W(p,a) g(a,b) conj(W(q,b)), I_lambda^-mu = (-1)^mu conj(I_lambda^mu).
  subroutine build_real_terms(this)
    class(multipole_layout_t), intent(inout) :: this
    real(wp), allocatable :: acc(:), coefs(:)
    integer, allocatable :: slots(:), ungrp(:)
    integer :: p, q, gp, gq, ia, ib, a, b, nterm, s, kk, kflat, lambda, mu, off, na, nbb, t
    complex(wp) :: w, z
    real(wp) :: big, sg
    integer :: touched(16), ntouch, it

    this%nslot = 2*((2*this%order + 1)*(2*this%order + 2)/2)
    allocate (acc(2*this%nslot), slots(this%nb*this%nb*16), coefs(this%nb*this%nb*16))
    allocate (this%term_ptr(this%nb*this%nb + 1), ungrp(this%nb))
    do t = 1, this%nb
      ungrp(this%grp(t)) = t
    end do
    nterm = 0
    do gq = 1, this%nb
      q = ungrp(gq)
      nbb = 2
      if (this%widx(1, q) == this%widx(2, q)) nbb = 1
      do gp = 1, this%nb
        p = ungrp(gp)
        na = 2
        if (this%widx(1, p) == this%widx(2, p)) na = 1
        ntouch = 0
        do ib = 1, nbb
          b = this%widx(ib, q)
          do ia = 1, na
            a = this%widx(ia, p)
            w = this%wval(ia, p)*conjg(this%wval(ib, q))
            do kk = 1, 3
              select case (kk)
              case (1)
                z = w*this%c1(a, b)
                kflat = this%k1(a, b)
                off = 0
              case (2)
                z = w*this%c1d(a, b)
                kflat = this%k1(a, b)
                off = this%nslot
              case default
                z = w*this%c2(a, b)
                kflat = this%k2(a, b)
                off = 0
              end select
              if (z == (0.0_wp, 0.0_wp)) cycle
              lambda = modulo(kflat - 1, 2*this%order + 1)
              mu = (kflat - 1)/(2*this%order + 1) - 2*this%order
              s = off + slot_of(lambda, abs(mu), 0)
              if (.not. any(touched(1:ntouch) == s)) then
                ntouch = ntouch + 1
                touched(ntouch) = s
                acc(s) = 0.0_wp
                acc(s + 1) = 0.0_wp
              end if
              if (mu >= 0) then
                acc(s) = acc(s) + real(z, wp)
                acc(s + 1) = acc(s + 1) - aimag(z)
              else
                sg = real(1 - 2*modulo(mu, 2), wp)
                acc(s) = acc(s) + sg*real(z, wp)
                acc(s + 1) = acc(s + 1) + sg*aimag(z)
              end if
            end do
          end do
        end do
        this%term_ptr(gp + this%nb*(gq - 1)) = nterm + 1
        big = 0.0_wp
        do it = 1, ntouch
          big = max(big, abs(acc(touched(it))), abs(acc(touched(it) + 1)))
        end do
        call sort_small(touched(1:ntouch))
        do it = 1, ntouch
          do s = touched(it), touched(it) + 1
            if (abs(acc(s)) > 1.0e-13_wp*big) then
              nterm = nterm + 1
              slots(nterm) = s
              coefs(nterm) = acc(s)
            end if
          end do
        end do
      end do
    end do
    this%term_ptr(this%nb*this%nb + 1) = nterm + 1
    this%term_slot = slots(1:nterm)
    this%term_coef = coefs(1:nterm)
  end subroutine build_real_terms

  !> The entries evaluated per pair (layout components half_*): every element (p, q), p >= q,
  !> of the grouped block with terms, and its mirror (q, p) as +-(p, q) where the mirror's
  !> terms are the same slots with coefficients sign times (p, q)'s (checked to 1e-12 of the
  !> largest, sign from the first term); a mirror that does not match is evaluated on its own.
  subroutine build_half_terms(this)
    class(multipole_layout_t), intent(inout) :: this
    integer :: p, q, e, em, ne, nem, k, u, nt
    real(wp) :: sg, big
    logical :: same
    integer, allocatable :: row(:), col(:), ptr(:), slot(:)
    real(wp), allocatable :: coef(:), mirror(:)

    allocate (row(this%nb*this%nb), col(this%nb*this%nb), mirror(this%nb*this%nb), ptr(this%nb*this%nb + 1))
    allocate (slot(size(this%term_slot)), coef(size(this%term_coef)))
    u = 0
    nt = 0
    do q = 1, this%nb
      do p = q, this%nb
        e = p + this%nb*(q - 1)
        em = q + this%nb*(p - 1)
        ne = this%term_ptr(e + 1) - this%term_ptr(e)
        nem = this%term_ptr(em + 1) - this%term_ptr(em)
        sg = 0.0_wp
        same = .false.
        if (p /= q .and. ne == nem .and. ne > 0) then
          sg = sign(1.0_wp, this%term_coef(this%term_ptr(em))*this%term_coef(this%term_ptr(e)))
          big = maxval(abs(this%term_coef(this%term_ptr(e):this%term_ptr(e + 1) - 1)))
          same = .true.
          do k = 0, ne - 1
            if (this%term_slot(this%term_ptr(e) + k) /= this%term_slot(this%term_ptr(em) + k) .or. &
                abs(this%term_coef(this%term_ptr(em) + k) - sg*this%term_coef(this%term_ptr(e) + k)) > 1.0e-12_wp*big) &
              same = .false.
          end do
        end if
        if (ne > 0) call add(p, q, e, merge(sg, 0.0_wp, same))
        if (p /= q .and. nem > 0 .and. .not. same) call add(q, p, em, 0.0_wp)
      end do
    end do
    ptr(u + 1) = nt + 1
    this%nhalf = u
    this%half_row = row(1:u)
    this%half_col = col(1:u)
    this%half_sign = mirror(1:u)
    this%half_ptr = ptr(1:u + 1)
    this%half_slot = slot(1:nt)
    this%half_coef = coef(1:nt)

  contains

    !> Entry (pr, pc) with the terms of element ee, mirror sign sm (0: none).
    subroutine add(pr, pc, ee, sm)
      integer, intent(in) :: pr, pc, ee
      real(wp), intent(in) :: sm
      integer :: kk
      u = u + 1
      row(u) = pr
      col(u) = pc
      mirror(u) = sm
      ptr(u) = nt + 1
      do kk = this%term_ptr(ee), this%term_ptr(ee + 1) - 1
        nt = nt + 1
        slot(nt) = this%term_slot(kk)
        coef(nt) = this%term_coef(kk)
      end do
    end subroutine add

  end subroutine build_half_terms

  !> The entries half_* reordered by their number of terms (layout components fast_*).
  subroutine build_fast_terms(this)
    class(multipole_layout_t), intent(inout) :: this
    integer :: c, u, e, nt, k
    integer, allocatable :: cnt(:)

    allocate (cnt(this%nhalf))
    do u = 1, this%nhalf
      cnt(u) = this%half_ptr(u + 1) - this%half_ptr(u)
    end do
    this%nterm_max = 0
    if (this%nhalf > 0) this%nterm_max = maxval(cnt)
    allocate (this%fast_first(this%nterm_max + 2), this%fast_tfirst(this%nterm_max + 1))
    allocate (this%fast_row(this%nhalf), this%fast_col(this%nhalf), this%fast_slot(size(this%half_slot)))
    allocate (this%fast_coef(size(this%half_coef)), this%fast_mirror(this%nhalf), this%fast_msign(this%nhalf))
    e = 0
    nt = 0
    this%nmirror = 0
    do c = 1, this%nterm_max + 1
      this%fast_first(c) = e + 1
      if (c > this%nterm_max) exit
      this%fast_tfirst(c) = nt + 1
      do u = 1, this%nhalf
        if (cnt(u) /= c) cycle
        e = e + 1
        this%fast_row(e) = this%half_row(u)
        this%fast_col(e) = this%half_col(u)
        do k = 0, c - 1
          this%fast_slot(nt + k + 1) = this%half_slot(this%half_ptr(u) + k)
          this%fast_coef(nt + k + 1) = this%half_coef(this%half_ptr(u) + k)
        end do
        nt = nt + c
        if (this%half_sign(u) /= 0.0_wp) then
          this%nmirror = this%nmirror + 1
          this%fast_mirror(this%nmirror) = e
          this%fast_msign(this%nmirror) = this%half_sign(u)
        end if
      end do
    end do
    this%fast_first(this%nterm_max + 2) = e + 1
  end subroutine build_fast_terms

  !> The entries of the scaled real translation blocks in grouped order for nd displacements
  !> d(:, i) (receiver - source): v(i, u), u = 1..nhalf, is element (fast_row(u), fast_col(u))
  !> of block i, and for fast_mirror(m) = u its element (fast_col(u), fast_row(u)) is
  !> fast_msign(m) v(i, u); all other elements are zero for every d. y: work (nd, 2*nslot), the
  !> real slots Re, Im of I_lambda^mu(d), mu >= 0, lambda <= 2L, then the same times |d|^2.
  !> The sums go by groups of entries with the same number of terms (fixed-length sums, the
  !> terms in the order of half_*, from zero), the loops over the displacements innermost.
  pure subroutine pair_entries(lay, nd, d, y, v)
    type(multipole_layout_t), intent(in) :: lay
    integer, intent(in) :: nd
    real(wp), intent(in) :: d(3, nd)
    real(wp), intent(out) :: y(nd, 2*lay%nslot)
    real(wp), intent(inout) :: v(:, :)
    integer :: c, u, k, j, i, s
    real(wp) :: acc

    call irregular_harmonics_real(nd, d, 2*lay%order, y)
    do s = 1, lay%nslot
      do i = 1, nd
        y(i, lay%nslot + s) = sum(d(:, i)**2)*y(i, s)
      end do
    end do
    do c = 1, lay%nterm_max
      k = lay%fast_tfirst(c)
      associate (cf => lay%fast_coef, sl => lay%fast_slot)
        select case (c)
        case (1)
          do u = lay%fast_first(c), lay%fast_first(c + 1) - 1
            v(1:nd, u) = cf(k)*y(:, sl(k))
            k = k + 1
          end do
        case (2)
          do u = lay%fast_first(c), lay%fast_first(c + 1) - 1
            v(1:nd, u) = cf(k)*y(:, sl(k)) + cf(k + 1)*y(:, sl(k + 1))
            k = k + 2
          end do
        case (3)
          do u = lay%fast_first(c), lay%fast_first(c + 1) - 1
            v(1:nd, u) = cf(k)*y(:, sl(k)) + cf(k + 1)*y(:, sl(k + 1)) + cf(k + 2)*y(:, sl(k + 2))
            k = k + 3
          end do
        case (4)
          do u = lay%fast_first(c), lay%fast_first(c + 1) - 1
            v(1:nd, u) = cf(k)*y(:, sl(k)) + cf(k + 1)*y(:, sl(k + 1)) + cf(k + 2)*y(:, sl(k + 2)) &
                         + cf(k + 3)*y(:, sl(k + 3))
            k = k + 4
          end do
        case default
          do u = lay%fast_first(c), lay%fast_first(c + 1) - 1
            do i = 1, nd
              acc = 0.0_wp
              do j = 0, c - 1
                acc = acc + cf(k + j)*y(i, sl(k + j))
              end do
              v(i, u) = acc
            end do
            k = k + c
          end do
        end select
      end associate
    end do
  end subroutine pair_entries

  !> Unscaled single-sphere inverse operator Z0^-1 at rank n, order m, radius a (section 5.1):
  !> zinv = [phi-phi, phi-p, p-p, chi-chi].
  pure function z0_inverse(n, m, a) result(zinv)
    integer, intent(in) :: n, m
    real(wp), intent(in) :: a
    real(wp) :: zinv(4)
    real(wp) :: nu
    nu = gamma(real(n + m + 1, wp))*gamma(real(n - m + 1, wp))
    zinv(1) = nu*(n + 1)*(2*n + 1)/(16.0_wp*pi*n*(2*n - 1)*a**(2*n - 1))
    zinv(2) = -nu*(n + 1)*(2*n + 3)/(8.0_wp*pi*n*a**(2*n + 1))
    zinv(3) = nu*(n + 1)*(2*n + 1)*(2*n + 3)/(4.0_wp*pi*n*a**(2*n + 3))
    zinv(4) = nu/(4.0_wp*pi*n*(n + 1)*a**(2*n + 1))
  end function z0_inverse

  !> Coefficients of the scaled complex translation element (row tr <- column tc), section 6.1:
  !> g = (c1 + c1d |d|^2) ih(k1) + c2 ih(k2), with ih the irregular harmonics of d flattened
  !> as (lambda, mu) -> lambda + (mu + 2L)(2L + 1) + 1.
  pure subroutine element_coefficients(lay, tr, tc, c1, c1d, k1, c2, k2)
    type(multipole_layout_t), intent(in) :: lay
    integer, intent(in) :: tr, tc
    complex(wp), intent(out) :: c1, c1d, c2
    integer, intent(out) :: k1, k2
    integer :: k, l, n, m, sr, sc, lam, mu, knl
    real(wp) :: sgn, alam, bq, qq, pref
    real(wp), parameter :: c4pi = 1.0_wp/(4.0_wp*pi)

    n = lay%rank_n(tc)
    m = lay%m_of(tc)
    sc = lay%fam(tc)
    k = lay%rank_n(tr)
    l = lay%m_of(tr)
    sr = lay%fam(tr)
    lam = n + k
    mu = m - l
    knl = n*l + k*m
    sgn = real(1 - 2*modulo(k + l, 2), wp)
    pref = lay%sigma(tr)*lay%sigma(tc)*c4pi*sgn
    c1 = (0.0_wp, 0.0_wp)
    c1d = (0.0_wp, 0.0_wp)
    c2 = (0.0_wp, 0.0_wp)
    k1 = flat(lam)
    k2 = flat(lam - 2)
    select case (3*sr + sc)
    case (3*fam_p + fam_phi, 3*fam_phi + fam_p)
      if (abs(mu) <= lam) c1 = pref
    case (3*fam_chi + fam_chi)
      if (abs(mu) <= lam) c1 = -pref/real((n + 1)*(k + 1), wp)
    case (3*fam_phi + fam_chi)
      k1 = flat(lam - 1)
      if (abs(mu) <= lam - 1) c1 = pref*cmplx(0.0_wp, real(knl, wp), wp)/real(k*n*(n + 1), wp)
    case (3*fam_chi + fam_phi)
      k1 = flat(lam - 1)
      if (abs(mu) <= lam - 1) c1 = pref*cmplx(0.0_wp, real(knl, wp), wp)/real(n*k*(k + 1), wp)
    case (3*fam_phi + fam_phi)
      alam = -1.0_wp/real(2*(2*lam - 1), wp)
      qq = real(2*knl*knl - (m + l)*knl - (lam - 1)*(n*k + l*m), wp)
      bq = -real(n*k - 2*n - 2*k + 1, wp)*qq/real(n*k*(2*n - 1)*(2*k - 1)*(2*lam - 1), wp)
      if (abs(mu) <= lam) c1d = pref*alam
      if (abs(mu) <= lam - 2) c2 = pref*bq
    end select

  contains

    pure integer function flat(lambda)
      integer, intent(in) :: lambda
      if (abs(mu) > lambda) then
        flat = 1
      else
        flat = lambda + (mu + 2*lay%order)*(2*lay%order + 1) + 1
      end if
    end function flat

  end subroutine element_coefficients

  !> Scaled complex translation block g = sigma G sigma (section 6.1) for the displacement
  !> d = R_receiver - R_source; rows: receiver unknowns, columns: source unknowns (complex form).
  !> ihf holds the irregular harmonics I_lambda^mu(d) of shape (0:2L, -2L:2L), passed as a whole.
  pure subroutine pair_block_complex(lay, d, ihf, g)
    type(multipole_layout_t), intent(in) :: lay
    real(wp), intent(in) :: d(3)
    complex(wp), intent(in) :: ihf(*)
    complex(wp), intent(out) :: g(:, :)
    integer :: tr, tc
    real(wp) :: d2

    d2 = sum(d**2)
    do tc = 1, lay%nb
      do tr = 1, lay%nb
        g(tr, tc) = (lay%c1(tr, tc) + lay%c1d(tr, tc)*d2)*ihf(lay%k1(tr, tc)) &
                    + lay%c2(tr, tc)*ihf(lay%k2(tr, tc))
      end do
    end do
  end subroutine pair_block_complex

  !> Scaled real translation block (section 7): gr = Re(W g W^dagger) of the complex block g.
  !> x is complex work space of the same shape as g.
  pure subroutine pair_block_real(lay, g, x, gr)
    type(multipole_layout_t), intent(in) :: lay
    complex(wp), intent(in) :: g(:, :)
    complex(wp), intent(out) :: x(:, :)
    real(wp), intent(out) :: gr(:, :)
    integer :: p, q
    do q = 1, lay%nb
      do p = 1, lay%nb
        x(p, q) = lay%wval(1, p)*g(lay%widx(1, p), q) + lay%wval(2, p)*g(lay%widx(2, p), q)
      end do
    end do
    do q = 1, lay%nb
      do p = 1, lay%nb
        gr(p, q) = real(x(p, lay%widx(1, q))*conjg(lay%wval(1, q)) &
                        + x(p, lay%widx(2, q))*conjg(lay%wval(2, q)), wp)
      end do
    end do
  end subroutine pair_block_real

end module kf_multipole_blocks
