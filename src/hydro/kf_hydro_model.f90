!> The abstract hydrodynamic model. Bead velocities are
!>   dr_i/dt = v0(r_i) + sum_j mu_ij F_j + sum_j C_ij : E,
!> with mu (3N x 3N) the translational mobility of torque-free beads and C:E the disturbance
!> of force-free, torque-free beads in the ambient rate of strain E.
!> Units of PHYSICS.md section 1: an isolated bead has mobility 1/3.
!>
!> The expensive work depends only on positions: `prepare(r)` (assemble, factorise), then any
!> number of cheap `apply_mobility(f, u)` / `add_strain_disturbance(e, u)` calls.
module kf_hydro_model
  use kf_kinds, only: wp
  use kf_error, only: error_t
  implicit none
  private

  type, abstract, public :: hydro_model_t
    integer :: n = 0   !< number of beads at the last prepare
  contains
    procedure(prepare_i), deferred :: prepare
    procedure(apply_i), deferred :: apply_mobility
    procedure(disturb_i), deferred :: add_strain_disturbance
    procedure(name_i), deferred :: name
    procedure :: mobility_matrix
  end type hydro_model_t

  abstract interface
    !> Set up for bead centres r(3, N).
    subroutine prepare_i(this, r, error)
      import :: hydro_model_t, wp, error_t
      class(hydro_model_t), intent(inout) :: this
      real(wp), intent(in) :: r(:, :)
      type(error_t), allocatable, intent(out) :: error
    end subroutine prepare_i
    !> u = mu f for forces f(3, N) (u is overwritten).
    subroutine apply_i(this, f, u)
      import :: hydro_model_t, wp
      class(hydro_model_t), intent(inout) :: this
      real(wp), intent(in) :: f(:, :)
      real(wp), intent(out) :: u(:, :)
    end subroutine apply_i
    !> u = u + C:E for the symmetric traceless rate of strain e(3, 3).
    subroutine disturb_i(this, e, u)
      import :: hydro_model_t, wp
      class(hydro_model_t), intent(inout) :: this
      real(wp), intent(in) :: e(3, 3)
      real(wp), intent(inout) :: u(:, :)
    end subroutine disturb_i
    !> A short description of the model, e.g. "rpy" or "multipole L=2 lubrication".
    function name_i(this) result(label)
      import :: hydro_model_t
      class(hydro_model_t), intent(in) :: this
      character(len=:), allocatable :: label
    end function name_i
  end interface

contains

  !> The full 3N x 3N mobility, row 3(i-1)+a, column 3(j-1)+b (after prepare).
  !> Models that hold the matrix override this; the default applies mu to unit forces.
  subroutine mobility_matrix(this, mu)
    class(hydro_model_t), intent(inout) :: this
    real(wp), intent(out) :: mu(:, :)
    real(wp), allocatable :: f(:, :), u(:, :)
    integer :: j, b
    allocate (f(3, this%n), u(3, this%n))
    do j = 1, this%n
      do b = 1, 3
        f = 0.0_wp
        f(b, j) = 1.0_wp
        call this%apply_mobility(f, u)
        mu(:, 3*(j - 1) + b) = reshape(u, [3*this%n])
      end do
    end do
  end subroutine mobility_matrix

end module kf_hydro_model
