!> The effective scene as a flat list of typed items named `<group>.<variable>` (kf_scene_item),
!> each group contributing its part: used to echo the scene (as re-readable namelist text), to
!> write it as HDF5 attributes, to match it against a case file, and as the catalogue of
!> allowed variable names per group.
module kf_scene_items
  use kf_scene, only: scene_t
  use kf_scene_item, only: scene_item_t, item_value_text
  use kf_scene_chain, only: chain_items
  use kf_scene_forces, only: forces_items
  use kf_scene_flow, only: flow_items
  use kf_scene_hydro, only: hydro_items
  use kf_scene_integrator, only: integrator_items
  use kf_scene_output, only: output_items
  implicit none
  private

  public :: scene_items, scene_text, group_names

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
    call chain_items(sc%chain, items)
    call forces_items(sc%forces, items)
    call flow_items(sc%flow, items)
    call hydro_items(sc%hydro, items)
    call integrator_items(sc%integrator, items)
    call output_items(sc%output, items)
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

end module kf_scene_items
