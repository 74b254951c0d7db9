#!/usr/bin/env bash
# One multipole evaluation (knotflow-bench-multipole) with each BLAS/LAPACK this machine has,
# the same binary swapped by LD_PRELOAD, one thread, the libraries interleaved in every round so
# that a change of the machine's load reaches all of them alike.
#
#   scripts/bench_blas.sh [--rounds K] [--mkl LIBMKL_RT] [--max-seconds S]
#
#   --rounds       rounds of all libraries (default 3); the table gives the median per library
#   --mkl          Intel MKL's single dynamic library (libmkl_rt.so.*), e.g. from `pip install
#                  mkl` into any venv; without it MKL is left out
#   --max-seconds  passed to knotflow-bench-multipole (default 2: N = 99 and 152 at L = 2)
#
# Libraries: OpenBLAS as linked (OPENBLAS_CORETYPE as scripts/blas_env.sh sets it); BLIS from
# Debian (libblis4-pthread, with Debian's reference LAPACK, liblapack3, for the factorisation's
# LAPACK layer) when installed. Printed: per library the median factorisation and whole
# evaluation at N = 99 and 152, L = 2, with and without lubrication, and the ratio of the linked
# OpenBLAS's time to it (above 1: faster than OpenBLAS); the load before and after.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck source=scripts/blas_env.sh
source "${here}/blas_env.sh"
bench="${here}/../build/bin/knotflow-bench-multipole"
rounds=3 mkl="" max_seconds=2
while (($#)); do
  case "$1" in
    --rounds) rounds="$2"; shift 2 ;;
    --mkl) mkl="$2"; shift 2 ;;
    --max-seconds) max_seconds="$2"; shift 2 ;;
    -h | --help) sed -n '2,17p' "$0" | cut -c3-; exit 0 ;;
    *) echo "bench_blas.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ "${rounds}" =~ ^[1-9][0-9]*$ ]] || { echo "bench_blas.sh: --rounds ${rounds}: expected a positive integer" >&2; exit 2; }
[[ -x "${bench}" ]] || { echo "bench_blas.sh: ${bench} missing: run scripts/build.sh first" >&2; exit 2; }

arch="$(uname -m)-linux-gnu"
names=(openblas) preloads=("")
blis="/usr/lib/${arch}/blis-pthread/libblis.so.4" lapack="/usr/lib/${arch}/lapack/liblapack.so.3"
if [[ -r "${blis}" && -r "${lapack}" ]]; then
  names+=(blis) preloads+=("${lapack} ${blis}")
else
  echo "# BLIS left out: ${blis} or ${lapack} missing (apt-get install libblis4-pthread liblapack3)"
fi
if [[ -n "${mkl}" ]]; then
  [[ -r "${mkl}" ]] || { echo "bench_blas.sh: --mkl ${mkl}: not a readable file" >&2; exit 2; }
  names+=(mkl) preloads+=("${mkl}")
else
  echo "# MKL left out: no --mkl (pip install mkl gives lib/libmkl_rt.so.*)"
fi

kf_openblas_environment
work="$(mktemp -d)"
trap 'rm -rf "${work}"' EXIT
echo "# $(date -u +%FT%TZ) $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), OPENBLAS_CORETYPE=${OPENBLAS_CORETYPE:-unset}"
echo "# load before: $(cut -d' ' -f1-3 /proc/loadavg)"
for ((round = 1; round <= rounds; round++)); do
  for i in "${!names[@]}"; do
    OPENBLAS_NUM_THREADS=1 BLIS_NUM_THREADS=1 MKL_NUM_THREADS=1 OMP_NUM_THREADS=1 \
      LD_PRELOAD="${preloads[$i]}" "${bench}" "${max_seconds}" > "${work}/${names[$i]}.${round}"
  done
done
echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg); ${rounds} round(s), median per library"
printf '%-9s %4s %3s %10s %10s %10s %10s\n' library N lub 'factor[s]' 'total[s]' 'x factor' 'x total'
# rows: N, L = 2, lub; columns 5 (factor) and 8 (total) of knotflow-bench-multipole
median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
for lub in F T; do
  for n in 99 152; do
    ref_f="" ref_t=""
    for name in "${names[@]}"; do
      rows="$(cat "${work}/${name}".* | awk -v n="${n}" -v lub="${lub}" '$1 == n && $2 == 2 && $3 == lub && $4 != "skipped"')"
      if [[ -z "${rows}" ]]; then
        printf '%-9s %4s %3s %10s\n' "${name}" "${n}" "${lub}" skipped
        continue
      fi
      f="$(awk '{print $5}' <<< "${rows}" | median)" t="$(awk '{print $8}' <<< "${rows}" | median)"
      [[ -n "${ref_f}" ]] || { ref_f="${f}"; ref_t="${t}"; }
      awk -v name="${name}" -v n="${n}" -v lub="${lub}" -v f="${f}" -v t="${t}" -v rf="${ref_f}" -v rt="${ref_t}" \
        'BEGIN {printf "%-9s %4s %3s %10.4f %10.4f %10.2f %10.2f\n", name, n, lub, f, t, (f > 0) ? rf / f : 0, (t > 0) ? rt / t : 0}'
    done
  done
done
