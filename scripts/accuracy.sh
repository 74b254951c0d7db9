#!/usr/bin/env bash
# The accuracy-versus-cost report (docs/accuracy.md): build (Release), run knotflow-accuracy
# --all on one core, then knotflow-accuracy-report, which writes docs/accuracy.md, the figures
# docs/figures/accuracy_*.png and the summary block of docs/models.md (between
# <!-- accuracy:begin --> and <!-- accuracy:end -->).  About 20-30 min on a quiet machine.
#   scripts/accuracy.sh [knotflow-accuracy options]   (default: --all; e.g. --quick for a smoke run)
# Environment: KNOTFLOW_ACCURACY_OUT (results directory, default build/accuracy),
#              KNOTFLOW_ACCURACY_README=0 (do not touch docs/models.md), KNOTFLOW_JOBS, KNOTFLOW_PYTHON,
#              KNOTFLOW_NO_INSTALL=1.
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

cd "$KF_ROOT"
kf_ensure_system_packages
kf_ensure_python
kf_build "$KF_ROOT/build" Release knotflow-accuracy

exe="$KF_ROOT/build/bin/knotflow-accuracy"
[ -x "$exe" ] || kf_die "knotflow-accuracy was not built"
out="${KNOTFLOW_ACCURACY_OUT:-$KF_ROOT/build/accuracy}"
args=("$@")
[ "${#args[@]}" -eq 0 ] && args=(--all)

kf_log "load before the run: $(cat /proc/loadavg 2>/dev/null || echo unknown)"
kf_log "OPENBLAS_NUM_THREADS=1 $exe ${args[*]} --out $out"
OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 "$exe" "${args[@]}" --out "$out"
kf_log "load after the run: $(cat /proc/loadavg 2>/dev/null || echo unknown)"

readme_args=(--readme "$KF_ROOT/docs/models.md")
[ "${KNOTFLOW_ACCURACY_README:-1}" = 0 ] && readme_args=()
kf_log "knotflow-accuracy-report $out"
knotflow-accuracy-report "$out" --markdown "$KF_ROOT/docs/accuracy.md" \
  --figures "$KF_ROOT/docs/figures" "${readme_args[@]}"
