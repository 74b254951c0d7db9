#!/bin/bash
# Analyse the reference-study sweeps under PBS (after they ran with jobs/pbs_sweep.sh):
#   qsub [-v HYDRO=multipole] jobs/pbs_study.sh
# Runs scripts/reproduce.sh --no-run --no-build --no-extras on the job's ranks, for the sweeps of
# scripts/study_sweeps.sh (multipole: the rotations ensemble too): k_f of every frame, knot
# matrices, and the comparison with the study in STUDY_DIR/reproduction[_multipole]/.
# jobs/submit_study.sh submits the study's sweeps and this job in one go (and sets STUDY_DIR and
# WAIT_FOR). Resumable: stored k_f and knot matrices are reused.
# ---- edit these for your site ------------------------------------------------------------
#PBS -N knotflow-study
#PBS -A CHANGE_ME
#PBS -q workq
#PBS -l select=1:ncpus=16:mpiprocs=16
#PBS -l walltime=04:00:00
#PBS -j oe
HYDRO="${HYDRO:-rpy}"
KNOTFLOW_DIR="${KNOTFLOW_DIR:-${PBS_O_WORKDIR:-$PWD}}"
BUILD_DIR="${BUILD_DIR:-build}"
MODULES="${MODULES:-}"
MPIRUN="${MPIRUN:-mpirun}"
MPIRUN_FLAGS="${MPIRUN_FLAGS:-}"
MPIRUN_HOSTFILE="${MPIRUN_HOSTFILE:---hostfile}"
HDF5_FILE_LOCKING="${HDF5_FILE_LOCKING:-on}"
# As in slurm_study.sh: where the sweeps wrote, the job name of the sweep jobs to wait for, and
# STUDY_QUICK=1 for the quick analysis of a trial.
STUDY_DIR="${STUDY_DIR:-results}"
WAIT_FOR="${WAIT_FOR:-}"
STUDY_QUICK="${STUDY_QUICK:-0}"
# --------------------------------------------------------------------------------------------
set -euo pipefail
cd "${KNOTFLOW_DIR}"
# shellcheck source=jobs/job_lib.sh
source "${KNOTFLOW_DIR}/jobs/job_lib.sh"
kf_job_environment

if [[ -n "${WAIT_FOR}" ]]; then
  busy=$(qselect -u "$(id -un)" -N "${WAIT_FOR}" -s QRHWTE 2>/dev/null | grep -vx "${PBS_JOBID:-}" | paste -sd: || true)
  if [[ -n "${busy}" ]]; then
    kf_pbs_same_job
    again=$(qsub "${KF_SAME_JOB[@]}" -W "depend=afterany:${busy}" \
      -v "HYDRO=${HYDRO},KNOTFLOW_DIR=${KNOTFLOW_DIR},BUILD_DIR=${BUILD_DIR},MODULES=${MODULES},MPIRUN=${MPIRUN},MPIRUN_FLAGS=${MPIRUN_FLAGS},MPIRUN_HOSTFILE=${MPIRUN_HOSTFILE},HDF5_FILE_LOCKING=${HDF5_FILE_LOCKING},STUDY_DIR=${STUDY_DIR},WAIT_FOR=${WAIT_FOR},STUDY_QUICK=${STUDY_QUICK}" \
      "${KNOTFLOW_DIR}/jobs/pbs_study.sh")
    echo "sweep jobs ${busy//:/ } (${WAIT_FOR}) still queued or running: analysis moved to job ${again}"
    exit 0
  fi
fi

nranks=1
launch="${MPIRUN} ${MPIRUN_FLAGS}"
if [[ -n "${PBS_NODEFILE:-}" && -r "${PBS_NODEFILE}" ]]; then
  nranks=$(wc -l < "${PBS_NODEFILE}")
  launch="${launch} ${MPIRUN_HOSTFILE} ${PBS_NODEFILE}"
fi
quick=()
[[ "${STUDY_QUICK}" == 1 ]] && quick=(--quick)
KNOTFLOW_BUILD_DIR="${BUILD_DIR}" KNOTFLOW_LAUNCHER="${launch} -n ${nranks}" KNOTFLOW_NO_INSTALL=1 \
  exec bash scripts/reproduce.sh --hydro "${HYDRO}" --no-run --no-build --no-extras --results "${STUDY_DIR}" "${quick[@]}"
