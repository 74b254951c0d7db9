# shellcheck shell=bash
# OpenBLAS's kernels for this CPU (sourced by scripts/lib.sh and jobs/job_lib.sh; defines
# functions only). OpenBLAS picks its kernels from the CPU model when it starts; a model newer
# than the library falls back to the Prescott (SSE3) kernels. Debian 12's OpenBLAS 0.3.21 does
# that on Intel family 6 model 207 (5th-generation Xeon): one multipole evaluation of N = 152
# (L = 2, lubrication) took 0.96 s with them and 0.29 s with the SkylakeX kernels
# (docs/multipole.md, "Performance"). Unless OPENBLAS_CORETYPE is set, it is chosen from the
# CPU's instruction sets: SkylakeX with AVX-512 (F, DQ, BW, VL), Haswell with AVX2 and FMA, the
# double-precision kernels OpenBLAS also takes for the newer models it knows. A BLAS other than
# OpenBLAS, or one built for a single CPU, ignores the variable.

# The OpenBLAS core type for the CPU flags "$1" (as /proc/cpuinfo lists them); empty: none.
kf_openblas_coretype() {
  local flags=" $1 " f avx512=1
  for f in avx512f avx512dq avx512bw avx512vl; do
    [[ "${flags}" == *" ${f} "* ]] || avx512=0
  done
  if ((avx512)); then
    echo SkylakeX
  elif [[ "${flags}" == *" avx2 "* && "${flags}" == *" fma "* ]]; then
    echo Haswell
  fi
}

# Export OPENBLAS_CORETYPE for this machine's CPU unless it is set (Linux on x86-64 only).
kf_openblas_environment() {
  local core
  [[ -z "${OPENBLAS_CORETYPE:-}" && "$(uname -m)" == x86_64 && -r /proc/cpuinfo ]] || return 0
  core="$(kf_openblas_coretype "$(grep -m1 '^flags' /proc/cpuinfo | cut -d: -f2)")"
  if [[ -n "${core}" ]]; then export OPENBLAS_CORETYPE="${core}"; fi
  return 0
}
