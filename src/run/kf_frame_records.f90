!> The records a case file takes for one frame, filled from what the run computed: the shape
!> observables, the run diagnostics (with the configuration diagnostics of the frame, computed
!> here) and the fibre's stresslet. The case file (kf_case_file) writes them as given.
module kf_frame_records
  use kf_kinds, only: wp
  use kf_shape, only: shape_t
  use kf_rheology, only: fibre_stresslet_t
  use kf_run_diagnostics, only: run_diagnostics_t, configuration_diagnostics, diag_n_counters, diag_n_values
  use kf_case_file, only: observables_record_t, diagnostics_record_t, stresslet_record_t
  implicit none
  private

  public :: observables_record, diagnostics_record, stresslet_record

contains

  !> The observables record of the shape `s`.
  pure function observables_record(s) result(rec)
    type(shape_t), intent(in) :: s
    type(observables_record_t) :: rec
    rec = observables_record_t(rg=s%rg, a=s%a, b=s%b, c=s%c, theta=s%theta, phi=s%phi, close_pairs=s%close_pairs)
  end function observables_record

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

  !> The stresslet record of `st`.
  pure function stresslet_record(st) result(rec)
    type(fibre_stresslet_t), intent(in) :: st
    type(stresslet_record_t) :: rec
    rec = stresslet_record_t(hydrodynamic=st%hydrodynamic, elastic=st%elastic, viscosity=st%viscosity, &
                             psi1=st%psi1, psi2=st%psi2)
  end function stresslet_record

end module kf_frame_records
