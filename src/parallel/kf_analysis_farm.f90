!> The parallel side of knotflow-analyze: the ranks of a communicator, the reductions that merge
!> per-rank partial results (entries a rank did not compute are zero for sums, -huge for maxima),
!> and the sharing of what rank 0 decided, so that every rank takes the same branch.
!>
!> MPI goes through kf_comm only; the farm works on the communicator it is given (`farm_on`) or
!> on the world (`farm_start`), and every failed call returns an error.
module kf_analysis_farm
  use kf_kinds, only: wp, i8
  use kf_error, only: error_t, fatal_error
  use kf_comm, only: comm_t, comm_init, comm_finalize
  implicit none
  private

  !> The communicator of the analysis and this rank's place in it (rank and size are read-only
  !> by convention: set by `farm_on`).
  type, public :: analysis_farm_t
    private
    type(comm_t) :: comm
    integer, public :: rank = 0
    integer, public :: size = 1
  end type analysis_farm_t

  public :: farm_start, farm_on, farm_stop, farm_sum, farm_max, farm_barrier, farm_abort, farm_any, farm_share, &
    farm_failed

contains

  !> Start the communication layer (MPI, unless already started) and farm over the world.
  subroutine farm_start(farm, error)
    type(analysis_farm_t), intent(out) :: farm
    type(error_t), allocatable, intent(out) :: error
    type(comm_t) :: world
    call comm_init(world, error)
    if (allocated(error)) return
    call farm_on(farm, world, error)
  end subroutine farm_start

  !> The farm on the ranks of `comm`.
  subroutine farm_on(farm, comm, error)
    type(analysis_farm_t), intent(out) :: farm
    type(comm_t), intent(in) :: comm
    type(error_t), allocatable, intent(out) :: error
    farm%comm = comm
    farm%rank = comm%rank()
    farm%size = comm%size()
    if (farm%rank < 0 .or. farm%size < 1) call fatal_error(error, 'analysis farm: cannot get the rank and size')
  end subroutine farm_on

  !> Wait for every rank, then finalise the communication layer (after `farm_start`).
  subroutine farm_stop(farm, error)
    type(analysis_farm_t), intent(in) :: farm
    type(error_t), allocatable, intent(out) :: error
    call farm%comm%barrier(error)
    if (allocated(error)) return
    call comm_finalize(error)
  end subroutine farm_stop

  subroutine farm_barrier(farm, error)
    type(analysis_farm_t), intent(in) :: farm
    type(error_t), allocatable, intent(out) :: error
    call farm%comm%barrier(error)
  end subroutine farm_barrier

  !> Abort all ranks with `code` (after a fatal error on one rank; programs only).
  subroutine farm_abort(farm, code)
    type(analysis_farm_t), intent(in) :: farm
    integer, intent(in) :: code
    call farm%comm%abort(code)
  end subroutine farm_abort

  !> Element-wise sum over all ranks, in place.
  subroutine farm_sum(farm, x, error)
    type(analysis_farm_t), intent(in) :: farm
    real(wp), contiguous, intent(inout) :: x(:)
    type(error_t), allocatable, intent(out) :: error
    call farm%comm%sum(x, error)
  end subroutine farm_sum

  !> Element-wise maximum over all ranks, in place.
  subroutine farm_max(farm, x, error)
    type(analysis_farm_t), intent(in) :: farm
    real(wp), contiguous, intent(inout) :: x(:)
    type(error_t), allocatable, intent(out) :: error
    call farm%comm%max(x, error)
  end subroutine farm_max

  !> `any` is true on every rank when `flag` is true on any rank (true as well when the
  !> reduction itself failed, with `error` set).
  subroutine farm_any(farm, flag, any, error)
    type(analysis_farm_t), intent(in) :: farm
    logical, intent(in) :: flag
    logical, intent(out) :: any
    type(error_t), allocatable, intent(out) :: error
    integer :: v(1)
    v = merge(1, 0, flag)
    call farm%comm%max(v, error)
    any = v(1) > 0 .or. allocated(error)
  end subroutine farm_any

  !> Rank 0's list `x` on every rank (its size included): a decision taken once, on rank 0.
  subroutine farm_share(farm, x, error)
    type(analysis_farm_t), intent(in) :: farm
    integer(i8), allocatable, intent(inout) :: x(:)
    type(error_t), allocatable, intent(out) :: error
    call farm%comm%bcast(x, error)
  end subroutine farm_share

  !> True on every rank when `error` is set on any rank (a collective call: every rank makes it
  !> at the same point); a rank without an error of its own gets one naming `what`.
  logical function farm_failed(farm, error, what) result(failed)
    type(analysis_farm_t), intent(in) :: farm
    type(error_t), allocatable, intent(inout) :: error
    character(len=*), intent(in) :: what
    type(error_t), allocatable :: comm_error
    call farm_any(farm, allocated(error), failed, comm_error)
    if (allocated(comm_error) .and. .not. allocated(error)) call move_alloc(comm_error, error)
    if (failed .and. .not. allocated(error)) call fatal_error(error, what//': failed on another rank')
  end function farm_failed

end module kf_analysis_farm
