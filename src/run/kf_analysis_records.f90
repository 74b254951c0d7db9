!> The records the analysis store (kf_analysis_store) writes to /analysis, filled from the
!> results of the analysis (kf_knot_case, kf_transitions): the one place that knows both, so that
!> `analysis` needs no I/O and `io` nothing of the analysis.
module kf_analysis_records
  use kf_kinds, only: i4, i8
  use kf_knot_invariants, only: n_knot_types, knot_type_names
  use kf_knot_case, only: frame_knots_t, shape_analysis_t
  use kf_transitions, only: event_names, default_low, default_high
  use kf_analysis_store, only: knots_record_t, events_record_t, shape_record_t
  implicit none
  private

  public :: knots_record, events_record, shape_record

contains

  !> The record of the frame knots `knots`, computed with `closures` closures and `seed`.
  function knots_record(knots, closures, seed) result(rec)
    type(frame_knots_t), intent(in) :: knots
    integer, intent(in) :: closures
    integer(i8), intent(in) :: seed
    type(knots_record_t) :: rec
    rec%closures = closures
    rec%seed = seed
    allocate (rec%frame_index, source=knots%frame_index)
    allocate (rec%time, source=knots%time)
    allocate (rec%kf, source=knots%kf)
    allocate (rec%spectrum, source=knots%spectrum)
    allocate (character(len=len(knot_type_names)) :: rec%type_names(n_knot_types), rec%dominant(size(knots%dominant)))
    rec%type_names = knot_type_names
    rec%dominant = knot_type_names(knots%dominant)
  end function knots_record

  !> The record of the transitions of kinds ev_kind at the positions ev_pos of `knots` (found
  !> with the default thresholds of kf_transitions).
  function events_record(knots, ev_kind, ev_pos) result(rec)
    type(frame_knots_t), intent(in) :: knots
    integer, intent(in) :: ev_kind(:), ev_pos(:)
    type(events_record_t) :: rec
    allocate (character(len=len(event_names)) :: rec%kind(size(ev_kind)))
    rec%kind = event_names(ev_kind)
    allocate (rec%frame_index, source=knots%frame_index(ev_pos))
    allocate (rec%time, source=knots%time(ev_pos))
    rec%low = default_low
    rec%high = default_high
  end function events_record

  !> The record of the modes and spectra `shapes`.
  function shape_record(shapes) result(rec)
    type(shape_analysis_t), intent(in) :: shapes
    type(shape_record_t) :: rec
    allocate (rec%mode, source=int(shapes%mode, i4))
    rec%case_mode = shapes%case_mode
    allocate (rec%frequency, source=shapes%frequency)
    allocate (rec%power_rg, source=shapes%power_rg)
    allocate (rec%power_phi, source=shapes%power_phi)
    allocate (rec%power_end_to_end, source=shapes%power_end_to_end)
    rec%period_rg = shapes%period_rg
    rec%period_phi = shapes%period_phi
  end function shape_record

end module kf_analysis_records
