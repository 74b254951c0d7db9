#!/usr/bin/env bash
# Does a knot change the fluid? (issue 15, docs/RHEOLOGY.md) The open trefoil of Table 2 with
# k_f(0) = 0.98 (29 cases) and the candy-canes (A = 1, 1.4, 3) with RPY + excluded volume and the
# fibre's stresslet recorded; k_f of every frame (200 closures) and the shape modes with
# knotflow-analyze; then knotflow-rheology: viscosity, psi1, psi2 of knotted against unknotted
# intervals and of modes I against II, over the whole runs and after the start-up (t >= 100).
#   scripts/rheology.sh [--no-run]
# Output: results/trefoil_table2_p24_rheology/, results/candycane_rheology/ (case files) and
# results/rheology/{all,late}/ (rheology.md, rheology.json, figures). Re-running continues:
# finished cases are skipped, stored k_f reused. About 25 min of CPU (docs/RHEOLOGY.md).
# Environment: KNOTFLOW_NP (MPI ranks, default 2), KNOTFLOW_NO_INSTALL=1 (see scripts/lib.sh).
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

run=1
while [ $# -gt 0 ]; do
  case "$1" in
    --no-run) run=0; shift ;;
    *) kf_die "unknown argument '$1' (allowed: --no-run)" ;;
  esac
done
np="$(kf_ranks)"

cd "$KF_ROOT"
kf_ensure_system_packages
kf_ensure_python
kf_build "$KF_BUILD_DIR" Release
[ -d "$KF_BUILD_DIR/venv/bin" ] && PATH="$KF_BUILD_DIR/venv/bin:$PATH"
kf_mpirun_flags
mpi=(mpirun -n "$np" "${KF_MPIRUN_FLAGS[@]}")
trefoils=results/trefoil_table2_p24_rheology
canes=results/candycane_rheology
if [ "$run" = 1 ]; then
  for sweep in "$trefoils" "$canes"; do
    kf_log "knotflow inputs/$(basename "$sweep").nml on $np rank(s)"
    # A failed case (exit 3) is reported in the summary; the others are still analysed.
    "${mpi[@]}" "$KF_BUILD_DIR/bin/knotflow" "inputs/$(basename "$sweep").nml" || [ $? -eq 3 ]
  done
fi
shopt -s nullglob
for sweep in "$trefoils" "$canes"; do
  files=("$sweep"/*.h5)
  [ "${#files[@]}" -gt 0 ] || kf_die "no case files in $sweep (run without --no-run first)"
  kf_log "knotflow-analyze: ${#files[@]} case(s) of $sweep (k_f of every frame, 200 closures)"
  "${mpi[@]}" "$KF_BUILD_DIR/bin/knotflow-analyze" "${files[@]}" --closures 200 --stride 1
done
kf_log "knotflow-rheology -> results/rheology/all and results/rheology/late (t >= 100)"
knotflow-rheology --knots "$trefoils" --modes "$canes" --out results/rheology/all
knotflow-rheology --knots "$trefoils" --modes "$canes" --out results/rheology/late --t-from 100
