!> The HDF5 case file of one simulation case: the contract between the simulation and the
!> analysis tools. The layout (groups, datasets, attributes, schema versions) is documented
!> once, in docs/case-file.md; keep that page in step with this module.
!>
!> How the layout is written: `create` writes the root attributes and /frames;
!> `enable_diagnostics` and `enable_stresslet` after `create` add /frames/diagnostics and
!> /frames/stresslet; `start_run` appends the segment's /runs entry (a `run_record_t` the run
!> layer fills), and `append_frame` and `finish` given the record rewrite its changing figures
!> in place; `open_resume` restores /runs to the checkpoint it continues from.
!>
!> The file takes plain records (observables, run diagnostics, stresslet of a frame) and writes
!> them as given: it computes nothing (the run layer fills the records, kf_frame_records).
!>
!> Choices made here:
!> - The file is created under its final name (no '<path>.tmp' and rename): the very first
!>   thing written is the root attribute status = 'running', so a file left half-initialised by
!>   a kill says 'running'. Such a file has no /checkpoint yet, `open_resume` then fails and the
!>   caller recreates the case from scratch. A file whose HDF5 structure was damaged by a kill
!>   reports 'corrupt: ...' from `case_file_status` and is recreated as well.
!> - `append_frame` appends to every /frames dataset and flushes, then writes the checkpoint
!>   into the slot the previous frame did not use (digest, then nframes last) and flushes
!>   again; every HDF5 status is checked, and a failed write names the operating system's
!>   reason. A kill or a failed write (full disk) at any moment leaves at least one whole
!>   checkpoint: the previous one in the other slot while a slot is rewritten. /frames may hold
!>   entries beyond it (or some datasets one entry more than others): `open_resume` truncates
!>   all of /frames to the checkpoint's nframes, so no frame is lost or duplicated.
!> - `open_resume` continues from the newest checkpoint that is whole: its digest matches its
!>   parts and it equals the frame it counts (time and positions). When no slot is whole it
!>   fails and the caller moves the file aside (kf_case_runner).
!> - `finish` writes status = 'finished' only after the last frame is flushed, the file closed,
!>   read back and verified (`verify_case_file`: frame counts, checksums, finite positions,
!>   times from 0 to t_end, checkpoint = last frame).
!> - `open_resume` sets the status back to 'running'.
!> - Frame times must increase strictly; `append_frame` rejects a time not after the last one.
!> - Logical scene variables are stored as int32 attributes (1 true, 0 false): HDF5 has no
!>   boolean type (h5py's is an enum), and an integer reads naturally in every tool.
module kf_case_file
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use, intrinsic :: iso_fortran_env, only: int8
  use kf_kinds, only: wp, i4, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_build_info, only: knotflow_version, knotflow_git_hash, knotflow_compiler, knotflow_flags
  use kf_file_type, only: check_regular_file
  use kf_h5, only: h5_file_t, h5_create_file, h5_open_file, h5_close_file, h5_flush, &
    h5_create_group, h5_exists, h5_attr_exists, h5_write_attr, h5_read_attr, h5_write, h5_read, &
    h5_create_extendible, h5_append, h5_set_length, h5_length, h5_real, h5_int32, h5_int64, h5_read_entry, &
    h5_delete, h5_move
  implicit none
  private

  public :: case_file_status, read_frames, read_open_frames, verify_case_file, has_checkpoint
  public :: read_observables

  !> Version of the case file layout written by `create`. 1: files without the attribute
  !> (before it existed); 2: the attribute itself; 3: two checkpoint slots written alternately
  !> (/checkpoint/slot0, /checkpoint/slot1) instead of one /checkpoint rewritten in place;
  !> 4: /runs, one entry per run segment (kept up to date only by a program that knows it: an
  !> older one refuses to continue such a file); 5: /runs/blas (an older program would leave it
  !> shorter than the rest). Raise it with any change a reader must know.
  integer(i4), parameter, public :: case_schema_version = 5

  !> The checkpoint slots of schema 3: the checkpoint of frame count k is written to
  !> slot_groups(mod(k, 2)), so the other slot keeps the previous checkpoint whole while one is
  !> rewritten. Files of schema 1 and 2 have a single checkpoint in `legacy_group`.
  character(len=*), parameter :: slot_groups(0:1) = [character(len=17) :: '/checkpoint/slot0', &
    '/checkpoint/slot1']
  character(len=*), parameter :: legacy_group = '/checkpoint'

  !> The status attribute is stored with at least this many bytes (null-padded), so that
  !> 'running' and 'finished' replace each other in place (a kill while the root object header
  !> is flushed then leaves one or the other, never no status).
  integer, parameter :: status_capacity = 64

  !> The /runs datasets, in the order of `run_record_t`: strings, int32, float64, int64.
  character(len=*), parameter :: runs_group = '/runs'
  !> `start_run` writes the longer list here first and then renames it to /runs, so a kill while
  !> the list grows never leaves it without a whole copy (`restore_runs` reads this one when
  !> /runs cannot be read).
  character(len=*), parameter :: runs_next_group = '/runs_next'
  !> The longest string of /runs read back (commit, start time, host name: host names have at
  !> most 255 bytes).
  integer, parameter :: run_text_capacity = 256
  !> The string datasets come first (`run_texts` numbers them); 'blas' may be missing (schema 4).
  integer, parameter :: run_string_sets = 4, run_blas_set = 4
  character(len=*), parameter :: run_sets(12) = [character(len=12) :: 'commit', 'started', 'host', 'blas', &
    'ranks', 'threads', 't_start', 't_end', 'steps', 'wall_seconds', 'load_start', 'load_mean']
  !> What a file without /runs/blas (schema 4) reads as.
  character(len=*), parameter :: blas_unrecorded = 'unknown'

  integer, parameter :: kind_str = 1, kind_i4 = 2, kind_i8 = 3, kind_real = 4, kind_real1 = 5, &
    kind_real2 = 6

  !> One named attribute value of any of the supported kinds.
  type :: attribute_t
    character(len=:), allocatable :: name
    integer :: kind = 0
    character(len=:), allocatable :: str
    integer(i4) :: ival = 0
    integer(i8) :: lval = 0
    real(wp) :: rval = 0.0_wp
    real(wp), allocatable :: r1(:), r2(:, :)
  end type attribute_t

  !> A list of named values (e.g. every effective scene variable as '<group>.<variable>')
  !> collected by the caller and written as root attributes by `case_file_t%create`.
  type, public :: attribute_list_t
    private
    type(attribute_t), allocatable :: items(:)
    integer :: n = 0
  contains
    !> Add (name, value): character string, int32, int64, real(wp), logical (stored as int32
    !> 1/0), 1-D or 2-D real(wp) array.
    generic :: add => add_str, add_i4, add_i8, add_real, add_logical, add_real1, add_real2
    procedure :: count => list_count
    procedure, private :: add_str, add_i4, add_i8, add_real, add_logical, add_real1, add_real2
    procedure, private :: push
  end type attribute_list_t

  !> The shape observables of one frame (/frames/observables).
  type, public :: observables_record_t
    real(wp) :: rg = 0.0_wp, a = 0.0_wp, b = 0.0_wp, c = 0.0_wp, theta = 0.0_wp, phi = 0.0_wp
    integer :: close_pairs = 0
  end type observables_record_t

  !> The run diagnostics after a frame: its values (/frames/diagnostics), the run totals (root
  !> attributes diagnostics.*) and the monitor's state (checkpoint).
  type, public :: diagnostics_record_t
    integer(i8) :: strand_passages = 0, overlap_episodes = 0   !< cumulative since t = 0
    integer :: overlapping_pairs = 0                           !< of the frame's configuration
    real(wp) :: min_distance = 0.0_wp, max_bond_strain = 0.0_wp !< of the frame's configuration
    real(wp) :: first_passage_time = -1.0_wp                    !< run totals from here on
    real(wp) :: overlap_mean_duration = 0.0_wp, overlap_max_duration = 0.0_wp
    integer :: max_overlapping_pairs = 0
    real(wp) :: run_min_distance = 0.0_wp, run_max_bond_strain = 0.0_wp
    integer(i8), allocatable :: state_counters(:)               !< the monitor's state
    real(wp), allocatable :: state_values(:), state_ongoing(:, :)
  end type diagnostics_record_t

  !> The fibre's stresslet at one frame (/frames/stresslet).
  type, public :: stresslet_record_t
    real(wp) :: hydrodynamic(3, 3) = 0.0_wp, elastic(3, 3) = 0.0_wp
    real(wp) :: viscosity = 0.0_wp, psi1 = 0.0_wp, psi2 = 0.0_wp
  end type stresslet_record_t

  !> One run segment of the case (the first start or a resume): an entry of /runs, filled by
  !> the run layer (kf_run_segment).
  type, public :: run_record_t
    character(len=:), allocatable :: commit    !< git hash the program was built from
    character(len=:), allocatable :: started   !< start of the segment, ISO 8601 UTC
    character(len=:), allocatable :: host      !< host name
    character(len=:), allocatable :: blas      !< BLAS library and kernels (kf_blas_threads' blas_library)
    integer :: ranks = 0, threads = 0          !< MPI ranks of the sweep, BLAS threads of the rank
    real(wp) :: t_start = 0.0_wp, t_end = 0.0_wp   !< model time at the start, newest reached
    integer(i8) :: steps = 0                   !< steps taken in the segment
    real(wp) :: wall_seconds = 0.0_wp          !< wall time of the segment so far
    real(wp) :: load_start = 0.0_wp, load_mean = 0.0_wp   !< 1-minute load average (NaN: unknown)
  end type run_record_t

  !> The state of the time stepper in the checkpoint: the plain arrays of its `get_state` and
  !> the name of its method. Unallocated components: no stepper state.
  type, public :: stepper_checkpoint_t
    character(len=:), allocatable :: name
    real(wp), allocatable :: reals(:)
    integer(i8), allocatable :: ints(:)
  end type stepper_checkpoint_t

  !> One checkpoint as read back from a file: the state after frame `nframes`.
  type :: checkpoint_t
    integer(i8) :: nframes = 0, steps = 0, rejected = 0
    real(wp) :: t = 0.0_wp, dt = 0.0_wp
    real(wp), allocatable :: r(:, :)
    type(stepper_checkpoint_t) :: stepper
    integer(i8), allocatable :: counters(:)         !< the caller's run counters (or none)
    integer(i8), allocatable :: diag_counters(:)    !< run diagnostics state (or none)
    real(wp), allocatable :: diag_values(:), diag_ongoing(:, :)
    integer(i8), allocatable :: run_counts(:)       !< [/runs entries, steps of the segment] (or none)
    real(wp), allocatable :: run_figures(:)         !< [t_end, wall_seconds, load_mean] of the segment
  end type checkpoint_t

  !> An open case file being written by the simulation.
  type, public :: case_file_t
    private
    type(h5_file_t) :: file
    integer :: n_beads = 0
    integer(i8) :: nframes = 0
    real(wp) :: last_time = 0.0_wp
    logical :: diagnostics = .false.     !< the file has /frames/diagnostics
    logical :: stresslet = .false.       !< the file has /frames/stresslet
    real(wp) :: flushed_time = -1.0_wp   !< time of the last checkpoint flushed (-1: none)
    type(checkpoint_t) :: resumed         !< the checkpoint `open_resume` continued from
    type(run_record_t), allocatable :: runs(:)   !< the /runs entries (the last: this segment)
    logical :: run_started = .false.     !< `start_run` gave this segment's entry
  contains
    !> create(path, case_name, n_beads, scene_text, [scene_attrs,] rotation, error): the
    !> scene attributes can also be written afterwards with `write_attribute`.
    generic :: create => create_with_attrs, create_plain
    procedure, private :: create_with_attrs, create_plain
    procedure :: scene_text => file_scene_text
    procedure :: open_resume
    procedure :: append_frame
    procedure :: set_status
    procedure :: finish
    procedure :: close => close_case
    procedure :: is_open => case_is_open
    procedure :: frame_count
    procedure :: checkpoint_time
    procedure :: enable_diagnostics
    procedure :: has_diagnostics
    procedure :: resumed_diagnostics
    procedure :: enable_stresslet
    procedure :: has_stresslet
    procedure :: read_counter
    procedure :: start_run
    !> Write one more root attribute (same kinds as `attribute_list_t%add`).
    generic :: write_attribute => write_attr_str, write_attr_i4, write_attr_i8, write_attr_real, &
      write_attr_logical, write_attr_real1, write_attr_real2
    procedure, private :: write_attr_str, write_attr_i4, write_attr_i8, write_attr_real, &
      write_attr_logical, write_attr_real1, write_attr_real2
  end type case_file_t

  !> The /frames datasets of one-value-per-frame kind real.
  character(len=*), parameter :: frame_real_sets(8) = [character(len=32) :: '/frames/time', &
    '/frames/observables/rg', '/frames/observables/a', '/frames/observables/b', &
    '/frames/observables/c', '/frames/observables/theta', '/frames/observables/phi', &
    '/frames/integrator/dt']

  !> The /frames/diagnostics datasets and their element kinds.
  character(len=*), parameter :: diag_sets(5) = [character(len=40) :: &
    '/frames/diagnostics/strand_passages', '/frames/diagnostics/overlapping_pairs', &
    '/frames/diagnostics/overlap_episodes', '/frames/diagnostics/min_distance', &
    '/frames/diagnostics/max_bond_strain']
  integer, parameter :: diag_kinds(5) = [h5_int64, h5_int32, h5_int64, h5_real, h5_real]

  !> The /frames/stresslet datasets: the first two hold a 3 x 3 tensor per frame, the others a
  !> number.
  character(len=*), parameter :: stresslet_sets(5) = [character(len=40) :: &
    '/frames/stresslet/hydrodynamic', '/frames/stresslet/elastic', '/frames/stresslet/viscosity', &
    '/frames/stresslet/psi1', '/frames/stresslet/psi2']
  integer, parameter :: stresslet_tensors = 2

contains

  ! ---------------------------------------------------------------- attribute list

  subroutine push(this, item)
    class(attribute_list_t), intent(inout) :: this
    type(attribute_t), intent(in) :: item
    type(attribute_t), allocatable :: tmp(:)
    if (.not. allocated(this%items)) allocate (this%items(16))
    if (this%n == size(this%items)) then
      allocate (tmp(2*this%n))
      tmp(1:this%n) = this%items(1:this%n)
      call move_alloc(tmp, this%items)
    end if
    this%n = this%n + 1
    this%items(this%n) = item
  end subroutine push

  subroutine add_str(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name, value
    type(attribute_t) :: item
    item%name = name
    item%kind = kind_str
    item%str = value
    call this%push(item)
  end subroutine add_str

  subroutine add_i4(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer(i4), intent(in) :: value
    type(attribute_t) :: item
    item%name = name
    item%kind = kind_i4
    item%ival = value
    call this%push(item)
  end subroutine add_i4

  subroutine add_i8(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer(i8), intent(in) :: value
    type(attribute_t) :: item
    item%name = name
    item%kind = kind_i8
    item%lval = value
    call this%push(item)
  end subroutine add_i8

  subroutine add_real(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value
    type(attribute_t) :: item
    item%name = name
    item%kind = kind_real
    item%rval = value
    call this%push(item)
  end subroutine add_real

  subroutine add_logical(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    logical, intent(in) :: value
    call this%add_i4(name, merge(1_i4, 0_i4, value))
  end subroutine add_logical

  subroutine add_real1(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value(:)
    type(attribute_t) :: item
    item%name = name
    item%kind = kind_real1
    item%r1 = value
    call this%push(item)
  end subroutine add_real1

  subroutine add_real2(this, name, value)
    class(attribute_list_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value(:, :)
    type(attribute_t) :: item
    item%name = name
    item%kind = kind_real2
    item%r2 = value
    call this%push(item)
  end subroutine add_real2

  !> Number of entries in the list.
  pure integer function list_count(this)
    class(attribute_list_t), intent(in) :: this
    list_count = this%n
  end function list_count

  ! ---------------------------------------------------------------- creating and writing

  !> Create the case file `path` (replacing any old file) for a chain of `n_beads` beads:
  !> status 'running' first, then build information, case name, the scene as namelist text,
  !> every entry of `scene_attrs`, the initial random rotation (identity if none) and the
  !> empty extendible /frames datasets. The file is flushed before returning.
  subroutine create_with_attrs(this, path, case_name, n_beads, scene_text, scene_attrs, rotation, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: path, case_name, scene_text
    integer, intent(in) :: n_beads
    type(attribute_list_t), intent(in) :: scene_attrs
    real(wp), intent(in) :: rotation(3, 3)
    type(error_t), allocatable, intent(out) :: error
    integer :: i
    call this%close()
    if (n_beads < 1) then
      call fatal_error(error, "case file '"//path//"': n_beads must be >= 1")
      return
    end if
    call h5_create_file(this%file, path, error)
    if (allocated(error)) return
    this%n_beads = n_beads
    this%nframes = 0
    this%diagnostics = .false.
    this%stresslet = .false.
    this%flushed_time = -1.0_wp
    this%run_started = .false.
    if (allocated(this%runs)) deallocate (this%runs)
    allocate (this%runs(0))
    call h5_write_attr(this%file, '/', 'status', status_value('running'), error)
    if (allocated(error)) return
    call h5_write_attr(this%file, '/', 'schema_version', case_schema_version, error)
    if (.not. allocated(error)) call h5_write_attr(this%file, '/', 'knotflow_version', knotflow_version, error)
    if (.not. allocated(error)) call h5_write_attr(this%file, '/', 'git_hash', knotflow_git_hash, error)
    if (.not. allocated(error)) call h5_write_attr(this%file, '/', 'compiler', knotflow_compiler, error)
    if (.not. allocated(error)) call h5_write_attr(this%file, '/', 'compiler_flags', knotflow_flags, error)
    if (.not. allocated(error)) call h5_write_attr(this%file, '/', 'case_name', case_name, error)
    if (.not. allocated(error)) call h5_write_attr(this%file, '/', 'n_beads', int(n_beads, i4), error)
    if (.not. allocated(error)) call h5_write_attr(this%file, '/', 'scene', scene_text, error)
    if (allocated(error)) return
    do i = 1, scene_attrs%n
      call write_item(this%file, scene_attrs%items(i), error)
      if (allocated(error)) return
    end do
    call h5_write_attr(this%file, '/', 'chain.rotation', rotation, error)
    if (allocated(error)) return

    call h5_create_extendible(this%file, '/frames/positions', h5_real, [3, n_beads], error, chunk=16)
    if (allocated(error)) return
    do i = 1, size(frame_real_sets)
      call h5_create_extendible(this%file, trim(frame_real_sets(i)), h5_real, [integer ::], error)
      if (allocated(error)) return
    end do
    call h5_create_extendible(this%file, '/frames/observables/close_pairs', h5_int32, [integer ::], error)
    if (.not. allocated(error)) &
      call h5_create_extendible(this%file, '/frames/integrator/steps', h5_int64, [integer ::], error)
    if (.not. allocated(error)) &
      call h5_create_extendible(this%file, '/frames/integrator/rejected', h5_int64, [integer ::], error)
    if (allocated(error)) return
    call h5_flush(this%file, error)
  end subroutine create_with_attrs

  !> `create` without an attribute list (the caller writes them with `write_attribute`).
  subroutine create_plain(this, path, case_name, n_beads, scene_text, rotation, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: path, case_name, scene_text
    integer, intent(in) :: n_beads
    real(wp), intent(in) :: rotation(3, 3)
    type(error_t), allocatable, intent(out) :: error
    type(attribute_list_t) :: none
    call this%create_with_attrs(path, case_name, n_beads, scene_text, none, rotation, error)
  end subroutine create_plain

  !> The scene text stored in the open file ('' when it cannot be read).
  function file_scene_text(this) result(text)
    class(case_file_t), intent(in) :: this
    character(len=:), allocatable :: text
    type(error_t), allocatable :: error
    call h5_read_attr(this%file, '/', 'scene', text, error)
    if (allocated(error)) text = ''
  end function file_scene_text

  !> Create the (empty) /frames/diagnostics datasets of a file just created, before its first
  !> frame: from then on every `append_frame` must pass the run diagnostics.
  subroutine enable_diagnostics(this, error)
    class(case_file_t), intent(inout) :: this
    type(error_t), allocatable, intent(out) :: error
    integer :: i
    if (.not. this%file%is_open()) then
      call fatal_error(error, 'case file: enable_diagnostics on a file that is not open')
      return
    end if
    if (this%nframes > 0) then
      call fatal_error(error, "case file '"//this%file%name()//"': diagnostics must be enabled before the first frame")
      return
    end if
    do i = 1, size(diag_sets)
      if (h5_exists(this%file, trim(diag_sets(i)))) cycle
      call h5_create_extendible(this%file, trim(diag_sets(i)), diag_kinds(i), [integer ::], error)
      if (allocated(error)) return
    end do
    this%diagnostics = .true.
    call h5_flush(this%file, error)
  end subroutine enable_diagnostics

  !> Create the (empty) /frames/stresslet datasets of a file just created, before its first
  !> frame: from then on every `append_frame` must pass the fibre's stresslet.
  subroutine enable_stresslet(this, error)
    class(case_file_t), intent(inout) :: this
    type(error_t), allocatable, intent(out) :: error
    integer :: i
    if (.not. this%file%is_open()) then
      call fatal_error(error, 'case file: enable_stresslet on a file that is not open')
      return
    end if
    if (this%nframes > 0) then
      call fatal_error(error, "case file '"//this%file%name()//"': the stresslet must be enabled before the first frame")
      return
    end if
    do i = 1, size(stresslet_sets)
      if (h5_exists(this%file, trim(stresslet_sets(i)))) cycle
      if (i <= stresslet_tensors) then
        call h5_create_extendible(this%file, trim(stresslet_sets(i)), h5_real, [3, 3], error)
      else
        call h5_create_extendible(this%file, trim(stresslet_sets(i)), h5_real, [integer ::], error)
      end if
      if (allocated(error)) return
    end do
    this%stresslet = .true.
    call h5_flush(this%file, error)
  end subroutine enable_stresslet

  !> Does the open file hold the fibre's stresslet (/frames/stresslet)?
  pure logical function has_stresslet(this)
    class(case_file_t), intent(in) :: this
    has_stresslet = this%stresslet
  end function has_stresslet

  !> Does the open file hold run diagnostics (/frames/diagnostics)?
  pure logical function has_diagnostics(this)
    class(case_file_t), intent(in) :: this
    has_diagnostics = this%diagnostics
  end function has_diagnostics

  !> The run diagnostics' state in the checkpoint (its `diagnostics` group) that `open_resume`
  !> continued from, as the monitor's `get_state` gave it.
  subroutine resumed_diagnostics(this, counters, values, ongoing, error)
    class(case_file_t), intent(in) :: this
    integer(i8), allocatable, intent(out) :: counters(:)
    real(wp), allocatable, intent(out) :: values(:), ongoing(:, :)
    type(error_t), allocatable, intent(out) :: error
    if (.not. (this%diagnostics .and. allocated(this%resumed%diag_counters))) then
      call fatal_error(error, "case file '"//this%file%name()//"' has no diagnostics checkpoint")
      return
    end if
    counters = this%resumed%diag_counters
    values = this%resumed%diag_values
    ongoing = this%resumed%diag_ongoing
  end subroutine resumed_diagnostics

  !> Append frame (t, r(3, N)) with its shape observables and cumulative integrator counts,
  !> rewrite /checkpoint with this state and flush the file. A file with diagnostics
  !> (`enable_diagnostics`) needs `diagnostics`, the run diagnostics after the frame's last step:
  !> its per-frame values, run totals (root attributes) and state (checkpoint) are written too.
  !> `stepper`, the time stepper's state after the frame's last step, goes to the checkpoint's
  !> `stepper` group; `counters`, any run counters of the caller (e.g. the hydrodynamic model's
  !> work), to its `counters` dataset (`open_resume` returns both).
  !> The checkpoint is written to the slot the previous frame did not use (schema 3), so a kill
  !> or a failed write while it is written leaves the previous checkpoint whole. A file with the
  !> stresslet (`enable_stresslet`) needs `stresslet`, the fibre's stresslet at the frame.
  !> `run`, the record of the run segment after the frame (after `start_run`), replaces the
  !> segment's /runs entry and goes into the checkpoint.
  subroutine append_frame(this, t, r, shape, steps, rejected, dt, error, diagnostics, stepper, counters, &
                          stresslet, run)
    class(case_file_t), intent(inout) :: this
    real(wp), intent(in) :: t
    real(wp), intent(in) :: r(:, :)
    type(observables_record_t), intent(in) :: shape
    integer(i8), intent(in) :: steps, rejected
    real(wp), intent(in) :: dt
    type(error_t), allocatable, intent(out) :: error
    type(diagnostics_record_t), intent(in), optional :: diagnostics
    type(stepper_checkpoint_t), intent(in), optional :: stepper
    integer(i8), intent(in), optional :: counters(:)
    type(stresslet_record_t), intent(in), optional :: stresslet
    type(run_record_t), intent(in), optional :: run
    real(wp), allocatable :: rc(:, :)
    type(checkpoint_t) :: ck
    if (.not. this%file%is_open()) then
      call fatal_error(error, 'case file: append_frame on a file that is not open')
      return
    end if
    if (this%diagnostics .and. .not. present(diagnostics)) then
      call fatal_error(error, "case file '"//this%file%name()//"': append_frame needs the run diagnostics")
      return
    else if (present(diagnostics) .and. .not. this%diagnostics) then
      call fatal_error(error, "case file '"//this%file%name()//"': append_frame got diagnostics "// &
        'but the file has none (enable_diagnostics)')
      return
    end if
    if (this%stresslet .and. .not. present(stresslet)) then
      call fatal_error(error, "case file '"//this%file%name()//"': append_frame needs the stresslet")
      return
    else if (present(stresslet) .and. .not. this%stresslet) then
      call fatal_error(error, "case file '"//this%file%name()//"': append_frame got a stresslet "// &
        'but the file has none (enable_stresslet)')
      return
    end if
    if (size(r, 1) /= 3 .or. size(r, 2) /= this%n_beads) then
      call fatal_error(error, "case file '"//this%file%name()//"': frame positions do not have shape (3, n_beads)")
      return
    end if
    if (present(run) .and. .not. this%run_started) then
      call fatal_error(error, "case file '"//this%file%name()//"': append_frame got a run record before start_run")
      return
    end if
    if (this%nframes > 0 .and. .not. t > this%last_time) then
      call fatal_error(error, "case file '"//this%file%name()//"': frame time does not increase")
      return
    end if
    if (present(diagnostics)) then
      if (.not. (allocated(diagnostics%state_counters) .and. allocated(diagnostics%state_values) .and. &
                 allocated(diagnostics%state_ongoing))) then
        call fatal_error(error, "case file '"//this%file%name()//"': append_frame got run diagnostics without "// &
          'their state')
        return
      end if
    end if
    if (present(stepper)) then
      if (.not. (allocated(stepper%name) .and. allocated(stepper%reals) .and. allocated(stepper%ints))) then
        call fatal_error(error, "case file '"//this%file%name()//"': append_frame got an incomplete stepper state")
        return
      end if
    end if
    rc = r
    call h5_append(this%file, '/frames/time', t, error)
    if (.not. allocated(error)) call h5_append(this%file, '/frames/positions', rc, error)
    if (.not. allocated(error)) call h5_append(this%file, '/frames/observables/rg', shape%rg, error)
    if (.not. allocated(error)) call h5_append(this%file, '/frames/observables/a', shape%a, error)
    if (.not. allocated(error)) call h5_append(this%file, '/frames/observables/b', shape%b, error)
    if (.not. allocated(error)) call h5_append(this%file, '/frames/observables/c', shape%c, error)
    if (.not. allocated(error)) call h5_append(this%file, '/frames/observables/theta', shape%theta, error)
    if (.not. allocated(error)) call h5_append(this%file, '/frames/observables/phi', shape%phi, error)
    if (.not. allocated(error)) call h5_append(this%file, '/frames/observables/close_pairs', &
      int(shape%close_pairs, i4), error)
    if (.not. allocated(error)) call h5_append(this%file, '/frames/integrator/steps', steps, error)
    if (.not. allocated(error)) call h5_append(this%file, '/frames/integrator/rejected', rejected, error)
    if (.not. allocated(error)) call h5_append(this%file, '/frames/integrator/dt', dt, error)
    if (allocated(error)) return
    if (present(diagnostics)) then
      call write_diagnostics_frame(this%file, diagnostics, error)
      if (allocated(error)) return
    end if
    if (present(stresslet)) then
      call write_stresslet_frame(this%file, stresslet, error)
      if (allocated(error)) return
    end if
    ! The frame reaches the disk before the checkpoint is touched: a write that fails here (full
    ! disk) leaves the previous checkpoint as it was, and a resume drops the partial frame.
    call h5_flush(this%file, error)
    if (allocated(error)) return
    this%nframes = this%nframes + 1
    this%last_time = t
    if (present(diagnostics)) then
      call write_diagnostics_totals(this%file, diagnostics, error)
      if (allocated(error)) return
      ck%diag_counters = diagnostics%state_counters
      ck%diag_values = diagnostics%state_values
      ck%diag_ongoing = diagnostics%state_ongoing
      call pad_columns(ck%diag_ongoing)
    end if
    ck%nframes = this%nframes
    ck%t = t
    ck%r = rc
    ck%dt = dt
    ck%steps = steps
    ck%rejected = rejected
    if (present(stepper)) ck%stepper = stepper
    if (present(counters)) ck%counters = counters
    if (present(run)) then
      this%runs(size(this%runs)) = run
      ck%run_counts = [size(this%runs, kind=i8), run%steps]
      ck%run_figures = [run%t_end, run%wall_seconds, run%load_mean]
    end if
    ! The first checkpoint goes to both slots, so that their structure exists before any frame
    ! but the first could be lost.
    if (this%nframes == 1) call write_checkpoint(this%file, trim(slot_groups(0)), ck, error)
    if (.not. allocated(error)) call write_checkpoint(this%file, trim(slot_groups(mod(this%nframes, 2_i8))), ck, error)
    if (.not. allocated(error) .and. present(run)) call write_run_figures(this%file, runs_group, this%runs, error)
    if (allocated(error)) return
    call h5_flush(this%file, error)
    if (.not. allocated(error)) this%flushed_time = t
  end subroutine append_frame

  !> Per-frame values of the run diagnostics.
  subroutine write_diagnostics_frame(file, diag, error)
    type(h5_file_t), intent(in) :: file
    type(diagnostics_record_t), intent(in) :: diag
    type(error_t), allocatable, intent(out) :: error
    call h5_append(file, '/frames/diagnostics/strand_passages', diag%strand_passages, error)
    if (.not. allocated(error)) call h5_append(file, '/frames/diagnostics/overlapping_pairs', &
      int(diag%overlapping_pairs, i4), error)
    if (.not. allocated(error)) call h5_append(file, '/frames/diagnostics/overlap_episodes', diag%overlap_episodes, error)
    if (.not. allocated(error)) call h5_append(file, '/frames/diagnostics/min_distance', diag%min_distance, error)
    if (.not. allocated(error)) call h5_append(file, '/frames/diagnostics/max_bond_strain', diag%max_bond_strain, error)
  end subroutine write_diagnostics_frame

  !> Per-frame values of the fibre's stresslet.
  subroutine write_stresslet_frame(file, st, error)
    type(h5_file_t), intent(in) :: file
    type(stresslet_record_t), intent(in) :: st
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: a(3, 3)
    a = st%hydrodynamic
    call h5_append(file, trim(stresslet_sets(1)), a, error)
    a = st%elastic
    if (.not. allocated(error)) call h5_append(file, trim(stresslet_sets(2)), a, error)
    if (.not. allocated(error)) call h5_append(file, trim(stresslet_sets(3)), st%viscosity, error)
    if (.not. allocated(error)) call h5_append(file, trim(stresslet_sets(4)), st%psi1, error)
    if (.not. allocated(error)) call h5_append(file, trim(stresslet_sets(5)), st%psi2, error)
  end subroutine write_stresslet_frame

  ! ---------------------------------------------------------------- run segments (/runs)

  !> Begin a run segment (after `create`, or after `open_resume`): `run` is appended to /runs
  !> (a file without /runs gets it) and the file marked with this schema version; flushed.
  !> Later `append_frame` and `finish` calls given the segment's record update its entry.
  !> The longer list is written whole to /runs_next and flushed, then /runs is deleted and
  !> /runs_next renamed to it: a kill at any point leaves one whole list (`restore_runs`).
  subroutine start_run(this, run, error)
    class(case_file_t), intent(inout) :: this
    type(run_record_t), intent(in) :: run
    type(error_t), allocatable, intent(out) :: error
    type(run_record_t), allocatable :: longer(:)
    integer :: n
    if (.not. this%file%is_open()) then
      call fatal_error(error, 'case file: start_run on a file that is not open')
      return
    end if
    if (this%run_started) then
      call fatal_error(error, "case file '"//this%file%name()//"': start_run called twice")
      return
    end if
    if (.not. allocated(this%runs)) allocate (this%runs(0))
    n = size(this%runs)
    allocate (longer(n + 1))
    longer(1:n) = this%runs
    longer(n + 1) = run
    call move_alloc(longer, this%runs)
    call h5_delete(this%file, runs_next_group, error)   ! a part written by a killed start_run
    if (.not. allocated(error)) call write_runs(this%file, runs_next_group, this%runs, error)
    if (.not. allocated(error)) call h5_flush(this%file, error)
    if (.not. allocated(error)) call h5_delete(this%file, runs_group, error)
    if (.not. allocated(error)) call h5_move(this%file, runs_next_group, runs_group, error)
    if (.not. allocated(error)) call h5_write_attr(this%file, '/', 'schema_version', case_schema_version, error)
    if (.not. allocated(error)) call h5_flush(this%file, error)
    if (.not. allocated(error)) this%run_started = .true.
  end subroutine start_run

  !> Every run dataset of `group` (/runs or /runs_next), `runs` in full (a dataset of another
  !> length is replaced).
  subroutine write_runs(file, group, runs, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: group
    type(run_record_t), intent(in) :: runs(:)
    type(error_t), allocatable, intent(out) :: error
    integer :: k
    do k = 1, run_string_sets
      call h5_write(file, group//'/'//trim(run_sets(k)), run_texts(runs, k), error)
      if (allocated(error)) return
    end do
    call h5_write(file, group//'/ranks', int(runs%ranks, i4), error)
    if (.not. allocated(error)) call h5_write(file, group//'/threads', int(runs%threads, i4), error)
    if (.not. allocated(error)) call h5_write(file, group//'/t_start', runs%t_start, error)
    if (.not. allocated(error)) call h5_write(file, group//'/load_start', runs%load_start, error)
    if (.not. allocated(error)) call write_run_figures(file, group, runs, error)
  end subroutine write_runs

  !> The run datasets of `group` that change during a segment (t_end, steps, wall_seconds,
  !> load_mean), rewritten in place.
  subroutine write_run_figures(file, group, runs, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: group
    type(run_record_t), intent(in) :: runs(:)
    type(error_t), allocatable, intent(out) :: error
    call h5_write(file, group//'/t_end', runs%t_end, error)
    if (.not. allocated(error)) call h5_write(file, group//'/steps', runs%steps, error)
    if (.not. allocated(error)) call h5_write(file, group//'/wall_seconds', runs%wall_seconds, error)
    if (.not. allocated(error)) call h5_write(file, group//'/load_mean', runs%load_mean, error)
  end subroutine write_run_figures

  !> The string field `field` (1 commit, 2 started, 3 host, 4 blas) of every entry ('' if not set).
  pure function run_texts(runs, field) result(text)
    type(run_record_t), intent(in) :: runs(:)
    integer, intent(in) :: field
    character(len=:), allocatable :: text(:)
    integer :: k, n
    n = 1
    do k = 1, size(runs)
      n = max(n, len(run_text(runs(k), field)))
    end do
    allocate (character(len=n) :: text(size(runs)))
    do k = 1, size(runs)
      text(k) = run_text(runs(k), field)
    end do
  end function run_texts

  pure function run_text(run, field) result(text)
    type(run_record_t), intent(in) :: run
    integer, intent(in) :: field
    character(len=:), allocatable :: text
    text = ''
    select case (field)
    case (1)
      if (allocated(run%commit)) text = run%commit
    case (2)
      if (allocated(run%started)) text = run%started
    case (3)
      if (allocated(run%host)) text = run%host
    case (run_blas_set)
      if (allocated(run%blas)) text = run%blas
    end select
  end function run_text

  !> Read the run list of `group` (/runs or /runs_next): the entries as far as every dataset
  !> holds them, at most `limit` (`equal`: all datasets have the same length). The error names
  !> the missing or unreadable dataset; a file without /runs/blas (schema 4) reads as
  !> `blas_unrecorded`.
  subroutine read_runs_table(file, group, runs, equal, error, limit)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: group
    type(run_record_t), allocatable, intent(out) :: runs(:)
    logical, intent(out) :: equal
    type(error_t), allocatable, intent(out) :: error
    integer, intent(in), optional :: limit
    character(len=run_text_capacity), allocatable :: commit(:), started(:), host(:), blas(:)
    integer(i4), allocatable :: ranks(:), threads(:)
    real(wp), allocatable :: t_start(:), t_end(:), wall(:), load_start(:), load_mean(:)
    integer(i8), allocatable :: steps(:)
    integer :: k, n, lengths(size(run_sets))
    logical :: has_blas
    equal = .false.
    has_blas = h5_exists(file, group//'/'//trim(run_sets(run_blas_set)))
    do k = 1, size(run_sets)
      if (k == run_blas_set) cycle
      if (.not. h5_exists(file, group//'/'//trim(run_sets(k)))) then
        call fatal_error(error, "case file '"//file%name()//"': no dataset "//group//'/'//trim(run_sets(k)))
        return
      end if
    end do
    call h5_read(file, group//'/commit', commit, error)
    if (.not. allocated(error)) call h5_read(file, group//'/started', started, error)
    if (.not. allocated(error)) call h5_read(file, group//'/host', host, error)
    if (.not. allocated(error) .and. has_blas) call h5_read(file, group//'/blas', blas, error)
    if (.not. allocated(error)) call h5_read(file, group//'/ranks', ranks, error)
    if (.not. allocated(error)) call h5_read(file, group//'/threads', threads, error)
    if (.not. allocated(error)) call h5_read(file, group//'/t_start', t_start, error)
    if (.not. allocated(error)) call h5_read(file, group//'/t_end', t_end, error)
    if (.not. allocated(error)) call h5_read(file, group//'/steps', steps, error)
    if (.not. allocated(error)) call h5_read(file, group//'/wall_seconds', wall, error)
    if (.not. allocated(error)) call h5_read(file, group//'/load_start', load_start, error)
    if (.not. allocated(error)) call h5_read(file, group//'/load_mean', load_mean, error)
    if (allocated(error)) return
    if (.not. has_blas) then
      allocate (blas(size(commit)))
      blas = blas_unrecorded
    end if
    lengths = [size(commit), size(started), size(host), size(blas), size(ranks), size(threads), &
               size(t_start), size(t_end), size(steps), size(wall), size(load_start), size(load_mean)]
    equal = all(lengths == lengths(1))
    n = minval(lengths)
    if (present(limit)) n = min(n, limit)
    allocate (runs(n))
    do k = 1, n
      runs(k)%commit = trim(commit(k))
      runs(k)%started = trim(started(k))
      runs(k)%host = trim(host(k))
      runs(k)%blas = trim(blas(k))
      runs(k)%ranks = ranks(k)
      runs(k)%threads = threads(k)
      runs(k)%t_start = t_start(k)
      runs(k)%t_end = t_end(k)
      runs(k)%steps = steps(k)
      runs(k)%wall_seconds = wall(k)
      runs(k)%load_start = load_start(k)
      runs(k)%load_mean = load_mean(k)
    end do
  end subroutine read_runs_table

  !> The /runs entries of a file being resumed, as they were at the checkpoint it continues
  !> from: the entries the checkpoint counts, the last with the checkpoint's figures (a kill
  !> after the checkpoint may have left /runs ahead of or behind it). A file whose /runs cannot
  !> be read (a kill inside `start_run`) is read from /runs_next; a file without either, or
  !> whose lists cannot be read, starts a new list (the resume itself never fails for it);
  !> a checkpoint without run figures (written before they existed) keeps /runs as it is.
  subroutine restore_runs(this)
    class(case_file_t), intent(inout) :: this
    type(error_t), allocatable :: err
    logical :: equal, fix
    integer :: n
    this%run_started = .false.
    if (allocated(this%runs)) deallocate (this%runs)
    associate (ck => this%resumed)
      fix = allocated(ck%run_counts) .and. allocated(ck%run_figures)
      if (fix) fix = size(ck%run_counts) == 2 .and. size(ck%run_figures) == 3
      if (fix) fix = ck%run_counts(1) >= 1 .and. ck%run_counts(1) <= huge(n)
      n = huge(n)
      if (fix) n = int(ck%run_counts(1))
      if (h5_exists(this%file, runs_group)) call read_runs_table(this%file, runs_group, this%runs, equal, err, n)
      if (allocated(err) .or. .not. allocated(this%runs)) then
        if (h5_exists(this%file, runs_next_group)) then
          if (allocated(err)) deallocate (err)
          call read_runs_table(this%file, runs_next_group, this%runs, equal, err, n)
        end if
      end if
      if (allocated(err) .or. .not. allocated(this%runs)) then
        if (allocated(this%runs)) deallocate (this%runs)
        allocate (this%runs(0))
        return
      end if
      if (.not. fix .or. size(this%runs) /= n) return
      this%runs(n)%steps = ck%run_counts(2)
      this%runs(n)%t_end = ck%run_figures(1)
      this%runs(n)%wall_seconds = ck%run_figures(2)
      this%runs(n)%load_mean = ck%run_figures(3)
    end associate
  end subroutine restore_runs

  !> Run totals of the run diagnostics (root attributes).
  subroutine write_diagnostics_totals(file, diag, error)
    type(h5_file_t), intent(in) :: file
    type(diagnostics_record_t), intent(in) :: diag
    type(error_t), allocatable, intent(out) :: error
    call h5_write_attr(file, '/', 'diagnostics.strand_passages', diag%strand_passages, error)
    if (.not. allocated(error)) &
      call h5_write_attr(file, '/', 'diagnostics.first_passage_time', diag%first_passage_time, error)
    if (.not. allocated(error)) &
      call h5_write_attr(file, '/', 'diagnostics.overlap_episodes', diag%overlap_episodes, error)
    if (.not. allocated(error)) &
      call h5_write_attr(file, '/', 'diagnostics.overlap_mean_duration', diag%overlap_mean_duration, error)
    if (.not. allocated(error)) &
      call h5_write_attr(file, '/', 'diagnostics.overlap_max_duration', diag%overlap_max_duration, error)
    if (.not. allocated(error)) &
      call h5_write_attr(file, '/', 'diagnostics.max_overlapping_pairs', int(diag%max_overlapping_pairs, i4), error)
    if (.not. allocated(error)) &
      call h5_write_attr(file, '/', 'diagnostics.min_distance', diag%run_min_distance, error)
    if (.not. allocated(error)) &
      call h5_write_attr(file, '/', 'diagnostics.max_bond_strain', diag%run_max_bond_strain, error)
  end subroutine write_diagnostics_totals

  !> Pad the columns of `a` with zero columns to the next power of two (at least 1), so that
  !> a dataset holding it changes its shape (and the file its structure) only rarely.
  pure subroutine pad_columns(a)
    real(wp), allocatable, intent(inout) :: a(:, :)
    real(wp), allocatable :: padded(:, :)
    integer :: n
    n = 1
    do while (n < size(a, 2))
      n = 2*n
    end do
    if (n == size(a, 2)) return
    allocate (padded(size(a, 1), n))
    padded = 0.0_wp
    padded(:, 1:size(a, 2)) = a
    call move_alloc(padded, a)
  end subroutine pad_columns

  !> Write the checkpoint `ck` into `group`: every part, then its digest, then its frame count
  !> (a checkpoint is trusted only when its digest matches its parts: `read_checkpoint`).
  subroutine write_checkpoint(file, group, ck, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: group
    type(checkpoint_t), intent(in) :: ck
    type(error_t), allocatable, intent(out) :: error
    call h5_write(file, group//'/time', ck%t, error)
    if (.not. allocated(error)) call h5_write(file, group//'/positions', ck%r, error)
    if (.not. allocated(error)) call h5_write(file, group//'/dt', ck%dt, error)
    if (.not. allocated(error)) call h5_write(file, group//'/steps', ck%steps, error)
    if (.not. allocated(error)) call h5_write(file, group//'/rejected', ck%rejected, error)
    if (allocated(error)) return
    if (allocated(ck%stepper%ints)) then
      call h5_write(file, group//'/stepper/reals', ck%stepper%reals, error)
      if (.not. allocated(error)) call h5_write(file, group//'/stepper/ints', ck%stepper%ints, error)
      if (.not. allocated(error)) call h5_write_attr(file, group//'/stepper', 'name', ck%stepper%name, error)
      if (allocated(error)) return
    end if
    if (allocated(ck%counters)) then
      call h5_write(file, group//'/counters', ck%counters, error)
      if (allocated(error)) return
    end if
    if (allocated(ck%diag_counters)) then
      call h5_write(file, group//'/diagnostics/counters', ck%diag_counters, error)
      if (.not. allocated(error)) call h5_write(file, group//'/diagnostics/values', ck%diag_values, error)
      if (.not. allocated(error)) call h5_write(file, group//'/diagnostics/ongoing', ck%diag_ongoing, error)
      if (allocated(error)) return
    end if
    if (allocated(ck%run_counts)) then
      call h5_write(file, group//'/run/counts', ck%run_counts, error)
      if (.not. allocated(error)) call h5_write(file, group//'/run/figures', ck%run_figures, error)
      if (allocated(error)) return
    end if
    call h5_write(file, group//'/digest', digest_value(checkpoint_digest(ck)), error)
    if (.not. allocated(error)) call h5_write(file, group//'/nframes', ck%nframes, error)
  end subroutine write_checkpoint

  !> Open an existing case file to continue it from its newest whole checkpoint (schema 3: the
  !> newer of the two slots whose digest matches and that equals the frame it counts; older
  !> schemas: /checkpoint), truncate every /frames dataset to that checkpoint's frame count,
  !> set status 'running' and return the state. `stepper` returns the checkpoint's stepper
  !> state and `counters` the run counters passed to `append_frame`, unallocated when the file
  !> has none (written before they were saved). On error the file is closed again.
  subroutine open_resume(this, path, r, t, dt, steps, rejected, nframes, error, stepper, counters)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: path
    real(wp), allocatable, intent(out) :: r(:, :)
    real(wp), intent(out) :: t, dt
    integer(i8), intent(out) :: steps, rejected, nframes
    type(error_t), allocatable, intent(out) :: error
    type(stepper_checkpoint_t), intent(out), optional :: stepper
    integer(i8), allocatable, intent(out), optional :: counters(:)
    t = 0.0_wp
    dt = 0.0_wp
    steps = 0
    rejected = 0
    nframes = 0
    call resume(this, path, error)
    if (allocated(error)) then
      call this%close()
      return
    end if
    associate (ck => this%resumed)
      r = ck%r
      t = ck%t
      dt = ck%dt
      steps = ck%steps
      rejected = ck%rejected
      nframes = ck%nframes
      if (present(stepper)) stepper = ck%stepper
      if (present(counters) .and. allocated(ck%counters)) counters = ck%counters
    end associate
  end subroutine open_resume

  subroutine resume(this, path, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: path
    type(error_t), allocatable, intent(out) :: error
    integer(i4) :: n_beads
    integer(i8) :: length
    integer :: i
    character(len=32), parameter :: other_sets(4) = [character(len=32) :: '/frames/positions', &
      '/frames/observables/close_pairs', '/frames/integrator/steps', '/frames/integrator/rejected']
    character(len=40) :: all_sets(size(frame_real_sets) + size(other_sets) + size(diag_sets) + size(stresslet_sets))
    character(len=:), allocatable :: damaged_slot
    logical :: legacy
    integer :: n_sets
    call this%close()
    this%run_started = .false.
    call h5_open_file(this%file, path, .true., error)
    if (allocated(error)) return
    call h5_read_attr(this%file, '/', 'n_beads', n_beads, error)
    if (allocated(error)) return
    call latest_checkpoint(this%file, int(n_beads), this%resumed, error, damaged_slot, legacy)
    if (allocated(error)) return
    ! A slot left damaged by a kill while its structure changed is renamed, not deleted
    ! (freeing objects whose headers are inconsistent could free space still in use), and the
    ! next checkpoint creates the slot anew.
    if (len(damaged_slot) > 0) call set_aside(this%file, damaged_slot, error)
    if (.not. allocated(error) .and. legacy) call upgrade_layout(this%file, this%resumed, error)
    if (allocated(error)) return
    this%diagnostics = h5_exists(this%file, trim(diag_sets(1)))
    this%stresslet = h5_exists(this%file, trim(stresslet_sets(1)))
    n_sets = size(frame_real_sets) + size(other_sets)
    all_sets(1:size(frame_real_sets)) = frame_real_sets
    all_sets(size(frame_real_sets) + 1:n_sets) = other_sets
    if (this%diagnostics) then
      all_sets(n_sets + 1:n_sets + size(diag_sets)) = diag_sets
      n_sets = n_sets + size(diag_sets)
    end if
    if (this%stresslet) then
      all_sets(n_sets + 1:n_sets + size(stresslet_sets)) = stresslet_sets
      n_sets = n_sets + size(stresslet_sets)
    end if
    do i = 1, n_sets
      call h5_length(this%file, trim(all_sets(i)), length, error)
      if (allocated(error)) return
      if (length < this%resumed%nframes) then
        call fatal_error(error, "case file '"//path//"': dataset '"//trim(all_sets(i))// &
          "' is shorter than the checkpoint's frame count")
        return
      end if
      if (length > this%resumed%nframes) call h5_set_length(this%file, trim(all_sets(i)), this%resumed%nframes, error)
      if (allocated(error)) return
    end do
    call restore_runs(this)
    call h5_write_attr(this%file, '/', 'status', status_value('running'), error)
    if (.not. allocated(error)) call h5_flush(this%file, error)
    if (allocated(error)) return
    this%n_beads = n_beads
    this%nframes = this%resumed%nframes
    this%last_time = this%resumed%t
    this%flushed_time = this%resumed%t
  end subroutine resume

  !> The newest whole checkpoint of the open file: of a file of schema 3 the slot with the
  !> larger frame count among those that `read_checkpoint` and `check_last_frame` accept; of an
  !> older file its single /checkpoint. The error names the file and what is wrong with each.
  !> `damaged` (optional) returns the group of a slot that exists but is not whole ('' if none),
  !> `legacy` (optional) whether the file has the single checkpoint of schema 1 or 2.
  subroutine latest_checkpoint(file, n_beads, ck, error, damaged, legacy)
    type(h5_file_t), intent(in) :: file
    integer, intent(in) :: n_beads
    type(checkpoint_t), intent(out) :: ck
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable, intent(out), optional :: damaged
    logical, intent(out), optional :: legacy
    type(checkpoint_t) :: candidate
    type(error_t), allocatable :: err
    character(len=:), allocatable :: reasons
    integer(i4) :: schema
    integer :: k
    logical :: found
    if (present(damaged)) damaged = ''
    schema = 1
    if (h5_attr_exists(file, '/', 'schema_version')) then
      call h5_read_attr(file, '/', 'schema_version', schema, error)
      if (allocated(error)) return
    end if
    if (present(legacy)) legacy = schema < 3
    if (schema < 3) then
      call read_checkpoint(file, legacy_group, n_beads, .false., ck, error)
      if (.not. allocated(error)) call check_last_frame(file, ck, error)
      if (allocated(error)) error%message = "case file '"//file%name()//"': "//error%message
      return
    end if
    found = .false.
    reasons = ''
    do k = 0, 1
      call read_checkpoint(file, trim(slot_groups(k)), n_beads, .true., candidate, err)
      if (.not. allocated(err)) call check_last_frame(file, candidate, err)
      if (allocated(err)) then
        reasons = reasons//merge('; ', '  ', k > 0)//trim(slot_groups(k))//': '//err%message
        deallocate (err)
        if (present(damaged)) then
          if (h5_exists(file, trim(slot_groups(k)))) damaged = trim(slot_groups(k))
        end if
        cycle
      end if
      if (found) then
        if (candidate%nframes <= ck%nframes) cycle
      end if
      ck = candidate
      found = .true.
    end do
    if (.not. found) call fatal_error(error, "case file '"//file%name()//"' has no whole checkpoint ("// &
      trim(adjustl(reasons))//')')
  end subroutine latest_checkpoint

  !> Rename the group `group` to the first free `<group>_damaged<k>`, k = 1, 2, ...
  subroutine set_aside(file, group, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: group
    type(error_t), allocatable, intent(out) :: error
    integer :: k
    k = 1
    do while (h5_exists(file, group//'_damaged'//to_str(k)))
      k = k + 1
    end do
    call h5_move(file, group, group//'_damaged'//to_str(k), error)
  end subroutine set_aside

  !> Give a file of schema 1 or 2, resumed from its single /checkpoint `ck`, the layout of this
  !> version: `ck` written to both slots, then schema_version, then the old checkpoint's parts
  !> removed, each step flushed (a kill in between leaves a file that reads as the old or as
  !> the new layout).
  subroutine upgrade_layout(file, ck, error)
    type(h5_file_t), intent(in) :: file
    type(checkpoint_t), intent(in) :: ck
    type(error_t), allocatable, intent(out) :: error
    character(len=*), parameter :: old_parts(11) = [character(len=11) :: 'time', 'positions', 'dt', &
      'steps', 'rejected', 'nframes', 'digest', 'stepper', 'counters', 'diagnostics', 'run']
    integer :: k
    call write_checkpoint(file, trim(slot_groups(0)), ck, error)
    if (.not. allocated(error)) call write_checkpoint(file, trim(slot_groups(1)), ck, error)
    if (.not. allocated(error)) call h5_flush(file, error)
    if (.not. allocated(error)) call h5_write_attr(file, '/', 'schema_version', case_schema_version, error)
    if (.not. allocated(error)) call h5_flush(file, error)
    do k = 1, size(old_parts)
      if (.not. allocated(error)) call h5_delete(file, legacy_group//'/'//trim(old_parts(k)), error)
    end do
  end subroutine upgrade_layout

  !> Read the checkpoint in `group` and check it against its digest (`need_digest`: a checkpoint
  !> without one is refused; otherwise, files written before it existed, it is taken as is).
  subroutine read_checkpoint(file, group, n_beads, need_digest, ck, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: group
    integer, intent(in) :: n_beads
    logical, intent(in) :: need_digest
    type(checkpoint_t), intent(out) :: ck
    type(error_t), allocatable, intent(out) :: error
    integer(i8) :: stored_digest
    if (.not. h5_exists(file, group//'/nframes')) then
      call fatal_error(error, 'no checkpoint (created but never written)')
      return
    end if
    call h5_read(file, group//'/nframes', ck%nframes, error)
    if (.not. allocated(error)) call h5_read(file, group//'/time', ck%t, error)
    if (.not. allocated(error)) call h5_read(file, group//'/dt', ck%dt, error)
    if (.not. allocated(error)) call h5_read(file, group//'/steps', ck%steps, error)
    if (.not. allocated(error)) call h5_read(file, group//'/rejected', ck%rejected, error)
    if (.not. allocated(error)) call h5_read(file, group//'/positions', ck%r, error)
    if (allocated(error)) return
    if (size(ck%r, 1) /= 3 .or. size(ck%r, 2) /= n_beads) then
      call fatal_error(error, 'checkpoint positions do not have shape (3, n_beads)')
      return
    end if
    if (h5_exists(file, group//'/stepper/ints')) then
      call h5_read(file, group//'/stepper/reals', ck%stepper%reals, error)
      if (.not. allocated(error)) call h5_read(file, group//'/stepper/ints', ck%stepper%ints, error)
      if (.not. allocated(error)) call h5_read_attr(file, group//'/stepper', 'name', ck%stepper%name, error)
      if (allocated(error)) return
    end if
    if (h5_exists(file, group//'/counters')) then
      call h5_read(file, group//'/counters', ck%counters, error)
      if (allocated(error)) return
    end if
    if (h5_exists(file, group//'/diagnostics/counters')) then
      call h5_read(file, group//'/diagnostics/counters', ck%diag_counters, error)
      if (.not. allocated(error)) call h5_read(file, group//'/diagnostics/values', ck%diag_values, error)
      if (.not. allocated(error)) call h5_read(file, group//'/diagnostics/ongoing', ck%diag_ongoing, error)
      if (allocated(error)) return
    end if
    if (h5_exists(file, group//'/run/counts')) then
      call h5_read(file, group//'/run/counts', ck%run_counts, error)
      if (.not. allocated(error)) call h5_read(file, group//'/run/figures', ck%run_figures, error)
      if (allocated(error)) return
    end if
    if (.not. h5_exists(file, group//'/digest')) then
      if (need_digest) call fatal_error(error, 'the checkpoint (t = '//to_str(ck%t, '(g0.6)')//') has no digest')
      return
    end if
    call h5_read(file, group//'/digest', stored_digest, error)
    if (allocated(error)) return
    if (digest_value(checkpoint_digest(ck)) /= stored_digest) call fatal_error(error, 'the checkpoint (t = '// &
      to_str(ck%t, '(g0.6)')//') does not match its digest: it was not written completely')
  end subroutine read_checkpoint

  !> A checkpoint is trusted only when it is the frame it counts: /frames holds at least
  !> `nframes` frames and frame `nframes` has the checkpoint's time and positions.
  subroutine check_last_frame(file, ck, error)
    type(h5_file_t), intent(in) :: file
    type(checkpoint_t), intent(in) :: ck
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: times(:), last(:, :)
    if (ck%nframes < 1) then
      call fatal_error(error, 'the checkpoint has no frames')
      return
    end if
    call h5_read(file, '/frames/time', times, error)
    if (allocated(error)) return
    if (size(times, kind=i8) < ck%nframes) then
      call fatal_error(error, "/frames/time is shorter than the checkpoint's frame count")
      return
    end if
    call h5_read_entry(file, '/frames/positions', ck%nframes, last, error)
    if (allocated(error)) return
    if (times(ck%nframes) /= ck%t .or. any(shape(last) /= shape(ck%r))) then
      call fatal_error(error, 'the checkpoint (t = '//to_str(ck%t, '(g0.6)')//') is not its last frame')
    else if (any(last /= ck%r)) then
      call fatal_error(error, 'the checkpoint (t = '//to_str(ck%t, '(g0.6)')//') is not its last frame')
    end if
  end subroutine check_last_frame

  !> Set the status attribute ('running', 'finished', 'failed: <reason>') and flush.
  subroutine set_status(this, text, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: text
    type(error_t), allocatable, intent(out) :: error
    call h5_write_attr(this%file, '/', 'status', status_value(text), error)
    if (.not. allocated(error)) call h5_flush(this%file, error)
  end subroutine set_status

  !> Close the file (a closed case file is left alone). `error`, when present, reports a
  !> failed close (the last writes may not have reached the disk).
  subroutine close_case(this, error)
    class(case_file_t), intent(inout) :: this
    type(error_t), allocatable, intent(out), optional :: error
    call h5_close_file(this%file, error)
  end subroutine close_case

  !> End a run that reached `t_end`: flush and close the file (both checked), read it back and
  !> verify it (`verify_case_file`), and only then write status = 'finished' (written, flushed
  !> and closed, all checked). On error the file is closed and still says 'running'; `damaged`
  !> tells that the verification found the file itself bad (then it must not be resumed).
  !> `run`, the final record of the run segment (after `start_run`), replaces its /runs entry
  !> before the flush.
  subroutine finish(this, t_end, error, damaged, run)
    class(case_file_t), intent(inout) :: this
    real(wp), intent(in) :: t_end
    type(error_t), allocatable, intent(out) :: error
    logical, intent(out) :: damaged
    type(run_record_t), intent(in), optional :: run
    character(len=:), allocatable :: path
    damaged = .false.
    path = this%file%name()
    if (present(run) .and. this%run_started) then
      this%runs(size(this%runs)) = run
      call write_run_figures(this%file, runs_group, this%runs, error)
      if (allocated(error)) then
        call this%close()
        return
      end if
    end if
    call h5_flush(this%file, error)
    if (allocated(error)) then
      call this%close()
      return
    end if
    call this%close(error)
    if (allocated(error)) return
    call verify_case_file(path, t_end, error)
    if (allocated(error)) then
      damaged = .true.
      return
    end if
    call h5_open_file(this%file, path, .true., error)
    if (allocated(error)) return
    call h5_write_attr(this%file, '/', 'status', status_value('finished'), error)
    if (.not. allocated(error)) call h5_flush(this%file, error)
    if (allocated(error)) then
      call this%close()
      return
    end if
    call this%close(error)
  end subroutine finish

  !> `text` null-padded to `status_capacity` bytes (readers stop at the first null).
  pure function status_value(text) result(value)
    character(len=*), intent(in) :: text
    character(len=max(len(text), status_capacity)) :: value
    value = repeat(achar(0), len(value))
    value(1:len(text)) = text
  end function status_value

  pure logical function case_is_open(this)
    class(case_file_t), intent(in) :: this
    case_is_open = this%file%is_open()
  end function case_is_open

  !> Time of the last checkpoint flushed to the file by `append_frame` (or found by
  !> `open_resume`); -1 when there is none yet.
  pure real(wp) function checkpoint_time(this)
    class(case_file_t), intent(in) :: this
    checkpoint_time = this%flushed_time
  end function checkpoint_time

  !> Number of frames in the file.
  pure integer(i8) function frame_count(this)
    class(case_file_t), intent(in) :: this
    frame_count = this%nframes
  end function frame_count

  subroutine write_item(file, item, error)
    type(h5_file_t), intent(in) :: file
    type(attribute_t), intent(in) :: item
    type(error_t), allocatable, intent(out) :: error
    select case (item%kind)
    case (kind_str)
      call h5_write_attr(file, '/', item%name, item%str, error)
    case (kind_i4)
      call h5_write_attr(file, '/', item%name, item%ival, error)
    case (kind_i8)
      call h5_write_attr(file, '/', item%name, item%lval, error)
    case (kind_real)
      call h5_write_attr(file, '/', item%name, item%rval, error)
    case (kind_real1)
      call h5_write_attr(file, '/', item%name, item%r1, error)
    case (kind_real2)
      call h5_write_attr(file, '/', item%name, item%r2, error)
    case default
      call fatal_error(error, "case file: attribute '"//item%name//"' has no value")
    end select
  end subroutine write_item

  subroutine write_attr_str(this, name, value, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name, value
    type(error_t), allocatable, intent(out) :: error
    call h5_write_attr(this%file, '/', name, value, error)
  end subroutine write_attr_str

  subroutine write_attr_i4(this, name, value, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer(i4), intent(in) :: value
    type(error_t), allocatable, intent(out) :: error
    call h5_write_attr(this%file, '/', name, value, error)
  end subroutine write_attr_i4

  !> The int64 root attribute `name`, or 0 when the file does not have it.
  subroutine read_counter(this, name, value, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer(i8), intent(out) :: value
    type(error_t), allocatable, intent(out) :: error
    value = 0
    if (.not. h5_attr_exists(this%file, '/', name)) return
    call h5_read_attr(this%file, '/', name, value, error)
  end subroutine read_counter

  subroutine write_attr_i8(this, name, value, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer(i8), intent(in) :: value
    type(error_t), allocatable, intent(out) :: error
    call h5_write_attr(this%file, '/', name, value, error)
  end subroutine write_attr_i8

  subroutine write_attr_real(this, name, value, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value
    type(error_t), allocatable, intent(out) :: error
    call h5_write_attr(this%file, '/', name, value, error)
  end subroutine write_attr_real

  subroutine write_attr_logical(this, name, value, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    logical, intent(in) :: value
    type(error_t), allocatable, intent(out) :: error
    call h5_write_attr(this%file, '/', name, merge(1_i4, 0_i4, value), error)
  end subroutine write_attr_logical

  subroutine write_attr_real1(this, name, value, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value(:)
    type(error_t), allocatable, intent(out) :: error
    call h5_write_attr(this%file, '/', name, value, error)
  end subroutine write_attr_real1

  subroutine write_attr_real2(this, name, value, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value(:, :)
    type(error_t), allocatable, intent(out) :: error
    call h5_write_attr(this%file, '/', name, value, error)
  end subroutine write_attr_real2

  ! ---------------------------------------------------------------- inspecting files

  !> Status of the case file `path`: 'missing' (no file), the status attribute ('running',
  !> 'finished', 'failed: <reason>'), or 'corrupt: <reason>' when the file exists but cannot be
  !> opened as HDF5 or has no status attribute (the caller reports it and recreates the case).
  !> `error` is set only for an invalid request (an empty path), not for a bad file.
  subroutine case_file_status(path, status, error)
    character(len=*), intent(in) :: path
    character(len=:), allocatable, intent(out) :: status
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t) :: file
    type(error_t), allocatable :: err
    logical :: exists, is_directory
    if (len_trim(path) == 0) then
      call fatal_error(error, 'case_file_status: empty path')
      status = 'missing'
      return
    end if
    inquire (file=path, exist=exists)
    if (.not. exists) then
      status = 'missing'
      return
    end if
    ! A FIFO, device or socket under the case file's name is no damaged case file: it is refused
    ! (not moved aside, not opened: a FIFO would block HDF5's open for ever).
    inquire (file=path//'/.', exist=is_directory)
    if (.not. is_directory) then
      call check_regular_file(path, 'case file', error)
      if (allocated(error)) then
        status = 'not a regular file'
        return
      end if
    end if
    call h5_open_file(file, path, .false., err)
    if (allocated(err)) then
      status = 'corrupt: '//err%message
      return
    end if
    if (.not. h5_attr_exists(file, '/', 'status')) then
      status = 'corrupt: no status attribute'
    else
      call h5_read_attr(file, '/', 'status', status, err)
      if (allocated(err)) status = 'corrupt: '//err%message
    end if
    call h5_close_file(file)
  end subroutine case_file_status

  ! ---------------------------------------------------------------- checkpoint digest

  !> The digest of a checkpoint's parts (an Adler-style pair of sums modulo a prime over their
  !> bytes): it tells whether parts read back were written by the same `append_frame`. Parts
  !> a checkpoint does not have (stepper state, run diagnostics, run counters) are left out.
  pure function checkpoint_digest(ck) result(d)
    type(checkpoint_t), intent(in) :: ck
    integer(i8) :: d(2)
    d = [1_i8, 0_i8]
    call add_bytes(d, transfer([ck%nframes, ck%steps, ck%rejected], [0_int8]))
    call add_bytes(d, transfer([ck%t, ck%dt], [0_int8]))
    call add_bytes(d, transfer(ck%r, [0_int8]))
    if (allocated(ck%stepper%ints)) then
      call add_bytes(d, transfer(ck%stepper%reals, [0_int8]))
      call add_bytes(d, transfer(ck%stepper%ints, [0_int8]))
    end if
    if (allocated(ck%diag_counters)) then
      call add_bytes(d, transfer(ck%diag_counters, [0_int8]))
      call add_bytes(d, transfer(ck%diag_values, [0_int8]))
      call add_bytes(d, transfer(ck%diag_ongoing, [0_int8]))
    end if
    if (allocated(ck%counters)) call add_bytes(d, transfer(ck%counters, [0_int8]))
    if (allocated(ck%run_counts)) then
      call add_bytes(d, transfer(ck%run_counts, [0_int8]))
      call add_bytes(d, transfer(ck%run_figures, [0_int8]))
    end if
  end function checkpoint_digest

  pure subroutine add_bytes(d, bytes)
    integer(i8), intent(inout) :: d(2)
    integer(int8), intent(in) :: bytes(:)
    integer(i8), parameter :: prime = 2147483629_i8
    integer :: k
    do k = 1, size(bytes)
      d(1) = mod(d(1) + iand(int(bytes(k), i8), 255_i8), prime)
      d(2) = mod(d(2) + d(1), prime)
    end do
  end subroutine add_bytes

  pure integer(i8) function digest_value(d)
    integer(i8), intent(in) :: d(2)
    digest_value = d(2)*2147483648_i8 + d(1)
  end function digest_value

  !> Read the case file `path` back and check what a finished run must hold: every /frames
  !> dataset has the checkpoint's frame count and reads without a checksum error; the times
  !> start at 0, increase strictly and end at `t_end`; every position is finite; the checkpoint
  !> is the last frame. The message names the file, dataset and frame of the first problem.
  subroutine verify_case_file(path, t_end, error)
    character(len=*), intent(in) :: path
    real(wp), intent(in) :: t_end
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t) :: file
    real(wp), allocatable :: t(:), r(:, :, :), values(:), tensors(:, :, :)
    type(checkpoint_t) :: ck
    integer(i4), allocatable :: ivalues(:)
    integer(i8), allocatable :: lvalues(:)
    integer(i8) :: nframes, length
    integer(i4) :: n_beads
    integer :: k, bad
    character(len=40) :: sets(size(frame_real_sets) + 3 + size(diag_sets) + size(stresslet_sets))
    integer :: kinds(size(sets)), n_sets
    call h5_open_file(file, path, .false., error)
    if (allocated(error)) return
    call check()
    call h5_close_file(file)
    if (allocated(error)) then
      k = index(error%message, "case file '"//path//"'")
      if (k == 1) error%message = error%message(len("case file '"//path//"'") + 1:)
      if (k == 1 .and. error%message(1:1) == ':') error%message = adjustl(error%message(2:))
      error%message = "case file '"//path//"' fails verification: "//error%message
    end if

  contains

    subroutine check()
      call h5_read_attr(file, '/', 'n_beads', n_beads, error)
      if (allocated(error)) return
      ! the newest whole checkpoint, which must be the last frame
      call latest_checkpoint(file, int(n_beads), ck, error)
      if (allocated(error)) return
      nframes = ck%nframes
      call h5_read(file, '/frames/time', t, error)
      if (allocated(error)) return
      if (size(t, kind=i8) /= nframes .or. nframes < 1) then
        call fatal_error(error, '/frames/time has '//to_str(size(t, kind=i8))//' frames, the newest whole '// &
          'checkpoint '//to_str(nframes))
        return
      end if
      if (t(1) /= 0.0_wp) then
        call fatal_error(error, 'frame 0 is not at t = 0')
        return
      end if
      do k = 1, size(t)
        if (.not. ieee_is_finite(t(k))) then
          call fatal_error(error, 'frame '//to_str(int(k - 1, i8))//' has a non-finite time')
          return
        end if
      end do
      do k = 2, size(t)
        if (.not. t(k) > t(k - 1)) then
          call fatal_error(error, 'frame '//to_str(int(k - 1, i8))//': time does not increase')
          return
        end if
      end do
      if (.not. abs(t(size(t)) - t_end) <= 1.0e-9_wp*max(1.0_wp, abs(t_end))) then
        call fatal_error(error, 'the last frame is not at t_end')
        return
      end if
      call h5_read(file, '/frames/positions', r, error)
      if (allocated(error)) return
      if (size(r, 1) /= 3 .or. size(r, 2) /= n_beads .or. size(r, 3, kind=i8) /= nframes) then
        call fatal_error(error, '/frames/positions does not have shape (nframes, n_beads, 3)')
        return
      end if
      do k = 1, size(r, 3)
        bad = count(.not. ieee_is_finite(r(:, :, k)))
        if (bad > 0) then
          call fatal_error(error, 'frame '//to_str(int(k - 1, i8))//' (t = '//to_str(t(k), '(g0.6)')//') holds '// &
            to_str(int(bad, i8))//' non-finite coordinates')
          return
        end if
      end do
      n_sets = size(frame_real_sets)
      sets(1:n_sets) = frame_real_sets
      kinds(1:n_sets) = h5_real
      sets(n_sets + 1:n_sets + 3) = [character(len=40) :: '/frames/observables/close_pairs', &
        '/frames/integrator/steps', '/frames/integrator/rejected']
      kinds(n_sets + 1:n_sets + 3) = [h5_int32, h5_int64, h5_int64]
      n_sets = n_sets + 3
      if (h5_exists(file, trim(diag_sets(1)))) then
        sets(n_sets + 1:n_sets + size(diag_sets)) = diag_sets
        kinds(n_sets + 1:n_sets + size(diag_sets)) = diag_kinds
        n_sets = n_sets + size(diag_sets)
      end if
      if (h5_exists(file, trim(stresslet_sets(1)))) then
        sets(n_sets + 1:n_sets + size(stresslet_sets)) = stresslet_sets
        kinds(n_sets + 1:n_sets + size(stresslet_sets)) = h5_real
        n_sets = n_sets + size(stresslet_sets)
      end if
      do k = 1, n_sets
        call h5_length(file, trim(sets(k)), length, error)
        if (allocated(error)) return
        if (length /= nframes) then
          call fatal_error(error, trim(sets(k))//' has '//to_str(length)//' frames, the checkpoint '// &
            to_str(nframes))
          return
        end if
        select case (kinds(k))
        case (h5_real)
          if (any(sets(k) == stresslet_sets(1:stresslet_tensors))) then
            call h5_read(file, trim(sets(k)), tensors, error)
          else
            call h5_read(file, trim(sets(k)), values, error)
          end if
        case (h5_int32)
          call h5_read(file, trim(sets(k)), ivalues, error)
        case default
          call h5_read(file, trim(sets(k)), lvalues, error)
        end select
        if (allocated(error)) return
      end do
      if (h5_exists(file, runs_group)) call check_runs()
    end subroutine check

    !> /runs (files of schema 4 and later): every dataset reads back, all of one length, at
    !> least 1.
    subroutine check_runs()
      type(run_record_t), allocatable :: runs(:)
      logical :: equal
      call read_runs_table(file, runs_group, runs, equal, error)
      if (allocated(error)) return
      if (.not. equal .or. size(runs) < 1) call fatal_error(error, runs_group// &
        ' does not hold one entry per run segment in every dataset')
    end subroutine check_runs

  end subroutine verify_case_file

  !> Read the complete frames of a case file: times t(nframes) and positions r(3, N, nframes).
  !> A file with a checkpoint is read up to the frames its newest checkpoint counts (a frame
  !> beyond it was being written when the run stopped). Refused with an error naming the file
  !> and the problem: no /frames group, /frames/time or /frames/positions missing, not numbers
  !> or unreadable (checksums), positions not of shape (frames, beads, 3), fewer than 2 beads,
  !> time and positions of different lengths (without a checkpoint), no frame, a non-finite time
  !> or coordinate, times that do not increase.
  subroutine read_frames(path, t, r, error)
    character(len=*), intent(in) :: path
    real(wp), allocatable, intent(out) :: t(:)
    real(wp), allocatable, intent(out) :: r(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    type(h5_file_t) :: file
    call h5_open_file(file, path, .false., error)
    if (allocated(error)) return
    call read_open_frames(file, t, r, error)
    call h5_close_file(file)
  end subroutine read_frames

  !> `read_frames` of a case file that is already open.
  subroutine read_open_frames(file, t, r, error)
    type(h5_file_t), intent(in) :: file
    real(wp), allocatable, intent(out) :: t(:)
    real(wp), allocatable, intent(out) :: r(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    character(len=:), allocatable :: path
    integer(i8) :: counted
    integer :: n, k
    path = file%name()
    if (.not. h5_exists(file, '/frames')) then
      call fatal_error(error, "case file '"//path//"': no /frames group (not a knotflow case file)")
    else
      call h5_read(file, '/frames/time', t, error)
      if (.not. allocated(error)) call h5_read(file, '/frames/positions', r, error)
      if (.not. allocated(error)) call checkpoint_frames(file, counted, error)
    end if
    if (allocated(error)) return
    if (size(r, 1) /= 3) then
      call fatal_error(error, "case file '"//path//"': /frames/positions has shape ("//to_str(size(r, 3))//', '// &
        to_str(size(r, 2))//', '//to_str(size(r, 1))//'), expected (frames, beads, 3)')
      return
    end if
    if (size(r, 2) < 2) then
      call fatal_error(error, "case file '"//path//"': /frames/positions holds "//to_str(size(r, 2))// &
        ' bead(s) per frame, a chain needs at least 2')
      return
    end if
    if (counted >= 0) then
      n = int(min(int(min(size(t), size(r, 3)), i8), counted))
    else if (size(r, 3) /= size(t)) then
      call fatal_error(error, "case file '"//path//"': /frames/time and /frames/positions have different "// &
        'lengths ('//to_str(size(t))//' and '//to_str(size(r, 3))//' frames)')
      return
    else
      n = size(t)
    end if
    if (n < 1) then
      call fatal_error(error, "case file '"//path//"': no complete frame (/frames is empty)")
      return
    end if
    if (n < size(t)) t = t(1:n)
    if (n < size(r, 3)) r = r(:, :, 1:n)
    call check_finite_frames(path, t, r, error)
    if (allocated(error)) return
    do k = 2, n
      if (.not. t(k) > t(k - 1)) then
        call fatal_error(error, "case file '"//path//"': frame "//to_str(k - 1)//' (t = '//to_str(t(k), '(g0.6)')// &
          ') is not after frame '//to_str(k - 2)//' (t = '//to_str(t(k - 1), '(g0.6)')//'): times must increase')
        return
      end if
    end do
  end subroutine read_open_frames

  !> Read the shape observables of the first `nframes` frames of the case file `path`
  !> (/frames/observables: as many frames as `read_frames` returns): values(nframes, 6) holds
  !> rg, a, b, c, theta, phi (in this order, one column each) and close_pairs(nframes).
  !> Refused with an error naming the file and the dataset: missing, unreadable, or shorter than
  !> `nframes`.
  subroutine read_observables(path, nframes, values, close_pairs, error)
    character(len=*), intent(in) :: path
    integer, intent(in) :: nframes
    real(wp), allocatable, intent(out) :: values(:, :)
    integer(i4), allocatable, intent(out) :: close_pairs(:)
    type(error_t), allocatable, intent(out) :: error
    character(len=*), parameter :: names(6) = [character(len=5) :: 'rg', 'a', 'b', 'c', 'theta', 'phi']
    type(h5_file_t) :: file
    real(wp), allocatable :: column(:)
    integer(i4), allocatable :: counts(:)
    integer :: k
    allocate (values(nframes, 6), close_pairs(nframes))
    call h5_open_file(file, path, .false., error)
    if (allocated(error)) return
    do k = 1, size(names)
      call read_column('/frames/observables/'//trim(names(k)))
      if (allocated(error)) exit
      values(:, k) = column(1:nframes)
    end do
    if (.not. allocated(error)) then
      if (.not. h5_exists(file, '/frames/observables/close_pairs')) then
        call fatal_error(error, '/frames/observables/close_pairs missing (not a knotflow case file)')
      else
        call h5_read(file, '/frames/observables/close_pairs', counts, error)
      end if
      if (.not. allocated(error) .and. size(counts) < nframes) call too_short('/frames/observables/close_pairs', &
                                                                             size(counts))
      if (.not. allocated(error)) close_pairs = counts(1:nframes)
    end if
    call h5_close_file(file)
    if (allocated(error)) error%message = "case file '"//path//"': "//error%message

  contains

    subroutine read_column(name)
      character(len=*), intent(in) :: name
      if (.not. h5_exists(file, name)) then
        call fatal_error(error, name//' missing (not a knotflow case file)')
        return
      end if
      call h5_read(file, name, column, error)
      if (.not. allocated(error) .and. size(column) < nframes) call too_short(name, size(column))
    end subroutine read_column

    subroutine too_short(name, length)
      character(len=*), intent(in) :: name
      integer, intent(in) :: length
      call fatal_error(error, name//' holds '//to_str(length)//' frame(s), fewer than the '//to_str(nframes)// &
        ' of /frames/positions')
    end subroutine too_short

  end subroutine read_observables

  !> Does the case file `path` hold a checkpoint (of at least one frame)? A file killed while it
  !> was created has none (and may lack its scene attributes): nothing in it can be reused.
  logical function has_checkpoint(path)
    character(len=*), intent(in) :: path
    type(h5_file_t) :: file
    type(error_t), allocatable :: error
    integer(i8) :: counted
    has_checkpoint = .false.
    call h5_open_file(file, path, .false., error)
    if (allocated(error)) return
    call checkpoint_frames(file, counted, error)
    has_checkpoint = .not. allocated(error) .and. counted >= 1
    call h5_close_file(file)
  end function has_checkpoint

  !> The frames the newest checkpoint of an open file counts, without checking it: the larger
  !> frame count of the slots (schema 3; a slot's count is written last) or /checkpoint/nframes
  !> (older files); -1 when the file has no checkpoint.
  subroutine checkpoint_frames(file, counted, error)
    type(h5_file_t), intent(in) :: file
    integer(i8), intent(out) :: counted
    type(error_t), allocatable, intent(out) :: error
    character(len=*), parameter :: groups(3) = [character(len=17) :: slot_groups(0), slot_groups(1), legacy_group]
    integer(i8) :: n
    integer :: k
    counted = -1
    do k = 1, size(groups)
      if (.not. h5_exists(file, trim(groups(k))//'/nframes')) cycle
      call h5_read(file, trim(groups(k))//'/nframes', n, error)
      if (allocated(error)) return
      counted = max(counted, n)
    end do
  end subroutine checkpoint_frames

  !> Every frame time and coordinate must be finite: the error names the file, the first bad
  !> frame (0-based), its time and the number of non-finite coordinates.
  subroutine check_finite_frames(path, t, r, error)
    character(len=*), intent(in) :: path
    real(wp), intent(in) :: t(:), r(:, :, :)
    type(error_t), allocatable, intent(out) :: error
    integer :: k, bad
    do k = 1, size(t)
      bad = count(.not. ieee_is_finite(r(:, :, k)))
      if (bad > 0 .or. .not. ieee_is_finite(t(k))) then
        call fatal_error(error, "case file '"//path//"': frame "//to_str(k - 1)//' (t = '// &
          to_str(t(k), '(g0.6)')//') holds '//to_str(bad)//' non-finite coordinates'// &
          merge(' and a non-finite time', '                      ', .not. ieee_is_finite(t(k))))
        error%message = trim(error%message)
        return
      end if
    end do
  end subroutine check_finite_frames

end module kf_case_file
