#!/bin/bash
# Submit the whole reproduction of the reference study: the trefoil Table 2 sweep (29 cases), the
# candy-cane sweep (3 cases), and the analysis job that runs when both have ended (follow-up jobs
# included) and analyses exactly these two sweeps.
#   bash jobs/submit_study.sh slurm|pbs [rpy|multipole] [options]
# Options:
#   --time-scale F       a shortened trial: every t_end times F (0 < F <= 1), into its own
#                        directory results/study_<hydro>_t<F>/ (inputs and results), with its own
#                        job names, so a trial never blocks or touches the real run
#   --ntasks-trefoil N   MPI ranks of the trefoil sweep (default: the sweep script's directives;
#   --ntasks-candycane N   29 and 3 run every case at once)
#   --ntasks-analysis N  MPI ranks of the analysis job (default: the study script's directives)
#   --max-resubmits N    follow-up jobs of each sweep (MAX_RESUBMITS, default 0)
#   --quick-analysis     few closures in the analysis (scripts/reproduce.sh --quick): for a trial
# Settings of the job scripts (BUILD_DIR, MODULES, LAUNCHER, SRUN_MPI, HDF5_FILE_LOCKING; MPIRUN,
# MPIRUN_FLAGS, MPIRUN_HOSTFILE on PBS) are taken from the environment. Everything is checked
# before the first job is submitted; if a submission fails, the jobs already queued are
# cancelled. Prints the job ids.
# With multipole (L = 2 + lubrication) a trefoil case takes hours and a candy-cane case about a
# day: raise the walltime in the sweep scripts or use --max-resubmits (jobs/README.md).
set -euo pipefail
die() { echo "ERROR: $*" >&2; exit 2; }
usage="usage: bash jobs/submit_study.sh slurm|pbs [rpy|multipole] [--time-scale F] [--ntasks-trefoil N] [--ntasks-candycane N] [--ntasks-analysis N] [--max-resubmits N] [--quick-analysis]"
scheduler="${1:-}"
[[ "${scheduler}" == slurm || "${scheduler}" == pbs ]] || die "${usage}"
shift
hydro=rpy
if [[ $# -gt 0 && "$1" != --* ]]; then hydro="$1"; shift; fi
scale="" nt_trefoil="" nt_cane="" nt_analysis="" resubmits=0 quick=0
while [[ $# -gt 0 ]]; do
  if [[ "$1" == --quick-analysis ]]; then quick=1; shift; continue; fi
  [[ $# -ge 2 ]] || die "option $1 needs a value (${usage})"
  case "$1" in
    --time-scale) scale="$2" ;;
    --ntasks-trefoil) nt_trefoil="$2" ;;
    --ntasks-candycane) nt_cane="$2" ;;
    --ntasks-analysis) nt_analysis="$2" ;;
    --max-resubmits) resubmits="$2" ;;
    *) die "unknown option $1 (${usage})" ;;
  esac
  shift 2
done
case "${hydro}" in
  rpy) suffix="" ;;
  multipole) suffix="_multipole" ;;
  *) die "hydro '${hydro}' is unknown (allowed: rpy, multipole)" ;;
esac
for n in "${nt_trefoil}" "${nt_cane}" "${nt_analysis}"; do
  [[ -z "${n}" || "${n}" =~ ^[1-9][0-9]*$ ]] || die "a task count must be an integer >= 1, not '${n}'"
done
[[ "${resubmits}" =~ ^[0-9]+$ ]] || die "--max-resubmits must be an integer >= 0, not '${resubmits}'"
if [[ -n "${scale}" ]]; then
  awk -v f="${scale}" 'BEGIN { exit !(f ~ /^[0-9]*\.?[0-9]+([eE][-+]?[0-9]+)?$/ && f + 0 > 0 && f + 0 <= 1) }' \
    || die "--time-scale must be a number in (0, 1], not '${scale}'"
fi

cd "$(dirname "${BASH_SOURCE[0]}")/.."
export KNOTFLOW_DIR="${PWD}"
build="${BUILD_DIR:-build}"
sweeps=("trefoil_table2${suffix}" "candycane${suffix}")

# Inputs and names: the study, or a shortened trial with its own directory and job names.
if [[ -z "${scale}" ]]; then
  study_dir=results
  tag="knotflow-${hydro}"
  inputs=("inputs/${sweeps[0]}.nml" "inputs/${sweeps[1]}.nml")
else
  study_dir="results/study_${hydro}_t${scale}"
  tag="knotflow-${hydro}-t${scale}"
  inputs=()
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
for exe in "${build}/bin/knotflow" "${build}/bin/knotflow-analyze" "${build}/venv/bin/knotflow-study"; do
  [[ -x "${exe}" ]] || die "${exe} not found: build with 'KNOTFLOW_BUILD_DIR=${build} bash scripts/build.sh' (installs the analysis tools too)"
done
command -v "$([[ ${scheduler} == slurm ]] && echo sbatch || echo qsub)" >/dev/null \
  || die "no $([[ ${scheduler} == slurm ]] && echo sbatch || echo qsub) on this machine"

submitted=()
cancel_queued() {
  if [[ ${#submitted[@]} -gt 0 ]]; then
    echo "ERROR: a submission failed: cancelling the jobs already queued: ${submitted[*]}" >&2
    if [[ "${scheduler}" == slurm ]]; then scancel "${submitted[@]}" || true; else qdel "${submitted[@]}" || true; fi
  fi
}
trap 'cancel_queued' ERR

if [[ "${scheduler}" == slurm ]]; then
  sweep_export="ALL,BUILD_DIR=${build},KNOTFLOW_DIR=${KNOTFLOW_DIR},MAX_RESUBMITS=${resubmits}"
  opt_a=(--job-name="${tag}-sweep" --export="${sweep_export}")
  opt_b=(--job-name="${tag}-sweep" --export="${sweep_export}")
  opt_c=(--job-name="${tag}-analysis"
         --export="ALL,BUILD_DIR=${build},KNOTFLOW_DIR=${KNOTFLOW_DIR},STUDY_DIR=${study_dir},WAIT_FOR=${tag}-sweep,STUDY_QUICK=${quick}")
  [[ -n "${nt_trefoil}" ]] && opt_a+=(--ntasks="${nt_trefoil}")
  [[ -n "${nt_cane}" ]] && opt_b+=(--ntasks="${nt_cane}")
  [[ -n "${nt_analysis}" ]] && opt_c+=(--ntasks="${nt_analysis}")
  # sbatch --test-only checks the script and the resources (partition, account, tasks)
  test_only() {
    local what="$1" why
    shift
    why=$(sbatch --test-only "$@" 2>&1) || die "sbatch refuses the ${what} job: $(tail -n 1 <<<"${why}")"
  }
  test_only "trefoil sweep" "${opt_a[@]}" jobs/slurm_sweep.sh "${inputs[0]}"
  test_only "candy-cane sweep" "${opt_b[@]}" jobs/slurm_sweep.sh "${inputs[1]}"
  test_only analysis "${opt_c[@]}" jobs/slurm_study.sh "${hydro}"
  a=$(sbatch --parsable "${opt_a[@]}" jobs/slurm_sweep.sh "${inputs[0]}"); submitted+=("${a}")
  b=$(sbatch --parsable "${opt_b[@]}" jobs/slurm_sweep.sh "${inputs[1]}"); submitted+=("${b}")
  c=$(sbatch --parsable --dependency="afterany:${a}:${b}" "${opt_c[@]}" jobs/slurm_study.sh "${hydro}")
  submitted+=("${c}")
else
  vars="BUILD_DIR=${build},KNOTFLOW_DIR=${KNOTFLOW_DIR},MODULES=${MODULES:-},MPIRUN=${MPIRUN:-mpirun},MPIRUN_FLAGS=${MPIRUN_FLAGS:-},MPIRUN_HOSTFILE=${MPIRUN_HOSTFILE:---hostfile},HDF5_FILE_LOCKING=${HDF5_FILE_LOCKING:-on}"
  sel() { [[ -n "$1" ]] && echo "-l select=1:ncpus=$1:mpiprocs=$1"; return 0; }
  # shellcheck disable=SC2046  # sel prints options or nothing
  a=$(qsub -N "${tag}-sweep" $(sel "${nt_trefoil}") -v "${vars},SWEEP=${inputs[0]},MAX_RESUBMITS=${resubmits}" jobs/pbs_sweep.sh)
  submitted+=("${a}")
  # shellcheck disable=SC2046
  b=$(qsub -N "${tag}-sweep" $(sel "${nt_cane}") -v "${vars},SWEEP=${inputs[1]},MAX_RESUBMITS=${resubmits}" jobs/pbs_sweep.sh)
  submitted+=("${b}")
  # shellcheck disable=SC2046
  c=$(qsub -N "${tag}-analysis" $(sel "${nt_analysis}") -W "depend=afterany:${a}:${b}" \
        -v "${vars},HYDRO=${hydro},STUDY_DIR=${study_dir},WAIT_FOR=${tag}-sweep,STUDY_QUICK=${quick}" jobs/pbs_study.sh)
  submitted+=("${c}")
fi
trap - ERR
echo "submitted: trefoil sweep ${a}, candy-cane sweep ${b}, analysis ${c} (runs after both and their follow-ups)"
echo "inputs ${inputs[*]}; results in ${study_dir}/; job names ${tag}-sweep, ${tag}-analysis"
