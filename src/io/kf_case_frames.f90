!> The frames of a case file (/frames): the record of one frame (`frame_t`, filled by the run
!> layer, kf_frame_records) and the one table of its datasets (`frame_table`), from which
!> creating, appending, truncating (on a resume) and checking (verification) are all driven.
!>
!> The table names each dataset once, with its value in the record: the value's type is the
!> dataset's element kind (real(wp) float64, integer(i4) int32, integer(i8) int64) and its shape
!> the per-frame shape (a number, or a 2-D array: the positions (3, N), a 3 x 3 tensor). Every
!> dataset is chunked and extendible along the frame axis (kf_h5). A per-frame quantity is one
!> component of the record (or of the `shape_t` it holds, kf_shape) and one line of the table.
!>
!> The optional parts, /frames/diagnostics and /frames/stresslet, are written when the record
!> has them (its allocatable components allocated); a file has a part when its group exists.
module kf_case_frames
  use kf_kinds, only: wp, i4, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_shape, only: shape_t
  use kf_rheology, only: fibre_stresslet_t
  use kf_h5, only: h5_file_t, h5_exists, h5_create_extendible, h5_append, h5_set_length, h5_length, h5_read, &
    h5_write_attr, h5_real, h5_int32, h5_int64
  implicit none
  private

  public :: frame_template, file_frame_template, create_frames, append_frames, truncate_frames, check_frames, &
    frame_refusal, write_diagnostics_totals

  !> The datasets every reader needs (also read on their own: checkpoint, verification, readers).
  character(len=*), parameter, public :: frames_time = '/frames/time', frames_positions = '/frames/positions'
  !> The groups of the optional parts.
  character(len=*), parameter :: diagnostics_group = '/frames/diagnostics', stresslet_group = '/frames/stresslet'
  !> Frames per chunk of the positions (the other datasets: kf_h5's default).
  integer, parameter :: positions_chunk = 16

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

  !> One frame as the case file writes it (/frames): the state after the frame's last step.
  type, public :: frame_t
    real(wp) :: t = 0.0_wp                   !< model time
    real(wp), allocatable :: r(:, :)         !< positions (3, N)
    type(shape_t) :: observables             !< shape observables (kf_shape)
    integer(i8) :: steps = 0, rejected = 0   !< the stepper's counts since t = 0
    real(wp) :: dt = 0.0_wp                  !< the stepper's next step size
    !> Run diagnostics (allocated: the file has /frames/diagnostics)
    type(diagnostics_record_t), allocatable :: diagnostics
    !> The fibre's stresslet (allocated: the file has /frames/stresslet)
    type(fibre_stresslet_t), allocatable :: stresslet
  end type frame_t

  !> What is done with each line of the table: `visit` is called with the dataset's name and
  !> its value in the frame; the first error stops the visits.
  type, abstract :: frame_visitor_t
    type(h5_file_t) :: file
    type(error_t), allocatable :: error
  contains
    generic :: visit => visit_number, visit_array
    procedure(visit_number_i), deferred :: visit_number
    procedure(visit_array_i), deferred :: visit_array
  end type frame_visitor_t

  abstract interface
    !> A dataset of one number per frame (real(wp), integer(i4) or integer(i8)).
    subroutine visit_number_i(this, name, value)
      import :: frame_visitor_t
      class(frame_visitor_t), intent(inout) :: this
      character(len=*), intent(in) :: name
      class(*), intent(in) :: value
    end subroutine visit_number_i
    !> A dataset of one 2-D real array per frame, `chunk` frames per chunk (default: kf_h5's).
    subroutine visit_array_i(this, name, value, chunk)
      import :: frame_visitor_t, wp
      class(frame_visitor_t), intent(inout) :: this
      character(len=*), intent(in) :: name
      real(wp), intent(in) :: value(:, :)
      integer, intent(in), optional :: chunk
    end subroutine visit_array_i
  end interface

  !> Creates the datasets a file does not have yet.
  type, extends(frame_visitor_t) :: creator_t
  contains
    procedure :: visit_number => create_number
    procedure :: visit_array => create_array
  end type creator_t

  !> Appends the frame's values.
  type, extends(frame_visitor_t) :: appender_t
  contains
    procedure :: visit_number => append_number
    procedure :: visit_array => append_array
  end type appender_t

  !> Cuts every dataset to `nframes` (a dataset shorter than that is an error).
  type, extends(frame_visitor_t) :: truncator_t
    integer(i8) :: nframes = 0
  contains
    procedure :: visit_number => truncate_number
    procedure :: visit_array => truncate_array
  end type truncator_t

  !> Checks that every dataset holds `nframes` frames and reads back (checksums); the positions
  !> only by their length (the verification reads and checks them itself).
  type, extends(frame_visitor_t) :: checker_t
    integer(i8) :: nframes = 0
  contains
    procedure :: visit_number => check_number
    procedure :: visit_array => check_array
  end type checker_t

contains

  !> The table of /frames: one line per dataset, its name and its value in the frame `f`.
  !> A new per-frame quantity is one line here (and one component of the record); the schema
  !> is documented in docs/case-file.md.
  subroutine frame_table(v, f)
    class(frame_visitor_t), intent(inout) :: v
    type(frame_t), intent(in) :: f
    call v%visit(frames_time, f%t)
    call v%visit(frames_positions, f%r, chunk=positions_chunk)
    associate (s => f%observables)
      call v%visit('/frames/observables/rg', s%rg)
      call v%visit('/frames/observables/a', s%a)
      call v%visit('/frames/observables/b', s%b)
      call v%visit('/frames/observables/c', s%c)
      call v%visit('/frames/observables/theta', s%theta)
      call v%visit('/frames/observables/phi', s%phi)
      call v%visit('/frames/observables/close_pairs', int(s%close_pairs, i4))
    end associate
    call v%visit('/frames/integrator/steps', f%steps)
    call v%visit('/frames/integrator/rejected', f%rejected)
    call v%visit('/frames/integrator/dt', f%dt)
    if (allocated(f%diagnostics)) then
      associate (d => f%diagnostics)
        call v%visit(diagnostics_group//'/strand_passages', d%strand_passages)
        call v%visit(diagnostics_group//'/overlapping_pairs', int(d%overlapping_pairs, i4))
        call v%visit(diagnostics_group//'/overlap_episodes', d%overlap_episodes)
        call v%visit(diagnostics_group//'/min_distance', d%min_distance)
        call v%visit(diagnostics_group//'/max_bond_strain', d%max_bond_strain)
      end associate
    end if
    if (allocated(f%stresslet)) then
      associate (st => f%stresslet)
        call v%visit(stresslet_group//'/hydrodynamic', st%hydrodynamic)
        call v%visit(stresslet_group//'/elastic', st%elastic)
        call v%visit(stresslet_group//'/viscosity', st%viscosity)
        call v%visit(stresslet_group//'/psi1', st%psi1)
        call v%visit(stresslet_group//'/psi2', st%psi2)
      end associate
    end if
  end subroutine frame_table

  ! ---------------------------------------------------------------- operations on the table

  !> A frame of `n_beads` beads (zero positions) with the optional parts asked for: what
  !> `create_frames`, `truncate_frames` and `check_frames` take the datasets from.
  pure function frame_template(n_beads, diagnostics, stresslet) result(f)
    integer, intent(in) :: n_beads
    logical, intent(in) :: diagnostics, stresslet
    type(frame_t) :: f
    allocate (f%r(3, n_beads))
    f%r = 0.0_wp
    if (diagnostics) allocate (f%diagnostics)
    if (stresslet) allocate (f%stresslet)
  end function frame_template

  !> The template of the frames an open file holds: its optional parts are those whose group
  !> it has.
  function file_frame_template(file, n_beads) result(f)
    type(h5_file_t), intent(in) :: file
    integer, intent(in) :: n_beads
    type(frame_t) :: f
    f = frame_template(n_beads, h5_exists(file, diagnostics_group), h5_exists(file, stresslet_group))
  end function file_frame_template

  !> Create the (empty) datasets of the frame `f` that the file does not have yet.
  subroutine create_frames(file, f, error)
    type(h5_file_t), intent(in) :: file
    type(frame_t), intent(in) :: f
    type(error_t), allocatable, intent(out) :: error
    type(creator_t) :: v
    v%file = file
    call frame_table(v, f)
    if (allocated(v%error)) call move_alloc(v%error, error)
  end subroutine create_frames

  !> Append the frame `f` to every dataset it has (not flushed).
  subroutine append_frames(file, f, error)
    type(h5_file_t), intent(in) :: file
    type(frame_t), intent(in) :: f
    type(error_t), allocatable, intent(out) :: error
    type(appender_t) :: v
    v%file = file
    call frame_table(v, f)
    if (allocated(v%error)) call move_alloc(v%error, error)
  end subroutine append_frames

  !> Cut every dataset of the frames like `f` to `nframes` frames (a resume drops the frames
  !> beyond its checkpoint); a dataset with fewer frames is an error naming it.
  subroutine truncate_frames(file, f, nframes, error)
    type(h5_file_t), intent(in) :: file
    type(frame_t), intent(in) :: f
    integer(i8), intent(in) :: nframes
    type(error_t), allocatable, intent(out) :: error
    type(truncator_t) :: v
    v%file = file
    v%nframes = nframes
    call frame_table(v, f)
    if (allocated(v%error)) call move_alloc(v%error, error)
  end subroutine truncate_frames

  !> Check that every dataset of the frames like `f` holds `nframes` frames and reads back
  !> without a checksum error; the message names the first dataset that does not.
  subroutine check_frames(file, f, nframes, error)
    type(h5_file_t), intent(in) :: file
    type(frame_t), intent(in) :: f
    integer(i8), intent(in) :: nframes
    type(error_t), allocatable, intent(out) :: error
    type(checker_t) :: v
    v%file = file
    v%nframes = nframes
    call frame_table(v, f)
    if (allocated(v%error)) call move_alloc(v%error, error)
  end subroutine check_frames

  !> Why a file of `n_beads` beads, with the optional parts `diagnostics` and `stresslet` or
  !> without, holding `nframes` frames (the last at `last_time`), refuses the frame `f` ('' when
  !> it takes it): a part the file has missing or one it has not given, positions not of shape
  !> (3, n_beads), a time not after the last frame's, run diagnostics without their state.
  pure function frame_refusal(f, n_beads, diagnostics, stresslet, nframes, last_time) result(reason)
    type(frame_t), intent(in) :: f
    integer, intent(in) :: n_beads
    logical, intent(in) :: diagnostics, stresslet
    integer(i8), intent(in) :: nframes
    real(wp), intent(in) :: last_time
    character(len=:), allocatable :: reason
    reason = ''
    if (diagnostics .and. .not. allocated(f%diagnostics)) then
      reason = 'append_frame needs the run diagnostics'
    else if (allocated(f%diagnostics) .and. .not. diagnostics) then
      reason = 'append_frame got diagnostics but the file has none (enable_diagnostics)'
    else if (stresslet .and. .not. allocated(f%stresslet)) then
      reason = 'append_frame needs the stresslet'
    else if (allocated(f%stresslet) .and. .not. stresslet) then
      reason = 'append_frame got a stresslet but the file has none (enable_stresslet)'
    else if (.not. allocated(f%r)) then
      reason = 'append_frame got a frame without positions'
    else if (size(f%r, 1) /= 3 .or. size(f%r, 2) /= n_beads) then
      reason = 'frame positions do not have shape (3, n_beads)'
    else if (nframes > 0 .and. .not. f%t > last_time) then
      reason = 'frame time does not increase'
    else if (allocated(f%diagnostics)) then
      if (.not. (allocated(f%diagnostics%state_counters) .and. allocated(f%diagnostics%state_values) .and. &
                 allocated(f%diagnostics%state_ongoing))) reason = 'append_frame got run diagnostics without their state'
    end if
  end function frame_refusal

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

  ! ---------------------------------------------------------------- the visitors

  !> The element kind of a number of the table (0: a type the table does not use).
  integer function number_kind(value)
    class(*), intent(in) :: value
    select type (value)
    type is (real(wp))
      number_kind = h5_real
    type is (integer(i4))
      number_kind = h5_int32
    type is (integer(i8))
      number_kind = h5_int64
    class default
      number_kind = 0
    end select
  end function number_kind

  subroutine create_number(this, name, value)
    class(creator_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    class(*), intent(in) :: value
    if (allocated(this%error)) return
    if (h5_exists(this%file, name)) return
    if (number_kind(value) == 0) then
      call fatal_error(this%error, 'case file: /frames dataset '//name//' has a type the file cannot hold')
      return
    end if
    call h5_create_extendible(this%file, name, number_kind(value), [integer ::], this%error)
  end subroutine create_number

  subroutine create_array(this, name, value, chunk)
    class(creator_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value(:, :)
    integer, intent(in), optional :: chunk
    if (allocated(this%error)) return
    if (h5_exists(this%file, name)) return
    call h5_create_extendible(this%file, name, h5_real, shape(value), this%error, chunk)
  end subroutine create_array

  subroutine append_number(this, name, value)
    class(appender_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    class(*), intent(in) :: value
    if (allocated(this%error)) return
    select type (value)
    type is (real(wp))
      call h5_append(this%file, name, value, this%error)
    type is (integer(i4))
      call h5_append(this%file, name, value, this%error)
    type is (integer(i8))
      call h5_append(this%file, name, value, this%error)
    class default
      call fatal_error(this%error, 'case file: /frames dataset '//name//' has a type the file cannot hold')
    end select
  end subroutine append_number

  subroutine append_array(this, name, value, chunk)
    class(appender_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value(:, :)
    integer, intent(in), optional :: chunk
    real(wp), allocatable :: a(:, :)
    if (allocated(this%error)) return
    a = value
    call h5_append(this%file, name, a, this%error)
  end subroutine append_array

  subroutine truncate_number(this, name, value)
    class(truncator_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    class(*), intent(in) :: value
    call truncate(this, name)
  end subroutine truncate_number

  subroutine truncate_array(this, name, value, chunk)
    class(truncator_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value(:, :)
    integer, intent(in), optional :: chunk
    call truncate(this, name)
  end subroutine truncate_array

  subroutine truncate(this, name)
    class(truncator_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer(i8) :: length
    if (allocated(this%error)) return
    call h5_length(this%file, name, length, this%error)
    if (allocated(this%error)) return
    if (length < this%nframes) then
      call fatal_error(this%error, "case file '"//this%file%name()//"': dataset '"//name// &
        "' is shorter than the checkpoint's frame count")
      return
    end if
    if (length > this%nframes) call h5_set_length(this%file, name, this%nframes, this%error)
  end subroutine truncate

  subroutine check_number(this, name, value)
    class(checker_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    class(*), intent(in) :: value
    real(wp), allocatable :: values(:)
    integer(i4), allocatable :: ivalues(:)
    integer(i8), allocatable :: lvalues(:)
    if (.not. has_length(this, name)) return
    select case (number_kind(value))
    case (h5_real)
      call h5_read(this%file, name, values, this%error)
    case (h5_int32)
      call h5_read(this%file, name, ivalues, this%error)
    case default
      call h5_read(this%file, name, lvalues, this%error)
    end select
  end subroutine check_number

  subroutine check_array(this, name, value, chunk)
    class(checker_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value(:, :)
    integer, intent(in), optional :: chunk
    real(wp), allocatable :: values(:, :, :)
    if (.not. has_length(this, name)) return
    if (name /= frames_positions) call h5_read(this%file, name, values, this%error)
  end subroutine check_array

  !> Does the dataset `name` hold the checker's frame count (error set if not)?
  logical function has_length(this, name)
    class(checker_t), intent(inout) :: this
    character(len=*), intent(in) :: name
    integer(i8) :: length
    has_length = .false.
    if (allocated(this%error)) return
    call h5_length(this%file, name, length, this%error)
    if (allocated(this%error)) return
    if (length /= this%nframes) then
      call fatal_error(this%error, name//' has '//to_str(length)//' frames, the checkpoint '//to_str(this%nframes))
      return
    end if
    has_length = .true.
  end function has_length

end module kf_case_frames
