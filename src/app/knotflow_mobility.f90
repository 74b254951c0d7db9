!> Program knotflow-mobility: the 3N x 3N mobility or the shear disturbance of beads read from a file.
!>
!>   knotflow-mobility FILE [--model none|rpy|multipole] [--order L] [--lubrication on|off]
!>                          [--eps-lub X] [--overlap RULE] [--output mobility|shear|spectrum]
!>
!> Defaults: --model multipole --order 2 --lubrication on --eps-lub 1e-4 --overlap pair
!> --output mobility (eps_lub: overlapping pairs, r <= 1, are evaluated at 1 + eps_lub; it is also
!> passed to the factory as the tolerance for none/rpy, which ignore it). --overlap (multipole):
!> the model's part of an &hydro overlap rule at these positions: 'bwe' the literal BWE rule
!> (many-body system at the real positions, only the lubrication of pairs at r <= 1 moved to
!> 1 + eps_lub), the others the clamp of 'pair' (the configuration 'separate' and 'relax' move to
!> is the dynamics' business, not done here).
!> spectrum (multipole): lines "key values": overlapping_pairs (r <= 1); many_body_cholesky ok |
!> failed; many_body_lowest, the 3 smallest eigenvalues of the scaled many-body matrix that is
!> factorised (kf_multipole_system), and many_body_highest; then, where the many-body system
!> factorises, friction_cholesky ok | failed and friction_lowest, the 3 smallest eigenvalues of
!> the 6N x 6N friction (lubrication-corrected; project units), and friction_highest.
!> FILE: one bead per line "x y z" (blank lines and lines starting with # are ignored).
!> mobility: 3N lines of 3N numbers, row 3(i-1)+a = velocity component, column 3(j-1)+b = force
!> component (project units: an isolated bead has 1/3). shear: N lines of the velocity minus
!> v0 of force-free, torque-free beads in simple shear v0 = (z, 0, 0).
!> Errors: one line on stderr and exit code 2.
program knotflow_mobility
  use, intrinsic :: iso_fortran_env, only: output_unit
  use kf_kinds, only: wp
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_strings, only: to_str
  use kf_cli, only: standard_option, argument, die
  use kf_error, only: error_t
  use kf_text_coords, only: read_coordinates
  use kf_hydro_model, only: hydro_model_t
  use kf_hydro_multipole, only: multipole_model_t
  use kf_multipole_system, only: max_multipole_order
  use kf_hydro_factory, only: make_hydro_model, hydro_model_names, standalone_eps_lub
  use kf_scene_check, only: name_list
  use kf_scene, only: hydro_params_t
  use kf_scene_hydro, only: overlap_names, overlap_bwe, overlap_pair
  use kf_lapack, only: symmetric_eigenvalues, cholesky_factor
  use kf_hydro_limits, only: eps_lub_in_range, eps_lub_range_text
  use kf_blas_threads, only: set_openmp_threads, blas_threads_in_use
  implicit none

  character(len=*), parameter :: program_name = 'knotflow-mobility'

  character(len=:), allocatable :: file, model_name, output, arg, val, overlap
  integer :: order, i, j, nargs, ios, n
  logical :: lubrication, exists
  real(wp) :: eps_lub, e(3, 3)
  real(wp), allocatable :: r(:, :), mu(:, :), u(:, :)
  class(hydro_model_t), allocatable :: model
  type(error_t), allocatable :: error
  logical :: omp_set

  ! The OpenMP pair loops get the BLAS's thread count (OPENBLAS_NUM_THREADS=1: one core; kf_blas_threads).
  call set_openmp_threads(blas_threads_in_use(), omp_set)
  model_name = 'multipole'
  order = 2
  lubrication = .true.
  eps_lub = standalone_eps_lub
  output = 'mobility'
  overlap = overlap_pair
  file = ''

  nargs = command_argument_count()
  i = 1
  do while (i <= nargs)
    arg = argument(i)
    select case (arg)
    case ('-h', '--help', '--version')
      call standard_option(program_name, arg, 'usage: knotflow-mobility FILE [--model none|rpy|multipole] '// &
        '[--order L] [--lubrication on|off] [--eps-lub X] [--overlap RULE] '// &
        '[--output mobility|shear|spectrum]'//new_line('a')// &
        '       knotflow-mobility --help | --version')
    case ('--model', '--order', '--lubrication', '--eps-lub', '--output', '--overlap')
      if (i == nargs) call die(program_name, 'option '//arg//' needs a value', 2)
      val = argument(i + 1)
      i = i + 2
      select case (arg)
      case ('--model')
        if (.not. any(hydro_model_names == val)) &
          call die(program_name, '--model '//val//': allowed values are '//name_list(hydro_model_names), 2)
        model_name = val
      case ('--order')
        read (val, *, iostat=ios) order
        if (ios /= 0 .or. verify(trim(val), '0123456789') /= 0) order = 0
        if (order < 1 .or. order > max_multipole_order) &
          call die(program_name, '--order '//val//': expected an integer 1..'//to_str(max_multipole_order), 2)
      case ('--lubrication')
        if (val /= 'on' .and. val /= 'off') call die(program_name, '--lubrication '//val//': allowed values are on, off', 2)
        lubrication = (val == 'on')
      case ('--eps-lub')
        read (val, *, iostat=ios) eps_lub
        if (ios /= 0) call die(program_name, '--eps-lub '//val//': expected a number in '//eps_lub_range_text(), 2)
        if (.not. eps_lub_in_range(eps_lub)) &
          call die(program_name, '--eps-lub '//val//': expected a number in '//eps_lub_range_text(), 2)
      case ('--output')
        if (val /= 'mobility' .and. val /= 'shear' .and. val /= 'spectrum') &
          call die(program_name, '--output '//val//': allowed values are mobility, shear, spectrum', 2)
        output = val
      case ('--overlap')
        if (.not. any(overlap_names == val)) &
          call die(program_name, '--overlap '//val//': allowed values are '//name_list(overlap_names), 2)
        overlap = val
      end select
    case default
      if (arg(1:min(1, len(arg))) == '-') call die(program_name, 'unknown option '//arg// &
        ' (allowed: --model, --order, --lubrication, --eps-lub, --overlap, --output, --help, --version)', 2)
      if (len(file) > 0) call die(program_name, 'more than one coordinate file given: '//file//' and '//arg, 2)
      file = arg
      i = i + 1
    end select
  end do
  if (len(file) == 0) call die(program_name, 'no coordinate file given (usage: knotflow-mobility FILE [options])', 2)

  inquire (file=file, exist=exists)
  if (.not. exists) call die(program_name, 'cannot open coordinate file '//file//': no such file', 2)
  call read_coordinates(file, r, error)
  if (allocated(error)) call die(program_name, error%message, 2)
  n = size(r, 2)

  select case (model_name)
  case ('multipole')
    block
      type(multipole_model_t), allocatable :: mp
      allocate (mp)
      call mp%init(order, lubrication, eps_lub, error, literal_bwe=(overlap == overlap_bwe))
      if (allocated(error)) call die(program_name, error%message, 2)
      if (output == 'spectrum') call print_spectrum(mp)
      call move_alloc(mp, model)
    end block
  case default
    block
      type(hydro_params_t) :: params
      params%model = model_name
      params%order = order
      params%lubrication = lubrication
      params%eps_lub = eps_lub
      if (overlap /= overlap_pair) call die(program_name, '--overlap '//overlap//' is for the multipole model', 2)
      call make_hydro_model(params, eps_lub, model, error)
      if (allocated(error)) call die(program_name, error%message, 2)
    end block
  end select
  if (output == 'spectrum') call die(program_name, '--output spectrum is for the multipole model', 2)

  call model%prepare(r, error)
  if (allocated(error)) call die(program_name, error%message, 2)

  select case (output)
  case ('mobility')
    allocate (mu(3*n, 3*n))
    call model%mobility_matrix(mu)
    ! never print a non-finite matrix with exit status 0
    if (.not. all(ieee_is_finite(mu))) call die(program_name, 'the '//model_name//' mobility of '//file//' holds '// &
      to_str(count(.not. ieee_is_finite(mu)))//' non-finite entries; nothing printed', 2)
    do i = 1, 3*n
      write (output_unit, '(*(1x, es24.16e3))') (mu(i, j), j = 1, 3*n)
    end do
  case ('shear')
    allocate (u(3, n))
    e = 0.0_wp
    e(1, 3) = 0.5_wp
    e(3, 1) = 0.5_wp
    u = 0.0_wp
    call model%add_strain_disturbance(e, u)
    if (.not. all(ieee_is_finite(u))) call die(program_name, 'the '//model_name//' shear disturbance of '//file// &
      ' holds non-finite values; nothing printed', 2)
    do i = 1, n
      write (output_unit, '(3(1x, es24.16e3))') u(:, i)
    end do
  end select

contains

  !> --output spectrum: the many-body system's and the friction's lowest eigenvalues; stops.
  subroutine print_spectrum(mp)
    type(multipole_model_t), intent(inout) :: mp
    real(wp), allocatable :: w(:), zeta(:, :), zc(:, :)
    type(error_t), allocatable :: err, err2
    integer :: n_over, m
    call mp%many_body_spectrum(r, w, n_over, err)
    if (allocated(err)) call die(program_name, err%message, 2)
    m = min(3, size(w))
    write (output_unit, '(a, 1x, i0)') 'overlapping_pairs', n_over
    call mp%prepare(r, err)
    if (allocated(err)) then
      if (index(err%message, 'multipole system') > 0) then
        write (output_unit, '(a)') 'many_body_cholesky failed: '//err%message
      else
        write (output_unit, '(a)') 'many_body_cholesky ok'
      end if
    else
      write (output_unit, '(a)') 'many_body_cholesky ok'
    end if
    write (output_unit, '(a, *(1x, es24.16e3))') 'many_body_lowest', w(1:m)
    write (output_unit, '(a, 1x, es24.16e3)') 'many_body_highest', w(size(w))
    if (allocated(err)) then
      if (index(err%message, 'multipole system') > 0) stop
    end if
    allocate (zeta(6*n, 6*n))
    call mp%friction_matrix(zeta, err2)
    if (allocated(err2)) call die(program_name, err2%message, 2)
    zc = zeta
    call cholesky_factor(zc, err2, 'friction')
    if (allocated(err2)) then
      write (output_unit, '(a)') 'friction_cholesky failed: '//err2%message
    else
      write (output_unit, '(a)') 'friction_cholesky ok'
    end if
    deallocate (w)
    allocate (w(6*n))
    call symmetric_eigenvalues(zeta, w, err2, 'friction')
    if (allocated(err2)) call die(program_name, err2%message, 2)
    write (output_unit, '(a, *(1x, es24.16e3))') 'friction_lowest', w(1:3)
    write (output_unit, '(a, 1x, es24.16e3)') 'friction_highest', w(6*n)
    stop
  end subroutine print_spectrum

end program knotflow_mobility
