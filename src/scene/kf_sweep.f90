!> A sweep: listed parameter values applied to a base scene.
!> Group &sweep (optional): bending_a = list, orientation = list, seed = list, and
!> combine = 'product' (default: every combination of the lists) or 'zip' (case k takes the
!> k-th value of every list; the non-empty lists must have equal lengths), so that a table of
!> cases that is not a product (the study's Table 2) is one sweep.
module kf_sweep
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str, to_str_fixed, to_str_exact
  use kf_error, only: error_t, fatal_error
  use kf_scene, only: scene_t
  use kf_scene_read, only: read_scene, validate_scene, find_group
  use kf_namelist_scan, only: nml_group_t, group_text
  implicit none
  private

  integer, parameter :: max_values = 256
  real(wp), parameter :: unset_real = -huge(1.0_wp)
  integer(i8), parameter :: unset_int = -huge(1_i8)
  integer, parameter :: a_part = 1, o_part = 2, s_part = 3   !< the parts of a case name

  !> The cases of a sweep.
  type, public :: sweep_t
    type(scene_t) :: base                       !< the scene all cases start from
    real(wp), allocatable :: bending_a(:)       !< listed values (empty: the base value only)
    character(len=1), allocatable :: orientation(:)
    integer(i8), allocatable :: seed(:)
    logical :: zip = .false.                    !< combine = 'zip': lists are paired, not multiplied
  contains
    procedure :: n_cases
    procedure :: case_scene
  end type sweep_t

  public :: read_sweep, sweep_reference

contains

  !> The variables of &sweep as Markdown table rows `| variable | default | allowed | meaning |`
  !> (the scene reference, kf_scene_reference; docs/scenes.md).
  function sweep_reference() result(text)
    character(len=:), allocatable :: text
    character(len=1), parameter :: nl = new_line('a')
    character(len=:), allocatable :: most
    most = 'a list of at most '//to_str(max_values)//' values'
    text = '| `bending_a` | not given | '//most//' | values of &forces bending_a |'//nl// &
      '| `orientation` | not given | '//most//" of 'a' to 'e' (trefoil only) | values of &chain orientation |"//nl// &
      '| `seed` | not given | '//most//' | values of &chain seed |'//nl// &
      "| `combine` | `'product'` | product, zip | product: every combination of the lists; zip: case k takes "// &
      'the k-th value of each list (the lists given must have equal lengths) |'//nl
  end function sweep_reference

  !> Read the base scene and the optional &sweep group from `path`.
  subroutine read_sweep(path, sw, error)
    character(len=*), intent(in) :: path
    type(sweep_t), intent(out) :: sw
    type(error_t), allocatable, intent(out) :: error
    type(nml_group_t), allocatable :: groups(:)
    integer :: ig, k, ios
    character(len=512) :: msg
    character(len=:), allocatable :: text
    real(wp) :: bending_a(max_values)
    character(len=1) :: orientation(max_values)
    integer(i8) :: seed(max_values)
    character(len=16) :: combine
    integer :: lengths(3)
    namelist /sweep/ bending_a, orientation, seed, combine

    call read_scene(path, sw%base, error, extra_groups=['sweep'], scanned=groups)
    if (allocated(error)) return
    bending_a = unset_real
    orientation = ' '
    seed = unset_int
    combine = 'product'
    ig = find_group(groups, 'sweep')
    if (ig > 0) then
      do k = 1, size(groups(ig)%items)
        select case (groups(ig)%items(k)%name)
        case ('bending_a', 'orientation', 'seed', 'combine')
        case default
          call fatal_error(error, trim(path)//': &sweep: unknown variable '''// &
            groups(ig)%items(k)%name//''' (allowed: bending_a, orientation, seed, combine)')
          return
        end select
        if (has_empty_item(groups(ig)%items(k)%value)) then
          call fatal_error(error, trim(path)//': &sweep: '//groups(ig)%items(k)%lhs//' = '// &
            groups(ig)%items(k)%value//' has an empty item (allowed: a list of '// &
            trim(merge('quoted letters a-e', 'values            ', groups(ig)%items(k)%name == 'orientation'))// &
            ' separated by commas, none empty: no ",,", no leading comma, no empty quotes)')
          return
        end if
        text = group_text(groups(ig), only=k)
        read (text, nml=sweep, iostat=ios, iomsg=msg)
        if (ios /= 0) then
          call fatal_error(error, trim(path)//': &sweep: '//groups(ig)%items(k)%lhs//' = '// &
            groups(ig)%items(k)%value//' is not valid (expected a list of '// &
            trim(merge('quoted letters a-e', 'values            ', groups(ig)%items(k)%name == 'orientation'))// &
            ', at most 256)')
          return
        end if
      end do
    end if
    sw%bending_a = pack(bending_a, bending_a /= unset_real)
    sw%orientation = pack(orientation, orientation /= ' ')
    sw%seed = pack(seed, seed /= unset_int)
    select case (combine)
    case ('product')
      sw%zip = .false.
    case ('zip')
      sw%zip = .true.
      lengths = [size(sw%bending_a), size(sw%orientation), size(sw%seed)]
      if (any(lengths > 0 .and. lengths /= maxval(lengths))) then
        call fatal_error(error, trim(path)//': &sweep: combine = ''zip'' needs lists of equal length, '// &
          'but bending_a has '//to_str(lengths(1))//' values, orientation '//to_str(lengths(2))// &
          ' and seed '//to_str(lengths(3))//' (empty lists are allowed)')
        return
      end if
    case default
      call fatal_error(error, trim(path)//': &sweep: combine = '''//trim(combine)// &
        ''' is unknown (allowed: product, zip)')
      return
    end select
    if (size(sw%orientation) > 0 .and. sw%base%chain%shape /= 'trefoil') then
      call fatal_error(error, trim(path)//': &sweep: orientation is listed but &chain: shape = '''// &
        trim(sw%base%chain%shape)//''' has no orientations (only trefoil has a-e)')
      return
    end if
    call check_unique_names(path, sw, error)
    if (allocated(error)) return
    ! Every case must be valid: check them all before anything runs.
    block
      type(scene_t) :: sc
      character(len=:), allocatable :: name
      do k = 1, sw%n_cases()
        call sw%case_scene(k, sc, name)
        call validate_scene(sc, error)
        if (allocated(error)) then
          error%message = error%message//' [in &sweep case '//name//']'
          return
        end if
      end do
    end block
  end subroutine read_sweep

  !> Does a list as written hold an empty item: nothing at all, an item between two commas, a
  !> leading comma, or a quoted item of blanks? Fortran's namelist read would take each as
  !> "no value" and the sweep would drop it in silence. (A comma before the closing '/' ends
  !> the list, as in Fortran, and is no item.)
  pure logical function has_empty_item(value) result(empty)
    character(len=*), intent(in) :: value
    integer :: k
    character(len=1) :: quote
    logical :: item_seen, quoted_blank
    empty = .true.
    if (len_trim(value) == 0) return
    quote = ' '
    item_seen = .false.
    quoted_blank = .true.
    do k = 1, len_trim(value)
      if (quote /= ' ') then
        if (value(k:k) == quote) then
          quote = ' '
          if (quoted_blank) return
        else if (value(k:k) /= ' ') then
          quoted_blank = .false.
        end if
      else if (value(k:k) == "'" .or. value(k:k) == '"') then
        quote = value(k:k)
        quoted_blank = .true.
        item_seen = .true.
      else if (value(k:k) == ',') then
        if (.not. item_seen) return
        item_seen = .false.
      else if (value(k:k) /= ' ' .and. value(k:k) /= achar(9)) then
        item_seen = .true.
      end if
    end do
    empty = .not. item_seen
  end function has_empty_item

  !> Every case must have its own name (its own file): refuse a sweep whose cases would share
  !> one, naming the two cases, their values and what to change. Names are kept short and stable
  !> (a case keeps its name when values are added to the sweep), so a clash is refused rather
  !> than resolved by longer names: it comes from values equal to the precision of the name
  !> (bending_a has 2 decimals) or from a value, seed or orientation listed twice.
  subroutine check_unique_names(path, sw, error)
    character(len=*), intent(in) :: path
    type(sweep_t), intent(in) :: sw
    type(error_t), allocatable, intent(out) :: error
    integer :: k, m, n
    n = sw%n_cases()
    if (sw%zip) then
      do m = 2, n
        do k = 1, m - 1
          if (same_part(a_part, k, m) .and. same_part(o_part, k, m) .and. same_part(s_part, k, m)) then
            call clash(k, m)
            return
          end if
        end do
      end do
    else
      call product_clash(size(sw%bending_a), a_part)
      if (.not. allocated(error)) call product_clash(size(sw%orientation), o_part)
      if (.not. allocated(error)) call product_clash(size(sw%seed), s_part)
    end if

  contains

    !> Two entries of one list with the same name part: the first cases that differ only there
    !> (bending_a varies slowest, seed fastest, as in `case_scene`).
    subroutine product_clash(length, which)
      integer, intent(in) :: length, which
      integer :: i, j, no, ns
      no = max(1, size(sw%orientation))
      ns = max(1, size(sw%seed))
      do j = 2, length
        do i = 1, j - 1
          if (part(which, i) /= part(which, j)) cycle
          select case (which)
          case (a_part)
            call clash((i - 1)*no*ns + 1, (j - 1)*no*ns + 1)
          case (o_part)
            call clash((i - 1)*ns + 1, (j - 1)*ns + 1)
          case default
            call clash(i, j)
          end select
          return
        end do
      end do
    end subroutine product_clash

    logical function same_part(which, k1, k2)
      integer, intent(in) :: which, k1, k2
      integer :: length
      select case (which)
      case (a_part)
        length = size(sw%bending_a)
      case (o_part)
        length = size(sw%orientation)
      case default
        length = size(sw%seed)
      end select
      same_part = .true.
      if (length > 0) same_part = part(which, min(k1, length)) == part(which, min(k2, length))
    end function same_part

    !> The name part of entry i of a list ('A2.20', 'orb', 's7').
    function part(which, i) result(text)
      integer, intent(in) :: which, i
      character(len=:), allocatable :: text
      select case (which)
      case (a_part)
        text = 'A'//to_str_fixed(sw%bending_a(i), 2)
      case (o_part)
        text = 'or'//sw%orientation(i)
      case default
        text = 's'//to_str(sw%seed(i))
      end select
    end function part

    subroutine clash(k1, k2)
      integer, intent(in) :: k1, k2
      type(scene_t) :: s1, s2
      character(len=:), allocatable :: n1, n2
      call sw%case_scene(k1, s1, n1)
      call sw%case_scene(k2, s2, n2)
      call fatal_error(error, trim(path)//': &sweep: cases '//to_str(k1)//' ('//case_values(sw, s1)// &
        ') and '//to_str(k2)//' ('//case_values(sw, s2)//') would both be written to case file '''// &
        n1//'.h5'': every case needs its own name (allowed: each value, orientation and seed '// &
        'listed once, bending_a values that differ in their first 2 decimals)')
    end subroutine clash

  end subroutine check_unique_names

  !> The listed parameters of a case, e.g. "bending_a = 2.201, seed = 3".
  function case_values(sw, sc) result(text)
    type(sweep_t), intent(in) :: sw
    type(scene_t), intent(in) :: sc
    character(len=:), allocatable :: text
    text = ''
    if (size(sw%bending_a) > 0) text = 'bending_a = '//to_str_exact(sc%forces%bending_a)
    if (size(sw%orientation) > 0) text = text//merge(', ', '  ', len(text) > 0)//"orientation = '"// &
      sc%chain%orientation//"'"
    if (size(sw%seed) > 0) text = text//merge(', ', '  ', len(text) > 0)//'seed = '//to_str(sc%chain%seed)
    text = trim(adjustl(text))
  end function case_values

  !> Number of cases (1 without a &sweep group).
  pure integer function n_cases(this)
    class(sweep_t), intent(in) :: this
    if (this%zip) then
      n_cases = max(1, size(this%bending_a), size(this%orientation), size(this%seed))
    else
      n_cases = max(1, size(this%bending_a))*max(1, size(this%orientation))*max(1, size(this%seed))
    end if
  end function n_cases

  !> The scene of case `k` (1-based; product: bending_a varies slowest, seed fastest; zip: the
  !> k-th value of each list) and its name,
  !> e.g. "A2.20_orc". Without listed parameters the name is output%case_name or "case".
  subroutine case_scene(this, k, sc, name)
    class(sweep_t), intent(in) :: this
    integer, intent(in) :: k
    type(scene_t), intent(out) :: sc
    character(len=:), allocatable, intent(out) :: name
    integer :: ia, io, is, na, no, ns, r

    na = max(1, size(this%bending_a))
    no = max(1, size(this%orientation))
    ns = max(1, size(this%seed))
    if (this%zip) then
      ia = min(k, na)
      io = min(k, no)
      is = min(k, ns)
    else
      r = k - 1
      is = mod(r, ns) + 1
      r = r/ns
      io = mod(r, no) + 1
      ia = r/no + 1
    end if
    sc = this%base
    name = ''
    if (size(this%bending_a) > 0) then
      sc%forces%bending_a = this%bending_a(ia)
      name = 'A'//to_str_fixed(sc%forces%bending_a, 2)
    end if
    if (size(this%orientation) > 0) then
      sc%chain%orientation = this%orientation(io)
      name = name//merge('_', ' ', len(name) > 0)//'or'//this%orientation(io)
      name = trim(adjustl(name))
    end if
    if (size(this%seed) > 0) then
      sc%chain%seed = this%seed(is)
      name = name//merge('_', ' ', len(name) > 0)//'s'//to_str(this%seed(is))
      name = trim(adjustl(name))
    end if
    if (len_trim(this%base%output%case_name) > 0) then
      if (len(name) > 0) then
        name = trim(this%base%output%case_name)//'_'//name
      else
        name = trim(this%base%output%case_name)
      end if
    else if (len(name) == 0) then
      name = 'case'
    end if
    sc%output%case_name = name
  end subroutine case_scene

end module kf_sweep
