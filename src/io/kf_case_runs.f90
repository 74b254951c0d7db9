!> The run segments of a case file (/runs, schema 4 and later): one entry per segment (the
!> first start or a resume), one dataset per field (docs/case-file.md). The run layer fills the
!> records (kf_run_segment); the case file appends the segment's entry when it starts
!> (`replace_runs`), rewrites its changing figures with every frame (`write_run_figures`) and
!> restores the list to its checkpoint on a resume (`restored_runs`).
module kf_case_runs
  use kf_kinds, only: wp, i4, i8
  use kf_error, only: error_t, fatal_error
  use kf_h5, only: h5_file_t, h5_flush, h5_exists, h5_write, h5_read, h5_delete, h5_move
  implicit none
  private

  public :: replace_runs, write_run_figures, restored_runs, check_runs

  !> The /runs datasets, in the order of `run_record_t`: strings, int32, float64, int64.
  character(len=*), parameter :: runs_group = '/runs'
  !> `replace_runs` writes the longer list here first and then renames it to /runs, so a kill
  !> while the list grows never leaves it without a whole copy (`restored_runs` reads this one
  !> when /runs cannot be read).
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

contains

  !> Replace /runs by `runs` (a new segment's longer list): written whole to /runs_next and
  !> flushed, then /runs deleted and /runs_next renamed to it, so that a kill at any point
  !> leaves one whole list (`restored_runs`). Not flushed after the rename.
  subroutine replace_runs(file, runs, error)
    type(h5_file_t), intent(in) :: file
    type(run_record_t), intent(in) :: runs(:)
    type(error_t), allocatable, intent(out) :: error
    call h5_delete(file, runs_next_group, error)   ! a part written by a killed start
    if (.not. allocated(error)) call write_runs(file, runs_next_group, runs, error)
    if (.not. allocated(error)) call h5_flush(file, error)
    if (.not. allocated(error)) call h5_delete(file, runs_group, error)
    if (.not. allocated(error)) call h5_move(file, runs_next_group, runs_group, error)
  end subroutine replace_runs

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
    if (.not. allocated(error)) call write_figures(file, group, runs, error)
  end subroutine write_runs

  !> The /runs datasets that change during a segment (t_end, steps, wall_seconds, load_mean),
  !> rewritten in place with `runs`.
  subroutine write_run_figures(file, runs, error)
    type(h5_file_t), intent(in) :: file
    type(run_record_t), intent(in) :: runs(:)
    type(error_t), allocatable, intent(out) :: error
    call write_figures(file, runs_group, runs, error)
  end subroutine write_run_figures

  subroutine write_figures(file, group, runs, error)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: group
    type(run_record_t), intent(in) :: runs(:)
    type(error_t), allocatable, intent(out) :: error
    call h5_write(file, group//'/t_end', runs%t_end, error)
    if (.not. allocated(error)) call h5_write(file, group//'/steps', runs%steps, error)
    if (.not. allocated(error)) call h5_write(file, group//'/wall_seconds', runs%wall_seconds, error)
    if (.not. allocated(error)) call h5_write(file, group//'/load_mean', runs%load_mean, error)
  end subroutine write_figures

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
  !> from (`counts` = [entries, steps of the segment], `figures` = [t_end, wall_seconds,
  !> load_mean], as the checkpoint holds them, or unallocated): the entries the checkpoint
  !> counts, the last with the checkpoint's figures (a kill after the checkpoint may have left
  !> /runs ahead of or behind it). A file whose /runs cannot be read (a kill inside
  !> `replace_runs`) is read from /runs_next; a file without either, or whose lists cannot be
  !> read, starts a new list (the resume itself never fails for it); a checkpoint without run
  !> figures (written before they existed) keeps /runs as it is.
  function restored_runs(file, counts, figures) result(runs)
    type(h5_file_t), intent(in) :: file
    integer(i8), allocatable, intent(in) :: counts(:)
    real(wp), allocatable, intent(in) :: figures(:)
    type(run_record_t), allocatable :: runs(:)
    type(error_t), allocatable :: err
    logical :: equal, fix
    integer :: n
    fix = allocated(counts) .and. allocated(figures)
    if (fix) fix = size(counts) == 2 .and. size(figures) == 3
    if (fix) fix = counts(1) >= 1 .and. counts(1) <= huge(n)
    n = huge(n)
    if (fix) n = int(counts(1))
    if (h5_exists(file, runs_group)) call read_runs_table(file, runs_group, runs, equal, err, n)
    if (allocated(err) .or. .not. allocated(runs)) then
      if (h5_exists(file, runs_next_group)) then
        if (allocated(err)) deallocate (err)
        call read_runs_table(file, runs_next_group, runs, equal, err, n)
      end if
    end if
    if (allocated(err) .or. .not. allocated(runs)) then
      if (allocated(runs)) deallocate (runs)
      allocate (runs(0))
      return
    end if
    if (.not. fix .or. size(runs) /= n) return
    runs(n)%steps = counts(2)
    runs(n)%t_end = figures(1)
    runs(n)%wall_seconds = figures(2)
    runs(n)%load_mean = figures(3)
  end function restored_runs

  !> /runs (files of schema 4 and later; nothing to check without it): every dataset reads
  !> back, all of one length, at least 1.
  subroutine check_runs(file, error)
    type(h5_file_t), intent(in) :: file
    type(error_t), allocatable, intent(out) :: error
    type(run_record_t), allocatable :: runs(:)
    logical :: equal
    if (.not. h5_exists(file, runs_group)) return
    call read_runs_table(file, runs_group, runs, equal, error)
    if (allocated(error)) return
    if (.not. equal .or. size(runs) < 1) call fatal_error(error, runs_group// &
      ' does not hold one entry per run segment in every dataset')
  end subroutine check_runs

end module kf_case_runs
