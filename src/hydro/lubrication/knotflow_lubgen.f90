!> knotflow-lubgen: writes the generated module kf_lubrication_data (the two-sphere lubrication
!> correction tables for truncation orders L = 1..6).
!>
!> Usage: knotflow-lubgen [output file]   (default: kf_lubrication_data.f90)
!>
!> For each L the table holds, for all 22 resistance functions, the regular remainder
!>   R_L(u) = f_exact(xi) - f_L(xi) - w(xi) * [g1/xi + g2 ln(1/xi) + g3 xi ln(1/xi)]
!> on a uniform grid in u = sqrt(xi), xi = 2 (r - 1), from contact (u = 0) to the cutoff r_c(L).
!> f_exact: kf_near_contact%exact_resistance (multipole at L ~ 20/sqrt(xi) joined to the
!> near-contact forms); f_L: kf_two_sphere at order L; w: kf_near_contact%singular_weight.
!> At u = 0 the remainder is the contact limit A_f - f_L(r = 1).
program knotflow_lubgen
  use kf_kinds, only: wp, i8
  use kf_error, only: error_t
  use kf_two_sphere, only: n_functions, two_sphere_resistance, function_names, has_strain
  use kf_near_contact, only: exact_resistance, singular_part, singular_weight, near_coeff
  implicit none

  integer, parameter :: max_order = 6
  !> Cutoff centre distances r_c(L) (units of d) and start of the taper to zero.
  real(wp), parameter :: cutoff(max_order) = [8.0_wp, 7.5_wp, 4.0_wp, 3.0_wp, 2.5_wp, 2.2_wp]
  !> Target grid step in u = sqrt(xi).
  real(wp), parameter :: du_target = 0.01_wp

  character(len=1024) :: path
  integer :: unit, ios, order, n, i, j, k, nf
  integer(i8) :: t0, t1, rate
  real(wp) :: uc, h, u, xi, r, w
  real(wp) :: fe(n_functions), fl(n_functions), sing(n_functions)
  real(wp), allocatable :: tab(:, :)
  integer :: ngrid(max_order)
  type(error_t), allocatable :: error
  character(len=40) :: buf

  path = 'kf_lubrication_data.f90'
  if (command_argument_count() >= 1) call get_command_argument(1, path)
  do order = 1, max_order
    ngrid(order) = ceiling(sqrt(2.0_wp*(cutoff(order) - 1.0_wp))/du_target) + 1
  end do

  open (newunit=unit, file=trim(path), status='replace', action='write', iostat=ios)
  if (ios /= 0) then
    write (*, '(a)') 'ERROR: cannot open '//trim(path)
    error stop 1
  end if
  call header()

  call system_clock(t0, rate)
  do order = 1, max_order
    n = ngrid(order)
    uc = sqrt(2.0_wp*(cutoff(order) - 1.0_wp))
    h = uc/real(n - 1, wp)
    allocate (tab(n, n_functions))
    nf = merge(n_functions, 10, has_strain(order))
    do i = 1, n
      u = h*real(i - 1, wp)
      xi = u*u
      r = 1.0_wp + 0.5_wp*xi
      call two_sphere_resistance(r, order, fl, error)
      call check()
      if (i == 1) then
        tab(i, :) = near_coeff(4, :) - fl
      else
        call exact_resistance(r, fe, error)
        call check()
        call singular_part(xi, sing)
        w = singular_weight(xi)
        tab(i, :) = fe - fl - w*sing
      end if
      if (nf < n_functions) tab(i, nf + 1:) = 0.0_wp
    end do
    do k = 1, n_functions
      write (buf, '(a,i0,a,i2.2)') 'tab_l', order, '_f', k
      write (unit, '(a,i0,a)') '  !> '//function_names(k)//', L = ', order, '.'
      write (unit, '(a,i0,a)') '  real(wp), parameter :: '//trim(buf)//'(', n, ') = [ &'
      do j = 1, n, 4
        write (unit, '(a)', advance='no') '    '
        do i = j, min(n, j + 3)
          write (unit, '(es24.16e3,a)', advance='no') tab(i, k), '_wp'
          if (i < n) write (unit, '(a)', advance='no') ', '
        end do
        if (j + 3 < n) then
          write (unit, '(a)') '&'
        else
          write (unit, '(a)') ']'
        end if
      end do
    end do
    deallocate (tab)
    call system_clock(t1)
    write (*, '(a,i0,a,i0,a,f8.1,a)') 'order ', order, ': ', n, ' grid points, ', &
      real(t1 - t0, wp)/real(rate, wp), ' s elapsed'
  end do
  call footer()
  close (unit)
  write (*, '(a)') 'wrote '//trim(path)

contains

  subroutine check()
    if (allocated(error)) then
      write (*, '(a)') 'ERROR: '//error%message
      error stop 1
    end if
  end subroutine check

  subroutine header()
    integer :: l
    write (unit, '(a)') '!> GENERATED FILE - do not edit. Regenerate with'
    write (unit, '(a)') '!>   cmake --build build --target knotflow-lubgen'
    write (unit, '(a)') '!>   ./build/src/hydro/lubrication/knotflow-lubgen src/hydro/lubrication/kf_lubrication_data.f90'
    write (unit, '(a)') '!> (a few minutes; see docs/lubrication.md). Produced by knotflow_lubgen.f90.'
    write (unit, '(a)') '!>'
    write (unit, '(a)') '!> Two-sphere lubrication correction tables for truncation orders L = 1..6: for each L and'
    write (unit, '(a)') '!> each of the 22 resistance functions (order of kf_two_sphere) the regular remainder'
    write (unit, '(a)') '!>   R_L(u) = f_exact - f_L - w(xi) (g1/xi + g2 ln(1/xi) + g3 xi ln(1/xi)),  xi = u**2 = 2 (r - 1),'
    write (unit, '(a)') '!> on the uniform grid u_i = (i - 1) sqrt(2 (r_c - 1))/(n - 1), i = 1..n (u = 0: contact).'
    write (unit, '(a)') '!> For L = 1 the strain functions (11..22) are not represented and stored as 0.'
    write (unit, '(a)') 'module kf_lubrication_data'
    write (unit, '(a)') '  use kf_kinds, only: wp'
    write (unit, '(a)') '  implicit none'
    write (unit, '(a)') '  private'
    write (unit, '(a)') ''
    write (unit, '(a)') '  public :: lubrication_table'
    write (unit, '(a)') ''
    write (unit, '(a)') '  !> Highest tabulated truncation order.'
    write (unit, '(a,i0)') '  integer, parameter, public :: lub_max_order = ', max_order
    write (unit, '(a)') '  !> Cutoff centre distance r_c(L) in bead diameters (tables end there).'
    write (unit, '(a)', advance='no') '  real(wp), parameter, public :: lub_cutoff(lub_max_order) = ['
    do l = 1, max_order
      write (unit, '(f0.4,a)', advance='no') cutoff(l), '_wp'
      if (l < max_order) write (unit, '(a)', advance='no') ', '
    end do
    write (unit, '(a)') ']'
    write (unit, '(a)') '  !> Number of grid points per order.'
    write (unit, '(a)', advance='no') '  integer, parameter, public :: lub_n_grid(lub_max_order) = ['
    do l = 1, max_order
      write (unit, '(i0)', advance='no') ngrid(l)
      if (l < max_order) write (unit, '(a)', advance='no') ', '
    end do
    write (unit, '(a)') ']'
    write (unit, '(a)') ''
  end subroutine header

  subroutine footer()
    integer :: l, kk
    write (unit, '(a)') ''
    write (unit, '(a)') 'contains'
    write (unit, '(a)') ''
    write (unit, '(a)') '  !> The table of order `order` (1..lub_max_order): tab(lub_n_grid(order), 22).'
    write (unit, '(a)') '  subroutine lubrication_table(order, tab)'
    write (unit, '(a)') '    integer, intent(in) :: order'
    write (unit, '(a)') '    real(wp), allocatable, intent(out) :: tab(:, :)'
    write (unit, '(a)') '    allocate (tab(lub_n_grid(order), 22))'
    write (unit, '(a)') '    select case (order)'
    do l = 1, max_order
      write (unit, '(a,i0,a)') '    case (', l, ')'
      do kk = 1, n_functions
        write (unit, '(a,i0,a,i0,a,i2.2)') '      tab(:, ', kk, ') = tab_l', l, '_f', kk
      end do
    end do
    write (unit, '(a)') '    end select'
    write (unit, '(a)') '  end subroutine lubrication_table'
    write (unit, '(a)') ''
    write (unit, '(a)') 'end module kf_lubrication_data'
  end subroutine footer

end program knotflow_lubgen
