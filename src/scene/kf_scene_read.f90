!> Reading a scene from a namelist file the CaNS way: defaults first, one group per concern, every
!> read checked; unknown groups and variables are rejected by name; then a validation pass whose
!> messages name the file, group, variable, value and what is allowed.
module kf_scene_read
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str, to_str_exact
  use kf_error, only: error_t, fatal_error
  use kf_scene, only: scene_t, chain_params_t, forces_params_t, flow_params_t, hydro_params_t, &
                      integrator_params_t, output_params_t, path_len, name_len
  use kf_scene_items, only: scene_item_t, scene_items, group_names, item_string, item_integer, &
                            item_real, item_logical, item_real_array
  use kf_overlap_rule, only: overlap_rule_names
  use kf_namelist_scan, only: nml_group_t, nml_assignment_t, scan_namelist_file, group_text, count_values
  implicit none
  private

  public :: read_scene, validate_scene, find_group

  character(len=*), parameter :: shapes = 'trefoil, candycane, straight, random, file'
  character(len=*), parameter :: flows = 'shear, linear, quiescent'
  character(len=*), parameter :: models = 'none, rpy, multipole'
  character(len=*), parameter :: methods = 'dopri45, rk4'
  character(len=*), parameter :: updates = 'stage, adaptive'

contains

  !> Read and validate the scene in `path`. Groups listed in `extra_groups` (e.g. 'sweep') are
  !> accepted and left to their own readers, which get the scanned groups through `scanned`.
  subroutine read_scene(path, sc, error, extra_groups, scanned)
    character(len=*), intent(in) :: path
    type(scene_t), intent(out) :: sc
    type(error_t), allocatable, intent(out) :: error
    character(len=*), intent(in), optional :: extra_groups(:)
    type(nml_group_t), allocatable, intent(out), optional :: scanned(:)
    type(nml_group_t), allocatable :: groups(:)
    type(scene_item_t), allocatable :: catalogue(:)
    integer :: k

    sc%source_file = path
    call scan_namelist_file(path, groups, error)
    if (allocated(error)) return
    call scene_items(sc, catalogue)
    call check_names(path, groups, catalogue, error, extra_groups)
    if (allocated(error)) return
    do k = 1, size(groups)
      call read_group(groups(k), error)
      if (allocated(error)) return
    end do
    call validate_scene(sc, error)
    if (present(scanned)) call move_alloc(groups, scanned)

  contains

    ! The readers are called, never passed as arguments: an internal procedure passed as an
    ! argument needs a trampoline on the stack, which makes the stack executable.

    !> Read one group; on failure, find the assignment that fails and name it.
    subroutine read_group(g, error)
      type(nml_group_t), intent(in) :: g
      type(error_t), allocatable, intent(out) :: error
      integer :: ios, m
      character(len=512) :: msg

      msg = ''
      call read_text(g%name, group_text(g), ios, msg)
      if (ios == 0) return
      do m = 1, size(g%items)
        msg = ''
        call read_text(g%name, group_text(g, only=m), ios, msg)
        if (ios /= 0) then
          call fatal_error(error, trim(path)//': &'//g%name//': '//g%items(m)%lhs//' = '// &
            g%items(m)%value//' is not valid (expected '// &
            expected_type(catalogue, g%name//'.'//g%items(m)%name)//')')
          return
        end if
      end do
      call fatal_error(error, trim(path)//': &'//g%name//': cannot read the group: '//trim(msg))
    end subroutine read_group

    !> The namelist text of group `name` into the scene; groups of other readers (`extra_groups`)
    !> are left alone.
    subroutine read_text(name, text, ios, msg)
      character(len=*), intent(in) :: name, text
      integer, intent(out) :: ios
      character(len=*), intent(inout) :: msg
      ios = 0
      select case (name)
      case ('chain')
        call read_chain(text, ios, msg)
      case ('forces')
        call read_forces(text, ios, msg)
      case ('flow')
        call read_flow(text, ios, msg)
      case ('hydro')
        call read_hydro(text, ios, msg)
      case ('integrator')
        call read_integrator(text, ios, msg)
      case ('output')
        call read_output(text, ios, msg)
      end select
    end subroutine read_text

    ! Each reader declares the namelist over local copies of one parameter type.
    subroutine read_chain(text, ios, msg)
      character(len=*), intent(in) :: text
      integer, intent(out) :: ios
      character(len=*), intent(inout) :: msg
      character(len=name_len) :: shape
      integer :: n_beads, trefoil_removed_point
      character(len=1) :: orientation
      real(wp) :: bond_length, straight_direction(3)
      character(len=path_len) :: coordinate_file
      integer(i8) :: seed
      namelist /chain/ shape, n_beads, orientation, trefoil_removed_point, bond_length, &
        coordinate_file, seed, straight_direction
      associate (p => sc%chain)
        shape = p%shape; n_beads = p%n_beads; orientation = p%orientation
        trefoil_removed_point = p%trefoil_removed_point; bond_length = p%bond_length
        coordinate_file = p%coordinate_file; seed = p%seed; straight_direction = p%straight_direction
        read (text, nml=chain, iostat=ios, iomsg=msg)
        p%shape = shape; p%n_beads = n_beads; p%orientation = orientation
        p%trefoil_removed_point = trefoil_removed_point; p%bond_length = bond_length
        p%coordinate_file = coordinate_file; p%seed = seed; p%straight_direction = straight_direction
      end associate
    end subroutine read_chain

    subroutine read_forces(text, ios, msg)
      character(len=*), intent(in) :: text
      integer, intent(out) :: ios
      character(len=*), intent(inout) :: msg
      logical :: springs, bending, excluded_volume
      real(wp) :: spring_k, bending_a, ev_strength, ev_range, external_force(3)
      namelist /forces/ springs, spring_k, bending, bending_a, excluded_volume, ev_strength, &
        ev_range, external_force
      associate (p => sc%forces)
        springs = p%springs; spring_k = p%spring_k; bending = p%bending; bending_a = p%bending_a
        excluded_volume = p%excluded_volume; ev_strength = p%ev_strength; ev_range = p%ev_range
        external_force = p%external_force
        read (text, nml=forces, iostat=ios, iomsg=msg)
        p%springs = springs; p%spring_k = spring_k; p%bending = bending; p%bending_a = bending_a
        p%excluded_volume = excluded_volume; p%ev_strength = ev_strength; p%ev_range = ev_range
        p%external_force = external_force
      end associate
    end subroutine read_forces

    subroutine read_flow(text, ios, msg)
      character(len=*), intent(in) :: text
      integer, intent(out) :: ios
      character(len=*), intent(inout) :: msg
      character(len=name_len) :: flow_type
      real(wp) :: shear_rate, velocity_gradient(3, 3)
      namelist /flow/ flow_type, shear_rate, velocity_gradient
      associate (p => sc%flow)
        flow_type = p%flow_type; shear_rate = p%shear_rate; velocity_gradient = p%velocity_gradient
        read (text, nml=flow, iostat=ios, iomsg=msg)
        p%flow_type = flow_type; p%shear_rate = shear_rate; p%velocity_gradient = velocity_gradient
      end associate
    end subroutine read_flow

    subroutine read_hydro(text, ios, msg)
      character(len=*), intent(in) :: text
      integer, intent(out) :: ios
      character(len=*), intent(inout) :: msg
      character(len=name_len) :: model
      integer :: order
      logical :: lubrication
      real(wp) :: eps_lub
      character(len=name_len) :: update, overlap
      namelist /hydro/ model, order, lubrication, eps_lub, update, overlap
      associate (p => sc%hydro)
        model = p%model; order = p%order; lubrication = p%lubrication; eps_lub = p%eps_lub
        update = p%update; overlap = p%overlap
        read (text, nml=hydro, iostat=ios, iomsg=msg)
        p%model = model; p%order = order; p%lubrication = lubrication; p%eps_lub = eps_lub
        p%update = update; p%overlap = overlap
      end associate
    end subroutine read_hydro

    subroutine read_integrator(text, ios, msg)
      character(len=*), intent(in) :: text
      integer, intent(out) :: ios
      character(len=*), intent(inout) :: msg
      character(len=name_len) :: method
      real(wp) :: t_end, tolerance, dt_initial, dt_min, dt_max
      integer(i8) :: max_steps
      namelist /integrator/ method, t_end, tolerance, dt_initial, dt_min, dt_max, max_steps
      associate (p => sc%integrator)
        method = p%method; t_end = p%t_end; tolerance = p%tolerance; dt_initial = p%dt_initial
        dt_min = p%dt_min; dt_max = p%dt_max; max_steps = p%max_steps
        read (text, nml=integrator, iostat=ios, iomsg=msg)
        p%method = method; p%t_end = t_end; p%tolerance = tolerance; p%dt_initial = dt_initial
        p%dt_min = dt_min; p%dt_max = dt_max; p%max_steps = max_steps
      end associate
    end subroutine read_integrator

    subroutine read_output(text, ios, msg)
      character(len=*), intent(in) :: text
      integer, intent(out) :: ios
      character(len=*), intent(inout) :: msg
      character(len=path_len) :: directory, case_name
      real(wp) :: frame_interval, progress_interval
      logical :: diagnostics, stresslet
      namelist /output/ directory, case_name, frame_interval, progress_interval, diagnostics, stresslet
      associate (p => sc%output)
        directory = p%directory; case_name = p%case_name; frame_interval = p%frame_interval
        progress_interval = p%progress_interval; diagnostics = p%diagnostics; stresslet = p%stresslet
        read (text, nml=output, iostat=ios, iomsg=msg)
        p%directory = directory; p%case_name = case_name; p%frame_interval = frame_interval
        p%progress_interval = progress_interval; p%diagnostics = diagnostics; p%stresslet = stresslet
      end associate
    end subroutine read_output

  end subroutine read_scene

  function expected_type(catalogue, name) result(text)
    type(scene_item_t), intent(in) :: catalogue(:)
    character(len=*), intent(in) :: name
    character(len=:), allocatable :: text
    integer :: k
    text = 'a value of the right type'
    do k = 1, size(catalogue)
      if (catalogue(k)%name /= name) cycle
      select case (catalogue(k)%kind)
      case (item_string)
        text = "a quoted string, e.g. 'abc'"
      case (item_integer)
        text = 'an integer'
      case (item_real)
        text = 'a real number'
      case (item_logical)
        text = '.true. or .false.'
      case (item_real_array)
        if (catalogue(k)%dims(2) > 0) then
          text = 'real numbers (a 3x3 array)'
        else
          text = 'real numbers (3 components)'
        end if
      end select
    end do
  end function expected_type

  !> Reject unknown or repeated groups and unknown variables, naming the allowed ones.
  subroutine check_names(path, groups, catalogue, error, extra_groups)
    character(len=*), intent(in) :: path
    type(nml_group_t), intent(in) :: groups(:)
    type(scene_item_t), intent(in) :: catalogue(:)
    type(error_t), allocatable, intent(out) :: error
    character(len=*), intent(in), optional :: extra_groups(:)
    character(len=10) :: known(6)
    character(len=:), allocatable :: allowed
    integer :: k, j, m
    logical :: found

    known = group_names()
    do k = 1, size(groups)
      do j = 1, k - 1
        if (groups(j)%name == groups(k)%name) then
          call fatal_error(error, trim(path)//': group &'//groups(k)%name//' appears twice')
          return
        end if
      end do
      if (present(extra_groups)) then
        if (any(extra_groups == groups(k)%name)) cycle
      end if
      if (.not. any(known == groups(k)%name)) then
        allowed = ''
        do j = 1, size(known)
          allowed = allowed//merge(', ', '  ', j > 1)//'&'//trim(known(j))
        end do
        if (present(extra_groups)) then
          do j = 1, size(extra_groups)
            allowed = allowed//', &'//trim(extra_groups(j))
          end do
        end if
        call fatal_error(error, trim(path)//': unknown group &'//groups(k)%name// &
          ' (allowed: '//trim(adjustl(allowed))//')')
        return
      end if
      do m = 1, size(groups(k)%items)
        found = .false.
        allowed = ''
        do j = 1, size(catalogue)
          if (index(catalogue(j)%name, groups(k)%name//'.') /= 1) cycle
          if (catalogue(j)%name == groups(k)%name//'.'//groups(k)%items(m)%name) found = .true.
          allowed = allowed//merge(', ', '  ', len(allowed) > 0)// &
                    trim(catalogue(j)%name(len(groups(k)%name) + 2:))
        end do
        if (.not. found) then
          call fatal_error(error, trim(path)//': &'//groups(k)%name//': unknown variable '''// &
            groups(k)%items(m)%name//''' (allowed: '//trim(adjustl(allowed))//')')
          return
        end if
        call check_shape(path, groups(k)%name, groups(k)%items(m), catalogue, error)
        if (allocated(error)) return
      end do
    end do
  end subroutine check_names

  !> The value of an assignment must fit its variable: one value for a scalar, exactly the
  !> number of components for a whole array (a subscripted one, x(2) = ..., is left to the
  !> namelist read), and a string no longer than the variable holds (it would be cut in silence).
  subroutine check_shape(path, group, a, catalogue, error)
    character(len=*), intent(in) :: path, group
    type(nml_assignment_t), intent(in) :: a
    type(scene_item_t), intent(in) :: catalogue(:)
    type(error_t), allocatable, intent(out) :: error
    integer :: j, n, want, q
    character(len=:), allocatable :: v
    do j = 1, size(catalogue)
      if (catalogue(j)%name /= group//'.'//a%name) cycle
      if (index(a%lhs, '(') > 0) return
      n = count_values(a%value)
      select case (catalogue(j)%kind)
      case (item_real_array)
        want = max(1, catalogue(j)%dims(1))*max(1, catalogue(j)%dims(2))
        if (n /= want) then
          call fatal_error(error, trim(path)//': &'//group//': '//a%lhs//' = '//a%value//' has '// &
            to_str(n)//' value(s) (allowed: exactly '//to_str(want)//')')
          return
        end if
      case default
        if (n /= 1) then
          call fatal_error(error, trim(path)//': &'//group//': '//a%lhs//' = '//a%value//' has '// &
            to_str(n)//' values (allowed: one)')
          return
        end if
        if (catalogue(j)%kind == item_string) then
          v = trim(adjustl(a%value))
          q = len(v)
          if (q >= 2) then
            if ((v(1:1) == "'" .or. v(1:1) == '"') .and. v(q:q) == v(1:1)) q = q - 2
          end if
          if (q > catalogue(j)%max_len) then
            call fatal_error(error, trim(path)//': &'//group//': '//a%lhs//' = '//a%value//' is '// &
              to_str(q)//' characters long (allowed: at most '//to_str(catalogue(j)%max_len)//')')
            return
          end if
        end if
      end select
      return
    end do
  end subroutine check_shape

  !> The index of group `name` in `groups`, 0 if absent.
  integer function find_group(groups, name) result(idx)
    type(nml_group_t), intent(in) :: groups(:)
    character(len=*), intent(in) :: name
    integer :: k
    idx = 0
    do k = 1, size(groups)
      if (groups(k)%name == name) then
        idx = k
        return
      end if
    end do
  end function find_group

  !> Check every value against its allowed range. Messages: "<file>: &group: var = value: allowed".
  subroutine validate_scene(sc, error)
    type(scene_t), intent(in) :: sc
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: f
    logical :: exists
    real(wp) :: g(3, 3)

    f = trim(sc%source_file)
    ! Every real must be finite (checked first, with ieee_is_finite: the range tests below would
    ! trap on NaN in a build with -ffpe-trap=invalid).
    block
      type(scene_item_t), allocatable :: items(:)
      integer :: k, dot
      call scene_items(sc, items)
      do k = 1, size(items)
        dot = index(items(k)%name, '.')
        select case (items(k)%kind)
        case (item_real)
          if (ieee_is_finite(items(k)%r)) cycle
          call bad(error, f, items(k)%name(1:dot - 1), trim(items(k)%name(dot + 1:)), &
            to_str_exact(items(k)%r), 'a finite number'); return
        case (item_real_array)
          if (all(ieee_is_finite(items(k)%ra))) cycle
          call bad(error, f, items(k)%name(1:dot - 1), trim(items(k)%name(dot + 1:)), &
            vector_text(items(k)%ra), 'finite numbers'); return
        end select
      end do
    end block
    associate (c => sc%chain)
      if (.not. one_of(c%shape, shapes)) then
        call bad(error, f, 'chain', 'shape', quoted(c%shape), 'one of '//shapes); return
      end if
      if (c%shape == 'straight' .or. c%shape == 'random') then
        if (c%n_beads < 2) then
          call bad(error, f, 'chain', 'n_beads', to_str(c%n_beads), 'an integer >= 2'); return
        end if
        if (c%n_beads > 100000) then
          call bad(error, f, 'chain', 'n_beads', to_str(c%n_beads), 'at most 100000'); return
        end if
      end if
      if (.not. one_of(c%orientation, 'a, b, c, d, e')) then
        call bad(error, f, 'chain', 'orientation', quoted(c%orientation), 'one of a, b, c, d, e'); return
      end if
      if (c%trefoil_removed_point < 1 .or. c%trefoil_removed_point > 100) then
        call bad(error, f, 'chain', 'trefoil_removed_point', to_str(c%trefoil_removed_point), &
          'an integer from 1 to 100'); return
      end if
      if (.not. (c%bond_length > 0.0_wp .and. c%bond_length < 100.0_wp)) then
        call bad(error, f, 'chain', 'bond_length', to_str_exact(c%bond_length), 'a number in (0, 100)'); return
      end if
      if (c%shape == 'file') then
        if (len_trim(c%coordinate_file) == 0) then
          call bad(error, f, 'chain', 'coordinate_file', "''", &
            "a file name (required with shape = 'file')"); return
        end if
        inquire (file=trim(c%coordinate_file), exist=exists)
        if (.not. exists) then
          call bad(error, f, 'chain', 'coordinate_file', quoted(c%coordinate_file), &
            'an existing file (not found)'); return
        end if
      end if
      if (.not. all(ieee_is_finite(c%straight_direction))) then
        call bad(error, f, 'chain', 'straight_direction', vector_text(c%straight_direction), &
          'finite numbers'); return
      end if
      if (c%shape == 'straight' .and. .not. norm2(c%straight_direction) > 0.0_wp) then
        call bad(error, f, 'chain', 'straight_direction', vector_text(c%straight_direction), &
          'a non-zero vector'); return
      end if
    end associate
    associate (p => sc%forces)
      if (.not. (p%spring_k >= 0.0_wp .and. p%spring_k < 1.0e7_wp)) then
        call bad(error, f, 'forces', 'spring_k', to_str_exact(p%spring_k), 'a number in [0, 1e7)'); return
      end if
      if (.not. (p%bending_a >= 0.0_wp .and. p%bending_a < 1.0e7_wp)) then
        call bad(error, f, 'forces', 'bending_a', to_str_exact(p%bending_a), 'a number in [0, 1e7)'); return
      end if
      if (.not. (p%ev_strength >= 0.0_wp .and. p%ev_strength < 1.0e7_wp)) then
        call bad(error, f, 'forces', 'ev_strength', to_str_exact(p%ev_strength), 'a number in [0, 1e7)'); return
      end if
      if (.not. (p%ev_range > 0.0_wp .and. p%ev_range <= 10.0_wp)) then
        call bad(error, f, 'forces', 'ev_range', to_str_exact(p%ev_range), 'a number in (0, 10]'); return
      end if
      if (.not. all(abs(p%external_force) < 1.0e7_wp)) then
        call bad(error, f, 'forces', 'external_force', 'non-finite', 'finite numbers'); return
      end if
    end associate
    associate (w => sc%flow)
      if (.not. one_of(w%flow_type, flows)) then
        call bad(error, f, 'flow', 'flow_type', quoted(w%flow_type), 'one of '//flows); return
      end if
      if (.not. (abs(w%shear_rate) < 1.0e6_wp)) then
        call bad(error, f, 'flow', 'shear_rate', to_str_exact(w%shear_rate), 'a finite number'); return
      end if
      g = w%velocity_gradient
      if (w%flow_type == 'linear') then
        if (.not. all(abs(g) < 1.0e6_wp)) then
          call bad(error, f, 'flow', 'velocity_gradient', 'non-finite', 'finite numbers'); return
        end if
        if (abs(g(1, 1) + g(2, 2) + g(3, 3)) > 1.0e-12_wp*max(1.0_wp, maxval(abs(g)))) then
          call bad(error, f, 'flow', 'velocity_gradient', 'trace '//to_str_exact(g(1, 1) + g(2, 2) + g(3, 3)), &
            'a traceless matrix (incompressible flow)'); return
        end if
      end if
    end associate
    associate (h => sc%hydro)
      if (.not. one_of(h%model, models)) then
        call bad(error, f, 'hydro', 'model', quoted(h%model), 'one of '//models); return
      end if
      if (h%model == 'multipole') then
        if (h%order < 1 .or. h%order > 8) then
          call bad(error, f, 'hydro', 'order', to_str(h%order), 'an integer from 1 to 8'); return
        end if
        if (h%lubrication .and. h%order > 6) then
          call bad(error, f, 'hydro', 'order', to_str(h%order), &
            'at most 6 with lubrication = .true. (tables exist for L = 1..6)'); return
        end if
      end if
      ! the lubrication model's own range (kf_lubrication, kf_hydro_multipole): 0 < eps_lub < 0.5
      if (.not. (h%eps_lub < 0.5_wp .and. h%eps_lub /= 0.0_wp)) then
        call bad(error, f, 'hydro', 'eps_lub', to_str_exact(h%eps_lub), &
          'a number in (0, 0.5), or negative for the integration tolerance'); return
      end if
      if (.not. one_of(h%update, updates)) then
        call bad(error, f, 'hydro', 'update', quoted(h%update), 'one of '//updates); return
      end if
      if (.not. one_of(h%overlap, overlap_rule_names)) then
        call bad(error, f, 'hydro', 'overlap', quoted(h%overlap), 'one of '//overlap_rule_names); return
      end if
      if (h%overlap /= 'pair' .and. h%model /= 'multipole') then
        call bad(error, f, 'hydro', 'overlap', quoted(h%overlap), &
          "'pair' with model = "//quoted(h%model)//" (the rule is for the multipole model)"); return
      end if
    end associate
    associate (g => sc%integrator)
      if (.not. one_of(g%method, methods)) then
        call bad(error, f, 'integrator', 'method', quoted(g%method), 'one of '//methods); return
      end if
      if (.not. (g%t_end > 0.0_wp .and. g%t_end < 1.0e12_wp)) then
        call bad(error, f, 'integrator', 't_end', to_str_exact(g%t_end), 'a number > 0'); return
      end if
      if (.not. (g%tolerance > 0.0_wp .and. g%tolerance < 1.0_wp)) then
        call bad(error, f, 'integrator', 'tolerance', to_str_exact(g%tolerance), 'a number in (0, 1)'); return
      end if
      if (.not. (g%dt_min > 0.0_wp)) then
        call bad(error, f, 'integrator', 'dt_min', to_str_exact(g%dt_min), 'a number > 0'); return
      end if
      if (.not. (g%dt_max > g%dt_min)) then
        call bad(error, f, 'integrator', 'dt_max', to_str_exact(g%dt_max), 'a number > dt_min = '//to_str_exact(g%dt_min))
        return
      end if
      if (.not. (g%dt_initial >= g%dt_min .and. g%dt_initial <= g%dt_max)) then
        call bad(error, f, 'integrator', 'dt_initial', to_str_exact(g%dt_initial), &
          'a number in [dt_min, dt_max] = ['//to_str_exact(g%dt_min)//', '//to_str_exact(g%dt_max)//']'); return
      end if
      if (g%max_steps < 1) then
        call bad(error, f, 'integrator', 'max_steps', to_str(int(g%max_steps)), 'an integer >= 1'); return
      end if
    end associate
    associate (o => sc%output)
      if (len_trim(o%directory) == 0) then
        call bad(error, f, 'output', 'directory', "''", 'a directory name'); return
      end if
      if (.not. (o%frame_interval > 0.0_wp)) then
        call bad(error, f, 'output', 'frame_interval', to_str_exact(o%frame_interval), 'a number > 0'); return
      end if
      if (.not. (o%progress_interval >= 0.0_wp)) then
        call bad(error, f, 'output', 'progress_interval', to_str_exact(o%progress_interval), &
          'a number >= 0 (seconds; 0 = every frame)'); return
      end if
      if (verify(trim(o%case_name), 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-+') /= 0) then
        call bad(error, f, 'output', 'case_name', quoted(o%case_name), &
          'letters, digits and _ . - + only'); return
      end if
      ! the stresslet's rheological observables are those of simple shear (kf_rheology), and a
      ! multipole model represents the beads' stresslets only from L = 2 on
      if (o%stresslet .and. .not. (sc%flow%flow_type == 'shear' .and. sc%flow%shear_rate /= 0.0_wp)) then
        call bad(error, f, 'output', 'stresslet', '.true.', ".false. unless &flow flow_type = 'shear' "// &
          'with shear_rate /= 0 (the viscosity and normal-stress coefficients are those of simple shear)'); return
      end if
      if (o%stresslet .and. sc%hydro%model == 'multipole' .and. sc%hydro%order < 2) then
        call bad(error, f, 'output', 'stresslet', '.true.', '.false. with &hydro model = '// &
          "'multipole' and order = 1 (L = 1 has no stresslet moments; use order >= 2)"); return
      end if
    end associate
  end subroutine validate_scene

  subroutine bad(error, file, group, var, value, allowed)
    type(error_t), allocatable, intent(out) :: error
    character(len=*), intent(in) :: file, group, var, value, allowed
    call fatal_error(error, file//': &'//group//': '//var//' = '//value//' is not allowed ('// &
      allowed//')')
  end subroutine bad

  !> Is `value` one of the comma-separated words in `list`?
  logical function one_of(value, list)
    character(len=*), intent(in) :: value, list
    integer :: start, comma
    character(len=:), allocatable :: word
    one_of = .false.
    start = 1
    do
      comma = index(list(start:), ',')
      if (comma == 0) then
        word = trim(adjustl(list(start:)))
      else
        word = trim(adjustl(list(start:start + comma - 2)))
      end if
      if (trim(value) == word) then
        one_of = .true.
        return
      end if
      if (comma == 0) return
      start = start + comma
    end do
  end function one_of

  function vector_text(v) result(t)
    real(wp), intent(in) :: v(:)
    character(len=:), allocatable :: t
    integer :: k
    t = ''
    do k = 1, size(v)
      t = t//merge(', ', '  ', k > 1)//to_str_exact(v(k))
    end do
    t = trim(adjustl(t))
  end function vector_text

  function quoted(s) result(t)
    character(len=*), intent(in) :: s
    character(len=:), allocatable :: t
    t = "'"//trim(s)//"'"
  end function quoted

end module kf_scene_read
