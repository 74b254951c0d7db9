#!/usr/bin/env bash
# Install what is missing and build knotflow: Release in build/ (default) or, with
# KNOTFLOW_BUILD_TYPE=Debug, Debug in build-debug/.  Works from any directory; safe to re-run.
# Environment: KNOTFLOW_BUILD_TYPE, KNOTFLOW_JOBS (default 2), KNOTFLOW_PYTHON, KNOTFLOW_NO_INSTALL=1.
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cd "$KF_ROOT"

kf_ensure_system_packages
kf_ensure_python
case "${KNOTFLOW_BUILD_TYPE:-Release}" in
  Release) kf_build "$KF_ROOT/build" Release ;;
  Debug) kf_build "$KF_ROOT/build-debug" Debug ;;
  *) kf_die "KNOTFLOW_BUILD_TYPE must be Release or Debug" ;;
esac
