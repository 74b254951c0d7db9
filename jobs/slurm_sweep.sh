#!/bin/bash
# Run a knotflow parameter sweep under SLURM:   sbatch jobs/slurm_sweep.sh [sweep.nml]
#
# All MPI ranks compute: they take cases one at a time from a shared counter, so any number of
# tasks works (more tasks than cases leaves the extra ranks idle). Each case writes its own
# HDF5 file with a checkpoint at every frame. Re-submitting the same script continues the sweep:
# knotflow skips cases whose file says 'finished', resumes 'running' ones from their checkpoint
# and recomputes failed or corrupt ones. Submit from the project directory (or set KNOTFLOW_DIR).
# jobs/README.md explains every setting.
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
# Launcher: srun (default) or mpirun. srun needs the PMI type of your MPI library: SRUN_MPI=auto
# takes pmix when srun offers it (Open MPI), else pmi2 (MPICH, Intel MPI); or name it.
LAUNCHER="${LAUNCHER:-srun}"
SRUN_MPI="${SRUN_MPI:-auto}"
# HDF5 file locking: on, or off for a file system where it fails (every case file has one writer).
HDF5_FILE_LOCKING="${HDF5_FILE_LOCKING:-on}"
# Automatic follow-up jobs: submit up to this many more jobs that continue the sweep after this
# one ends (each one re-runs this script with this job's resources; 0 = off). A follow-up is
# cancelled when the sweep has run to its end (cases finished, or failed for good).
MAX_RESUBMITS="${MAX_RESUBMITS:-0}"
# --------------------------------------------------------------------------------------------

set -euo pipefail
export SWEEP KNOTFLOW_DIR BUILD_DIR MODULES LAUNCHER SRUN_MPI HDF5_FILE_LOCKING
cd "${KNOTFLOW_DIR}"
# shellcheck source=jobs/job_lib.sh
source "${KNOTFLOW_DIR}/jobs/job_lib.sh"
kf_job_environment
kf_sweep_job_checks
kf_slurm_launcher

# Chain a follow-up job before starting, so it also runs when this job hits its walltime.
# (SLURM runs a spooled copy of this script: the follow-up runs the one in the checkout.)
next=""
if (( MAX_RESUBMITS > 0 )); then
  kf_slurm_same_job
  next=$(sbatch --parsable "${KF_SAME_JOB[@]}" --dependency="afterany:${SLURM_JOB_ID}" \
    --export="ALL,MAX_RESUBMITS=$(( MAX_RESUBMITS - 1 ))" \
    "${KNOTFLOW_DIR}/jobs/slurm_sweep.sh" "${SWEEP}")
  echo "follow-up job ${next} submitted (${MAX_RESUBMITS} resubmissions left before it)"
fi

echo "knotflow sweep ${SWEEP}: job ${SLURM_JOB_ID:-none}, ${SLURM_NTASKS:-?} ranks on ${SLURM_JOB_NUM_NODES:-?} node(s), launcher ${KF_LAUNCH[*]}, $(date -u)"
status=0
out="$(mktemp)"
"${KF_LAUNCH[@]}" "${KF_JOB_EXE}" "${SWEEP}" | tee "${out}" || status=$?
echo "knotflow exited with status ${status} at $(date -u)"

# A walltime kill ends this script before this point, and the follow-up continues the sweep.
# Here knotflow has ended: it ran to its end when it printed its closing line (status 0: every case
# finished; 3: cases failed for good, a follow-up would fail them again), or refused its input
# (2). Then the follow-up has nothing to do. Otherwise (killed by a signal, or the launcher
# failed to start it, which srun may report with status 0) the follow-up continues the sweep.
kf_sweep_ended "${status}" "${out}" && ended=1 || ended=0
rm -f "${out}"
if [[ -n "${next}" ]] && (( ended )); then
  scancel "${next}" && echo "sweep ended (status ${status}): follow-up job ${next} cancelled"
fi
(( ended || status != 0 )) || status=1
exit "${status}"
