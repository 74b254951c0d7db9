!> The ends of a run segment of a case file (kf_case_file's `case_file_t`): `start_run` (its
!> /runs entry), `open_resume` (continuing a file from its newest whole checkpoint: frames cut
!> back, damaged slot set aside, older layouts upgraded, /runs restored) and `finish` (read
!> back, verified, marked finished). What each does is said at its interface in kf_case_file.
submodule (kf_case_file) kf_case_segment
  use kf_h5, only: h5_open_file
  use kf_case_frames, only: file_frame_template, truncate_frames
  use kf_case_checkpoint, only: upgrade_checkpoint, remove_legacy_checkpoint, latest_checkpoint, set_aside
  use kf_case_runs, only: replace_runs, restored_runs
  use kf_case_verify, only: verify_case_file
  implicit none

contains

  module procedure start_run
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
    call replace_runs(this%file, this%runs, error)
    if (.not. allocated(error)) call h5_write_attr(this%file, '/', 'schema_version', case_schema_version, error)
    if (.not. allocated(error)) call h5_flush(this%file, error)
    if (.not. allocated(error)) this%run_started = .true.
  end procedure start_run

  module procedure open_resume
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
  end procedure open_resume

  subroutine resume(this, path, error)
    class(case_file_t), intent(inout) :: this
    character(len=*), intent(in) :: path
    type(error_t), allocatable, intent(out) :: error
    type(frame_t) :: kept
    integer(i4) :: n_beads
    character(len=:), allocatable :: damaged_slot
    logical :: legacy
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
    kept = file_frame_template(this%file, int(n_beads))
    this%diagnostics = allocated(kept%diagnostics)
    this%stresslet = allocated(kept%stresslet)
    call truncate_frames(this%file, kept, this%resumed%nframes, error)
    if (allocated(error)) return
    this%runs = restored_runs(this%file, this%resumed%run_counts, this%resumed%run_figures)
    call h5_write_attr(this%file, '/', 'status', status_value('running'), error)
    if (.not. allocated(error)) call h5_flush(this%file, error)
    if (allocated(error)) return
    this%n_beads = n_beads
    this%nframes = this%resumed%nframes
    this%last_time = this%resumed%t
    this%flushed_time = this%resumed%t
  end subroutine resume

  !> Give a file of schema 1 or 2, resumed from its single /checkpoint `ck`, the layout of this
  !> version: `ck` written to both slots, then schema_version, then the old checkpoint's parts
  !> removed, each step flushed (a kill in between leaves a file that reads as the old or as
  !> the new layout).
  subroutine upgrade_layout(file, ck, error)
    type(h5_file_t), intent(in) :: file
    type(checkpoint_t), intent(in) :: ck
    type(error_t), allocatable, intent(out) :: error
    call upgrade_checkpoint(file, ck, error)
    if (.not. allocated(error)) call h5_write_attr(file, '/', 'schema_version', case_schema_version, error)
    if (.not. allocated(error)) call h5_flush(file, error)
    if (.not. allocated(error)) call remove_legacy_checkpoint(file, error)
  end subroutine upgrade_layout

  module procedure finish
    character(len=:), allocatable :: path
    damaged = .false.
    path = this%file%name()
    if (present(run) .and. this%run_started) then
      this%runs(size(this%runs)) = run
      call write_run_figures(this%file, this%runs, error)
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
  end procedure finish

end submodule kf_case_segment
