!> The communication layer for one process without MPI (-DKNOTFLOW_WITH_MPI=OFF): the interface
!> of src/parallel/kf_comm.f90 on a world of one rank. Broadcasts and reductions leave the
!> values as they are (the result of one rank), a split or dup gives the same single rank, and
!> the shared counters are plain local counters. A root other than 0 is refused, as MPI would.
module kf_comm
  use, intrinsic :: iso_fortran_env, only: int64
  use kf_kinds, only: wp, i8
  use kf_error, only: error_t, fatal_error
  use kf_exit, only: exit_program
  implicit none
  private

  public :: comm_init, comm_finalize, comm_world, comm_from_handle

  !> A communicator (always the one rank of this process).
  type, public :: comm_t
    private
    integer :: handle = 0
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
    generic :: bcast => bcast_int, bcast_i8, bcast_real, bcast_logical, bcast_str, bcast_i8_list
    generic :: sum => sum_int, sum_int1, sum_real1
    generic :: max => max_int1, max_real, max_real1
    generic :: min => min_real
    procedure :: merge_bytes
    procedure, private :: bcast_int, bcast_i8, bcast_real, bcast_logical, bcast_str, bcast_i8_list
    procedure, private :: sum_int, sum_int1, sum_real1, max_int1, max_real, max_real1, min_real
  end type comm_t

  !> Counters (int64) of this process.
  type, public :: shared_counter_t
    private
    integer(int64), allocatable :: counters(:)
  contains
    procedure :: create => counter_create
    procedure :: fetch_add => counter_fetch_add
    procedure :: free => counter_free
  end type shared_counter_t

contains

  subroutine comm_init(comm, error)
    type(comm_t), intent(out) :: comm
    type(error_t), allocatable, intent(out) :: error
    comm%handle = 0
  end subroutine comm_init

  subroutine comm_finalize(error)
    type(error_t), allocatable, intent(out) :: error
  end subroutine comm_finalize

  function comm_world() result(comm)
    type(comm_t) :: comm
    comm%handle = 0
  end function comm_world

  function comm_from_handle(handle) result(comm)
    integer, intent(in) :: handle
    type(comm_t) :: comm
    comm%handle = handle
  end function comm_from_handle

  integer function comm_rank(this)
    class(comm_t), intent(in) :: this
    comm_rank = 0
  end function comm_rank

  integer function comm_size(this)
    class(comm_t), intent(in) :: this
    comm_size = 1
  end function comm_size

  integer function comm_ranks_on_node(this) result(n)
    class(comm_t), intent(in) :: this
    n = 1
  end function comm_ranks_on_node

  subroutine comm_split(this, color, key, new, error)
    class(comm_t), intent(in) :: this
    integer, intent(in) :: color, key
    type(comm_t), intent(out) :: new
    type(error_t), allocatable, intent(out) :: error
    new = this
  end subroutine comm_split

  subroutine comm_dup(this, new, error)
    class(comm_t), intent(in) :: this
    type(comm_t), intent(out) :: new
    type(error_t), allocatable, intent(out) :: error
    new = this
  end subroutine comm_dup

  subroutine comm_free(this, error)
    class(comm_t), intent(inout) :: this
    type(error_t), allocatable, intent(out) :: error
  end subroutine comm_free

  subroutine comm_return_errors(this, error)
    class(comm_t), intent(in) :: this
    type(error_t), allocatable, intent(out) :: error
  end subroutine comm_return_errors

  subroutine comm_barrier(this, error)
    class(comm_t), intent(in) :: this
    type(error_t), allocatable, intent(out) :: error
  end subroutine comm_barrier

  !> End the process with exit code `code` (for programs only).
  subroutine comm_abort(this, code)
    class(comm_t), intent(in) :: this
    integer, intent(in) :: code
    call exit_program(code)
  end subroutine comm_abort

  !> Rank 0 is the only root.
  subroutine check_root(what, error, root)
    character(len=*), intent(in) :: what
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: root
    if (present(root)) then
      if (root /= 0) call fatal_error(error, 'broadcast ('//what//'): invalid root (one rank)')
    end if
  end subroutine check_root

  subroutine bcast_int(this, value, error, root)
    class(comm_t), intent(in) :: this
    integer, intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: root
    call check_root('integer', error, root)
  end subroutine bcast_int

  subroutine bcast_i8(this, value, error, root)
    class(comm_t), intent(in) :: this
    integer(i8), intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: root
    call check_root('int64', error, root)
  end subroutine bcast_i8

  subroutine bcast_real(this, value, error, root)
    class(comm_t), intent(in) :: this
    real(wp), intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: root
    call check_root('real', error, root)
  end subroutine bcast_real

  subroutine bcast_logical(this, value, error, root)
    class(comm_t), intent(in) :: this
    logical, intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: root
    call check_root('logical', error, root)
  end subroutine bcast_logical

  subroutine bcast_str(this, value, error, root)
    class(comm_t), intent(in) :: this
    character(len=:), allocatable, intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: root
    call check_root('string', error, root)
    if (.not. allocated(value)) allocate (character(len=0) :: value)
  end subroutine bcast_str

  subroutine bcast_i8_list(this, values, error, root)
    class(comm_t), intent(in) :: this
    integer(i8), allocatable, intent(inout) :: values(:)
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: root
    call check_root('int64 list', error, root)
    if (.not. allocated(values)) allocate (values(0))
  end subroutine bcast_i8_list

  subroutine sum_int(this, value, error)
    class(comm_t), intent(in) :: this
    integer, intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
  end subroutine sum_int

  subroutine sum_int1(this, values, error)
    class(comm_t), intent(in) :: this
    integer, intent(inout) :: values(:)
    type(error_t), allocatable, intent(out) :: error
  end subroutine sum_int1

  subroutine sum_real1(this, values, error)
    class(comm_t), intent(in) :: this
    real(wp), intent(inout) :: values(:)
    type(error_t), allocatable, intent(out) :: error
  end subroutine sum_real1

  subroutine max_int1(this, values, error)
    class(comm_t), intent(in) :: this
    integer, intent(inout) :: values(:)
    type(error_t), allocatable, intent(out) :: error
  end subroutine max_int1

  subroutine max_real(this, value, error)
    class(comm_t), intent(in) :: this
    real(wp), intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
  end subroutine max_real

  subroutine max_real1(this, values, error)
    class(comm_t), intent(in) :: this
    real(wp), intent(inout) :: values(:)
    type(error_t), allocatable, intent(out) :: error
  end subroutine max_real1

  subroutine min_real(this, value, error)
    class(comm_t), intent(in) :: this
    real(wp), intent(inout) :: value
    type(error_t), allocatable, intent(out) :: error
  end subroutine min_real

  subroutine merge_bytes(this, buffer, error)
    class(comm_t), intent(in) :: this
    character(len=*), intent(inout) :: buffer(:)
    type(error_t), allocatable, intent(out) :: error
  end subroutine merge_bytes

  subroutine counter_create(this, comm, n, error)
    class(shared_counter_t), intent(inout) :: this
    type(comm_t), intent(in) :: comm
    integer, intent(in) :: n
    type(error_t), allocatable, intent(out) :: error
    if (allocated(this%counters)) deallocate (this%counters)
    allocate (this%counters(n))
    this%counters = 0
  end subroutine counter_create

  subroutine counter_fetch_add(this, i, increment, old, error)
    class(shared_counter_t), intent(inout) :: this
    integer, intent(in) :: i
    integer(i8), intent(in) :: increment
    integer(i8), intent(out) :: old
    type(error_t), allocatable, intent(out) :: error
    old = -1
    if (.not. allocated(this%counters)) then
      call fatal_error(error, 'shared counter: no such counter or window not created')
      return
    end if
    if (i < 1 .or. i > size(this%counters)) then
      call fatal_error(error, 'shared counter: no such counter or window not created')
      return
    end if
    old = this%counters(i)
    this%counters(i) = this%counters(i) + increment
  end subroutine counter_fetch_add

  subroutine counter_free(this, error)
    class(shared_counter_t), intent(inout) :: this
    type(error_t), allocatable, intent(out) :: error
    if (allocated(this%counters)) deallocate (this%counters)
  end subroutine counter_free

end module kf_comm
