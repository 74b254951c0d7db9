!> The root attributes a case file is created with: a list of named values (e.g. every
!> effective scene variable as '<group>.<variable>') collected by the caller and written by
!> `write_attributes` (kf_case_file's `create`). Logical values are stored as int32 attributes
!> (1 true, 0 false): HDF5 has no boolean type (h5py's is an enum), and an integer reads
!> naturally in every tool. The status attribute is written through `status_value`.
module kf_case_attributes
  use kf_kinds, only: wp, i4, i8
  use kf_error, only: error_t, fatal_error
  use kf_h5, only: h5_file_t, h5_write_attr
  implicit none
  private

  public :: write_attributes, status_value

  !> The status attribute is stored with at least this many bytes (null-padded), so that
  !> 'running' and 'finished' replace each other in place (a kill while the root object header
  !> is flushed then leaves one or the other, never no status).
  integer, parameter :: status_capacity = 64

  integer, parameter :: kind_str = 1, kind_i4 = 2, kind_i8 = 3, kind_real = 4, kind_real1 = 5, &
    kind_real2 = 6

  !> One named attribute value of any of the supported kinds.
  type :: attribute_t
    character(len=:), allocatable :: name
    integer :: kind = 0
    character(len=:), allocatable :: str
    integer(i4) :: ival = 0
    integer(i8) :: lval = 0
    real(wp) :: rval = 0.0_wp
    real(wp), allocatable :: r1(:), r2(:, :)
  end type attribute_t

  !> A list of named values (e.g. every effective scene variable as '<group>.<variable>')
  !> collected by the caller and written as root attributes by `case_file_t%create`.
  type, public :: attribute_list_t
    private
    type(attribute_t), allocatable :: items(:)
    integer :: n = 0
  contains
    !> Add (name, value): character string, int32, int64, real(wp), logical (stored as int32
    !> 1/0), 1-D or 2-D real(wp) array.
    generic :: add => add_str, add_i4, add_i8, add_real, add_logical, add_real1, add_real2
    procedure :: count => list_count
    procedure, private :: add_str, add_i4, add_i8, add_real, add_logical, add_real1, add_real2
    procedure, private :: push
  end type attribute_list_t

contains

  subroutine push(this, item)
    class(attribute_list_t), intent(inout) :: this
    type(attribute_t), intent(in) :: item
    type(attribute_t), allocatable :: tmp(:)
    if (.not. allocated(this%items)) allocate (this%items(16))
    if (this%n == size(this%items)) then
      allocate (tmp(2*this%n))
      tmp(1:this%n) = this%items(1:this%n)
      call move_alloc(tmp, this%items)
    end if
    this%n = this%n + 1
    this%items(this%n) = item
  end subroutine push

  subroutine add_str(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name, value
    type(attribute_t) :: item
    item%name = name
    item%kind = kind_str
    item%str = value
    call this%push(item)
  end subroutine add_str

  subroutine add_i4(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer(i4), intent(in) :: value
    type(attribute_t) :: item
    item%name = name
    item%kind = kind_i4
    item%ival = value
    call this%push(item)
  end subroutine add_i4

  subroutine add_i8(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer(i8), intent(in) :: value
    type(attribute_t) :: item
    item%name = name
    item%kind = kind_i8
    item%lval = value
    call this%push(item)
  end subroutine add_i8

  subroutine add_real(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value
    type(attribute_t) :: item
    item%name = name
    item%kind = kind_real
    item%rval = value
    call this%push(item)
  end subroutine add_real

  subroutine add_logical(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    logical, intent(in) :: value
    call this%add_i4(name, merge(1_i4, 0_i4, value))
  end subroutine add_logical

  subroutine add_real1(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value(:)
    type(attribute_t) :: item
    item%name = name
    item%kind = kind_real1
    item%r1 = value
    call this%push(item)
  end subroutine add_real1

  subroutine add_real2(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value(:, :)
    type(attribute_t) :: item
    item%name = name
    item%kind = kind_real2
    item%r2 = value
    call this%push(item)
  end subroutine add_real2

  !> Number of entries in the list.
  pure integer function list_count(this)
    class(attribute_list_t), intent(in) :: this
    list_count = this%n
  end function list_count

  !> Write every entry of `list` as a root attribute of the open file.
  subroutine write_attributes(file, list, error)
    type(h5_file_t), intent(in) :: file
    type(attribute_list_t), intent(in) :: list
    type(error_t), allocatable, intent(out) :: error
    integer :: i
    do i = 1, list%n
      call write_item(file, list%items(i), error)
      if (allocated(error)) return
    end do
  end subroutine write_attributes

  subroutine write_item(file, item, error)
    type(h5_file_t), intent(in) :: file
    type(attribute_t), intent(in) :: item
    type(error_t), allocatable, intent(out) :: error
    select case (item%kind)
    case (kind_str)
      call h5_write_attr(file, '/', item%name, item%str, error)
    case (kind_i4)
      call h5_write_attr(file, '/', item%name, item%ival, error)
    case (kind_i8)
      call h5_write_attr(file, '/', item%name, item%lval, error)
    case (kind_real)
      call h5_write_attr(file, '/', item%name, item%rval, error)
    case (kind_real1)
      call h5_write_attr(file, '/', item%name, item%r1, error)
    case (kind_real2)
      call h5_write_attr(file, '/', item%name, item%r2, error)
    case default
      call fatal_error(error, "case file: attribute '"//item%name//"' has no value")
    end select
  end subroutine write_item

  !> `text` null-padded to `status_capacity` bytes (readers stop at the first null).
  pure function status_value(text) result(value)
    character(len=*), intent(in) :: text
    character(len=max(len(text), status_capacity)) :: value
    value = repeat(achar(0), len(value))
    value(1:len(text)) = text
  end function status_value

end module kf_case_attributes
