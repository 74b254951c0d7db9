!> knotflow-analyze: knot analysis of a coordinate file (text + --json), or of HDF5 case files
!> (the /analysis group). A thin program: parse and validate options, run the library, report.
!> Errors become one line on stderr and a non-zero exit.
program knotflow_analyze
  use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
  use, intrinsic :: ieee_arithmetic, only: ieee_is_nan
  use kf_kinds, only: wp, i8
  use kf_error, only: error_t, fatal_error
  use kf_knot_invariants, only: n_knot_types, knot_type_names
  use kf_knot_closure, only: knot_stats_t, analyse_closures, default_closures, default_knot_seed
  use kf_knot_matrix, only: knot_matrix, knot_core, is_slipknot, default_min_length, &
    default_matrix_closures
  use kf_knot_input, only: read_points
  use kf_analysis_farm, only: analysis_farm_t, farm_start, farm_stop, farm_max
  implicit none

  integer, parameter :: max_files = 4096
  integer, parameter :: path_len = 1024

  !> Command-line options.
  type :: options_t
    integer :: closures = default_closures
    integer(i8) :: seed = default_knot_seed
    logical :: matrix = .false.
    integer :: matrix_closures = default_matrix_closures
    integer :: min_length = default_min_length
    character(len=path_len) :: closure_points = ''
    logical :: json = .false.
    logical :: per_closure = .false.
    integer :: stride = 1
    character(len=path_len) :: matrix_frames = ''
    logical :: force = .false.
    integer :: nfiles = 0
    character(len=path_len) :: files(max_files)
  end type options_t

  type(options_t) :: opt
  type(error_t), allocatable :: error
  type(analysis_farm_t) :: farm

  call parse_options(opt, error)
  if (allocated(error)) call die(error%message)
  call farm_start(farm, error)
  if (allocated(error)) call die(error%message)
  if (is_case_file(opt%files(1))) then
    call fatal_error(error, 'HDF5 case files: not supported by this build yet (file '//trim(opt%files(1))//')')
  else
    call analyse_coordinates(opt, farm, error)
  end if
  if (allocated(error)) call die(error%message)
  call farm_stop(farm)

contains

  logical function is_case_file(path)
    character(len=*), intent(in) :: path
    integer :: n
    n = len_trim(path)
    is_case_file = .false.
    if (n >= 3) is_case_file = path(n - 2:n) == '.h5'
    if (n >= 5) is_case_file = is_case_file .or. path(n - 4:n) == '.hdf5'
  end function is_case_file

  subroutine die(message)
    use, intrinsic :: iso_c_binding, only: c_int
    character(len=*), intent(in) :: message
    interface
      subroutine c_exit(status) bind(c, name='exit')
        import :: c_int
        integer(c_int), value :: status
      end subroutine c_exit
    end interface
    write (error_unit, '(a)') 'knotflow-analyze: error: '//message
    flush (error_unit)
    call c_exit(1_c_int)          ! one line and a non-zero exit status, no runtime backtrace
  end subroutine die

  subroutine usage()
    write (output_unit, '(a)') &
      'usage: knotflow-analyze chain.xyz [--closures N] [--seed S] [--matrix] [--matrix-closures N]', &
      '                        [--min-length M] [--closure-points FILE] [--json] [--per-closure]', &
      '       knotflow-analyze CASE.h5 [CASE2.h5 ...] [--closures N] [--seed S] [--stride K]', &
      '                        [--matrix-frames k1,k2|last] [--min-length M] [--force]'
  end subroutine usage

  !> Read and validate the command line.
  subroutine parse_options(opt, error)
    type(options_t), intent(inout) :: opt
    type(error_t), allocatable, intent(out) :: error
    integer :: i, n, stat
    character(len=path_len) :: arg, val
    n = command_argument_count()
    if (n == 0) then
      call usage()
      call fatal_error(error, 'no input file given')
      return
    end if
    i = 0
    do while (i < n)
      i = i + 1
      call get_command_argument(i, arg)
      select case (trim(arg))
      case ('-h', '--help')
        call usage()
        stop
      case ('--matrix')
        opt%matrix = .true.
      case ('--json')
        opt%json = .true.
      case ('--per-closure')
        opt%per_closure = .true.
      case ('--force')
        opt%force = .true.
      case ('--closures', '--seed', '--min-length', '--closure-points', '--stride', '--matrix-frames', &
            '--matrix-closures')
        if (i == n) then
          call fatal_error(error, 'option '//trim(arg)//': missing value')
          return
        end if
        i = i + 1
        call get_command_argument(i, val)
        select case (trim(arg))
        case ('--closures')
          read (val, *, iostat=stat) opt%closures
          if (stat /= 0 .or. opt%closures < 1 .or. verify(trim(val), '0123456789') /= 0) &
            call bad(error, arg, val, 'an integer >= 1')
        case ('--matrix-closures')
          read (val, *, iostat=stat) opt%matrix_closures
          if (stat /= 0 .or. opt%matrix_closures < 1 .or. verify(trim(val), '0123456789') /= 0) &
            call bad(error, arg, val, 'an integer >= 1')
        case ('--seed')
          read (val, *, iostat=stat) opt%seed
          if (stat /= 0 .or. verify(trim(val), '-0123456789') /= 0) call bad(error, arg, val, 'an integer')
        case ('--min-length')
          read (val, *, iostat=stat) opt%min_length
          if (stat /= 0 .or. opt%min_length < 2 .or. verify(trim(val), '0123456789') /= 0) &
            call bad(error, arg, val, 'an integer >= 2')
        case ('--stride')
          read (val, *, iostat=stat) opt%stride
          if (stat /= 0 .or. opt%stride < 1 .or. verify(trim(val), '0123456789') /= 0) &
            call bad(error, arg, val, 'an integer >= 1')
        case ('--closure-points')
          opt%closure_points = val
        case ('--matrix-frames')
          opt%matrix_frames = val
          if (trim(val) /= 'last' .and. verify(trim(val), '0123456789,') /= 0) &
            call bad(error, arg, val, '"last" or a comma-separated list of frame numbers')
        end select
        if (allocated(error)) return
      case default
        if (arg(1:1) == '-') then
          call fatal_error(error, 'unknown option '//trim(arg)//' (allowed: --closures, --seed, --matrix, '// &
            '--matrix-closures, --min-length, --closure-points, --json, --per-closure, --stride, '// &
            '--matrix-frames, --force)')
          return
        end if
        if (opt%nfiles == max_files) then
          call fatal_error(error, 'too many input files')
          return
        end if
        opt%nfiles = opt%nfiles + 1
        opt%files(opt%nfiles) = arg
      end select
    end do
    if (opt%nfiles == 0) then
      call fatal_error(error, 'no input file given')
      return
    end if
    if (.not. is_case_file(opt%files(1)) .and. opt%nfiles > 1) then
      call fatal_error(error, 'a coordinate file is analysed alone: got '//trim(opt%files(2))//' as well')
      return
    end if
  end subroutine parse_options

  !> The error for an invalid option value.
  subroutine bad(error, name, value, allowed)
    type(error_t), allocatable, intent(out) :: error
    character(len=*), intent(in) :: name, value, allowed
    call fatal_error(error, 'option '//trim(name)//': invalid value "'//trim(value)//'" (allowed: '// &
      allowed//')')
  end subroutine bad

  !> Mode 1: one chain from a text coordinate file.
  subroutine analyse_coordinates(opt, farm, error)
    type(options_t), intent(in) :: opt
    type(analysis_farm_t), intent(in) :: farm
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: r(:, :), pts(:, :), kmat(:, :), flat(:)
    type(knot_stats_t) :: st
    integer :: core(2), n
    logical :: found, slip
    call read_points(opt%files(1), r, error)
    if (allocated(error)) return
    n = size(r, 2)
    if (len_trim(opt%closure_points) > 0) then
      call read_points(opt%closure_points, pts, error)
      if (allocated(error)) return
      call analyse_closures(r, size(pts, 2), opt%seed, st, error, points=pts, per_closure=.true.)
    else
      call analyse_closures(r, opt%closures, opt%seed, st, error, per_closure=.true.)
    end if
    if (allocated(error)) return
    found = .false.
    slip = .false.
    if (opt%matrix) then
      allocate (kmat(n, n))
      call knot_matrix(r, opt%matrix_closures, opt%seed, opt%min_length, kmat, error, &
                       part=farm%rank, nparts=farm%size)
      if (allocated(error)) return
      flat = reshape(kmat, [n*n])
      where (ieee_is_nan(flat)) flat = -huge(1.0_wp)
      call farm_max(farm, flat)
      kmat = reshape(flat, [n, n])
      where (kmat < -1.0_wp) kmat = ieee_nan()
      call knot_core(kmat, core, found)
      slip = is_slipknot(kmat, st%kf)
    end if
    if (farm%rank /= 0) return
    if (opt%json) then
      call print_json(opt, n, st, kmat, found, core, slip)
    else
      call print_text(opt, n, st, found, core, slip)
    end if
  end subroutine analyse_coordinates

  !> The human-readable report of one chain.
  subroutine print_text(opt, n, st, found, core, slip)
    type(options_t), intent(in) :: opt
    integer, intent(in) :: n, core(2)
    type(knot_stats_t), intent(in) :: st
    logical, intent(in) :: found, slip
      integer :: k, i
      write (output_unit, '(a,a)') 'file:      ', trim(opt%files(1))
      write (output_unit, '(a,i0)') 'beads:     ', n
      write (output_unit, '(a,i0,a,i0)') 'closures:  ', st%closures, '   seed: ', st%seed
      write (output_unit, '(a,f8.4)') 'k_f:       ', st%kf
      write (output_unit, '(a)') 'spectrum:'
      do k = 1, n_knot_types
        if (st%spectrum(k) > 0.0_wp) write (output_unit, '(4x,a6,f8.4)') knot_type_names(k), st%spectrum(k)
      end do
      write (output_unit, '(a,a)') 'dominant:  ', trim(knot_type_names(st%dominant))
      if (opt%per_closure) then
        write (output_unit, '(a)') 'per closure:'
        write (output_unit, '(10(1x,a5))') (knot_type_names(st%per_closure(i)), i=1, st%closures)
      end if
      if (opt%matrix) then
        write (output_unit, '(a,i0,a,i0)') 'knot matrix: closures per subchain ', opt%matrix_closures, &
          ', min length ', opt%min_length
        if (found) then
          write (output_unit, '(a,i0,a,i0,a)') 'knot core: beads ', core(1), '..', core(2), ' (0-based)'
        else
          write (output_unit, '(a)') 'knot core: none'
        end if
        write (output_unit, '(a,l1)') 'slipknot:  ', slip
      end if
  end subroutine print_text

  !> The JSON object of one chain (the convention shared with knotflow-kf).
  subroutine print_json(opt, n, st, kmat, found, core, slip)
    type(options_t), intent(in) :: opt
    integer, intent(in) :: n, core(2)
    type(knot_stats_t), intent(in) :: st
    real(wp), allocatable, intent(in) :: kmat(:, :)
    logical, intent(in) :: found, slip
      character(len=:), allocatable :: s
      integer :: k, i, j
      s = '{"n_beads": '//itoa(int(n, i8))//', "closures": '//itoa(int(st%closures, i8))// &
        ', "seed": '//itoa(st%seed)//', "kf": '//rtoa(st%kf)//', "spectrum": {'
      do k = 1, n_knot_types
        s = s//'"'//trim(knot_type_names(k))//'": '//rtoa(st%spectrum(k))
        if (k < n_knot_types) s = s//', '
      end do
      s = s//'}, "dominant": "'//trim(knot_type_names(st%dominant))//'"'
      if (opt%per_closure) then
        s = s//', "per_closure": ['
        do k = 1, st%closures
          s = s//'"'//trim(knot_type_names(st%per_closure(k)))//'"'
          if (k < st%closures) s = s//', '
        end do
        s = s//']'
      end if
      if (opt%matrix) then
        s = s//', "matrix": ['
        do i = 1, n
          s = s//'['
          do j = 1, n
            if (ieee_is_nan(kmat(i, j))) then
              s = s//'null'
            else
              s = s//rtoa(kmat(i, j))
            end if
            if (j < n) s = s//', '
          end do
          s = s//']'
          if (i < n) s = s//', '
        end do
        s = s//']'
      end if
      if (found) then
        s = s//', "knot_core": ['//itoa(int(core(1), i8))//', '//itoa(int(core(2), i8))//']'
      else
        s = s//', "knot_core": null'
      end if
      s = s//', "slipknot": '//merge('true ', 'false', slip)
      s = trim(s)//'}'
      write (output_unit, '(a)') s
  end subroutine print_json

  function itoa(v) result(s)
    integer(i8), intent(in) :: v
    character(len=:), allocatable :: s
    character(len=24) :: buf
    write (buf, '(i0)') v
    s = trim(buf)
  end function itoa

  function rtoa(v) result(s)
    real(wp), intent(in) :: v
    character(len=:), allocatable :: s
    character(len=32) :: buf
    write (buf, '(es23.16e2)') v
    s = trim(adjustl(buf))
  end function rtoa

  real(wp) function ieee_nan()
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    ieee_nan = ieee_value(0.0_wp, ieee_quiet_nan)
  end function ieee_nan

end program knotflow_analyze
