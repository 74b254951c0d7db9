!> Facts about the machine a run is on: the 1-minute load average and the host name (from the C
!> library through ISO_C_BINDING: getloadavg, gethostname) and the current time in UTC as an
!> ISO 8601 text. Each returns an error when the platform cannot tell; the caller decides what
!> stands in (kf_run_segment: NaN and 'unknown').
module kf_platform
  use, intrinsic :: iso_c_binding, only: c_int, c_double, c_char, c_size_t, c_null_char
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  implicit none
  private

  public :: load_average, host_name, utc_now, utc_iso, physical_memory, bytes_text

  interface
    !> int getloadavg(double loadavg[], int nelem): samples retrieved, or -1.
    function c_getloadavg(loadavg, nelem) bind(c, name='getloadavg') result(n)
      import :: c_double, c_int
      real(c_double), intent(out) :: loadavg(*)
      integer(c_int), value :: nelem
      integer(c_int) :: n
    end function c_getloadavg
    !> int gethostname(char *name, size_t len): 0, or -1.
    function c_gethostname(name, length) bind(c, name='gethostname') result(stat)
      import :: c_char, c_size_t, c_int
      character(kind=c_char), intent(out) :: name(*)
      integer(c_size_t), value :: length
      integer(c_int) :: stat
    end function c_gethostname
  end interface

  !> Seconds of one day.
  integer(i8), parameter :: day = 86400_i8

contains

  !> The machine's load average over the last minute (getloadavg); an error where the C
  !> library cannot tell.
  subroutine load_average(load, error)
    real(wp), intent(out) :: load
    type(error_t), allocatable, intent(out) :: error
    real(c_double) :: samples(1)
    load = 0.0_wp
    if (c_getloadavg(samples, 1_c_int) < 1) then
      call fatal_error(error, 'the load average is not available (getloadavg failed)')
      return
    end if
    load = real(samples(1), wp)
  end subroutine load_average

  !> The host name (gethostname); an error where it cannot be read.
  subroutine host_name(name, error)
    character(len=:), allocatable, intent(out) :: name
    type(error_t), allocatable, intent(out) :: error
    integer, parameter :: capacity = 256
    character(kind=c_char) :: buf(capacity + 1)
    integer :: n, k
    name = ''
    buf = c_null_char
    if (c_gethostname(buf, int(capacity, c_size_t)) /= 0) then
      call fatal_error(error, 'the host name is not available (gethostname failed)')
      return
    end if
    n = 0
    do while (n < capacity)
      if (buf(n + 1) == c_null_char) exit
      n = n + 1
    end do
    if (n == 0) then
      call fatal_error(error, 'the host name is empty')
      return
    end if
    name = repeat(' ', n)
    do k = 1, n
      name(k:k) = buf(k)
    end do
  end subroutine host_name

  !> The current time in UTC as 'YYYY-MM-DDThh:mm:ssZ' (the local clock of date_and_time less
  !> its offset from UTC); an error where the offset is not known.
  subroutine utc_now(text, error)
    character(len=:), allocatable, intent(out) :: text
    type(error_t), allocatable, intent(out) :: error
    integer :: v(8)
    integer(i8) :: local
    text = ''
    call date_and_time(values=v)
    if (v(1) == -huge(0) .or. v(4) == -huge(0)) then
      call fatal_error(error, 'the time in UTC is not available (date_and_time gives no offset from UTC)')
      return
    end if
    local = days_from_civil(int(v(1), i8), v(2), v(3))*day + 3600_i8*v(5) + 60_i8*v(6) + v(7)
    text = utc_iso(local - 60_i8*v(4))
  end subroutine utc_now

  !> The instant `seconds` after 1970-01-01T00:00:00Z as 'YYYY-MM-DDThh:mm:ssZ' (proleptic
  !> Gregorian calendar, no leap seconds, as POSIX time).
  pure function utc_iso(seconds) result(text)
    integer(i8), intent(in) :: seconds
    character(len=20) :: text
    integer(i8) :: days, s, y
    integer :: m, d
    days = seconds/day
    if (mod(seconds, day) < 0) days = days - 1
    s = seconds - days*day
    call civil_from_days(days, y, m, d)
    write (text, '(i4.4, "-", i2.2, "-", i2.2, "T", i2.2, ":", i2.2, ":", i2.2, "Z")') y, m, d, &
      s/3600, mod(s, 3600_i8)/60, mod(s, 60_i8)
  end function utc_iso

  !> Days since 1970-01-01 of the date (y, m, d) of the proleptic Gregorian calendar
  !> (H. Hinnant's days_from_civil).
  pure integer(i8) function days_from_civil(y, m, d) result(days)
    integer(i8), intent(in) :: y
    integer, intent(in) :: m, d
    integer(i8) :: yy, era, yoe, doy, doe
    yy = y
    if (m <= 2) yy = yy - 1
    era = merge(yy, yy - 399, yy >= 0)/400
    yoe = yy - era*400
    doy = (153*(m + merge(-3, 9, m > 2)) + 2)/5 + d - 1
    doe = yoe*365 + yoe/4 - yoe/100 + doy
    days = era*146097 + doe - 719468
  end function days_from_civil

  !> The date (y, m, d) of the day `days` after 1970-01-01 (H. Hinnant's civil_from_days).
  pure subroutine civil_from_days(days, y, m, d)
    integer(i8), intent(in) :: days
    integer(i8), intent(out) :: y
    integer, intent(out) :: m, d
    integer(i8) :: z, era, doe, yoe, doy, mp
    z = days + 719468
    era = merge(z, z - 146096, z >= 0)/146097
    doe = z - era*146097
    yoe = (doe - doe/1460 + doe/36524 - doe/146096)/365
    y = yoe + era*400
    doy = doe - (365*yoe + yoe/4 - yoe/100)
    mp = (5*doy + 2)/153
    d = int(doy - (153*mp + 2)/5 + 1)
    m = int(merge(mp + 3, mp - 9, mp < 10))
    if (m <= 2) y = y + 1
  end subroutine civil_from_days

  !> Physical memory of this machine in bytes (MemTotal of /proc/meminfo), -1 when unknown.
  function physical_memory() result(bytes)
    integer(i8) :: bytes
    character(len=256) :: line
    integer :: unit, ios, k
    integer(i8) :: kib
    bytes = -1
    open (newunit=unit, file='/proc/meminfo', status='old', action='read', iostat=ios)
    if (ios /= 0) return
    do
      read (unit, '(a)', iostat=ios) line
      if (ios /= 0) exit
      if (index(line, 'MemTotal:') /= 1) cycle
      k = index(line, 'kB')
      if (k == 0) exit
      read (line(10:k - 1), *, iostat=ios) kib
      if (ios == 0 .and. kib > 0) bytes = 1024_i8*kib
      exit
    end do
    close (unit)
  end function physical_memory

  !> Bytes as text with a binary-prefixed unit: '512 B', '3.2 GiB'.
  function bytes_text(bytes) result(text)
    integer(i8), intent(in) :: bytes
    character(len=:), allocatable :: text
    character(len=*), parameter :: units(5) = ['KiB', 'MiB', 'GiB', 'TiB', 'PiB']
    character(len=32) :: buf
    real(wp) :: x
    integer :: k
    if (bytes < 1024) then
      text = to_str(bytes)//' B'
      return
    end if
    x = real(bytes, wp)
    k = 0
    do while (x >= 1024.0_wp .and. k < size(units))
      x = x/1024.0_wp
      k = k + 1
    end do
    write (buf, '(f0.1)') x
    text = trim(adjustl(buf))//' '//units(k)
  end function bytes_text

end module kf_platform
