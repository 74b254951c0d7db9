#!/bin/bash
# Analyse the reference-study sweeps under SLURM (after they ran with jobs/slurm_sweep.sh):
#   sbatch jobs/slurm_study.sh [rpy|multipole]
# Runs scripts/reproduce.sh --no-run --no-build --no-extras on the job's ranks, for the sweeps of
# scripts/study_sweeps.sh (multipole: the rotations ensemble too): k_f of every frame, knot
# matrices, and the comparison with the study in STUDY_DIR/reproduction[_multipole]/.
# jobs/submit_study.sh submits the study's sweeps and this job in one go (and sets STUDY_DIR and
# WAIT_FOR). Resumable: stored k_f and knot matrices are reused.
# ---- edit these for your site ------------------------------------------------------------
#SBATCH --job-name=knotflow-study
#SBATCH --account=CHANGE_ME
#SBATCH --partition=compute
#SBATCH --nodes=1
#SBATCH --ntasks-per-node=16
#SBATCH --cpus-per-task=1
#SBATCH --time=04:00:00
#SBATCH --output=knotflow-study-%j.out
HYDRO="${1:-${HYDRO:-rpy}}"
KNOTFLOW_DIR="${KNOTFLOW_DIR:-${SLURM_SUBMIT_DIR:-$PWD}}"
BUILD_DIR="${BUILD_DIR:-build}"
MODULES="${MODULES:-}"
LAUNCHER="${LAUNCHER:-srun}"
SRUN_MPI="${SRUN_MPI:-auto}"
HDF5_FILE_LOCKING="${HDF5_FILE_LOCKING:-on}"
# Where the sweeps wrote their directories (results/<sweep>), and the job name of the sweep jobs
# (follow-ups included) to wait for: while one of them is queued or running this job re-submits
# itself behind them instead of analysing (set by jobs/submit_study.sh; empty: no wait).
STUDY_DIR="${STUDY_DIR:-results}"
WAIT_FOR="${WAIT_FOR:-}"
# STUDY_QUICK=1: the quick analysis of a trial run (scripts/reproduce.sh --quick: few closures).
STUDY_QUICK="${STUDY_QUICK:-0}"
# --------------------------------------------------------------------------------------------
set -euo pipefail
export KNOTFLOW_DIR BUILD_DIR MODULES LAUNCHER SRUN_MPI HDF5_FILE_LOCKING STUDY_DIR WAIT_FOR STUDY_QUICK
cd "${KNOTFLOW_DIR}"
# shellcheck source=jobs/job_lib.sh
source "${KNOTFLOW_DIR}/jobs/job_lib.sh"
kf_job_environment

if [[ -n "${WAIT_FOR}" ]]; then
  busy=$(squeue -h -u "$(id -un)" -n "${WAIT_FOR}" -t PENDING,RUNNING,SUSPENDED,CONFIGURING,COMPLETING,REQUEUED \
           -o %i | grep -vx "${SLURM_JOB_ID:-}" | paste -sd: || true)
  if [[ -n "${busy}" ]]; then
    kf_slurm_same_job
    again=$(sbatch --parsable "${KF_SAME_JOB[@]}" --dependency="afterany:${busy}" --export=ALL \
      "${KNOTFLOW_DIR}/jobs/slurm_study.sh" "${HYDRO}")
    echo "sweep jobs ${busy//:/ } (${WAIT_FOR}) still queued or running: analysis moved to job ${again}"
    exit 0
  fi
fi

kf_slurm_launcher
quick=()
[[ "${STUDY_QUICK}" == 1 ]] && quick=(--quick)
echo "knotflow study analysis (${HYDRO}, ${STUDY_DIR}): job ${SLURM_JOB_ID:-none}, ${SLURM_NTASKS:-?} ranks, launcher ${KF_LAUNCH[*]}, $(date -u)"
KNOTFLOW_BUILD_DIR="${BUILD_DIR}" KNOTFLOW_LAUNCHER="${KF_LAUNCH[*]}" KNOTFLOW_NO_INSTALL=1 \
  exec bash scripts/reproduce.sh --hydro "${HYDRO}" --no-run --no-build --no-extras --results "${STUDY_DIR}" "${quick[@]}"
