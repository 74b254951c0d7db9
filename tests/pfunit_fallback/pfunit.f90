!> Minimal stand-in for pFUnit 4's `pfunit` module (MPI tests) used by the fallback runner.
!>
!> `@mpitest(npes=[...])` procedures receive a `class(MpiTestMethod)` argument whose
!> communicator holds exactly npes processes (a split of MPI_COMM_WORLD; the other processes
!> wait).  A test fails when it fails on any process: the result is reduced over all ranks,
!> rank 0 prints the PASS/FAIL line and every rank prints its own failures.
!> The module also re-exports the assertions of module funit, like pFUnit's `pfunit`.
module pfunit
  use mpi_f08, only: MPI_Comm, MPI_COMM_WORLD, MPI_UNDEFINED, MPI_LOGICAL, MPI_LOR, &
                     MPI_Init, MPI_Initialized, MPI_Finalize, MPI_Comm_rank, MPI_Comm_size, &
                     MPI_Comm_split, MPI_Comm_free, MPI_Allreduce, MPI_Barrier
  use, intrinsic :: iso_fortran_env, only: output_unit
  use funit, only: SourceLocation, anyExceptions, throw, assertEqual, assertRelativelyEqual, &
                   assertTrue, assertFalse, assertLessThan, assertGreaterThan, &
                   assertLessThanOrEqual, assertGreaterThanOrEqual, assertIsNaN, assertIsFinite, &
                   funit_test_proc, funit_begin_test, funit_test_failed, funit_failure_count, &
                   funit_failure_text, funit_report_result, funit_summary, funit_counts
  implicit none
  private

  public :: MpiTestMethod
  public :: SourceLocation, anyExceptions, throw, assertEqual, assertRelativelyEqual
  public :: assertTrue, assertFalse, assertLessThan, assertGreaterThan
  public :: assertLessThanOrEqual, assertGreaterThanOrEqual, assertIsNaN, assertIsFinite
  public :: pfunit_mpi_init, pfunit_mpi_finalize, pfunit_run_mpi_test, pfunit_run_serial_test

  !> The context of one MPI test: its communicator (an integer handle, as in pFUnit),
  !> the process's rank in it and the number of processes.
  type :: MpiTestMethod
    integer :: comm = -1
    integer :: rank = -1
    integer :: npes = 0
  contains
    procedure :: getMpiCommunicator
    procedure :: getProcessRank
    procedure :: getNumProcesses
  end type MpiTestMethod

  !> Signature of an `@mpitest` procedure (and of `@before`/`@after` taking `this`).
  abstract interface
    subroutine mpi_test_proc(this)
      import :: MpiTestMethod
      class(MpiTestMethod), intent(inout) :: this
    end subroutine mpi_test_proc
  end interface

contains

  !> Communicator of the test (Fortran integer handle; `type(MPI_Comm) :: c; c%MPI_VAL = ...`).
  integer function getMpiCommunicator(this)
    class(MpiTestMethod), intent(in) :: this
    getMpiCommunicator = this%comm
  end function getMpiCommunicator

  !> Rank of this process in the test's communicator.
  integer function getProcessRank(this)
    class(MpiTestMethod), intent(in) :: this
    getProcessRank = this%rank
  end function getProcessRank

  !> Number of processes of the test's communicator.
  integer function getNumProcesses(this)
    class(MpiTestMethod), intent(in) :: this
    getNumProcesses = this%npes
  end function getNumProcesses

  !> Start MPI (once) for the driver.
  subroutine pfunit_mpi_init()
    logical :: started
    call MPI_Initialized(started)
    if (.not. started) call MPI_Init()
  end subroutine pfunit_mpi_init

  !> Print the closing line on rank 0, finish MPI; `failed` is the same on every rank.
  subroutine pfunit_mpi_finalize(failed)
    logical, intent(out) :: failed
    integer :: rank, n_passed, n_failed
    call MPI_Comm_rank(MPI_COMM_WORLD, rank)
    call MPI_Barrier(MPI_COMM_WORLD)
    if (rank == 0) call funit_summary()
    call funit_counts(n_passed, n_failed)
    failed = n_failed > 0
    call MPI_Finalize()
  end subroutine pfunit_mpi_finalize

  !> Run an `@mpitest` once per entry of npes on a communicator of that size.
  subroutine pfunit_run_mpi_test(suite, name, test, npes, setup, teardown, setup_plain, &
                                 teardown_plain)
    character(len=*), intent(in) :: suite
    character(len=*), intent(in) :: name
    procedure(mpi_test_proc) :: test
    integer, intent(in) :: npes(:)
    procedure(mpi_test_proc), optional :: setup
    procedure(mpi_test_proc), optional :: teardown
    procedure(funit_test_proc), optional :: setup_plain
    procedure(funit_test_proc), optional :: teardown_plain
    integer :: k, world_rank, world_size, color
    type(MPI_Comm) :: sub
    type(MpiTestMethod) :: this
    character(len=16) :: np_str

    call MPI_Comm_rank(MPI_COMM_WORLD, world_rank)
    call MPI_Comm_size(MPI_COMM_WORLD, world_size)
    do k = 1, size(npes)
      write(np_str, '(i0)') npes(k)
      call funit_begin_test()
      if (npes(k) > world_size) then
        if (world_rank == 0) then
          call throw('test needs ' // trim(np_str) // ' processes but the run has fewer; ' // &
                     'register it with a larger MPI_PES')
        end if
      else
        color = MPI_UNDEFINED
        if (world_rank < npes(k)) color = 0
        call MPI_Comm_split(MPI_COMM_WORLD, color, world_rank, sub)
        if (world_rank < npes(k)) then
          this%comm = sub%MPI_VAL
          call MPI_Comm_rank(sub, this%rank)
          call MPI_Comm_size(sub, this%npes)
          if (present(setup)) call setup(this)
          if (present(setup_plain)) call setup_plain()
          if (.not. anyExceptions()) call test(this)
          if (present(teardown)) call teardown(this)
          if (present(teardown_plain)) call teardown_plain()
          call MPI_Comm_free(sub)
        end if
      end if
      call finish_test(suite, name // '[npes=' // trim(np_str) // ']', world_rank, world_size)
    end do
  end subroutine pfunit_run_mpi_test

  !> Run a plain `@test` on every process of the MPI run.
  subroutine pfunit_run_serial_test(suite, name, test, setup_plain, teardown_plain)
    character(len=*), intent(in) :: suite
    character(len=*), intent(in) :: name
    procedure(funit_test_proc) :: test
    procedure(funit_test_proc), optional :: setup_plain
    procedure(funit_test_proc), optional :: teardown_plain
    integer :: world_rank, world_size
    call MPI_Comm_rank(MPI_COMM_WORLD, world_rank)
    call MPI_Comm_size(MPI_COMM_WORLD, world_size)
    call funit_begin_test()
    if (present(setup_plain)) call setup_plain()
    if (.not. anyExceptions()) call test()
    if (present(teardown_plain)) call teardown_plain()
    call finish_test(suite, name, world_rank, world_size)
  end subroutine pfunit_run_serial_test

  !> Reduce the result over all ranks, print it on rank 0, then each rank's failures in turn.
  subroutine finish_test(suite, name, world_rank, world_size)
    character(len=*), intent(in) :: suite
    character(len=*), intent(in) :: name
    integer, intent(in) :: world_rank
    integer, intent(in) :: world_size
    logical :: local_failed, any_failed
    integer :: r, i
    character(len=16) :: rank_str

    local_failed = funit_test_failed()
    call MPI_Allreduce(local_failed, any_failed, 1, MPI_LOGICAL, MPI_LOR, MPI_COMM_WORLD)
    call funit_report_result(suite, name, any_failed, quiet=(world_rank /= 0))
    if (.not. any_failed) return
    write(rank_str, '(i0)') world_rank
    do r = 0, world_size - 1
      if (r == world_rank) then
        do i = 1, funit_failure_count()
          write(output_unit, '(a)') '    [rank ' // trim(rank_str) // '] ' // funit_failure_text(i)
        end do
        flush(output_unit)
      end if
      call MPI_Barrier(MPI_COMM_WORLD)
    end do
  end subroutine finish_test

end module pfunit
