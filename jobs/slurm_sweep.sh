#!/bin/bash
# Run a knotflow parameter sweep under SLURM:   sbatch jobs/slurm_sweep.sh [sweep.nml]
#
# All MPI ranks compute: they take cases one at a time from a shared counter, so any number of
# tasks works (more tasks than cases leaves the extra ranks idle). Each case writes its own
# HDF5 file with a checkpoint at every frame. Re-submitting the same script continues the sweep:
# knotflow skips cases whose file says 'finished', resumes 'running' ones from their checkpoint
# and recomputes failed or corrupt ones. Submit from the project directory (or set KNOTFLOW_DIR).
#
# ---- edit these for your site ------------------------------------------------------------
#SBATCH --job-name=knotflow-sweep
#SBATCH --account=CHANGE_ME            # project/account to charge (ask your admin: sacctmgr show assoc)
#SBATCH --partition=compute            # partition (queue): sinfo -s lists them
#SBATCH --nodes=1                      # number of nodes
#SBATCH --ntasks-per-node=32           # MPI ranks per node = cases run at the same time per node
#SBATCH --cpus-per-task=1              # one core per rank (each case is serial)
#SBATCH --time=24:00:00                # walltime; unfinished cases resume on re-submission
#SBATCH --output=knotflow-sweep-%j.out # log file (%j = job id)

# Sweep namelist (first argument overrides); relative paths are relative to KNOTFLOW_DIR.
SWEEP="${1:-inputs/sweep.nml}"
# Project checkout and the CMake build directory that holds the knotflow executable.
KNOTFLOW_DIR="${KNOTFLOW_DIR:-${SLURM_SUBMIT_DIR:-$PWD}}"
BUILD_DIR="${BUILD_DIR:-build}"
# Modules to load (space-separated, empty for none), e.g. "gcc/12 openmpi/4.1 hdf5/1.10 openblas".
MODULES="${MODULES:-}"
# Launcher: srun (preferred under SLURM) or "mpirun" (e.g. when Open MPI lacks PMI support).
LAUNCHER="${LAUNCHER:-srun}"
# Automatic follow-up jobs: submit up to this many more jobs that continue the sweep after this
# one ends (each one re-runs this script; 0 = off). Stops early once every case is finished.
MAX_RESUBMITS="${MAX_RESUBMITS:-0}"
# --------------------------------------------------------------------------------------------

set -euo pipefail

if [[ -n "${MODULES}" ]]; then
  # shellcheck disable=SC2086  # word splitting of the module list is intended
  module load ${MODULES}
fi

cd "${KNOTFLOW_DIR}"
exe="${BUILD_DIR}/bin/knotflow"
if [[ ! -x "${exe}" ]]; then
  echo "ERROR: ${exe} not found or not executable (set BUILD_DIR; build with cmake first)" >&2
  exit 1
fi
if [[ ! -r "${SWEEP}" ]]; then
  echo "ERROR: sweep file ${SWEEP} not found in ${KNOTFLOW_DIR}" >&2
  exit 1
fi

# One thread per rank: the ranks already fill the cores.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
# HDF5 file locking fails on some parallel file systems; every case file has a single writer.
export HDF5_USE_FILE_LOCKING=FALSE

# Chain a follow-up job before starting, so it also runs when this job hits its walltime.
# (SLURM runs a spooled copy of this script: resubmit the one in the checkout when it exists.)
script="${KNOTFLOW_DIR}/jobs/slurm_sweep.sh"
[[ -r "${script}" ]] || script="$0"
if (( MAX_RESUBMITS > 0 )); then
  next=$(sbatch --parsable --dependency="afterany:${SLURM_JOB_ID}" \
    --export="ALL,MAX_RESUBMITS=$(( MAX_RESUBMITS - 1 )),KNOTFLOW_DIR=${KNOTFLOW_DIR},BUILD_DIR=${BUILD_DIR}" \
    "${script}" "${SWEEP}")
  echo "follow-up job ${next} submitted (${MAX_RESUBMITS} resubmissions left before it)"
fi

echo "knotflow sweep ${SWEEP}: job ${SLURM_JOB_ID:-none}, ${SLURM_NTASKS:-?} ranks on ${SLURM_JOB_NUM_NODES:-?} node(s), $(date -u)"
status=0
case "${LAUNCHER}" in
  srun) srun --kill-on-bad-exit=1 "${exe}" "${SWEEP}" || status=$? ;;
  mpirun) mpirun -n "${SLURM_NTASKS}" "${exe}" "${SWEEP}" || status=$? ;;
  *) echo "ERROR: LAUNCHER must be srun or mpirun, not '${LAUNCHER}'" >&2; exit 1 ;;
esac
echo "knotflow exited with status ${status} at $(date -u)"

# knotflow exits with status 0 when the sweep ran to its end: the follow-up job has nothing
# left to do (cases that failed would fail again), cancel it. After a walltime kill the status
# is non-zero and the follow-up job continues the sweep.
if (( status == 0 )) && [[ -n "${next:-}" ]]; then
  scancel "${next}" && echo "sweep complete: follow-up job ${next} cancelled"
fi
exit "${status}"
