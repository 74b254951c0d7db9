#!/bin/bash
# OpenBLAS's kernels (scripts/blas_env.sh, sourced by scripts/lib.sh and jobs/job_lib.sh):
#   1. the core type for given CPU flags: SkylakeX only with all of AVX-512 F, DQ, BW and VL,
#      else Haswell with AVX2 and FMA, else none; flags match as whole words;
#   2. an OPENBLAS_CORETYPE that is set is kept;
#   3. scripts/lib.sh exports the type this machine's flags call for (read here with grep);
#   4. OpenBLAS takes it: `OPENBLAS_VERBOSE=2 knotflow --version` names that core (skipped
#      without a build or when the BLAS is not OpenBLAS with run-time kernel choice).
# Usage: check_blas_env.sh SOURCE_DIR BUILD_DIR
set -uo pipefail
src="$(cd "$1" && pwd)" build="$2"
fail() { echo "FAIL: $*" >&2; exit 1; }
# shellcheck source=scripts/blas_env.sh
source "${src}/scripts/blas_env.sh"

# --- 1. flags -> core type
check() {   # check EXPECTED FLAGS
  local got
  got="$(kf_openblas_coretype "$2")"
  [[ "${got}" == "$1" ]] || fail "flags '$2': '${got}', expected '$1'"
}
all="fpu sse3 avx avx2 fma avx512f avx512dq avx512bw avx512vl avx512_bf16"
check SkylakeX "${all}"
check Haswell "${all/avx512bw /}"
check Haswell "fpu avx2 fma"
check "" "fpu sse3 avx avx2"
check "" "fpu sse3 avx512fx avx512dq avx512bw avx512vl avx2x fma"
check "" ""

# --- 2. a type that is set is kept
# shellcheck disable=SC2016  # expanded by the inner shell
kept="$(OPENBLAS_CORETYPE=Zen bash -c 'source "$1"; kf_openblas_environment; echo "${OPENBLAS_CORETYPE}"' \
  _ "${src}/scripts/blas_env.sh")"
[[ "${kept}" == Zen ]] || fail "kf_openblas_environment replaced OPENBLAS_CORETYPE=Zen by '${kept}'"

# --- 3. scripts/lib.sh on this machine
want=""
if [[ "$(uname -m)" == x86_64 && -r /proc/cpuinfo ]]; then
  line="$(grep -m1 '^flags' /proc/cpuinfo)"
  has() { grep -qw -- "$1" <<<"${line}"; }
  if has avx512f && has avx512dq && has avx512bw && has avx512vl; then
    want=SkylakeX
  elif has avx2 && has fma; then
    want=Haswell
  fi
fi
# shellcheck disable=SC2016  # expanded by the inner shell
got="$(env -u OPENBLAS_CORETYPE bash -c 'source "$1"; echo "${OPENBLAS_CORETYPE:-}"' _ "${src}/scripts/lib.sh")"
[[ "${got}" == "${want}" ]] || fail "scripts/lib.sh exported OPENBLAS_CORETYPE='${got}', expected '${want}'"

# --- 4. OpenBLAS takes it
exe="${build}/bin/knotflow"
if [[ -z "${want}" || ! -x "${exe}" ]]; then
  echo "scripts/blas_env.sh: flags checked; this machine: '${want}' (no OpenBLAS check)"
  exit 0
fi
core="$(OPENBLAS_CORETYPE="${want}" OPENBLAS_VERBOSE=2 "${exe}" --version 2>&1 | sed -n 's/^Core: //p')"
if [[ -z "${core}" ]]; then
  echo "scripts/blas_env.sh: flags checked; this machine: ${want} (the BLAS names no core: not checked)"
  exit 0
fi
[[ "${core}" == "${want}" ]] || fail "OpenBLAS ran the ${core} kernels with OPENBLAS_CORETYPE=${want}"
echo "scripts/blas_env.sh: flags checked; this machine: ${want}, and OpenBLAS runs its ${core} kernels"
