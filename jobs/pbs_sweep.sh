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
# jobs/README.md explains every setting.
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
# MPI launcher, its options, and its option that names the host file: the ranks are placed on
# the nodes of $PBS_NODEFILE through it (Open MPI: --hostfile, MPICH: -f). Needed for more than
# one node with an MPI library built without PBS support (Debian's and Ubuntu's Open MPI).
MPIRUN="${MPIRUN:-mpirun}"
MPIRUN_FLAGS="${MPIRUN_FLAGS:-}"
MPIRUN_HOSTFILE="${MPIRUN_HOSTFILE:---hostfile}"
# HDF5 file locking: on, or off for a file system where it fails (every case file has one writer).
HDF5_FILE_LOCKING="${HDF5_FILE_LOCKING:-on}"
# Automatic follow-up jobs: submit up to this many more jobs that continue the sweep after this
# one ends (with this job's resources and settings; 0 = off). A follow-up is deleted when the
# sweep has run to its end (cases finished, or failed for good).
MAX_RESUBMITS="${MAX_RESUBMITS:-0}"
# --------------------------------------------------------------------------------------------

set -euo pipefail
cd "${KNOTFLOW_DIR}"
# shellcheck source=jobs/job_lib.sh
source "${KNOTFLOW_DIR}/jobs/job_lib.sh"
kf_job_environment
kf_sweep_job_checks

# Ranks: one per line of the PBS node file (mpiprocs per node), passed to the launcher; 1 outside PBS.
nranks=1
hosts=()
if [[ -n "${PBS_NODEFILE:-}" && -r "${PBS_NODEFILE}" ]]; then
  nranks=$(wc -l < "${PBS_NODEFILE}")
  hosts=("${MPIRUN_HOSTFILE}" "${PBS_NODEFILE}")
fi

# Chain a follow-up job before starting, so it also runs when this job hits its walltime: the
# same script, resources (select, walltime, queue, account) and settings.
next=""
if (( MAX_RESUBMITS > 0 )); then
  kf_pbs_same_job
  next=$(qsub "${KF_SAME_JOB[@]}" -W "depend=afterany:${PBS_JOBID}" \
    -v "SWEEP=${SWEEP},KNOTFLOW_DIR=${KNOTFLOW_DIR},BUILD_DIR=${BUILD_DIR},MODULES=${MODULES},MPIRUN=${MPIRUN},MPIRUN_FLAGS=${MPIRUN_FLAGS},MPIRUN_HOSTFILE=${MPIRUN_HOSTFILE},HDF5_FILE_LOCKING=${HDF5_FILE_LOCKING},MAX_RESUBMITS=$(( MAX_RESUBMITS - 1 ))" \
    "${KNOTFLOW_DIR}/jobs/pbs_sweep.sh")
  echo "follow-up job ${next} submitted (${MAX_RESUBMITS} resubmissions left before it)"
fi

echo "knotflow sweep ${SWEEP}: job ${PBS_JOBID:-none}, ${nranks} ranks, $(date -u)"
status=0
out="$(mktemp)"
# shellcheck disable=SC2086  # MPIRUN_FLAGS is a list of options
"${MPIRUN}" ${MPIRUN_FLAGS} "${hosts[@]}" -n "${nranks}" "${KF_JOB_EXE}" "${SWEEP}" | tee "${out}" || status=$?
echo "knotflow exited with status ${status} at $(date -u)"

# As in slurm_sweep.sh: a walltime kill ends this script before this point.
# Here knotflow has ended: it ran to its end when it printed its closing line (status 0: every case
# finished; 3: cases failed for good, a follow-up would fail them again), or refused its input
# (2). Then the follow-up has nothing to do. Otherwise (killed by a signal, or the launcher
# failed to start it, which srun may report with status 0) the follow-up continues the sweep.
kf_sweep_ended "${status}" "${out}" && ended=1 || ended=0
rm -f "${out}"
if [[ -n "${next}" ]] && (( ended )); then
  qdel "${next}" && echo "sweep ended (status ${status}): follow-up job ${next} deleted"
fi
(( ended || status != 0 )) || status=1
exit "${status}"
