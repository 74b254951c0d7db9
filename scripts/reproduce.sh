#!/usr/bin/env bash
# Reproduce the reference study: run the trefoil Table 2 sweep (29 cases, N = 99) and the
# candy-cane sweep (A = 1, 1.4, 3; N = 152), analyse them, and write the comparison.
#   scripts/reproduce.sh [--hydro rpy|multipole] [--no-run]
#
#   --hydro rpy        (default) inputs/trefoil_table2.nml and inputs/candycane.nml:
#                      RPY + excluded volume, about 30 s per trefoil case on one core.
#   --hydro multipole  the *_multipole.nml variants: multipole L = 2 + lubrication, hours per case
#                      (a cluster job: jobs/README.md).
#   --no-run           only analyse what the sweeps already wrote (e.g. after cluster jobs).
#
# Re-running continues: finished cases are skipped, killed ones resumed, and knotflow-analyze
# reuses the k_f and knot matrices it already stored. Output: results/<sweep>/ (case files,
# report/) and results/reproduction[_multipole]/ (figures, results.md, results.json).
# Environment: KNOTFLOW_NP (MPI ranks, default 2), KNOTFLOW_NO_INSTALL=1 (see scripts/lib.sh).
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

hydro=rpy
run=1
while [ $# -gt 0 ]; do
  case "$1" in
    --hydro) [ $# -ge 2 ] || kf_die "--hydro needs a value (rpy or multipole)"; hydro="$2"; shift 2 ;;
    --no-run) run=0; shift ;;
    *) kf_die "unknown argument '$1' (allowed: --hydro rpy|multipole, --no-run)" ;;
  esac
done
case "$hydro" in
  rpy) suffix="" ;;
  multipole) suffix="_multipole" ;;
  *) kf_die "--hydro $hydro is unknown (allowed: rpy, multipole)" ;;
esac
np="${KNOTFLOW_NP:-2}"
[[ "$np" =~ ^[1-9][0-9]*$ ]] || kf_die "KNOTFLOW_NP must be a positive integer (got '$np')"

cd "$KF_ROOT"
kf_ensure_system_packages
kf_ensure_python
kf_build "$KF_ROOT/build" Release
kf_mpirun_flags
mpi=(mpirun -n "$np" "${KF_MPIRUN_FLAGS[@]}")
analyze="$KF_ROOT/build/src/app/knotflow-analyze"

trefoil_dir="results/trefoil_table2$suffix"
cane_dir="results/candycane$suffix"
if [ "$run" = 1 ]; then
  for sweep in trefoil_table2 candycane; do
    kf_log "knotflow inputs/$sweep$suffix.nml on $np rank(s)"
    # A failed case (exit 3) is reported in the summary; the others are still analysed.
    "${mpi[@]}" build/knotflow "inputs/$sweep$suffix.nml" || [ $? -eq 3 ]
  done
fi

shopt -s nullglob
trefoils=("$trefoil_dir"/*.h5)
canes=("$cane_dir"/*.h5)
[ "${#trefoils[@]}" -gt 0 ] || [ "${#canes[@]}" -gt 0 ] || kf_die "no case files in $trefoil_dir or $cane_dir"
# Trefoils: k_f of every frame (200 closures), knot matrix of the last frame.
if [ "${#trefoils[@]}" -gt 0 ]; then
  kf_log "knotflow-analyze: ${#trefoils[@]} trefoil case(s)"
  "${mpi[@]}" "$analyze" "${trefoils[@]}" --closures 200 --stride 1 --matrix-frames last
fi
# Candy-canes: k_f of every frame, knot matrices (20 closures per subchain) every 50 frames and
# at the 5 most entangled frames: the slipknot search.
for f in "${canes[@]}"; do
  frames="$(knotflow-study --select-frames "$f")"
  kf_log "knotflow-analyze $f (knot matrices of frames $frames)"
  "${mpi[@]}" "$analyze" "$f" --closures 200 --stride 1 --matrix-frames "$frames" --matrix-closures 20
done
out="results/reproduction$suffix"
kf_log "knotflow-study -> $out"
args=()
[ "${#trefoils[@]}" -gt 0 ] && args+=(--trefoil "$trefoil_dir")
[ "${#canes[@]}" -gt 0 ] && args+=(--candycane "$cane_dir")
knotflow-study "${args[@]}" --out "$out"
