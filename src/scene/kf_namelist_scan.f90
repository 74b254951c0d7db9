!> A small scanner of namelist files: finds the groups and the `name = value` assignments in them,
!> so that unknown groups and variables can be rejected by name before Fortran reads the values,
!> and a value that fails to read can be named precisely.
module kf_namelist_scan
  use kf_error, only: error_t, fatal_error
  use kf_file_type, only: check_regular_file
  implicit none
  private

  !> One assignment `name = value` (name lower-case, without subscript; value as written).
  type, public :: nml_assignment_t
    character(len=:), allocatable :: name
    character(len=:), allocatable :: lhs     !< the left-hand side as written (with subscripts)
    character(len=:), allocatable :: value
  end type nml_assignment_t

  !> One group `&name ... /`.
  type, public :: nml_group_t
    character(len=:), allocatable :: name    !< lower-case
    type(nml_assignment_t), allocatable :: items(:)
  end type nml_group_t

  public :: scan_namelist_file, group_text, lower, count_values

  !> The UTF-8 byte-order mark some editors write at the start of a file (skipped).
  character(len=*), parameter :: bom = char(239)//char(187)//char(191)

contains

  !> Scan `path` into its groups. Errors name the file.
  subroutine scan_namelist_file(path, groups, error)
    character(len=*), intent(in) :: path
    type(nml_group_t), allocatable, intent(out) :: groups(:)
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: text
    integer :: pos, n, gstart, gend
    type(nml_group_t) :: g

    call read_stripped(path, text, error)
    if (allocated(error)) return
    allocate (groups(0))
    n = len(text)
    pos = 1
    do
      gstart = index(text(pos:), '&')
      if (gstart == 0) then
        if (len_trim(text(pos:)) > 0) then
          call fatal_error(error, trim(path)//': text outside a group: "'//snippet(adjustl(text(pos:)))// &
            '" (allowed: only &group ... / blocks and ! comments)')
          return
        end if
        exit
      end if
      gstart = pos + gstart - 1
      if (len_trim(text(pos:gstart - 1)) > 0) then
        call fatal_error(error, trim(path)//': text outside a group: "'// &
          snippet(adjustl(text(pos:gstart - 1)))//'" (allowed: only &group ... / blocks and ! comments)')
        return
      end if
      gend = find_unquoted(text, '/', gstart + 1)
      if (gend == 0) then
        call fatal_error(error, trim(path)//': group starting at "'//snippet(text(gstart:))// &
          '" has no closing "/"')
        return
      end if
      call parse_group(text(gstart + 1:gend - 1), g, path, error)
      if (allocated(error)) return
      groups = [groups, g]
      pos = gend + 1
      if (pos > n) exit
    end do
    if (size(groups) == 0) then
      call fatal_error(error, trim(path)//': no namelist group found (the file is empty or not a '// &
        'scene; allowed: groups such as &chain shape = ''trefoil'' /)')
    end if
  end subroutine scan_namelist_file

  !> The text `&name assignments /` of a group, suitable for an internal namelist read.
  function group_text(g, only) result(text)
    type(nml_group_t), intent(in) :: g
    integer, intent(in), optional :: only   !< just this assignment
    character(len=:), allocatable :: text
    integer :: k
    text = '&'//g%name
    do k = 1, size(g%items)
      if (present(only)) then
        if (k /= only) cycle
      end if
      text = text//' '//g%items(k)%lhs//' = '//g%items(k)%value//','
    end do
    text = text//' /'
  end function group_text

  !> Read the file, drop `!` comments outside quotes, join lines with blanks.
  subroutine read_stripped(path, text, error)
    character(len=*), intent(in) :: path
    character(len=:), allocatable, intent(out) :: text
    type(error_t), allocatable, intent(out) :: error
    integer :: unit, ios, got
    character(len=4096) :: chunk
    character(len=:), allocatable :: line
    character(len=256) :: msg
    logical :: exists

    inquire (file=path, exist=exists)
    if (.not. exists) then
      ! not found, or not reachable (a directory on the way without search permission): the
      ! system's reason tells which
      open (newunit=unit, file=path, status='old', action='read', iostat=ios, iomsg=msg)
      if (ios == 0) close (unit)
      if (ios == 0 .or. index(msg, 'No such file') > 0) then
        call fatal_error(error, trim(path)//': file not found')
      else
        call fatal_error(error, trim(path)//': cannot be opened: '//trim(msg))
      end if
      return
    end if
    inquire (file=trim(path)//'/.', exist=exists)
    if (exists) then
      call fatal_error(error, trim(path)//': is a directory (allowed: a namelist scene file)')
      return
    end if
    call check_regular_file(path, 'scene', error)
    if (allocated(error)) return
    open (newunit=unit, file=path, status='old', action='read', iostat=ios, iomsg=msg)
    if (ios /= 0) then
      call fatal_error(error, trim(path)//': cannot open: '//trim(msg))
      return
    end if
    text = ''
    ! lines of any length: read in pieces (non-advancing) until the end of the record
    line = ''
    do
      read (unit, '(a)', advance='no', iostat=ios, size=got) chunk
      if (ios == 0) then
        line = line//chunk(1:got)
        cycle
      end if
      if (is_iostat_eor(ios)) then
        line = line//chunk(1:got)
        if (len(text) == 0 .and. len(line) >= 3) then
          if (line(1:3) == bom) line = line(4:)
        end if
        text = text//' '//strip_comment(blank_tabs(line))
        line = ''
        cycle
      end if
      if (is_iostat_end(ios)) then
        if (len(text) == 0 .and. len(line) >= 3) then
          if (line(1:3) == bom) line = line(4:)
        end if
        if (len(line) > 0) text = text//' '//strip_comment(blank_tabs(line))
        exit
      end if
      call fatal_error(error, trim(path)//': cannot read (a directory or not a text file?): '// &
        'read error '//trim(adjustl(itoa(ios))))
      close (unit)
      return
    end do
    close (unit)
    if (index(text, achar(0)) > 0) then
      call fatal_error(error, trim(path)//': not a text file (it holds NUL bytes; allowed: a namelist scene)')
    end if
  end subroutine read_stripped

  !> line with every tab and carriage return outside quotes made a blank (a tab separates like
  !> a blank; inside a quoted string it is kept).
  pure function blank_tabs(line) result(s)
    character(len=*), intent(in) :: line
    character(len=len(line)) :: s
    integer :: k
    character(len=1) :: quote
    s = line
    quote = ' '
    do k = 1, len(s)
      if (quote /= ' ') then
        if (s(k:k) == quote) quote = ' '
      else if (s(k:k) == '"' .or. s(k:k) == "'") then
        quote = s(k:k)
      else if (s(k:k) == achar(9) .or. s(k:k) == achar(13)) then
        s(k:k) = ' '
      end if
    end do
  end function blank_tabs

  pure function itoa(i) result(s)
    integer, intent(in) :: i
    character(len=16) :: s
    write (s, '(i0)') i
  end function itoa

  function strip_comment(line) result(s)
    character(len=*), intent(in) :: line
    character(len=:), allocatable :: s
    integer :: k
    character(len=1) :: quote
    quote = ' '
    do k = 1, len(line)
      if (quote /= ' ') then
        if (line(k:k) == quote) quote = ' '
      else if (line(k:k) == '"' .or. line(k:k) == "'") then
        quote = line(k:k)
      else if (line(k:k) == '!') then
        s = trim(line(1:k - 1))
        return
      end if
    end do
    s = trim(line)
  end function strip_comment

  !> First position >= start of character c outside quotes, 0 if none.
  integer function find_unquoted(text, c, start) result(pos)
    character(len=*), intent(in) :: text
    character(len=1), intent(in) :: c
    integer, intent(in) :: start
    integer :: k
    character(len=1) :: quote
    quote = ' '
    pos = 0
    do k = start, len(text)
      if (quote /= ' ') then
        if (text(k:k) == quote) quote = ' '
      else if (text(k:k) == '"' .or. text(k:k) == "'") then
        quote = text(k:k)
      else if (text(k:k) == c) then
        pos = k
        return
      end if
    end do
  end function find_unquoted

  !> body = "name a = 1, b(2) = 3 ..." (without & and /).
  subroutine parse_group(body, g, path, error)
    character(len=*), intent(in) :: body, path
    type(nml_group_t), intent(out) :: g
    type(error_t), allocatable, intent(out) :: error
    integer :: k, n, eq, next_eq, lhs_start, value_end
    integer, allocatable :: eqs(:), lhs_starts(:)

    n = len(body)
    k = 1
    do while (k <= n)
      if (.not. is_name_char(body(k:k))) exit
      k = k + 1
    end do
    g%name = lower(body(1:k - 1))
    if (len(g%name) == 0) then
      call fatal_error(error, trim(path)//': "&" not followed by a group name near "'// &
        snippet(body)//'"')
      return
    end if
    allocate (g%items(0), eqs(0), lhs_starts(0))
    ! Every unquoted '=' ends a left-hand side; find where each left-hand side starts.
    eq = find_unquoted(body, '=', k)
    do while (eq > 0)
      lhs_start = lhs_begin(body, eq)
      if (lhs_start < 1) then
        call fatal_error(error, trim(path)//': &'//g%name//': cannot find a variable name before "="'// &
          ' near "'//snippet(body(max(1, eq - 20):))//'"')
        return
      end if
      eqs = [eqs, eq]
      lhs_starts = [lhs_starts, lhs_start]
      eq = find_unquoted(body, '=', eq + 1)
    end do
    if (size(eqs) == 0) then
      if (len_trim(body(k:)) > 0) then
        call fatal_error(error, trim(path)//': &'//g%name//': expected "name = value", found "'// &
          snippet(adjustl(body(k:)))//'"')
      end if
      return
    end if
    if (len_trim(body(k:lhs_starts(1) - 1)) > 0) then
      call fatal_error(error, trim(path)//': &'//g%name//': unexpected text "'// &
        snippet(adjustl(body(k:lhs_starts(1) - 1)))//'"')
      return
    end if
    do k = 1, size(eqs)
      if (k < size(eqs)) then
        next_eq = lhs_starts(k + 1)
        value_end = next_eq - 1
      else
        value_end = n
      end if
      call add_assignment(g, body(lhs_starts(k):eqs(k) - 1), body(eqs(k) + 1:value_end))
    end do
    ! a variable given twice (the last value would win in silence)
    do k = 2, size(g%items)
      do n = 1, k - 1
        if (lower(g%items(n)%lhs) == lower(g%items(k)%lhs) .or. (g%items(n)%name == g%items(k)%name .and. &
            (index(g%items(n)%lhs, '(') == 0 .or. index(g%items(k)%lhs, '(') == 0))) then
          call fatal_error(error, trim(path)//': &'//g%name//': '//g%items(k)%name//' is given twice ('// &
            g%items(n)%lhs//' = '//g%items(n)%value//' and '//g%items(k)%lhs//' = '//g%items(k)%value// &
            '; allowed: each variable once)')
          return
        end if
      end do
    end do
  end subroutine parse_group

  subroutine add_assignment(g, lhs, value)
    type(nml_group_t), intent(inout) :: g
    character(len=*), intent(in) :: lhs, value
    type(nml_assignment_t) :: a
    integer :: p
    character(len=:), allocatable :: v
    a%lhs = trim(adjustl(lhs))
    p = index(a%lhs, '(')
    if (p > 0) then
      a%name = lower(trim(a%lhs(1:p - 1)))
    else
      a%name = lower(a%lhs)
    end if
    v = trim(adjustl(value))
    do while (len(v) > 0)
      if (v(len(v):len(v)) /= ',') exit
      v = trim(v(1:len(v) - 1))
    end do
    a%value = v
    g%items = [g%items, a]
  end subroutine add_assignment

  !> Start of the left-hand side ending just before position eq: a name with an optional
  !> parenthesised subscript.
  integer function lhs_begin(body, eq) result(start)
    character(len=*), intent(in) :: body
    integer, intent(in) :: eq
    integer :: k, depth
    k = eq - 1
    do while (k >= 1)
      if (body(k:k) /= ' ') exit
      k = k - 1
    end do
    if (k >= 1) then
      if (body(k:k) == ')') then
        depth = 0
        do while (k >= 1)
          if (body(k:k) == ')') depth = depth + 1
          if (body(k:k) == '(') depth = depth - 1
          if (depth == 0) exit
          k = k - 1
        end do
        k = k - 1
        do while (k >= 1)
          if (body(k:k) /= ' ') exit
          k = k - 1
        end do
      end if
    end if
    start = k
    do while (start >= 1)
      if (.not. is_name_char(body(start:start))) exit
      start = start - 1
    end do
    start = start + 1
    if (start > k) start = 0
  end function lhs_begin

  !> Number of values in the value text of an assignment: items separated by commas or blanks
  !> outside quotes, `r*c` counting r times.
  integer function count_values(value) result(n)
    character(len=*), intent(in) :: value
    integer :: k, start, star, r, ios
    character(len=1) :: quote
    logical :: in_item
    n = 0
    quote = ' '
    in_item = .false.
    start = 1
    do k = 1, len(value) + 1
      if (k <= len(value)) then
        if (quote /= ' ') then
          if (value(k:k) == quote) quote = ' '
          cycle
        end if
        if (value(k:k) == '"' .or. value(k:k) == "'") then
          quote = value(k:k)
          if (.not. in_item) start = k
          in_item = .true.
          cycle
        end if
        if (value(k:k) /= ',' .and. value(k:k) /= ' ') then
          if (.not. in_item) start = k
          in_item = .true.
          cycle
        end if
      end if
      if (in_item) then
        star = index(value(start:k - 1), '*')
        r = 1
        if (star > 1) then
          read (value(start:start + star - 2), *, iostat=ios) r
          if (ios /= 0) r = 1
        end if
        n = n + max(r, 1)
        in_item = .false.
      end if
    end do
  end function count_values

  logical elemental function is_name_char(c)
    character(len=1), intent(in) :: c
    is_name_char = (c >= 'a' .and. c <= 'z') .or. (c >= 'A' .and. c <= 'Z') .or. &
                   (c >= '0' .and. c <= '9') .or. c == '_' .or. c == '%'
  end function is_name_char

  !> Lower-case copy.
  function lower(s) result(t)
    character(len=*), intent(in) :: s
    character(len=len(s)) :: t
    integer :: k
    t = s
    do k = 1, len(s)
      if (s(k:k) >= 'A' .and. s(k:k) <= 'Z') t(k:k) = achar(iachar(s(k:k)) + 32)
    end do
  end function lower

  function snippet(s) result(t)
    character(len=*), intent(in) :: s
    character(len=:), allocatable :: t
    t = trim(s(1:min(len(s), 40)))
  end function snippet

end module kf_namelist_scan
