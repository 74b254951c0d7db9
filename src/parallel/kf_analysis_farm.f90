!> The MPI side of knotflow-analyze: start/stop, the rank and size, and the reductions that merge
!> per-rank partial results (entries a rank did not compute are zero for sums, -huge for maxima),
!> and the sharing of what rank 0 decided, so that every rank takes the same branch.
module kf_analysis_farm
  use mpi_f08, only: MPI_Comm, MPI_COMM_WORLD, MPI_Init, MPI_Finalize, MPI_Initialized, &
    MPI_Comm_rank, MPI_Comm_size, MPI_Allreduce, MPI_IN_PLACE, MPI_DOUBLE_PRECISION, &
    MPI_INTEGER, MPI_INTEGER8, MPI_SUM, MPI_MAX, MPI_Barrier, MPI_Abort, MPI_Bcast, MPI_SUCCESS
  use kf_kinds, only: wp, i8
  use kf_error, only: error_t, fatal_error
  implicit none
  private

  !> The communicator of the analysis and this rank's place in it.
  type, public :: analysis_farm_t
    type(MPI_Comm) :: comm
    integer :: rank = 0
    integer :: size = 1
  end type analysis_farm_t

  public :: farm_start, farm_stop, farm_sum, farm_max, farm_barrier, farm_abort, farm_any, farm_share

contains

  !> Initialise MPI (if needed) on MPI_COMM_WORLD.
  subroutine farm_start(farm, error)
    type(analysis_farm_t), intent(out) :: farm
    type(error_t), allocatable, intent(out) :: error
    logical :: started
    integer :: ierr
    call MPI_Initialized(started, ierr)
    if (.not. started) call MPI_Init(ierr)
    if (ierr /= MPI_SUCCESS) then
      call fatal_error(error, 'MPI_Init failed')
      return
    end if
    farm%comm = MPI_COMM_WORLD
    call MPI_Comm_rank(farm%comm, farm%rank, ierr)
    call MPI_Comm_size(farm%comm, farm%size, ierr)
  end subroutine farm_start

  !> Finalise MPI.
  subroutine farm_stop(farm)
    type(analysis_farm_t), intent(in) :: farm
    integer :: ierr
    call MPI_Barrier(farm%comm, ierr)
    call MPI_Finalize(ierr)
  end subroutine farm_stop

  subroutine farm_barrier(farm)
    type(analysis_farm_t), intent(in) :: farm
    integer :: ierr
    call MPI_Barrier(farm%comm, ierr)
  end subroutine farm_barrier

  !> Abort all ranks with `code` (after a fatal error on one rank).
  subroutine farm_abort(farm, code)
    type(analysis_farm_t), intent(in) :: farm
    integer, intent(in) :: code
    integer :: ierr
    call MPI_Abort(farm%comm, code, ierr)
  end subroutine farm_abort

  !> Element-wise sum over all ranks, in place.
  subroutine farm_sum(farm, x)
    type(analysis_farm_t), intent(in) :: farm
    real(wp), contiguous, intent(inout) :: x(:)
    integer :: ierr
    if (farm%size > 1) call MPI_Allreduce(MPI_IN_PLACE, x, size(x), MPI_DOUBLE_PRECISION, MPI_SUM, farm%comm, ierr)
  end subroutine farm_sum

  !> Element-wise maximum over all ranks, in place.
  subroutine farm_max(farm, x)
    type(analysis_farm_t), intent(in) :: farm
    real(wp), contiguous, intent(inout) :: x(:)
    integer :: ierr
    if (farm%size > 1) call MPI_Allreduce(MPI_IN_PLACE, x, size(x), MPI_DOUBLE_PRECISION, MPI_MAX, farm%comm, ierr)
  end subroutine farm_max

  !> True on every rank when `flag` is true on any rank.
  logical function farm_any(farm, flag)
    type(analysis_farm_t), intent(in) :: farm
    logical, intent(in) :: flag
    integer :: v(1), ierr
    v = merge(1, 0, flag)
    if (farm%size > 1) call MPI_Allreduce(MPI_IN_PLACE, v, 1, MPI_INTEGER, MPI_MAX, farm%comm, ierr)
    farm_any = v(1) > 0
  end function farm_any

  !> Rank 0's list `x` on every rank (its size included): a decision taken once, on rank 0.
  subroutine farm_share(farm, x)
    type(analysis_farm_t), intent(in) :: farm
    integer(i8), allocatable, intent(inout) :: x(:)
    integer :: n(1), ierr
    if (farm%size == 1) return
    n = 0
    if (farm%rank == 0) n = size(x)
    call MPI_Bcast(n, 1, MPI_INTEGER, 0, farm%comm, ierr)
    if (farm%rank /= 0) then
      if (allocated(x)) deallocate (x)
      allocate (x(n(1)))
    end if
    if (n(1) > 0) call MPI_Bcast(x, n(1), MPI_INTEGER8, 0, farm%comm, ierr)
  end subroutine farm_share

end module kf_analysis_farm
