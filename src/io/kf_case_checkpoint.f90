!> The checkpoint of a case file: the state after a frame, from which a run is resumed
!> (docs/case-file.md, /checkpoint).
!>
!> Files of schema 3 and later hold two slots, /checkpoint/slot0 and /checkpoint/slot1: the
!> checkpoint of frame count k is written to slot mod(k, 2), so the other slot keeps the
!> previous checkpoint whole while one is rewritten. A slot is written part by part, then its
!> digest, then its frame count (`write_slots`), and it is trusted only when its digest matches
!> its parts and it equals the frame it counts (time and positions: `latest_checkpoint`).
!> Files of schema 1 and 2 have a single checkpoint in /checkpoint (`upgrade_checkpoint` gives
!> them the slots).
module kf_case_checkpoint
  use, intrinsic :: iso_fortran_env, only: int8
  use kf_kinds, only: wp, i4, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_h5, only: h5_file_t, h5_open_file, h5_close_file, h5_flush, h5_exists, h5_attr_exists, h5_write_attr, &
    h5_read_attr, h5_write, h5_read, h5_read_entry, h5_delete, h5_move
  use kf_case_frames, only: frames_time, frames_positions
  implicit none
  private

  public :: write_slots, upgrade_checkpoint, remove_legacy_checkpoint, latest_checkpoint, set_aside, &
    checkpoint_frames, has_checkpoint, pad_columns, read_stepper

  !> The checkpoint slots of schema 3 (`slot_groups(mod(k, 2))` for frame count k) and the
  !> single checkpoint of schema 1 and 2.
  character(len=*), parameter :: slot_groups(0:1) = [character(len=17) :: '/checkpoint/slot0', &
    '/checkpoint/slot1']
  character(len=*), parameter :: legacy_group = '/checkpoint'

  !> The state of the time stepper in the checkpoint: the plain arrays of its `get_state` and
  !> the name of its method. Unallocated components: no stepper state.
  type, public :: stepper_checkpoint_t
    character(len=:), allocatable :: name
    real(wp), allocatable :: reals(:)
    integer(i8), allocatable :: ints(:)
  end type stepper_checkpoint_t

  !> One checkpoint: the state after frame `nframes`.
  type, public :: checkpoint_t
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

contains

  !> Write the checkpoint `ck` of frame count ck%nframes into its slot; the first checkpoint
  !> goes to both slots, so that their structure exists before any frame but the first could
  !> be lost. Not flushed.
  subroutine write_slots(file, ck, error)
    type(h5_file_t), intent(in) :: file
    type(checkpoint_t), intent(in) :: ck
    type(error_t), allocatable, intent(out) :: error
    if (ck%nframes == 1) call write_checkpoint(file, trim(slot_groups(0)), ck, error)
    if (.not. allocated(error)) call write_checkpoint(file, trim(slot_groups(mod(ck%nframes, 2_i8))), ck, error)
  end subroutine write_slots

  !> The first step of giving a file of schema 1 or 2, resumed from its single /checkpoint `ck`,
  !> the slots: `ck` written to both slots and flushed (then the caller marks the schema and
  !> calls `remove_legacy_checkpoint`).
  subroutine upgrade_checkpoint(file, ck, error)
    type(h5_file_t), intent(in) :: file
    type(checkpoint_t), intent(in) :: ck
    type(error_t), allocatable, intent(out) :: error
    call write_checkpoint(file, trim(slot_groups(0)), ck, error)
    if (.not. allocated(error)) call write_checkpoint(file, trim(slot_groups(1)), ck, error)
    if (.not. allocated(error)) call h5_flush(file, error)
  end subroutine upgrade_checkpoint

  !> Remove the parts of the single checkpoint of schema 1 and 2 (its slots are written).
  subroutine remove_legacy_checkpoint(file, error)
    type(h5_file_t), intent(in) :: file
    type(error_t), allocatable, intent(out) :: error
    character(len=*), parameter :: old_parts(11) = [character(len=11) :: 'time', 'positions', 'dt', &
      'steps', 'rejected', 'nframes', 'digest', 'stepper', 'counters', 'diagnostics', 'run']
    integer :: k
    do k = 1, size(old_parts)
      call h5_delete(file, legacy_group//'/'//trim(old_parts(k)), error)
      if (allocated(error)) return
    end do
  end subroutine remove_legacy_checkpoint

  !> The digest of a checkpoint's parts (an Adler-style pair of sums modulo a prime over their
  !> bytes): it tells whether parts read back were written by the same `write_checkpoint`. Parts
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
      call read_stepper(file, group//'/stepper', ck%stepper, error)
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

  !> The stepper's state in `group` (datasets reals and ints, attribute name): a checkpoint's
  !> and a stepper state file's (kf_stepper_state_file).
  subroutine read_stepper(file, group, stepper, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: group
    type(stepper_checkpoint_t), intent(out) :: stepper
    type(error_t), allocatable, intent(out) :: error
    call h5_read(file, group//'/reals', stepper%reals, error)
    if (.not. allocated(error)) call h5_read(file, group//'/ints', stepper%ints, error)
    if (.not. allocated(error)) call h5_read_attr(file, group, 'name', stepper%name, error)
  end subroutine read_stepper

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
    call h5_read(file, frames_time, times, error)
    if (allocated(error)) return
    if (size(times, kind=i8) < ck%nframes) then
      call fatal_error(error, frames_time//" is shorter than the checkpoint's frame count")
      return
    end if
    call h5_read_entry(file, frames_positions, ck%nframes, last, error)
    if (allocated(error)) return
    if (times(ck%nframes) /= ck%t .or. any(shape(last) /= shape(ck%r))) then
      call fatal_error(error, 'the checkpoint (t = '//to_str(ck%t, '(g0.6)')//') is not its last frame')
    else if (any(last /= ck%r)) then
      call fatal_error(error, 'the checkpoint (t = '//to_str(ck%t, '(g0.6)')//') is not its last frame')
    end if
  end subroutine check_last_frame

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

end module kf_case_checkpoint
