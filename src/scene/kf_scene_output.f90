!> The &output group: files and progress. Owns the parameter type with its defaults, the
!> reading of the group, its part of the item catalogue and its validation.
module kf_scene_output
  use kf_kinds, only: wp
  use kf_strings, only: to_str, to_str_exact
  use kf_error, only: error_t
  use kf_scene_item, only: scene_item_t, add_s, add_r, add_l, path_len
  use kf_scene_check, only: refuse, quoted, check_finite
  implicit none
  private

  ! The allowed values, in the words of the refusals and of the scene reference.
  character(len=*), parameter :: directory_allowed = 'a directory name'
  character(len=*), parameter :: frame_interval_allowed = 'a number > 0'
  character(len=*), parameter :: progress_interval_allowed = 'a number >= 0 (seconds; 0 = every frame)'
  !> The rule for case names: the stem of the case file and of the files named after it (locks,
  !> scenes, ledger entries), so a name is data, never a path: these characters only, the first
  !> a letter, a digit or '_' (no hidden name, no '.' or '..', no option-like '-x'), at most
  !> `case_name_max_len` characters (the longest derived name, '.knotflow.<case>.lock' or
  !> '<case>.h5.damaged.<k>', stays far below the 255 bytes of a file name). The Python tools
  !> apply the same rule (knotflow_tools.names); tests/data/case_names.txt holds the names both
  !> are tested against.
  character(len=*), parameter, public :: case_name_characters = &
    'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-+'
  character(len=*), parameter :: case_name_first = &
    'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_'
  integer, parameter, public :: case_name_max_len = 100

  !> &output: files and progress.
  type, public :: output_params_t
    character(len=path_len) :: directory = 'results'
    character(len=path_len) :: case_name = ''       !< default: derived from the parameters
    real(wp) :: frame_interval = 1.0_wp             !< simulated time between frames
    real(wp) :: progress_interval = 10.0_wp         !< wall seconds between progress lines
    logical :: diagnostics = .true.                 !< strand passages, overlaps, bond strain per step
    logical :: stresslet = .false.                  !< the fibre's stresslet and rheology per frame
  end type output_params_t

  public :: read_output_group, output_items, check_output, case_name_problem

contains

  !> Read the namelist text of &output into `p` (the values `p` holds are the defaults).
  subroutine read_output_group(p, text, ios, msg)
    type(output_params_t), intent(inout) :: p
    character(len=*), intent(in) :: text
    integer, intent(out) :: ios
    character(len=*), intent(inout) :: msg
    character(len=path_len) :: directory, case_name
    real(wp) :: frame_interval, progress_interval
    logical :: diagnostics, stresslet
    namelist /output/ directory, case_name, frame_interval, progress_interval, diagnostics, stresslet
    directory = p%directory; case_name = p%case_name; frame_interval = p%frame_interval
    progress_interval = p%progress_interval; diagnostics = p%diagnostics; stresslet = p%stresslet
    read (text, nml=output, iostat=ios, iomsg=msg)
    p%directory = directory; p%case_name = case_name; p%frame_interval = frame_interval
    p%progress_interval = progress_interval; p%diagnostics = diagnostics; p%stresslet = stresslet
  end subroutine read_output_group

  !> The variables of &output, in namelist order, appended to `items`.
  subroutine output_items(p, items)
    type(output_params_t), intent(in) :: p
    type(scene_item_t), allocatable, intent(inout) :: items(:)
    call add_s(items, 'output.directory', p%directory, directory_allowed, &
      'where the case files go; created if missing, must be writable')
    call add_s(items, 'output.case_name', p%case_name, case_name_allowed(), &
      "the case file's name stem; '': from the swept parameters, e.g. A2.20_orc, or 'case'")
    call add_r(items, 'output.frame_interval', p%frame_interval, frame_interval_allowed, &
      'simulated time between frames')
    call add_r(items, 'output.progress_interval', p%progress_interval, progress_interval_allowed, &
      'wall seconds between progress lines')
    call add_l(items, 'output.diagnostics', p%diagnostics, '.true. or .false.', &
      'run diagnostics at every accepted step: strand passages, overlap episodes, distances, bond strain '// &
      '(docs/case-file.md)')
    call add_l(items, 'output.stresslet', p%stresslet, ".false. unless &flow flow_type = 'shear' with "// &
      "shear_rate /= 0, and with &hydro model = 'multipole' order >= 2", &
      "the fibre's stresslet and its viscosity and normal-stress coefficients at every frame (docs/case-file.md)")
  end subroutine output_items

  !> Check &output on its own (`file`: the scene file named in the messages, '' from code); what
  !> depends on other groups (the stresslet) is checked by validate_scene.
  subroutine check_output(p, file, error)
    type(output_params_t), intent(in) :: p
    character(len=*), intent(in) :: file
    type(error_t), allocatable, intent(out) :: error
    type(scene_item_t), allocatable :: items(:)
    allocate (items(0))
    call output_items(p, items)
    call check_finite(items, file, error)
    if (allocated(error)) return
    if (len_trim(p%directory) == 0) then
      call refuse(error, file, 'output', 'directory', "''", directory_allowed); return
    end if
    if (.not. (p%frame_interval > 0.0_wp)) then
      call refuse(error, file, 'output', 'frame_interval', to_str_exact(p%frame_interval), frame_interval_allowed); return
    end if
    if (.not. (p%progress_interval >= 0.0_wp)) then
      call refuse(error, file, 'output', 'progress_interval', to_str_exact(p%progress_interval), &
        progress_interval_allowed); return
    end if
    if (len_trim(p%case_name) > 0) then
      if (len(case_name_problem(trim(p%case_name))) > 0) then
        call refuse(error, file, 'output', 'case_name', quoted(p%case_name), &
          case_name_allowed()); return
      end if
    end if
  end subroutine check_output

  !> The allowed case names, in the words of the refusals and of the scene reference.
  pure function case_name_allowed() result(text)
    character(len=:), allocatable :: text
    text = 'letters, digits and _ . - + only, starting with a letter, a digit or _, at most '// &
      to_str(case_name_max_len)//' characters'
  end function case_name_allowed

  !> What is wrong with the case name `name` by the rule above, '' when nothing.
  pure function case_name_problem(name) result(problem)
    character(len=*), intent(in) :: name
    character(len=:), allocatable :: problem
    integer :: k
    problem = ''
    if (len(name) == 0) then
      problem = 'an empty name'
    else if (len(name) > case_name_max_len) then
      problem = 'longer than '//to_str(case_name_max_len)//' characters'
    else if (verify(name(1:1), case_name_first) /= 0) then
      problem = 'it starts with '''//name(1:1)//''''
    else
      k = verify(name, case_name_characters)
      if (k > 0) problem = 'the character '''//name(k:k)//''' at position '//to_str(k)
    end if
  end function case_name_problem

end module kf_scene_output
