!> One scene variable as a typed item named `<group>.<variable>`, and how each group module
!> lists its variables (its part of the catalogue): used to echo the scene, to write it as HDF5
!> attributes, to match it against a case file and as the list of allowed variable names.
module kf_scene_item
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str, to_str_exact
  implicit none
  private

  integer, parameter, public :: path_len = 512   !< declared length of file and directory names
  integer, parameter, public :: name_len = 32    !< declared length of the names of choices

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
    !> What values are allowed, in the words of the group's refusals (the scene reference)
    character(len=:), allocatable :: allowed
    !> What the variable means (the scene reference, docs/scenes.md)
    character(len=:), allocatable :: meaning
  end type scene_item_t

  public :: item_value_text, add_s, add_i, add_l, add_r, add_a

contains

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
      ! an apostrophe inside is doubled, as a namelist reads it back ('o''brien.xyz')
      text = "'"//doubled_apostrophes(trim(it%s))//"'"
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

  !> `s` with every apostrophe doubled (the text of a string between apostrophes).
  pure function doubled_apostrophes(s) result(t)
    character(len=*), intent(in) :: s
    character(len=:), allocatable :: t
    integer :: k
    t = ''
    do k = 1, len(s)
      t = t//s(k:k)
      if (s(k:k) == "'") t = t//"'"
    end do
  end function doubled_apostrophes

  !> Attach the scene reference's words (allowed values, meaning) to an item.
  subroutine describe(it, allowed, meaning)
    type(scene_item_t), intent(inout) :: it
    character(len=*), intent(in), optional :: allowed, meaning
    if (present(allowed)) it%allowed = allowed
    if (present(meaning)) it%meaning = meaning
  end subroutine describe

  subroutine push(items, it)
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    type(scene_item_t), intent(in) :: it
    items = [items, it]
  end subroutine push

  !> Append a string variable (its declared length is the longest value allowed).
  subroutine add_s(items, name, value, allowed, meaning)
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    character(len=*), intent(in) :: name, value
    character(len=*), intent(in), optional :: allowed, meaning   !< the scene reference's words
    type(scene_item_t) :: it
    it%name = name
    it%kind = item_string
    it%s = trim(value)
    it%max_len = len(value)
    call describe(it, allowed, meaning)
    call push(items, it)
  end subroutine add_s

  !> Append an integer variable.
  subroutine add_i(items, name, value, allowed, meaning)
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    character(len=*), intent(in) :: name
    integer(i8), intent(in) :: value
    character(len=*), intent(in), optional :: allowed, meaning   !< the scene reference's words
    type(scene_item_t) :: it
    it%name = name
    it%kind = item_integer
    it%i = value
    call describe(it, allowed, meaning)
    call push(items, it)
  end subroutine add_i

  !> Append a logical variable.
  subroutine add_l(items, name, value, allowed, meaning)
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    character(len=*), intent(in) :: name
    logical, intent(in) :: value
    character(len=*), intent(in), optional :: allowed, meaning   !< the scene reference's words
    type(scene_item_t) :: it
    it%name = name
    it%kind = item_logical
    it%i = merge(1_i8, 0_i8, value)
    call describe(it, allowed, meaning)
    call push(items, it)
  end subroutine add_l

  !> Append a real variable.
  subroutine add_r(items, name, value, allowed, meaning)
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value
    character(len=*), intent(in), optional :: allowed, meaning   !< the scene reference's words
    type(scene_item_t) :: it
    it%name = name
    it%kind = item_real
    it%r = value
    call describe(it, allowed, meaning)
    call push(items, it)
  end subroutine add_r

  !> Append a real array variable, flattened in Fortran order, with its shape `dims`.
  subroutine add_a(items, name, values, dims, allowed, meaning)
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: values(:)
    integer, intent(in) :: dims(2)
    character(len=*), intent(in), optional :: allowed, meaning   !< the scene reference's words
    type(scene_item_t) :: it
    it%name = name
    it%kind = item_real_array
    it%ra = values
    it%dims = dims
    call describe(it, allowed, meaning)
    call push(items, it)
  end subroutine add_a

end module kf_scene_item
