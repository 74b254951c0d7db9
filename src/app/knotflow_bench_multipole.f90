!> knotflow-bench-multipole: time of one evaluation of the multipole hydrodynamics (assembly incl.
!> the p-moment elimination, Cholesky factorisation, solves for mobility and shear disturbance)
!> for self-avoiding random chains (bond 1.02, non-bonded distance >= 1.05, fixed seed) with
!> N = 10, 20, 99, 152 and L = 1..4. Best of 2-5 repeated evaluations (arrays reused).
!> Usage: knotflow-bench-multipole [max_seconds]  (combinations predicted to exceed it are skipped;
!> default 60). Run with OPENBLAS_NUM_THREADS=1 for single-core figures.
program knotflow_bench_multipole
  use, intrinsic :: iso_fortran_env, only: output_unit, error_unit, int64
  use kf_kinds, only: wp
  use kf_error, only: error_t
  use kf_multipole_system, only: multipole_system_t
  implicit none

  integer, parameter :: sizes(4) = [10, 20, 99, 152]
  type(multipole_system_t) :: sys
  type(error_t), allocatable :: error
  real(wp), allocatable :: r(:, :), mu(:, :), dist(:, :)
  real(wp) :: t_asm, t_fac, t_sol, t_tot, best, predicted, max_seconds, t_prev
  integer :: is, order, n, rep, nrep, ios, l_prev
  integer(int64) :: c0, c1, crate
  character(len=64) :: arg

  max_seconds = 60.0_wp
  if (command_argument_count() >= 1) then
    call get_command_argument(1, arg)
    read (arg, *, iostat=ios) max_seconds
    if (ios /= 0 .or. max_seconds <= 0.0_wp) then
      write (error_unit, '(a)') 'knotflow-bench-multipole: error: max_seconds '//trim(arg)// &
        ': expected a positive number'
      error stop 2
    end if
  end if

  write (output_unit, '(a)') '#   N  L  unknowns  assembly[s]  factor[s]   solve[s]   total[s]  '// &
    'assembly%  factor%  solve%'
  do order = 1, 4
    t_prev = 0.0_wp
    l_prev = 0
    do is = 1, size(sizes)
      n = sizes(is)
      ! cost grows like N^3 for the factorisation
      if (l_prev > 0) then
        predicted = t_prev*(real(n, wp)/real(l_prev, wp))**3
        if (predicted > max_seconds) then
          write (output_unit, '(i5,i3,a,f10.1,a)') n, order, '  skipped (predicted ', predicted, ' s)'
          cycle
        end if
      end if
      call random_chain(n, 20150509, r)
      call sys%init(order, 1.0001_wp, error)
      if (allocated(error)) call fail(error%message)
      if (allocated(mu)) deallocate (mu, dist)
      allocate (mu(3*n, 3*n), dist(6*n, 5))
      ! repeated calls reuse the arrays (as in a time integration): the first call pays for
      ! allocation and first touch of the memory, so report the best of several calls
      nrep = 2
      if (n <= 99) nrep = 3
      if (n <= 20) nrep = 5
      best = huge(1.0_wp)
      do rep = 1, nrep
        call system_clock(c0, crate)
        call sys%factorise(r, error)
        if (allocated(error)) call fail(error%message)
        call sys%translational_mobility(mu)
        call sys%strain_disturbance(dist)
        call system_clock(c1)
        t_tot = real(c1 - c0, wp)/real(crate, wp)
        if (t_tot < best) then
          best = t_tot
          t_asm = sys%t_assembly
          t_fac = sys%t_factor
          t_sol = t_tot - t_asm - t_fac
        end if
      end do
      write (output_unit, '(i5,i3,i10,4f11.4,3f9.1)') n, order, sys%nr + n*order*(order + 2), &
        t_asm, t_fac, t_sol, best, 100*t_asm/best, 100*t_fac/best, 100*t_sol/best
      flush (output_unit)
      t_prev = best
      l_prev = n
    end do
  end do

contains

  subroutine fail(message)
    character(len=*), intent(in) :: message
    write (error_unit, '(a)') 'knotflow-bench-multipole: error: '//message
    error stop 2
  end subroutine fail

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
