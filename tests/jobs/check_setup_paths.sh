#!/bin/bash
# The set-up paths of scripts/lib.sh that cluster jobs rely on, without installing anything:
#   1. KNOTFLOW_NO_APT=1 (libraries from environment modules): kf_ensure_system_packages and the
#      optional packages never call dpkg or apt-get (shims on PATH record any call), and accept
#      the tools on PATH;
#   2. with KNOTFLOW_NO_APT=1 a missing tool stops it with its name;
#   3. KNOTFLOW_BUILD_DIR, relative to the checkout or absolute, is the build directory
#      (KF_BUILD_DIR: scripts/build.sh and scripts/reproduce.sh build there, with <dir>/venv).
# Usage: check_setup_paths.sh SOURCE_DIR WORKDIR
set -uo pipefail
src="$(cd "$1" && pwd)" work="$2"
fail() { echo "FAIL: $*" >&2; exit 1; }
rm -rf "${work}"
mkdir -p "${work}/shims"
for tool in apt-get dpkg sudo; do
  printf '#!/bin/sh\necho "%s $*" >>"%s/calls"\nexit 1\n' "${tool}" "${work}" >"${work}/shims/${tool}"
  chmod +x "${work}/shims/${tool}"
done
out=$(PATH="${work}/shims:${PATH}" KNOTFLOW_NO_APT=1 bash -c \
  "source '${src}/scripts/lib.sh' && kf_ensure_system_packages && kf_ensure_optional_packages && echo DONE" 2>&1)
[[ "${out}" == *DONE* ]] || fail "KNOTFLOW_NO_APT=1 did not accept the tools on PATH: ${out}"
[[ ! -s "${work}/calls" ]] || fail "KNOTFLOW_NO_APT=1 called the package manager: $(cat "${work}/calls")"
echo "KNOTFLOW_NO_APT=1: no dpkg/apt-get call, tools on PATH accepted"

# a PATH without gfortran (only the shims and the basic tools bash needs)
mkdir -p "${work}/bin"
for tool in cmake make mpirun python3 dirname cat; do
  p="$(command -v "${tool}")" && ln -sf "${p}" "${work}/bin/${tool}"
done
out=$(PATH="${work}/shims:${work}/bin" KNOTFLOW_NO_APT=1 /bin/bash -c \
  "source '${src}/scripts/lib.sh' && kf_ensure_system_packages && echo DONE" 2>&1)
[[ "${out}" != *DONE* && "${out}" == *"'gfortran' not found"* ]] || fail "a missing gfortran was not reported: ${out}"
[[ ! -s "${work}/calls" ]] || fail "the package manager was called: $(cat "${work}/calls")"
echo "KNOTFLOW_NO_APT=1 without gfortran: stops, naming it"

got=$(KNOTFLOW_BUILD_DIR=build-cluster bash -c "source '${src}/scripts/lib.sh' && echo \"\${KF_BUILD_DIR}\"")
[[ "${got}" == "${src}/build-cluster" ]] || fail "KNOTFLOW_BUILD_DIR=build-cluster gave ${got}"
got=$(KNOTFLOW_BUILD_DIR=/opt/kf bash -c "source '${src}/scripts/lib.sh' && echo \"\${KF_BUILD_DIR}\"")
[[ "${got}" == /opt/kf ]] || fail "KNOTFLOW_BUILD_DIR=/opt/kf gave ${got}"
echo "KNOTFLOW_BUILD_DIR: relative to the checkout or absolute"
