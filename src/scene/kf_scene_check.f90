!> The wording of the scene's refusals, shared by the group modules and the factories:
!> "<file>: &group: variable = value is not allowed (what is allowed)", and the lists of allowed
!> names joined from the one array each choice owns.
module kf_scene_check
  use kf_kinds, only: wp
  use kf_strings, only: to_str_exact
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use kf_error, only: error_t, fatal_error
  use kf_scene_item, only: scene_item_t, item_real, item_real_array
  implicit none
  private

  public :: refuse, name_list, quoted, vector_text, check_finite

contains

  !> Set `error` to "<file>: &<group>: <var> = <value> is not allowed (<allowed>)"; without a
  !> file name (a factory called from code) the message starts at "&<group>".
  subroutine refuse(error, file, group, var, value, allowed)
    type(error_t), allocatable, intent(out) :: error
    character(len=*), intent(in) :: file, group, var, value, allowed
    character(len=:), allocatable :: where
    where = '&'//group//': '
    if (len(file) > 0) where = file//': '//where
    call fatal_error(error, where//var//' = '//value//' is not allowed ('//allowed//')')
  end subroutine refuse

  !> Every real of a group's `items` must be finite. Checked first, with ieee_is_finite: the
  !> range tests that follow would trap on NaN in a build with -ffpe-trap=invalid.
  subroutine check_finite(items, file, error)
    type(scene_item_t), intent(in) :: items(:)
    character(len=*), intent(in) :: file
    type(error_t), allocatable, intent(out) :: error
    integer :: k, dot
    do k = 1, size(items)
      dot = index(items(k)%name, '.')
      select case (items(k)%kind)
      case (item_real)
        if (ieee_is_finite(items(k)%r)) cycle
        call refuse(error, file, items(k)%name(1:dot - 1), trim(items(k)%name(dot + 1:)), &
          to_str_exact(items(k)%r), 'a finite number')
        return
      case (item_real_array)
        if (all(ieee_is_finite(items(k)%ra))) cycle
        call refuse(error, file, items(k)%name(1:dot - 1), trim(items(k)%name(dot + 1:)), &
          vector_text(items(k)%ra), 'finite numbers')
        return
      end select
    end do
  end subroutine check_finite

  !> The names as one comma-separated list: 'dopri45, rk4'.
  pure function name_list(names) result(list)
    character(len=*), intent(in) :: names(:)
    character(len=:), allocatable :: list
    integer :: k
    list = ''
    do k = 1, size(names)
      if (k > 1) list = list//', '
      list = list//trim(names(k))
    end do
  end function name_list

  !> 'text' in quotes, trailing blanks removed.
  pure function quoted(s) result(t)
    character(len=*), intent(in) :: s
    character(len=:), allocatable :: t
    t = "'"//trim(s)//"'"
  end function quoted

  !> The components of `v` in their exact shortest form, comma-separated.
  function vector_text(v) result(t)
    real(wp), intent(in) :: v(:)
    character(len=:), allocatable :: t
    integer :: k
    t = ''
    do k = 1, size(v)
      if (k > 1) t = t//', '
      t = t//to_str_exact(v(k))
    end do
  end function vector_text

end module kf_scene_check
