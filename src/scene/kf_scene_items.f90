!> The effective scene as a flat list of typed items named `<group>.<variable>`: used to echo the
!> scene (as re-readable namelist text), to write it as HDF5 attributes, and as the catalogue of
!> allowed variable names per group.
module kf_scene_items
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str, to_str_exact
  use kf_scene, only: scene_t
  implicit none
  private

  integer, parameter, public :: item_string = 1, item_integer = 2, item_real = 3, &
                                item_logical = 4, item_real_array = 5

  !> One scene variable.
  type, public :: scene_item_t
    character(len=64) :: name = ''                !< group.variable
    integer :: kind = 0
    character(len=:), allocatable :: s            !< item_string
    integer(i8) :: i = 0                          !< item_integer, item_logical (0/1)
    real(wp) :: r = 0.0_wp                        !< item_real
    real(wp), allocatable :: ra(:)                !< item_real_array (flattened, Fortran order)
    integer :: dims(2) = [0, 0]                   !< item_real_array: (n) -> [n, 0]; (n,m) -> [n, m]
    integer :: max_len = 0                        !< item_string: the declared length
  end type scene_item_t

  public :: scene_items, scene_text, item_value_text, group_names

  character(len=*), parameter :: group_list(6) = [character(len=10) :: &
    'chain', 'forces', 'flow', 'hydro', 'integrator', 'output']

contains

  !> The namelist groups of a scene, in order.
  pure function group_names() result(names)
    character(len=10) :: names(size(group_list))
    names = group_list
  end function group_names

  !> Every variable of the scene, in namelist order.
  subroutine scene_items(sc, items)
    type(scene_t), intent(in) :: sc
    type(scene_item_t), allocatable, intent(out) :: items(:)
    allocate (items(0))
    associate (c => sc%chain)
      call add_s(items, 'chain.shape', c%shape)
      call add_i(items, 'chain.n_beads', int(c%n_beads, i8))
      call add_s(items, 'chain.orientation', c%orientation)
      call add_i(items, 'chain.trefoil_removed_point', int(c%trefoil_removed_point, i8))
      call add_r(items, 'chain.bond_length', c%bond_length)
      call add_s(items, 'chain.coordinate_file', c%coordinate_file)
      call add_i(items, 'chain.seed', c%seed)
      call add_a(items, 'chain.straight_direction', c%straight_direction, [3, 0])
    end associate
    associate (f => sc%forces)
      call add_l(items, 'forces.springs', f%springs)
      call add_r(items, 'forces.spring_k', f%spring_k)
      call add_l(items, 'forces.bending', f%bending)
      call add_r(items, 'forces.bending_a', f%bending_a)
      call add_l(items, 'forces.excluded_volume', f%excluded_volume)
      call add_r(items, 'forces.ev_strength', f%ev_strength)
      call add_r(items, 'forces.ev_range', f%ev_range)
      call add_a(items, 'forces.external_force', f%external_force, [3, 0])
    end associate
    associate (w => sc%flow)
      call add_s(items, 'flow.flow_type', w%flow_type)
      call add_r(items, 'flow.shear_rate', w%shear_rate)
      call add_a(items, 'flow.velocity_gradient', reshape(w%velocity_gradient, [9]), [3, 3])
    end associate
    associate (h => sc%hydro)
      call add_s(items, 'hydro.model', h%model)
      call add_i(items, 'hydro.order', int(h%order, i8))
      call add_l(items, 'hydro.lubrication', h%lubrication)
      call add_r(items, 'hydro.eps_lub', h%eps_lub)
      call add_s(items, 'hydro.update', h%update)
      call add_s(items, 'hydro.overlap', h%overlap)
    end associate
    associate (g => sc%integrator)
      call add_s(items, 'integrator.method', g%method)
      call add_r(items, 'integrator.t_end', g%t_end)
      call add_r(items, 'integrator.tolerance', g%tolerance)
      call add_r(items, 'integrator.dt_initial', g%dt_initial)
      call add_r(items, 'integrator.dt_min', g%dt_min)
      call add_r(items, 'integrator.dt_max', g%dt_max)
      call add_i(items, 'integrator.max_steps', g%max_steps)
    end associate
    associate (o => sc%output)
      call add_s(items, 'output.directory', o%directory)
      call add_s(items, 'output.case_name', o%case_name)
      call add_r(items, 'output.frame_interval', o%frame_interval)
      call add_r(items, 'output.progress_interval', o%progress_interval)
      call add_l(items, 'output.diagnostics', o%diagnostics)
      call add_l(items, 'output.stresslet', o%stresslet)
    end associate
  end subroutine scene_items

  !> The scene as namelist text that reads back to the same scene.
  function scene_text(sc) result(text)
    type(scene_t), intent(in) :: sc
    character(len=:), allocatable :: text
    type(scene_item_t), allocatable :: items(:)
    character(len=:), allocatable :: group, current
    character(len=1), parameter :: nl = new_line('a')
    integer :: k, dot
    call scene_items(sc, items)
    text = ''
    current = ''
    do k = 1, size(items)
      dot = index(items(k)%name, '.')
      group = items(k)%name(1:dot - 1)
      if (group /= current) then
        if (len(current) > 0) text = text//'/'//nl
        text = text//'&'//group//nl
        current = group
      end if
      text = text//'  '//trim(items(k)%name(dot + 1:))//' = '//item_value_text(items(k))//nl
    end do
    text = text//'/'//nl
  end function scene_text

  !> The value of an item as namelist text.
  function item_value_text(it, exact) result(text)
    type(scene_item_t), intent(in) :: it
    logical, intent(in), optional :: exact   !< reals in their shortest exact form (messages)
    character(len=:), allocatable :: text
    integer :: k
    logical :: ex
    ex = .false.
    if (present(exact)) ex = exact
    select case (it%kind)
    case (item_string)
      text = "'"//trim(it%s)//"'"
    case (item_integer)
      text = to_str(it%i)
    case (item_logical)
      text = merge('.true. ', '.false.', it%i /= 0)
      text = trim(text)
    case (item_real)
      text = real_text(it%r)
    case (item_real_array)
      text = ''
      do k = 1, size(it%ra)
        if (k > 1) text = text//', '
        text = text//real_text(it%ra(k))
      end do
    case default
      text = '?'
    end select
  contains
    function real_text(x) result(t)
      real(wp), intent(in) :: x
      character(len=:), allocatable :: t
      if (ex) then
        t = to_str_exact(x)
      else
        t = to_str(x)
      end if
    end function real_text
  end function item_value_text

  subroutine push(items, it)
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    type(scene_item_t), intent(in) :: it
    items = [items, it]
  end subroutine push

  subroutine add_s(items, name, value)
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    character(len=*), intent(in) :: name, value
    type(scene_item_t) :: it
    it%name = name
    it%kind = item_string
    it%s = trim(value)
    it%max_len = len(value)
    call push(items, it)
  end subroutine add_s

  subroutine add_i(items, name, value)
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    character(len=*), intent(in) :: name
    integer(i8), intent(in) :: value
    type(scene_item_t) :: it
    it%name = name
    it%kind = item_integer
    it%i = value
    call push(items, it)
  end subroutine add_i

  subroutine add_l(items, name, value)
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    character(len=*), intent(in) :: name
    logical, intent(in) :: value
    type(scene_item_t) :: it
    it%name = name
    it%kind = item_logical
    it%i = merge(1_i8, 0_i8, value)
    call push(items, it)
  end subroutine add_l

  subroutine add_r(items, name, value)
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value
    type(scene_item_t) :: it
    it%name = name
    it%kind = item_real
    it%r = value
    call push(items, it)
  end subroutine add_r

  subroutine add_a(items, name, values, dims)
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: values(:)
    integer, intent(in) :: dims(2)
    type(scene_item_t) :: it
    it%name = name
    it%kind = item_real_array
    it%ra = values
    it%dims = dims
    call push(items, it)
  end subroutine add_a

end module kf_scene_items
