!> Comma-separated tables with a header line of column names, one row per frame (the frame rows
!> of the case ledger, docs/analysis.md "The case ledger"): the named columns read as reals,
!> `nan` for a missing value. Errors name the file, the line and the column.
module kf_frame_table
  use kf_kinds, only: wp
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  implicit none
  private

  public :: read_table_columns

  integer, parameter :: line_len = 4096
  integer, parameter :: max_fields = 256

contains

  !> The columns `names` of the table `path` as values(rows, size(names)). Refused: a file that
  !> cannot be read, a missing column, a row whose number of fields differs from the header's, a
  !> field of a requested column that is not a number, a table without rows.
  subroutine read_table_columns(path, names, values, error)
    character(len=*), intent(in) :: path
    character(len=*), intent(in) :: names(:)
    real(wp), allocatable, intent(out) :: values(:, :)
    type(error_t), allocatable, intent(out) :: error
    character(len=line_len) :: line
    character(len=256) :: msg
    integer :: unit, stat, nrows, nfields, k, pass, line_no, col(size(names))
    integer :: first(max_fields), last(max_fields)

    open (newunit=unit, file=path, status='old', action='read', iostat=stat, iomsg=msg)
    if (stat /= 0) then
      call fatal_error(error, "table: cannot open '"//trim(path)//"': "//trim(msg))
      return
    end if
    read (unit, '(a)', iostat=stat, iomsg=msg) line
    if (stat /= 0) then
      call fatal_error(error, "table '"//trim(path)//"': no header line")
      close (unit)
      return
    end if
    call split(line, first, last, nfields)
    do k = 1, size(names)
      col(k) = find_column(line, first, last, nfields, names(k))
      if (col(k) == 0) then
        call fatal_error(error, "table '"//trim(path)//"': no column '"//trim(names(k))//"' in its header")
        close (unit)
        return
      end if
    end do
    ! Pass 1 counts and validates, pass 2 stores.
    do pass = 1, 2
      nrows = 0
      line_no = 1
      do
        read (unit, '(a)', iostat=stat, iomsg=msg) line
        if (is_iostat_end(stat)) exit
        line_no = line_no + 1
        if (stat /= 0) then
          call fatal_error(error, "table '"//trim(path)//"' line "//to_str(line_no)//": "//trim(msg))
          close (unit)
          return
        end if
        if (len_trim(line) == 0) cycle
        call split(line, first, last, k)
        if (k /= nfields) then
          call fatal_error(error, "table '"//trim(path)//"' line "//to_str(line_no)//": "//to_str(k)// &
            ' fields, the header has '//to_str(nfields))
          close (unit)
          return
        end if
        nrows = nrows + 1
        call read_fields(line_no, nrows, pass == 2)
        if (allocated(error)) then
          close (unit)
          return
        end if
      end do
      if (pass == 1) then
        if (nrows == 0) then
          call fatal_error(error, "table '"//trim(path)//"' has no rows")
          close (unit)
          return
        end if
        allocate (values(nrows, size(names)))
        rewind (unit)
        read (unit, '(a)') line
      end if
    end do
    close (unit)

  contains

    subroutine read_fields(line_no, row, store)
      integer, intent(in) :: line_no, row
      logical, intent(in) :: store
      real(wp) :: x
      integer :: j, ios
      do j = 1, size(names)
        read (line(first(col(j)):last(col(j))), *, iostat=ios) x
        if (ios /= 0 .or. last(col(j)) < first(col(j))) then
          call fatal_error(error, "table '"//trim(path)//"' line "//to_str(line_no)//", column '"// &
            trim(names(j))//"': '"//line(first(col(j)):last(col(j)))//"' is not a number")
          return
        end if
        if (store) values(row, j) = x
      end do
    end subroutine read_fields

  end subroutine read_table_columns

  !> Field k of `line` is line(first(k):last(k)) (blanks around it excluded; empty: last < first).
  subroutine split(line, first, last, n)
    character(len=*), intent(in) :: line
    integer, intent(out) :: first(:), last(:), n
    integer :: start, comma
    n = 0
    start = 1
    do
      comma = index(line(start:), ',')
      n = n + 1
      if (n > size(first)) then
        n = size(first) + 1   ! more fields than anyone asks for: refused as a count mismatch
        return
      end if
      if (comma == 0) then
        call trim_field(start, len_trim(line))
        return
      end if
      call trim_field(start, start + comma - 2)
      start = start + comma
    end do
  contains
    subroutine trim_field(a, b)
      integer, intent(in) :: a, b
      integer :: i, j
      i = a
      j = b
      do while (i <= j)
        if (line(i:i) /= ' ') exit
        i = i + 1
      end do
      do while (j >= i)
        if (line(j:j) /= ' ') exit
        j = j - 1
      end do
      first(n) = i
      last(n) = j
    end subroutine trim_field
  end subroutine split

  pure integer function find_column(line, first, last, n, name) result(k)
    character(len=*), intent(in) :: line, name
    integer, intent(in) :: first(:), last(:), n
    do k = 1, min(n, size(first))
      if (line(first(k):last(k)) == trim(name)) return
    end do
    k = 0
  end function find_column

end module kf_frame_table
