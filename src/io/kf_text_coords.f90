!> Plain-text coordinate files: one bead per line, `x y z`; blank lines and lines whose first
!> non-blank character is `#` are ignored.
module kf_text_coords
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  implicit none
  private

  public :: read_coordinates, write_coordinates

  integer, parameter :: line_len = 1024

contains

  !> Read bead centres from `path` into r(3, N). Errors name the file and the line.
  subroutine read_coordinates(path, r, error)
    character(len=*), intent(in) :: path
    real(wp), allocatable, intent(out) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer :: unit, stat, n, pass, line_no
    character(len=line_len) :: line
    character(len=256) :: msg
    real(wp) :: x(3)

    open (newunit=unit, file=path, status='old', action='read', iostat=stat, iomsg=msg)
    if (stat /= 0) then
      call fatal_error(error, "coordinates: cannot open '"//trim(path)//"': "//trim(msg))
      return
    end if
    ! Pass 1 counts and validates, pass 2 stores.
    do pass = 1, 2
      n = 0
      line_no = 0
      do
        read (unit, '(a)', iostat=stat, iomsg=msg) line
        if (is_iostat_end(stat)) exit
        line_no = line_no + 1
        if (stat /= 0) then
          call fatal_error(error, "coordinates: reading '"//trim(path)//"' line "//to_str(line_no)//": "//trim(msg))
          close (unit)
          return
        end if
        line = adjustl(line)
        if (len_trim(line) == 0) cycle
        if (line(1:1) == '#') cycle
        call parse_point(line, x, stat)
        if (stat /= 0) then
          call fatal_error(error, "coordinates: '"//trim(path)//"' line "//to_str(line_no)// &
            ": expected three numbers 'x y z', got '"//trim(line)//"'")
          close (unit)
          return
        end if
        n = n + 1
        if (pass == 2) r(:, n) = x
      end do
      if (pass == 1) then
        if (n == 0) then
          call fatal_error(error, "coordinates: '"//trim(path)//"' contains no points")
          close (unit)
          return
        end if
        allocate (r(3, n))
        rewind (unit)
      end if
    end do
    close (unit)
  end subroutine read_coordinates

  !> Parse exactly three reals from a line; stat /= 0 if there are fewer, more, or non-numbers.
  subroutine parse_point(line, x, stat)
    character(len=*), intent(in) :: line
    real(wp), intent(out) :: x(3)
    integer, intent(out) :: stat
    character(len=len(line)) :: rest
    integer :: k, pos
    rest = line
    do k = 1, 3
      rest = adjustl(rest)
      if (len_trim(rest) == 0) then
        stat = 1
        return
      end if
      pos = scan(rest, ' '//achar(9))
      if (pos == 0) pos = len(rest) + 1
      read (rest(1:pos - 1), *, iostat=stat) x(k)
      if (stat /= 0) return
      if (.not. ieee_is_finite(x(k))) then
        stat = 1
        return
      end if
      if (pos > len(rest)) then
        rest = ''
      else
        rest = rest(pos:)
      end if
    end do
    if (len_trim(rest) /= 0) then
      stat = 1
    else
      stat = 0
    end if
  end subroutine parse_point

  !> Write r(3, N) to `path`, one bead per line, full precision.
  subroutine write_coordinates(path, r, error)
    character(len=*), intent(in) :: path
    real(wp), intent(in) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer :: unit, stat, i
    character(len=256) :: msg
    open (newunit=unit, file=path, status='replace', action='write', iostat=stat, iomsg=msg)
    if (stat /= 0) then
      call fatal_error(error, "coordinates: cannot create '"//trim(path)//"': "//trim(msg))
      return
    end if
    write (unit, '(a,i0,a)', iostat=stat, iomsg=msg) '# knotflow coordinates: ', size(r, 2), ' beads, x y z'
    do i = 1, size(r, 2)
      if (stat /= 0) exit
      write (unit, '(3es25.16e3)', iostat=stat, iomsg=msg) r(:, i)
    end do
    if (stat /= 0) then
      call fatal_error(error, "coordinates: writing '"//trim(path)//"': "//trim(msg))
      close (unit)
      return
    end if
    close (unit, iostat=stat, iomsg=msg)
    if (stat /= 0) call fatal_error(error, "coordinates: closing '"//trim(path)//"': "//trim(msg))
  end subroutine write_coordinates

end module kf_text_coords
