!> Minimal stand-in for pFUnit 4's `funit` module, used by the project's fallback test runner
!> when no real pFUnit is installed.
!>
!> It provides the subset documented in tests/README.md: `SourceLocation`, `anyExceptions`,
!> `throw` and the assertions (pFUnit argument order: expected, actual [, tolerance]; give
!> `message=` as a keyword).  Failures are recorded as exceptions of the running test; the
!> generated driver resets them before every test.  The name `funit` is dictated by pFUnit.
!>
!> The recorded exceptions are the one piece of module state: it is the test framework's own
!> bookkeeping (pFUnit keeps the same in its global context) and never part of the library.
module funit
  use, intrinsic :: iso_fortran_env, only: int32, int64, real64, output_unit
  use, intrinsic :: ieee_arithmetic, only: ieee_is_nan, ieee_is_finite
  implicit none
  private

  public :: SourceLocation
  public :: anyExceptions, throw
  public :: assertEqual, assertRelativelyEqual
  public :: assertTrue, assertFalse
  public :: assertLessThan, assertGreaterThan, assertLessThanOrEqual, assertGreaterThanOrEqual
  public :: assertIsNaN, assertIsFinite
  ! Runner interface (used by the generated drivers and by module pfunit).
  public :: funit_test_proc
  public :: funit_begin_test, funit_test_failed, funit_failure_count, funit_failure_text
  public :: funit_report_result, funit_run_test, funit_summary, funit_counts

  integer, parameter :: dp = real64

  !> Where an assertion sits: file name and line number of the `.pf` source.
  type :: SourceLocation
    character(len=256) :: fileName = '<unknown file>'
    integer :: lineNumber = -1
  end type SourceLocation

  !> One recorded failure (an "exception" in pFUnit's words).
  type :: exception_t
    character(len=:), allocatable :: text
  end type exception_t

  !> Signature of a serial test, `@before` or `@after` procedure.
  abstract interface
    subroutine funit_test_proc()
    end subroutine funit_test_proc
  end interface

  ! Framework bookkeeping: failures of the running test and the pass/fail tally.
  type(exception_t), allocatable :: exceptions(:)
  integer :: n_exceptions = 0
  integer :: n_passed = 0
  integer :: n_failed = 0

  !> `assertEqual(expected, actual [, tolerance] [, message=] [, location=])`.
  interface assertEqual
    module procedure assert_equal_i4_0_0, assert_equal_i8_0_0, assert_equal_i4_i8_0_0
    module procedure assert_equal_i4_0_1, assert_equal_i4_1_1, assert_equal_i4_2_2
    module procedure assert_equal_i8_1_1
    module procedure assert_equal_l_0_0, assert_equal_l_0_1, assert_equal_l_1_1
    module procedure assert_equal_r_0_0, assert_equal_r_0_1, assert_equal_r_0_2
    module procedure assert_equal_r_1_1, assert_equal_r_2_2
    module procedure assert_equal_i4_r_0_0
    module procedure assert_equal_string
  end interface assertEqual

  !> `assertRelativelyEqual(expected, actual, tolerance [, message=] [, location=])`:
  !> passes when |actual - expected| <= tolerance*|expected| (fails when expected is 0).
  interface assertRelativelyEqual
    module procedure assert_rel_r_0_0, assert_rel_r_0_1, assert_rel_r_1_1, assert_rel_r_2_2
  end interface assertRelativelyEqual

  interface assertTrue
    module procedure assert_true_0, assert_true_1
  end interface assertTrue

  interface assertFalse
    module procedure assert_false_0, assert_false_1
  end interface assertFalse

  !> `assertLessThan(a, b)` passes when a < b (likewise for the other comparisons).
  interface assertLessThan
    module procedure assert_lt_i4, assert_lt_r
  end interface assertLessThan

  interface assertGreaterThan
    module procedure assert_gt_i4, assert_gt_r
  end interface assertGreaterThan

  interface assertLessThanOrEqual
    module procedure assert_le_i4, assert_le_r
  end interface assertLessThanOrEqual

  interface assertGreaterThanOrEqual
    module procedure assert_ge_i4, assert_ge_r
  end interface assertGreaterThanOrEqual

  interface assertIsNaN
    module procedure assert_is_nan_0, assert_is_nan_1
  end interface assertIsNaN

  interface assertIsFinite
    module procedure assert_is_finite_0, assert_is_finite_1, assert_is_finite_2
  end interface assertIsFinite

contains

  ! ------------------------------------------------------------------------------------------
  ! Bookkeeping
  ! ------------------------------------------------------------------------------------------

  !> True when the running test has recorded at least one failure.
  logical function anyExceptions()
    anyExceptions = n_exceptions > 0
  end function anyExceptions

  !> Record a failure with a free-form message (pFUnit's `throw`).
  subroutine throw(message, location)
    character(len=*), intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    call record_failure('', message, location=location)
  end subroutine throw

  !> Forget the failures of the previous test.
  subroutine funit_begin_test()
    if (allocated(exceptions)) deallocate(exceptions)
    allocate(exceptions(0))
    n_exceptions = 0
  end subroutine funit_begin_test

  !> True when the running test failed (on this process).
  logical function funit_test_failed()
    funit_test_failed = n_exceptions > 0
  end function funit_test_failed

  !> Number of failures recorded for the running test.
  integer function funit_failure_count()
    funit_failure_count = n_exceptions
  end function funit_failure_count

  !> Text of failure i of the running test.
  function funit_failure_text(i) result(text)
    integer, intent(in) :: i
    character(len=:), allocatable :: text
    text = exceptions(i)%text
  end function funit_failure_text

  !> Count a test as passed or failed and print its PASS/FAIL line.
  subroutine funit_report_result(suite, name, failed, quiet)
    character(len=*), intent(in) :: suite
    character(len=*), intent(in) :: name
    logical, intent(in) :: failed
    logical, optional, intent(in) :: quiet   !< count without printing (MPI ranks other than 0)
    logical :: show
    show = .true.
    if (present(quiet)) show = .not. quiet
    if (failed) then
      n_failed = n_failed + 1
      if (show) write(output_unit, '(a)') 'FAIL ' // suite // '::' // name
    else
      n_passed = n_passed + 1
      if (show) write(output_unit, '(a)') 'PASS ' // suite // '::' // name
    end if
    flush(output_unit)
  end subroutine funit_report_result

  !> Run one serial test: reset, `@before`, the test (only if set-up passed), `@after`,
  !> then print the result and the failures with their locations.
  subroutine funit_run_test(suite, name, test, setup, teardown)
    character(len=*), intent(in) :: suite
    character(len=*), intent(in) :: name
    procedure(funit_test_proc) :: test
    procedure(funit_test_proc), optional :: setup
    procedure(funit_test_proc), optional :: teardown
    integer :: i
    call funit_begin_test()
    if (present(setup)) call setup()
    if (n_exceptions == 0) call test()
    if (present(teardown)) call teardown()
    call funit_report_result(suite, name, n_exceptions > 0)
    do i = 1, n_exceptions
      write(output_unit, '(a)') '    ' // exceptions(i)%text
    end do
    flush(output_unit)
  end subroutine funit_run_test

  !> Print the closing line `N passed, N failed`.
  subroutine funit_summary()
    write(output_unit, '(i0,a,i0,a)') n_passed, ' passed, ', n_failed, ' failed'
    flush(output_unit)
  end subroutine funit_summary

  !> Tally so far.
  subroutine funit_counts(passed, failed)
    integer, intent(out) :: passed
    integer, intent(out) :: failed
    passed = n_passed
    failed = n_failed
  end subroutine funit_counts

  !> Append one failure: "<file>:<line>: <what> failed: <detail> | message: <message>"
  !> (just "<file>:<line>: <detail>" when what is empty, as for throw).
  subroutine record_failure(what, detail, message, location)
    character(len=*), intent(in) :: what
    character(len=*), intent(in) :: detail
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    type(exception_t), allocatable :: grown(:)
    character(len=:), allocatable :: text
    character(len=32) :: line_str

    if (present(location)) then
      write(line_str, '(i0)') location%lineNumber
      text = trim(location%fileName) // ':' // trim(line_str) // ': '
    else
      text = '<unknown location>: '
    end if
    if (len(what) > 0) then
      text = text // what // ' failed: ' // detail
    else
      text = text // detail
    end if
    if (present(message)) then
      if (len(message) > 0) text = text // ' | message: ' // message
    end if

    if (.not. allocated(exceptions)) allocate(exceptions(0))
    if (n_exceptions >= size(exceptions)) then
      allocate(grown(max(4, 2*size(exceptions))))
      grown(1:n_exceptions) = exceptions(1:n_exceptions)
      call move_alloc(grown, exceptions)
    end if
    n_exceptions = n_exceptions + 1
    exceptions(n_exceptions)%text = text
  end subroutine record_failure

  ! ------------------------------------------------------------------------------------------
  ! Formatting helpers
  ! ------------------------------------------------------------------------------------------

  function str_r(x) result(s)
    real(dp), intent(in) :: x
    character(len=:), allocatable :: s
    character(len=40) :: buf
    if (ieee_is_nan(x)) then
      s = 'NaN'
    else if (.not. ieee_is_finite(x)) then
      if (x > 0.0_dp) then
        s = '+Infinity'
      else
        s = '-Infinity'
      end if
    else
      write(buf, '(es24.16e3)') x
      s = trim(adjustl(buf))
    end if
  end function str_r

  function str_i(n) result(s)
    integer(int64), intent(in) :: n
    character(len=:), allocatable :: s
    character(len=24) :: buf
    write(buf, '(i0)') n
    s = trim(buf)
  end function str_i

  function str_l(b) result(s)
    logical, intent(in) :: b
    character(len=:), allocatable :: s
    if (b) then
      s = '.true.'
    else
      s = '.false.'
    end if
  end function str_l

  !> "[n1,n2]" for a shape vector.
  function str_shape(shp) result(s)
    integer, intent(in) :: shp(:)
    character(len=:), allocatable :: s
    integer :: k
    s = '['
    do k = 1, size(shp)
      if (k > 1) s = s // ','
      s = s // str_i(int(shp(k), int64))
    end do
    s = s // ']'
  end function str_shape

  !> Multi-index "(i,j)" of column-major flat position k in an array of shape shp
  !> (empty for scalars).
  function str_index(k, shp) result(s)
    integer, intent(in) :: k
    integer, intent(in) :: shp(:)
    character(len=:), allocatable :: s
    integer :: rest, d
    if (size(shp) == 0) then
      s = ''
      return
    end if
    rest = k - 1
    s = ' at index ('
    do d = 1, size(shp)
      if (d > 1) s = s // ','
      s = s // str_i(int(mod(rest, shp(d)) + 1, int64))
      rest = rest / shp(d)
    end do
    s = s // ')'
  end function str_index

  ! ------------------------------------------------------------------------------------------
  ! Cores working on flattened data
  ! ------------------------------------------------------------------------------------------

  !> Compare real data element by element; `expected` is either one value or a flat array
  !> of the same size as `actual`.  Absolute (|a-e| <= tol, exact without tolerance) or
  !> relative (|a-e| <= tol*|e|, never with e = 0).
  subroutine check_real(what, expected, actual, shape_e, shape_a, tolerance, relative, &
                        message, location)
    character(len=*), intent(in) :: what
    real(dp), intent(in) :: expected(:)
    real(dp), intent(in) :: actual(:)
    integer, intent(in) :: shape_e(:)
    integer, intent(in) :: shape_a(:)
    real(dp), optional, intent(in) :: tolerance
    logical, intent(in) :: relative
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: k
    real(dp) :: e, a, diff, bound
    logical :: ok, finite_pair

    if (size(shape_e) > 0) then
      if (size(shape_e) /= size(shape_a)) then
        call record_failure(what, 'shapes differ: expected shape ' // str_shape(shape_e) // &
                            ' but found shape ' // str_shape(shape_a), message, location)
        return
      end if
      if (any(shape_e /= shape_a)) then
        call record_failure(what, 'shapes differ: expected shape ' // str_shape(shape_e) // &
                            ' but found shape ' // str_shape(shape_a), message, location)
        return
      end if
    end if

    do k = 1, size(actual)
      if (size(expected) == 1) then
        e = expected(1)
      else
        e = expected(k)
      end if
      a = actual(k)
      finite_pair = ieee_is_finite(a) .and. ieee_is_finite(e)
      diff = 0.0_dp
      bound = 0.0_dp
      if (.not. finite_pair) then
        ! NaN never matches; infinities only match themselves (and never relatively).
        ok = (.not. relative) .and. (.not. ieee_is_nan(a)) .and. (.not. ieee_is_nan(e))
        if (ok) ok = a == e
      else if (relative) then
        diff = abs(a - e)
        bound = tolerance*abs(e)
        ok = (e /= 0.0_dp) .and. (diff <= bound)
      else if (present(tolerance)) then
        diff = abs(a - e)
        bound = tolerance
        ok = diff <= bound
      else
        diff = abs(a - e)
        ok = a == e
      end if
      if (.not. ok) then
        if (.not. finite_pair) then
          call record_failure(what, 'expected ' // str_r(e) // ' but found ' // str_r(a) // &
                              str_index(k, shape_a), message, location)
        else if (relative .and. e == 0.0_dp) then
          call record_failure(what, 'expected value is zero (relative comparison undefined)' // &
                              str_index(k, shape_a) // '; found ' // str_r(a), message, location)
        else if (relative) then
          call record_failure(what, 'expected ' // str_r(e) // ' but found ' // str_r(a) // &
                              str_index(k, shape_a) // '; |difference| = ' // str_r(diff) // &
                              ' > tolerance*|expected| = ' // str_r(bound) // ' (tolerance ' // &
                              str_r(tolerance) // ')', message, location)
        else if (present(tolerance)) then
          call record_failure(what, 'expected ' // str_r(e) // ' but found ' // str_r(a) // &
                              str_index(k, shape_a) // '; |difference| = ' // str_r(diff) // &
                              ' > tolerance ' // str_r(tolerance), message, location)
        else
          call record_failure(what, 'expected ' // str_r(e) // ' but found ' // str_r(a) // &
                              str_index(k, shape_a) // '; |difference| = ' // str_r(diff) // &
                              ' (exact match required: no tolerance given)', message, location)
        end if
        return
      end if
    end do
  end subroutine check_real

  !> Integer counterpart of check_real (exact comparison).
  subroutine check_int(expected, actual, shape_e, shape_a, message, location)
    integer(int64), intent(in) :: expected(:)
    integer(int64), intent(in) :: actual(:)
    integer, intent(in) :: shape_e(:)
    integer, intent(in) :: shape_a(:)
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: k
    integer(int64) :: e

    if (size(shape_e) > 0) then
      if (size(shape_e) /= size(shape_a)) then
        call record_failure('assertEqual', 'shapes differ: expected shape ' // str_shape(shape_e) // &
                            ' but found shape ' // str_shape(shape_a), message, location)
        return
      end if
      if (any(shape_e /= shape_a)) then
        call record_failure('assertEqual', 'shapes differ: expected shape ' // str_shape(shape_e) // &
                            ' but found shape ' // str_shape(shape_a), message, location)
        return
      end if
    end if
    do k = 1, size(actual)
      if (size(expected) == 1) then
        e = expected(1)
      else
        e = expected(k)
      end if
      if (actual(k) /= e) then
        call record_failure('assertEqual', 'expected ' // str_i(e) // ' but found ' // &
                            str_i(actual(k)) // str_index(k, shape_a), message, location)
        return
      end if
    end do
  end subroutine check_int

  !> Logical counterpart (equivalence).
  subroutine check_logical(expected, actual, shape_e, shape_a, message, location)
    logical, intent(in) :: expected(:)
    logical, intent(in) :: actual(:)
    integer, intent(in) :: shape_e(:)
    integer, intent(in) :: shape_a(:)
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: k
    logical :: e

    if (size(shape_e) > 0) then
      if (size(shape_e) /= size(shape_a)) then
        call record_failure('assertEqual', 'shapes differ: expected shape ' // str_shape(shape_e) // &
                            ' but found shape ' // str_shape(shape_a), message, location)
        return
      end if
      if (any(shape_e /= shape_a)) then
        call record_failure('assertEqual', 'shapes differ: expected shape ' // str_shape(shape_e) // &
                            ' but found shape ' // str_shape(shape_a), message, location)
        return
      end if
    end if
    do k = 1, size(actual)
      if (size(expected) == 1) then
        e = expected(1)
      else
        e = expected(k)
      end if
      if (actual(k) .neqv. e) then
        call record_failure('assertEqual', 'expected ' // str_l(e) // ' but found ' // &
                            str_l(actual(k)) // str_index(k, shape_a), message, location)
        return
      end if
    end do
  end subroutine check_logical

  ! ------------------------------------------------------------------------------------------
  ! assertEqual
  ! ------------------------------------------------------------------------------------------

  subroutine assert_equal_i4_0_0(expected, actual, message, location)
    integer(int32), intent(in) :: expected
    integer(int32), intent(in) :: actual
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: no_shape(0)
    call check_int([int(expected, int64)], [int(actual, int64)], no_shape, no_shape, message, location)
  end subroutine assert_equal_i4_0_0

  subroutine assert_equal_i8_0_0(expected, actual, message, location)
    integer(int64), intent(in) :: expected
    integer(int64), intent(in) :: actual
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: no_shape(0)
    call check_int([expected], [actual], no_shape, no_shape, message, location)
  end subroutine assert_equal_i8_0_0

  subroutine assert_equal_i4_i8_0_0(expected, actual, message, location)
    integer(int32), intent(in) :: expected
    integer(int64), intent(in) :: actual
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: no_shape(0)
    call check_int([int(expected, int64)], [actual], no_shape, no_shape, message, location)
  end subroutine assert_equal_i4_i8_0_0

  subroutine assert_equal_i4_0_1(expected, actual, message, location)
    integer(int32), intent(in) :: expected
    integer(int32), intent(in) :: actual(:)
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: no_shape(0)
    call check_int([int(expected, int64)], int(actual, int64), no_shape, shape(actual), message, location)
  end subroutine assert_equal_i4_0_1

  subroutine assert_equal_i4_1_1(expected, actual, message, location)
    integer(int32), intent(in) :: expected(:)
    integer(int32), intent(in) :: actual(:)
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    call check_int(int(expected, int64), int(actual, int64), shape(expected), shape(actual), &
                   message, location)
  end subroutine assert_equal_i4_1_1

  subroutine assert_equal_i4_2_2(expected, actual, message, location)
    integer(int32), intent(in) :: expected(:, :)
    integer(int32), intent(in) :: actual(:, :)
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    call check_int(int(reshape(expected, [size(expected)]), int64), &
                   int(reshape(actual, [size(actual)]), int64), shape(expected), shape(actual), &
                   message, location)
  end subroutine assert_equal_i4_2_2

  subroutine assert_equal_i8_1_1(expected, actual, message, location)
    integer(int64), intent(in) :: expected(:)
    integer(int64), intent(in) :: actual(:)
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    call check_int(expected, actual, shape(expected), shape(actual), message, location)
  end subroutine assert_equal_i8_1_1

  subroutine assert_equal_l_0_0(expected, actual, message, location)
    logical, intent(in) :: expected
    logical, intent(in) :: actual
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: no_shape(0)
    call check_logical([expected], [actual], no_shape, no_shape, message, location)
  end subroutine assert_equal_l_0_0

  subroutine assert_equal_l_0_1(expected, actual, message, location)
    logical, intent(in) :: expected
    logical, intent(in) :: actual(:)
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: no_shape(0)
    call check_logical([expected], actual, no_shape, shape(actual), message, location)
  end subroutine assert_equal_l_0_1

  subroutine assert_equal_l_1_1(expected, actual, message, location)
    logical, intent(in) :: expected(:)
    logical, intent(in) :: actual(:)
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    call check_logical(expected, actual, shape(expected), shape(actual), message, location)
  end subroutine assert_equal_l_1_1

  subroutine assert_equal_r_0_0(expected, actual, tolerance, message, location)
    real(dp), intent(in) :: expected
    real(dp), intent(in) :: actual
    real(dp), optional, intent(in) :: tolerance
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: no_shape(0)
    call check_real('assertEqual', [expected], [actual], no_shape, no_shape, tolerance, .false., &
                    message, location)
  end subroutine assert_equal_r_0_0

  subroutine assert_equal_r_0_1(expected, actual, tolerance, message, location)
    real(dp), intent(in) :: expected
    real(dp), intent(in) :: actual(:)
    real(dp), optional, intent(in) :: tolerance
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: no_shape(0)
    call check_real('assertEqual', [expected], actual, no_shape, shape(actual), tolerance, .false., &
                    message, location)
  end subroutine assert_equal_r_0_1

  subroutine assert_equal_r_0_2(expected, actual, tolerance, message, location)
    real(dp), intent(in) :: expected
    real(dp), intent(in) :: actual(:, :)
    real(dp), optional, intent(in) :: tolerance
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: no_shape(0)
    call check_real('assertEqual', [expected], reshape(actual, [size(actual)]), no_shape, &
                    shape(actual), tolerance, .false., message, location)
  end subroutine assert_equal_r_0_2

  subroutine assert_equal_r_1_1(expected, actual, tolerance, message, location)
    real(dp), intent(in) :: expected(:)
    real(dp), intent(in) :: actual(:)
    real(dp), optional, intent(in) :: tolerance
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    call check_real('assertEqual', expected, actual, shape(expected), shape(actual), tolerance, &
                    .false., message, location)
  end subroutine assert_equal_r_1_1

  subroutine assert_equal_r_2_2(expected, actual, tolerance, message, location)
    real(dp), intent(in) :: expected(:, :)
    real(dp), intent(in) :: actual(:, :)
    real(dp), optional, intent(in) :: tolerance
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    call check_real('assertEqual', reshape(expected, [size(expected)]), reshape(actual, [size(actual)]), &
                    shape(expected), shape(actual), tolerance, .false., message, location)
  end subroutine assert_equal_r_2_2

  !> Integer expected value, real actual value (e.g. `@assertEqual(0, x, 1.0e-12_wp)`).
  subroutine assert_equal_i4_r_0_0(expected, actual, tolerance, message, location)
    integer(int32), intent(in) :: expected
    real(dp), intent(in) :: actual
    real(dp), optional, intent(in) :: tolerance
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: no_shape(0)
    call check_real('assertEqual', [real(expected, dp)], [actual], no_shape, no_shape, tolerance, &
                    .false., message, location)
  end subroutine assert_equal_i4_r_0_0

  !> Strings are equal when they agree after removing trailing blanks.
  subroutine assert_equal_string(expected, actual, message, location)
    character(len=*), intent(in) :: expected
    character(len=*), intent(in) :: actual
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: k
    if (trim(expected) == trim(actual)) return
    k = 1
    do while (k <= min(len(expected), len(actual)))
      if (expected(k:k) /= actual(k:k)) exit
      k = k + 1
    end do
    call record_failure('assertEqual', 'expected "' // expected // '" but found "' // actual // &
                        '" (first difference at character ' // str_i(int(k, int64)) // ')', &
                        message, location)
  end subroutine assert_equal_string

  ! ------------------------------------------------------------------------------------------
  ! assertRelativelyEqual
  ! ------------------------------------------------------------------------------------------

  subroutine assert_rel_r_0_0(expected, actual, tolerance, message, location)
    real(dp), intent(in) :: expected
    real(dp), intent(in) :: actual
    real(dp), intent(in) :: tolerance
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: no_shape(0)
    call check_real('assertRelativelyEqual', [expected], [actual], no_shape, no_shape, tolerance, &
                    .true., message, location)
  end subroutine assert_rel_r_0_0

  subroutine assert_rel_r_0_1(expected, actual, tolerance, message, location)
    real(dp), intent(in) :: expected
    real(dp), intent(in) :: actual(:)
    real(dp), intent(in) :: tolerance
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: no_shape(0)
    call check_real('assertRelativelyEqual', [expected], actual, no_shape, shape(actual), tolerance, &
                    .true., message, location)
  end subroutine assert_rel_r_0_1

  subroutine assert_rel_r_1_1(expected, actual, tolerance, message, location)
    real(dp), intent(in) :: expected(:)
    real(dp), intent(in) :: actual(:)
    real(dp), intent(in) :: tolerance
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    call check_real('assertRelativelyEqual', expected, actual, shape(expected), shape(actual), &
                    tolerance, .true., message, location)
  end subroutine assert_rel_r_1_1

  subroutine assert_rel_r_2_2(expected, actual, tolerance, message, location)
    real(dp), intent(in) :: expected(:, :)
    real(dp), intent(in) :: actual(:, :)
    real(dp), intent(in) :: tolerance
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    call check_real('assertRelativelyEqual', reshape(expected, [size(expected)]), &
                    reshape(actual, [size(actual)]), shape(expected), shape(actual), tolerance, &
                    .true., message, location)
  end subroutine assert_rel_r_2_2

  ! ------------------------------------------------------------------------------------------
  ! assertTrue / assertFalse
  ! ------------------------------------------------------------------------------------------

  subroutine assert_true_0(condition, message, location)
    logical, intent(in) :: condition
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    if (.not. condition) call record_failure('assertTrue', 'expected .true. but found .false.', &
                                             message, location)
  end subroutine assert_true_0

  subroutine assert_true_1(condition, message, location)
    logical, intent(in) :: condition(:)
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: k
    do k = 1, size(condition)
      if (.not. condition(k)) then
        call record_failure('assertTrue', 'expected .true. but found .false.' // &
                            str_index(k, shape(condition)), message, location)
        return
      end if
    end do
  end subroutine assert_true_1

  subroutine assert_false_0(condition, message, location)
    logical, intent(in) :: condition
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    if (condition) call record_failure('assertFalse', 'expected .false. but found .true.', &
                                       message, location)
  end subroutine assert_false_0

  subroutine assert_false_1(condition, message, location)
    logical, intent(in) :: condition(:)
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: k
    do k = 1, size(condition)
      if (condition(k)) then
        call record_failure('assertFalse', 'expected .false. but found .true.' // &
                            str_index(k, shape(condition)), message, location)
        return
      end if
    end do
  end subroutine assert_false_1

  ! ------------------------------------------------------------------------------------------
  ! Ordering comparisons
  ! ------------------------------------------------------------------------------------------

  subroutine assert_lt_i4(a, b, message, location)
    integer(int32), intent(in) :: a
    integer(int32), intent(in) :: b
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    if (.not. (a < b)) call record_failure('assertLessThan', 'expected ' // str_i(int(a, int64)) // &
                                           ' < ' // str_i(int(b, int64)), message, location)
  end subroutine assert_lt_i4

  subroutine assert_lt_r(a, b, message, location)
    real(dp), intent(in) :: a
    real(dp), intent(in) :: b
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    ! NaN is checked first: an ordered comparison with NaN would trap under -ffpe-trap=invalid.
    if (ieee_is_nan(a) .or. ieee_is_nan(b)) then
      call record_failure('assertLessThan', 'cannot order NaN: expected ' // str_r(a) // ' < ' // &
                          str_r(b), message, location)
    else if (.not. (a < b)) then
      call record_failure('assertLessThan', 'expected ' // str_r(a) // ' < ' // str_r(b), message, location)
    end if
  end subroutine assert_lt_r

  subroutine assert_gt_i4(a, b, message, location)
    integer(int32), intent(in) :: a
    integer(int32), intent(in) :: b
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    if (.not. (a > b)) call record_failure('assertGreaterThan', 'expected ' // str_i(int(a, int64)) // &
                                           ' > ' // str_i(int(b, int64)), message, location)
  end subroutine assert_gt_i4

  subroutine assert_gt_r(a, b, message, location)
    real(dp), intent(in) :: a
    real(dp), intent(in) :: b
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    ! NaN is checked first: an ordered comparison with NaN would trap under -ffpe-trap=invalid.
    if (ieee_is_nan(a) .or. ieee_is_nan(b)) then
      call record_failure('assertGreaterThan', 'cannot order NaN: expected ' // str_r(a) // ' > ' // &
                          str_r(b), message, location)
    else if (.not. (a > b)) then
      call record_failure('assertGreaterThan', 'expected ' // str_r(a) // ' > ' // str_r(b), message, location)
    end if
  end subroutine assert_gt_r

  subroutine assert_le_i4(a, b, message, location)
    integer(int32), intent(in) :: a
    integer(int32), intent(in) :: b
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    if (.not. (a <= b)) call record_failure('assertLessThanOrEqual', 'expected ' // &
                                            str_i(int(a, int64)) // ' <= ' // str_i(int(b, int64)), &
                                            message, location)
  end subroutine assert_le_i4

  subroutine assert_le_r(a, b, message, location)
    real(dp), intent(in) :: a
    real(dp), intent(in) :: b
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    ! NaN is checked first: an ordered comparison with NaN would trap under -ffpe-trap=invalid.
    if (ieee_is_nan(a) .or. ieee_is_nan(b)) then
      call record_failure('assertLessThanOrEqual', 'cannot order NaN: expected ' // str_r(a) // ' <= ' // &
                          str_r(b), message, location)
    else if (.not. (a <= b)) then
      call record_failure('assertLessThanOrEqual', 'expected ' // str_r(a) // ' <= ' // str_r(b), message, location)
    end if
  end subroutine assert_le_r

  subroutine assert_ge_i4(a, b, message, location)
    integer(int32), intent(in) :: a
    integer(int32), intent(in) :: b
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    if (.not. (a >= b)) call record_failure('assertGreaterThanOrEqual', 'expected ' // &
                                            str_i(int(a, int64)) // ' >= ' // str_i(int(b, int64)), &
                                            message, location)
  end subroutine assert_ge_i4

  subroutine assert_ge_r(a, b, message, location)
    real(dp), intent(in) :: a
    real(dp), intent(in) :: b
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    ! NaN is checked first: an ordered comparison with NaN would trap under -ffpe-trap=invalid.
    if (ieee_is_nan(a) .or. ieee_is_nan(b)) then
      call record_failure('assertGreaterThanOrEqual', 'cannot order NaN: expected ' // str_r(a) // ' >= ' // &
                          str_r(b), message, location)
    else if (.not. (a >= b)) then
      call record_failure('assertGreaterThanOrEqual', 'expected ' // str_r(a) // ' >= ' // str_r(b), message, location)
    end if
  end subroutine assert_ge_r

  ! ------------------------------------------------------------------------------------------
  ! NaN / finiteness
  ! ------------------------------------------------------------------------------------------

  subroutine assert_is_nan_0(x, message, location)
    real(dp), intent(in) :: x
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    if (.not. ieee_is_nan(x)) call record_failure('assertIsNaN', 'expected NaN but found ' // &
                                                  str_r(x), message, location)
  end subroutine assert_is_nan_0

  subroutine assert_is_nan_1(x, message, location)
    real(dp), intent(in) :: x(:)
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: k
    do k = 1, size(x)
      if (.not. ieee_is_nan(x(k))) then
        call record_failure('assertIsNaN', 'expected NaN but found ' // str_r(x(k)) // &
                            str_index(k, shape(x)), message, location)
        return
      end if
    end do
  end subroutine assert_is_nan_1

  subroutine assert_is_finite_0(x, message, location)
    real(dp), intent(in) :: x
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    if (.not. ieee_is_finite(x)) call record_failure('assertIsFinite', &
                                                     'expected a finite value but found ' // &
                                                     str_r(x), message, location)
  end subroutine assert_is_finite_0

  subroutine assert_is_finite_1(x, message, location)
    real(dp), intent(in) :: x(:)
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: k
    do k = 1, size(x)
      if (.not. ieee_is_finite(x(k))) then
        call record_failure('assertIsFinite', 'expected a finite value but found ' // &
                            str_r(x(k)) // str_index(k, shape(x)), message, location)
        return
      end if
    end do
  end subroutine assert_is_finite_1

  subroutine assert_is_finite_2(x, message, location)
    real(dp), intent(in) :: x(:, :)
    character(len=*), optional, intent(in) :: message
    type(SourceLocation), optional, intent(in) :: location
    integer :: k
    real(dp), allocatable :: flat(:)
    flat = reshape(x, [size(x)])
    do k = 1, size(flat)
      if (.not. ieee_is_finite(flat(k))) then
        call record_failure('assertIsFinite', 'expected a finite value but found ' // &
                            str_r(flat(k)) // str_index(k, shape(x)), message, location)
        return
      end if
    end do
  end subroutine assert_is_finite_2

end module funit
