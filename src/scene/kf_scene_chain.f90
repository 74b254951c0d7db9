!> The &chain group: the initial shape. Owns the parameter type with its defaults, the reading
!> of the group, its part of the item catalogue, its validation, the names of the shapes (the
!> shape factory kf_chain_shapes builds from them) and the resolution of the bead count.
module kf_scene_chain
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str, to_str_exact
  use kf_error, only: error_t, fatal_error
  use kf_scene_item, only: scene_item_t, add_s, add_i, add_r, add_a, path_len, name_len
  use kf_scene_check, only: refuse, name_list, quoted, vector_text, check_finite
  use kf_text_coords, only: read_coordinates
  implicit none
  private

  character(len=*), parameter, public :: shape_trefoil = 'trefoil', shape_candycane = 'candycane', &
    shape_straight = 'straight', shape_random = 'random', shape_file = 'file'
  !> The valid values of &chain shape.
  character(len=*), parameter, public :: shape_names(5) = [character(len=9) :: shape_trefoil, &
    shape_candycane, shape_straight, shape_random, shape_file]
  !> The valid values of &chain orientation (trefoil).
  character(len=*), parameter, public :: orientation_names(5) = ['a', 'b', 'c', 'd', 'e']
  !> The valid values of &chain candycane_rotation: a uniformly (Haar) random rotation drawn from
  !> `seed`, or the unrotated candy-cane (in the xy plane) turned about the x axis by tilt_deg.
  character(len=*), parameter, public :: rotation_random = 'random', rotation_tilt_x = 'tilt_x'
  character(len=*), parameter, public :: candycane_rotation_names(2) = [character(len=6) :: &
    rotation_random, rotation_tilt_x]
  real(wp), parameter, public :: max_tilt_deg = 360.0_wp   !< |tilt_deg| <= this
  !> &chain perturbation: at most this many d (a displacement, not a new shape).
  real(wp), parameter, public :: max_perturbation = 0.1_wp

  integer, parameter, public :: trefoil_points = 100     !< points on the closed trefoil (one is removed)
  integer, parameter, public :: candycane_beads = 152    !< beads of the candy-cane
  integer, parameter, public :: default_n_beads = 99     !< straight and random chains without n_beads
  integer, parameter :: max_beads = 100000
  !> Longest bond of a coordinate file, in rest lengths (bond_length): a strain of 100 %.
  real(wp), parameter, public :: max_bond_stretch = 2.0_wp

  ! The allowed values, in the words of the refusals and of the scene reference.
  character(len=*), parameter :: bond_length_allowed = 'a number in (0, 100)'
  character(len=*), parameter :: bond_length_random_allowed = &
    "a number > 0.5 with shape = 'random' (non-bonded beads stay 1 d apart)"
  character(len=*), parameter :: coordinate_file_allowed = "a file name (required with shape = 'file')"
  character(len=*), parameter :: stepper_state_allowed = &
    "'' (none) or an existing file, only with shape = 'file' (a state at its positions)"
  character(len=*), parameter :: straight_direction_allowed = 'a non-zero vector'
  character(len=*), parameter :: n_beads_min_allowed = 'an integer >= 2'

  !> &chain: the initial shape.
  type, public :: chain_params_t
    character(len=name_len) :: shape = shape_trefoil !< trefoil | candycane | straight | random | file
    !> 0 (not given): the shape's own count (trefoil 99, candy-cane 152, a file its lines,
    !> straight and random 99); resolve_chain sets the real count. An explicit value that
    !> contradicts the shape is refused.
    integer :: n_beads = 0
    character(len=1) :: orientation = 'a'           !< trefoil orientation a..e
    integer :: trefoil_removed_point = 100          !< which of the 100 trefoil points is removed
    real(wp) :: bond_length = 1.02_wp               !< l0, rest length of the springs
    character(len=path_len) :: coordinate_file = '' !< shape = 'file': one bead per line, x y z
    !> shape = 'file': the time stepper's state at the file's positions (HDF5, kf_stepper_state_file),
    !> so that the run continues another one exactly; '': the stepper starts afresh
    character(len=path_len) :: stepper_state = ''
    integer(i8) :: seed = 20150509_i8               !< candy-cane rotation, random chain
    real(wp) :: straight_direction(3) = [0.0_wp, 0.0_wp, 1.0_wp] !< axis of the straight chain
    !> candy-cane: 'random' (Haar rotation from seed) or 'tilt_x' (about x by tilt_deg)
    character(len=name_len) :: candycane_rotation = rotation_random
    real(wp) :: tilt_deg = 0.0_wp                   !< candycane_rotation = 'tilt_x': degrees about x
    !> every bead displaced by p times an isotropic random unit vector (from seed), p in d
    real(wp) :: perturbation = 0.0_wp
  end type chain_params_t

  public :: read_chain_group, chain_items, check_chain, resolve_chain, read_chain_file

contains

  !> Read the namelist text of &chain into `p` (the values `p` holds are the defaults).
  subroutine read_chain_group(p, text, ios, msg)
    type(chain_params_t), intent(inout) :: p
    character(len=*), intent(in) :: text
    integer, intent(out) :: ios
    character(len=*), intent(inout) :: msg
    character(len=name_len) :: shape
    integer :: n_beads, trefoil_removed_point
    character(len=1) :: orientation
    real(wp) :: bond_length, straight_direction(3), tilt_deg, perturbation
    character(len=path_len) :: coordinate_file, stepper_state
    character(len=name_len) :: candycane_rotation
    integer(i8) :: seed
    namelist /chain/ shape, n_beads, orientation, trefoil_removed_point, bond_length, &
      coordinate_file, seed, straight_direction, candycane_rotation, tilt_deg, perturbation, stepper_state
    shape = p%shape; n_beads = p%n_beads; orientation = p%orientation
    trefoil_removed_point = p%trefoil_removed_point; bond_length = p%bond_length
    coordinate_file = p%coordinate_file; seed = p%seed; straight_direction = p%straight_direction
    candycane_rotation = p%candycane_rotation; tilt_deg = p%tilt_deg; perturbation = p%perturbation
    stepper_state = p%stepper_state
    read (text, nml=chain, iostat=ios, iomsg=msg)
    p%shape = shape; p%n_beads = n_beads; p%orientation = orientation
    p%trefoil_removed_point = trefoil_removed_point; p%bond_length = bond_length
    p%coordinate_file = coordinate_file; p%seed = seed; p%straight_direction = straight_direction
    p%candycane_rotation = candycane_rotation; p%tilt_deg = tilt_deg; p%perturbation = perturbation
    p%stepper_state = stepper_state
  end subroutine read_chain_group

  !> The variables of &chain, in namelist order, appended to `items`.
  subroutine chain_items(p, items)
    type(chain_params_t), intent(in) :: p
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    call add_s(items, 'chain.shape', p%shape, 'one of '//name_list(shape_names), &
      'the initial shape: trefoil (N = 99: the closed trefoil of 100 points with one removed), candycane '// &
      '(N = 152), straight, random (a random walk whose non-bonded beads stay 1 d apart), file (a coordinate file)')
    call add_i(items, 'chain.n_beads', int(p%n_beads, i8), n_beads_allowed(), &
      "0: not given, the shape's own count (trefoil 99, candycane 152, the bead lines of a coordinate file, "// &
      "99 for straight and random); chosen only for 'straight' and 'random', a count that contradicts the "// &
      'shape is refused')
    call add_s(items, 'chain.orientation', p%orientation, 'one of '//name_list(orientation_names), &
      'trefoil orientation: b, c rotate a about x by pi/2, pi; d, e rotate it about z by pi/2, 3 pi/2')
    call add_i(items, 'chain.trefoil_removed_point', int(p%trefoil_removed_point, i8), removed_point_allowed(), &
      'which of the 100 points of the closed trefoil is removed to open it')
    call add_r(items, 'chain.bond_length', p%bond_length, bond_length_allowed//'; '//bond_length_random_allowed, &
      'l0, rest length of the springs (also the spacing of straight and random chains), units of d')
    call add_s(items, 'chain.coordinate_file', p%coordinate_file, coordinate_file_allowed, &
      "shape = 'file': one bead per line, x y z (# starts a comment)")
    call add_i(items, 'chain.seed', p%seed, 'an integer', &
      "seed of the candy-cane's random rotation and of the random chain (recorded in the case file)")
    call add_a(items, 'chain.straight_direction', p%straight_direction, [3, 0], straight_direction_allowed, &
      'axis of the straight chain')
    call add_s(items, 'chain.candycane_rotation', p%candycane_rotation, 'one of '//name_list(candycane_rotation_names), &
      "the candy-cane's start: random (a uniform random rotation drawn from seed) or tilt_x (the unrotated "// &
      'candy-cane in the xy plane tilted about x by tilt_deg)')
    call add_r(items, 'chain.tilt_deg', p%tilt_deg, tilt_allowed()//"; 0 unless candycane_rotation = 'tilt_x'", &
      "the tilt about x of candycane_rotation = 'tilt_x'")
    call add_r(items, 'chain.perturbation', p%perturbation, perturbation_allowed(), &
      'every bead moved by this length in a random isotropic direction drawn from seed (0: none)')
    call add_s(items, 'chain.stepper_state', p%stepper_state, stepper_state_allowed, &
      "the time stepper's state at the coordinate file's positions (HDF5: /time, /positions, /stepper; "// &
      'written by knotflow-campaign plan from the case ledger), so that the run continues the one it '// &
      'comes from as a resume would; checked against the scene at set-up')
  end subroutine chain_items

  !> Check &chain (`file`: the scene file named in the messages, '' from code).
  subroutine check_chain(p, file, error)
    type(chain_params_t), intent(in) :: p
    character(len=*), intent(in) :: file
    type(error_t), allocatable, intent(out) :: error
    type(scene_item_t), allocatable :: items(:)
    allocate (items(0))
    call chain_items(p, items)
    call check_finite(items, file, error)
    if (allocated(error)) return
    if (.not. any(shape_names == p%shape)) then
      call refuse(error, file, 'chain', 'shape', quoted(p%shape), 'one of '//name_list(shape_names)); return
    end if
    ! 0: not given (the shape's own count)
    if (p%n_beads /= 0 .and. p%n_beads < 2) then
      call refuse(error, file, 'chain', 'n_beads', to_str(p%n_beads), n_beads_min_allowed); return
    end if
    if (p%n_beads > max_beads) then
      call refuse(error, file, 'chain', 'n_beads', to_str(p%n_beads), n_beads_max_allowed()); return
    end if
    if (.not. any(orientation_names == p%orientation)) then
      call refuse(error, file, 'chain', 'orientation', quoted(p%orientation), &
        'one of '//name_list(orientation_names)); return
    end if
    if (p%trefoil_removed_point < 1 .or. p%trefoil_removed_point > trefoil_points) then
      call refuse(error, file, 'chain', 'trefoil_removed_point', to_str(p%trefoil_removed_point), &
        removed_point_allowed()); return
    end if
    if (.not. (p%bond_length > 0.0_wp .and. p%bond_length < 100.0_wp)) then
      call refuse(error, file, 'chain', 'bond_length', to_str_exact(p%bond_length), bond_length_allowed); return
    end if
    ! the random chain keeps non-bonded beads 1 d apart, which steps of l0 <= 0.5 cannot do
    if (p%shape == shape_random .and. .not. p%bond_length > 0.5_wp) then
      call refuse(error, file, 'chain', 'bond_length', to_str_exact(p%bond_length), &
        bond_length_random_allowed); return
    end if
    if (p%shape == shape_file) then
      if (len_trim(p%coordinate_file) == 0) then
        call refuse(error, file, 'chain', 'coordinate_file', "''", &
          coordinate_file_allowed); return
      end if
      call check_exists('coordinate_file', p%coordinate_file, error)
      if (allocated(error)) return
    end if
    if (len_trim(p%stepper_state) > 0) then
      if (p%shape /= shape_file) then
        call refuse(error, file, 'chain', 'stepper_state', quoted(p%stepper_state), &
          stepper_state_allowed); return
      end if
      call check_exists('stepper_state', p%stepper_state, error)
      if (allocated(error)) return
    end if
    if (p%shape == shape_straight .and. .not. norm2(p%straight_direction) > 0.0_wp) then
      call refuse(error, file, 'chain', 'straight_direction', vector_text(p%straight_direction), &
        straight_direction_allowed); return
    end if
    if (.not. any(candycane_rotation_names == p%candycane_rotation)) then
      call refuse(error, file, 'chain', 'candycane_rotation', quoted(p%candycane_rotation), &
        'one of '//name_list(candycane_rotation_names)); return
    end if
    if (p%candycane_rotation /= rotation_random .and. p%shape /= shape_candycane) then
      call refuse(error, file, 'chain', 'candycane_rotation', quoted(p%candycane_rotation), &
        quoted(rotation_random)//" (the default) unless shape = '"//shape_candycane//"'"); return
    end if
    if (abs(p%tilt_deg) > max_tilt_deg) then
      call refuse(error, file, 'chain', 'tilt_deg', to_str_exact(p%tilt_deg), &
        tilt_allowed()); return
    end if
    if (p%tilt_deg /= 0.0_wp .and. p%candycane_rotation /= rotation_tilt_x) then
      call refuse(error, file, 'chain', 'tilt_deg', to_str_exact(p%tilt_deg), &
        "0 unless candycane_rotation = '"//rotation_tilt_x//"'"); return
    end if
    if (.not. (p%perturbation >= 0.0_wp .and. p%perturbation <= max_perturbation)) then
      call refuse(error, file, 'chain', 'perturbation', to_str_exact(p%perturbation), &
        perturbation_allowed()); return
    end if

  contains

    !> The file that &chain `var` names must exist.
    subroutine check_exists(var, path, err)
      character(len=*), intent(in) :: var, path
      type(error_t), allocatable, intent(out) :: err
      logical :: found
      inquire (file=trim(path), exist=found)
      if (.not. found) call refuse(err, file, 'chain', var, quoted(path), 'an existing file (not found)')
    end subroutine check_exists

  end subroutine check_chain

  !> Set n_beads to the real bead count of the shape (a coordinate file is read and checked).
  !> An n_beads given in the scene that contradicts the shape is refused.
  subroutine resolve_chain(p, file, error)
    type(chain_params_t), intent(inout) :: p
    character(len=*), intent(in) :: file
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: r(:, :)
    real(wp) :: bond
    integer :: n, i
    select case (p%shape)
    case (shape_trefoil)
      n = trefoil_points - 1
    case (shape_candycane)
      n = candycane_beads
    case (shape_file)
      call read_chain_file(p%coordinate_file, r, error)
      if (allocated(error)) then
        error%message = prefix(file)//'&chain: '//error%message
        return
      end if
      n = size(r, 2)
      ! A bond far beyond its rest length l0 is a wrong file or a wrong bond_length, not a
      ! chain to relax: the spring force would throw the beads apart (docs/inputs.md).
      do i = 1, n - 1
        bond = norm2(r(:, i + 1) - r(:, i))
        if (bond > max_bond_stretch*p%bond_length) then
          call refuse(error, file, 'chain', 'coordinate_file', quoted(p%coordinate_file), &
            'bonds of at most '//to_str_exact(max_bond_stretch)//' times bond_length = '// &
            to_str_exact(p%bond_length)//'; bond '//to_str(i)//' (beads '//to_str(i)//' and '// &
            to_str(i + 1)//') is '//to_str(bond, '(f0.4)')//' long'); return
        end if
      end do
    case default
      if (p%n_beads == 0) p%n_beads = default_n_beads
      return
    end select
    if (p%n_beads /= 0 .and. p%n_beads /= n) then
      call refuse(error, file, 'chain', 'n_beads', to_str(p%n_beads), to_str(n)//', the bead count of shape = '// &
        quoted(p%shape)//", or not given (n_beads is chosen only for 'straight' and 'random')"); return
    end if
    p%n_beads = n
  end subroutine resolve_chain

  !> The beads of a coordinate file, checked: at least 2, no two at the same place (closer than
  !> 1e-9 d, which makes the hydrodynamic and bending terms singular; every pair is compared up
  !> to 20,000 beads, the bonded neighbours beyond). Messages start with "coordinate_file = ".
  subroutine read_chain_file(path, r, error)
    character(len=*), intent(in) :: path
    real(wp), allocatable, intent(out) :: r(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp), parameter :: tiny_distance2 = 1.0e-18_wp
    integer :: i, j, n
    call read_coordinates(trim(path), r, error)
    if (allocated(error)) then
      error%message = 'coordinate_file = '//quoted(path)//': '//error%message
      return
    end if
    n = size(r, 2)
    if (n < 2) then
      call fatal_error(error, 'coordinate_file = '//quoted(path)//' holds fewer than 2 beads (allowed: at least 2)')
      return
    end if
    do j = 2, n
      do i = merge(1, j - 1, n <= 20000), j - 1
        if (sum((r(:, j) - r(:, i))**2) < tiny_distance2) then
          call fatal_error(error, 'coordinate_file = '//quoted(path)//': beads '//to_str(i)//' and '// &
            to_str(j)//' coincide (allowed: distinct points)')
          return
        end if
      end do
    end do
  end subroutine read_chain_file

  !> The allowed values of n_beads: the two refusals' words together.
  function n_beads_allowed() result(t)
    character(len=:), allocatable :: t
    t = n_beads_min_allowed//', '//n_beads_max_allowed()
  end function n_beads_allowed

  !> The upper limit of n_beads, in words.
  function n_beads_max_allowed() result(t)
    character(len=:), allocatable :: t
    t = 'at most '//to_str(max_beads)
  end function n_beads_max_allowed

  !> The allowed values of trefoil_removed_point, in words.
  function removed_point_allowed() result(t)
    character(len=:), allocatable :: t
    t = 'an integer from 1 to '//to_str(trefoil_points)
  end function removed_point_allowed

  pure function prefix(file) result(t)
    character(len=*), intent(in) :: file
    character(len=:), allocatable :: t
    t = ''
    if (len(file) > 0) t = file//': '
  end function prefix

  !> The allowed values of tilt_deg, in the words of the refusal and of the scene reference.
  function tilt_allowed() result(text)
    character(len=:), allocatable :: text
    text = 'a number of degrees from -'//to_str_exact(max_tilt_deg)//' to '//to_str_exact(max_tilt_deg)
  end function tilt_allowed

  !> The allowed values of perturbation, in the words of the refusal and of the scene reference.
  function perturbation_allowed() result(text)
    character(len=:), allocatable :: text
    text = 'a length in d from 0 to '//to_str_exact(max_perturbation)
  end function perturbation_allowed

end module kf_scene_chain
