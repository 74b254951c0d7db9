!> Number-to-text conversion shared by the whole project (messages, logs, names), and C strings
!> as Fortran text.
module kf_strings
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use, intrinsic :: iso_c_binding, only: c_char, c_null_char, c_ptr, c_size_t, c_associated, c_f_pointer
  use kf_kinds, only: wp, i8
  implicit none
  private

  public :: to_str, to_str_fixed, to_str_short, to_str_exact
  public :: chars_to_string, c_string

  !> Text of a number without surrounding blanks: integers as `i0`, reals as `g0` or in the
  !> edit descriptor given as optional `fmt` (e.g. `'(es23.16e2)'`).
  interface to_str
    module procedure to_str_int, to_str_i8, to_str_real
  end interface to_str

  integer, parameter :: buf_len = 64

  interface
    function c_strlen(s) bind(c, name='strlen') result(n)
      import :: c_ptr, c_size_t
      type(c_ptr), value :: s
      integer(c_size_t) :: n
    end function c_strlen
  end interface

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

  !> The shortest text that reads back to exactly `x` (`g0.d` with the fewest significant
  !> digits d <= 17 that round-trip; trailing zeros removed; whole numbers below 1e15 as
  !> `10000000.0`): `2.201`, not `2.2010000000000001`.
  !> For messages that must tell apart values that differ only in their last digits.
  pure function to_str_exact(x) result(s)
    real(wp), intent(in) :: x
    character(len=:), allocatable :: s
    character(len=buf_len) :: buf
    character(len=16) :: edit
    real(wp) :: back
    integer :: digits, ios, e, k, decimals
    if (.not. ieee_is_finite(x)) then
      write (buf, '(g0)') x
      s = trim(adjustl(buf))
      return
    end if
    if (abs(x) < 1.0e15_wp .and. x == aint(x)) then
      write (buf, '(i0,a)') int(x, i8), '.0'
      s = trim(buf)
      return
    end if
    do digits = 1, 17
      write (edit, '(a,i0,a)') '(g0.', digits, ')'
      write (buf, edit) x
      read (buf, *, iostat=ios) back
      if (ios == 0 .and. back == x) exit
    end do
    if (abs(x) >= 1.0e-5_wp .and. abs(x) < 1.0e15_wp) then
      ! fixed notation with the decimals of those significant digits (0.0001, not 0.1E-3)
      decimals = max(1, digits - 1 - floor(log10(abs(x))))
      write (edit, '(a,i0,a)') '(f0.', decimals, ')'
      write (buf, edit) x
      read (buf, *, iostat=ios) back
      if (ios /= 0 .or. back /= x) write (buf, '(g0.17)') x
    end if
    s = trim(adjustl(buf))
    if (s(1:1) == '.') s = '0'//s
    if (s(1:2) == '-.') s = '-0'//s(2:)
    e = scan(s, 'eE')
    if (e == 0) e = len(s) + 1
    if (index(s(1:e - 1), '.') > 0) then
      k = e - 1
      do while (s(k:k) == '0')
        k = k - 1
      end do
      if (s(k:k) == '.') then
        s = s(1:k)//'0'//s(e:)
      else
        s = s(1:k)//s(e:)
      end if
    end if
  end function to_str_exact


  !> Bytes up to the first null as a string.
  pure function chars_to_string(buf) result(s)
    character(kind=c_char), intent(in) :: buf(:)
    character(len=:), allocatable :: s
    integer :: i, n
    n = size(buf)
    do i = 1, size(buf)
      if (buf(i) == c_null_char) then
        n = i - 1
        exit
      end if
    end do
    allocate (character(len=n) :: s)
    do i = 1, n
      s(i:i) = buf(i)
    end do
  end function chars_to_string

  !> Copy of a null-terminated C string.
  function c_string(p) result(s)
    type(c_ptr), intent(in) :: p
    character(len=:), allocatable :: s
    character(kind=c_char), pointer :: chars(:)
    integer :: n
    if (.not. c_associated(p)) then
      s = ''
      return
    end if
    n = int(c_strlen(p))
    call c_f_pointer(p, chars, [n])
    s = chars_to_string(chars)
  end function c_string

end module kf_strings
