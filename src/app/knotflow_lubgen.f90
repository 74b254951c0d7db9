!> Program knotflow-lubgen: writes the generated module kf_lubrication_data (the two-sphere lubrication
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
!> Before tabulating, the constants A, c1..c3 of the near-contact forms are re-fitted (least
!> squares, exact g1..g3 fixed) to converged multipole values at n_fit gaps xi in [0.0025, 0.02]
!> (L = ceil(25/sqrt(xi)) <= 500); the fit, its residual and the change from MULTIPOLE.md's
!> constants are printed, and the fitted constants are used for xi < 0.02.
program knotflow_lubgen
  use kf_kinds, only: wp, i8
  use kf_cli, only: standard_option, argument, die
  use kf_error, only: error_t
  use kf_two_sphere, only: n_functions, two_sphere_resistance, function_names, has_strain
  use kf_near_contact, only: exact_resistance, singular_part, singular_weight, near_coeff, &
    near_contact_form
  implicit none

  character(len=*), parameter :: program_name = 'knotflow-lubgen'

  integer, parameter :: max_order = 6
  !> Cutoff centre distances r_c(L) (units of d) and start of the taper to zero.
  real(wp), parameter :: cutoff(max_order) = [8.0_wp, 7.5_wp, 4.0_wp, 3.0_wp, 2.5_wp, 2.2_wp]
  !> Target grid step in u = sqrt(xi).
  real(wp), parameter :: du_target = 0.01_wp

  character(len=:), allocatable :: path
  integer :: unit, ios, order, n, i, j, k, nf
  integer(i8) :: t0, t1, rate
  real(wp) :: uc, h, u, xi, r, w
  real(wp) :: fe(n_functions), fl(n_functions), sing(n_functions)
  real(wp), allocatable :: tab(:, :)
  integer :: ngrid(max_order)
  type(error_t), allocatable :: error
  character(len=40) :: buf
  integer, parameter :: n_fit = 10
  real(wp), parameter :: xi_fit(n_fit) = [0.0025_wp, 0.003_wp, 0.004_wp, 0.005_wp, 0.006_wp, &
    0.008_wp, 0.01_wp, 0.0125_wp, 0.015_wp, 0.02_wp]
  real(wp) :: fitted(4, n_functions), fit_resid, fit_change

  path = 'kf_lubrication_data.f90'
  if (command_argument_count() >= 1) path = argument(1)
  ! options, not an output file named '--help' (which would also start the long generation)
  call standard_option(program_name, path, 'usage: knotflow-lubgen [output file]   (default: '// &
    'kf_lubrication_data.f90)'//new_line('a')//'       knotflow-lubgen --help | --version')
  if (index(path, '-') == 1) call die(program_name, 'unknown option '//path//' (allowed: --help, --version)', 2)
  do order = 1, max_order
    ngrid(order) = ceiling(sqrt(2.0_wp*(cutoff(order) - 1.0_wp))/du_target) + 1
  end do

  open (newunit=unit, file=trim(path), status='replace', action='write', iostat=ios)
  if (ios /= 0) call die(program_name, 'cannot open '//path, 1)
  call system_clock(t0, rate)
  call fit_near_contact()
  call system_clock(t1)
  write (*, '(a,es9.2,a,es9.2,a,f8.1,a)') 'near-contact fit: max residual ', fit_resid, &
    ', max change of A/c1..c3 vs MULTIPOLE.md ', fit_change, ' (', real(t1 - t0, wp)/real(rate, wp), ' s)'
  call header()

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
        tab(i, :) = fitted(1, :) - fl
      else
        call exact_resistance(r, fe, error, fitted)
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

  !> Least-squares fit of A, c1, c2, c3 for all functions (columns scaled, modified Gram-Schmidt
  !> applied twice); fills fitted, fit_resid (max abs residual) and fit_change.
  subroutine fit_near_contact()
    real(wp) :: a(n_fit, 4), y(n_fit, n_functions), q(n_fit, 4), rr(4, 4), scl(4), proj, sol(4)
    real(wp) :: fm(n_functions), sing(n_functions), fn(n_functions)
    integer :: p, kk, jj, pass
    do p = 1, n_fit
      call two_sphere_resistance(1.0_wp + 0.5_wp*xi_fit(p), ceiling(25.0_wp/sqrt(xi_fit(p))), fm, error)
      call check()
      call singular_part(xi_fit(p), sing)
      y(p, :) = fm - sing
      a(p, :) = [1.0_wp, xi_fit(p), xi_fit(p)**2*log(1.0_wp/xi_fit(p)), xi_fit(p)**2]
    end do
    do kk = 1, 4
      scl(kk) = maxval(abs(a(:, kk)))
      a(:, kk) = a(:, kk)/scl(kk)
    end do
    q = a
    rr = 0.0_wp
    do kk = 1, 4
      do pass = 1, 2
        do jj = 1, kk - 1
          proj = dot_product(q(:, jj), q(:, kk))
          rr(jj, kk) = rr(jj, kk) + proj
          q(:, kk) = q(:, kk) - proj*q(:, jj)
        end do
      end do
      rr(kk, kk) = norm2(q(:, kk))
      q(:, kk) = q(:, kk)/rr(kk, kk)
    end do
    fit_resid = 0.0_wp
    do jj = 1, n_functions
      do kk = 1, 4
        sol(kk) = dot_product(q(:, kk), y(:, jj))
      end do
      do kk = 4, 1, -1
        sol(kk) = (sol(kk) - dot_product(rr(kk, kk + 1:4), sol(kk + 1:4)))/rr(kk, kk)
      end do
      fitted(:, jj) = sol/scl
    end do
    do p = 1, n_fit
      call two_sphere_resistance(1.0_wp + 0.5_wp*xi_fit(p), ceiling(25.0_wp/sqrt(xi_fit(p))), fm, error)
      call check()
      call near_contact_form(xi_fit(p), fn, fitted)
      fit_resid = max(fit_resid, maxval(abs(fn - fm)))
    end do
    fit_change = maxval(abs(fitted - near_coeff(4:7, :)))
    do jj = 1, n_functions
      write (*, '(a,4f12.7,a,es9.2)') function_names(jj)//' A, c1..c3 = ', fitted(:, jj), &
        '   dA = ', fitted(1, jj) - near_coeff(4, jj)
    end do
  end subroutine fit_near_contact

  subroutine check()
    if (allocated(error)) call die(program_name, error%message, 1)
  end subroutine check

  subroutine header()
    integer :: l
    write (unit, '(a)') '!> GENERATED FILE - do not edit. Regenerate with'
    write (unit, '(a)') '!>   cmake --build build --target knotflow-lubgen'
    write (unit, '(a)') '!>   ./build/bin/knotflow-lubgen src/hydro/lubrication/kf_lubrication_data.f90'
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
    write (unit, '(a)') '  !> Near-contact constants (A, c1, c2, c3) re-fitted by the generator and used for xi < 0.02.'
    write (unit, '(a)') '  real(wp), parameter, public :: lub_near_fit(4, 22) = reshape([ &'
    do l = 1, n_functions
      write (unit, '(a,4(es24.16e3,a))', advance='no') '    ', fitted(1, l), '_wp, ', fitted(2, l), &
        '_wp, ', fitted(3, l), '_wp, ', fitted(4, l), '_wp'
      if (l < n_functions) then
        write (unit, '(a)') ', &'
      else
        write (unit, '(a)') '], [4, 22])'
      end if
    end do
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
