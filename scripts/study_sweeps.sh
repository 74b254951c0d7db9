# shellcheck shell=bash
# The sweeps of the reference study, per hydrodynamic model: the one list that
# scripts/reproduce.sh runs and analyses and jobs/submit_study.sh submits (sourced: it only
# defines functions; no variable set, nothing installed, nothing run; safe on a login node).
#
#   kf_study_sweeps HYDRO EXTRAS   prints one "ROLE SWEEP" line per sweep, in the order of the
#                                  study (HYDRO rpy|multipole; EXTRAS 1|0); status 2 and a message
#                                  on stderr for an unknown HYDRO
#   kf_study_arrays HYDRO EXTRAS   the same list in the arrays KF_STUDY_ROLES and KF_STUDY_SWEEPS
#                                  (loop over these: a loop reading the lines from stdin would
#                                  lose them to mpirun or srun inside it, which read stdin)
#   kf_study_closures HYDRO ROLE   prints "CLOSURES STRIDE": the closures per frame of k_f and
#                                  the frame stride knotflow-analyze uses for a sweep of ROLE
#                                  (scripts/reproduce.sh, scripts/campaign.sh)
#
# SWEEP names both the input, inputs/SWEEP.nml, and the output directory, <results>/SWEEP.
# ROLE says how the sweep is analysed and compared with the study:
#   trefoil      Table 2 (29 open trefoils): k_f of every frame, knot matrix of the last frame
#   candycane    the candy-cane (A = 1, 1.4, 3): k_f of every frame, knot matrices of selected
#                frames (the slipknot search) and the slipknot candidates confirmed
#   ensemble     candy-canes from further random rotations: k_f of every frame
#   probe        the candy-cane with one setting of the model changed (what decides its mode?):
#                k_f of every frame, compared on its own as a candy-cane sweep
#   trefoil_p24  Table 2 with the open trefoil whose k_f(0) = 0.98, compared on its own
#
# rpy:       trefoil_table2, candycane; the extras (EXTRAS = 1) candycane_seeds (5 rotations)
#            and trefoil_table2_p24 are checks beyond the study's inputs.
# multipole: the campaign of issue 11: trefoil_table2_multipole (with the k_f(0) = 0.98
#            trefoil), candycane_multipole, candycane_seeds_multipole (A = 1, 3 from two
#            further rotations) and the probes candycane_epslub_multipole (A = 1 with
#            eps_lub = 1e-2) and candycane_order3_multipole (A = 1 with L = 3 from t = 1100 of
#            the L = 2 run, after the window probe candycane_order3_window_multipole that is run
#            by hand) - the last three are part of the study, whatever EXTRAS says.

kf_study_sweeps() {
  local hydro="$1" extras="${2:-1}"
  case "$hydro" in
    rpy)
      printf '%s\n' "trefoil trefoil_table2" "candycane candycane"
      if [ "$extras" = 1 ]; then
        printf '%s\n' "ensemble candycane_seeds" "trefoil_p24 trefoil_table2_p24"
      fi
      ;;
    multipole)
      printf '%s\n' "trefoil trefoil_table2_multipole" "candycane candycane_multipole" \
                    "ensemble candycane_seeds_multipole" "probe candycane_epslub_multipole" \
                    "probe candycane_order3_multipole"
      ;;
    *)
      printf 'ERROR: hydro %s is unknown (allowed: rpy, multipole)\n' "$hydro" >&2
      return 2
      ;;
  esac
}

kf_study_arrays() {
  local list role sweep
  list="$(kf_study_sweeps "$@")" || return 2
  KF_STUDY_ROLES=() KF_STUDY_SWEEPS=()
  while read -r role sweep; do
    KF_STUDY_ROLES+=("$role")
    KF_STUDY_SWEEPS+=("$sweep")
  done <<<"$list"
}

kf_study_closures() {
  case "$1:$2" in
    rpy:ensemble) printf '100 2\n' ;;
    rpy:trefoil|rpy:candycane|rpy:trefoil_p24) printf '200 1\n' ;;
    multipole:trefoil|multipole:candycane|multipole:ensemble|multipole:probe) printf '1000 1\n' ;;
    *)
      printf 'ERROR: no closures for hydro %s, role %s\n' "$1" "$2" >&2
      return 2
      ;;
  esac
}
