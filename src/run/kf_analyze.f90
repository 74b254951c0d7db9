!> The analyses of knotflow-analyze (docs/analysis.md), as a library: the program parses the
!> command line and calls one of them.
!> - `analyse_case_files`: HDF5 case files; writes /analysis of each (knots of the frames, events,
!>   knot matrices, shapes and modes), taking over what is stored with the same settings and, with
!>   `reuse`, the k_f of an earlier copy of the file;
!> - `analyse_coordinates`: one chain of a text coordinate file (k_f, spectrum, knot matrix);
!> - `analyse_table`: the case mode of a table of frame rows (a case ledger's CSV).
!> With several ranks every decision (an error, what is already stored) is taken once and shared,
!> so that the ranks always meet in the same collective call; rank 0 alone reads the stored
!> analysis, writes /analysis (holding the directory lock knotflow's sweeps take) and writes the
!> report lines to the unit it is given.
module kf_analyze
  use, intrinsic :: ieee_arithmetic, only: ieee_is_nan, ieee_is_finite
  use kf_kinds, only: wp, i8
  use kf_strings, only: to_str
  use kf_error, only: error_t, fatal_error
  use kf_knot_invariants, only: n_knot_types, knot_type_names
  use kf_knot_closure, only: knot_stats_t, analyse_closures, default_closures, default_knot_seed
  use kf_knot_matrix, only: knot_matrix, knot_core, is_slipknot, default_min_length, &
    default_matrix_closures, for_max_merge, after_max_merge
  use kf_text_coords, only: read_coordinates
  use kf_frame_table, only: read_table_columns
  use kf_modes, only: frame_mode, case_mode, long_time_start, mode_elongation, mode_none, mode_one, mode_two
  use kf_shape, only: shape_t
  use kf_analysis_farm, only: analysis_farm_t, farm_max, farm_sum, farm_share, farm_failed
  use kf_fs, only: lock_directory, parent_directory
  use kf_h5, only: h5_initialize, h5_finalize
  use kf_analysis_store, only: analysis_store_t, knots_record_t, matrix_record_t
  use kf_analysis_records, only: knots_record, events_record, shape_record
  use kf_knot_case, only: frame_knots_t, shape_analysis_t, select_frames, analyse_frame_knots, analyse_shapes, &
    stored_positions, merge_frame_knots, same_frames, frame_digests
  use kf_transitions, only: detect_transitions, default_low, default_high
  implicit none
  private

  !> The longest path an option holds.
  integer, parameter, public :: path_len = 1024

  !> The options of an analysis (knotflow-analyze's command line; docs/analysis.md).
  type, public :: analyze_options_t
    integer :: closures = default_closures
    integer(i8) :: seed = default_knot_seed
    logical :: matrix = .false.
    integer :: matrix_closures = default_matrix_closures
    integer :: min_length = default_min_length
    character(len=path_len) :: closure_points = ''
    logical :: json = .false.
    logical :: per_closure = .false.
    integer :: stride = 1
    character(len=path_len) :: matrix_frames = ''
    logical :: force = .false.
    character(len=path_len) :: reuse = ''   !< an earlier copy of the one case file
    logical :: reclassify = .false.         !< frame modes from the shapes with `elongation`
    real(wp) :: elongation = mode_elongation
  end type analyze_options_t

  public :: is_case_file, is_table, check_inputs, bad_option
  public :: analyse_case_files, analyse_coordinates, analyse_table

contains

  !> True for a case file (.h5, .hdf5).
  logical function is_case_file(path)
    character(len=*), intent(in) :: path
    integer :: n
    n = len_trim(path)
    is_case_file = .false.
    if (n >= 3) is_case_file = path(n - 2:n) == '.h5'
    if (n >= 5) is_case_file = is_case_file .or. path(n - 4:n) == '.hdf5'
  end function is_case_file

  !> True for a table of frame rows (.csv).
  logical function is_table(path)
    character(len=*), intent(in) :: path
    integer :: n
    n = len_trim(path)
    is_table = .false.
    if (n >= 4) is_table = path(n - 3:n) == '.csv'
  end function is_table

  !> Check the inputs and the options together: the kind of the first file (case files, a table of
  !> frame rows or a coordinate file) decides which options apply and whether more files may
  !> follow; --reuse names an existing case file other than the one analysed.
  subroutine check_inputs(files, opt, error)
    character(len=*), intent(in) :: files(:)
    type(analyze_options_t), intent(in) :: opt
    type(error_t), allocatable, intent(out) :: error
    integer :: i
    if (size(files) == 0) then
      call fatal_error(error, 'no input file given')
      return
    end if
    if (is_table(files(1))) then
      if (size(files) > 1 .or. opt%matrix .or. opt%per_closure .or. len_trim(opt%closure_points) > 0 .or. &
          opt%stride /= 1 .or. opt%force .or. len_trim(opt%matrix_frames) > 0 .or. len_trim(opt%reuse) > 0) then
        call fatal_error(error, 'a table of frame rows (.csv) is read alone, with --json and --elongation at most')
        return
      end if
    else if (opt%reclassify) then
      call fatal_error(error, 'option --elongation applies to a table of frame rows (.csv), not to '// &
        trim(files(1)))
      return
    else if (is_case_file(files(1))) then
      if (opt%matrix .or. opt%json .or. opt%per_closure .or. len_trim(opt%closure_points) > 0) then
        call fatal_error(error, 'options --matrix, --json, --per-closure and --closure-points apply to '// &
          'coordinate files, not to case files (use --matrix-frames for knot matrices)')
        return
      end if
      do i = 2, size(files)
        if (.not. is_case_file(files(i))) then
          call fatal_error(error, 'input '//trim(files(i))//': expected a case file (.h5) like '// &
            trim(files(1)))
          return
        end if
      end do
      if (len_trim(opt%reuse) > 0) call check_reuse(files, opt, error)
    else if (opt%stride /= 1 .or. opt%force .or. len_trim(opt%matrix_frames) > 0 .or. len_trim(opt%reuse) > 0) then
      call fatal_error(error, 'options --stride, --force, --matrix-frames and --reuse apply to case files (.h5), '// &
        'not to the coordinate file '//trim(files(1)))
      return
    else if (size(files) > 1) then
      call fatal_error(error, 'a coordinate file is analysed alone: got '//trim(files(2))//' as well')
      return
    end if
  end subroutine check_inputs

  !> Check the option --reuse OLD.h5: one case file, no --force, OLD an existing case file other than it.
  subroutine check_reuse(files, opt, error)
    character(len=*), intent(in) :: files(:)
    type(analyze_options_t), intent(in) :: opt
    type(error_t), allocatable, intent(out) :: error
    logical :: exists
    if (size(files) > 1 .or. opt%force) then
      call fatal_error(error, 'option --reuse '//trim(opt%reuse)//': takes the k_f of an earlier copy of '// &
        'one case file (allowed: one case file, without --force)')
      return
    end if
    if (.not. is_case_file(opt%reuse) .or. trim(opt%reuse) == trim(files(1))) then
      call bad_option(error, '--reuse', opt%reuse, 'a case file (.h5) other than '//trim(files(1)))
      return
    end if
    inquire (file=trim(opt%reuse), exist=exists)
    if (.not. exists) call bad_option(error, '--reuse', opt%reuse, 'an existing case file (not found)')
  end subroutine check_reuse

  !> The error for an invalid option value.
  subroutine bad_option(error, name, value, allowed)
    type(error_t), allocatable, intent(out) :: error
    character(len=*), intent(in) :: name, value, allowed
    call fatal_error(error, 'option '//trim(name)//': invalid value "'//trim(value)//'" (allowed: '// &
      allowed//')')
  end subroutine bad_option

  !> HDF5 case files: writes /analysis of each (the trajectory is never touched); rank 0
  !> writes a line per file to `unit`.
  !> Rank 0 first takes the directory lock of every directory holding a case file (the lock a
  !> knotflow sweep holds while it writes there): a directory being written is refused
  !> (`refused`) before anything is read or written.
  subroutine analyse_case_files(files, opt, farm, unit, refused, error)
    character(len=*), intent(in) :: files(:)
    type(analyze_options_t), intent(in) :: opt
    type(analysis_farm_t), intent(in) :: farm
    integer, intent(in) :: unit
    logical, intent(out) :: refused
    type(error_t), allocatable, intent(out) :: error
    integer :: ifile
    refused = .true.
    if (farm%rank == 0) call lock_directories(files, error)
    if (farm_failed(farm, error, 'the directory lock')) return
    refused = .false.
    call h5_initialize(error)
    if (farm_failed(farm, error, 'HDF5 start-up')) return
    do ifile = 1, size(files)
      call analyse_case(trim(files(ifile)), opt, farm, unit, error)
      if (farm_failed(farm, error, 'case file '//trim(files(ifile)))) return
    end do
    call h5_finalize(error)
  end subroutine analyse_case_files

  !> Lock each distinct directory of the case files once (a second lock of the same directory by
  !> this process would be refused: flock locks belong to the open file).
  subroutine lock_directories(files, error)
    character(len=*), intent(in) :: files(:)
    type(error_t), allocatable, intent(out) :: error
    character(len=len(files)), allocatable :: dirs(:)
    integer :: i, ndirs
    allocate (dirs(size(files)))
    ndirs = 0
    do i = 1, size(files)
      if (any(dirs(1:ndirs) == parent_directory(files(i)))) cycle
      ndirs = ndirs + 1
      dirs(ndirs) = parent_directory(files(i))
      call lock_directory(trim(dirs(ndirs)), error)
      if (allocated(error)) then
        error%message = 'directory '''//trim(dirs(ndirs))//''' of '//trim(files(i))//': '//error%message
        return
      end if
    end do
  end subroutine lock_directories

  !> Analyse one case file. Every rank reads the frames; rank 0 alone reads what a previous run
  !> stored and decides what is left to compute (shared with the others), and writes /analysis.
  !> Rank 0 opens the file once to read and once to write; the others open it once to read.
  subroutine analyse_case(path, opt, farm, unit, error)
    character(len=*), intent(in) :: path
    type(analyze_options_t), intent(in) :: opt
    type(analysis_farm_t), intent(in) :: farm
    integer, intent(in) :: unit
    type(error_t), allocatable, intent(out) :: error
    type(analysis_store_t) :: store
    type(error_t), allocatable :: close_error
    real(wp), allocatable :: t(:), r(:, :, :)
    call store%open(path, error)
    if (.not. allocated(error)) call store%read_frames(t, r, error)
    if (farm%rank /= 0) call store%close()
    if (.not. farm_failed(farm, error, 'case file '//path)) call analyse_frames(path, t, r, store, opt, farm, unit, error)
    if (farm%rank /= 0) return
    call store%close(close_error)
    if (.not. allocated(error) .and. allocated(close_error)) call move_alloc(close_error, error)
  end subroutine analyse_case

  !> The analysis of the frames t, r of the case file `path` (`store`, open on rank 0).
  subroutine analyse_frames(path, t, r, store, opt, farm, unit, error)
    character(len=*), intent(in) :: path
    real(wp), intent(in) :: t(:), r(:, :, :)
    type(analysis_store_t), intent(inout) :: store
    type(analyze_options_t), intent(in) :: opt
    type(analysis_farm_t), intent(in) :: farm
    integer, intent(in) :: unit
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: flat(:)
    integer(i8), allocatable :: todo(:), need(:), mframes(:), compute(:)
    integer, allocatable :: ev_kind(:), ev_pos(:), pos_of(:)
    type(frame_knots_t) :: fresh, all
    type(knots_record_t) :: prev, krec
    type(shape_analysis_t) :: shapes
    type(matrix_record_t), allocatable :: mats(:)
    logical :: found
    integer :: nframes, n, k, carried
    nframes = size(t)
    if (nframes < 1) call fatal_error(error, 'case file '//path//': /frames is empty (nothing to analyse)')
    if (.not. allocated(error)) call matrix_frame_list(opt%matrix_frames, nframes, path, mframes, error)
    if (farm_failed(farm, error, 'case file '//path)) return
    n = size(r, 2)
    todo = select_frames(nframes, opt%stride)
    ! Rank 0: the stored k_f (pos_of(k) = position of todo(k) among them, 0 if absent), the
    ! frames still to do (need) and the knot matrices still to compute (compute(k) = 1).
    allocate (need(0), compute(size(mframes)), mats(size(mframes)), pos_of(size(todo)))
    compute = 1
    if (farm%rank == 0) then
      if (opt%force) then
        allocate (prev%frame_index(0), prev%kf(0), prev%spectrum(0, 0))
      else
        call store%read_knots(int(opt%closures, i8), opt%seed, prev, found, error)
      end if
      if (.not. allocated(error)) call drop_changed_frames(path, t, r, prev, unit)
      carried = 0
      if (.not. allocated(error) .and. len_trim(opt%reuse) > 0) &
        call carry_stored(trim(opt%reuse), t, r, opt, prev, carried, error)
      if (.not. allocated(error)) then
        pos_of = stored_positions(todo, prev%frame_index)
        need = pack(todo, pos_of == 0)
      end if
      do k = 1, size(mframes)
        if (opt%force .or. allocated(error)) exit
        call store%read_matrix(mframes(k), int(opt%matrix_closures, i8), int(opt%min_length, i8), mats(k), &
                               found, error)
        if (.not. allocated(error) .and. found) compute(k) = 0
      end do
    end if
    if (farm_failed(farm, error, 'case file '//path)) return
    call farm_share(farm, need, error)
    if (.not. allocated(error)) call farm_share(farm, compute, error)
    if (allocated(error)) return
    call analyse_frame_knots(r, t, need, opt%closures, opt%seed, fresh, error, part=farm%rank, nparts=farm%size)
    if (farm_failed(farm, error, 'case file '//path)) return
    call farm_sum(farm, fresh%kf, error)
    if (allocated(error)) return
    flat = reshape(fresh%spectrum, [size(fresh%spectrum)])
    call farm_sum(farm, flat, error)
    if (allocated(error)) return
    fresh%spectrum = reshape(flat, shape(fresh%spectrum))
    ! knot matrices not stored yet: computed by all ranks
    do k = 1, size(mframes)
      if (compute(k) == 0) cycle
      mats(k) = matrix_record_t(frame=mframes(k), closures=int(opt%matrix_closures, i8), &
                                min_length=int(opt%min_length, i8), &
                                time=t(mframes(k) + 1))
      allocate (mats(k)%k(n, n))
      call knot_matrix(r(:, :, mframes(k) + 1), opt%matrix_closures, opt%seed, opt%min_length, mats(k)%k, &
                       error, part=farm%rank, nparts=farm%size)
      if (farm_failed(farm, error, 'case file '//path)) return
      call merge_matrix(farm, mats(k)%k, error)
      if (allocated(error)) return
    end do
    if (farm%rank /= 0) return
    ! rank 0: merge previous and fresh results in the order of todo, and write
    call merge_frame_knots(todo, t, pos_of, prev%kf, prev%spectrum, fresh, all)
    call detect_transitions(all%kf, default_low, default_high, ev_kind, ev_pos)
    call analyse_shapes(r, t, shapes, error)
    if (.not. allocated(error)) then
      krec = knots_record(all, opt%closures, opt%seed)
      krec%frame_digest = frame_digests(all%frame_index, t, r)
      call store%write(krec, events_record(all, ev_kind, ev_pos), mats, shape_record(shapes), error)
    end if
    if (.not. allocated(error)) write (unit, '(a,i0,a,i0,a,i0,a)') trim(path)//': ', size(todo), &
      ' frames (', size(need), ' new), ', size(ev_kind), ' events written to /analysis'
    if (.not. allocated(error) .and. len_trim(opt%reuse) > 0) write (unit, '(a,i0,a)') &
      trim(path)//': k_f of ', carried, ' frame(s) taken from '//trim(opt%reuse)
  end subroutine analyse_frames

  !> Keep of the stored frame knots `prev` only those whose frame is still the same: its time and
  !> (when the file stores digests) its positions' digest (a resumed run may have rewritten the
  !> frames after its checkpoint, and /frames may have been changed otherwise); a line tells how
  !> many were dropped, which are then computed again.
  subroutine drop_changed_frames(path, t, r, prev, unit)
    character(len=*), intent(in) :: path
    real(wp), intent(in) :: t(:), r(:, :, :)
    type(knots_record_t), intent(inout) :: prev
    integer, intent(in) :: unit
    logical, allocatable :: keep(:)
    integer(i8), allocatable :: now(:)
    integer :: m
    allocate (keep(size(prev%frame_index)))
    keep = prev%frame_index >= 0 .and. prev%frame_index < size(t)
    if (size(prev%time) == size(keep)) then
      do m = 1, size(keep)
        if (keep(m)) keep(m) = prev%time(m) == t(prev%frame_index(m) + 1)
      end do
    end if
    if (allocated(prev%frame_digest)) then
      if (size(prev%frame_digest) == size(keep)) then
        allocate (now(size(keep)))
        now = frame_digests(merge(prev%frame_index, 0_i8, keep), t, r)
        keep = keep .and. prev%frame_digest == now
      end if
      deallocate (prev%frame_digest)
    end if
    if (all(keep)) return
    write (unit, '(a,i0,a)') trim(path)//': k_f stored for ', count(.not. keep), &
      ' frame(s) whose time or positions changed since: computed again'
    prev%frame_index = pack(prev%frame_index, keep)
    if (size(prev%time) == size(keep)) prev%time = pack(prev%time, keep)
    prev%kf = pack(prev%kf, keep)
    prev%spectrum = prev%spectrum(:, pack([(m, m=1, size(keep))], keep))
  end subroutine drop_changed_frames

  !> For --reuse, add to `prev` the k_f and spectra that the case file `old` stores with the same
  !> closures and seed for frames that are the same here (kf_knot_case `same_frames`: each
  !> frame's closures depend only on the seed and the frame's index and positions, so these are
  !> the values a computation here would give) and that `prev` does not hold yet; n: how many.
  subroutine carry_stored(old, t, r, opt, prev, n, error)
    character(len=*), intent(in) :: old
    real(wp), intent(in) :: t(:), r(:, :, :)
    type(analyze_options_t), intent(in) :: opt
    type(knots_record_t), intent(inout) :: prev
    integer, intent(out) :: n
    type(error_t), allocatable, intent(out) :: error
    type(analysis_store_t) :: store
    type(knots_record_t) :: rec
    type(error_t), allocatable :: close_error
    real(wp), allocatable :: t_old(:), r_old(:, :, :), sp(:, :)
    logical, allocatable :: keep(:)
    integer, allocatable :: idx(:)
    logical :: found
    integer :: m, np
    n = 0
    call store%open(old, error)
    if (.not. allocated(error)) call store%read_frames(t_old, r_old, error)
    if (.not. allocated(error)) call store%read_knots(int(opt%closures, i8), opt%seed, rec, found, error)
    call store%close(close_error)
    if (.not. allocated(error) .and. allocated(close_error)) call move_alloc(close_error, error)
    if (allocated(error)) then
      error%message = '--reuse '//old//': '//error%message
      return
    end if
    if (.not. found) return
    keep = same_frames(rec%frame_index, t_old, r_old, t, r)
    keep = keep .and. stored_positions(rec%frame_index, prev%frame_index) == 0
    n = count(keep)
    if (n == 0) return
    idx = pack([(m, m=1, size(keep))], keep)
    np = size(prev%frame_index)
    allocate (sp(size(rec%spectrum, 1), np + n))
    if (np > 0) sp(:, :np) = prev%spectrum
    sp(:, np + 1:) = rec%spectrum(:, idx)
    call move_alloc(sp, prev%spectrum)
    prev%frame_index = [prev%frame_index, rec%frame_index(idx)]
    prev%time = [prev%time, rec%time(idx)]
    prev%kf = [prev%kf, rec%kf(idx)]
  end subroutine carry_stored

  !> Merge the partial knot matrices of the ranks (NaN where a rank computed nothing).
  subroutine merge_matrix(farm, k, error)
    type(analysis_farm_t), intent(in) :: farm
    real(wp), intent(inout) :: k(:, :)
    type(error_t), allocatable, intent(out) :: error
    real(wp) :: flat(size(k))
    flat = for_max_merge(reshape(k, [size(k)]))
    call farm_max(farm, flat, error)
    if (allocated(error)) return
    k = reshape(after_max_merge(flat), shape(k))
  end subroutine merge_matrix

  !> The frames of --matrix-frames ('' none, 'last', or a comma-separated list), checked.
  subroutine matrix_frame_list(spec, nframes, path, frames, error)
    character(len=*), intent(in) :: spec, path
    integer, intent(in) :: nframes
    integer(i8), allocatable, intent(out) :: frames(:)
    type(error_t), allocatable, intent(out) :: error
    integer :: i, j, k, stat
    integer(i8) :: v
    allocate (frames(0))
    if (len_trim(spec) == 0) return
    i = 1
    do while (i <= len_trim(spec))
      j = index(spec(i:), ',')
      k = merge(len_trim(spec), i + j - 2, j == 0)
      if (k >= i .and. spec(i:max(i, k)) == 'last') then
        frames = [frames, int(nframes - 1, i8)]
        i = k + 2
        cycle
      end if
      read (spec(i:max(i, k)), *, iostat=stat) v
      if (stat /= 0 .or. k < i) then
        call fatal_error(error, 'option --matrix-frames: invalid value "'//trim(spec)// &
          '" (allowed: "last" or frame numbers 0..'//to_str(nframes - 1)//')')
        return
      end if
      if (v < 0 .or. v >= nframes) then
        call fatal_error(error, 'option --matrix-frames: frame '//spec(i:k)//' is not in '//path// &
          ' (allowed: 0..'//to_str(nframes - 1)//')')
        return
      end if
      frames = [frames, v]
      i = k + 2
    end do
  end subroutine matrix_frame_list

  !> One chain from the text coordinate file `path`; rank 0 writes the report to `unit`.
  subroutine analyse_coordinates(path, opt, farm, unit, error)
    character(len=*), intent(in) :: path
    type(analyze_options_t), intent(in) :: opt
    type(analysis_farm_t), intent(in) :: farm
    integer, intent(in) :: unit
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: r(:, :), pts(:, :), kmat(:, :)
    type(knot_stats_t) :: st
    integer :: core(2), n
    logical :: found, slip
    call read_coordinates(path, r, error)
    if (.not. allocated(error) .and. len_trim(opt%closure_points) > 0) &
      call read_coordinates(opt%closure_points, pts, error)
    if (farm_failed(farm, error, trim(path))) return
    n = size(r, 2)
    if (len_trim(opt%closure_points) > 0) then
      call analyse_closures(r, size(pts, 2), opt%seed, st, error, points=pts, per_closure=.true.)
    else
      call analyse_closures(r, opt%closures, opt%seed, st, error, per_closure=.true.)
    end if
    if (farm_failed(farm, error, trim(path))) return
    found = .false.
    slip = .false.
    if (opt%matrix) then
      allocate (kmat(n, n))
      call knot_matrix(r, opt%matrix_closures, opt%seed, opt%min_length, kmat, error, &
                       part=farm%rank, nparts=farm%size)
      if (farm_failed(farm, error, trim(path))) return
      call merge_matrix(farm, kmat, error)
      if (allocated(error)) return
      call knot_core(kmat, core, found)
      slip = is_slipknot(kmat, st%kf)
    end if
    if (farm%rank /= 0) return
    if (opt%json) then
      call print_json(path, opt, unit, n, st, kmat, found, core, slip)
    else
      call print_text(path, opt, unit, n, st, found, core, slip)
    end if
  end subroutine analyse_coordinates

  !> The human-readable report of one chain.
  subroutine print_text(path, opt, unit, n, st, found, core, slip)
    character(len=*), intent(in) :: path
    type(analyze_options_t), intent(in) :: opt
    integer, intent(in) :: unit
    integer, intent(in) :: n, core(2)
    type(knot_stats_t), intent(in) :: st
    logical, intent(in) :: found, slip
    integer :: k, i
    write (unit, '(a,a)') 'file:      ', trim(path)
    write (unit, '(a,i0)') 'beads:     ', n
    write (unit, '(a,i0,a,i0)') 'closures:  ', st%closures, '   seed: ', st%seed
    write (unit, '(a,f8.4)') 'k_f:       ', st%kf
    write (unit, '(a)') 'spectrum:'
    do k = 1, n_knot_types
      if (st%spectrum(k) > 0.0_wp) write (unit, '(4x,a6,f8.4)') knot_type_names(k), st%spectrum(k)
    end do
    write (unit, '(a,a)') 'dominant:  ', trim(knot_type_names(st%dominant))
    if (opt%per_closure) then
      write (unit, '(a)') 'per closure:'
      write (unit, '(10(1x,a5))') (knot_type_names(st%per_closure(i)), i=1, st%closures)
    end if
    if (opt%matrix) then
      write (unit, '(a,i0,a,i0)') 'knot matrix: closures per subchain ', opt%matrix_closures, &
          ', min length ', opt%min_length
      if (found) then
        write (unit, '(a,i0,a,i0,a)') 'knot core: beads ', core(1), '..', core(2), ' (0-based)'
      else
        write (unit, '(a)') 'knot core: none'
      end if
      write (unit, '(a,l1)') 'slipknot:  ', slip
    end if
  end subroutine print_text

  !> The JSON object of one chain (the convention shared with knotflow-kf).
  subroutine print_json(path, opt, unit, n, st, kmat, found, core, slip)
    character(len=*), intent(in) :: path
    type(analyze_options_t), intent(in) :: opt
    integer, intent(in) :: unit
    integer, intent(in) :: n, core(2)
    type(knot_stats_t), intent(in) :: st
    real(wp), allocatable, intent(in) :: kmat(:, :)
    logical, intent(in) :: found, slip
    character(len=:), allocatable :: s
    integer :: k, i, j
    s = '{"n_beads": '//to_str(int(n, i8))//', "closures": '//to_str(int(st%closures, i8))// &
        ', "seed": '//to_str(st%seed)//', "kf": '//to_str(st%kf, '(es23.16e2)')//', "spectrum": {'
    do k = 1, n_knot_types
      s = s//'"'//trim(knot_type_names(k))//'": '//to_str(st%spectrum(k), '(es23.16e2)')
      if (k < n_knot_types) s = s//', '
    end do
    s = s//'}, "dominant": "'//trim(knot_type_names(st%dominant))//'"'
    if (opt%per_closure) then
      s = s//', "per_closure": ['
      do k = 1, st%closures
        s = s//'"'//trim(knot_type_names(st%per_closure(k)))//'"'
        if (k < st%closures) s = s//', '
      end do
      s = s//']'
    end if
    if (opt%matrix) then
      s = s//', "matrix": ['
      do i = 1, n
        s = s//'['
        do j = 1, n
          if (ieee_is_nan(kmat(i, j))) then
            s = s//'null'
          else
            s = s//to_str(kmat(i, j), '(es23.16e2)')
          end if
          if (j < n) s = s//', '
        end do
        s = s//']'
        if (i < n) s = s//', '
      end do
      s = s//']'
    end if
    if (found) then
      s = s//', "knot_core": ['//to_str(int(core(1), i8))//', '//to_str(int(core(2), i8))//']'
    else
      s = s//', "knot_core": null'
    end if
    s = s//', "slipknot": '//merge('true ', 'false', slip)
    s = trim(s)//'}'
    write (unit, '(a)') s
  end subroutine print_json

  !> The case mode of frame rows (columns `mode`, the mode of each frame, and `phi`;
  !> every frame in time order), by the one rule of kf_modes: the whole case's long-time mode
  !> when its frames come from several runs (the case ledger). With --elongation the frame modes
  !> are classified again from the columns a, b, c, theta, phi and close_pairs with that a/b
  !> threshold. Every rank reads; rank 0 prints, with the frames of each mode (all and the
  !> long-time half that the case mode counts).
  subroutine analyse_table(path, opt, farm, unit, error)
    character(len=*), intent(in) :: path
    type(analyze_options_t), intent(in) :: opt
    type(analysis_farm_t), intent(in) :: farm
    integer, intent(in) :: unit
    type(error_t), allocatable, intent(out) :: error
    real(wp), allocatable :: v(:, :), phi(:)
    integer, allocatable :: modes(:)
    integer :: mode, k, late
    character(len=:), allocatable :: counts, late_counts, rule
    if (opt%reclassify) then
      call frame_modes_from_shapes(path, opt%elongation, modes, phi, error)
      if (allocated(error)) return
    else
      call read_table_columns(path, [character(len=4) :: 'mode', 'phi'], v, error)
      if (allocated(error)) return
      do k = 1, size(v, 1)
        if (ieee_is_nan(v(k, 1)) .or. ieee_is_nan(v(k, 2)) .or. &
            .not. any(v(k, 1) == [real(wp) :: mode_none, mode_one, mode_two])) then
          call fatal_error(error, "table '"//trim(path)//"' row "//to_str(k)//': mode '// &
            to_str(v(k, 1), '(g0.6)')//', phi '//to_str(v(k, 2), '(g0.6)')// &
            ' (allowed: mode 0, 1 or 2 and a number for phi)')
          return
        end if
      end do
      modes = nint(v(:, 1))
      phi = v(:, 2)
    end if
    mode = case_mode(modes, phi)
    if (farm%rank /= 0) return
    late = long_time_start(size(modes))
    counts = mode_counts(modes)
    late_counts = mode_counts(modes(late:))
    if (opt%json) then
      write (unit, '(a)') '{"file": "'//trim(path)//'", "frames": '//to_str(size(modes))// &
        ', "case_mode": '//to_str(mode)//', "mode_frames": ['//counts//'], "late_mode_frames": ['// &
        late_counts//'], "elongation": '//to_str(opt%elongation, '(g0.6)')//'}'
    else
      rule = ''
      if (opt%reclassify) rule = ', classified again with a/b >= '//to_str(opt%elongation, '(g0.6)')
      write (unit, '(a)') trim(path)//': '//to_str(size(modes))//' frames, case mode '// &
        to_str(mode)//'; frames of no mode, mode I, mode II: '//counts//' (from frame '//to_str(late)// &
        ': '//late_counts//')'//rule
    end if
  end subroutine analyse_table

  !> "n0, n1, n2": the frames of no mode, mode I and mode II.
  function mode_counts(modes) result(text)
    integer, intent(in) :: modes(:)
    character(len=:), allocatable :: text
    text = to_str(count(modes == mode_none))//', '//to_str(count(modes == mode_one))//', '// &
      to_str(count(modes == mode_two))
  end function mode_counts

  !> The modes of frame rows classified again from their shape columns with the a/b threshold
  !> `elongation`, and their phi. Refused: a row with a value that is not a number, a negative
  !> semi-axis, or close_pairs that is not a whole number >= 0.
  subroutine frame_modes_from_shapes(path, elongation, modes, phi, error)
    character(len=*), intent(in) :: path
    real(wp), intent(in) :: elongation
    integer, allocatable, intent(out) :: modes(:)
    real(wp), allocatable, intent(out) :: phi(:)
    type(error_t), allocatable, intent(out) :: error
    character(len=*), parameter :: names(6) = [character(len=11) :: 'a', 'b', 'c', 'theta', 'phi', 'close_pairs']
    real(wp), allocatable :: v(:, :)
    type(shape_t), allocatable :: s(:)
    integer :: k
    call read_table_columns(path, names, v, error)
    if (allocated(error)) return
    do k = 1, size(v, 1)
      if (.not. all(ieee_is_finite(v(k, :))) .or. any(v(k, 1:3) < 0.0_wp) .or. v(k, 6) < 0.0_wp .or. &
          v(k, 6) /= aint(v(k, 6)) .or. v(k, 6) > real(huge(0), wp)) then
        call fatal_error(error, "table '"//trim(path)//"' row "//to_str(k)//': a '//to_str(v(k, 1), '(g0.6)')// &
          ', b '//to_str(v(k, 2), '(g0.6)')//', c '//to_str(v(k, 3), '(g0.6)')//', theta '// &
          to_str(v(k, 4), '(g0.6)')//', phi '//to_str(v(k, 5), '(g0.6)')//', close_pairs '// &
          to_str(v(k, 6), '(g0.6)')//' (allowed: finite numbers, semi-axes >= 0, close_pairs a whole number >= 0)')
        return
      end if
    end do
    allocate (s(size(v, 1)))
    s%a = v(:, 1)
    s%b = v(:, 2)
    s%c = v(:, 3)
    s%theta = v(:, 4)
    s%phi = v(:, 5)
    s%close_pairs = nint(v(:, 6))
    modes = frame_mode(s, elongation)
    phi = v(:, 5)
  end subroutine frame_modes_from_shapes

end module kf_analyze
