!> Program knotflow-bench-knots: wall time of (1) k_f with 1000 closures of the N = 99 open trefoil
!> (PHYSICS.md 5, orientation a, 100th point removed) and (2) the full knot matrix of an N = 152
!> candy-cane frame (PHYSICS.md 5, made non-planar by z_i = 0.5 sin(0.37 i) as a simulation frame
!> would be), parallel over subchains with MPI.
!> usage: knotflow-bench-knots [matrix_closures (default 100)] [min_length (default 10)]
program knotflow_bench_knots
  use, intrinsic :: iso_fortran_env, only: output_unit, int64
  use, intrinsic :: ieee_arithmetic, only: ieee_is_nan, ieee_value, ieee_quiet_nan
  use kf_kinds, only: wp, i8
  use kf_constants, only: pi
  use kf_error, only: error_t
  use kf_memory, only: keep_freed_heap
  use kf_knot_closure, only: knot_stats_t, analyse_closures
  use kf_knot_matrix, only: knot_matrix, knot_core, n_subchains
  use kf_analysis_farm, only: analysis_farm_t, farm_start, farm_stop, farm_max, farm_barrier
  use kf_cli, only: standard_option, argument, die
  implicit none

  character(len=*), parameter :: program_name = 'knotflow-bench-knots'

  type(analysis_farm_t) :: farm
  type(error_t), allocatable :: error
  type(knot_stats_t) :: st
  real(wp) :: trefoil(3, 99), cane(3, 152), kmat(152, 152), flat(152*152), t0, t1
  integer :: mclos, minlen, stat, core(2)
  logical :: found
  character(len=:), allocatable :: arg

  mclos = 100
  minlen = 10
  if (command_argument_count() >= 1) then
    arg = argument(1)
    call standard_option(program_name, arg, 'usage: [mpirun -n P] knotflow-bench-knots '// &
      '[MATRIX_CLOSURES [MIN_LENGTH]]'//new_line('a')//'       knotflow-bench-knots --help | --version'// &
      new_line('a')//'Times k_f of an N = 99 trefoil frame (1000 closures) and the knot matrix of an '// &
      'N = 152'//new_line('a')//'candy-cane frame (MATRIX_CLOSURES per subchain, default 100; subchains of '// &
      'at least'//new_line('a')//'MIN_LENGTH beads, default 10) over the MPI ranks (one without MPI).')
    read (arg, *, iostat=stat) mclos
    if (stat /= 0 .or. mclos < 1) call die(program_name, 'matrix_closures: invalid value "'//trim(arg)//'" (allowed: integer >= 1)', 1)
  end if
  if (command_argument_count() >= 2) then
    arg = argument(2)
    read (arg, *, iostat=stat) minlen
    if (stat /= 0 .or. minlen < 2) call die(program_name, 'min_length: invalid value "'//trim(arg)//'" (allowed: integer >= 2)', 1)
  end if
  call farm_start(farm, error)
  if (allocated(error)) call die(program_name, error%message, 1)
  call keep_freed_heap()

  call open_trefoil(trefoil)
  if (farm%rank == 0) then
    t0 = wall()
    call analyse_closures(trefoil, 1000, 1972_i8, st, error)
    if (allocated(error)) call die(program_name, error%message, 1)
    t1 = wall()
    write (output_unit, '(a,f8.4,a,f9.4,a)') 'trefoil N=99: k_f = ', st%kf, ' with 1000 closures in ', t1 - t0, ' s'
  end if

  call candy_cane(cane)
  call farm_barrier(farm, error)
  if (allocated(error)) call die(program_name, error%message, 1)
  t0 = wall()
  call knot_matrix(cane, mclos, 1972_i8, minlen, kmat, error, part=farm%rank, nparts=farm%size)
  if (allocated(error)) call die(program_name, error%message, 1)
  flat = reshape(kmat, [size(flat)])
  where (ieee_is_nan(flat)) flat = -huge(1.0_wp)
  call farm_max(farm, flat, error)
  if (allocated(error)) call die(program_name, error%message, 1)
  kmat = reshape(flat, [152, 152])
  where (kmat < -1.0_wp) kmat = ieee_value(0.0_wp, ieee_quiet_nan)
  t1 = wall()
  if (farm%rank == 0) then
    call knot_core(kmat, core, found)
    write (output_unit, '(a,i0,a,i0,a,i0,a,i0,a,f9.2,a)') 'candy-cane N=152 knot matrix: ', &
      n_subchains(152, minlen), ' subchains (min length ', minlen, '), ', mclos, &
      ' closures per subchain, ', farm%size, ' ranks: ', t1 - t0, ' s'
    write (output_unit, '(a,f8.4,a,l1)') '  max K = ', maxval(kmat, mask=.not. ieee_is_nan(kmat)), &
      ', knot core found: ', found
  end if
  call farm_stop(farm, error)
  if (allocated(error)) call die(program_name, error%message, 1)

contains

  real(wp) function wall()
    integer(int64) :: c, rate
    call system_clock(c, rate)
    wall = real(c, wp)/real(rate, wp)
  end function wall

  subroutine open_trefoil(r)
    real(wp), intent(out) :: r(3, 99)
    integer, parameter :: nf = 20000
    real(wp), allocatable :: s(:), len(:)
    real(wp) :: target, w
    integer :: i, k
    allocate (s(0:nf), len(0:nf))
    len(0) = 0.0_wp
    do i = 0, nf
      s(i) = 2.0_wp*pi*i/nf
      if (i > 0) len(i) = len(i - 1) + norm2(tc(s(i)) - tc(s(i - 1)))
    end do
    k = 0
    do i = 1, 99
      target = len(nf)*(i - 1)/100.0_wp
      do while (len(k + 1) < target)
        k = k + 1
      end do
      w = (target - len(k))/(len(k + 1) - len(k))
      r(:, i) = 3.538436590931158_wp*tc(s(k) + w*(s(k + 1) - s(k)))
    end do
  end subroutine open_trefoil

  function tc(s) result(x)
    real(wp), intent(in) :: s
    real(wp) :: x(3)
    x = [sin(s) + 2.0_wp*sin(2*s), cos(s) - 2.0_wp*cos(2*s), -sin(3*s)]
  end function tc

  subroutine candy_cane(r)
    real(wp), intent(out) :: r(3, 152)
    real(wp) :: s
    integer :: i
    do i = 1, 90
      r(:, i) = [-1.02_wp*(91 - i), 0.0_wp, 0.0_wp]
    end do
    do i = 1, 62
      s = -pi/2 + 0.05105_wp*(i - 1)
      r(:, 90 + i) = [20.0_wp*cos(s), 20.0_wp*sin(s) + 20.0_wp, 0.0_wp]
    end do
    do i = 1, 152
      r(3, i) = 0.5_wp*sin(0.37_wp*i)
    end do
  end subroutine candy_cane

end program knotflow_bench_knots
