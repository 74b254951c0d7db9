!> Plain-text coordinate files: one bead per line, `x y z`. The rules (docs/inputs.md), the same
!> as knotflow-kf's reader (knotflow_tools.io.read_xyz): blanks are spaces, tabs and carriage
!> returns; blank lines and lines whose first non-blank character is `#` are ignored; a UTF-8
!> byte-order mark at the start of the file is skipped; every other line holds exactly three
!> whole numbers `[+-]digits[.digits][(e|E)[+-]digits]` (or `.digits`), finite; lines of any
!> length. Anything else is refused naming the file, the line and the token. Only a regular
!> file is read (a FIFO or a device such as /dev/zero is refused before it is opened).
module kf_text_coords
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_file_type, only: check_regular_file
  use kf_vector_ops, only: distances_representable, too_far_apart
  implicit none
  private

  public :: read_coordinates, write_coordinates

  !> Characters read per non-advancing read while a line is assembled (lines may be longer).
  integer, parameter :: chunk_len = 4096
  character(len=*), parameter :: bom = char(239)//char(187)//char(191)

contains

  !> Read bead centres from `path` into r(3, N). Errors name the file, the line and the token.
  subroutine read_coordinates(path, r, error)
    character(len=*), intent(in) :: path
    real(wp), allocatable, intent(out) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    integer :: unit, stat, n, pass, line_no
    character(len=:), allocatable :: line
    character(len=256) :: msg
    real(wp) :: x(3)
    logical :: at_end

    call check_regular_file(path, 'coordinates: coordinate file', error)
    if (allocated(error)) return
    open (newunit=unit, file=path, status='old', action='read', access='stream', &
      form='formatted', iostat=stat, iomsg=msg)
    if (stat /= 0) then
      call fatal_error(error, "coordinates: cannot open '"//trim(path)//"': "//trim(msg))
      return
    end if
    ! Pass 1 counts and validates, pass 2 stores.
    do pass = 1, 2
      n = 0
      line_no = 0
      do
        call read_line(unit, line, at_end, stat, msg)
        if (at_end) exit
        line_no = line_no + 1
        if (stat /= 0) then
          call fatal_error(error, "coordinates: reading '"//trim(path)//"' line "//to_str(line_no)//": "//trim(msg))
          close (unit)
          return
        end if
        if (line_no == 1 .and. len(line) >= 3) then
          if (line(1:3) == bom) line = line(4:)
        end if
        call parse_point(line, x, msg, stat)
        if (stat < 0) cycle
        if (stat /= 0) then
          call fatal_error(error, "coordinates: '"//trim(path)//"' line "//to_str(line_no)//": "//trim(msg))
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
    if (.not. distances_representable(r)) &
      call fatal_error(error, "coordinates: "//too_far_apart("the points of '"//trim(path)//"'"))
  end subroutine read_coordinates

  !> The next line of `unit`, of any length, without its end of line (non-advancing reads).
  !> at_end: no line was left; stat /= 0: a read error (msg).
  subroutine read_line(unit, line, at_end, stat, msg)
    integer, intent(in) :: unit
    character(len=:), allocatable, intent(out) :: line
    logical, intent(out) :: at_end
    integer, intent(out) :: stat
    character(len=*), intent(inout) :: msg
    character(len=chunk_len) :: chunk
    integer :: got
    line = ''
    at_end = .false.
    do
      read (unit, '(a)', advance='no', size=got, iostat=stat, iomsg=msg) chunk
      if (is_iostat_eor(stat)) then
        line = line//chunk(1:got)
        stat = 0
        return
      end if
      if (is_iostat_end(stat)) then
        ! End of file: a last line without a newline still counts.
        if (got > 0 .or. len(line) > 0) then
          line = line//chunk(1:got)
          stat = 0
        else
          at_end = .true.
        end if
        return
      end if
      if (stat /= 0) return
      line = line//chunk(1:got)
    end do
  end subroutine read_line

  !> Parse exactly three numbers from a line. stat = -1: a blank or comment line; stat = 0: x
  !> holds the point; stat > 0: msg says what is wrong (naming the token).
  subroutine parse_point(line, x, msg, stat)
    character(len=*), intent(in) :: line
    real(wp), intent(out) :: x(3)
    character(len=*), intent(out) :: msg
    integer, intent(out) :: stat
    integer :: pos, first, last, k
    logical :: ok
    x = 0
    msg = ''
    k = 0
    pos = 1
    do
      call next_token(line, pos, first, last)
      if (first == 0) exit
      if (k == 0 .and. line(first:first) == '#') then
        stat = -1
        return
      end if
      k = k + 1
      if (k > 3) then
        msg = "expected three numbers 'x y z', found a fourth item '"//visible(line(first:last))//"'"
        stat = 1
        return
      end if
      call parse_number(line(first:last), x(k), ok)
      if (.not. ok) then
        msg = "item "//to_str(k)//" '"//visible(line(first:last))// &
          "' is not a number (allowed: [+-]digits[.digits][e[+-]digits], finite)"
        stat = 1
        return
      end if
    end do
    if (k == 0) then
      stat = -1
    else if (k < 3) then
      msg = "expected three numbers 'x y z', found "//to_str(k)//" item(s) in '"//visible(line)//"'"
      stat = 1
    else
      stat = 0
    end if
  end subroutine parse_point

  !> The next item of `line` from `pos` on, between blanks (space, tab, carriage return):
  !> line(first:last), first = 0 when none is left; pos moves past it.
  subroutine next_token(line, pos, first, last)
    character(len=*), intent(in) :: line
    integer, intent(inout) :: pos
    integer, intent(out) :: first, last
    first = 0
    last = 0
    do while (pos <= len(line))
      if (.not. is_blank(line(pos:pos))) exit
      pos = pos + 1
    end do
    if (pos > len(line)) return
    first = pos
    do while (pos <= len(line))
      if (is_blank(line(pos:pos))) exit
      pos = pos + 1
    end do
    last = pos - 1
  end subroutine next_token

  pure logical function is_blank(c)
    character, intent(in) :: c
    is_blank = c == ' ' .or. c == achar(9) .or. c == achar(13)
  end function is_blank

  !> A whole token as a finite real: [+-](digits[.[digits]] | .digits)[(e|E)[+-]digits],
  !> nothing else (no `1,5`, `7/8`, `/`, `1d0`, `inf`, `nan`). ok = .false. otherwise.
  subroutine parse_number(token, value, ok)
    character(len=*), intent(in) :: token
    real(wp), intent(out) :: value
    logical, intent(out) :: ok
    integer :: i, n, mantissa_digits, exponent_digits, stat
    character(len=16) :: fmt
    value = 0
    ok = .false.
    n = len(token)
    i = 1
    if (n == 0) return
    if (token(1:1) == '+' .or. token(1:1) == '-') i = 2
    mantissa_digits = count_digits(token, i)
    if (i <= n) then
      if (token(i:i) == '.') then
        i = i + 1
        mantissa_digits = mantissa_digits + count_digits(token, i)
      end if
    end if
    if (mantissa_digits == 0) return
    if (i <= n) then
      if (token(i:i) /= 'e' .and. token(i:i) /= 'E') return
      i = i + 1
      if (i <= n) then
        if (token(i:i) == '+' .or. token(i:i) == '-') i = i + 1
      end if
      exponent_digits = count_digits(token, i)
      if (exponent_digits == 0 .or. i <= n) return
    end if
    write (fmt, '(a,i0,a)') '(f', n, '.0)'
    read (token, fmt, iostat=stat) value
    if (stat /= 0) return
    ok = ieee_is_finite(value)
  end subroutine parse_number

  !> Digits of token from i on; i moves past them.
  integer function count_digits(token, i) result(k)
    character(len=*), intent(in) :: token
    integer, intent(inout) :: i
    k = 0
    do while (i <= len(token))
      if (token(i:i) < '0' .or. token(i:i) > '9') exit
      i = i + 1
      k = k + 1
    end do
  end function count_digits

  !> text with every character outside printable ASCII shown as <TAB>, <CR> or <0xNN>, and cut
  !> to 80 characters (a message quoting an invisible character would be unreadable).
  function visible(text) result(shown)
    character(len=*), intent(in) :: text
    character(len=:), allocatable :: shown
    character(len=*), parameter :: hex = '0123456789ABCDEF'
    integer :: i, c
    shown = ''
    do i = 1, len(text)
      c = iachar(text(i:i))
      if (c == 9) then
        shown = shown//'<TAB>'
      else if (c == 13) then
        shown = shown//'<CR>'
      else if (c < 32 .or. c > 126) then
        shown = shown//'<0x'//hex(c / 16 + 1:c / 16 + 1)//hex(mod(c, 16) + 1:mod(c, 16) + 1)//'>'
      else
        shown = shown//text(i:i)
      end if
      if (len(shown) > 80) then
        shown = shown(1:80)//'...'
        exit
      end if
    end do
  end function visible

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
