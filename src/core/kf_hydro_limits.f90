!> The ranges of the hydrodynamic parameters, defined once for the scene's checks, the models'
!> own checks, the programs' options and the C interface (issue 38: each limit once). Texts that
!> name a range are built from these numbers (`eps_lub_range_text`, `order_range_text`).
module kf_hydro_limits
  use kf_kinds, only: wp
  use kf_strings, only: to_str, to_str_exact
  implicit none
  private

  !> The lubrication model's shift: 0 < eps_lub < eps_lub_max (the two-sphere tables and the
  !> near-contact forms hold for gaps below it).
  real(wp), parameter, public :: eps_lub_max = 0.5_wp
  !> The largest multipole order L a scene or program may ask for (the multipole system itself
  !> runs to kf_multipole_system's max_multipole_order; above 8 a case of N = 99 no longer fits a
  !> workstation's time and memory).
  integer, parameter, public :: order_max = 8
  !> The largest order with lubrication corrections: the orders kf_lubrication_data tabulates
  !> (its lub_max_order; test_lubrication checks that the two agree).
  integer, parameter, public :: lubrication_order_max = 6
  !> update = 'iterative' (kf_hydro_multipole_iterative): the default of the relative solver
  !> tolerance (largest change of a bead velocity per iteration over the largest bead velocity)
  !> and its allowed range.
  real(wp), parameter, public :: solver_tolerance_default = 1.0e-6_wp
  real(wp), parameter, public :: solver_tolerance_min = 1.0e-12_wp, solver_tolerance_max = 1.0e-2_wp

  public :: eps_lub_in_range, eps_lub_range_text, order_range_text

contains

  !> True when `eps_lub` is an allowed shift: 0 < eps_lub < eps_lub_max.
  pure logical function eps_lub_in_range(eps_lub)
    real(wp), intent(in) :: eps_lub
    eps_lub_in_range = eps_lub > 0.0_wp .and. eps_lub < eps_lub_max
  end function eps_lub_in_range

  !> '(0, 0.5)': the open interval of eps_lub.
  function eps_lub_range_text() result(text)
    character(len=:), allocatable :: text
    text = '(0, '//to_str_exact(eps_lub_max)//')'
  end function eps_lub_range_text

  !> '1 to 8', or with `lubrication` '1 to 6'.
  function order_range_text(lubrication) result(text)
    logical, intent(in) :: lubrication
    character(len=:), allocatable :: text
    if (lubrication) then
      text = '1 to '//to_str(lubrication_order_max)
    else
      text = '1 to '//to_str(order_max)
    end if
  end function order_range_text

end module kf_hydro_limits
