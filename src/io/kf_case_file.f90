!> The HDF5 case file of one simulation case: the contract between the simulation and the
!> analysis tools. The layout (groups, datasets, attributes, schema versions) is documented
!> once, in docs/case-file.md; keep that page in step with this module and the ones it uses:
!> kf_case_frames (the frame record `frame_t` and the one table of the /frames datasets),
!> kf_case_checkpoint (the two checkpoint slots), kf_case_runs (/runs), kf_case_attributes (the
!> root attributes of `create`) and kf_case_verify (status, reading back, verification).
!>
!> How the layout is written: `create` writes the root attributes and /frames;
!> `enable_diagnostics` and `enable_stresslet` after `create` add /frames/diagnostics and
!> /frames/stresslet; `start_run` appends the segment's /runs entry (a `run_record_t` the run
!> layer fills), and `append_frame` and `finish` given the record rewrite its changing figures
!> in place; `open_resume` restores /runs to the checkpoint it continues from.
!>
!> The file takes plain records (the frame `frame_t`, the stepper's state, the run segment) and
!> writes them as given: it computes nothing (the run layer fills the records, kf_frame_records).
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
module kf_case_file
  use kf_kinds, only: wp, i4, i8
  use kf_error, only: error_t, fatal_error
  use kf_build_info, only: knotflow_version, knotflow_git_hash, knotflow_compiler, knotflow_flags
  use kf_h5, only: h5_file_t, h5_create_file, h5_close_file, h5_flush, h5_attr_exists, h5_write_attr, h5_read_attr
  use kf_case_attributes, only: attribute_list_t, write_attributes, status_value
  use kf_case_frames, only: frame_t, frame_template, create_frames, append_frames, write_diagnostics_totals, &
    frame_refusal
  use kf_case_checkpoint, only: checkpoint_t, stepper_checkpoint_t, write_slots, pad_columns
  use kf_case_runs, only: run_record_t, write_run_figures
  implicit none
  private

  !> Version of the case file layout written by `create`. 1: files without the attribute
  !> (before it existed); 2: the attribute itself; 3: two checkpoint slots written alternately
  !> (/checkpoint/slot0, /checkpoint/slot1) instead of one /checkpoint rewritten in place;
  !> 4: /runs, one entry per run segment (kept up to date only by a program that knows it: an
  !> older one refuses to continue such a file); 5: /runs/blas (an older program would leave it
  !> shorter than the rest). Raise it with any change a reader must know.
  integer(i4), parameter, public :: case_schema_version = 5

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

  !> The ends of a run segment: starting it, resuming a file, finishing it (kf_case_segment).
  interface
    !> Begin a run segment (after `create`, or after `open_resume`): `run` is appended to /runs
    !> (a file without /runs gets it, kf_case_runs' `replace_runs`: a kill at any point leaves
    !> one whole list) and the file marked with this schema version; flushed. Later
    !> `append_frame` and `finish` calls given the segment's record update its entry.
    module subroutine start_run(this, run, error)
      class(case_file_t), intent(inout) :: this
      type(run_record_t), intent(in) :: run
      type(error_t), allocatable, intent(out) :: error
    end subroutine start_run

    !> Open an existing case file to continue it from its newest whole checkpoint (schema 3: the
    !> newer of the two slots whose digest matches and that equals the frame it counts; older
    !> schemas: /checkpoint), truncate every /frames dataset to that checkpoint's frame count,
    !> set status 'running' and return the state. `stepper` returns the checkpoint's stepper
    !> state and `counters` the run counters passed to `append_frame`, unallocated when the file
    !> has none (written before they were saved). On error the file is closed again.
    module subroutine open_resume(this, path, r, t, dt, steps, rejected, nframes, error, stepper, counters)
      class(case_file_t), intent(inout) :: this
      character(len=*), intent(in) :: path
      real(wp), allocatable, intent(out) :: r(:, :)
      real(wp), intent(out) :: t, dt
      integer(i8), intent(out) :: steps, rejected, nframes
      type(error_t), allocatable, intent(out) :: error
      type(stepper_checkpoint_t), intent(out), optional :: stepper
      integer(i8), allocatable, intent(out), optional :: counters(:)
    end subroutine open_resume

    !> End a run that reached `t_end`: flush and close the file (both checked), read it back and
    !> verify it (`verify_case_file`), and only then write status = 'finished' (written, flushed
    !> and closed, all checked). On error the file is closed and still says 'running'; `damaged`
    !> tells that the verification found the file itself bad (then it must not be resumed).
    !> `run`, the final record of the run segment (after `start_run`), replaces its /runs entry
    !> before the flush.
    module subroutine finish(this, t_end, error, damaged, run)
      class(case_file_t), intent(inout) :: this
      real(wp), intent(in) :: t_end
      type(error_t), allocatable, intent(out) :: error
      logical, intent(out) :: damaged
      type(run_record_t), intent(in), optional :: run
    end subroutine finish
  end interface

contains

  ! ---------------------------------------------------------------- creating

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
    if (.not. allocated(error)) call write_attributes(this%file, scene_attrs, error)
    if (.not. allocated(error)) call h5_write_attr(this%file, '/', 'chain.rotation', rotation, error)
    if (.not. allocated(error)) call create_frames(this%file, frame_template(n_beads, .false., .false.), error)
    if (.not. allocated(error)) call h5_flush(this%file, error)
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
  !> frame: from then on every frame must hold the run diagnostics.
  subroutine enable_diagnostics(this, error)
    class(case_file_t), intent(inout) :: this
    type(error_t), allocatable, intent(out) :: error
    call enable_part(this, 'diagnostics', 'diagnostics', .true., .false., error)
    if (allocated(error)) return
    this%diagnostics = .true.
    call h5_flush(this%file, error)
  end subroutine enable_diagnostics

  !> Create the (empty) /frames/stresslet datasets of a file just created, before its first
  !> frame: from then on every frame must hold the fibre's stresslet.
  subroutine enable_stresslet(this, error)
    class(case_file_t), intent(inout) :: this
    type(error_t), allocatable, intent(out) :: error
    call enable_part(this, 'stresslet', 'the stresslet', .false., .true., error)
    if (allocated(error)) return
    this%stresslet = .true.
    call h5_flush(this%file, error)
  end subroutine enable_stresslet

  !> Create the datasets of an optional part of /frames (`what`, `subject`: its names in the
  !> messages).
  subroutine enable_part(this, what, subject, diagnostics, stresslet, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: what, subject
    logical, intent(in) :: diagnostics, stresslet
    type(error_t), allocatable, intent(out) :: error
    if (.not. this%file%is_open()) then
      call fatal_error(error, 'case file: enable_'//what//' on a file that is not open')
      return
    end if
    if (this%nframes > 0) then
      call fatal_error(error, "case file '"//this%file%name()//"': "//subject//' must be enabled before the first frame')
      return
    end if
    call create_frames(this%file, frame_template(this%n_beads, diagnostics, stresslet), error)
  end subroutine enable_part

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

  ! ---------------------------------------------------------------- frames and checkpoints

  !> Append the frame `frame` (every /frames dataset of the table, kf_case_frames), write the
  !> checkpoint of this state and flush the file. A file with diagnostics (`enable_diagnostics`)
  !> needs frame%diagnostics, the run diagnostics after the frame's last step: its run totals
  !> (root attributes) and state (checkpoint) are written too; a file with the stresslet
  !> (`enable_stresslet`) needs frame%stresslet. `stepper`, the time stepper's state after the
  !> frame's last step, goes to the checkpoint's `stepper` group; `counters`, any run counters
  !> of the caller (e.g. the hydrodynamic model's work), to its `counters` dataset
  !> (`open_resume` returns both). The checkpoint is written to the slot the previous frame did
  !> not use (schema 3), so a kill or a failed write while it is written leaves the previous
  !> checkpoint whole. `run`, the record of the run segment after the frame (after
  !> `start_run`), replaces the segment's /runs entry and goes into the checkpoint.
  subroutine append_frame(this, frame, error, stepper, counters, run)
    class(case_file_t), intent(inout) :: this
    type(frame_t), intent(in) :: frame
    type(error_t), allocatable, intent(out) :: error
    type(stepper_checkpoint_t), intent(in), optional :: stepper
    integer(i8), intent(in), optional :: counters(:)
    type(run_record_t), intent(in), optional :: run
    type(checkpoint_t) :: ck
    character(len=:), allocatable :: reason
    if (.not. this%file%is_open()) then
      call fatal_error(error, 'case file: append_frame on a file that is not open')
      return
    end if
    reason = frame_refusal(frame, this%n_beads, this%diagnostics, this%stresslet, this%nframes, this%last_time)
    if (len(reason) == 0 .and. present(run) .and. .not. this%run_started) &
      reason = 'append_frame got a run record before start_run'
    if (len(reason) == 0 .and. present(stepper)) then
      if (.not. (allocated(stepper%name) .and. allocated(stepper%reals) .and. allocated(stepper%ints))) &
        reason = 'append_frame got an incomplete stepper state'
    end if
    if (len(reason) > 0) then
      call fatal_error(error, "case file '"//this%file%name()//"': "//reason)
      return
    end if
    call append_frames(this%file, frame, error)
    if (allocated(error)) return
    ! The frame reaches the disk before the checkpoint is touched: a write that fails here (full
    ! disk) leaves the previous checkpoint as it was, and a resume drops the partial frame.
    call h5_flush(this%file, error)
    if (allocated(error)) return
    this%nframes = this%nframes + 1
    this%last_time = frame%t
    if (allocated(frame%diagnostics)) then
      call write_diagnostics_totals(this%file, frame%diagnostics, error)
      if (allocated(error)) return
      ck%diag_counters = frame%diagnostics%state_counters
      ck%diag_values = frame%diagnostics%state_values
      ck%diag_ongoing = frame%diagnostics%state_ongoing
      call pad_columns(ck%diag_ongoing)
    end if
    ck%nframes = this%nframes
    ck%t = frame%t
    ck%r = frame%r
    ck%dt = frame%dt
    ck%steps = frame%steps
    ck%rejected = frame%rejected
    if (present(stepper)) ck%stepper = stepper
    if (present(counters)) ck%counters = counters
    if (present(run)) then
      this%runs(size(this%runs)) = run
      ck%run_counts = [size(this%runs, kind=i8), run%steps]
      ck%run_figures = [run%t_end, run%wall_seconds, run%load_mean]
    end if
    call write_slots(this%file, ck, error)
    if (.not. allocated(error) .and. present(run)) call write_run_figures(this%file, this%runs, error)
    if (allocated(error)) return
    call h5_flush(this%file, error)
    if (.not. allocated(error)) this%flushed_time = frame%t
  end subroutine append_frame

  ! ---------------------------------------------------------------- status, finishing

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

  ! ---------------------------------------------------------------- root attributes

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

  !> A logical as int32 1/0 (HDF5 has no boolean type).
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

end module kf_case_file
