!> Program knotflow-mobility: the 3N x 3N mobility or the shear disturbance of beads read from a file.
!>
!>   knotflow-mobility FILE [--model none|rpy|multipole] [--order L] [--lubrication on|off]
!>                          [--eps-lub X] [--output mobility|shear]
!>
!> Defaults: --model multipole --order 2 --lubrication on --eps-lub 1e-4 --output mobility
!> (eps_lub: overlapping pairs, r <= 1, are evaluated at 1 + eps_lub; it is also passed to the
!> factory as the tolerance for none/rpy, which ignore it).
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
  implicit none

  character(len=*), parameter :: program_name = 'knotflow-mobility'

  character(len=:), allocatable :: file, model_name, output, arg, val
  integer :: order, i, j, nargs, ios, n
  logical :: lubrication, exists
  real(wp) :: eps_lub, e(3, 3)
  real(wp), allocatable :: r(:, :), mu(:, :), u(:, :)
  class(hydro_model_t), allocatable :: model
  type(error_t), allocatable :: error

  model_name = 'multipole'
  order = 2
  lubrication = .true.
  eps_lub = standalone_eps_lub
  output = 'mobility'
  file = ''

  nargs = command_argument_count()
  i = 1
  do while (i <= nargs)
    arg = argument(i)
    select case (arg)
    case ('-h', '--help', '--version')
      call standard_option(program_name, arg, 'usage: knotflow-mobility FILE [--model none|rpy|multipole] '// &
        '[--order L] [--lubrication on|off] [--eps-lub X] [--output mobility|shear]'//new_line('a')// &
        '       knotflow-mobility --help | --version')
    case ('--model', '--order', '--lubrication', '--eps-lub', '--output')
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
        if (ios /= 0) call die(program_name, '--eps-lub '//val//': expected a number in (0, 0.5)', 2)
        if (.not. (eps_lub > 0.0_wp .and. eps_lub < 0.5_wp)) &
          call die(program_name, '--eps-lub '//val//': expected a number in (0, 0.5)', 2)
      case ('--output')
        if (val /= 'mobility' .and. val /= 'shear') &
          call die(program_name, '--output '//val//': allowed values are mobility, shear', 2)
        output = val
      end select
    case default
      if (arg(1:min(1, len(arg))) == '-') call die(program_name, 'unknown option '//arg// &
        ' (allowed: --model, --order, --lubrication, --eps-lub, --output, --help, --version)', 2)
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
      call mp%init(order, lubrication, eps_lub, error)
      if (allocated(error)) call die(program_name, error%message, 2)
      call move_alloc(mp, model)
    end block
  case default
    block
      type(hydro_params_t) :: params
      params%model = model_name
      params%order = order
      params%lubrication = lubrication
      params%eps_lub = eps_lub
      call make_hydro_model(params, eps_lub, model, error)
      if (allocated(error)) call die(program_name, error%message, 2)
    end block
  end select

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

end program knotflow_mobility
