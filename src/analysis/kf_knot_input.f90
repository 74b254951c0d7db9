!> Text coordinate files for the knot tools: one point per line, `x y z`; blank lines and lines
!> starting with `#` are ignored.
module kf_knot_input
  use kf_kinds, only: wp
  use kf_error, only: error_t, fatal_error
  implicit none
  private

  public :: read_points

contains

  !> Read the points of `path` into p(3, n).
  subroutine read_points(path, p, error)
    character(len=*), intent(in) :: path
    real(wp), allocatable, intent(out) :: p(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer :: unit, stat, n, lineno
    character(len=1024) :: line, msg
    real(wp), allocatable :: tmp(:, :)
    real(wp) :: x(3)
    character(len=24) :: buf
    open (newunit=unit, file=path, status='old', action='read', iostat=stat, iomsg=msg)
    if (stat /= 0) then
      call fatal_error(error, 'cannot open '//trim(path)//': '//trim(msg))
      return
    end if
    allocate (tmp(3, 256))
    n = 0
    lineno = 0
    do
      read (unit, '(a)', iostat=stat, iomsg=msg) line
      if (stat /= 0) exit
      lineno = lineno + 1
      line = adjustl(line)
      if (len_trim(line) == 0 .or. line(1:1) == '#') cycle
      read (line, *, iostat=stat) x
      if (stat /= 0) then
        write (buf, '(i0)') lineno
        call fatal_error(error, trim(path)//', line '//trim(buf)//': expected three numbers "x y z", got "'// &
          trim(line)//'"')
        close (unit)
        return
      end if
      n = n + 1
      if (n > size(tmp, 2)) call grow(tmp)
      tmp(:, n) = x
    end do
    close (unit)
    if (n == 0) then
      call fatal_error(error, trim(path)//': no points found')
      return
    end if
    p = tmp(:, 1:n)
  end subroutine read_points

  subroutine grow(a)
    real(wp), allocatable, intent(inout) :: a(:, :)
    real(wp), allocatable :: b(:, :)
    allocate (b(3, 2*size(a, 2)))
    b(:, 1:size(a, 2)) = a
    call move_alloc(b, a)
  end subroutine grow

end module kf_knot_input
