!> The only module of knotflow that uses MPI (mpi_f08): start-up and shutdown, rank and size,
!> barrier, abort, the small broadcasts and reductions the sweep driver needs, and a shared
!> counter (one-sided MPI_Fetch_and_op on a window owned by rank 0) for dynamic load balancing.
!>
!> Every MPI call passes `ierror` and a non-zero value becomes an `error_t` naming the call.
!> Error handler: the programs keep MPI's default, MPI_ERRORS_ARE_FATAL, on MPI_COMM_WORLD (a
!> failed collective cannot be recovered on one rank while the others wait in it, so MPI aborts
!> the job with its own message); `return_errors` installs MPI_ERRORS_RETURN on a communicator,
!> and then every failed call comes back as an error (tests/mpi/test_comm.pf checks that path).
!>
!> src/parallel/serial/kf_comm.f90 is the same interface for one rank without MPI
!> (-DKNOTFLOW_WITH_MPI=OFF); everything else in src/parallel uses MPI only through this module.
module kf_comm
  use, intrinsic :: iso_c_binding, only: c_ptr, c_f_pointer
  use, intrinsic :: iso_fortran_env, only: int64
  use kf_kinds, only: wp, i8
  use kf_error, only: error_t, fatal_error
  use mpi_f08, only: MPI_Comm, MPI_Win, MPI_COMM_WORLD, MPI_Init, MPI_Initialized, MPI_Finalize, &
    MPI_Finalized, MPI_Comm_rank, MPI_Comm_size, MPI_Barrier, MPI_Abort, MPI_Bcast, MPI_Allreduce, &
    MPI_Win_allocate, MPI_Win_free, MPI_Win_lock, MPI_Win_unlock, MPI_Fetch_and_op, &
    MPI_INTEGER, MPI_INTEGER8, MPI_DOUBLE_PRECISION, MPI_LOGICAL, MPI_CHARACTER, MPI_BYTE, &
    MPI_SUM, MPI_MAX, MPI_MIN, MPI_BOR, MPI_INFO_NULL, MPI_LOCK_SHARED, MPI_LOCK_EXCLUSIVE, &
    MPI_ADDRESS_KIND, MPI_IN_PLACE, MPI_Comm_split_type, MPI_COMM_TYPE_SHARED, MPI_Comm_free, &
    MPI_Comm_split, MPI_Comm_dup, MPI_Comm_set_errhandler, MPI_ERRORS_RETURN
  implicit none
  private

  public :: comm_init, comm_finalize, comm_world, comm_from_handle

  !> A communicator.
  type, public :: comm_t
    private
    type(MPI_Comm) :: comm
  contains
    procedure :: rank => comm_rank
    procedure :: size => comm_size
    procedure :: barrier => comm_barrier
    procedure :: abort => comm_abort
    procedure :: ranks_on_node => comm_ranks_on_node
    procedure :: split => comm_split
    procedure :: dup => comm_dup
    procedure :: free => comm_free
    procedure :: return_errors => comm_return_errors
    !> Broadcast from rank `root` (default 0): integer, int64, real(wp), logical, string
    !> (allocatable; its length travels with it), int64 list (allocatable; its size travels).
    generic :: bcast => bcast_int, bcast_i8, bcast_real, bcast_logical, bcast_str, bcast_i8_list
    !> Element-wise sum / maximum / minimum over all ranks, result on every rank.
    generic :: sum => sum_int, sum_int1, sum_real1
    generic :: max => max_int1, max_real, max_real1
    generic :: min => min_real
    procedure :: merge_bytes
    procedure, private :: bcast_int, bcast_i8, bcast_real, bcast_logical, bcast_str, bcast_i8_list
    procedure, private :: sum_int, sum_int1, sum_real1, max_int1, max_real, max_real1, min_real
  end type comm_t

  !> Counters (int64) in a window owned by rank 0 of a communicator, incremented atomically
  !> by any rank with MPI_Fetch_and_op under a passive-target lock. Create and free are
  !> collective.
  type, public :: shared_counter_t
    private
    type(MPI_Win) :: win
    integer :: n = 0
    logical :: active = .false.
  contains
    procedure :: create => counter_create
    procedure :: fetch_add => counter_fetch_add
    procedure :: free => counter_free
  end type shared_counter_t

contains

  !> Initialise MPI (unless already initialised) and return MPI_COMM_WORLD.
  subroutine comm_init(comm, error)
    type(comm_t), intent(out) :: comm
    type(error_t), allocatable, intent(out) :: error
    logical :: done
    integer :: ierr
    call MPI_Initialized(done, ierr)
    if (ierr /= 0) then
      call fatal_error(error, 'MPI_Initialized failed')
      return
    end if
    if (.not. done) then
      call MPI_Init(ierr)
      if (ierr /= 0) then
        call fatal_error(error, 'MPI_Init failed')
        return
      end if
    end if
    comm%comm = MPI_COMM_WORLD
  end subroutine comm_init

  !> Finalise MPI (unless already finalised).
  subroutine comm_finalize(error)
    type(error_t), allocatable, intent(out) :: error
    logical :: done
    integer :: ierr
    call MPI_Finalized(done, ierr)
    if (ierr == 0 .and. .not. done) call MPI_Finalize(ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Finalize failed')
  end subroutine comm_finalize

  !> MPI_COMM_WORLD (MPI must be initialised).
  function comm_world() result(comm)
    type(comm_t) :: comm
    comm%comm = MPI_COMM_WORLD
  end function comm_world

  !> A communicator from its Fortran integer handle (e.g. pFUnit's getMpiCommunicator()).
  function comm_from_handle(handle) result(comm)
    integer, intent(in) :: handle
    type(comm_t) :: comm
    comm%comm%mpi_val = handle
  end function comm_from_handle

  integer function comm_rank(this)
    class(comm_t), intent(in) :: this
    integer :: ierr
    call MPI_Comm_rank(this%comm, comm_rank, ierr)
    if (ierr /= 0) comm_rank = -1
  end function comm_rank

  integer function comm_size(this)
    class(comm_t), intent(in) :: this
    integer :: ierr
    call MPI_Comm_size(this%comm, comm_size, ierr)
    if (ierr /= 0) comm_size = -1
  end function comm_size

  !> Number of ranks of this communicator on this rank's node (shared memory); 1 on failure.
  integer function comm_ranks_on_node(this) result(n)
    class(comm_t), intent(in) :: this
    type(MPI_Comm) :: node
    integer :: ierr
    n = 1
    call MPI_Comm_split_type(this%comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, node, ierr)
    if (ierr /= 0) return
    call MPI_Comm_size(node, n, ierr)
    if (ierr /= 0) n = 1
    call MPI_Comm_free(node, ierr)
  end function comm_ranks_on_node

  !> Collective: the ranks with the same `color` (>= 0) form `new`, ordered by `key`.
  subroutine comm_split(this, color, key, new, error)
    class(comm_t), intent(in) :: this
    integer, intent(in) :: color, key
    type(comm_t), intent(out) :: new
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    call MPI_Comm_split(this%comm, color, key, new%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Comm_split failed')
  end subroutine comm_split

  !> Collective: a new communicator with the same ranks (own error handler, own messages).
  subroutine comm_dup(this, new, error)
    class(comm_t), intent(in) :: this
    type(comm_t), intent(out) :: new
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    call MPI_Comm_dup(this%comm, new%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Comm_dup failed')
  end subroutine comm_dup

  !> Collective: free a communicator made by `split` or `dup`.
  subroutine comm_free(this, error)
    class(comm_t), intent(inout) :: this
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    call MPI_Comm_free(this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Comm_free failed')
  end subroutine comm_free

  !> Failed MPI calls on this communicator return their error (MPI_ERRORS_RETURN) instead of
  !> aborting the job.
  subroutine comm_return_errors(this, error)
    class(comm_t), intent(in) :: this
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    call MPI_Comm_set_errhandler(this%comm, MPI_ERRORS_RETURN, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Comm_set_errhandler failed')
  end subroutine comm_return_errors

  subroutine comm_barrier(this, error)
    class(comm_t), intent(in) :: this
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    call MPI_Barrier(this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Barrier failed')
  end subroutine comm_barrier

  !> Abort all ranks with exit code `code` (for programs only).
  subroutine comm_abort(this, code)
    class(comm_t), intent(in) :: this
    integer, intent(in) :: code
    integer :: ierr
    call MPI_Abort(this%comm, code, ierr)
  end subroutine comm_abort

  subroutine bcast_int(this, value, error, root)
    class(comm_t), intent(in) :: this
    integer, intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: root
    integer :: ierr
    call MPI_Bcast(value, 1, MPI_INTEGER, root_of(root), this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Bcast (integer) failed')
  end subroutine bcast_int

  subroutine bcast_i8(this, value, error, root)
    class(comm_t), intent(in) :: this
    integer(i8), intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: root
    integer :: ierr
    call MPI_Bcast(value, 1, MPI_INTEGER8, root_of(root), this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Bcast (int64) failed')
  end subroutine bcast_i8

  subroutine bcast_real(this, value, error, root)
    class(comm_t), intent(in) :: this
    real(wp), intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: root
    integer :: ierr
    call MPI_Bcast(value, 1, MPI_DOUBLE_PRECISION, root_of(root), this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Bcast (real) failed')
  end subroutine bcast_real

  subroutine bcast_logical(this, value, error, root)
    class(comm_t), intent(in) :: this
    logical, intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: root
    integer :: ierr
    call MPI_Bcast(value, 1, MPI_LOGICAL, root_of(root), this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Bcast (logical) failed')
  end subroutine bcast_logical

  !> Broadcast a string; on the other ranks `value` is (re)allocated to the root's length.
  subroutine bcast_str(this, value, error, root)
    class(comm_t), intent(in) :: this
    character(len=:), allocatable, intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: root
    integer :: n, ierr
    n = 0
    if (this%rank() == root_of(root)) then
      if (allocated(value)) n = len(value)
    end if
    call MPI_Bcast(n, 1, MPI_INTEGER, root_of(root), this%comm, ierr)
    if (ierr /= 0) then
      call fatal_error(error, 'MPI_Bcast (string length) failed')
      return
    end if
    if (this%rank() /= root_of(root)) then
      if (allocated(value)) deallocate (value)
      allocate (character(len=n) :: value)
    else if (.not. allocated(value)) then
      allocate (character(len=0) :: value)
    end if
    if (n == 0) return
    call MPI_Bcast(value, n, MPI_CHARACTER, root_of(root), this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Bcast (string) failed')
  end subroutine bcast_str

  !> Broadcast an int64 list; on the other ranks `values` is (re)allocated to the root's size.
  subroutine bcast_i8_list(this, values, error, root)
    class(comm_t), intent(in) :: this
    integer(i8), allocatable, intent(inout) :: values(:)
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: root
    integer :: n, ierr
    n = 0
    if (this%rank() == root_of(root)) then
      if (allocated(values)) n = size(values)
    end if
    call MPI_Bcast(n, 1, MPI_INTEGER, root_of(root), this%comm, ierr)
    if (ierr /= 0) then
      call fatal_error(error, 'MPI_Bcast (list size) failed')
      return
    end if
    if (this%rank() /= root_of(root)) then
      if (allocated(values)) deallocate (values)
      allocate (values(n))
    else if (.not. allocated(values)) then
      allocate (values(0))
    end if
    if (n == 0) return
    call MPI_Bcast(values, n, MPI_INTEGER8, root_of(root), this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Bcast (int64 list) failed')
  end subroutine bcast_i8_list

  subroutine sum_int(this, value, error)
    class(comm_t), intent(in) :: this
    integer, intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    call MPI_Allreduce(MPI_IN_PLACE, value, 1, MPI_INTEGER, MPI_SUM, this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Allreduce (sum) failed')
  end subroutine sum_int

  subroutine sum_int1(this, values, error)
    class(comm_t), intent(in) :: this
    integer, intent(inout) :: values(:)
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    if (size(values) == 0) return
    call MPI_Allreduce(MPI_IN_PLACE, values, size(values), MPI_INTEGER, MPI_SUM, this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Allreduce (sum) failed')
  end subroutine sum_int1

  subroutine sum_real1(this, values, error)
    class(comm_t), intent(in) :: this
    real(wp), intent(inout) :: values(:)
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    if (size(values) == 0) return
    call MPI_Allreduce(MPI_IN_PLACE, values, size(values), MPI_DOUBLE_PRECISION, MPI_SUM, this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Allreduce (sum) failed')
  end subroutine sum_real1

  subroutine max_real1(this, values, error)
    class(comm_t), intent(in) :: this
    real(wp), intent(inout) :: values(:)
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    if (size(values) == 0) return
    call MPI_Allreduce(MPI_IN_PLACE, values, size(values), MPI_DOUBLE_PRECISION, MPI_MAX, this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Allreduce (max) failed')
  end subroutine max_real1

  subroutine max_int1(this, values, error)
    class(comm_t), intent(in) :: this
    integer, intent(inout) :: values(:)
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    if (size(values) == 0) return
    call MPI_Allreduce(MPI_IN_PLACE, values, size(values), MPI_INTEGER, MPI_MAX, this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Allreduce (max) failed')
  end subroutine max_int1

  subroutine max_real(this, value, error)
    class(comm_t), intent(in) :: this
    real(wp), intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    call MPI_Allreduce(MPI_IN_PLACE, value, 1, MPI_DOUBLE_PRECISION, MPI_MAX, this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Allreduce (max) failed')
  end subroutine max_real

  subroutine min_real(this, value, error)
    class(comm_t), intent(in) :: this
    real(wp), intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    call MPI_Allreduce(MPI_IN_PLACE, value, 1, MPI_DOUBLE_PRECISION, MPI_MIN, this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Allreduce (min) failed')
  end subroutine min_real

  !> Bitwise OR of character buffers over all ranks (MPI_BOR on MPI_BYTE): when every byte
  !> is NUL on all ranks but one, the result is that rank's byte, so disjoint pieces of text
  !> written by different ranks into NUL-filled buffers are merged everywhere.
  subroutine merge_bytes(this, buffer, error)
    class(comm_t), intent(in) :: this
    character(len=*), intent(inout) :: buffer(:)
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    if (size(buffer) == 0 .or. len(buffer) == 0) return
    call MPI_Allreduce(MPI_IN_PLACE, buffer, size(buffer)*len(buffer), MPI_BYTE, MPI_BOR, this%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Allreduce (bor) failed')
  end subroutine merge_bytes

  pure integer function root_of(root)
    integer, intent(in), optional :: root
    root_of = 0
    if (present(root)) root_of = root
  end function root_of

  ! ---------------------------------------------------------------- shared counter

  !> Collective: create `n` counters, all zero, in a window owned by rank 0 of `comm`.
  subroutine counter_create(this, comm, n, error)
    class(shared_counter_t), intent(inout) :: this
    type(comm_t), intent(in) :: comm
    integer, intent(in) :: n
    type(error_t), allocatable, intent(out) :: error
    integer(MPI_ADDRESS_KIND) :: bytes
    type(c_ptr) :: base
    integer(int64), pointer :: counters(:)
    integer :: ierr, disp_unit
    disp_unit = storage_size(0_int64)/8
    bytes = 0
    if (comm%rank() == 0) bytes = int(n, MPI_ADDRESS_KIND)*disp_unit
    call MPI_Win_allocate(bytes, disp_unit, MPI_INFO_NULL, comm%comm, base, this%win, ierr)
    if (ierr /= 0) then
      call fatal_error(error, 'MPI_Win_allocate failed')
      return
    end if
    this%n = n
    this%active = .true.
    if (comm%rank() == 0) then
      ! Local stores to the window inside an exclusive lock epoch on the own rank.
      call MPI_Win_lock(MPI_LOCK_EXCLUSIVE, 0, 0, this%win, ierr)
      if (ierr == 0) then
        call c_f_pointer(base, counters, [n])
        counters = 0
        call MPI_Win_unlock(0, this%win, ierr)
      end if
      if (ierr /= 0) then
        call fatal_error(error, 'initialising the shared counter window failed')
        return
      end if
    end if
    ! Nobody may increment before rank 0 has zeroed the counters.
    call MPI_Barrier(comm%comm, ierr)
    if (ierr /= 0) call fatal_error(error, 'MPI_Barrier failed')
  end subroutine counter_create

  !> Atomically add `increment` to counter `i` (1-based) and return its previous value.
  subroutine counter_fetch_add(this, i, increment, old, error)
    class(shared_counter_t), intent(inout) :: this
    integer, intent(in) :: i
    integer(i8), intent(in) :: increment
    integer(i8), intent(out) :: old
    type(error_t), allocatable, intent(out) :: error
    integer(int64), asynchronous :: inc, res
    integer :: ierr
    old = -1
    if (.not. this%active .or. i < 1 .or. i > this%n) then
      call fatal_error(error, 'shared counter: no such counter or window not created')
      return
    end if
    inc = increment
    res = -1
    call MPI_Win_lock(MPI_LOCK_SHARED, 0, 0, this%win, ierr)
    if (ierr /= 0) then
      call fatal_error(error, 'MPI_Win_lock failed')
      return
    end if
    call MPI_Fetch_and_op(inc, res, MPI_INTEGER8, 0, int(i - 1, MPI_ADDRESS_KIND), MPI_SUM, this%win, ierr)
    if (ierr /= 0) then
      call fatal_error(error, 'MPI_Fetch_and_op failed')
      return
    end if
    call MPI_Win_unlock(0, this%win, ierr)
    if (ierr /= 0) then
      call fatal_error(error, 'MPI_Win_unlock failed')
      return
    end if
    old = res
  end subroutine counter_fetch_add

  !> Collective: free the window.
  subroutine counter_free(this, error)
    class(shared_counter_t), intent(inout) :: this
    type(error_t), allocatable, intent(out) :: error
    integer :: ierr
    if (.not. this%active) return
    call MPI_Win_free(this%win, ierr)
    this%active = .false.
    if (ierr /= 0) call fatal_error(error, 'MPI_Win_free failed')
  end subroutine counter_free

end module kf_comm
