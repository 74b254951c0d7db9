#!/bin/bash
# The study's sweep list (scripts/study_sweeps.sh) and how jobs/submit_study.sh submits it under
# PBS, with qsub and qdel replaced by recorders (no PBS server here; jobs_slurm submits to a real
# SLURM). Expected lists from issue 11 and docs/REPRODUCTION.md, written out here:
#   1. scripts/reproduce.sh --list-sweeps: rpy = trefoil_table2, candycane (+ candycane_seeds,
#      trefoil_table2_p24 unless --no-extras); multipole = trefoil_table2_multipole,
#      candycane_multipole, candycane_seeds_multipole and the probes candycane_epslub_multipole,
#      candycane_order3_multipole, with or without --no-extras;
#   2. sourcing scripts/study_sweeps.sh sets no variable and runs no command (a login node);
#   3. submit_study.sh pbs multipole --time-scale: one sweep job per multipole sweep, each with
#      its scaled input (t_end x F, output in the trial's directory) and its --ntasks-*; the
#      analysis job depends on every sweep job id qsub printed; rpy submits exactly two sweeps
#      (with --hold: every job held);
#   4. a submission refused by a check (knotflow-analyze missing) writes no trial inputs; a
#      qsub that fails at the third job: the two queued are deleted, no analysis submitted;
#      --ntasks-ensemble for rpy (no ensemble there) is refused before any qsub.
# Usage: check_study_sweeps.sh SOURCE_DIR WORKDIR
set -uo pipefail
src="$(cd "$1" && pwd)" work="$2"
fail() { echo "FAIL: $*" >&2; exit 1; }
rm -rf "${work}"
mkdir -p "${work}"

# --- 1. the lists ---------------------------------------------------------------------------
lists() { bash "${src}/scripts/reproduce.sh" --list-sweeps "$@" | awk '{print $2}' | paste -sd' '; }
check_list() {   # check_list "EXPECTED" ARGS...
  local want="$1" got
  shift
  got="$(lists "$@")" || fail "reproduce.sh --list-sweeps $*: failed"
  [[ "${got}" == "${want}" ]] || fail "reproduce.sh --list-sweeps $*: '${got}', expected '${want}'"
}
check_list "trefoil_table2 candycane candycane_seeds trefoil_table2_p24"
check_list "trefoil_table2 candycane" --no-extras
check_list "trefoil_table2_multipole candycane_multipole candycane_seeds_multipole candycane_epslub_multipole candycane_order3_multipole" --hydro multipole
check_list "trefoil_table2_multipole candycane_multipole candycane_seeds_multipole candycane_epslub_multipole candycane_order3_multipole" --hydro multipole --no-extras
out=$(bash "${src}/scripts/reproduce.sh" --list-sweeps --hydro lattice 2>&1) && fail "an unknown --hydro was accepted: ${out}"
[[ "${out}" == *"lattice is unknown (allowed: rpy, multipole)"* ]] || fail "unknown --hydro: ${out}"
for s in trefoil_table2_multipole candycane_multipole candycane_seeds_multipole candycane_epslub_multipole candycane_order3_multipole; do
  [[ -r "${src}/inputs/${s}.nml" ]] || fail "the listed sweep has no input inputs/${s}.nml"
done
echo "sweep lists: rpy 4 (2 without extras), multipole 5 with the seeds ensemble and the two probes"

# --- 2. sourcing without side effects ---------------------------------------------------------
mkdir -p "${work}/shims"
for tool in apt-get dpkg sudo python3 mpirun; do
  printf '#!/bin/sh\necho "%s $*" >>"%s/calls"\nexit 1\n' "${tool}" "${work}" >"${work}/shims/${tool}"
  chmod +x "${work}/shims/${tool}"
done
diff_vars=$(PATH="${work}/shims:${PATH}" bash -c '
  before="$(compgen -v | sort)"
  source "$1/scripts/study_sweeps.sh"
  comm -13 <(printf "%s\n" "${before}") <(compgen -v | sort | grep -vxE "before|PIPESTATUS")' _ "${src}")
[[ -z "${diff_vars}" ]] || fail "sourcing scripts/study_sweeps.sh set variables: ${diff_vars}"
[[ ! -s "${work}/calls" ]] || fail "sourcing scripts/study_sweeps.sh ran commands: $(cat "${work}/calls")"
echo "sourcing scripts/study_sweeps.sh: no variable set, no command run"

# --- 3. PBS submission of the multipole study ------------------------------------------------
proj="${work}/project"
mkdir -p "${proj}/build/bin" "${proj}/build/venv/bin" "${proj}/inputs" "${work}/bin"
cp -r "${src}/jobs" "${src}/scripts" "${proj}/"
cp "${src}"/inputs/trefoil_table2*.nml "${src}"/inputs/candycane*.nml "${proj}/inputs/"
# submit_study.sh only checks that the executables are there; these fail if anything runs them
for exe in build/bin/knotflow build/bin/knotflow-analyze build/venv/bin/knotflow-study; do
  printf '#!/bin/sh\necho "%s must not run at submission" >&2\nexit 1\n' "${exe}" >"${proj}/${exe}"
  chmod +x "${proj}/${exe}"
done
# qsub: one line per call (the arguments, tab-separated) in qsub.calls, job id N.pbs printed;
# it fails at call QSUB_FAIL_AT. qdel: its arguments in qdel.calls.
cat >"${work}/bin/qsub" <<SH
#!/bin/bash
n=\$(( \$(cat "${work}/qsub.calls" 2>/dev/null | wc -l) + 1 ))
(IFS=\$'\t'; echo "\$*") >>"${work}/qsub.calls"
[[ "\${QSUB_FAIL_AT:-0}" == "\${n}" ]] && { echo "qsub: Job exceeds queue resource limits" >&2; exit 1; }
echo "\${n}.pbs"
SH
printf '#!/bin/bash\necho "$*" >>"%s/qdel.calls"\n' "${work}" >"${work}/bin/qdel"
chmod +x "${work}/bin/qsub" "${work}/bin/qdel"
submit() { (cd "${proj}" && PATH="${work}/bin:${PATH}" bash jobs/submit_study.sh pbs "$@" 2>&1); }
call() { sed -n "$1p" "${work}/qsub.calls" | tr '\t' ' '; }

rm -f "${work}/qsub.calls" "${work}/qdel.calls"
out=$(submit multipole --time-scale 0.001 --ntasks-trefoil 29 --ntasks-ensemble 4 --ntasks-analysis 8) \
  || fail "submit_study.sh pbs multipole: ${out}"
study=results/study_multipole_t0.001
[[ "$(wc -l < "${work}/qsub.calls")" -eq 6 ]] || fail "expected 5 sweep jobs and the analysis, qsub got: $(cat "${work}/qsub.calls")"
declare -A t_end=([trefoil_table2_multipole]=1 [candycane_multipole]=2 [candycane_seeds_multipole]=2
                  [candycane_epslub_multipole]=2 [candycane_order3_multipole]=0.9)
declare -A select=([trefoil_table2_multipole]=29 [candycane_multipole]="" [candycane_seeds_multipole]=4
                   [candycane_epslub_multipole]="" [candycane_order3_multipole]="")
found=""
for k in 1 2 3 4 5; do
  c="$(call "${k}")"
  [[ "${c}" == *"-N knotflow-multipole-t0.001-sweep "* && "${c}" == *jobs/pbs_sweep.sh ]] || fail "qsub call ${k} is not a sweep job: ${c}"
  s=$(sed -n "s|.*SWEEP=${study}/inputs/\([a-z0-9_]*\)\.nml.*|\1|p" <<<"${c}")
  [[ -n "${s}" && -n "${t_end[${s}]+set}" ]] || fail "qsub call ${k}: not a multipole sweep of the trial: ${c}"
  found="${found} ${s}"
  nml="${proj}/${study}/inputs/${s}.nml"
  grep -q "t_end = ${t_end[${s}]}," "${nml}" || fail "${nml}: t_end not scaled to ${t_end[${s}]}: $(grep t_end "${nml}")"
  grep -q "directory = '${study}/${s}'" "${nml}" || fail "${nml}: output not in the trial's directory: $(grep directory "${nml}")"
  if [[ -n "${select[${s}]}" ]]; then
    [[ "${c}" == *"-l select=1:ncpus=${select[${s}]}:mpiprocs=${select[${s}]} "* ]] || fail "sweep ${s} without its ${select[${s}]} ranks: ${c}"
  else
    [[ "${c}" != *"-l select"* ]] || fail "sweep ${s} with ranks nobody asked for: ${c}"
  fi
  grep -qx "submitted: sweep ${s} ${k}.pbs" <<<"${out}" || fail "no 'submitted: sweep ${s} ${k}.pbs' line: ${out}"
done
[[ "$(tr ' ' '\n' <<<"${found}" | sort | paste -sd' ')" == " candycane_epslub_multipole candycane_multipole candycane_order3_multipole candycane_seeds_multipole trefoil_table2_multipole" ]] \
  || fail "the multipole sweeps submitted: ${found}, expected each of trefoil_table2_multipole candycane_multipole candycane_seeds_multipole candycane_epslub_multipole candycane_order3_multipole once"
c="$(call 6)"
[[ "${c}" == *"-N knotflow-multipole-t0.001-analysis "* && "${c}" == *jobs/pbs_study.sh ]] || fail "qsub call 6 is not the analysis: ${c}"
[[ "${c}" == *"-W depend=afterany:1.pbs:2.pbs:3.pbs:4.pbs:5.pbs "* ]] || fail "the analysis does not wait for the 5 sweep jobs: ${c}"
[[ "${c}" == *"-l select=1:ncpus=8:mpiprocs=8 "* && "${c}" == *"HYDRO=multipole,STUDY_DIR=${study},WAIT_FOR=knotflow-multipole-t0.001-sweep,"* ]] \
  || fail "the analysis job's ranks or settings: ${c}"
grep -q "^submitted: analysis 6.pbs (runs after the 5 sweep jobs" <<<"${out}" || fail "no analysis line: ${out}"
[[ ! -e "${work}/qdel.calls" ]] || fail "jobs deleted after a successful submission: $(cat "${work}/qdel.calls")"
echo "pbs multipole: 5 sweep jobs (scaled inputs, ranks per role), the analysis after all 5 ids"

rm -f "${work}/qsub.calls"
out=$(submit rpy --time-scale 0.001 --hold) || fail "submit_study.sh pbs rpy: ${out}"
[[ "$(grep -c '^submitted: sweep ' <<<"${out}")" -eq 2 && "${out}" == *"sweep trefoil_table2 1.pbs"* && "${out}" == *"sweep candycane 2.pbs"* ]] \
  || fail "pbs rpy: expected the sweeps trefoil_table2 and candycane: ${out}"
[[ "$(call 3)" == *"-W depend=afterany:1.pbs:2.pbs "* ]] || fail "rpy analysis dependency: $(call 3)"
for k in 1 2 3; do [[ "$(call "${k}")" == "-h -N "* ]] || fail "--hold: qsub call ${k} not held: $(call "${k}")"; done
grep -qx "held: release with qrls 1.pbs 2.pbs 3.pbs" <<<"${out}" || fail "--hold: no release command: ${out}"
echo "pbs rpy --hold: 2 sweep jobs, the analysis after both, all held"

# --- 4. failures ------------------------------------------------------------------------------
# a submission refused by a check (an executable missing) writes no trial inputs first
mv "${proj}/build/bin/knotflow-analyze" "${work}/knotflow-analyze.away"
out=$(submit rpy --time-scale 0.5) && fail "a missing knotflow-analyze went unnoticed: ${out}"
[[ "${out}" == *"knotflow-analyze not found"* ]] || fail "missing executable not named: ${out}"
[[ ! -e "${proj}/results/study_rpy_t0.5" ]] || fail "a refused submission wrote its trial inputs: $(ls -R "${proj}/results/study_rpy_t0.5")"
mv "${work}/knotflow-analyze.away" "${proj}/build/bin/knotflow-analyze"
echo "a refused trial submission writes nothing (checks first)"
rm -f "${work}/qsub.calls"
out=$(QSUB_FAIL_AT=3 submit multipole --time-scale 0.001) && fail "a failed qsub went unnoticed: ${out}"
[[ "$(cat "${work}/qdel.calls" 2>/dev/null)" == "1.pbs 2.pbs" ]] || fail "the queued jobs were not deleted: qdel $(cat "${work}/qdel.calls" 2>/dev/null); ${out}"
[[ "$(wc -l < "${work}/qsub.calls")" -eq 3 ]] || fail "submissions went on after the failure: $(cat "${work}/qsub.calls")"
echo "a qsub failing at the third sweep: the two queued deleted, no analysis submitted"
rm -f "${work}/qsub.calls"
out=$(submit rpy --ntasks-ensemble 4); rc=$?
[[ ${rc} -eq 2 && "${out}" == *"the rpy study has no ensemble sweep"* ]] || fail "--ntasks-ensemble for rpy: exit ${rc}: ${out}"
[[ ! -e "${work}/qsub.calls" ]] || fail "qsub called before the options were checked"
echo "--ntasks-ensemble for rpy refused before any qsub"
