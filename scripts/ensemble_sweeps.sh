# shellcheck shell=bash
# The ensembles of issue 36 (inputs/ensembles/; RPY + excluded volume, then the study's model
# on chosen cells and starts): the one list that
# scripts/campaign.sh --set ensembles runs, in the order it runs them (sourced: it only defines
# functions; nothing set, nothing run).
#
#   kf_ensemble_sweeps            prints one "ROLE SWEEP" line per sweep, most informative first
#   kf_ensemble_arrays            the same list in the arrays KF_STUDY_ROLES and KF_STUDY_SWEEPS
#   kf_ensemble_closures ROLE     prints "CLOSURES STRIDE" for k_f of a sweep of ROLE (stride 1:
#                                 the ledger takes k_f of every frame)
#
# SWEEP names the input, inputs/ensembles/SWEEP.nml, and the output directory <results>/SWEEP.
# ROLE: ensemble (candy-canes, t_end = 2000: positions kept every 50 time units in the ledger),
#       trefoil (Table 2 samples, t_end = 1000: positions every 100).
# The order is the campaign's (cases of one sweep in the order of its &sweep lists, which list
# the seeds in turn, so every A or cell gains a sample before any gets a second):
#   candycane_haar_A1_A3    A = 1, 3, Haar rotations of seeds 1..20            40 cases
#   candycane_tilt0..90     the unrotated candy-cane tilted about x, six A       4 x 6
#   trefoil_samples_first   cells (c, 2.1-2.3), (0.8, a), (1, c), (1.4, b)      6 x 10 seeds
#   candycane_haar_rest     A = 0.5, 0.8, 1.4, 2, seeds 1..20                   80
#   trefoil_samples_rest    the other 23 cells, perturbation seeds 1..10       230
#   trefoil_samples_p1e-3   the six cells of trefoil_samples_first, 1e-3 d     6 x 10 seeds
# and then the study's model (multipole L = 2 + lubrication, overlap 'relax', update 'iterative'):
#   trefoil_samples_multipole_first   the six cells of trefoil_samples_first, seeds 1, 2   12
#   candycane_haar_multipole          A = 1, 3, four Haar starts each (the file says which) 8
#   trefoil_samples_multipole_rest    the six cells, seeds 3..10                          48

kf_ensemble_sweeps() {
  printf '%s\n' "ensemble candycane_haar_A1_A3" \
                "ensemble candycane_tilt0" "ensemble candycane_tilt30" \
                "ensemble candycane_tilt60" "ensemble candycane_tilt90" \
                "trefoil trefoil_samples_first" \
                "ensemble candycane_haar_rest" \
                "trefoil trefoil_samples_rest" \
                "trefoil trefoil_samples_p1e-3" \
                "trefoil trefoil_samples_multipole_first" \
                "ensemble candycane_haar_multipole" \
                "trefoil trefoil_samples_multipole_rest"
}

kf_ensemble_arrays() {
  local role sweep
  KF_STUDY_ROLES=() KF_STUDY_SWEEPS=()
  while read -r role sweep; do
    KF_STUDY_ROLES+=("$role")
    KF_STUDY_SWEEPS+=("$sweep")
  done <<<"$(kf_ensemble_sweeps)"
}

kf_ensemble_closures() {
  case "$1" in
    ensemble|trefoil) printf '200 1\n' ;;
    *)
      printf 'ERROR: no closures for the ensembles role %s\n' "$1" >&2
      return 2
      ;;
  esac
}
