!> The record a case file takes for one frame (kf_case_frames' `frame_t`), filled from what the
!> run computed: time and positions, the stepper's counts and step size, the shape observables
!> and the run diagnostics (with the configuration diagnostics of the frame, computed here).
!> The fibre's stresslet goes into the record straight from the dynamics (kf_case_runner), so
!> that this module stays below kf_dynamics. The case file (kf_case_file) writes it as given.
module kf_frame_records
  use kf_kinds, only: wp
  use kf_error, only: error_t
  use kf_shape, only: compute_shape
  use kf_stepper, only: stepper_t
  use kf_run_diagnostics, only: run_diagnostics_t, configuration_diagnostics, diag_n_counters, diag_n_values
  use kf_case_frames, only: frame_t, diagnostics_record_t
  implicit none
  private

  public :: fill_frame, diagnostics_record

contains

  !> The record of the frame at time `t` with positions r(3, N), after the last step of
  !> `stepper`: its counts and next step size, the shape observables and, when the record has
  !> room for them (kf_case_frames' `frame_template`), the run diagnostics of `diag`. The
  !> error comes from the shape.
  subroutine fill_frame(frame, t, r, stepper, error, diag)
    type(frame_t), intent(inout) :: frame
    real(wp), intent(in) :: t
    real(wp), intent(in) :: r(:, :)
    class(stepper_t), intent(in) :: stepper
    type(error_t), allocatable, intent(out) :: error
    type(run_diagnostics_t), intent(in), optional :: diag
    frame%t = t
    frame%r = r
    frame%steps = stepper%steps()
    frame%rejected = stepper%rejected()
    frame%dt = stepper%dt()
    call compute_shape(r, frame%observables, error)
    if (allocated(error)) return
    if (allocated(frame%diagnostics) .and. present(diag)) frame%diagnostics = diagnostics_record(diag, r)
  end subroutine fill_frame

  !> The diagnostics record of the monitor `diag` after the frame with positions r(3, N).
  function diagnostics_record(diag, r) result(rec)
    type(run_diagnostics_t), intent(in) :: diag
    real(wp), intent(in) :: r(:, :)
    type(diagnostics_record_t) :: rec
    call configuration_diagnostics(r, diag%bond_length, rec%overlapping_pairs, rec%min_distance, rec%max_bond_strain)
    rec%strand_passages = diag%strand_passages
    rec%overlap_episodes = diag%overlap_episodes
    rec%first_passage_time = diag%first_passage_time
    rec%overlap_mean_duration = diag%mean_duration()
    rec%overlap_max_duration = diag%duration_max
    rec%max_overlapping_pairs = diag%max_overlapping_pairs
    rec%run_min_distance = diag%min_distance()
    rec%run_max_bond_strain = diag%max_bond_strain
    allocate (rec%state_counters(diag_n_counters), rec%state_values(diag_n_values))
    call diag%get_state(rec%state_counters, rec%state_values, rec%state_ongoing)
  end function diagnostics_record

end module kf_frame_records
