!> Program knotflow-bench-reuse: accuracy and cost of the adaptive reuse of the multipole many-body
!> part (`&hydro update = 'adaptive'`) against the exact solve at every stage ('stage'), on the
!> study's model (multipole L = 2 + lubrication, eps_lub = tolerance, shear flow) with the overlap
!> rule of the multipole campaign (`--overlap`, default relax, a variant of ours).
!>
!> Usage: knotflow-bench-reuse PART [options]
!>   velocity   [--config C] [--t-end T] [--every K] [--update iterative] [--solver-tolerance S]
!>              [--single-operator yes|no]: integrate with the adaptive path (or the iterative
!>              one, with its solver_tolerance S; --single-operator yes: its whole operator in
!>              single at any S and chain length, no: never) and, at every K-th stage, compare
!>              its velocities with the exact ones at the same positions
!>   trajectory [--config C] [--t-end T]: largest bead deviation at T between the two paths at
!>              tolerance 1e-4, and of the exact path between tolerances 1e-4 and 1e-6
!>   speed      [--config C] [--t-end T]: wall time of both paths to T and their ratio
!>   compare    [--config C] [--t-end T]: 'stage', 'adaptive' and 'iterative' in one run at
!>              tolerance 1e-4: wall times, ratios to 'stage', largest bead deviation from
!>              'stage' at T, iterations per iterative solve, factorisations
!>   scaling    [--t-end T]: adaptive wall time per unit time for random chains N = 50..400
!>   overlaps   [--config C] [--t-end T] [--eps-lub E]: overlap statistics (run
!>              diagnostics) of both paths
!>   stiffness  [--config C] [--t-end T] [--update U] [--tolerance TOL] [--table FILE]: which
!>              limit sets dopri45's step: at every trial step lambda_max*h of mu dF/dr
!>              (kf_stiffness_probe), the error estimate and the outcome; per-trial rows into
!>              FILE, a summary on stdout; TOL (default 1e-4) is the dopri45 tolerance only
!>              (eps_lub stays 1e-4 unless --eps-lub is given)
!>   threads    [--config C] [--t-end T]: both cores for one case: one evaluation ('stage'
!>              prepare, best of 5; assembly, factorisation, lubrication blocks) at N = 99
!>              (trefoil) and N = 152 (candy-cane), then 'stage' and 'iterative' from 0 to T,
!>              each with 1 and with 2 threads (OpenMP pair loops and OpenBLAS together; needs
!>              OPENBLAS_NUM_THREADS unset), the ratios 1 thread / 2 threads, the largest bead
!>              deviation between the thread counts at T and the load average at every figure
!>   evaluation [--config C]: the cost of one evaluation of the study's model, split: processor
!>              seconds (cpu_time, best of 5-20 repetitions) of the assembly of K, the
!>              lubrication blocks, the 6N friction Cholesky of an 'iterative' call that
!>              refactorises it, the largest scaled change of the lubrication blocks (the rule
!>              that decides it) between the start and a configuration deformed by 0.003 d per
!>              bead, one product K x (and in single precision, with the cost of the single
!>              copies of K0 and B), one triangular-solve pair with the factor of K and with
!>              its single-precision copy, the assembly with the single copies of K0 and B,
!>              and of whole 'iterative' calls (at that deformed
!>              configuration: the GMRES solve from zero, the forces and strain changing sign
!>              between repetitions so that the last solution is no start, the 6N factor
!>              refactorised where its rule says (the number of such factorisations printed);
!>              a factorising call) and 'stage' calls; then whole 'iterative' calls from the
!>              last call's solution, the configuration alternating with one 0.001 d further,
!>              with the Krylov loop's products in single where the rule allows (at any size)
!>              and always in double, the two interleaved in 100 pairs (medians and the median
!>              ratio)
!>   rosenbrock [--config C] [--t-end T] [--model M] [--jacobian-steps K] [--rosenbrock-stage
!>              yes|no] [--steppers LIST] [--tolerance TOL]: the Rosenbrock-W steppers of LIST
!>              (comma-separated, default ros34pw2,ros34pw3) at tolerance TOL (default 1e-4)
!>              against dopri45 at tolerance 1e-4 in one run: with 'stage' (with the multipole model unless
!>              --rosenbrock-stage no; dopri45 'stage' always, the reference) and 'iterative'
!>              (multipole; rpy: the one exact path), each Rosenbrock 'iterative' also with
!>              the mobility of its Jacobian kept for K steps (&integrator jacobian_steps,
!>              default 4; after a 'stage' evaluation a new mobility costs nothing); per run wall time, steps, rejected,
!>              velocity evaluations (per unit time), Jacobians, processor seconds (cpu_time)
!>              and the load average at its end, and the largest bead deviation
!>              at T from dopri45 'stage'; the cost of one Jacobian (after an evaluation at its
!>              positions, and cold). M: multipole (the study's model, default) or rpy.
!>              --jacobian-order J: each Rosenbrock 'iterative' run also with the Jacobian's
!>              mobility of order J (&hydro jacobian_order; labels <method>_jorder<J>...)
!>              --friction-change F: each 'iterative' run followed by the same run with the
!>              iterative model's 6N friction factor threshold friction_change = F (labels
!>              <run>_fc<F>.iterative; F = 0: refactorised at every call, as before)
!>              --warm-history K: each 'iterative' run followed by the same run with the
!>              iterative model's warm_history = K (labels <run>_wh<K>.iterative; K = 1: GMRES
!>              starts from the last call's solution, as before)
!>              --refactor-iterations K: each 'iterative' run followed by the same run with
!>              the iterative model's refactor_iterations = K (labels <run>_ri<K>.iterative;
!>              the next call factorises after a call with more than K GMRES iterations)
!>              --solver-tolerance S: each 'iterative' run followed by the same run with the
!>              iterative model's solver_tolerance = S (labels <run>_st<S>.iterative; the
!>              default kf_hydro_limits' solver_tolerance_default)
!>              --double-products yes: each 'iterative' run followed by the same run with the
!>              Krylov loop's products always in double (single_products = .false.; labels
!>              <run>_double.iterative; the model before the single-precision products)
!>              --single-operator no: each 'iterative' run followed by the same run with K0
!>              assembled in double and the start's residual in double at every solver tolerance
!>              (single_operator_tolerance = huge; labels <run>_loopsingle.iterative, with
!>              --solver-tolerance S at S: <run>_st<S>_loopsingle.iterative; the model before
!>              the whole operator in single)
!>              --single-min-beads K: each 'iterative' run followed by the same run with the
!>              iterative model's single_min_beads and single_operator_min_beads = K (labels
!>              <run>_smb<K>.iterative, with --solver-tolerance S at S:
!>              <run>_st<S>_smb<K>.iterative; the single products and the whole operator in
!>              single on chains shorter than the defaults')
!>   rigid      [--config C]: the reused part at rigidly moved and at deformed configurations
!>              (overlap rule pair only: the model's reused part against its exact one, both
!>              without the dynamics' configuration rules separate and relax)
!> C: trefoil (N = 99, orientation c, A = 2.2; default), random60 (a self-avoiding random chain,
!> N = 60, the &chain default seed, A = 1.3), coil (inputs/configs/
!> coil_candycane_A1.xyz, A = 1) or a coordinate file path (A = 1). --overlap RULE: the &hydro
!> overlap rule, one of kf_scene_hydro's overlap_names (default relax, as inputs/*_multipole.nml;
!> rigid: pair). Output:
!> `key = value` lines
!> (read by knotflow-accuracy-report --reuse).
program knotflow_bench_reuse
  use, intrinsic :: iso_fortran_env, only: output_unit
  use kf_kinds, only: wp, sp, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t
  use kf_scene, only: scene_t
  use kf_scene_hydro, only: overlap_names, overlap_pair, overlap_relax, update_names, update_default, update_stage, &
    update_adaptive, update_iterative
  use kf_scene_integrator, only: jacobian_steps_max, method_dopri45, method_ros34pw2, method_ros34pw3
  use kf_scene_check, only: name_list
  use kf_hydro_limits, only: eps_lub_in_range, eps_lub_range_text, solver_tolerance_min, solver_tolerance_max
  use kf_chain_shapes, only: build_initial_chain
  use kf_dynamics, only: dynamics_t
  use kf_stepper, only: stepper_t
  use kf_stepper_factory, only: make_stepper
  use kf_stepper_rosenbrock, only: rosenbrock_stepper_t
  use kf_hydro_model, only: hydro_stats_t, hydro_model_t
  use kf_hydro_factory, only: make_hydro_model
  use kf_hydro_multipole, only: multipole_model_t
  use kf_reuse_check, only: checked_dynamics_t
  use kf_run_diagnostics, only: run_diagnostics_t
  use kf_cli, only: standard_option, argument, die
  use kf_accuracy, only: wall_seconds, max_bead_deviation, loglog_slope, median
  use kf_stiffness_probe, only: stiffness_probe_t, stability_boundary
  use kf_blas_threads, only: set_blas_threads, blas_threads_in_use, openmp_threads_in_use, use_openmp_threads, &
    set_openmp_threads
  use kf_scene_chain, only: chain_params_t
  use kf_multipole_system, only: multipole_system_t
  use kf_hydro_multipole_iterative, only: multipole_iterative_t, warm_history_max, max_iterations
  use kf_lubrication, only: lubrication_t
  use kf_pair_blocks, only: pair_blocks_t
  use kf_lapack, only: cholesky_factor
  implicit none

  character(len=*), parameter :: program_name = 'knotflow-bench-reuse'

  character(len=:), allocatable :: part, config, overlap, update, table, model, steppers
  real(wp) :: t_end, eps_lub, tolerance, friction_change, solver_tolerance
  logical :: double_products, loop_single, force_single
  integer :: every, jacobian_steps, jacobian_order, warm_history, refactor_iterations, min_beads_single
  logical :: omp_set, rosenbrock_stage

  ! The OpenMP pair loops get the BLAS's thread count (OPENBLAS_NUM_THREADS=1: one core; kf_blas_threads).
  call set_openmp_threads(blas_threads_in_use(), omp_set)
  call parse_arguments()
  select case (part)
  case ('velocity')
    call run_velocity()
  case ('trajectory')
    call run_trajectory()
  case ('speed')
    call run_speed()
  case ('compare')
    call run_compare()
  case ('scaling')
    call run_scaling()
  case ('rigid')
    call run_rigid()
  case ('overlaps')
    call run_overlaps()
  case ('stiffness')
    call run_stiffness()
  case ('threads')
    call run_threads()
  case ('rosenbrock')
    call run_rosenbrock()
  case ('evaluation')
    call run_evaluation()
  case default
    call die(program_name, "unknown part '"//part//"' (allowed: velocity, trajectory, speed, compare, scaling, "// &
             "overlaps, rigid, stiffness, threads, rosenbrock, evaluation)", 2)
  end select

contains

  subroutine parse_arguments()
    character(len=:), allocatable :: arg, val
    integer :: k, ios
    if (command_argument_count() < 1) call die(program_name, 'usage: knotflow-bench-reuse velocity|trajectory|speed|scaling [options]', 2)
    part = argument(1)
    call standard_option(program_name, part, 'usage: knotflow-bench-reuse velocity|trajectory|speed|compare|'// &
      'overlaps|scaling|rigid|stiffness|threads|rosenbrock|evaluation [--config trefoil|random60|coil|FILE] [--t-end T] [--every K]'// &
      ' [--eps-lub E] [--overlap RULE (one of '//name_list(overlap_names)//')] [--update U] [--tolerance TOL]'// &
      ' [--table FILE] [--model multipole|rpy] [--jacobian-steps K] [--jacobian-order J] [--rosenbrock-stage yes|no]'// &
      ' [--steppers LIST] [--friction-change F] [--warm-history K] [--refactor-iterations K] [--solver-tolerance S]'// &
      ' [--double-products yes|no] [--single-operator yes|no] [--single-min-beads K]'//new_line('a')// &
      '       knotflow-bench-reuse --help | --version'//new_line('a')// &
      'The adaptive multipole path against the exact one (scripts/bench_reuse.sh, docs/accuracy.md).')
    config = 'trefoil'
    t_end = 10.0_wp
    every = 1
    eps_lub = -1.0_wp
    overlap = ''
    update = update_default
    table = ''
    tolerance = 1.0e-4_wp
    model = 'multipole'
    jacobian_steps = 4
    jacobian_order = 0
    rosenbrock_stage = .true.
    friction_change = -1.0_wp
    warm_history = 0
    refactor_iterations = 0
    solver_tolerance = -1.0_wp
    double_products = .false.
    loop_single = .false.
    force_single = .false.
    min_beads_single = 0
    steppers = method_ros34pw2//','//method_ros34pw3
    k = 2
    do while (k <= command_argument_count())
      arg = argument(k)
      if (k + 1 > command_argument_count()) call die(program_name, trim(arg)//' needs a value', 2)
      val = argument(k + 1)
      select case (trim(arg))
      case ('--config')
        config = trim(val)
      case ('--t-end')
        read (val, *, iostat=ios) t_end
        if (ios /= 0 .or. .not. t_end > 0.0_wp) call die(program_name, '--t-end '//trim(val)//': expected a number > 0', 2)
      case ('--eps-lub')
        read (val, *, iostat=ios) eps_lub
        if (ios /= 0 .or. .not. eps_lub_in_range(eps_lub)) &
          call die(program_name, '--eps-lub '//trim(val)//': expected a number in '//eps_lub_range_text(), 2)
      case ('--overlap')
        overlap = trim(val)
        if (.not. any(overlap_names == overlap)) &
          call die(program_name, '--overlap '//overlap//': allowed values are '//name_list(overlap_names), 2)
      case ('--update')
        update = trim(val)
        if (.not. any(update_names == update)) &
          call die(program_name, '--update '//update//': allowed values are '//name_list(update_names), 2)
      case ('--tolerance')
        read (val, *, iostat=ios) tolerance
        if (ios /= 0 .or. .not. (tolerance > 0.0_wp .and. tolerance < 1.0_wp)) &
          call die(program_name, '--tolerance '//trim(val)//': expected a number in (0, 1)', 2)
      case ('--table')
        table = trim(val)
      case ('--model')
        model = trim(val)
        if (model /= 'multipole' .and. model /= 'rpy') &
          call die(program_name, '--model '//model//': allowed values are multipole, rpy', 2)
      case ('--jacobian-steps')
        read (val, *, iostat=ios) jacobian_steps
        if (ios /= 0 .or. jacobian_steps < 1 .or. jacobian_steps > jacobian_steps_max) &
          call die(program_name, '--jacobian-steps '//trim(val)//': expected an integer in [1, '// &
                   to_str(jacobian_steps_max)//']', 2)
      case ('--jacobian-order')
        read (val, *, iostat=ios) jacobian_order
        if (ios /= 0 .or. jacobian_order < 1) &
          call die(program_name, '--jacobian-order '//trim(val)//': expected an integer >= 1 (at most the order, 2)', 2)
      case ('--friction-change')
        read (val, *, iostat=ios) friction_change
        if (ios /= 0 .or. .not. friction_change >= 0.0_wp) &
          call die(program_name, '--friction-change '//trim(val)//': expected a number >= 0', 2)
      case ('--warm-history')
        read (val, *, iostat=ios) warm_history
        if (ios /= 0 .or. warm_history < 1 .or. warm_history > warm_history_max) &
          call die(program_name, '--warm-history '//trim(val)//': expected an integer in [1, '// &
                   to_str(warm_history_max)//']', 2)
      case ('--refactor-iterations')
        read (val, *, iostat=ios) refactor_iterations
        if (ios /= 0 .or. refactor_iterations < 1 .or. refactor_iterations >= max_iterations) &
          call die(program_name, '--refactor-iterations '//trim(val)//': expected an integer in [1, '// &
                   to_str(max_iterations - 1)//']', 2)
      case ('--solver-tolerance')
        read (val, *, iostat=ios) solver_tolerance
        if (ios /= 0 .or. .not. (solver_tolerance >= solver_tolerance_min .and. solver_tolerance <= solver_tolerance_max)) &
          call die(program_name, '--solver-tolerance '//trim(val)//': expected a number in ['// &
                   to_str(solver_tolerance_min, '(es8.1)')//', '//to_str(solver_tolerance_max, '(es8.1)')//']', 2)
      case ('--double-products')
        if (val /= 'yes' .and. val /= 'no') &
          call die(program_name, '--double-products '//trim(val)//': allowed values are yes, no', 2)
        double_products = val == 'yes'
      case ('--single-operator')
        if (val /= 'yes' .and. val /= 'no') &
          call die(program_name, '--single-operator '//trim(val)//': allowed values are yes, no', 2)
        loop_single = val == 'no'
        force_single = val == 'yes'
      case ('--single-min-beads')
        read (val, *, iostat=ios) min_beads_single
        if (ios /= 0 .or. min_beads_single < 1) &
          call die(program_name, '--single-min-beads '//trim(val)//': expected an integer >= 1', 2)
      case ('--steppers')
        steppers = trim(val)
        call check_steppers(steppers)
      case ('--rosenbrock-stage')
        if (val /= 'yes' .and. val /= 'no') &
          call die(program_name, '--rosenbrock-stage '//trim(val)//': allowed values are yes, no', 2)
        rosenbrock_stage = val == 'yes'
      case ('--every')
        read (val, *, iostat=ios) every
        if (ios /= 0 .or. every < 1) call die(program_name, '--every '//trim(val)//': expected an integer >= 1', 2)
      case default
        call die(program_name, 'unknown option '//trim(arg), 2)
      end select
      k = k + 2
    end do
    if (part == 'rigid') then
      if (overlap /= '' .and. overlap /= overlap_pair) &
        call die(program_name, '--overlap '//overlap//': rigid compares the model''s reused and exact parts, '// &
                 'which only the rule pair leaves alone (allowed: pair)', 2)
      overlap = overlap_pair
    else if (overlap == '') then
      overlap = overlap_relax
    end if
  end subroutine parse_arguments

  !> The comma-separated list of --steppers: each one of the Rosenbrock methods.
  subroutine check_steppers(list)
    character(len=*), intent(in) :: list
    integer :: m
    do m = 1, count_items(list)
      if (item(list, m) /= method_ros34pw2 .and. item(list, m) /= method_ros34pw3) &
        call die(program_name, '--steppers '//list//': '''//item(list, m)//''' is not allowed (each one of '// &
                 method_ros34pw2//', '//method_ros34pw3//')', 2)
    end do
  end subroutine check_steppers

  !> The number of comma-separated items of a list.
  pure integer function count_items(list)
    character(len=*), intent(in) :: list
    integer :: k
    count_items = 1
    do k = 1, len(list)
      if (list(k:k) == ',') count_items = count_items + 1
    end do
  end function count_items

  !> Item m of a comma-separated list (blanks trimmed; '' past the end).
  function item(list, m) result(name)
    character(len=*), intent(in) :: list
    integer, intent(in) :: m
    character(len=:), allocatable :: name
    integer :: k, first, last, seen
    first = 1
    last = len(list)
    seen = 1
    do k = 1, len(list)
      if (list(k:k) /= ',') cycle
      if (seen == m) then
        last = k - 1
        exit
      end if
      seen = seen + 1
      first = k + 1
    end do
    name = ''
    if (seen == m) name = trim(adjustl(list(first:last)))
  end function item

  !> The study's model on configuration `name`, tolerance tol, with initial positions r.
  subroutine study_scene(name, tol, update, scene, r)
    character(len=*), intent(in) :: name, update
    real(wp), intent(in) :: tol
    type(scene_t), intent(out) :: scene
    real(wp), allocatable, intent(out) :: r(:, :)
    type(error_t), allocatable :: error
    real(wp) :: rot(3, 3)
    scene%hydro%model = model
    scene%hydro%order = 2
    scene%hydro%lubrication = .true.
    scene%hydro%update = update
    scene%hydro%eps_lub = eps_lub
    scene%hydro%overlap = overlap
    scene%integrator%tolerance = tol
    select case (name)
    case ('trefoil')
      scene%chain%shape = 'trefoil'
      scene%chain%orientation = 'c'
      scene%forces%bending_a = 2.2_wp
    case ('random60')
      scene%chain%shape = 'random'
      scene%chain%n_beads = 60
      scene%forces%bending_a = 1.3_wp
    case ('coil')
      scene%chain%shape = 'file'
      scene%chain%coordinate_file = 'inputs/configs/coil_candycane_A1.xyz'
      scene%forces%bending_a = 1.0_wp
    case default
      scene%chain%shape = 'file'
      scene%chain%coordinate_file = name
      scene%forces%bending_a = 1.0_wp
    end select
    call build_initial_chain(scene%chain, r, rot, error)
    if (allocated(error)) call die(program_name, error%message, 2)
  end subroutine study_scene

  !> The part, configuration, t_end, the load average and the BLAS threads (environment).
  !> The first line of /proc/loadavg ('unknown' where there is none).
  function loadavg() result(line)
    character(len=:), allocatable :: line
    character(len=128) :: text
    integer :: unit, ios
    text = 'unknown'
    open (newunit=unit, file='/proc/loadavg', action='read', status='old', iostat=ios)
    if (ios == 0) then
      read (unit, '(a)', iostat=ios) text
      close (unit)
    end if
    line = trim(text)
  end function loadavg

  subroutine header()
    character(len=128) :: text
    integer :: status
    write (output_unit, '(a)') 'part = '//part
    write (output_unit, '(a)') 'config = '//config
    write (output_unit, '(a)') 't_end = '//to_str(t_end, '(g0.6)')
    write (output_unit, '(a)') 'overlap = '//overlap
    write (output_unit, '(a)') 'loadavg_start = '//loadavg()
    call get_environment_variable('OPENBLAS_NUM_THREADS', text, status=status)
    if (status /= 0) text = 'unset'
    write (output_unit, '(a)') 'openblas_num_threads = '//trim(text)
  end subroutine header

  subroutine print_stats(prefix, s)
    character(len=*), intent(in) :: prefix
    type(hydro_stats_t), intent(in) :: s
    write (output_unit, '(a)') prefix//'evaluations = '//to_str(s%evaluations)
    write (output_unit, '(a)') prefix//'refreshes = '//to_str(s%refreshes)
    write (output_unit, '(a)') prefix//'reused = '//to_str(s%reused)
    write (output_unit, '(a)') prefix//'cg_iterations = '//to_str(s%cg_iterations)
    write (output_unit, '(a)') prefix//'single_solves = '//to_str(s%single_solves)
    write (output_unit, '(a)') prefix//'single_iterations = '//to_str(s%single_iterations)
    write (output_unit, '(a)') prefix//'preconditioners = '//to_str(s%preconditioners)
    write (output_unit, '(a)') prefix//'mobilities = '//to_str(s%mobilities)
    write (output_unit, '(a)') prefix//'max_error_ratio = '//to_str(s%max_error_ratio, '(es10.3)')
    write (output_unit, '(a)') prefix//'refresh_seconds = '//to_str(s%refresh_seconds, '(f0.3)')
    write (output_unit, '(a)') prefix//'reused_seconds = '//to_str(s%reused_seconds, '(f0.3)')
  end subroutine print_stats

  subroutine run_velocity()
    type(scene_t) :: scene
    type(checked_dynamics_t) :: sys
    class(stepper_t), allocatable :: integ
    type(error_t), allocatable :: error
    real(wp), allocatable :: r(:, :)
    real(wp) :: t, w0
    character(len=:), allocatable :: fast
    class(hydro_model_t), allocatable :: hydro
    call header()
    fast = update_adaptive
    if (update == update_iterative) fast = update_iterative
    call study_scene(config, 1.0e-4_wp, fast, scene, r)
    if (solver_tolerance > 0.0_wp .and. fast == update_iterative) then
      scene%hydro%solver_tolerance = solver_tolerance
      write (output_unit, '(a)') 'solver_tolerance = '//to_str(solver_tolerance, '(es8.1)')
    end if
    if (force_single .or. loop_single) then
      call make_hydro_model(scene%hydro, scene%integrator%tolerance, hydro, error)
      if (allocated(error)) call die(program_name, error%message, 2)
      select type (hydro)
      type is (multipole_iterative_t)
        hydro%single_operator_tolerance = merge(0.0_wp, huge(1.0_wp), force_single)
        if (force_single) then
          hydro%single_min_beads = 1
          hydro%single_operator_min_beads = 1
        end if
      class default
        call die(program_name, '--single-operator: the model is not the iterative one', 2)
      end select
      write (output_unit, '(a)') 'single_operator = '//merge('yes', 'no ', force_single)
    end if
    call sys%init(scene, size(r, 2), error, every, fast, hydro)
    if (allocated(error)) call die(program_name, error%message, 2)
    call make_stepper(scene%integrator, integ, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    t = 0.0_wp
    w0 = wall_seconds()
    call integ%advance(sys, t, r, t_end, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    write (output_unit, '(a)') 'steps = '//to_str(integ%steps())
    write (output_unit, '(a)') 'rejected = '//to_str(integ%rejected())
    write (output_unit, '(a)') 'checks = '//to_str(sys%checks)
    write (output_unit, '(a)') 'every = '//to_str(every)
    write (output_unit, '(a)') 'velocity_rms_max = '//to_str(sys%max_rms, '(es10.3)')
    write (output_unit, '(a)') 'velocity_rms_mean = '//to_str(sys%sum_rms/max(1_i8, sys%checks), '(es10.3)')
    write (output_unit, '(a)') 'velocity_maxnorm_max = '//to_str(sys%max_max, '(es10.3)')
    call print_stats(fast//'.', sys%fast%hydro_statistics())
    write (output_unit, '(a)') 'wall_s = '//to_str(wall_seconds() - w0, '(f10.2)')
  end subroutine run_velocity

  !> Integrate the scene from r to t_end; wall seconds, steps and the model's statistics.
  subroutine integrate(scene, r, wall, steps, stats)
    type(scene_t), intent(in) :: scene
    real(wp), intent(inout) :: r(:, :)
    real(wp), intent(out) :: wall
    integer(i8), intent(out) :: steps
    type(hydro_stats_t), intent(out) :: stats
    type(dynamics_t) :: dyn
    class(stepper_t), allocatable :: integ
    type(error_t), allocatable :: error
    real(wp) :: t, w0
    call dyn%init(scene, size(r, 2), error)
    if (allocated(error)) call die(program_name, error%message, 2)
    call make_stepper(scene%integrator, integ, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    t = 0.0_wp
    w0 = wall_seconds()
    call integ%advance(dyn, t, r, t_end, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    wall = wall_seconds() - w0
    steps = integ%steps()
    stats = dyn%hydro_statistics()
  end subroutine integrate

  !> Integrate the configuration with one path (update, tolerance) to t_end from its start;
  !> writes <label>.wall_s, <label>.steps (and the statistics of an adaptive path); r returns
  !> the final state. eps_lub stays 1e-4 (the default tolerance) unless --eps-lub is given.
  subroutine run_path(label, update, tol, r, wall)
    character(len=*), intent(in) :: label, update
    real(wp), intent(in) :: tol
    real(wp), allocatable, intent(out) :: r(:, :)
    real(wp), intent(out) :: wall
    type(scene_t) :: scene
    integer(i8) :: steps
    type(hydro_stats_t) :: stats
    call study_scene(config, tol, update, scene, r)
    if (eps_lub < 0.0_wp) scene%hydro%eps_lub = 1.0e-4_wp
    call integrate(scene, r, wall, steps, stats)
    write (output_unit, '(a)') label//'.wall_s = '//to_str(wall, '(f10.2)')
    write (output_unit, '(a)') label//'.steps = '//to_str(steps)
    if (update /= update_stage) call print_stats(label//'.', stats)
  end subroutine run_path

  subroutine run_trajectory()
    real(wp), allocatable :: r_stage(:, :), r_adapt(:, :), r_fine(:, :)
    real(wp) :: wall
    call header()
    call run_path(update_stage, update_stage, 1.0e-4_wp, r_stage, wall)
    call run_path(update_adaptive, update_adaptive, 1.0e-4_wp, r_adapt, wall)
    call run_path('stage_tol1e-6', update_stage, 1.0e-6_wp, r_fine, wall)
    write (output_unit, '(a)') 'deviation_adaptive_vs_stage = '// &
      to_str(max_bead_deviation(r_adapt, r_stage), '(es10.3)')
    write (output_unit, '(a)') 'deviation_stage_tol1e-4_vs_1e-6 = '// &
      to_str(max_bead_deviation(r_stage, r_fine), '(es10.3)')
  end subroutine run_trajectory

  subroutine run_speed()
    real(wp), allocatable :: r(:, :)
    real(wp) :: wall_stage, wall_adapt
    call header()
    call run_path(update_adaptive, update_adaptive, 1.0e-4_wp, r, wall_adapt)
    call run_path(update_stage, update_stage, 1.0e-4_wp, r, wall_stage)
    write (output_unit, '(a)') 'ratio_stage_over_adaptive = '//to_str(wall_stage/wall_adapt, '(f8.2)')
  end subroutine run_speed

  !> The three update modes in one run (tolerance 1e-4): 'stage' first (the reference), then
  !> 'adaptive' and 'iterative'.
  subroutine run_compare()
    character(len=*), parameter :: modes(2) = [character(len=9) :: update_adaptive, update_iterative]
    real(wp), allocatable :: r_stage(:, :), r(:, :)
    real(wp) :: wall_stage, wall
    integer :: k
    call header()
    call run_path(update_stage, update_stage, 1.0e-4_wp, r_stage, wall_stage)
    do k = 1, size(modes)
      call run_path(trim(modes(k)), trim(modes(k)), 1.0e-4_wp, r, wall)
      write (output_unit, '(a)') 'ratio_stage_over_'//trim(modes(k))//' = '//to_str(wall_stage/wall, '(f8.2)')
      write (output_unit, '(a)') 'deviation_'//trim(modes(k))//'_vs_stage = '// &
        to_str(max_bead_deviation(r, r_stage), '(es10.3)')
    end do
    write (output_unit, '(a)') 'loadavg_end = '//loadavg()
  end subroutine run_compare

  !> Both cores for one case: 1 and 2 threads (OpenMP pair loops and BLAS) on one evaluation
  !> and on a window of 'stage' and 'iterative' (module header, part threads).
  subroutine run_threads()
    character(len=*), parameter :: modes(2) = [character(len=9) :: update_stage, update_iterative]
    character(len=*), parameter :: shapes(2) = [character(len=9) :: 'trefoil', 'candycane']
    real(wp) :: wall(2), asm(2), fac(2), lub(2)
    real(wp), allocatable :: r1(:, :), r2(:, :)
    integer :: k, m, threads
    character(len=:), allocatable :: label
    call header()
    do k = 1, size(shapes)
      do threads = 1, 2
        call use_threads(threads)
        label = 'eval.'//trim(shapes(k))//'.threads'//to_str(threads)
        call one_evaluation(trim(shapes(k)), label, wall(threads), asm(threads), fac(threads), lub(threads))
      end do
      label = 'eval.'//trim(shapes(k))
      write (output_unit, '(a)') label//'.ratio_total = '//to_str(wall(1)/wall(2), '(f8.2)')
      write (output_unit, '(a)') label//'.ratio_assembly = '//to_str(asm(1)/asm(2), '(f8.2)')
      write (output_unit, '(a)') label//'.ratio_factor = '//to_str(fac(1)/fac(2), '(f8.2)')
      write (output_unit, '(a)') label//'.ratio_lubrication_blocks = '//to_str(lub(1)/lub(2), '(f8.2)')
    end do
    do m = 1, size(modes)
      do threads = 1, 2
        call use_threads(threads)
        label = trim(modes(m))//'.threads'//to_str(threads)
        write (output_unit, '(a)') label//'.loadavg_start = '//loadavg()
        if (threads == 1) then
          call run_path(label, trim(modes(m)), 1.0e-4_wp, r1, wall(1))
        else
          call run_path(label, trim(modes(m)), 1.0e-4_wp, r2, wall(2))
        end if
      end do
      write (output_unit, '(a)') trim(modes(m))//'.ratio_threads1_over_threads2 = '//to_str(wall(1)/wall(2), '(f8.2)')
      write (output_unit, '(a)') trim(modes(m))//'.deviation_threads1_vs_threads2 = '// &
        to_str(max_bead_deviation(r1, r2), '(es10.3)')
    end do
    call use_threads(1)
    write (output_unit, '(a)') 'loadavg_end = '//loadavg()
  end subroutine run_threads

  !> n threads for the OpenMP pair loops and the BLAS; stops when the BLAS cannot be told
  !> (OPENBLAS_NUM_THREADS set, or not OpenBLAS): the figures would not be what they say.
  subroutine use_threads(n)
    integer, intent(in) :: n
    logical :: applied
    call use_openmp_threads(n)
    call set_blas_threads(n, applied)
    if (.not. applied) call die(program_name, 'threads: the BLAS threads cannot be set (unset '// &
                                'OPENBLAS_NUM_THREADS; OpenBLAS only)', 2)
    write (output_unit, '(a)') 'threads = '//to_str(n)//' (OpenMP '//to_str(openmp_threads_in_use())// &
      ', BLAS '//to_str(blas_threads_in_use())//')'
  end subroutine use_threads

  !> One 'stage' evaluation of the study's model (L = 2 + lubrication) of shape `name`: best of
  !> 5 wall times of prepare and the parts of that best one.
  subroutine one_evaluation(name, label, best, t_asm, t_fac, t_lub)
    character(len=*), intent(in) :: name, label
    real(wp), intent(out) :: best, t_asm, t_fac, t_lub
    type(multipole_model_t) :: model
    type(chain_params_t) :: p
    type(error_t), allocatable :: error
    real(wp), allocatable :: r(:, :)
    real(wp) :: rot(3, 3), w0, w
    integer :: rep
    p%shape = name
    call build_initial_chain(p, r, rot, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    call model%init(2, .true., 1.0e-4_wp, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    write (output_unit, '(a)') label//'.loadavg_start = '//loadavg()
    best = huge(1.0_wp)
    do rep = 1, 5
      w0 = wall_seconds()
      call model%prepare(r, error)
      if (allocated(error)) call die(program_name, error%message, 2)
      w = wall_seconds() - w0
      if (w < best) then
        best = w
        call model%prepare_seconds(t_asm, t_fac, t_lub)
      end if
    end do
    write (output_unit, '(a)') label//'.n_beads = '//to_str(size(r, 2))
    write (output_unit, '(a)') label//'.total_s = '//to_str(best, '(f8.4)')
    write (output_unit, '(a)') label//'.assembly_s = '//to_str(t_asm, '(f8.4)')
    write (output_unit, '(a)') label//'.factor_s = '//to_str(t_fac, '(f8.4)')
    write (output_unit, '(a)') label//'.factor_gflops = '//to_str(factor_flops(size(r, 2))/t_fac/1.0e9_wp, '(f8.2)')
    write (output_unit, '(a)') label//'.lubrication_blocks_s = '//to_str(t_lub, '(f8.4)')
    write (output_unit, '(a)') label//'.rest_s = '//to_str(best - t_asm - t_fac - t_lub, '(f8.4)')
    call factor_cpu_seconds(r, w)
    write (output_unit, '(a)') label//'.factor_cpu_s = '//to_str(w, '(f8.4)')
    write (output_unit, '(a)') label//'.factor_gflops_per_cpu_s = '//to_str(factor_flops(size(r, 2))/w/1.0e9_wp, '(f8.2)')
  end subroutine one_evaluation

  !> The cost of one evaluation of the study's model at the configuration `config`, split
  !> (module header, part evaluation); processor seconds, so that the time the process waits
  !> for a CPU on a shared machine does not count.
  subroutine run_evaluation()
    integer, parameter :: reps(15) = [7, 7, 20, 20, 7, 5, 3, 3, 0, 6, 20, 7, 20, 0, 7] ! 9, 14: warm_calls_interleaved
    type(scene_t) :: scene
    type(multipole_system_t) :: sys
    type(lubrication_t) :: lub
    type(pair_blocks_t) :: blocks, blocks2
    type(multipole_iterative_t) :: iter
    type(multipole_model_t) :: stage
    type(hydro_stats_t) :: s0, s1
    type(error_t), allocatable :: error
    real(wp), allocatable :: r(:, :), r2(:, :), r3(:, :), f(:, :), u(:, :), zeta(:, :), pre(:, :), x(:), y(:)
    real(sp), allocatable :: xs(:)
    real(wp), allocatable :: pscale(:)
    integer, allocatable :: slot(:, :)
    real(wp) :: e(3, 3), eps, best(15), c0, c1, sgn, change
    integer :: n, i, rep, what
    integer(i8) :: factors6
    call header()
    call study_scene(config, 1.0e-4_wp, update_stage, scene, r)
    eps = merge(eps_lub, 1.0e-4_wp, eps_lub > 0.0_wp)
    n = size(r, 2)
    allocate (f(3, n), u(3, n), r2(3, n), r3(3, n), zeta(6*n, 6*n), pre(6*n, 6*n))
    do i = 1, n
      f(:, i) = [sin(1.7_wp*i), cos(2.3_wp*i), 0.5_wp*sin(0.9_wp*i)]
      r2(:, i) = r(:, i) + 0.003_wp*[sin(3.1_wp*i), cos(1.3_wp*i), sin(0.7_wp*i)]
      r3(:, i) = r2(:, i) + 0.001_wp*[cos(2.9_wp*i), sin(1.1_wp*i), cos(0.3_wp*i)]
    end do
    e = 0.0_wp
    e(1, 3) = 0.5_wp
    e(3, 1) = 0.5_wp
    write (output_unit, '(a)') 'n_beads = '//to_str(n)
    call sys%init(2, 1.0_wp + eps, error, single_copy=.true.)
    if (allocated(error)) call die(program_name, error%message, 2)
    call lub%init(2, eps, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    call stage%init(2, .true., eps, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    ! the pieces in order: 1 assembly, 2 lubrication blocks, 3 K x, 4 solve pair, 5 6N Cholesky,
    ! 6 'iterative' GMRES calls from zero, 7 'iterative' factorising calls, 8 'stage' calls,
    ! 10 single-precision solve pair, 11 the largest scaled change of the lubrication blocks
    ! between r and r2 (the 6N factor's rule), 12 the single copies of K0 and B, 13 one
    ! single-precision product K x, 15 the assembly with the single copies made column by
    ! column (assemble's `single`); the calls from the last solution (9, 14) after the loop,
    ! interleaved (warm_calls_interleaved)
    best = huge(1.0_wp)
    do what = 1, 15
      select case (what)
      case (3)
        allocate (x(sys%unknowns()), y(sys%unknowns()), xs(sys%unknowns()))
        x = 1.0_wp
      case (4)
        call sys%factorise(r, error)
      case (5)
        call sys%grand_friction(zeta, error)
        if (.not. allocated(error)) call blocks%add_friction(zeta)
      case (11)
        allocate (pscale(6*n), slot(n, n))
        slot = 0
        do i = 1, 6*n
          pscale(i) = 1.0_wp/sqrt(zeta(i, i))
        end do
        call lub%pair_blocks(r, blocks)
        call lub%pair_blocks(r2, blocks2)
      case (12)
        call sys%assemble(r, error)
      case (6)
        call iter%setup(2, .true., eps, error)
        if (.not. allocated(error)) call iter%velocities(r, f, u, error, e)
        s0 = iter%statistics()
      end select
      if (allocated(error)) call die(program_name, error%message, 2)
      do rep = 1, reps(what)
        if (what == 4) x = 1.0_wp
        if (what == 10) xs = 1.0_sp
        if (what == 5) pre = zeta
        if (what == 7) then
          call iter%setup(2, .true., eps, error)
          if (allocated(error)) call die(program_name, error%message, 2)
        end if
        sgn = real(1 - 2*mod(rep, 2), wp)
        call cpu_time(c0)
        select case (what)
        case (1)
          call sys%assemble(r, error)
        case (2)
          call lub%pair_blocks(r, blocks)
        case (3)
          call sys%apply(x, y)
        case (4)
          call sys%forward(x)
          call sys%backward(x)
        case (5)
          call cholesky_factor(pre, error, 'lubrication-corrected friction')
        case (6)
          ! the system is linear in (f, e): the last solution, negated, has twice the residual
          call iter%velocities(r2, sgn*f, u, error, sgn*e)
        case (7)
          call iter%velocities(r2, f, u, error, e)
        case (12)
          call sys%copy_products_single()
        case (15)
          call sys%assemble(r, error, single=.true.)
        case (13)
          call sys%apply_single(x, y)
        case (10)
          call sys%forward_single(xs)
          call sys%backward_single(xs)
        case (11)
          change = blocks2%largest_scaled_change(blocks, pscale, slot)
        case default
          call stage%velocities(r2, f, u, error, e)
        end select
        call cpu_time(c1)
        if (allocated(error)) call die(program_name, error%message, 2)
        best(what) = min(best(what), c1 - c0)
      end do
      if (what == 6) s1 = iter%statistics()
      if (what == 6) factors6 = s1%preconditioners - s0%preconditioners
    end do
    write (output_unit, '(a)') 'lubrication_pairs = '//to_str(blocks%n_pairs())
    write (output_unit, '(a)') 'assembly_ms = '//to_str(1.0e3_wp*best(1), '(f0.3)')
    write (output_unit, '(a)') 'lubrication_blocks_ms = '//to_str(1.0e3_wp*best(2), '(f0.3)')
    write (output_unit, '(a)') 'product_k_ms = '//to_str(1.0e3_wp*best(3), '(f0.3)')
    write (output_unit, '(a)') 'solve_pair_k_ms = '//to_str(1.0e3_wp*best(4), '(f0.3)')
    write (output_unit, '(a)') 'solve_pair_k_single_ms = '//to_str(1.0e3_wp*best(10), '(f0.3)')
    write (output_unit, '(a)') 'friction_cholesky_6n_ms = '//to_str(1.0e3_wp*best(5), '(f0.3)')
    write (output_unit, '(a)') 'iterative_reused_ms = '//to_str(1.0e3_wp*best(6), '(f0.3)')
    write (output_unit, '(a)') 'iterative_reused_iterations = '// &
      to_str(real(s1%cg_iterations - s0%cg_iterations, wp)/real(max(1_i8, s1%reused - s0%reused), wp), '(f0.2)')
    write (output_unit, '(a)') 'friction_change_ms = '//to_str(1.0e3_wp*best(11), '(f0.3)')
    write (output_unit, '(a)') 'friction_change_r_r2 = '//to_str(change, '(es10.3)')
    write (output_unit, '(a)') 'iterative_reused_friction_factorisations = '//to_str(factors6)
    write (output_unit, '(a)') 'iterative_reused_rest_ms = '// &
      to_str(1.0e3_wp*(best(6) - best(1) - best(2) - best(11)), '(f0.3)')
    call warm_calls_interleaved(r, r2, r3, f, e, eps)
    write (output_unit, '(a)') 'copy_products_single_ms = '//to_str(1.0e3_wp*best(12), '(f0.3)')
    write (output_unit, '(a)') 'assembly_with_single_copies_ms = '//to_str(1.0e3_wp*best(15), '(f0.3)')
    write (output_unit, '(a)') 'product_k_single_ms = '//to_str(1.0e3_wp*best(13), '(f0.3)')
    write (output_unit, '(a)') 'iterative_refresh_ms = '//to_str(1.0e3_wp*best(7), '(f0.3)')
    write (output_unit, '(a)') 'stage_ms = '//to_str(1.0e3_wp*best(8), '(f0.3)')
    write (output_unit, '(a)') 'loadavg_end = '//loadavg()
  end subroutine run_evaluation

  !> Whole 'iterative' calls from the last call's solution (warm_history 1: with a longer history
  !> the configuration two calls back, the same, would give the exact start), the configuration
  !> alternating between r2 and r3 (0.001 d apart), by two models: the Krylov loop's products in
  !> single where the rule allows, at any size (single_min_beads = 1), and always in double
  !> (single_products = .false.). The two calls of a pair follow each other, in alternating order, so that both see
  !> the same state of the machine; warm_pairs pairs after one call each at r. Printed: the
  !> median processor time of each (ms), the median of the pairs' ratios double / single, the
  !> GMRES iterations per call and the calls with single products.
  subroutine warm_calls_interleaved(r, r2, r3, f, e, eps)
    real(wp), intent(in) :: r(:, :), r2(:, :), r3(:, :), f(:, :), e(3, 3), eps
    integer, parameter :: warm_pairs = 100
    type(multipole_iterative_t) :: models(2)
    type(hydro_stats_t) :: s0(2), s1(2)
    type(error_t), allocatable :: error
    real(wp) :: u(3, size(r, 2)), c0, c1, times(warm_pairs, 2)
    integer :: rep, k, m
    do m = 1, 2
      call models(m)%setup(2, .true., eps, error, warm_history=1)
      if (allocated(error)) call die(program_name, error%message, 2)
      models(m)%single_products = m == 1
      models(m)%single_min_beads = 1
      call models(m)%velocities(r, f, u, error, e)
      if (allocated(error)) call die(program_name, error%message, 2)
      s0(m) = models(m)%statistics()
    end do
    do rep = 1, warm_pairs
      do k = 1, 2
        m = merge(k, 3 - k, mod(rep, 2) == 1)
        call cpu_time(c0)
        if (mod(rep, 2) == 1) then
          call models(m)%velocities(r2, f, u, error, e)
        else
          call models(m)%velocities(r3, f, u, error, e)
        end if
        call cpu_time(c1)
        if (allocated(error)) call die(program_name, error%message, 2)
        times(rep, m) = c1 - c0
      end do
    end do
    do m = 1, 2
      s1(m) = models(m)%statistics()
    end do
    write (output_unit, '(a)') 'iterative_warm_pairs = '//to_str(warm_pairs)
    write (output_unit, '(a)') 'iterative_warm_ms = '//to_str(1.0e3_wp*median(times(:, 1)), '(f0.3)')
    write (output_unit, '(a)') 'iterative_warm_double_ms = '//to_str(1.0e3_wp*median(times(:, 2)), '(f0.3)')
    write (output_unit, '(a)') 'iterative_warm_ratio_double_over_single = '// &
      to_str(median(times(:, 2)/times(:, 1)), '(f0.3)')
    write (output_unit, '(a)') 'iterative_warm_iterations = '// &
      to_str(real(s1(1)%cg_iterations - s0(1)%cg_iterations, wp)/real(warm_pairs, wp), '(f0.2)')// &
      ' (double: '//to_str(real(s1(2)%cg_iterations - s0(2)%cg_iterations, wp)/real(warm_pairs, wp), '(f0.2)')//')'
    write (output_unit, '(a)') 'iterative_warm_single_solves = '//to_str(s1(1)%single_solves - s0(1)%single_solves)// &
      ' of '//to_str(warm_pairs)
  end subroutine warm_calls_interleaved

  !> Processor time (all threads; cpu_time) of the factorisation of the L = 2 system at r: the
  !> best of 5 factorise calls (assembly + factorisation) less the best of 5 assemblies. Time
  !> the process spent waiting for a CPU on a loaded machine does not count, so at one thread
  !> flops / this time is the rate the core achieved while it ran this code.
  subroutine factor_cpu_seconds(r, seconds)
    real(wp), intent(in) :: r(:, :)
    real(wp), intent(out) :: seconds
    type(multipole_system_t) :: sys
    type(error_t), allocatable :: error
    real(wp) :: c0, c1, best_assembly, best_both
    integer :: rep
    call sys%init(2, 1.0_wp + 1.0e-4_wp, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    best_assembly = huge(1.0_wp)
    best_both = huge(1.0_wp)
    do rep = 1, 5
      call cpu_time(c0)
      call sys%assemble(r, error)
      call cpu_time(c1)
      if (allocated(error)) call die(program_name, error%message, 2)
      best_assembly = min(best_assembly, c1 - c0)
      call cpu_time(c0)
      call sys%factorise(r, error)
      call cpu_time(c1)
      if (allocated(error)) call die(program_name, error%message, 2)
      best_both = min(best_both, c1 - c0)
    end do
    seconds = best_both - best_assembly
  end subroutine factor_cpu_seconds

  !> Floating-point operations of the factorisation at L = 2 (kf_multipole_system `factorise`)
  !> for n beads: the p-moment elimination (DSYRK on the na = (h - 3) n rows of B, DGEMM of its
  !> nc = 3 n rows against them, DSYRK on those; np = h n columns, h = L (L + 2) = 8) and the
  !> Cholesky factorisation DPOTRF of K (nr = 2 h n): nr^3/3 + nr^2/2 + nr/6.
  pure real(wp) function factor_flops(n) result(flops)
    integer, intent(in) :: n
    integer, parameter :: h = 8
    real(wp) :: na, nc, np, nr
    na = real((h - 3)*n, wp)
    nc = real(3*n, wp)
    np = real(h*n, wp)
    nr = real(2*h*n, wp)
    flops = na*(na + 1.0_wp)*np + 2.0_wp*nc*na*np + nc*(nc + 1.0_wp)*np + nr**3/3.0_wp + nr**2/2.0_wp + nr/6.0_wp
  end function factor_flops

  subroutine run_rigid()
    type(scene_t) :: scene
    type(dynamics_t) :: fast, exact
    type(error_t), allocatable :: error
    real(wp), allocatable :: r(:, :), r2(:, :), v(:, :), vx(:, :)
    real(wp) :: q(3, 3), ang, dr
    integer :: i, k
    call header()
    call study_scene(config, 1.0e-4_wp, update_adaptive, scene, r)
    call fast%init(scene, size(r, 2), error)
    scene%hydro%update = update_stage
    call exact%init(scene, size(r, 2), error)
    allocate (v(3, size(r, 2)), vx(3, size(r, 2)), r2(3, size(r, 2)))
    call fast%step_begin(0.0_wp, r, 0.05_wp)
    call fast%velocity(r, v, error)
    do k = 1, 4
      ang = 0.3_wp*k
      q = reshape([cos(ang), sin(ang), 0.0_wp, -sin(ang), cos(ang), 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [3, 3])
      dr = 1.0e-3_wp*(k - 1)
      do i = 1, size(r, 2)
        r2(:, i) = matmul(q, r(:, i)) + [1.0_wp, 2.0_wp, 3.0_wp] + dr*[sin(real(i, wp)), cos(real(3*i, wp)), 0.0_wp]
      end do
      call reused(fast, r2, v)
      call exact%velocity(r2, vx, error)
      write (output_unit, '(a)') 'rigid'//to_str(k)//'.angle = '//to_str(ang, '(f6.3)')
      write (output_unit, '(a)') 'rigid'//to_str(k)//'.perturbation = '//to_str(dr, '(es10.3)')
      write (output_unit, '(a)') 'rigid'//to_str(k)//'.max_error = '//to_str(maxval(norm2(v - vx, dim=1)), '(es10.3)')
    end do
    ! bond-length perturbation only: each bond scaled by (1 + eps_k) from bead 1 on
    do k = 1, 3
      dr = 1.0e-3_wp*k
      r2(:, 1) = r(:, 1)
      do i = 2, size(r, 2)
        r2(:, i) = r2(:, i - 1) + (r(:, i) - r(:, i - 1))*(1.0_wp + dr*sin(7.0_wp*i))
      end do
      call reused(fast, r2, v)
      call exact%velocity(r2, vx, error)
      write (output_unit, '(a)') 'stretch'//to_str(k)//'.amplitude = '//to_str(dr, '(es10.3)')
      write (output_unit, '(a)') 'stretch'//to_str(k)//'.max_error = '//to_str(maxval(norm2(v - vx, dim=1)), '(es10.3)')
    end do
    ! transverse perturbation only: bead i moved perpendicular to its bonds
    do k = 1, 3
      dr = 1.0e-2_wp*k
      do i = 1, size(r, 2)
        r2(:, i) = r(:, i) + dr*[sin(3.0_wp*i), cos(5.0_wp*i), sin(11.0_wp*i)]
      end do
      call reused(fast, r2, v)
      call exact%velocity(r2, vx, error)
      write (output_unit, '(a)') 'move'//to_str(k)//'.amplitude = '//to_str(dr, '(es10.3)')
      write (output_unit, '(a)') 'move'//to_str(k)//'.max_error = '//to_str(maxval(norm2(v - vx, dim=1)), '(es10.3)')
    end do
    call print_stats(update_adaptive//'.', fast%hydro_statistics())
  end subroutine run_rigid

  !> Overlap statistics of both paths (the run diagnostics at every accepted step).
  subroutine run_overlaps()
    character(len=8), parameter :: paths(2) = [character(len=8) :: update_stage, update_adaptive]
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    type(run_diagnostics_t) :: diag
    class(stepper_t), allocatable :: integ
    type(error_t), allocatable :: error
    real(wp), allocatable :: r(:, :)
    real(wp) :: t, w0
    integer :: k
    character(len=:), allocatable :: p
    call header()
    do k = 1, 2
      p = trim(paths(k))
      call study_scene(config, 1.0e-4_wp, p, scene, r)
      call dyn%init(scene, size(r, 2), error)
      if (allocated(error)) call die(program_name, error%message, 2)
      call make_stepper(scene%integrator, integ, error)
      if (allocated(error)) call die(program_name, error%message, 2)
      call diag%init(size(r, 2), scene%chain%bond_length)
      t = 0.0_wp
      call diag%start(t, r)
      w0 = wall_seconds()
      call integ%advance(dyn, t, r, t_end, error, diag)
      if (allocated(error)) call die(program_name, error%message, 2)
      write (output_unit, '(a)') p//'.wall_s = '//to_str(wall_seconds() - w0, '(f10.2)')
      write (output_unit, '(a)') p//'.steps = '//to_str(integ%steps())
      write (output_unit, '(a)') p//'.overlap_episodes = '//to_str(diag%overlap_episodes)
      write (output_unit, '(a)') p//'.completed_episodes = '//to_str(diag%completed_episodes)
      write (output_unit, '(a)') p//'.mean_duration = '//to_str(diag%mean_duration(), '(f10.4)')
      write (output_unit, '(a)') p//'.max_duration = '//to_str(diag%duration_max, '(f10.4)')
      write (output_unit, '(a)') p//'.max_overlapping_pairs = '//to_str(diag%max_overlapping_pairs)
      write (output_unit, '(a)') p//'.strand_passages = '//to_str(diag%strand_passages)
      write (output_unit, '(a)') p//'.min_distance = '//to_str(diag%min_distance(), '(f10.5)')
      if (k == 2) call print_stats(update_adaptive//'.', dyn%hydro_statistics())
    end do
  end subroutine run_overlaps

  !> The Rosenbrock methods of --steppers (tolerance --tolerance) against dopri45 (tolerance
  !> 1e-4) in one run: dopri45 'stage' first (the reference), then each Rosenbrock method
  !> 'stage' (with the multipole model only when rosenbrock_stage), and with the multipole model
  !> dopri45 and each Rosenbrock method 'iterative', also with the mobility of its Jacobian kept
  !> for jacobian_steps steps (K > 1).
  subroutine run_rosenbrock()
    character(len=9), allocatable :: updates(:)
    character(len=:), allocatable :: label, method
    real(wp), allocatable :: r_ref(:, :)
    real(wp) :: wall_ref
    integer :: k, m
    call header()
    write (output_unit, '(a)') 'model = '//model
    write (output_unit, '(a)') 'jacobian_steps = '//to_str(jacobian_steps)
    write (output_unit, '(a)') 'jacobian_order = '//to_str(jacobian_order)
    write (output_unit, '(a)') 'rosenbrock_tolerance = '//to_str(tolerance, '(es10.3)')
    if (model == 'multipole') then
      updates = [character(len=9) :: update_stage, update_iterative]
    else
      updates = [character(len=9) :: update_stage]
    end if
    call jacobian_cost()
    call run_method(method_dopri45//'.stage', method_dopri45, update_stage, 1, 1.0e-4_wp, r_ref, wall_ref)
    do k = 1, size(updates)
      if (k > 1) call run_compared(method_dopri45, method_dopri45, trim(updates(k)), 1, 1.0e-4_wp, 0, r_ref, wall_ref)
      if (trim(updates(k)) == update_stage .and. model == 'multipole' .and. .not. rosenbrock_stage) cycle
      do m = 1, count_items(steppers)
        method = item(steppers, m)
        call run_compared(method, method, trim(updates(k)), 1, tolerance, 0, r_ref, wall_ref)
        if (jacobian_steps > 1 .and. trim(updates(k)) /= update_stage) &
          call run_compared(method//'_mobility'//to_str(jacobian_steps), method, trim(updates(k)), jacobian_steps, &
                            tolerance, 0, r_ref, wall_ref)
        if (jacobian_order > 0 .and. trim(updates(k)) /= update_stage) then
          label = method//'_jorder'//to_str(jacobian_order)
          call run_compared(label, method, trim(updates(k)), 1, tolerance, jacobian_order, r_ref, wall_ref)
          if (jacobian_steps > 1) &
            call run_compared(label//'_mobility'//to_str(jacobian_steps), method, trim(updates(k)), jacobian_steps, &
                              tolerance, jacobian_order, r_ref, wall_ref)
        end if
      end do
    end do
    write (output_unit, '(a)') 'loadavg_end = '//loadavg()
  end subroutine run_rosenbrock

  !> One run (run_method: label <name>.<upd>, jorder 0 the scene default) compared with the
  !> reference; with --friction-change F and upd 'iterative' the same run follows with the
  !> iterative model's friction_change set to F (label <name>_fc<F>.<upd>), in the same process;
  !> with --warm-history K likewise with its warm_history set to K (label <name>_wh<K>.<upd>);
  !> with --refactor-iterations K likewise with its refactor_iterations set to K (label
  !> <name>_ri<K>.<upd>); with --solver-tolerance S likewise with its solver_tolerance set to S
  !> (label <name>_st<S>.<upd>); with --double-products yes likewise with the Krylov loop's products in
  !> double (label <name>_double.<upd>); with --single-operator no likewise with K0 and the start's
  !> residual in double (label <name>_loopsingle.<upd>; with --solver-tolerance S at S, label
  !> <name>_st<S>_loopsingle.<upd>); with --single-min-beads K likewise with its single_min_beads
  !> and single_operator_min_beads set to K (label <name>_smb<K>.<upd>, with --solver-tolerance S
  !> <name>_st<S>_smb<K>.<upd>).
  subroutine run_compared(name, method, upd, keep, tol, jorder, r_ref, wall_ref)
    character(len=*), intent(in) :: name, method, upd
    integer, intent(in) :: keep, jorder
    real(wp), intent(in) :: tol, r_ref(:, :), wall_ref
    real(wp), allocatable :: r(:, :)
    real(wp) :: wall
    character(len=:), allocatable :: label, st
    label = name//'.'//upd
    call run_method(label, method, upd, keep, tol, r, wall, jorder)
    call compare_with_reference(label, r, wall, r_ref, wall_ref)
    if (upd /= update_iterative) return
    if (friction_change >= 0.0_wp) then
      label = name//'_fc'//to_str(friction_change, '(g0.3)')//'.'//upd
      call run_method(label, method, upd, keep, tol, r, wall, jorder, fchange=friction_change)
      call compare_with_reference(label, r, wall, r_ref, wall_ref)
    end if
    if (warm_history > 0) then
      label = name//'_wh'//to_str(warm_history)//'.'//upd
      call run_method(label, method, upd, keep, tol, r, wall, jorder, whistory=warm_history)
      call compare_with_reference(label, r, wall, r_ref, wall_ref)
    end if
    if (refactor_iterations > 0) then
      label = name//'_ri'//to_str(refactor_iterations)//'.'//upd
      call run_method(label, method, upd, keep, tol, r, wall, jorder, refactor=refactor_iterations)
      call compare_with_reference(label, r, wall, r_ref, wall_ref)
    end if
    if (solver_tolerance > 0.0_wp) then
      label = name//'_st'//to_str(solver_tolerance, '(es7.1)')//'.'//upd
      call run_method(label, method, upd, keep, tol, r, wall, jorder, stol=solver_tolerance)
      call compare_with_reference(label, r, wall, r_ref, wall_ref)
    end if
    if (double_products) then
      label = name//'_double.'//upd
      call run_method(label, method, upd, keep, tol, r, wall, jorder, double=.true.)
      call compare_with_reference(label, r, wall, r_ref, wall_ref)
    end if
    ! the next two at --solver-tolerance S when given (stol <= 0: the scene's)
    st = ''
    if (solver_tolerance > 0.0_wp) st = '_st'//to_str(solver_tolerance, '(es7.1)')
    if (loop_single) then
      label = name//st//'_loopsingle.'//upd
      call run_method(label, method, upd, keep, tol, r, wall, jorder, stol=solver_tolerance, loopsingle=.true.)
      call compare_with_reference(label, r, wall, r_ref, wall_ref)
    end if
    if (min_beads_single > 0) then
      label = name//st//'_smb'//to_str(min_beads_single)//'.'//upd
      call run_method(label, method, upd, keep, tol, r, wall, jorder, stol=solver_tolerance, smb=min_beads_single)
      call compare_with_reference(label, r, wall, r_ref, wall_ref)
    end if
  end subroutine run_compared

  !> The wall-time ratio and the largest bead deviation of a run (r, wall) from the reference.
  subroutine compare_with_reference(label, r, wall, r_ref, wall_ref)
    character(len=*), intent(in) :: label
    real(wp), intent(in) :: r(:, :), wall, r_ref(:, :), wall_ref
    write (output_unit, '(a)') label//'.ratio_wall_dopri45_stage_over_this = '//to_str(wall_ref/wall, '(f8.3)')
    write (output_unit, '(a)') label//'.deviation_vs_dopri45_stage = '//to_str(max_bead_deviation(r, r_ref), '(es10.3)')
  end subroutine compare_with_reference

  !> One integration of the configuration to t_end (tolerance tol; eps_lub 1e-4 unless
  !> --eps-lub) with `method` and `upd`: its figures under `label`; r the final positions.
  !> `jorder` (optional): &hydro jacobian_order; `fchange` (optional): the iterative model's
  !> friction_change, `whistory` (optional): its warm_history, `double` (optional): .true. sets
  !> its single_products = .false., `loopsingle` (optional): .true. sets its
  !> single_operator_tolerance = huge, `smb` (optional): its single_min_beads and
  !> single_operator_min_beads, `refactor` (optional): its refactor_iterations (the factory's
  !> model with those values, taken over by the dynamics); `stol` (optional): the scene's &hydro
  !> solver_tolerance (<= 0: the scene's own).
  subroutine run_method(label, method, upd, keep, tol, r, wall, jorder, fchange, whistory, double, refactor, stol, &
                        loopsingle, smb)
    character(len=*), intent(in) :: label, method, upd
    integer, intent(in) :: keep
    real(wp), intent(in) :: tol
    real(wp), allocatable, intent(out) :: r(:, :)
    real(wp), intent(out) :: wall
    integer, intent(in), optional :: jorder
    real(wp), intent(in), optional :: fchange
    integer, intent(in), optional :: whistory
    logical, intent(in), optional :: double
    integer, intent(in), optional :: refactor
    real(wp), intent(in), optional :: stol
    logical, intent(in), optional :: loopsingle
    integer, intent(in), optional :: smb
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    class(hydro_model_t), allocatable :: hydro
    class(stepper_t), allocatable :: integ
    type(error_t), allocatable :: error
    real(wp) :: t, w0, c0, c1
    call study_scene(config, tol, upd, scene, r)
    if (eps_lub < 0.0_wp) scene%hydro%eps_lub = 1.0e-4_wp
    scene%integrator%method = method
    scene%integrator%jacobian_steps = keep
    if (present(jorder)) scene%hydro%jacobian_order = jorder
    if (present(stol)) then
      if (stol > 0.0_wp) scene%hydro%solver_tolerance = stol
    end if
    if (present(fchange) .or. present(whistory) .or. present(double) .or. present(refactor) .or. &
        present(loopsingle) .or. present(smb)) then
      call make_hydro_model(scene%hydro, scene%integrator%tolerance, hydro, error)
      if (allocated(error)) call die(program_name, error%message, 2)
      select type (hydro)
      type is (multipole_iterative_t)
        if (present(fchange)) hydro%friction_change = fchange
        if (present(whistory)) hydro%warm_history = whistory
        if (present(double)) hydro%single_products = .not. double
        if (present(refactor)) hydro%refactor_iterations = refactor
        if (present(smb)) then
          hydro%single_min_beads = smb
          hydro%single_operator_min_beads = smb
        end if
        if (present(loopsingle)) then
          if (loopsingle) hydro%single_operator_tolerance = huge(1.0_wp)
        end if
      class default
        call die(program_name, '--friction-change, --warm-history, --double-products, --refactor-iterations, '// &
                 '--single-operator, --single-min-beads: '// &
                 'the model is not the iterative one', 2)
      end select
    end if
    call dyn%init(scene, size(r, 2), error, hydro)
    if (allocated(error)) call die(program_name, error%message, 2)
    call make_stepper(scene%integrator, integ, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    t = 0.0_wp
    w0 = wall_seconds()
    call cpu_time(c0)
    call integ%advance(dyn, t, r, t_end, error)
    call cpu_time(c1)
    if (allocated(error)) call die(program_name, label//': '//error%message, 2)
    wall = wall_seconds() - w0
    write (output_unit, '(a)') label//'.wall_s = '//to_str(wall, '(f10.2)')
    write (output_unit, '(a)') label//'.processor_s = '//to_str(c1 - c0, '(f10.2)')
    write (output_unit, '(a)') label//'.loadavg_end = '//loadavg()
    write (output_unit, '(a)') label//'.steps = '//to_str(integ%steps())
    write (output_unit, '(a)') label//'.rejected = '//to_str(integ%rejected())
    write (output_unit, '(a)') label//'.evaluations = '//to_str(dyn%evaluations)
    write (output_unit, '(a)') label//'.evaluations_per_unit_time = '// &
      to_str(real(dyn%evaluations, wp)/t_end, '(f10.2)')
    write (output_unit, '(a)') label//'.mean_dt = '//to_str(t_end/real(max(1_i8, integ%steps()), wp), '(es10.3)')
    select type (integ)
    type is (rosenbrock_stepper_t)
      write (output_unit, '(a)') label//'.jacobians = '//to_str(integ%jacobians())
    end select
    if (upd /= update_stage) call print_stats(label//'.', dyn%hydro_statistics())
  end subroutine run_method

  !> Wall time of one Jacobian of the dynamics at the start configuration: right after a
  !> 'stage' evaluation there (the mobility cached) and cold (the model prepared first), and of
  !> one 'stage' evaluation, each the mean of 3.
  subroutine jacobian_cost()
    type(scene_t) :: scene
    type(dynamics_t) :: dyn
    type(error_t), allocatable :: error
    real(wp), allocatable :: r(:, :), v(:, :), jac(:, :), r2(:, :)
    real(wp) :: w0, t_eval, t_cached, t_cold
    integer :: k, evals
    call study_scene(config, 1.0e-4_wp, update_stage, scene, r)
    if (eps_lub < 0.0_wp) scene%hydro%eps_lub = 1.0e-4_wp
    call dyn%init(scene, size(r, 2), error)
    if (allocated(error)) call die(program_name, error%message, 2)
    allocate (v, r2, mold=r)
    allocate (jac(size(r), size(r)))
    t_eval = 0.0_wp
    t_cached = 0.0_wp
    t_cold = 0.0_wp
    do k = 1, 3
      w0 = wall_seconds()
      call dyn%velocity(r, v, error)
      t_eval = t_eval + (wall_seconds() - w0)/3.0_wp
      w0 = wall_seconds()
      call dyn%jacobian(0.0_wp, r, jac, evals, error)
      t_cached = t_cached + (wall_seconds() - w0)/3.0_wp
      r2 = r
      r2(1, 1) = r2(1, 1) + 1.0e-3_wp*k
      w0 = wall_seconds()
      call dyn%jacobian(0.0_wp, r2, jac, evals, error)
      t_cold = t_cold + (wall_seconds() - w0)/3.0_wp
      if (allocated(error)) call die(program_name, error%message, 2)
    end do
    write (output_unit, '(a)') 'stage_evaluation_s = '//to_str(t_eval, '(f10.4)')
    write (output_unit, '(a)') 'jacobian_after_evaluation_s = '//to_str(t_cached, '(f10.4)')
    write (output_unit, '(a)') 'jacobian_cold_s = '//to_str(t_cold, '(f10.4)')
  end subroutine jacobian_cost

  !> Velocities from the adaptive model's last many-body part reused as it is at rr.
  subroutine reused(fast, rr, vv)
    type(dynamics_t), intent(inout) :: fast
    real(wp), intent(in) :: rr(:, :)
    real(wp), intent(out) :: vv(:, :)
    type(error_t), allocatable :: error
    call fast%reused_velocity(rr, vv, error)
    if (allocated(error)) call die(program_name, error%message, 2)
  end subroutine reused

  !> dopri45 along the configuration with the study's model (update from --update), the
  !> stiffness of mu dF/dr at every trial step (kf_stiffness_probe); rows into --table.
  subroutine run_stiffness()
    type(scene_t) :: scene
    type(stiffness_probe_t) :: sys
    class(stepper_t), allocatable, target :: integ
    type(error_t), allocatable :: error
    real(wp), allocatable :: r(:, :), lh(:)
    real(wp) :: t, w0
    integer :: unit, ios, k, n, n_acc
    logical, allocatable :: acc(:)
    call header()
    call study_scene(config, tolerance, update, scene, r)
    if (eps_lub < 0.0_wp) scene%hydro%eps_lub = 1.0e-4_wp
    call sys%init(scene, size(r, 2), error)
    if (allocated(error)) call die(program_name, error%message, 2)
    call make_stepper(scene%integrator, integ, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    sys%stepper => integ
    t = 0.0_wp
    w0 = wall_seconds()
    call integ%advance(sys, t, r, t_end, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    n = sys%n_trials
    allocate (acc(n), lh(n))
    associate (tr => sys%trials(1:n))
      acc(:) = tr%accepted
      lh(:) = abs(tr%lambda)*tr%h
      n_acc = count(acc)
      write (output_unit, '(a)') 'update = '//update
      write (output_unit, '(a)') 'tolerance = '//to_str(tolerance, '(es10.3)')
      write (output_unit, '(a)') 'n_beads = '//to_str(size(r, 2))
      write (output_unit, '(a)') 'stability_boundary = '//to_str(stability_boundary, '(f6.3)')
      write (output_unit, '(a)') 'trials = '//to_str(n)
      write (output_unit, '(a)') 'steps = '//to_str(integ%steps())
      write (output_unit, '(a)') 'rejected = '//to_str(integ%rejected())
      write (output_unit, '(a)') 'evaluations_per_time = '//to_str(real(integ%evaluations(), wp)/t_end, '(f8.2)')
      write (output_unit, '(a)') 'h_mean = '//to_str(t_end/max(1, n_acc), '(es10.3)')
      write (output_unit, '(a)') 'lambda_min = '//to_str(minval(abs(tr%lambda)), '(f8.3)')
      write (output_unit, '(a)') 'lambda_max = '//to_str(maxval(abs(tr%lambda)), '(f8.3)')
      write (output_unit, '(a)') 'lambda_mean = '//to_str(sum(abs(tr%lambda))/max(1, n), '(f8.3)')
      write (output_unit, '(a)') 'lambda_h_mean_accepted = '//to_str(sum(lh, mask=acc)/max(1, n_acc), '(f8.3)')
      write (output_unit, '(a)') 'lambda_h_max_accepted = '//to_str(maxval(lh, mask=acc), '(f8.3)')
      write (output_unit, '(a)') 'lambda_h_mean_rejected = '//to_str(sum(lh, mask=.not. acc)/max(1, n - n_acc), '(f8.3)')
      write (output_unit, '(a)') 'accepted_above_0.9_boundary = '// &
        to_str(count(acc .and. lh > 0.9_wp*stability_boundary))
      write (output_unit, '(a)') 'error_over_tol_mean_accepted = '// &
        to_str(sum(tr%error, mask=acc)/max(1, n_acc)/tolerance, '(f8.3)')
      write (output_unit, '(a)') 'lanczos_iterations_mean = '//to_str(real(sum(tr%iterations), wp)/max(1, n), '(f8.2)')
      if (table /= '') then
        open (newunit=unit, file=table, action='write', status='replace', iostat=ios)
        if (ios /= 0) call die(program_name, '--table '//table//': cannot open for writing', 2)
        write (unit, '(a)') '# t h lambda lambda_h error_over_tol accepted lanczos_iterations'
        do k = 1, n
          write (unit, '(es14.6,1x,es12.4,1x,f10.4,1x,f8.4,1x,es12.4,1x,i1,1x,i3)') tr(k)%t, tr(k)%h, &
            tr(k)%lambda, lh(k), tr(k)%error/tolerance, merge(1, 0, tr(k)%accepted), tr(k)%iterations
        end do
        close (unit)
      end if
    end associate
    call print_stats(update//'.', sys%dyn%hydro_statistics())
    write (output_unit, '(a)') 'wall_s = '//to_str(wall_seconds() - w0, '(f10.2)')
  end subroutine run_stiffness

  subroutine run_scaling()
    integer, parameter :: sizes(4) = [50, 100, 200, 400]
    type(scene_t) :: scene
    type(error_t), allocatable :: error
    real(wp), allocatable :: r(:, :)
    real(wp) :: rot(3, 3), walls(size(sizes)), slope
    integer(i8) :: steps
    type(hydro_stats_t) :: stats
    integer :: k
    call header()
    do k = 1, size(sizes)
      call study_scene('trefoil', 1.0e-4_wp, update_adaptive, scene, r)
      scene%chain%shape = 'random'
      scene%chain%n_beads = sizes(k)
      call build_initial_chain(scene%chain, r, rot, error)
      if (allocated(error)) call die(program_name, error%message, 2)
      call integrate(scene, r, walls(k), steps, stats)
      walls(k) = walls(k)/t_end
      write (output_unit, '(a)') 'N'//to_str(sizes(k))//'.wall_s_per_time = '//to_str(walls(k), '(es10.3)')
      write (output_unit, '(a)') 'N'//to_str(sizes(k))//'.steps = '//to_str(steps)
      write (output_unit, '(a)') 'N'//to_str(sizes(k))//'.evaluations = '//to_str(stats%evaluations)
      write (output_unit, '(a)') 'N'//to_str(sizes(k))//'.refreshes = '//to_str(stats%refreshes)
    end do
    call loglog_slope(real(sizes, wp), walls, slope, error)
    if (allocated(error)) call die(program_name, error%message, 2)
    write (output_unit, '(a)') 'exponent = '//to_str(slope, '(f6.2)')
    write (output_unit, '(a)') 'exponent_n_min = '//to_str(sizes(1))
    write (output_unit, '(a)') 'exponent_n_max = '//to_str(sizes(size(sizes)))
  end subroutine run_scaling

end program knotflow_bench_reuse
