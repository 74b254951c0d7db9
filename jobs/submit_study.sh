#!/bin/bash
# Submit the whole reproduction of the reference study: one sweep job for every sweep of the
# study (scripts/study_sweeps.sh, the list scripts/reproduce.sh analyses; without the RPY
# extras), and the analysis job that runs when all of them have ended (follow-up jobs included)
# and analyses exactly these sweeps:
#   rpy        trefoil_table2 (29 cases), candycane (3 cases)
#   multipole  trefoil_table2_multipole (29), candycane_multipole (3), candycane_seeds_multipole (4),
#              candycane_epslub_multipole (1) and candycane_order3_multipole (1), the probes of
#              issue 11
#   bash jobs/submit_study.sh slurm|pbs [rpy|multipole] [options]
# Options:
#   --time-scale F       a shortened trial: every t_end times F (0 < F <= 1), into its own
#                        directory results/study_<hydro>_t<F>/ (inputs and results), with its own
#                        job names, so a trial never blocks or touches the real run
#   --ntasks-trefoil N   MPI ranks of the sweep of that role (default: the sweep script's
#   --ntasks-candycane N   directives; 29, 3 and 4 run every case at once);
#   --ntasks-ensemble N    --ntasks-ensemble and --ntasks-probe only where the study has them
#   --ntasks-probe N       (multipole)
#   --ntasks-analysis N  MPI ranks of the analysis job (default: the study script's directives)
#   --max-resubmits N    follow-up jobs of each sweep (MAX_RESUBMITS, default 0)
#   --quick-analysis     few closures in the analysis (scripts/reproduce.sh --quick): for a trial
#   --hold               submit every job held (sbatch --hold, qsub -h): nothing starts until
#                        released (scontrol release ID... / qrls ID..., printed), e.g. after a look
#                        at the queue
# Settings of the job scripts (BUILD_DIR, MODULES, LAUNCHER, SRUN_MPI, HDF5_FILE_LOCKING; MPIRUN,
# MPIRUN_FLAGS, MPIRUN_HOSTFILE on PBS) are taken from the environment. Everything is checked
# before the first job is submitted (under SLURM every job with sbatch --test-only); if a
# submission fails, the jobs already queued are cancelled. Prints the job ids, one
# "submitted: sweep NAME ID" line per sweep and "submitted: analysis ID ...".
# With multipole (L = 2 + lubrication) a trefoil case takes hours and a candy-cane case about a
# day: raise the walltime in the sweep scripts or use --max-resubmits (jobs/README.md).
set -euo pipefail
die() { echo "ERROR: $*" >&2; exit 2; }
usage="usage: bash jobs/submit_study.sh slurm|pbs [rpy|multipole] [--time-scale F] [--ntasks-trefoil N] [--ntasks-candycane N] [--ntasks-ensemble N] [--ntasks-probe N] [--ntasks-analysis N] [--max-resubmits N] [--quick-analysis] [--hold]"
scheduler="${1:-}"
[[ "${scheduler}" == slurm || "${scheduler}" == pbs ]] || die "${usage}"
shift
hydro=rpy
if [[ $# -gt 0 && "$1" != --* ]]; then hydro="$1"; shift; fi

cd "$(dirname "${BASH_SOURCE[0]}")/.."
export KNOTFLOW_DIR="${PWD}"
build="${BUILD_DIR:-build}"
# The study's sweeps and their roles (trefoil, candycane, ensemble): one job each.
# shellcheck source=scripts/study_sweeps.sh
source scripts/study_sweeps.sh
kf_study_arrays "${hydro}" 0 || exit 2
roles=("${KF_STUDY_ROLES[@]}") sweeps=("${KF_STUDY_SWEEPS[@]}")

scale="" resubmits=0 quick=0 hold=()
declare -A ntasks=()
while [[ $# -gt 0 ]]; do
  if [[ "$1" == --quick-analysis ]]; then quick=1; shift; continue; fi
  if [[ "$1" == --hold ]]; then hold=("$([[ ${scheduler} == slurm ]] && echo --hold || echo -h)"); shift; continue; fi
  [[ $# -ge 2 ]] || die "option $1 needs a value (${usage})"
  case "$1" in
    --time-scale) scale="$2" ;;
    --ntasks-*)
      what="${1#--ntasks-}"
      [[ " ${roles[*]} analysis " == *" ${what} "* ]] \
        || die "option $1: the ${hydro} study has no ${what} sweep (its ranks: $(printf -- '--ntasks-%s ' "${roles[@]}" analysis))"
      [[ "$2" =~ ^[1-9][0-9]*$ ]] || die "$1 must be an integer >= 1, not '$2'"
      ntasks[${what}]="$2" ;;
    --max-resubmits) resubmits="$2" ;;
    *) die "unknown option $1 (${usage})" ;;
  esac
  shift 2
done
[[ "${resubmits}" =~ ^[0-9]+$ ]] || die "--max-resubmits must be an integer >= 0, not '${resubmits}'"
if [[ -n "${scale}" ]]; then
  awk -v f="${scale}" 'BEGIN { exit !(f ~ /^[0-9]*\.?[0-9]+([eE][-+]?[0-9]+)?$/ && f + 0 > 0 && f + 0 <= 1) }' \
    || die "--time-scale must be a number in (0, 1], not '${scale}'"
fi

# Check everything that needs no written input before a trial's inputs are written (a refused
# submission leaves no trial directory behind).
for s in "${sweeps[@]}"; do [[ -r "inputs/${s}.nml" ]] || die "inputs/${s}.nml not found"; done
for exe in "${build}/bin/knotflow" "${build}/bin/knotflow-analyze" "${build}/venv/bin/knotflow-study"; do
  [[ -x "${exe}" ]] || die "${exe} not found: build with 'KNOTFLOW_BUILD_DIR=${build} bash scripts/build.sh' (installs the analysis tools too)"
done
command -v "$([[ ${scheduler} == slurm ]] && echo sbatch || echo qsub)" >/dev/null \
  || die "no $([[ ${scheduler} == slurm ]] && echo sbatch || echo qsub) on this machine"

# Inputs and names: the study, or a shortened trial with its own directory and job names.
inputs=()
if [[ -z "${scale}" ]]; then
  study_dir=results
  tag="knotflow-${hydro}"
  for s in "${sweeps[@]}"; do inputs+=("inputs/${s}.nml"); done
else
  study_dir="results/study_${hydro}_t${scale}"
  tag="knotflow-${hydro}-t${scale}"
  mkdir -p "${study_dir}/inputs"
  for s in "${sweeps[@]}"; do
    [[ -r "inputs/${s}.nml" ]] || die "inputs/${s}.nml not found"
    # t_end scaled, the output directory moved into the trial's directory
    awk -v f="${scale}" -v dir="${study_dir}/${s}" -v q="'" '
      /^[ \t]*!/ { print; next }
      { if (match($0, /t_end *= *[0-9.eEdD+-]+/)) {
          v = substr($0, RSTART, RLENGTH); sub(/t_end *= */, "", v); gsub(/[dD]/, "e", v)
          $0 = substr($0, 1, RSTART - 1) sprintf("t_end = %.6g", v * f) substr($0, RSTART + RLENGTH) }
        if (match($0, /directory *= *\047[^\047]*\047/))
          $0 = substr($0, 1, RSTART - 1) "directory = " q dir q substr($0, RSTART + RLENGTH)
        print }' "inputs/${s}.nml" > "${study_dir}/inputs/${s}.nml"
    grep -q "t_end = " "${study_dir}/inputs/${s}.nml" || die "inputs/${s}.nml: no t_end to scale"
    inputs+=("${study_dir}/inputs/${s}.nml")
  done
fi

# Check everything before submitting anything.
for f in "${inputs[@]}"; do [[ -r "${f}" ]] || die "sweep file ${f} not found"; done

submitted=()
cancel_queued() {
  if [[ ${#submitted[@]} -gt 0 ]]; then
    echo "ERROR: a submission failed: cancelling the jobs already queued: ${submitted[*]}" >&2
    if [[ "${scheduler}" == slurm ]]; then scancel "${submitted[@]}" || true; else qdel "${submitted[@]}" || true; fi
  fi
}
trap 'cancel_queued' ERR

ids=()
if [[ "${scheduler}" == slurm ]]; then
  sweep_opts() {   # sweep_opts ROLE: the sbatch options of the sweep job of that role
    opts=("${hold[@]}" --job-name="${tag}-sweep" --export="ALL,BUILD_DIR=${build},KNOTFLOW_DIR=${KNOTFLOW_DIR},MAX_RESUBMITS=${resubmits}")
    [[ -n "${ntasks[$1]:-}" ]] && opts+=(--ntasks="${ntasks[$1]}")
    return 0
  }
  opt_c=("${hold[@]}" --job-name="${tag}-analysis"
         --export="ALL,BUILD_DIR=${build},KNOTFLOW_DIR=${KNOTFLOW_DIR},STUDY_DIR=${study_dir},WAIT_FOR=${tag}-sweep,STUDY_QUICK=${quick}")
  [[ -n "${ntasks[analysis]:-}" ]] && opt_c+=(--ntasks="${ntasks[analysis]}")
  # sbatch --test-only checks the script and the resources (partition, account, tasks)
  test_only() {
    local what="$1" why
    shift
    why=$(sbatch --test-only "$@" 2>&1) || die "sbatch refuses the ${what} job: $(tail -n 1 <<<"${why}")"
  }
  for i in "${!sweeps[@]}"; do
    sweep_opts "${roles[i]}"
    test_only "${sweeps[i]} sweep" "${opts[@]}" jobs/slurm_sweep.sh "${inputs[i]}"
  done
  test_only analysis "${opt_c[@]}" jobs/slurm_study.sh "${hydro}"
  for i in "${!sweeps[@]}"; do
    sweep_opts "${roles[i]}"
    ids+=("$(sbatch --parsable "${opts[@]}" jobs/slurm_sweep.sh "${inputs[i]}")"); submitted+=("${ids[i]}")
  done
  c=$(sbatch --parsable --dependency="afterany:$(IFS=:; echo "${ids[*]}")" "${opt_c[@]}" jobs/slurm_study.sh "${hydro}")
  submitted+=("${c}")
else
  vars="BUILD_DIR=${build},KNOTFLOW_DIR=${KNOTFLOW_DIR},MODULES=${MODULES:-},MPIRUN=${MPIRUN:-mpirun},MPIRUN_FLAGS=${MPIRUN_FLAGS:-},MPIRUN_HOSTFILE=${MPIRUN_HOSTFILE:---hostfile},HDF5_FILE_LOCKING=${HDF5_FILE_LOCKING:-on}"
  sel() { [[ -n "${ntasks[$1]:-}" ]] && echo "-l select=1:ncpus=${ntasks[$1]}:mpiprocs=${ntasks[$1]}"; return 0; }
  for i in "${!sweeps[@]}"; do
    # shellcheck disable=SC2046  # sel prints options or nothing
    ids+=("$(qsub "${hold[@]}" -N "${tag}-sweep" $(sel "${roles[i]}") -v "${vars},SWEEP=${inputs[i]},MAX_RESUBMITS=${resubmits}" jobs/pbs_sweep.sh)")
    submitted+=("${ids[i]}")
  done
  # shellcheck disable=SC2046
  c=$(qsub "${hold[@]}" -N "${tag}-analysis" $(sel analysis) -W "depend=afterany:$(IFS=:; echo "${ids[*]}")" \
        -v "${vars},HYDRO=${hydro},STUDY_DIR=${study_dir},WAIT_FOR=${tag}-sweep,STUDY_QUICK=${quick}" jobs/pbs_study.sh)
  submitted+=("${c}")
fi
trap - ERR
for i in "${!sweeps[@]}"; do echo "submitted: sweep ${sweeps[i]} ${ids[i]}"; done
echo "submitted: analysis ${c} (runs after the ${#ids[@]} sweep jobs and their follow-ups)"
echo "inputs ${inputs[*]}; results in ${study_dir}/; job names ${tag}-sweep, ${tag}-analysis"
if [[ ${#hold[@]} -gt 0 ]]; then
  echo "held: release with $([[ ${scheduler} == slurm ]] && echo scontrol release || echo qrls) ${submitted[*]}"
fi
