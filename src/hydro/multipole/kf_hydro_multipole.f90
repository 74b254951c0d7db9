!> The multipole hydrodynamic model (PHYSICS.md 3.3): N-sphere induced-force multipoles
!> truncated at order L, optionally with two-sphere lubrication corrections (HYDROLIB scheme,
!> MULTIPOLE.md 13.3) and the BWE overlap rule.
!>
!> prepare(r) assembles and factorises the system and caches the translational mobility mu
!> (3N x 3N) and the disturbance of free beads for the five basis strains; apply_mobility and
!> add_strain_disturbance are then matrix-vector products.
module kf_hydro_multipole
  use kf_kinds, only: wp
  use kf_strings, only: to_str
  use kf_blas, only: dgemv
  use kf_error, only: error_t, fatal_error
  use kf_hydro_model, only: hydro_model_t
  use kf_multipole_system, only: multipole_system_t, strain_coefficients, strain_basis
  use kf_lubrication, only: lubrication_t
  implicit none
  private

  !> Multipole model of order L with or without lubrication corrections.
  type, extends(hydro_model_t), public :: multipole_model_t
    integer :: order = 2
    logical :: lubrication = .false.
    real(wp) :: eps_lub = 1.0e-4_wp      !< BWE shift: overlapping pairs are evaluated at 1 + eps_lub
    type(multipole_system_t) :: sys
    real(wp), allocatable :: mu(:, :)    !< 3N x 3N translational mobility
    real(wp), allocatable :: dist(:, :)  !< 3N x 5 disturbance for the basis strains
    real(wp), allocatable :: fbuf(:, :)  !< 3N x 2 work for apply_mobility
    real(wp), allocatable :: d6(:, :)    !< 6N x 5 work (disturbance incl. rotations)
    real(wp), allocatable :: dz(:, :), dx(:, :) !< summed pair corrections (6N x 6N, 6N x 5)
    type(lubrication_t) :: lub
    integer :: n_lub_pairs = 0           !< pairs corrected at the last prepare
    integer :: n_overlaps = 0            !< overlapping pairs (r <= 1) at the last prepare
    real(wp) :: t_lubrication = 0.0_wp   !< seconds in the lubrication part of the last prepare
  contains
    procedure :: init => multipole_init
    procedure :: prepare => multipole_prepare
    procedure :: apply_mobility => multipole_apply
    procedure :: add_strain_disturbance => multipole_disturbance
    procedure :: name => multipole_name
    procedure :: mobility_matrix => multipole_mobility_matrix
    procedure :: friction_matrix => multipole_friction_matrix
  end type multipole_model_t

contains

  !> Order L (1..20), lubrication on/off, BWE shift eps_lub (0 < eps_lub < 0.5).
  subroutine multipole_init(this, order, lubrication, eps_lub, error)
    class(multipole_model_t), intent(inout) :: this
    integer, intent(in) :: order
    logical, intent(in) :: lubrication
    real(wp), intent(in) :: eps_lub
    type(error_t), allocatable, intent(out) :: error

    if (.not. (eps_lub > 0.0_wp .and. eps_lub < 0.5_wp)) then
      call fatal_error(error, 'multipole: eps_lub = '//to_str(eps_lub, '(es12.4)')// &
                       ' not allowed (0 < eps_lub < 0.5)')
      return
    end if
    if (lubrication) then
      call this%lub%init(order, eps_lub, error)
      if (allocated(error)) return
    end if
    this%order = order
    this%lubrication = lubrication
    this%eps_lub = eps_lub
    this%n = 0
    call this%sys%init(order, 1.0_wp + eps_lub, error)
  end subroutine multipole_init

  !> Assemble and factorise for bead centres r(3, N); cache mu and the strain disturbances.
  subroutine multipole_prepare(this, r, error)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer :: nb

    nb = size(r, 2)
    if (nb /= this%n .or. .not. allocated(this%mu)) then
      if (allocated(this%mu)) deallocate (this%mu, this%dist, this%fbuf, this%d6)
      allocate (this%mu(3*nb, 3*nb), this%dist(3*nb, 5), this%fbuf(3*nb, 2), this%d6(6*nb, 5))
      if (this%lubrication) then
        if (allocated(this%dz)) deallocate (this%dz, this%dx)
        allocate (this%dz(6*nb, 6*nb), this%dx(6*nb, 5))
      end if
    end if
    this%n = 0
    call this%sys%factorise(r, error)
    if (allocated(error)) return
    this%n_overlaps = this%sys%n_clamped
    if (this%lubrication) then
      call lubrication_route(this, r, error)
      if (allocated(error)) return
    else
      call this%sys%translational_mobility(this%mu)
      call disturbance_translational(this)
    end if
    this%n = nb
  end subroutine multipole_prepare

  !> Friction route with the pair corrections of every pair closer than lub%cutoff():
  !> zeta = zeta_L + sum dzeta, x = x_L + sum dxe:E (five basis strains).
  subroutine lubrication_route(this, r, error)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: dzeta(12, 12), dxe(12, 3, 3), d(3), rc, bas(3, 3, 5)
    integer :: i, j, k, nb, ii(12), a, b
    integer(8) :: c0, c1, crate

    call system_clock(c0, crate)
    nb = size(r, 2)
    rc = this%lub%cutoff()
    do k = 1, 5
      bas(:, :, k) = strain_basis(k)
    end do
    this%dz = 0.0_wp
    this%dx = 0.0_wp
    this%n_lub_pairs = 0
    do i = 1, nb
      do j = i + 1, nb
        d = r(:, j) - r(:, i)
        if (norm2(d) >= rc) cycle
        call this%lub%pair_correction(d, dzeta, dxe)
        this%n_lub_pairs = this%n_lub_pairs + 1
        ii(1:6) = [(6*(i - 1) + k, k = 1, 6)]
        ii(7:12) = [(6*(j - 1) + k, k = 1, 6)]
        do b = 1, 12
          do a = 1, 12
            this%dz(ii(a), ii(b)) = this%dz(ii(a), ii(b)) + dzeta(a, b)
          end do
        end do
        do k = 1, 5
          do a = 1, 12
            this%dx(ii(a), k) = this%dx(ii(a), k) + sum(dxe(a, :, :)*bas(:, :, k))
          end do
        end do
      end do
    end do
    call this%sys%corrected(this%dz, this%dx, this%mu, this%dist, error)
    call system_clock(c1)
    this%t_lubrication = real(c1 - c0, wp)/real(crate, wp)
  end subroutine lubrication_route

  !> The translational part of the system's free-sphere disturbance for the basis strains.
  subroutine disturbance_translational(this)
    class(multipole_model_t), intent(inout) :: this
    integer :: i
    call this%sys%strain_disturbance(this%d6)
    do i = 1, this%sys%n
      this%dist(3*i - 2:3*i, :) = this%d6(6*i - 5:6*i - 3, :)
    end do
  end subroutine disturbance_translational

  !> u = mu f.
  subroutine multipole_apply(this, f, u)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: f(:, :)
    real(wp), intent(out) :: u(:, :)
    integer :: n3
    n3 = 3*this%n
    this%fbuf(:, 1) = reshape(f(:, 1:this%n), [n3])
    call dgemv('N', n3, n3, 1.0_wp, this%mu, n3, this%fbuf(:, 1), 1, 0.0_wp, this%fbuf(:, 2), 1)
    u(:, 1:this%n) = reshape(this%fbuf(:, 2), [3, this%n])
  end subroutine multipole_apply

  !> u = u + C:E for the symmetric traceless rate of strain e.
  subroutine multipole_disturbance(this, e, u)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(in) :: e(3, 3)
    real(wp), intent(inout) :: u(:, :)
    real(wp) :: c(5)
    integer :: i
    c = strain_coefficients(e)
    do i = 1, this%n
      u(:, i) = u(:, i) + matmul(this%dist(3*i - 2:3*i, :), c)
    end do
  end subroutine multipole_disturbance

  !> "multipole L=<order>" plus " lubrication" when corrections are on.
  function multipole_name(this) result(label)
    class(multipole_model_t), intent(in) :: this
    character(len=:), allocatable :: label
    label = 'multipole L='//to_str(this%order)
    if (this%lubrication) label = label//' lubrication'
  end function multipole_name

  !> The cached 3N x 3N mobility.
  subroutine multipole_mobility_matrix(this, mu)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(out) :: mu(:, :)
    mu = this%mu
  end subroutine multipole_mobility_matrix

  !> The 6N x 6N generalised friction [F; T] = zeta [U; Omega] (project units, ordering
  !> [U_1, Omega_1, U_2, ...]) at the last prepare, including the lubrication corrections.
  subroutine multipole_friction_matrix(this, zeta, error)
    class(multipole_model_t), intent(inout) :: this
    real(wp), intent(out) :: zeta(:, :)
    type(error_t), allocatable, intent(out) :: error
    call this%sys%grand_friction(zeta, error)
    if (allocated(error)) return
    if (this%lubrication) zeta = zeta + this%dz
  end subroutine multipole_friction_matrix

end module kf_hydro_multipole
