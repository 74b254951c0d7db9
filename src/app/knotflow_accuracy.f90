!> Program knotflow-accuracy: accuracy versus cost of the hydrodynamic models, measured by the code
!> itself (docs/accuracy.md). Parts, selected by flags (default: all):
!>   --models     velocity error and time per evaluation of none, rpy, multipole L = 1..Lref-1
!>                without and with lubrication, against multipole L = Lref with lubrication,
!>                on the open trefoil (N = 99), the compact coil (file) and a loose chain (the
!>                candy-cane initial shape, N = 152)
!>   --tolerance  integration tolerance versus wall time and trajectory deviation (trefoil)
!>   --scaling    time per evaluation versus N (self-avoiding random walks) and fitted exponents
!>   --case-time  wall time of the reference case (N = 99, t_end = 1000, A = 2.2, orientation c,
!>                tolerance 1e-4): measured for none and rpy, extrapolated for multipole
!> Other options: --quick (small sizes and orders: a smoke test of a few seconds), --out DIR
!> (default results/accuracy), --ref-order L (default 6; 2 with --quick), --coil FILE (default
!> inputs/configs/coil_candycane_A1.xyz). Results: DIR/{meta,models,tolerance,scaling,
!> scaling_fit,case_time}.csv and readable tables on stdout. Errors: one line on stderr, exit 2.
program knotflow_accuracy
  use, intrinsic :: iso_fortran_env, only: output_unit
  use kf_kinds, only: wp, i8
  use kf_exit, only: exit_program
  use kf_cli, only: standard_option, argument, die
  use kf_error, only: error_t, fatal_error
  use kf_strings, only: to_str
  use kf_scene, only: scene_t
  use kf_scene_hydro, only: update_stage
  use kf_hydro_limits, only: lubrication_order_max
  use kf_blas_threads, only: set_openmp_threads, blas_threads_in_use
  use kf_fs, only: make_directory
  use kf_chain_shapes, only: build_initial_chain
  use kf_dynamics, only: dynamics_t
  use kf_accuracy, only: wall_seconds, relative_velocity, velocity_error_norms, &
                         time_per_evaluation, max_bead_deviation, loglog_slope, &
                         integrate_timed, run_stats_t
  implicit none

  character(len=*), parameter :: program_name = 'knotflow-accuracy'

  !> One hydrodynamic model of the comparison.
  type :: model_t
    character(len=16) :: label = ''
    character(len=16) :: name = ''
    integer :: order = 0
    logical :: lubrication = .false.
  end type model_t

  !> Settings of one invocation (full or --quick).
  type :: settings_t
    logical :: quick = .false.
    character(len=:), allocatable :: out, coil
    integer :: ref_order = 6
    real(wp) :: min_seconds = 0.5_wp      !< timing: at least this long ...
    integer :: min_evals = 3              !< ... and this many evaluations,
    real(wp) :: max_seconds = 15.0_wp     !< ... unless this much time has passed
    real(wp) :: bending_a = 1.4_wp        !< bending stiffness of the velocity comparison
  end type settings_t

  type(settings_t) :: cfg
  type(error_t), allocatable :: error
  logical :: do_models, do_tolerance, do_scaling, do_case_time, any_part
  character(len=:), allocatable :: arg, value
  integer :: i, nargs, ios
  real(wp) :: t_start
  logical :: omp_set

  ! The OpenMP pair loops get the BLAS's thread count (OPENBLAS_NUM_THREADS=1: one core; kf_blas_threads).
  call set_openmp_threads(blas_threads_in_use(), omp_set)
  cfg%out = 'results/accuracy'
  cfg%coil = 'inputs/configs/coil_candycane_A1.xyz'
  do_models = .false.
  do_tolerance = .false.
  do_scaling = .false.
  do_case_time = .false.
  cfg%ref_order = -1
  nargs = command_argument_count()
  i = 1
  do while (i <= nargs)
    arg = argument(i)
    i = i + 1
    select case (arg)
    case ('--models')
      do_models = .true.
    case ('--tolerance')
      do_tolerance = .true.
    case ('--scaling')
      do_scaling = .true.
    case ('--case-time')
      do_case_time = .true.
    case ('--all')
      do_models = .true.
      do_tolerance = .true.
      do_scaling = .true.
      do_case_time = .true.
    case ('--quick')
      cfg%quick = .true.
    case ('--out', '--ref-order', '--coil')
      if (i > nargs) call die(program_name, 'option '//arg//' needs a value', 2)
      select case (arg)
      case ('--out')
        cfg%out = argument(i)
      case ('--coil')
        cfg%coil = argument(i)
      case ('--ref-order')
        value = argument(i)
        read (value, *, iostat=ios) cfg%ref_order
        if (ios /= 0 .or. verify(value, '0123456789') /= 0) &
          call die(program_name, '--ref-order '//value//': expected an integer 2..'//to_str(lubrication_order_max), 2)
        if (cfg%ref_order < 2 .or. cfg%ref_order > lubrication_order_max) &
          call die(program_name, '--ref-order '//value//': expected an integer 2..'//to_str(lubrication_order_max), 2)
      end select
      i = i + 1
    case ('-h', '--help', '--version')
      call standard_option(program_name, arg, 'usage: knotflow-accuracy [--models] [--tolerance] [--scaling] '// &
        '[--case-time] [--all] [--quick] [--out DIR] [--ref-order L] [--coil FILE]')
    case default
      call die(program_name, "unknown argument '"//arg//"' (allowed: --models --tolerance --scaling "// &
        "--case-time --all --quick --out DIR --ref-order L --coil FILE --help --version)", 2)
    end select
  end do
  any_part = do_models .or. do_tolerance .or. do_scaling .or. do_case_time
  if (.not. any_part) then
    do_models = .true.
    do_tolerance = .true.
    do_scaling = .true.
    do_case_time = .true.
  end if
  if (cfg%quick) then
    if (cfg%ref_order < 0) cfg%ref_order = 2
    cfg%min_seconds = 0.0_wp
    cfg%min_evals = 1
    cfg%max_seconds = 0.2_wp
  else if (cfg%ref_order < 0) then
    cfg%ref_order = 6
  end if

  call make_directory(cfg%out, error)
  if (allocated(error)) call die(program_name, error%message, 2)
  t_start = wall_seconds()
  call write_meta(cfg, error)
  if (allocated(error)) call die(program_name, error%message, 2)
  if (do_models) call part_models(cfg, error)
  if (allocated(error)) call die(program_name, error%message, 2)
  if (do_tolerance) call part_tolerance(cfg, error)
  if (allocated(error)) call die(program_name, error%message, 2)
  if (do_scaling) call part_scaling(cfg, error)
  if (allocated(error)) call die(program_name, error%message, 2)
  if (do_case_time) call part_case_time(cfg, error)
  if (allocated(error)) call die(program_name, error%message, 2)
  call append_meta('loadavg_end', load_average(), error)
  if (allocated(error)) call die(program_name, error%message, 2)
  write (output_unit, '(a)') '# knotflow-accuracy: done in '//to_str(wall_seconds() - t_start, '(f10.1)')// &
    ' s; results in '//cfg%out
  call exit_program(0)

contains

  !> A model entry.
  function make_model(name, order, lubrication) result(m)
    character(len=*), intent(in) :: name
    integer, intent(in) :: order
    logical, intent(in) :: lubrication
    type(model_t) :: m
    m%name = name
    m%order = order
    m%lubrication = lubrication
    if (name == 'multipole') then
      m%label = 'L'//to_str(order)
      if (lubrication) m%label = trim(m%label)//'+lub'
    else
      m%label = name
    end if
  end function make_model

  !> The scene of a configuration for one model (forces: springs k = 500, bending; shear 1).
  subroutine apply_model(scene, m)
    type(scene_t), intent(inout) :: scene
    type(model_t), intent(in) :: m
    scene%hydro%model = m%name
    scene%hydro%order = max(1, m%order)
    scene%hydro%lubrication = m%lubrication
    ! The exact solve at every stage: this report measures the models themselves (the adaptive
    ! reuse of the multipole part is measured by knotflow-bench-reuse).
    scene%hydro%update = update_stage
  end subroutine apply_model

  !> The force-driven part mu(r) F(r) of the bead velocities (exact at r).
  subroutine force_part(dyn, r, uf, error)
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: uf(:, :)
    type(error_t), allocatable, intent(out) :: error
    call dyn%force_velocity(r, uf, error)
  end subroutine force_part

  !> Open DIR/name for writing and write the header line.
  subroutine open_csv(name, header, unit, error)
    character(len=*), intent(in) :: name, header
    integer, intent(out) :: unit
    type(error_t), allocatable, intent(out) :: error
    integer :: ios
    character(len=256) :: msg
    open (newunit=unit, file=cfg%out//'/'//name, status='replace', action='write', iostat=ios, iomsg=msg)
    if (ios /= 0) then
      call fatal_error(error, 'cannot write '//cfg%out//'/'//name//': '//trim(msg))
      return
    end if
    call put_line(unit, header, error)
  end subroutine open_csv

  !> Write one line to a results file.
  subroutine put_line(unit, line, error)
    integer, intent(in) :: unit
    character(len=*), intent(in) :: line
    type(error_t), allocatable, intent(out) :: error
    integer :: ios
    character(len=256) :: msg
    write (unit, '(a)', iostat=ios, iomsg=msg) line
    if (ios /= 0) call fatal_error(error, 'writing a results file: '//trim(msg))
  end subroutine put_line

  !> Close a results file.
  subroutine close_csv(unit, error)
    integer, intent(in) :: unit
    type(error_t), allocatable, intent(out) :: error
    integer :: ios
    character(len=256) :: msg
    close (unit, iostat=ios, iomsg=msg)
    if (ios /= 0) call fatal_error(error, 'closing a results file: '//trim(msg))
  end subroutine close_csv

  !> A real for the CSV tables (6 significant digits).
  function es(x) result(s)
    real(wp), intent(in) :: x
    character(len=:), allocatable :: s
    s = to_str(x, '(es12.5)')
  end function es

  !> A logical for the CSV tables: 1 or 0.
  function lg(x) result(s)
    logical, intent(in) :: x
    character(len=:), allocatable :: s
    s = merge('1', '0', x)
  end function lg

  !> The load average of the machine (first line of /proc/loadavg), or 'unknown'.
  function load_average() result(s)
    character(len=:), allocatable :: s
    integer :: unit, ios
    character(len=128) :: line
    s = 'unknown'
    open (newunit=unit, file='/proc/loadavg', status='old', action='read', iostat=ios)
    if (ios /= 0) return
    read (unit, '(a)', iostat=ios) line
    if (ios == 0) s = trim(line)
    close (unit, iostat=ios)
  end function load_average

  !> DIR/meta.csv: the settings of the run and the load at its start.
  subroutine write_meta(cfg, error)
    type(settings_t), intent(in) :: cfg
    type(error_t), allocatable, intent(out) :: error
    integer :: unit
    call open_csv('meta.csv', 'key,value', unit, error)
    if (allocated(error)) return
    call put_line(unit, 'quick,'//lg(cfg%quick), error)
    if (allocated(error)) return
    call put_line(unit, 'ref_order,'//to_str(cfg%ref_order), error)
    if (allocated(error)) return
    call put_line(unit, 'bending_a_models,'//to_str(cfg%bending_a, '(f6.2)'), error)
    if (allocated(error)) return
    call put_line(unit, 'coil_file,'//cfg%coil, error)
    if (allocated(error)) return
    call put_line(unit, 'loadavg_start,'//load_average(), error)
    if (allocated(error)) return
    call close_csv(unit, error)
  end subroutine write_meta

  !> Append one key,value line to DIR/meta.csv.
  subroutine append_meta(key, value, error)
    character(len=*), intent(in) :: key, value
    type(error_t), allocatable, intent(out) :: error
    integer :: unit, ios
    character(len=256) :: msg
    open (newunit=unit, file=cfg%out//'/meta.csv', status='old', position='append', action='write', &
          iostat=ios, iomsg=msg)
    if (ios /= 0) then
      call fatal_error(error, 'cannot append to '//cfg%out//'/meta.csv: '//trim(msg))
      return
    end if
    call put_line(unit, key//','//value, error)
    if (allocated(error)) return
    call close_csv(unit, error)
  end subroutine append_meta

  !> Velocity errors and time per evaluation of every model on the three configurations.
  subroutine part_models(cfg, error)
    type(settings_t), intent(in) :: cfg
    type(error_t), allocatable, intent(out) :: error
    character(len=8), parameter :: configs(3) = ['trefoil ', 'coil    ', 'loose   ']
    type(model_t), allocatable :: models(:)
    type(model_t) :: ref
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    real(wp), allocatable :: r(:, :), u(:, :), u_ref(:, :), uf_ref(:, :), uf(:, :)
    real(wp) :: rot(3, 3), rms, max_rel, t_eval, rms_force, rms_shear, dummy
    integer :: ic, im, unit, n, n_evals, l, n_configs
    character(len=:), allocatable :: status

    allocate (models(0))
    models = [models, make_model('none', 0, .false.), make_model('rpy', 0, .false.)]
    do l = 1, cfg%ref_order - 1
      models = [models, make_model('multipole', l, .false.), make_model('multipole', l, .true.)]
    end do
    ref = make_model('multipole', cfg%ref_order, .true.)
    models = [models, ref]

    call open_csv('models.csv', 'config,n,model,order,lubrication,rms_rel,max_rel,rms_force,rms_shear,'// &
                  't_eval,n_evals,status', &
                  unit, error)
    if (allocated(error)) return
    n_configs = 3
    if (cfg%quick) n_configs = 1
    write (output_unit, '(a)') '# velocity error against multipole L = '//to_str(cfg%ref_order)// &
      ' + lubrication (u = dr/dt - v0(r); springs k = 500, bending A = '// &
      to_str(cfg%bending_a, '(f4.2)')//', shear rate 1)'
    write (output_unit, '(a8,a5,a10,4a12,a14,a7)') 'config', 'N', 'model', 'rms rel', 'max rel', &
      'rms force', 'rms shear', 't_eval [s]', 'evals'
    do ic = 1, n_configs
      scene = scene_t()
      scene%forces%bending_a = cfg%bending_a
      select case (trim(configs(ic)))
      case ('trefoil')
        scene%chain%shape = 'trefoil'
      case ('coil')
        scene%chain%shape = 'file'
        scene%chain%coordinate_file = cfg%coil
      case ('loose')
        scene%chain%shape = 'candycane'
      end select
      call build_initial_chain(scene%chain, r, rot, error)
      if (allocated(error)) return
      n = size(r, 2)
      allocate (u(3, n), u_ref(3, n), uf_ref(3, n), uf(3, n))
      ! The reference first.
      call apply_model(scene, ref)
      call dyn%init(scene, n, error)
      if (allocated(error)) return
      call relative_velocity(dyn, r, u_ref, error)
      if (allocated(error)) then
        call fatal_error(error, trim(configs(ic))//': reference '//trim(ref%label)//': '//error%message)
        return
      end if
      call force_part(dyn, r, uf_ref, error)
      if (allocated(error)) return
      do im = 1, size(models)
        call apply_model(scene, models(im))
        call dyn%init(scene, n, error)
        if (allocated(error)) return
        status = 'ok'
        call relative_velocity(dyn, r, u, error)
        if (allocated(error)) then
          status = 'failed: '//error%message
          deallocate (error)
          rms = -1.0_wp
          max_rel = -1.0_wp
          rms_force = -1.0_wp
          rms_shear = -1.0_wp
          t_eval = -1.0_wp
          n_evals = 0
        else
          call velocity_error_norms(u, u_ref, rms, max_rel)
          ! uf is the force-driven part mu F; the rest is the disturbance of the flow.
          call force_part(dyn, r, uf, error)
          if (allocated(error)) return
          call velocity_error_norms(uf, uf_ref, rms_force, dummy)
          call velocity_error_norms(u - uf, u_ref - uf_ref, rms_shear, dummy)
          call time_per_evaluation(dyn, r, cfg%min_evals, cfg%min_seconds, cfg%max_seconds, &
                                   t_eval, n_evals, error)
          if (allocated(error)) return
        end if
        call put_line(unit, trim(configs(ic))//','//to_str(n)//','//trim(models(im)%name)//','// &
          to_str(models(im)%order)//','//lg(models(im)%lubrication)//','//es(rms)//','// &
          es(max_rel)//','//es(rms_force)//','//es(rms_shear)//','//es(t_eval)//','// &
          to_str(n_evals)//','//status, error)
        if (allocated(error)) return
        write (output_unit, '(a8,i5,a10,4es12.3,es14.4,i7,1x,a)') trim(configs(ic)), n, &
          trim(models(im)%label), rms, max_rel, rms_force, rms_shear, t_eval, n_evals, trim(status)
        flush (output_unit)
      end do
      deallocate (u, u_ref, uf_ref)
    end do
    call close_csv(unit, error)
  end subroutine part_models

  !> Tolerance versus wall time and deviation from a tight-tolerance trajectory (trefoil,
  !> orientation a, A = 2.2): rpy and multipole L = 2 + lubrication (eps_lub fixed at 1e-4 so
  !> that only the integration changes with the tolerance).
  subroutine part_tolerance(cfg, error)
    type(settings_t), intent(in) :: cfg
    type(error_t), allocatable, intent(out) :: error
    type(scene_t) :: scene
    type(run_stats_t) :: stats
    type(model_t) :: models(2), m
    real(wp), allocatable :: r0(:, :), r(:, :), r_ref(:, :), tols(:)
    real(wp) :: rot(3, 3), t_end, tol_ref
    integer :: im, it, unit, n_models

    models(1) = make_model('rpy', 0, .false.)
    models(2) = make_model('multipole', 2, .true.)
    n_models = 2
    allocate (tols(0))
    if (cfg%quick) then
      n_models = 1
      tols = [1.0e-3_wp, 1.0e-4_wp, 1.0e-5_wp]
    else
      tols = [1.0e-3_wp, 1.0e-4_wp, 1.0e-5_wp, 1.0e-6_wp, 1.0e-7_wp]
    end if
    call open_csv('tolerance.csv', 'model,order,lubrication,t_end,tolerance,wall,steps,rejected,'// &
                  'evaluations,max_deviation,ref_tolerance', unit, error)
    if (allocated(error)) return
    write (output_unit, '(a)') '# integration tolerance: trefoil (N = 99, orientation a, A = 2.2) '// &
      'from t = 0; deviation = max over beads |r - r_ref| at t_end'
    write (output_unit, '(a10,a8,a10,a10,a10,a9,a12,a12)') 'model', 't_end', 'tol', 'wall [s]', &
      'steps', 'rejected', 'evals', 'max dev'
    do im = 1, n_models
      m = models(im)
      scene = scene_t()
      call apply_model(scene, m)
      scene%hydro%eps_lub = 1.0e-4_wp
      if (m%name == 'rpy') then
        t_end = 20.0_wp
        tol_ref = 1.0e-9_wp
        if (cfg%quick) t_end = 2.0_wp
        if (cfg%quick) tol_ref = 1.0e-7_wp
      else
        t_end = 0.5_wp
        tol_ref = 1.0e-8_wp
      end if
      call build_initial_chain(scene%chain, r0, rot, error)
      if (allocated(error)) return
      r_ref = r0
      scene%integrator%tolerance = tol_ref
      call integrate_timed(scene, r_ref, t_end, stats, error)
      if (allocated(error)) return
      call tolerance_row(unit, m, t_end, tol_ref, tol_ref, stats, r_ref, r_ref, error)
      if (allocated(error)) return
      do it = 1, size(tols)
        r = r0
        scene%integrator%tolerance = tols(it)
        call integrate_timed(scene, r, t_end, stats, error)
        if (allocated(error)) return
        call tolerance_row(unit, m, t_end, tols(it), tol_ref, stats, r, r_ref, error)
        if (allocated(error)) return
      end do
    end do
    call close_csv(unit, error)
  end subroutine part_tolerance

  !> One row of the tolerance table (file and screen).
  subroutine tolerance_row(unit, m, t_end, tol, tol_ref, stats, r, r_ref, error)
    integer, intent(in) :: unit
    type(model_t), intent(in) :: m
    real(wp), intent(in) :: t_end, tol, tol_ref
    type(run_stats_t), intent(in) :: stats
    real(wp), intent(in) :: r(:, :), r_ref(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: dev
    dev = max_bead_deviation(r, r_ref)
    call put_line(unit, trim(m%name)//','//to_str(m%order)//','//lg(m%lubrication)//','// &
      es(t_end)//','//es(tol)//','//es(stats%wall)//','//to_str(stats%steps)//','// &
      to_str(stats%rejected)//','//to_str(stats%evaluations)//','//es(dev)//','//es(tol_ref), error)
    write (output_unit, '(a10,f8.2,es10.1,f10.3,i10,i9,i12,es12.3)') trim(m%label), t_end, tol, &
      stats%wall, stats%steps, stats%rejected, stats%evaluations, dev
    flush (output_unit)
  end subroutine tolerance_row

  !> Time per evaluation versus N for self-avoiding random walks (shape 'random', bond 1.02,
  !> fixed seed); sizes predicted (cubic growth from the previous size) to take longer than
  !> the limit per evaluation are skipped. Exponent: least squares over the (up to) three
  !> largest measured sizes.
  subroutine part_scaling(cfg, error)
    type(settings_t), intent(in) :: cfg
    type(error_t), allocatable, intent(out) :: error
    type(model_t), allocatable :: models(:)
    integer, allocatable :: sizes(:)
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    real(wp), allocatable :: r(:, :), times(:)
    real(wp) :: rot(3, 3), t_eval, predicted, limit, slope
    integer :: im, is, unit, unit_fit, n_evals, n_ok, first
    character(len=:), allocatable :: status

    if (cfg%quick) then
      sizes = [25, 50]
      models = [make_model('none', 0, .false.), make_model('rpy', 0, .false.), &
                make_model('multipole', 1, .true.)]
      limit = 2.0_wp
    else
      sizes = [25, 50, 100, 200, 400]
      models = [make_model('none', 0, .false.), make_model('rpy', 0, .false.), &
                make_model('multipole', 1, .true.), make_model('multipole', 2, .false.), &
                make_model('multipole', 2, .true.), make_model('multipole', 3, .true.)]
      limit = 30.0_wp
    end if
    allocate (times(size(sizes)))
    call open_csv('scaling.csv', 'model,order,lubrication,n,t_eval,n_evals,status', unit, error)
    if (allocated(error)) return
    call open_csv('scaling_fit.csv', 'model,order,lubrication,exponent,n_min,n_max,points', unit_fit, error)
    if (allocated(error)) return
    write (output_unit, '(a)') '# time per evaluation [s] versus N (self-avoiding random walks, '// &
      'bond 1.02); exponent: least squares over the largest sizes'
    write (output_unit, '(a10,*(i12))') 'model', sizes
    do im = 1, size(models)
      times = -1.0_wp
      n_ok = 0
      do is = 1, size(sizes)
        status = 'ok'
        t_eval = -1.0_wp
        n_evals = 0
        if (is > 1) then
          predicted = times(is - 1)*(real(sizes(is), wp)/sizes(is - 1))**3
          if (times(is - 1) < 0.0_wp .or. predicted > limit) status = 'skipped'
        end if
        if (status == 'ok') then
          scene = scene_t()
          scene%chain%shape = 'random'
          scene%chain%n_beads = sizes(is)
          call apply_model(scene, models(im))
          call build_initial_chain(scene%chain, r, rot, error)
          if (allocated(error)) return
          call dyn%init(scene, sizes(is), error)
          if (allocated(error)) return
          call time_per_evaluation(dyn, r, cfg%min_evals, cfg%min_seconds, cfg%max_seconds, &
                                   t_eval, n_evals, error)
          if (allocated(error)) then
            status = 'failed: '//error%message
            deallocate (error)
            t_eval = -1.0_wp
          else
            times(is) = t_eval
            n_ok = is
          end if
        end if
        call put_line(unit, trim(models(im)%name)//','//to_str(models(im)%order)//','// &
          lg(models(im)%lubrication)//','//to_str(sizes(is))//','//es(t_eval)//','// &
          to_str(n_evals)//','//status, error)
        if (allocated(error)) return
      end do
      ! Measured sizes are a prefix 1..n_ok; fit the last (up to) three.
      slope = -1.0_wp
      first = max(1, n_ok - 2)
      if (n_ok >= 2) then
        call loglog_slope(real(sizes(first:n_ok), wp), times(first:n_ok), slope, error)
        if (allocated(error)) return
        call put_line(unit_fit, trim(models(im)%name)//','//to_str(models(im)%order)//','// &
          lg(models(im)%lubrication)//','//to_str(slope, '(f8.3)')//','//to_str(sizes(first))// &
          ','//to_str(sizes(n_ok))//','//to_str(n_ok - first + 1), error)
        if (allocated(error)) return
      end if
      write (output_unit, '(a10,*(es12.3))', advance='no') trim(models(im)%label), times
      write (output_unit, '(a,f6.2)') '   exponent ', slope
      flush (output_unit)
    end do
    call close_csv(unit, error)
    if (allocated(error)) return
    call close_csv(unit_fit, error)
  end subroutine part_scaling

  !> Wall time of the reference case (trefoil N = 99, A = 2.2, orientation c, tolerance 1e-4,
  !> t_end = 1000). none and rpy: run in full (measured). multipole (and rpy again, as a check
  !> of the method): extrapolated as (evaluations per unit time over a short window after a
  !> warm-up) x t_end x (median time per evaluation at t = 0); the rate is measured for rpy and
  !> L = 1, 2 (+ lubrication) and, for higher orders, taken from L = 2.
  subroutine part_case_time(cfg, error)
    type(settings_t), intent(in) :: cfg
    type(error_t), allocatable, intent(out) :: error
    type(scene_t) :: scene
    type(run_stats_t) :: stats
    type(dynamics_t) :: dyn
    type(model_t), allocatable :: models(:)
    logical, allocatable :: extrapolate(:)
    real(wp), allocatable :: r(:, :)
    real(wp) :: rot(3, 3), t_end, t_warm, t_window, rate, rate_l2, t_eval, wall
    integer :: im, unit, n_evals, l, l_max
    character(len=:), allocatable :: kind, rate_source

    t_end = 1000.0_wp
    t_warm = 0.1_wp
    t_window = 0.5_wp
    l_max = 5
    if (cfg%quick) then
      t_end = 10.0_wp
      t_warm = 0.05_wp
      t_window = 0.05_wp
      l_max = 1
    end if
    allocate (models(0), extrapolate(0))
    models = [models, make_model('none', 0, .false.), make_model('rpy', 0, .false.), &
              make_model('rpy', 0, .false.)]
    extrapolate = [extrapolate, .false., .false., .true.]
    do l = 1, l_max
      models = [models, make_model('multipole', l, .true.)]
      extrapolate = [extrapolate, .true.]
    end do
    call open_csv('case_time.csv', 'model,order,lubrication,kind,t_end,wall,evaluations,'// &
                  'evals_per_time,t_eval,rate_source', unit, error)
    if (allocated(error)) return
    write (output_unit, '(a)') '# reference case: trefoil N = 99, A = 2.2, orientation c, '// &
      'tolerance 1e-4, t_end = '//to_str(t_end, '(f7.1)')
    write (output_unit, '(a10,a14,a14,a14,a14,2x,a)') 'model', 'wall [s]', 'evals/time', &
      't_eval [s]', 'wall [h]', 'kind'
    rate_l2 = -1.0_wp
    do im = 1, size(models)
      scene = scene_t()
      scene%chain%orientation = 'c'
      scene%forces%bending_a = 2.2_wp
      scene%integrator%tolerance = 1.0e-4_wp
      call apply_model(scene, models(im))
      call build_initial_chain(scene%chain, r, rot, error)
      if (allocated(error)) return
      if (.not. extrapolate(im)) then
        kind = 'measured'
        rate_source = 'full run'
        call integrate_timed(scene, r, t_end, stats, error)
        if (allocated(error)) return
        wall = stats%wall
        rate = real(stats%evaluations, wp)/t_end
        t_eval = stats%wall/real(max(1_i8, stats%evaluations), wp)
      else
        kind = 'extrapolated'
        call dyn%init(scene, size(r, 2), error)
        if (allocated(error)) return
        call time_per_evaluation(dyn, r, cfg%min_evals, cfg%min_seconds, cfg%max_seconds, &
                                 t_eval, n_evals, error)
        if (allocated(error)) return
        if (models(im)%order <= 2) then
          call integrate_timed(scene, r, t_warm + t_window, stats, error, t_skip=t_warm)
          if (allocated(error)) return
          rate = real(stats%evaluations, wp)/t_window
          rate_source = 'rate over t = '//to_str(t_warm, '(f4.2)')//'..'//to_str(t_warm + t_window, '(f4.2)')
          if (models(im)%order == 2) rate_l2 = rate
        else
          rate = rate_l2
          rate_source = 'rate of L2+lub'
        end if
        wall = rate*t_end*t_eval
      end if
      call put_line(unit, trim(models(im)%name)//','//to_str(models(im)%order)//','// &
        lg(models(im)%lubrication)//','//kind//','//es(t_end)//','//es(wall)//','// &
        to_str(nint(rate*t_end, i8))//','//es(rate)//','//es(t_eval)//','//rate_source, error)
      if (allocated(error)) return
      write (output_unit, '(a10,es14.4,f14.1,es14.4,f14.3,2x,a)') trim(models(im)%label), wall, &
        rate, t_eval, wall/3600.0_wp, kind//' ('//rate_source//')'
      flush (output_unit)
    end do
    call close_csv(unit, error)
  end subroutine part_case_time

end program knotflow_accuracy
