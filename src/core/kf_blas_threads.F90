!> Threads of the BLAS/LAPACK library for one case, chosen once by the program (issue: both
!> cores for one case when a run has fewer cases than cores). Only OpenBLAS can be told at run
!> time (openblas_set_num_threads, detected by CMake); with another BLAS nothing changes.
!>
!> The rule (`blas_threads_for`): more than one thread only for a run with one rank on its node
!> (`knotflow scene.nml`, `mpirun -n 1`, a batch task with several CPUs), because the other ranks
!> of a run occupy the remaining CPUs, computing or waiting in MPI (Open MPI polls while it
!> waits); then the CPUs this process may run on (its affinity mask, from /proc/self/status on
!> Linux; 1 where unknown) less those busy at start-up (the 1-minute load average of
!> kf_platform, rounded), at least 1. Threads that must share a busy CPU slow a BLAS call down
!> several-fold (measured: 4x for a 2-thread factorisation with the other core busy), hence the
!> load. A sweep that keeps every core busy keeps 1 thread per rank. An explicit
!> OPENBLAS_NUM_THREADS (any count >= 1) in the environment is the user's choice and is left alone: `OPENBLAS_NUM_THREADS=1 knotflow ...`
!> really runs on one core (scripts/lib.sh sets 1 unless the caller set it).
!>
!> The same count, once, for the OpenMP threads over the pair blocks of one evaluation (the
!> assembly of the multipole system, the lubrication blocks; `set_openmp_threads`, rule in
!> `openmp_threads_for`): an explicit OMP_NUM_THREADS is the user's and left to the OpenMP
!> runtime; else an explicit OPENBLAS_NUM_THREADS sets it too (so `OPENBLAS_NUM_THREADS=1 knotflow`
!> still runs on one core); else the count of `blas_threads_for`. A build without OpenMP runs
!> the pair loops on one thread and `openmp_threads_in_use` is 0.
!>
!> `blas_library` names the library and the kernels it runs ('OpenBLAS 0.3.21 SkylakeX'), for
!> the start-up line and the /runs record of every run segment: OpenBLAS chooses its kernels
!> from the CPU at start-up (or takes OPENBLAS_CORETYPE, scripts/blas_env.sh), and a CPU it does
!> not know gets its oldest x86-64 kernels, about 3.4 times slower (docs/multipole.md), so a
!> timing means little without them.
module kf_blas_threads
#ifdef _OPENMP
  use omp_lib, only: omp_set_num_threads, omp_get_max_threads
#endif
#ifdef KNOTFLOW_HAVE_OPENBLAS_THREADS
  use, intrinsic :: iso_c_binding, only: c_int
#endif
#ifdef KNOTFLOW_HAVE_OPENBLAS_CORENAME
  use, intrinsic :: iso_c_binding, only: c_ptr
  use kf_strings, only: c_string
#endif
  implicit none
  private

  public :: allowed_cpus, cpu_list_count, blas_threads_for, requested_threads, set_blas_threads, blas_threads_in_use
  public :: blas_library, blas_description
  public :: openmp_threads_for, set_openmp_threads, openmp_threads_in_use, use_openmp_threads

contains

  !> Number of CPUs in this process's affinity mask (Cpus_allowed_list of /proc/self/status),
  !> or 1 when it cannot be read.
  integer function allowed_cpus() result(n)
    character(len=4096) :: line
    integer :: unit, ios, k
    n = 1
    open (newunit=unit, file='/proc/self/status', action='read', status='old', iostat=ios)
    if (ios /= 0) return
    do
      read (unit, '(a)', iostat=ios) line
      if (ios /= 0) exit
      k = index(line, 'Cpus_allowed_list:')
      if (k == 1) then
        n = max(1, cpu_list_count(adjustl(line(19:))))
        exit
      end if
    end do
    close (unit)
  end function allowed_cpus

  !> Number of CPUs in a list such as "0-3,8,10-11" (0 if it cannot be parsed).
  pure integer function cpu_list_count(text) result(n)
    character(len=*), intent(in) :: text
    integer :: p, q, dash, a, b, ios
    character(len=len(text)) :: item
    n = 0
    p = 1
    do while (p <= len_trim(text))
      q = index(text(p:), ',')
      if (q == 0) then
        item = text(p:len_trim(text))
        p = len_trim(text) + 1
      else
        item = text(p:p + q - 2)
        p = p + q
      end if
      dash = index(item, '-')
      if (dash > 0) then
        read (item(:dash - 1), *, iostat=ios) a
        if (ios /= 0) then
          n = 0
          return
        end if
        read (item(dash + 1:), *, iostat=ios) b
      else
        read (item, *, iostat=ios) a
        b = a
      end if
      if (ios /= 0 .or. b < a) then
        n = 0
        return
      end if
      n = n + b - a + 1
    end do
  end function cpu_list_count

  !> BLAS threads for a rank with `cpus` CPUs in its affinity mask, `ranks_on_node` ranks of
  !> its run on the node and the given load average at start-up (the rule above).
  pure integer function blas_threads_for(cpus, ranks_on_node, load) result(threads)
    integer, intent(in) :: cpus, ranks_on_node
    real, intent(in) :: load
    threads = 1
    if (ranks_on_node == 1) threads = max(1, cpus - nint(load))
  end function blas_threads_for

  !> The thread count the user asked for in the value `env` of OPENBLAS_NUM_THREADS (a whole
  !> number >= 1), or 0 when it asks for none (empty, not a number, < 1).
  pure integer function requested_threads(env) result(n)
    character(len=*), intent(in) :: env
    integer :: ios
    n = 0
    if (len_trim(env) == 0 .or. verify(trim(adjustl(env)), '0123456789') /= 0) return
    read (env, *, iostat=ios) n
    if (ios /= 0 .or. n < 1) n = 0
  end function requested_threads

  !> Ask the BLAS library for `threads` threads; `applied` is false when it cannot be told (not
  !> OpenBLAS) or the environment sets OPENBLAS_NUM_THREADS (left to the user).
  subroutine set_blas_threads(threads, applied)
    integer, intent(in) :: threads
    logical, intent(out) :: applied
#ifdef KNOTFLOW_HAVE_OPENBLAS_THREADS
    interface
      subroutine openblas_set_num_threads(n) bind(c, name='openblas_set_num_threads')
        import :: c_int
        integer(c_int), value :: n
      end subroutine openblas_set_num_threads
    end interface
    applied = .false.
    if (requested_from('OPENBLAS_NUM_THREADS') > 0) return
    call openblas_set_num_threads(int(max(1, threads), c_int))
    applied = .true.
#else
    applied = .false.
#endif
  end subroutine set_blas_threads

  !> The threads the BLAS library uses now (openblas_get_num_threads), 0 where the library
  !> cannot be asked (not OpenBLAS).
  integer function blas_threads_in_use() result(n)
#ifdef KNOTFLOW_HAVE_OPENBLAS_THREADS
    interface
      function openblas_get_num_threads() bind(c, name='openblas_get_num_threads') result(k)
        import :: c_int
        integer(c_int) :: k
      end function openblas_get_num_threads
    end interface
    n = int(openblas_get_num_threads())
#else
    n = 0
#endif
  end function blas_threads_in_use

  !> OpenMP threads for the pair loops from the counts requested in OMP_NUM_THREADS
  !> (`omp_request`) and OPENBLAS_NUM_THREADS (`blas_request`; each as `requested_threads`, 0:
  !> none) and the count `automatic` of `blas_threads_for`: the first of the three that is > 0
  !> (at least 1).
  pure integer function openmp_threads_for(omp_request, blas_request, automatic) result(threads)
    integer, intent(in) :: omp_request, blas_request, automatic
    if (omp_request > 0) then
      threads = omp_request
    else if (blas_request > 0) then
      threads = blas_request
    else
      threads = max(1, automatic)
    end if
  end function openmp_threads_for

  !> Give the OpenMP pair loops the threads of `openmp_threads_for` with `automatic` the count of
  !> `blas_threads_for`; `applied` is false in a build without OpenMP and when OMP_NUM_THREADS
  !> holds a count (the OpenMP runtime already took it). Called once, at set-up.
  subroutine set_openmp_threads(automatic, applied)
    integer, intent(in) :: automatic
    logical, intent(out) :: applied
#ifdef _OPENMP
    integer :: omp_request, blas_request
    omp_request = requested_from('OMP_NUM_THREADS')
    blas_request = requested_from('OPENBLAS_NUM_THREADS')
    applied = omp_request == 0
    if (applied) call use_openmp_threads(openmp_threads_for(omp_request, blas_request, automatic))
#else
    applied = .false.
#endif
  end subroutine set_openmp_threads

  !> `threads` (>= 1) OpenMP threads for the pair loops from now on, whatever the environment
  !> says (benchmarks and tests; a program takes `set_openmp_threads`). No effect without OpenMP.
  subroutine use_openmp_threads(threads)
    integer, intent(in) :: threads
#ifdef _OPENMP
    call omp_set_num_threads(max(1, threads))
#else
    if (threads < 1) return
#endif
  end subroutine use_openmp_threads

  !> The count `requested_threads` reads in environment variable `name` (0: unset or none).
  integer function requested_from(name) result(n)
    character(len=*), intent(in) :: name
    character(len=32) :: env
    integer :: status
    n = 0
    call get_environment_variable(name, env, status=status)
    if (status == 0) n = requested_threads(env)
  end function requested_from

  !> The threads the OpenMP pair loops use now (omp_get_max_threads), 0 in a build without OpenMP.
  integer function openmp_threads_in_use() result(n)
#ifdef _OPENMP
    n = omp_get_max_threads()
#else
    n = 0
#endif
  end function openmp_threads_in_use

  !> The library and its kernels as recorded: 'OpenBLAS <version> <core>' from OpenBLAS's
  !> configuration string `config` (openblas_get_config: 'OpenBLAS 0.3.21 DYNAMIC_ARCH ...', the
  !> version its second word) and its core name `core` (openblas_get_corename); a word that is
  !> missing is left out.
  pure function blas_description(config, core) result(text)
    character(len=*), intent(in) :: config, core
    character(len=:), allocatable :: text
    character(len=len(config)) :: rest
    integer :: k
    text = 'OpenBLAS'
    rest = adjustl(config)
    k = index(trim(rest), ' ')
    if (k > 0) then
      rest = adjustl(rest(k + 1:))
      k = index(trim(rest), ' ')
      if (k == 0) k = len_trim(rest) + 1
      if (k > 1) text = text//' '//rest(:k - 1)
    end if
    if (len_trim(core) > 0) text = text//' '//trim(adjustl(core))
  end function blas_description

  !> The BLAS library this program runs and its kernels ('OpenBLAS 0.3.21 SkylakeX'), 'unknown'
  !> for a library other than OpenBLAS (it cannot be asked).
  function blas_library() result(text)
    character(len=:), allocatable :: text
#ifdef KNOTFLOW_HAVE_OPENBLAS_CORENAME
    interface
      function openblas_get_config() bind(c, name='openblas_get_config') result(p)
        import :: c_ptr
        type(c_ptr) :: p
      end function openblas_get_config
      function openblas_get_corename() bind(c, name='openblas_get_corename') result(p)
        import :: c_ptr
        type(c_ptr) :: p
      end function openblas_get_corename
    end interface
    text = blas_description(c_string(openblas_get_config()), c_string(openblas_get_corename()))
#else
    text = 'unknown'
#endif
  end function blas_library

end module kf_blas_threads
