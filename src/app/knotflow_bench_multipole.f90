!> Program knotflow-bench-multipole: wall time of one evaluation of the multipole hydrodynamics
!> (multipole_model_t%prepare: assembly of the pair blocks, factorisation = p-moment elimination
!> + Cholesky, solves for mobility and shear disturbance, lubrication corrections and the
!> friction route) for N = 10, 20 (self-avoiding random chains: bond 1.02, non-bonded centre
!> distance >= 1.05, fixed seed), 99 (the open trefoil of PHYSICS.md 5, orientation a) and 152
!> (the candy-cane), L = 1..4, without and with lubrication.
!> Best of 2-5 repeated evaluations (arrays reused, as in a time integration).
!> Usage: knotflow-bench-multipole [max_seconds]  (combinations predicted to take longer are
!> skipped; default 60). Run with OPENBLAS_NUM_THREADS=1 for single-core figures.
program knotflow_bench_multipole
  use, intrinsic :: iso_fortran_env, only: output_unit, int64
  use kf_kinds, only: wp
  use kf_error, only: error_t
  use kf_hydro_multipole, only: multipole_model_t
  use kf_hydro_factory, only: standalone_eps_lub
  use kf_scene, only: chain_params_t
  use kf_chain_shapes, only: build_initial_chain
  use kf_cli, only: standard_option, argument, die
  use kf_blas_threads, only: set_openmp_threads, blas_threads_in_use
  implicit none

  character(len=*), parameter :: program_name = 'knotflow-bench-multipole'

  integer, parameter :: sizes(4) = [10, 20, 99, 152]
  type(multipole_model_t) :: model
  type(error_t), allocatable :: error
  real(wp), allocatable :: r(:, :)
  real(wp) :: t_asm, t_fac, t_lub, t_sol, t_tot, best, predicted, max_seconds, t_prev
  integer :: is, order, n, rep, nrep, ios, n_prev, ilub
  integer(int64) :: c0, c1, crate
  logical :: lub
  character(len=:), allocatable :: arg
  logical :: omp_set

  ! The OpenMP pair loops get the BLAS's thread count (OPENBLAS_NUM_THREADS=1: one core; kf_blas_threads).
  call set_openmp_threads(blas_threads_in_use(), omp_set)
  max_seconds = 60.0_wp
  if (command_argument_count() >= 1) then
    arg = argument(1)
    call standard_option(program_name, arg, 'usage: knotflow-bench-multipole [MAX_SECONDS]'// &
      new_line('a')//'       knotflow-bench-multipole --help | --version'//new_line('a')// &
      'Times one multipole evaluation (assembly, factorisation, solves, lubrication) for N = 10-152'// &
      new_line('a')//'and L = 1-4; sizes predicted to take more than MAX_SECONDS (default 60) are skipped.')
    read (arg, *, iostat=ios) max_seconds
    if (ios /= 0 .or. max_seconds <= 0.0_wp) &
      call die(program_name, 'max_seconds '//arg//': expected a positive number', 2)
  end if

  write (output_unit, '(a)') '#   N  L lub  assembly[s] factor[s]  solve[s]    lub[s]  total[s]'// &
    '  asm%  fac%  sol%  lub%'
  do ilub = 0, 1
    lub = (ilub == 1)
    do order = 1, 4
      t_prev = 0.0_wp
      n_prev = 0
      call model%init(order, lub, standalone_eps_lub, error)
      if (allocated(error)) then
        write (output_unit, '(a)') '# skipped: '//error%message
        exit
      end if
      do is = 1, size(sizes)
        n = sizes(is)
        if (n_prev > 0) then
          predicted = t_prev*(real(n, wp)/real(n_prev, wp))**3
          if (predicted > max_seconds) then
            write (output_unit, '(i5,i3,l4,a,f8.1,a)') n, order, lub, '  skipped (predicted ', &
              predicted, ' s)'
            cycle
          end if
        end if
        call bench_chain(n, r)
        nrep = 2
        if (n <= 99) nrep = 3
        if (n <= 20) nrep = 5
        best = huge(1.0_wp)
        do rep = 1, nrep
          call system_clock(c0, crate)
          call model%prepare(r, error)
          if (allocated(error)) call die(program_name, error%message, 2)
          call system_clock(c1)
          t_tot = real(c1 - c0, wp)/real(crate, wp)
          if (t_tot < best) then
            best = t_tot
            call model%prepare_seconds(t_asm, t_fac, t_lub)
            t_sol = t_tot - t_asm - t_fac - t_lub
          end if
        end do
        write (output_unit, '(i5,i3,l4,5f10.4,4f6.1)') n, order, lub, t_asm, t_fac, t_sol, t_lub, &
          best, 100*t_asm/best, 100*t_fac/best, 100*t_sol/best, 100*t_lub/best
        flush (output_unit)
        t_prev = best
        n_prev = n
      end do
    end do
  end do

contains

  !> The benchmark geometry with N beads.
  subroutine bench_chain(nbeads, pos)
    integer, intent(in) :: nbeads
    real(wp), allocatable, intent(out) :: pos(:, :)
    type(chain_params_t) :: params
    real(wp) :: rotation(3, 3)
    select case (nbeads)
    case (99)
      params%shape = 'trefoil'
    case (152)
      params%shape = 'candycane'
    case default
      call random_chain(nbeads, 20150509, pos)
      return
    end select
    call build_initial_chain(params, pos, rotation, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    if (size(pos, 2) /= nbeads) call die(program_name, 'unexpected number of beads in '//trim(params%shape), 2)
  end subroutine bench_chain

  !> Self-avoiding random chain: bond 1.02, non-bonded centres at least 1.05 apart
  !> (xorshift generator with a fixed seed, so every run sees the same chain).
  subroutine random_chain(n, seed, pos)
    integer, intent(in) :: n, seed
    real(wp), allocatable, intent(out) :: pos(:, :)
    integer(int64) :: s
    real(wp) :: u(3), trial(3)
    integer :: i, j, k
    logical :: ok
    allocate (pos(3, n))
    s = int(seed, int64)*2654435761_int64 + 1_int64
    pos(:, 1) = 0.0_wp
    i = 2
    do while (i <= n)
      do k = 1, 3
        u(k) = 2.0_wp*next_uniform(s) - 1.0_wp
      end do
      if (norm2(u) > 1.0_wp .or. norm2(u) < 0.1_wp) cycle
      trial = pos(:, i - 1) + 1.02_wp*u/norm2(u)
      ok = .true.
      do j = 1, i - 2
        if (norm2(trial - pos(:, j)) < 1.05_wp) ok = .false.
      end do
      if (ok) then
        pos(:, i) = trial
        i = i + 1
      end if
    end do
  end subroutine random_chain

  !> xorshift64 uniform number in [0, 1).
  function next_uniform(s) result(x)
    integer(int64), intent(inout) :: s
    real(wp) :: x
    s = ieor(s, ishft(s, 13))
    s = ieor(s, ishft(s, -7))
    s = ieor(s, ishft(s, 17))
    x = real(ishft(s, -11), wp)*2.0_wp**(-53)
  end function next_uniform

end program knotflow_bench_multipole
