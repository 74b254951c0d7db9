!> Program knotflow-analyze: knot analysis of a coordinate file (text + --json), or of HDF5 case files
!> (the /analysis group), or the case mode (kf_modes) of a table of frame rows (a case ledger's
!> CSV, docs/analysis.md). A thin program: parse and validate options, call the library
!> (kf_analyze), report. Errors become one line on stderr and a non-zero exit: 2 for a usage
!> error or a refused directory (nothing written), 1 for a failure while analysing.
program knotflow_analyze
  use, intrinsic :: iso_fortran_env, only: output_unit
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_cli, only: standard_option, argument, die
  use kf_memory, only: keep_freed_heap
  use kf_error, only: error_t, fatal_error
  use kf_kinds, only: wp
  use kf_analysis_farm, only: analysis_farm_t, farm_start, farm_stop
  use kf_analyze, only: analyze_options_t, path_len, is_case_file, is_table, check_inputs, bad_option, &
    analyse_case_files, analyse_coordinates, analyse_table
  implicit none

  character(len=*), parameter :: program_name = 'knotflow-analyze'
  character(len=*), parameter :: usage = &
    'usage: knotflow-analyze chain.xyz [--closures N] [--seed S] [--matrix] [--matrix-closures N]'//new_line('a')// &
    '                        [--min-length M] [--closure-points FILE] [--json] [--per-closure]'//new_line('a')// &
    '       knotflow-analyze CASE.h5 [CASE2.h5 ...] [--closures N] [--seed S] [--stride K]'//new_line('a')// &
    '                        [--matrix-frames k1,k2|last] [--min-length M] [--force] [--reuse OLD.h5]'// &
    new_line('a')// &
    '       knotflow-analyze ROWS.csv [--json]   (the case mode of frame rows with columns mode, phi)'// &
    new_line('a')// &
    '       knotflow-analyze ROWS.csv --elongation X [--json]   (modes again from the shape columns,'// &
    new_line('a')// &
    '                        a/b threshold X instead of 3)'//new_line('a')// &
    '       knotflow-analyze --help | --version'
  integer, parameter :: max_files = 4096

  type(analyze_options_t) :: opt
  character(len=path_len) :: files(max_files)
  integer :: nfiles
  type(error_t), allocatable :: error
  type(analysis_farm_t) :: farm
  !> Exit status: a failure while analysing; bad usage or a refused directory (nothing written).
  integer, parameter :: status_failed = 1, status_refused = 2
  integer :: status
  logical :: refused

  call parse_options(opt, files, nfiles, error)
  if (allocated(error)) call die(program_name, error%message, status_refused)
  call farm_start(farm, error)
  if (allocated(error)) call die(program_name, error%message, status_failed)
  call keep_freed_heap()   ! after MPI start-up, which sets its own allocator options
  status = status_failed
  if (is_case_file(files(1))) then
    call analyse_case_files(files(:nfiles), opt, farm, output_unit, refused, error)
    if (refused) status = status_refused
  else if (is_table(files(1))) then
    status = status_refused
    call analyse_table(trim(files(1)), opt, farm, output_unit, error)
  else
    call analyse_coordinates(trim(files(1)), opt, farm, output_unit, error)
  end if
  if (allocated(error)) call die(program_name, error%message, status)
  call farm_stop(farm, error)
  if (allocated(error)) call die(program_name, error%message, status_failed)

contains

  !> Read and validate the command line.
  subroutine parse_options(opt, files, nfiles, error)
    type(analyze_options_t), intent(inout) :: opt
    character(len=path_len), intent(out) :: files(max_files)
    integer, intent(out) :: nfiles
    type(error_t), allocatable, intent(out) :: error
    integer :: i, n, stat
    character(len=path_len) :: arg, val
    nfiles = 0
    n = command_argument_count()
    if (n == 0) then
      write (output_unit, '(a)') usage
      call fatal_error(error, 'no input file given')
      return
    end if
    i = 0
    do while (i < n)
      i = i + 1
      arg = argument(i)
      select case (trim(arg))
      case ('-h', '--help', '--version')
        call standard_option(program_name, trim(arg), usage)
      case ('--matrix')
        opt%matrix = .true.
      case ('--json')
        opt%json = .true.
      case ('--per-closure')
        opt%per_closure = .true.
      case ('--force')
        opt%force = .true.
      case ('--closures', '--seed', '--min-length', '--closure-points', '--stride', '--matrix-frames', &
            '--matrix-closures', '--reuse', '--elongation')
        if (i == n) then
          call fatal_error(error, 'option '//trim(arg)//': missing value')
          return
        end if
        i = i + 1
        val = argument(i)
        select case (trim(arg))
        case ('--closures')
          read (val, *, iostat=stat) opt%closures
          if (stat /= 0 .or. opt%closures < 1 .or. verify(trim(val), '0123456789') /= 0) &
            call bad_option(error, arg, val, 'an integer >= 1')
        case ('--matrix-closures')
          read (val, *, iostat=stat) opt%matrix_closures
          if (stat /= 0 .or. opt%matrix_closures < 1 .or. verify(trim(val), '0123456789') /= 0) &
            call bad_option(error, arg, val, 'an integer >= 1')
        case ('--seed')
          read (val, *, iostat=stat) opt%seed
          if (stat /= 0 .or. verify(trim(val), '-0123456789') /= 0) call bad_option(error, arg, val, 'an integer')
        case ('--min-length')
          read (val, *, iostat=stat) opt%min_length
          if (stat /= 0 .or. opt%min_length < 2 .or. verify(trim(val), '0123456789') /= 0) &
            call bad_option(error, arg, val, 'an integer >= 2')
        case ('--stride')
          read (val, *, iostat=stat) opt%stride
          if (stat /= 0 .or. opt%stride < 1 .or. verify(trim(val), '0123456789') /= 0) &
            call bad_option(error, arg, val, 'an integer >= 1')
        case ('--closure-points')
          opt%closure_points = val
        case ('--reuse')
          opt%reuse = val
        case ('--elongation')
          read (val, *, iostat=stat) opt%elongation
          opt%reclassify = .true.
          if (stat /= 0 .or. verify(trim(val), '0123456789.eE+-') /= 0) then
            call bad_option(error, arg, val, 'a number >= 1')
          else if (.not. ieee_is_finite(opt%elongation) .or. opt%elongation < 1.0_wp) then
            call bad_option(error, arg, val, 'a number >= 1')
          end if
        case ('--matrix-frames')
          opt%matrix_frames = val
          if (verify(trim(val), '0123456789,last') /= 0) &
            call bad_option(error, arg, val, '"last" or a comma-separated list of frame numbers and "last"')
        end select
        if (allocated(error)) return
      case default
        if (arg(1:1) == '-') then
          call fatal_error(error, 'unknown option '//trim(arg)//' (allowed: --closures, --seed, --matrix, '// &
            '--matrix-closures, --min-length, --closure-points, --json, --per-closure, --stride, '// &
            '--matrix-frames, --force, --reuse, --elongation)')
          return
        end if
        if (nfiles == max_files) then
          call fatal_error(error, 'too many input files')
          return
        end if
        nfiles = nfiles + 1
        files(nfiles) = arg
      end select
    end do
    call check_inputs(files(:nfiles), opt, error)
  end subroutine parse_options

end program knotflow_analyze
