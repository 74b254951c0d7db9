#!/usr/bin/env bash
# Install what is missing and build knotflow: Release in build/ (default; KNOTFLOW_BUILD_DIR
# chooses another directory) or, with KNOTFLOW_BUILD_TYPE=Debug, Debug in build-debug/. Also
# installs the Python tools (knotflow-study, ...) into <build dir>/venv: everything the analysis
# needs. Works from any directory; safe to re-run.
# Environment: KNOTFLOW_BUILD_TYPE, KNOTFLOW_BUILD_DIR, KNOTFLOW_JOBS (default 2), KNOTFLOW_PYTHON,
# KNOTFLOW_NO_INSTALL=1, KNOTFLOW_NO_APT=1 (libraries from environment modules: see lib.sh).
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cd "$KF_ROOT"

kf_ensure_system_packages
kf_ensure_python
case "${KNOTFLOW_BUILD_TYPE:-Release}" in
  Release) kf_build "$KF_BUILD_DIR" Release ;;
  Debug) kf_build "$KF_ROOT/build-debug" Debug ;;
  *) kf_die "KNOTFLOW_BUILD_TYPE must be Release or Debug" ;;
esac
