#!/usr/bin/env bash
# Build and test knotflow: installs what is missing, builds Release (build/) and Debug
# (build-debug/, unit tests only, with -fcheck=all and FPE traps), runs ctest in both.
# Exit status is non-zero when anything fails.  Works from any directory; safe to re-run.
#
# Environment: KNOTFLOW_JOBS (default 2), KNOTFLOW_PYTHON, KNOTFLOW_NO_INSTALL=1,
#              KNOTFLOW_SKIP_DEBUG=1 (Release only), KNOTFLOW_CTEST_ARGS (extra ctest args).
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cd "$KF_ROOT"

kf_ensure_system_packages
kf_ensure_python

# shellcheck disable=SC2206
extra_ctest=(${KNOTFLOW_CTEST_ARGS:-})

kf_build "$KF_ROOT/build" Release
kf_log "ctest (Release): default label set (-LE slow)"
status_release=0
ctest --test-dir "$KF_ROOT/build" --output-on-failure -LE slow -j "$KF_JOBS" "${extra_ctest[@]}" \
  || status_release=$?

status_debug=0
if [ "${KNOTFLOW_SKIP_DEBUG:-0}" != 1 ]; then
  kf_build "$KF_ROOT/build-debug" Debug knotflow_unit_tests
  kf_log "ctest (Debug): unit tests (-L unit -LE slow)"
  ctest --test-dir "$KF_ROOT/build-debug" --output-on-failure -L unit -LE slow -j "$KF_JOBS" \
        "${extra_ctest[@]}" || status_debug=$?
fi

verdict() { if [ "$1" -eq 0 ]; then echo passed; else echo "FAILED (ctest exit $1)"; fi; }
kf_log "Release tests: $(verdict "$status_release")"
[ "${KNOTFLOW_SKIP_DEBUG:-0}" != 1 ] && kf_log "Debug unit tests: $(verdict "$status_debug")"
if [ "$status_release" -ne 0 ] || [ "$status_debug" -ne 0 ]; then
  exit 1
fi
