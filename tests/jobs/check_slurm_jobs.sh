#!/bin/bash
# The job scripts under a real SLURM (a single node started here: tests/jobs/slurm_cluster.sh),
# jobs submitted by an ordinary user from a copy of the project whose job scripts are edited
# only where jobs/README.md says (account, partition, tasks per node, time):
#   1. a small sweep with the srun launcher (SRUN_MPI=auto picks the PMI type srun offers):
#      COMPLETED, every case finished; the same sweep with srun --mpi=none (srun without the
#      PMI type, the old script's call) fails: the choice of the PMI type is what makes it work;
#   2. scancel of a running sweep (CANCELLED, the case file left 'running'), resubmission: the
#      case resumes and finishes with every frame exactly once;
#   3. a walltime kill (--time=1 given to sbatch) with MAX_RESUBMITS=12: the first job ends in
#      TIMEOUT, its follow-ups inherit the time limit and task count given on the command line
#      and resume (on a busy machine more than one ends in TIMEOUT), one completes, and its own
#      follow-up is cancelled (CANCELLED, never ran) -- or the sweep finishes in the seconds
#      between a job's walltime signal and its end (TIMEOUT, exit 0:0), and that job cancels
#      its follow-up before it runs;
#   4. a sweep whose case fails for good (max_steps): exit status 3, the follow-up cancelled;
#   5. jobs/submit_study.sh with a refused analysis job (too many tasks): exit 2, no job queued;
#   5b. the multipole study submitted held (--hold; its runs take hours): a sweep job for each of
#      its five sweeps (trefoil_table2_multipole, candycane_multipole, candycane_seeds_multipole,
#      candycane_epslub_multipole, candycane_order3_multipole, the list of issue 11 written out
#      here) with its scaled input and --ntasks-*, all held, and the analysis job depending on all
#      five; then cancelled, nothing ran;
#   6. the shortened study (--time-scale) with a follow-up per sweep: in its own directory, the
#      analysis job starts only after every sweep job (follow-ups included) has ended, COMPLETED,
#      analysing exactly the two sweeps it submitted (results.json); nothing written to results/;
#      the analysis re-run while a sweep job of the study is queued moves behind it, then reuses
#      everything stored;
# Every job state is read with scontrol show job (the controller keeps finished jobs for an
# hour: MinJobAge) and checked again in the job completion log (jobcomp/filetxt).
# Exit status 77 (ctest: skipped) with the reason when the daemons cannot start.
# Usage: check_slurm_jobs.sh SOURCE_DIR BUILD_DIR WORKDIR
set -uo pipefail
src="$(cd "$1" && pwd)" build="$(cd "$2" && pwd)" work="$3"
here="$(dirname "${BASH_SOURCE[0]}")"
# shellcheck source=tests/jobs/slurm_cluster.sh
source "${here}/slurm_cluster.sh"

t_start=$(date +%s)
fail() { echo "FAIL: $*" >&2; exit 1; }
log() { printf '[%4ds] %s\n' "$(( $(date +%s) - t_start ))" "$*"; }

rm -rf "${work}"
mkdir -p "${work}"
chmod 755 "${work}"
trap 'kf_slurm_stop' EXIT
if ! kf_slurm_start "${work}/slurm"; then
  echo "SKIP: no SLURM here: ${KF_SLURM_WHY}"
  exit 77
fi
log "SLURM up: $(sinfo -h -N -o '%N %c CPUs %T'), srun --mpi=list: $(srun --mpi=list 2>&1 | tr -d '\t' | tr '\n' ' ')"

# The ordinary user, and a copy of the project it owns (the executables of BUILD_DIR linked).
user=kfslurm
id -u "${user}" >/dev/null 2>&1 || useradd -r -M -d /nonexistent -s /bin/bash "${user}" \
  || { echo "SKIP: cannot create the user ${user} to submit jobs"; exit 77; }
proj="${work}/project"
mkdir -p "${proj}/build/bin" "${proj}/inputs" "${work}/home"
cp -r "${src}/jobs" "${src}/scripts" "${proj}/"
mkdir -p "${proj}/tools" && cp -r "${src}/tools/pyproject.toml" "${src}/tools/src" "${proj}/tools/"
cp "${src}/inputs/trefoil_table2.nml" "${src}/inputs/candycane.nml" "${src}"/inputs/*_multipole.nml "${proj}/inputs/"
ln -s "${build}/bin/knotflow" "${proj}/build/bin/knotflow"
ln -s "${build}/bin/knotflow-analyze" "${proj}/build/bin/knotflow-analyze"
# the C-interface library the tools call (knot cores in knotflow-study; tests/jobs/project_copy.sh)
mkdir -p "${proj}/build/lib" && ln -s "${build}/lib/libknotflow_capi.so" "${proj}/build/lib/libknotflow_capi.so"
chown -R "${user}" "${proj}" "${work}/home"
as_user() {
  runuser -u "${user}" -- env HOME="${work}/home" SLURM_CONF="${SLURM_CONF}" PATH="/usr/local/bin:/usr/bin:/bin" \
    bash -c "cd '${proj}' && $1"
}
# The analysis needs the Python tools in build/venv (scripts/build.sh installs them; here without
# a network: the system's numpy/h5py/matplotlib and the tools of this checkout).
as_user "/usr/bin/python3 -m venv --system-site-packages build/venv && build/venv/bin/python -m pip install -q --no-deps --no-build-isolation --no-index -e tools && build/venv/bin/knotflow-study --help >/dev/null" \
  >"${work}/venv.log" 2>&1 || { echo "SKIP: no Python tools for the analysis job (system python3 without numpy/h5py/matplotlib?): $(tail -n 2 "${work}/venv.log")"; exit 77; }

# The edits jobs/README.md asks for: account (none here), partition, ranks per node, walltime.
for f in "${proj}"/jobs/slurm_*.sh; do
  sed -i -e 's/^#SBATCH --account=.*/#SBATCH --account=kftest/' -e 's/^#SBATCH --partition=.*/#SBATCH --partition=debug/' \
         -e 's/^#SBATCH --ntasks-per-node=.*/#SBATCH --ntasks-per-node=2/' -e 's/^#SBATCH --time=.*/#SBATCH --time=00:10:00/' "${f}"
done

scene() {   # scene NAME "sweep line" "integrator extras" [frame interval]
  cat >"${proj}/inputs/$1.nml" <<NML
&chain shape = 'trefoil' /
&forces excluded_volume = .true. /
&integrator $3 /
&output directory = 'results/$1', frame_interval = ${4:-1.0}, progress_interval = 0.0 /
$2
NML
}
state() { scontrol show job "$1" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | cut -d= -f2; }
field() { scontrol show job "$1" 2>/dev/null | grep -o "$2=[^ ]*" | head -n 1 | cut -d= -f2-; }
wait_end() {   # wait_end JOBID SECONDS: the final state
  local k s
  for (( k = 0; k < $2; k++ )); do
    s="$(state "$1")"
    case "${s}" in COMPLETED|FAILED|CANCELLED|TIMEOUT|NODE_FAIL|OUT_OF_MEMORY|PREEMPTED|BOOT_FAIL|DEADLINE) echo "${s}"; return 0 ;; esac
    sleep 1
  done
  echo "${s:-UNKNOWN}"
}
expect_state() {   # expect_state JOBID STATE [EXIT]
  local s
  s="$(state "$1")"
  [[ "${s}" == "$2" ]] || fail "job $1: state ${s}, expected $2 ($(scontrol show job "$1" | tr '\n' ' '))"
  [[ -z "${3:-}" || "$(field "$1" ExitCode)" == "$3" ]] || fail "job $1: exit code $(field "$1" ExitCode), expected $3"
  grep -q "JobId=$1 .*JobState=$2" "${work}/slurm/log/jobcomp.txt" || fail "job $1: no JobState=$2 in the job completion log"
  log "job $1 ($(field "$1" JobName)): $2 exit $(field "$1" ExitCode)"
}
h5() { "${proj}/build/venv/bin/python" - "$@"; }   # the venv made above has h5py
frames_check() {   # frames_check FILE T_END INTERVAL: status finished, frames 0, dt, ..., t_end once each
  h5 "$1" "$2" "$3" <<'PY' || fail "case file $1 is not a finished sweep case with every frame once"
import sys, h5py, numpy as np
path, t_end, dt = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
with h5py.File(path, "r") as h:
    status = h.attrs["status"]
    status = status.decode() if isinstance(status, bytes) else status
    t = h["frames/time"][:]
assert status == "finished", status
assert np.allclose(t, np.arange(len(t)) * dt) and abs(t[-1] - t_end) < 1e-9, t
PY
}
status_of() { h5 "$1" <<'PY'
import sys, h5py
with h5py.File(sys.argv[1], "r") as h:
    s = h.attrs["status"]
print(s.decode() if isinstance(s, bytes) else s)
PY
}

# --- 3. (started first: it is the longest) walltime kill with follow-ups ----------------------
scene walltime "" "t_end = 5000.0" 50.0
w1=$(as_user "sbatch --parsable --time=1 --ntasks=1 --export=ALL,MAX_RESUBMITS=12 jobs/slurm_sweep.sh inputs/walltime.nml") \
  || fail "sbatch of the walltime sweep"
log "walltime sweep: job ${w1} (--time=1 --ntasks=1, MAX_RESUBMITS=12)"

# --- 1. a small sweep with srun ---------------------------------------------------------------
scene tiny "&sweep orientation = 'b', 'c' /" "t_end = 4.0"
j=$(as_user "sbatch --parsable --ntasks=2 jobs/slurm_sweep.sh inputs/tiny.nml") || fail "sbatch tiny"
[[ "$(wait_end "${j}" 120)" == COMPLETED ]] || true
expect_state "${j}" COMPLETED 0:0
grep -q -- "--mpi=pmix" "${proj}/knotflow-sweep-${j}.out" || fail "job ${j}: srun without --mpi=pmix: $(grep launcher "${proj}/knotflow-sweep-${j}.out")"
grep -q "2 ranks" "${proj}/knotflow-sweep-${j}.out" || fail "job ${j}: not on 2 ranks"
for c in b c; do frames_check "${proj}/results/tiny/or${c}.h5" 4 1; done
log "small sweep: 2 cases finished on 2 ranks with $(grep -o -- '--mpi=[a-z0-9_]*' "${proj}/knotflow-sweep-${j}.out")"
scene tiny_none "&sweep orientation = 'b', 'c' /" "t_end = 4.0"
j=$(as_user "SRUN_MPI=none sbatch --parsable --ntasks=2 jobs/slurm_sweep.sh inputs/tiny_none.nml") || fail "sbatch tiny_none"
wait_end "${j}" 120 >/dev/null
expect_state "${j}" FAILED
log "the same sweep with srun --mpi=none fails (the old script's srun call on this site)"

# --- 2. scancel and resubmit ------------------------------------------------------------------
scene cancel "" "t_end = 600.0" 5.0
c1=$(as_user "sbatch --parsable --ntasks=1 jobs/slurm_sweep.sh inputs/cancel.nml") || fail "sbatch cancel"
for (( k = 0; k < 240; k++ )); do   # until the case has written frames up to t = 20
  [[ -f "${proj}/results/cancel/case.h5" ]] && grep -q "t = 20.0" "${proj}/knotflow-sweep-${c1}.out" 2>/dev/null && break
  case "$(state "${c1}")" in COMPLETED|FAILED|CANCELLED|TIMEOUT) fail "job ${c1} ended before it could be cancelled" ;; esac
  sleep 0.5
done
as_user "scancel ${c1}"
wait_end "${c1}" 60 >/dev/null
expect_state "${c1}" CANCELLED
for (( k = 0; k < 20; k++ )); do   # the killed process may hold the file (HDF5 lock) a moment
  s="$(status_of "${proj}/results/cancel/case.h5" 2>/dev/null)" && break
  sleep 0.5
done
[[ "${s}" == running ]] || fail "after scancel the case file says '${s}', expected running"
c2=$(as_user "sbatch --parsable --ntasks=1 jobs/slurm_sweep.sh inputs/cancel.nml") || fail "sbatch resubmit"
wait_end "${c2}" 240 >/dev/null
expect_state "${c2}" COMPLETED 0:0
grep -q "resum" "${proj}/knotflow-sweep-${c2}.out" || fail "job ${c2} did not resume the case: $(cat "${proj}/knotflow-sweep-${c2}.out")"
frames_check "${proj}/results/cancel/case.h5" 600 5
log "scancel left the case 'running'; the resubmitted job resumed it: every frame once"

# --- 4. cases that fail for good stop the follow-ups ------------------------------------------
scene failing "" "t_end = 50.0, max_steps = 20"
f1=$(as_user "sbatch --parsable --ntasks=1 --export=ALL,MAX_RESUBMITS=3 jobs/slurm_sweep.sh inputs/failing.nml") || fail "sbatch failing"
wait_end "${f1}" 120 >/dev/null
expect_state "${f1}" FAILED 3:0
f2=$(grep -o 'follow-up job [0-9]*' "${proj}/knotflow-sweep-${f1}.out" | awk 'NR == 1 {print $3}')
[[ -n "${f2}" ]] || fail "job ${f1} submitted no follow-up"
wait_end "${f2}" 30 >/dev/null
expect_state "${f2}" CANCELLED
[[ "$(field "${f2}" RunTime)" == 00:00:00 ]] || fail "follow-up ${f2} of a sweep whose case failed for good ran"
log "a case failing for good (exit 3): the follow-up ${f2} cancelled before it ran"

# --- 5. no orphan jobs: a study whose analysis job is refused submits nothing -------------------
before=$(squeue -h | wc -l)
out=$(as_user "bash jobs/submit_study.sh slurm rpy --time-scale 0.004 --ntasks-analysis 64 2>&1"); rc=$?
[[ ${rc} -eq 2 ]] || fail "submit_study.sh with 64 analysis tasks on a 2-CPU node: exit ${rc}, expected 2: ${out}"
grep -q "refuses the analysis job" <<<"${out}" || fail "no reason given: ${out}"
[[ "$(squeue -h | wc -l)" -eq "${before}" ]] || fail "submit_study.sh left jobs queued: $(squeue)"
log "submit_study.sh with a refused analysis job: exit 2, nothing queued ($(tail -n 1 <<<"${out}"))"

# --- 5b. the multipole study, held: five sweep jobs, the analysis after all of them ------------
out=$(as_user "bash jobs/submit_study.sh slurm multipole --time-scale 0.001 --hold --ntasks-trefoil 1 --ntasks-ensemble 1 --ntasks-analysis 1 2>&1") \
  || fail "submit_study.sh slurm multipole --hold: ${out}"
mp="results/study_multipole_t0.001"
held=()
for s in trefoil_table2_multipole candycane_multipole candycane_seeds_multipole candycane_epslub_multipole candycane_order3_multipole; do
  j=$(sed -n "s/^submitted: sweep ${s} \([0-9]*\)\$/\1/p" <<<"${out}")
  [[ -n "${j}" ]] || fail "the multipole study submitted no ${s} sweep: ${out}"
  held+=("${j}")
  [[ "$(scontrol show job "${j}" | grep -o 'Command=.*')" == *"/jobs/slurm_sweep.sh ${mp}/inputs/${s}.nml" ]] \
    || fail "job ${j} does not run the sweep ${mp}/inputs/${s}.nml: $(scontrol show job "${j}" | grep Command)"
  [[ "$(state "${j}")" == PENDING && "$(field "${j}" Reason)" == JobHeldUser ]] || fail "sweep job ${j} is not held: $(state "${j}") $(field "${j}" Reason)"
  want=1   # --ntasks-trefoil 1, --ntasks-ensemble 1; the candy-canes and the probes the script's 2 per node
  [[ "${s}" == candycane_multipole || "${s}" == candycane_*_multipole && "${s}" != candycane_seeds_multipole ]] && want=2
  [[ "$(field "${j}" NumTasks)" == "${want}" ]] || fail "sweep job ${j} (${s}): NumTasks=$(field "${j}" NumTasks), expected ${want}"
  case "${s}" in trefoil*) te=1 ;; candycane_order3_multipole) te=0.9 ;; *) te=2 ;; esac
  grep -q "t_end = ${te}," "${proj}/${mp}/inputs/${s}.nml" || fail "${mp}/inputs/${s}.nml: t_end not scaled"
done
[[ "$(grep -c '^submitted: sweep ' <<<"${out}")" -eq 5 ]] || fail "the multipole study submitted other sweeps too: ${out}"
ma=$(sed -n 's/^submitted: analysis \([0-9]*\) .*/\1/p' <<<"${out}")
[[ -n "${ma}" ]] || fail "no analysis job: ${out}"
dep="$(field "${ma}" Dependency)"
for j in "${held[@]}"; do [[ "${dep}" == *"afterany:${j}("* ]] || fail "the multipole analysis ${ma} does not wait for sweep job ${j}: Dependency=${dep}"; done
[[ "$(scontrol show job "${ma}" | grep -o 'Command=.*')" == *"jobs/slurm_study.sh multipole" ]] || fail "analysis ${ma}: $(scontrol show job "${ma}" | grep Command)"
as_user "scancel ${held[*]} ${ma}"
for j in "${held[@]}" "${ma}"; do
  wait_end "${j}" 30 >/dev/null
  [[ "$(state "${j}")" == CANCELLED && "$(field "${j}" RunTime)" == 00:00:00 ]] || fail "held job ${j} ran or was not cancelled: $(state "${j}")"
done
log "multipole study (held): sweeps ${held[*]} (trefoil_table2_multipole, candycane_multipole, candycane_seeds_multipole, candycane_epslub_multipole, candycane_order3_multipole), analysis ${ma} after all five; cancelled unrun"

# --- 6. the shortened study with its analysis job ---------------------------------------------
out=$(as_user "bash jobs/submit_study.sh slurm rpy --time-scale 0.004 --ntasks-trefoil 2 --ntasks-candycane 1 --ntasks-analysis 2 --max-resubmits 1 --quick-analysis 2>&1") \
  || fail "submit_study.sh: ${out}"
log "${out//$'\n'/ }"
sa=$(sed -n 's/^submitted: sweep trefoil_table2 \([0-9]*\)$/\1/p' <<<"${out}")
sb=$(sed -n 's/^submitted: sweep candycane \([0-9]*\)$/\1/p' <<<"${out}")
sc=$(sed -n 's/^submitted: analysis \([0-9]*\) .*/\1/p' <<<"${out}")
[[ -n "${sa}" && -n "${sb}" && -n "${sc}" && "$(grep -c '^submitted: sweep ' <<<"${out}")" -eq 2 ]] \
  || fail "not the two rpy sweeps and the analysis: ${out}"
study="${proj}/results/study_rpy_t0.004"
for j in "${sa}" "${sb}"; do
  wait_end "${j}" 300 >/dev/null
  expect_state "${j}" COMPLETED 0:0
done
# the analysis job: the one submitted, or the one it moved to while follow-ups were queued
last="${sc}"
for (( k = 0; k < 600; k++ )); do
  s="$(state "${last}")"
  if [[ "${s}" == COMPLETED ]] && grep -q "analysis moved to job" "${proj}/knotflow-study-${last}.out" 2>/dev/null; then
    last=$(sed -n 's/.*analysis moved to job \([0-9]*\).*/\1/p' "${proj}/knotflow-study-${last}.out")
    log "analysis job moved behind the follow-ups: job ${last}"
    continue
  fi
  case "${s}" in COMPLETED|FAILED|CANCELLED|TIMEOUT) break ;; esac
  sleep 1
done
expect_state "${last}" COMPLETED 0:0
start_analysis=$(date -d "$(field "${last}" StartTime)" +%s)
for j in $(squeue -h -t all -n knotflow-rpy-t0.004-sweep -o %i 2>/dev/null; echo "${sa} ${sb}"); do
  s="$(state "${j}")"
  [[ "${s}" == CANCELLED && "$(field "${j}" RunTime)" == 00:00:00 ]] && continue
  end=$(date -d "$(field "${j}" EndTime)" +%s)
  (( end <= start_analysis )) || fail "sweep job ${j} ended at $(field "${j}" EndTime), after the analysis started ($(field "${last}" StartTime))"
done
[[ -s "${study}/reproduction/results.json" ]] || fail "no ${study}/reproduction/results.json: $(tail -n 5 "${proj}/knotflow-study-${last}.out")"
grep -q "candycane_seeds\|trefoil_table2_p24" "${proj}/knotflow-study-${last}.out" && fail "the analysis looked at sweeps it did not submit"
[[ ! -e "${proj}/results/trefoil_table2" && ! -e "${proj}/results/reproduction" ]] || fail "the shortened study wrote into results/ of the real run"
log "shortened study: sweeps ${sa} ${sb} (and follow-ups), analysis ${last} COMPLETED after all of them; ${study}/reproduction/results.json"

# --- 6b. re-running the analysis while a sweep job of the study is queued: it moves behind it,
# and runs when that job has ended (reusing everything stored: no new frame analysed) ---------
hold=$(as_user "sbatch --parsable --hold --job-name=knotflow-rpy-t0.004-sweep --ntasks=1 --output=/dev/null --wrap true") \
  || fail "sbatch of the held job"
r1=$(as_user "sbatch --parsable --ntasks=2 --export=ALL,STUDY_DIR=results/study_rpy_t0.004,WAIT_FOR=knotflow-rpy-t0.004-sweep,STUDY_QUICK=1 jobs/slurm_study.sh rpy") \
  || fail "sbatch of the analysis re-run"
wait_end "${r1}" 120 >/dev/null
expect_state "${r1}" COMPLETED 0:0
r2=$(sed -n 's/.*analysis moved to job \([0-9]*\).*/\1/p' "${proj}/knotflow-study-${r1}.out")
[[ -n "${r2}" ]] || fail "the analysis ${r1} ran while sweep job ${hold} was queued: $(head -n 5 "${proj}/knotflow-study-${r1}.out")"
sleep 3
[[ "$(state "${r2}")" == PENDING && "$(field "${r2}" Dependency)" == *"${hold}"* ]] \
  || fail "the moved analysis ${r2} does not wait for ${hold}: $(state "${r2}") $(field "${r2}" Dependency)"
as_user "scontrol release ${hold}"
wait_end "${hold}" 60 >/dev/null
wait_end "${r2}" 300 >/dev/null
expect_state "${r2}" COMPLETED 0:0
{ grep -q "0 new)" "${proj}/knotflow-study-${r2}.out" && ! grep -qE "\(([1-9][0-9]*) new\)" "${proj}/knotflow-study-${r2}.out"; } \
  || fail "the re-run analysis ${r2} recomputed stored frames: $(grep new "${proj}/knotflow-study-${r2}.out" | head -n 3)"
log "analysis re-run ${r1} moved behind the queued sweep job ${hold} to ${r2}, which ran after it and reused everything"

# --- 3. (end) the walltime chain: TIMEOUT, follow-ups that resume (more TIMEOUTs on a slow or
# busy machine), one COMPLETED and its own follow-up CANCELLED, or the last TIMEOUT the one that
# finished the sweep and cancelled its follow-up ------------------------------------------------
follow() { grep -o 'follow-up job [0-9]*' "${proj}/knotflow-sweep-$1.out" 2>/dev/null | awk 'NR == 1 {print $3}'; }
wait_end "${w1}" 400 >/dev/null
expect_state "${w1}" TIMEOUT
chain="${w1} TIMEOUT"
prev="${w1}"
while true; do
  next="$(follow "${prev}")"
  [[ -n "${next}" ]] || fail "job ${prev} (TIMEOUT) submitted no follow-up: $(head -n 3 "${proj}/knotflow-sweep-${prev}.out")"
  [[ "$(field "${next}" TimeLimit)" == 00:01:00 ]] \
    || fail "follow-up ${next} did not inherit --time=1: TimeLimit=$(field "${next}" TimeLimit)"
  s="$(wait_end "${next}" 400)"
  # The walltime's SIGTERM may reach knotflow while it writes the last frame: the sweep then
  # ends (status 0, the closing line printed), the job is still TIMEOUT (its script exits 0) and
  # the script cancels the follow-up before it runs. That ends the chain.
  if [[ "${s}" == CANCELLED ]] && grep -q "follow-up job ${next} cancelled" "${proj}/knotflow-sweep-${prev}.out"; then
    [[ "$(field "${next}" RunTime)" == 00:00:00 ]] || fail "follow-up ${next}, cancelled by ${prev}, ran"
    [[ "$(field "${prev}" ExitCode)" == 0:0 ]] || fail "job ${prev} cancelled its follow-up but exited $(field "${prev}" ExitCode)"
    expect_state "${next}" CANCELLED
    chain="${chain}, ${next} CANCELLED (the sweep finished in ${prev}'s last seconds)"
    next=""
    break
  fi
  grep -q "job ${next}, 1 ranks" "${proj}/knotflow-sweep-${next}.out" \
    || fail "follow-up ${next} did not inherit --ntasks=1: $(grep ranks "${proj}/knotflow-sweep-${next}.out")"
  grep -q "resum" "${proj}/knotflow-sweep-${next}.out" || fail "follow-up ${next} did not resume: $(cat "${proj}/knotflow-sweep-${next}.out")"
  chain="${chain}, ${next} ${s}"
  [[ "${s}" == TIMEOUT ]] || break
  expect_state "${next}" TIMEOUT
  prev="${next}"
done
last_follow=""
if [[ -n "${next}" ]]; then
  expect_state "${next}" COMPLETED 0:0
  last_follow="$(follow "${next}")"
fi
if [[ -n "${last_follow}" ]]; then
  wait_end "${last_follow}" 30 >/dev/null
  expect_state "${last_follow}" CANCELLED
  chain="${chain}, ${last_follow} CANCELLED"
fi
frames_check "${proj}/results/walltime/case.h5" 5000 50
log "walltime chain (--time=1 --ntasks=1 inherited, each follow-up resumed): ${chain}"
log "all SLURM checks passed"
