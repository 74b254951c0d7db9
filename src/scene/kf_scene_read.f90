!> Reading a scene from a namelist file the CaNS way: defaults first, one group per concern, every
!> read checked (each group by its own module, kf_scene_<group>); unknown groups and variables are
!> rejected by name; then a validation pass whose messages name the file, group, variable, value
!> and what is allowed; then the resolution of the effective values (resolve_scene).
module kf_scene_read
  use kf_kinds, only: wp
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_scene, only: scene_t
  use kf_scene_item, only: scene_item_t, item_string, item_integer, item_real, item_logical, item_real_array
  use kf_scene_items, only: scene_items, group_names
  use kf_scene_check, only: refuse
  use kf_scene_chain, only: read_chain_group, check_chain, resolve_chain
  use kf_scene_forces, only: read_forces_group, check_forces
  use kf_scene_flow, only: read_flow_group, check_flow, flow_shear
  use kf_scene_hydro, only: read_hydro_group, check_hydro, resolve_hydro, model_multipole
  use kf_scene_integrator, only: read_integrator_group, check_integrator
  use kf_scene_output, only: read_output_group, check_output
  use kf_namelist_scan, only: nml_group_t, nml_assignment_t, scan_namelist_file, group_text, count_values
  implicit none
  private

  public :: read_scene, validate_scene, resolve_scene, find_group

contains

  !> Read, validate and resolve the scene in `path`. Groups listed in `extra_groups` (e.g.
  !> 'sweep') are accepted and left to their own readers, which get the scanned groups through
  !> `scanned`.
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
    if (allocated(error)) return
    call resolve_scene(sc, error)
    if (allocated(error)) return
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
        call read_chain_group(sc%chain, text, ios, msg)
      case ('forces')
        call read_forces_group(sc%forces, text, ios, msg)
      case ('flow')
        call read_flow_group(sc%flow, text, ios, msg)
      case ('hydro')
        call read_hydro_group(sc%hydro, text, ios, msg)
      case ('integrator')
        call read_integrator_group(sc%integrator, text, ios, msg)
      case ('output')
        call read_output_group(sc%output, text, ios, msg)
      end select
    end subroutine read_text

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

  !> Check every value against its allowed range: each group's own check (kf_scene_<group>),
  !> then what ties groups together. Messages: "<file>: &group: var = value is not allowed (...)".
  subroutine validate_scene(sc, error)
    type(scene_t), intent(in) :: sc
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: f

    f = trim(sc%source_file)
    call check_chain(sc%chain, f, error)
    if (.not. allocated(error)) call check_forces(sc%forces, f, error)
    if (.not. allocated(error)) call check_flow(sc%flow, f, error)
    if (.not. allocated(error)) call check_hydro(sc%hydro, f, error)
    if (.not. allocated(error)) call check_integrator(sc%integrator, f, error)
    if (.not. allocated(error)) call check_output(sc%output, f, error)
    if (allocated(error)) return
    ! the stresslet's rheological observables are those of simple shear (kf_rheology), and a
    ! multipole model represents the beads' stresslets only from L = 2 on
    associate (o => sc%output)
      if (o%stresslet .and. .not. (sc%flow%flow_type == flow_shear .and. sc%flow%shear_rate /= 0.0_wp)) then
        call refuse(error, f, 'output', 'stresslet', '.true.', ".false. unless &flow flow_type = 'shear' "// &
          'with shear_rate /= 0 (the viscosity and normal-stress coefficients are those of simple shear)'); return
      end if
      if (o%stresslet .and. sc%hydro%model == model_multipole .and. sc%hydro%order < 2) then
        call refuse(error, f, 'output', 'stresslet', '.true.', '.false. with &hydro model = '// &
          "'multipole' and order = 1 (L = 1 has no stresslet moments; use order >= 2)"); return
      end if
    end associate
  end subroutine validate_scene

  !> Turn a validated scene into its effective values, once at set-up: eps_lub from the
  !> integration tolerance when it is not given, chain.n_beads the real bead count of the shape
  !> (a coordinate file is read and checked). A given value that contradicts the shape is
  !> refused. Resolving a resolved scene changes nothing.
  subroutine resolve_scene(sc, error)
    type(scene_t), intent(inout) :: sc
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: f
    f = trim(sc%source_file)
    call resolve_chain(sc%chain, f, error)
    if (allocated(error)) return
    call resolve_hydro(sc%hydro, sc%integrator%tolerance, f, error)
  end subroutine resolve_scene

end module kf_scene_read
