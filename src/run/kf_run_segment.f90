!> A run segment of a case (its first start or one resume) as the case file records it in
!> /runs (kf_case_runs' run_record_t): who ran it (commit, host, BLAS library and kernels, MPI
!> ranks, BLAS threads), when
!> (start in UTC), how far (model time, steps) and at what cost (wall time; the machine's
!> 1-minute load average at the start and its mean over the start and every checkpoint).
!> What the platform cannot tell is recorded as NaN (load) or 'unknown' (host, start time).
module kf_run_segment
  use, intrinsic :: iso_fortran_env, only: int64
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_nan
  use kf_kinds, only: wp, i8
  use kf_error, only: error_t
  use kf_build_info, only: knotflow_git_hash
  use kf_platform, only: load_average, host_name, utc_now
  use kf_case_runs, only: run_record_t
  implicit none
  private

  !> How the program launched the case: the MPI ranks of the sweep, the BLAS threads of the
  !> rank (kf_blas_threads' blas_threads_in_use; 0: not known) and the BLAS library with its
  !> kernels (kf_blas_threads' blas_library).
  type, public :: run_launch_t
    integer :: ranks = 1
    integer :: threads = 0
    character(len=:), allocatable :: blas
  end type run_launch_t

  !> The segment being run: its record and what its figures are computed from.
  type, public :: run_segment_t
    private
    type(run_record_t) :: rec
    integer(int64) :: clock0 = 0, rate = 1
    integer(i8) :: steps0 = 0
    real(wp) :: load_sum = 0.0_wp
    integer :: load_samples = 0
  contains
    !> begin(launch): the segment starts now (clock, UTC time, host, load).
    procedure :: begin => segment_begin
    !> place(t, steps): the model time and the stepper's step count it starts from.
    procedure :: place => segment_place
    !> sample_load(): one more load sample (at a checkpoint) for the mean.
    procedure :: sample_load => segment_sample_load
    !> record(t, steps): the segment's record now, at model time t after `steps` steps in all.
    procedure :: record => segment_record
  end type run_segment_t

contains

  !> The machine's 1-minute load average, NaN where the platform cannot tell.
  function machine_load() result(load)
    real(wp) :: load
    type(error_t), allocatable :: error
    call load_average(load, error)
    if (allocated(error)) load = ieee_value(load, ieee_quiet_nan)
  end function machine_load

  subroutine segment_begin(this, launch)
    class(run_segment_t), intent(inout) :: this
    type(run_launch_t), intent(in) :: launch
    type(error_t), allocatable :: error
    call system_clock(this%clock0, this%rate)
    this%rec%commit = knotflow_git_hash
    call utc_now(this%rec%started, error)
    if (allocated(error)) then
      this%rec%started = 'unknown'
      deallocate (error)
    end if
    call host_name(this%rec%host, error)
    if (allocated(error)) this%rec%host = 'unknown'
    this%rec%blas = 'unknown'
    if (allocated(launch%blas)) this%rec%blas = launch%blas
    this%rec%ranks = launch%ranks
    this%rec%threads = launch%threads
    this%rec%load_start = machine_load()
    this%load_sum = 0.0_wp
    this%load_samples = 0
    call add_sample(this, this%rec%load_start)
    this%rec%t_start = 0.0_wp
    this%rec%t_end = 0.0_wp
    this%steps0 = 0
  end subroutine segment_begin

  subroutine segment_place(this, t, steps)
    class(run_segment_t), intent(inout) :: this
    real(wp), intent(in) :: t
    integer(i8), intent(in) :: steps
    this%rec%t_start = t
    this%rec%t_end = t
    this%steps0 = steps
  end subroutine segment_place

  subroutine segment_sample_load(this)
    class(run_segment_t), intent(inout) :: this
    call add_sample(this, machine_load())
  end subroutine segment_sample_load

  !> NaN samples (load unknown) do not count; the mean of none is NaN.
  subroutine add_sample(this, load)
    type(run_segment_t), intent(inout) :: this
    real(wp), intent(in) :: load
    if (ieee_is_nan(load)) return
    this%load_sum = this%load_sum + load
    this%load_samples = this%load_samples + 1
  end subroutine add_sample

  function segment_record(this, t, steps) result(rec)
    class(run_segment_t), intent(in) :: this
    real(wp), intent(in) :: t
    integer(i8), intent(in) :: steps
    type(run_record_t) :: rec
    integer(int64) :: now
    call system_clock(now)
    rec = this%rec
    rec%t_end = t
    rec%steps = steps - this%steps0
    rec%wall_seconds = real(now - this%clock0, wp)/real(this%rate, wp)
    if (this%load_samples > 0) then
      rec%load_mean = this%load_sum/this%load_samples
    else
      rec%load_mean = ieee_value(rec%load_mean, ieee_quiet_nan)
    end if
  end function segment_record

end module kf_run_segment
