#!/bin/bash
# Run a knotflow parameter sweep under PBS Pro / OpenPBS (Torque: see the -l line below):
#   qsub jobs/pbs_sweep.sh                         (sweep file inputs/sweep.nml)
#   qsub -v SWEEP=inputs/my_sweep.nml jobs/pbs_sweep.sh
#
# All MPI ranks compute: they take cases one at a time from a shared counter, so any number of
# ranks works (more ranks than cases leaves the extra ranks idle). Each case writes its own
# HDF5 file with a checkpoint at every frame. Re-submitting the same script continues the sweep:
# knotflow skips cases whose file says 'finished', resumes 'running' ones from their checkpoint
# and recomputes failed or corrupt ones. Submit from the project directory (or set KNOTFLOW_DIR).
#
# ---- edit these for your site ------------------------------------------------------------
#PBS -N knotflow-sweep
#PBS -A CHANGE_ME
#PBS -q workq
#PBS -l select=1:ncpus=32:mpiprocs=32
#PBS -l walltime=24:00:00
#PBS -j oe
#   -A: project/account to charge;  -q: queue (qstat -Q lists them);
#   select=<nodes>:ncpus=<cores per node>:mpiprocs=<MPI ranks per node> (one rank per core:
#   each case is serial). Torque uses "-l nodes=<nodes>:ppn=<ranks per node>" instead.
#   walltime: unfinished cases resume on re-submission;  -j oe: one log file (job name + id).

# Sweep namelist (qsub -v SWEEP=... overrides); relative paths are relative to KNOTFLOW_DIR.
SWEEP="${SWEEP:-inputs/sweep.nml}"
# Project checkout and the CMake build directory that holds the knotflow executable.
KNOTFLOW_DIR="${KNOTFLOW_DIR:-${PBS_O_WORKDIR:-$PWD}}"
BUILD_DIR="${BUILD_DIR:-build}"
# Modules to load (space-separated, empty for none), e.g. "gcc/12 openmpi/4.1 hdf5/1.10 openblas".
MODULES="${MODULES:-}"
# MPI launcher and its options (Open MPI and MPICH both read the PBS node file themselves).
MPIRUN="${MPIRUN:-mpirun}"
MPIRUN_FLAGS="${MPIRUN_FLAGS:-}"
# Automatic follow-up jobs: submit up to this many more jobs that continue the sweep after this
# one ends (0 = off). The follow-up is cancelled when the sweep runs to its end.
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

# Number of ranks: one per line of the PBS node file (mpiprocs per node), 1 outside PBS.
if [[ -n "${PBS_NODEFILE:-}" && -r "${PBS_NODEFILE}" ]]; then
  nranks=$(wc -l < "${PBS_NODEFILE}")
else
  nranks=1
fi

# One thread per rank: the ranks already fill the cores.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
# HDF5 file locking fails on some parallel file systems; every case file has a single writer.
export HDF5_USE_FILE_LOCKING=FALSE

# Chain a follow-up job before starting, so it also runs when this job hits its walltime.
next=""
if (( MAX_RESUBMITS > 0 )); then
  next=$(qsub -W "depend=afterany:${PBS_JOBID}" \
    -v "SWEEP=${SWEEP},KNOTFLOW_DIR=${KNOTFLOW_DIR},BUILD_DIR=${BUILD_DIR},MODULES=${MODULES},MAX_RESUBMITS=$(( MAX_RESUBMITS - 1 ))" \
    "${KNOTFLOW_DIR}/jobs/pbs_sweep.sh")
  echo "follow-up job ${next} submitted"
fi

echo "knotflow sweep ${SWEEP}: job ${PBS_JOBID:-none}, ${nranks} ranks, $(date -u)"
status=0
# shellcheck disable=SC2086  # MPIRUN_FLAGS is a list of options
"${MPIRUN}" ${MPIRUN_FLAGS} -n "${nranks}" "${exe}" "${SWEEP}" || status=$?
echo "knotflow exited with status ${status} at $(date -u)"

# Status 0: the sweep ran to its end, the follow-up job has nothing left to do.
if (( status == 0 )) && [[ -n "${next}" ]]; then
  qdel "${next}" && echo "sweep complete: follow-up job ${next} deleted"
fi
exit "${status}"
