!> Number-to-text conversion shared by the whole project (messages, logs, names).
module kf_strings
  use kf_kinds, only: wp, i8
  implicit none
  private

  public :: to_str, to_str_fixed, to_str_short

  !> Text of a number without surrounding blanks: integers as `i0`, reals as `g0` or in the
  !> edit descriptor given as optional `fmt` (e.g. `'(es23.16e2)'`).
  interface to_str
    module procedure to_str_int, to_str_i8, to_str_real
  end interface to_str

  integer, parameter :: buf_len = 64

contains

  !> Default integer as `i0`.
  pure function to_str_int(i) result(s)
    integer, intent(in) :: i
    character(len=:), allocatable :: s
    character(len=buf_len) :: buf
    write (buf, '(i0)') i
    s = trim(buf)
  end function to_str_int

  !> 64-bit integer as `i0`.
  pure function to_str_i8(i) result(s)
    integer(i8), intent(in) :: i
    character(len=:), allocatable :: s
    character(len=buf_len) :: buf
    write (buf, '(i0)') i
    s = trim(buf)
  end function to_str_i8

  !> Real as `g0`, or with the format `fmt` when given; leading and trailing blanks removed.
  pure function to_str_real(x, fmt) result(s)
    real(wp), intent(in) :: x
    character(len=*), intent(in), optional :: fmt
    character(len=:), allocatable :: s
    character(len=buf_len) :: buf
    if (present(fmt)) then
      write (buf, fmt) x
    else
      write (buf, '(g0)') x
    end if
    s = trim(adjustl(buf))
  end function to_str_real

  !> Real in fixed notation with `decimals` decimals (`f0.d`), with a leading zero for
  !> positive values below one (`0.50`, not `.50`).
  pure function to_str_fixed(x, decimals) result(s)
    real(wp), intent(in) :: x
    integer, intent(in) :: decimals
    character(len=:), allocatable :: s
    character(len=buf_len) :: buf
    character(len=16) :: edit
    write (edit, '(a,i0,a)') '(f0.', decimals, ')'
    write (buf, edit) x
    if (buf(1:1) == '.') then
      s = '0'//trim(buf)
    else
      s = trim(adjustl(buf))
    end if
  end function to_str_fixed

  !> Short text for progress lines: three decimals when 1e-3 <= |x| < 1e6, otherwise `es10.3`.
  pure function to_str_short(x) result(s)
    real(wp), intent(in) :: x
    character(len=:), allocatable :: s
    if (abs(x) >= 1.0e-3_wp .and. abs(x) < 1.0e6_wp) then
      s = to_str_fixed(x, 3)
    else
      s = to_str(x, '(es10.3)')
    end if
  end function to_str_short

end module kf_strings
