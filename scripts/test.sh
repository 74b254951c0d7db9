#!/usr/bin/env bash
# Build and test knotflow: installs what is missing, builds Release (build/) and Debug
# (build-debug/, unit tests only, with -fcheck=all and FPE traps), runs ctest in both.
# Exit status is non-zero when anything fails.  Works from any directory; safe to re-run.
#
#   scripts/test.sh           the default suite: every test except those labelled slow
#                             (under 15 minutes on 2 cores; docs/setup.md)
#   scripts/test.sh --slow    the tests labelled slow as well (the whole suite)
#
# Environment: KNOTFLOW_JOBS (default 2), KNOTFLOW_PYTHON, KNOTFLOW_NO_INSTALL=1,
#              KNOTFLOW_SKIP_DEBUG=1 (Release only), KNOTFLOW_CTEST_ARGS (extra ctest args).
set -euo pipefail
slow=0
for arg in "$@"; do
  case "$arg" in
    --slow) slow=1 ;;
    -h|--help) sed -n '2,11p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) printf 'test.sh: unknown argument %s (allowed: --slow)\n' "$arg" >&2; exit 2 ;;
  esac
done
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cd "$KF_ROOT"

kf_ensure_system_packages
kf_ensure_python

# shellcheck disable=SC2206
extra_ctest=(${KNOTFLOW_CTEST_ARGS:-})
labels=(-LE slow) which="default label set (-LE slow)"
if [ "$slow" = 1 ]; then
  labels=() which="every test, the slow ones included"
fi

# ctest_run NAME DIR ARGS...: ctest with its output also in DIR/ctest-NAME.log (for the summary).
ctest_run() {
  local name="$1" dir="$2"
  shift 2
  ctest --test-dir "$dir" --output-on-failure "$@" 2>&1 | tee "$dir/ctest-$name.log"
}
# The closing lines of a ctest log: "N% tests passed, ..." and "Total Test time (real) = ...".
ctest_summary() {
  grep -E '^[0-9]+% tests passed|^Total Test time|^No tests were found' "$1" 2>/dev/null \
    | tr '\n' ' ' || true
}

kf_build "$KF_ROOT/build" Release
kf_log "ctest (Release): $which"
status_release=0
ctest_run release "$KF_ROOT/build" "${labels[@]}" -j "$KF_JOBS" "${extra_ctest[@]}" || status_release=$?

status_debug=0
if [ "${KNOTFLOW_SKIP_DEBUG:-0}" != 1 ]; then
  kf_build "$KF_ROOT/build-debug" Debug knotflow_unit_tests
  kf_log "ctest (Debug): unit tests (-L unit ${labels[*]})"
  ctest_run debug "$KF_ROOT/build-debug" -L unit "${labels[@]}" -j "$KF_JOBS" "${extra_ctest[@]}" \
    || status_debug=$?
fi

verdict() { if [ "$1" -eq 0 ]; then echo passed; else echo "FAILED (ctest exit $1)"; fi; }
kf_log "Release tests: $(verdict "$status_release"): $(ctest_summary "$KF_ROOT/build/ctest-release.log")"
if [ "${KNOTFLOW_SKIP_DEBUG:-0}" != 1 ]; then
  kf_log "Debug unit tests: $(verdict "$status_debug"): $(ctest_summary "$KF_ROOT/build-debug/ctest-debug.log")"
fi
if [ "$status_release" -ne 0 ] || [ "$status_debug" -ne 0 ]; then
  exit 1
fi
