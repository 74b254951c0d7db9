!> The &forces group: which forces act. Owns the parameter type with its defaults, the reading
!> of the group, its part of the item catalogue and its validation (kf_forces builds from it).
module kf_scene_forces
  use kf_kinds, only: wp
  use kf_strings, only: to_str_exact
  use kf_error, only: error_t
  use kf_scene_item, only: scene_item_t, add_l, add_r, add_a
  use kf_scene_check, only: refuse, check_finite
  implicit none
  private

  ! The allowed values, in the words of the refusals and of the scene reference.
  character(len=*), parameter :: strength_allowed = 'a number in [0, 1e7)'
  character(len=*), parameter :: ev_range_allowed = 'a number in (0, 10]'
  character(len=*), parameter :: finite_allowed = 'finite numbers'
  character(len=*), parameter :: logical_allowed = '.true. or .false.'

  !> &forces: which forces exist.
  type, public :: forces_params_t
    logical :: springs = .true.
    real(wp) :: spring_k = 500.0_wp                 !< per pi eta d gamma_dot
    logical :: bending = .true.
    real(wp) :: bending_a = 2.2_wp                  !< A, per pi eta d^4 gamma_dot
    logical :: excluded_volume = .false.
    real(wp) :: ev_strength = 100.0_wp              !< stiffness of the non-bonded repulsion
    real(wp) :: ev_range = 1.0_wp                   !< repulsion acts for |r_i - r_j| < ev_range
    real(wp) :: external_force(3) = 0.0_wp          !< the same force on every bead
  end type forces_params_t

  public :: read_forces_group, forces_items, check_forces

contains

  !> Read the namelist text of &forces into `p` (the values `p` holds are the defaults).
  subroutine read_forces_group(p, text, ios, msg)
    type(forces_params_t), intent(inout) :: p
    character(len=*), intent(in) :: text
    integer, intent(out) :: ios
    character(len=*), intent(inout) :: msg
    logical :: springs, bending, excluded_volume
    real(wp) :: spring_k, bending_a, ev_strength, ev_range, external_force(3)
    namelist /forces/ springs, spring_k, bending, bending_a, excluded_volume, ev_strength, &
      ev_range, external_force
    springs = p%springs; spring_k = p%spring_k; bending = p%bending; bending_a = p%bending_a
    excluded_volume = p%excluded_volume; ev_strength = p%ev_strength; ev_range = p%ev_range
    external_force = p%external_force
    read (text, nml=forces, iostat=ios, iomsg=msg)
    p%springs = springs; p%spring_k = spring_k; p%bending = bending; p%bending_a = bending_a
    p%excluded_volume = excluded_volume; p%ev_strength = ev_strength; p%ev_range = ev_range
    p%external_force = external_force
  end subroutine read_forces_group

  !> The variables of &forces, in namelist order, appended to `items`.
  subroutine forces_items(p, items)
    type(forces_params_t), intent(in) :: p
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    call add_l(items, 'forces.springs', p%springs, logical_allowed, 'harmonic springs between bonded beads')
    call add_r(items, 'forces.spring_k', p%spring_k, strength_allowed, 'spring constant k, units of pi eta d gamma_dot')
    call add_l(items, 'forces.bending', p%bending, logical_allowed, 'bending stiffness (discrete elastica)')
    call add_r(items, 'forces.bending_a', p%bending_a, strength_allowed, &
      'bending stiffness A, units of pi eta d^4 gamma_dot')
    call add_l(items, 'forces.excluded_volume', p%excluded_volume, logical_allowed, &
      'repulsion of non-bonded pairs (|i-j| > 1) closer than ev_range: U = (ev_strength/2)(ev_range - r)^2')
    call add_r(items, 'forces.ev_strength', p%ev_strength, strength_allowed, 'stiffness of the excluded volume')
    call add_r(items, 'forces.ev_range', p%ev_range, ev_range_allowed, 'range of the excluded volume, units of d')
    call add_a(items, 'forces.external_force', p%external_force, [3, 0], finite_allowed, &
      'the same force on every bead, units of pi eta d^2 gamma_dot')
  end subroutine forces_items

  !> Check &forces (`file`: the scene file named in the messages, '' from code).
  subroutine check_forces(p, file, error)
    type(forces_params_t), intent(in) :: p
    character(len=*), intent(in) :: file
    type(error_t), allocatable, intent(out) :: error
    type(scene_item_t), allocatable :: items(:)
    allocate (items(0))
    call forces_items(p, items)
    call check_finite(items, file, error)
    if (allocated(error)) return
    if (.not. (p%spring_k >= 0.0_wp .and. p%spring_k < 1.0e7_wp)) then
      call refuse(error, file, 'forces', 'spring_k', to_str_exact(p%spring_k), strength_allowed); return
    end if
    if (.not. (p%bending_a >= 0.0_wp .and. p%bending_a < 1.0e7_wp)) then
      call refuse(error, file, 'forces', 'bending_a', to_str_exact(p%bending_a), strength_allowed); return
    end if
    if (.not. (p%ev_strength >= 0.0_wp .and. p%ev_strength < 1.0e7_wp)) then
      call refuse(error, file, 'forces', 'ev_strength', to_str_exact(p%ev_strength), strength_allowed); return
    end if
    if (.not. (p%ev_range > 0.0_wp .and. p%ev_range <= 10.0_wp)) then
      call refuse(error, file, 'forces', 'ev_range', to_str_exact(p%ev_range), ev_range_allowed); return
    end if
    if (.not. all(abs(p%external_force) < 1.0e7_wp)) then
      call refuse(error, file, 'forces', 'external_force', 'non-finite', finite_allowed); return
    end if
  end subroutine check_forces

end module kf_scene_forces
