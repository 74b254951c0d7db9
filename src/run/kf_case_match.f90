!> Does an existing case file hold the scene that is requested now? A finished case is skipped
!> and an interrupted one resumed only when it does (DESIGN: "a rerun skips finished cases whose
!> stored scene equals the requested one, resumes interrupted ones, and refuses a mismatch").
!>
!> The comparison is value by value on the effective scene, using the root attributes
!> `<group>.<variable>` that every case file holds (exact float64, int and string values), not
!> the `scene` text. Rules, one per file generation (`schema_version`, kf_case_file):
!> - a variable the file does not record (it was added to the scene after the file was
!>   written, e.g. `hydro.update` or `output.diagnostics`) counts as the value that reproduces
!>   what the older program did: its default, or the value listed in `value_when_absent` where
!>   the default has changed since (`hydro.update`: 'stage', the only behaviour before the
!>   variable existed, while the default may be 'adaptive');
!> - the scene attributes hold effective values (kf_scene_read: resolve_scene). Files written
!>   before the scene was resolved recorded `hydro.eps_lub = -1` (not given: the tolerance) and
!>   `chain.n_beads` = the namelist default 99 also where the shape fixes the count (trefoil,
!>   candy-cane, file): a negative stored eps_lub counts as the file's `integrator.tolerance`,
!>   and `chain.n_beads` is compared with the number of beads the file holds (root `n_beads`);
!> - a file of a newer schema than this program writes is never reused;
!> - an interrupted file without a checkpoint (killed while it was created, perhaps before its
!>   scene attributes were written) holds nothing to reuse and is not compared;
!> - `output.directory` (where the file is found) and `output.progress_interval` (wall-clock
!>   progress lines only) do not take part: they do not change what is computed.
module kf_case_match
  use kf_kinds, only: wp, i4, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_scene, only: scene_t
  use kf_scene_items, only: scene_items
  use kf_scene_item, only: scene_item_t, item_value_text, item_string, item_integer, item_real, &
    item_logical, item_real_array
  use kf_h5, only: h5_file_t, h5_open_file, h5_close_file, h5_attr_exists, h5_read_attr
  use kf_case_file, only: case_schema_version
  use kf_case_verify, only: case_file_status
  use kf_case_checkpoint, only: has_checkpoint
  implicit none
  private

  public :: scene_differences, check_reusable, ignored_in_match

  !> Variables added after files were written, whose older behaviour is not their default:
  !> `absent_names(k)` read as the string `absent_values(k)` when a file does not record it.
  character(len=*), parameter :: absent_names(1) = [character(len=32) :: 'hydro.update']
  character(len=*), parameter :: absent_values(1) = [character(len=32) :: 'stage']

  !> Scene variables that do not take part in the comparison.
  character(len=*), parameter :: ignored(2) = [character(len=32) :: 'output.directory', &
    'output.progress_interval']

contains

  !> Is the scene variable `name` left out of the comparison?
  pure logical function ignored_in_match(name)
    character(len=*), intent(in) :: name
    ignored_in_match = any(ignored == name)
  end function ignored_in_match

  !> The differences between the scene stored in the case file `path` and `sc`, as
  !> '&group: variable = <stored> in the file, <requested> requested' joined by '; ' ('' when
  !> they are equal). `error` is set when the file cannot be read.
  subroutine scene_differences(path, sc, differences, error)
    character(len=*), intent(in) :: path
    type(scene_t), intent(in) :: sc
    character(len=:), allocatable, intent(out) :: differences
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t) :: file
    type(scene_t) :: defaults
    type(scene_item_t), allocatable :: wanted(:), default_items(:)
    type(scene_item_t) :: stored
    integer(i4) :: version
    integer :: k, dot

    differences = ''
    call h5_open_file(file, path, .false., error)
    if (allocated(error)) return
    version = 1
    if (h5_attr_exists(file, '/', 'schema_version')) then
      call h5_read_attr(file, '/', 'schema_version', version, error)
      if (allocated(error)) then
        call h5_close_file(file)
        return
      end if
    end if
    if (version > case_schema_version) then
      differences = 'schema_version = '//to_str(version)//' in the file, this program writes '// &
        to_str(case_schema_version)//' and reuses no newer file'
      call h5_close_file(file)
      return
    end if
    call scene_items(sc, wanted)
    call scene_items(defaults, default_items)
    do k = 1, size(wanted)
      if (ignored_in_match(trim(wanted(k)%name))) cycle
      if (h5_attr_exists(file, '/', trim(wanted(k)%name))) then
        call read_item(file, wanted(k), stored, error)
        if (allocated(error)) exit
      else
        stored = value_when_absent(default_items(k))
      end if
      call as_effective(file, stored, error)
      if (allocated(error)) exit
      if (.not. same_value(stored, wanted(k))) then
        dot = index(wanted(k)%name, '.')
        if (len(differences) > 0) differences = differences//'; '
        differences = differences//'&'//wanted(k)%name(1:dot - 1)//': '// &
          trim(wanted(k)%name(dot + 1:))//' = '//item_value_text(stored, exact=.true.)//' in the file, '// &
          item_value_text(wanted(k), exact=.true.)//' requested'
      end if
    end do
    call h5_close_file(file)
  end subroutine scene_differences

  !> May the case file `path` be reused (skipped when finished, resumed when running) for
  !> `sc`? `error` is set, with a message naming the file, the differing variables and what to
  !> do, when the file is finished or running but holds another scene. Missing, failed and
  !> corrupt files are not reused (the case is recomputed): no error. A finished or running file
  !> whose scene cannot be read is no error either: `unreadable` (when present) says so, and the
  !> case runner moves such a file aside.
  subroutine check_reusable(path, sc, error, unreadable)
    character(len=*), intent(in) :: path
    type(scene_t), intent(in) :: sc
    type(error_t), allocatable, intent(out) :: error
    logical, intent(out), optional :: unreadable
    character(len=:), allocatable :: state, differences
    type(error_t), allocatable :: read_error
    if (present(unreadable)) unreadable = .false.
    call case_file_status(path, state, error)
    if (allocated(error)) return
    if (state /= 'finished' .and. state /= 'running') return
    ! killed while it was created: nothing to reuse (the case runner moves it aside)
    if (state == 'running') then
      if (.not. has_checkpoint(path)) return
    end if
    call scene_differences(path, sc, differences, read_error)
    if (allocated(read_error)) then
      if (present(unreadable)) unreadable = .true.
      return
    end if
    if (len(differences) == 0) return
    if (state == 'running') state = 'interrupted'
    call fatal_error(error, path//' ('//state//') was computed with another scene: '//differences// &
      ': remove or move away that file to recompute it, or use another &output directory')
  end subroutine check_reusable

  !> Read the stored value of the variable `like` names, as an item of the same kind.
  subroutine read_item(file, like, item, error)
    type(h5_file_t), intent(in) :: file
    type(scene_item_t), intent(in) :: like
    type(scene_item_t), intent(out) :: item
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: a2(:, :)
    item%name = like%name
    item%kind = like%kind
    item%dims = like%dims
    select case (like%kind)
    case (item_string)
      call h5_read_attr(file, '/', trim(like%name), item%s, error)
    case (item_integer, item_logical)
      call h5_read_attr(file, '/', trim(like%name), item%i, error)
    case (item_real)
      call h5_read_attr(file, '/', trim(like%name), item%r, error)
    case (item_real_array)
      if (like%dims(2) > 0) then
        call h5_read_attr(file, '/', trim(like%name), a2, error)
        if (.not. allocated(error)) item%ra = reshape(a2, [size(a2)])
      else
        call h5_read_attr(file, '/', trim(like%name), item%ra, error)
      end if
    end select
  end subroutine read_item

  !> The value a file that does not record the variable of `default` was computed with.
  function value_when_absent(default) result(item)
    type(scene_item_t), intent(in) :: default
    type(scene_item_t) :: item
    integer :: k
    item = default
    do k = 1, size(absent_names)
      if (trim(default%name) == trim(absent_names(k)) .and. default%kind == item_string) &
        item%s = trim(absent_values(k))
    end do
  end function value_when_absent


  !> A stored value as the effective value the run used (files from before the scene was
  !> resolved): a negative hydro.eps_lub is the file's integrator.tolerance, chain.n_beads the
  !> file's bead count.
  subroutine as_effective(file, stored, error)
    type(h5_file_t), intent(in) :: file
    type(scene_item_t), intent(inout) :: stored
    type(error_t), allocatable, intent(out) :: error
    integer(i4) :: n
    select case (trim(stored%name))
    case ('hydro.eps_lub')
      if (stored%r < 0.0_wp) then
        if (h5_attr_exists(file, '/', 'integrator.tolerance')) &
          call h5_read_attr(file, '/', 'integrator.tolerance', stored%r, error)
      end if
    case ('chain.n_beads')
      if (h5_attr_exists(file, '/', 'n_beads')) then
        call h5_read_attr(file, '/', 'n_beads', n, error)
        if (.not. allocated(error)) stored%i = n
      end if
    end select
  end subroutine as_effective

  !> Equal values (exact: the attributes hold the values the run used, bit for bit).
  pure logical function same_value(a, b)
    type(scene_item_t), intent(in) :: a, b
    same_value = .false.
    if (a%kind /= b%kind) return
    select case (a%kind)
    case (item_string)
      same_value = trim(a%s) == trim(b%s)
    case (item_integer)
      same_value = a%i == b%i
    case (item_logical)
      same_value = (a%i /= 0) .eqv. (b%i /= 0)
    case (item_real)
      same_value = a%r == b%r
    case (item_real_array)
      if (size(a%ra) == size(b%ra)) same_value = all(a%ra == b%ra)
    end select
  end function same_value

end module kf_case_match
