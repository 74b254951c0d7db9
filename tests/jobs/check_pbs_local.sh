#!/bin/bash
# jobs/pbs_sweep.sh run locally, as jobs/README.md describes, with a PBS node file of 2 slots:
# the ranks come from the node file, which is passed to mpirun (MPIRUN_HOSTFILE, Open MPI's
# --hostfile; without it a multi-node job would start every rank on the first node): the sweep
# runs on 2 ranks and every case finishes; a rerun skips them all.
# Usage: check_pbs_local.sh SOURCE_DIR BUILD_DIR WORKDIR "MPIEXEC_FLAGS"
set -uo pipefail
src="$(cd "$1" && pwd)" build="$(cd "$2" && pwd)" work="$3" flags="${4:-}"
fail() { echo "FAIL: $*" >&2; exit 1; }
rm -rf "${work}"
mkdir -p "${work}/project/build/bin" "${work}/project/inputs"
cp -r "${src}/jobs" "${src}/scripts" "${work}/project/"
ln -s "${build}/bin/knotflow" "${work}/project/build/bin/knotflow"
cat >"${work}/project/inputs/tiny.nml" <<'NML'
&chain shape = 'trefoil' /
&forces excluded_volume = .true. /
&integrator t_end = 3.0 /
&output directory = 'results/tiny', frame_interval = 1.0, progress_interval = 0.0 /
&sweep orientation = 'a', 'b', 'c' /
NML
printf '%s\n%s\n' "$(hostname)" "$(hostname)" >"${work}/nodefile"
# mpirun behind a wrapper that records its arguments (the node file must be among them)
printf '#!/bin/bash\necho "$*" >>"%s/mpirun.args"\nexec mpirun "$@"\n' "${work}" >"${work}/mpirun"
chmod +x "${work}/mpirun"
cd "${work}/project" || fail "no project directory"
run() {
  PBS_NODEFILE="${work}/nodefile" PBS_JOBID=local.1 SWEEP=inputs/tiny.nml MPIRUN="${work}/mpirun" MPIRUN_FLAGS="${flags}" \
    bash jobs/pbs_sweep.sh >"${work}/$1.log" 2>&1
}
run first || fail "pbs_sweep.sh failed: $(tail -n 20 "${work}/first.log")"
grep -q "job local.1, 2 ranks" "${work}/first.log" || fail "not 2 ranks from the node file: $(head -n 3 "${work}/first.log")"
grep -q -- "--hostfile ${work}/nodefile -n 2 " "${work}/mpirun.args" || fail "mpirun without the node file: $(cat "${work}/mpirun.args")"
grep -q "on 2 rank(s)" "${work}/first.log" || fail "knotflow did not run on 2 ranks: $(cat "${work}/first.log")"
grep -q "3 finished, 0 skipped" "${work}/first.log" || fail "not every case finished: $(tail -n 5 "${work}/first.log")"
run again || fail "the rerun failed: $(tail -n 20 "${work}/again.log")"
grep -q "0 finished, 3 skipped" "${work}/again.log" || fail "the rerun did not skip the cases: $(tail -n 5 "${work}/again.log")"
echo "pbs_sweep.sh: 3 cases on 2 ranks of the node file, rerun skipped them"
