# shellcheck shell=bash
# shellcheck disable=SC2034  # the KF_* arrays set here are used by the job scripts
# Shared by the job scripts (sourced from the checkout: jobs/job_lib.sh). Settings it reads:
#   MODULES             modules to `module load` (space-separated; empty: none)
#   HDF5_FILE_LOCKING   on (default) | off: off exports HDF5_USE_FILE_LOCKING=FALSE, for file
#                       systems where HDF5's file locking fails (some Lustre, GPFS, NFS mounts)
#   SRUN_MPI            auto (default) | pmix | pmi2 | ...: the PMI type of `srun --mpi=`; auto
#                       takes the first of pmix, pmi2 that `srun --mpi=list` offers

kf_job_die() { echo "ERROR: $*" >&2; exit 2; }

# Modules, threads (one per rank: the ranks fill the cores) and HDF5 file locking.
kf_job_environment() {
  if [[ -n "${MODULES:-}" ]]; then
    command -v module >/dev/null 2>&1 || kf_job_die "MODULES='${MODULES}' but there is no 'module' command"
    # shellcheck disable=SC2086  # word splitting of the module list is intended
    module load ${MODULES}
  fi
  export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
  # OpenBLAS's kernels for the node's CPU (scripts/blas_env.sh), unless OPENBLAS_CORETYPE is set.
  # shellcheck source=scripts/blas_env.sh
  source "${KNOTFLOW_DIR}/scripts/blas_env.sh"
  kf_openblas_environment
  case "${HDF5_FILE_LOCKING:-on}" in
    on) ;;
    off) export HDF5_USE_FILE_LOCKING=FALSE ;;
    *) kf_job_die "HDF5_FILE_LOCKING must be on or off, not '${HDF5_FILE_LOCKING}'" ;;
  esac
}

# What every sweep job checks before it starts anything: the executable of BUILD_DIR (set as
# KF_JOB_EXE), the sweep file and MAX_RESUBMITS.
kf_sweep_job_checks() {
  KF_JOB_EXE="${BUILD_DIR}/bin/knotflow"
  [[ -x "${KF_JOB_EXE}" ]] || kf_job_die "${KF_JOB_EXE} not found or not executable (set BUILD_DIR; build with scripts/build.sh)"
  [[ -r "${SWEEP}" ]] || kf_job_die "sweep file ${SWEEP} not found in ${KNOTFLOW_DIR}"
  [[ "${MAX_RESUBMITS}" =~ ^[0-9]+$ ]] || kf_job_die "MAX_RESUBMITS must be a number >= 0, not '${MAX_RESUBMITS}'"
}

# The PMI type for srun --mpi (see SRUN_MPI above). Open MPI as Debian/Ubuntu build it needs
# pmix; MPICH and Intel MPI usually pmi2. Printed on stdout.
kf_srun_mpi() {
  local want="${SRUN_MPI:-auto}" offered type
  offered="$(srun --mpi=list 2>&1 | tr -d ' \t' || true)"
  if [[ "${want}" != auto ]]; then
    grep -qx -- "${want}" <<<"${offered}" \
      || kf_job_die "SRUN_MPI=${want} is not offered by this SLURM (srun --mpi=list: $(tr '\n' ' ' <<<"${offered}"))"
    echo "${want}"
    return 0
  fi
  for type in pmix pmi2; do
    if grep -qx -- "${type}" <<<"${offered}"; then
      echo "${type}"
      return 0
    fi
  done
  kf_job_die "srun offers neither pmix nor pmi2 (srun --mpi=list: $(tr '\n' ' ' <<<"${offered}")); set SRUN_MPI, or LAUNCHER=mpirun"
}

# The command that starts an MPI program on the job's ranks: LAUNCHER=srun (default) or mpirun.
# Sets the array KF_LAUNCH.
kf_slurm_launcher() {
  case "${LAUNCHER:-srun}" in
    srun) KF_LAUNCH=(srun --kill-on-bad-exit=1 "--mpi=$(kf_srun_mpi)") ;;
    mpirun) KF_LAUNCH=(mpirun -n "${SLURM_NTASKS:?SLURM_NTASKS is not set: run inside a SLURM job}") ;;
    *) kf_job_die "LAUNCHER must be srun or mpirun, not '${LAUNCHER}'" ;;
  esac
}

# sbatch options that give a follow-up job the resources of this one (command-line options of
# the original sbatch included): name, partition, account, nodes, tasks, cpus, time limit.
# Sets the array KF_SAME_JOB.
kf_slurm_same_job() {
  local limit
  limit="$(squeue -h -j "${SLURM_JOB_ID}" -o %l)"
  KF_SAME_JOB=(--job-name="${SLURM_JOB_NAME}" --nodes="${SLURM_JOB_NUM_NODES}"
               --ntasks="${SLURM_NTASKS}" --time="${limit}")
  [[ -n "${SLURM_JOB_PARTITION:-}" ]] && KF_SAME_JOB+=(--partition="${SLURM_JOB_PARTITION}")
  [[ -n "${SLURM_JOB_ACCOUNT:-}" ]] && KF_SAME_JOB+=(--account="${SLURM_JOB_ACCOUNT}")
  [[ -n "${SLURM_CPUS_PER_TASK:-}" ]] && KF_SAME_JOB+=(--cpus-per-task="${SLURM_CPUS_PER_TASK}")
  return 0
}

# qsub options that give a follow-up job the resources of this one (qstat -f of this job: the
# select or nodes request, walltime, queue, account, name). Sets the array KF_SAME_JOB.
kf_pbs_same_job() {
  local info key
  info="$(qstat -f "${PBS_JOBID}" 2>/dev/null | sed -e ':a' -e 'N' -e '$!ba' -e 's/\n\t//g' || true)"
  KF_SAME_JOB=(-N "${PBS_JOBNAME:-knotflow-sweep}")
  [[ -n "${PBS_QUEUE:-}" ]] && KF_SAME_JOB+=(-q "${PBS_QUEUE}")
  for key in select nodes walltime; do
    local value
    value="$(sed -n "s/^ *Resource_List\.${key} = //p" <<<"${info}" | head -n 1)"
    [[ -n "${value}" ]] && KF_SAME_JOB+=(-l "${key}=${value}")
  done
  local account
  account="$(sed -n 's/^ *Account_Name = //p' <<<"${info}" | head -n 1)"
  [[ -n "${account}" ]] && KF_SAME_JOB+=(-A "${account}")
  return 0
}

# Did knotflow run to its end? Status 2 (input refused) or 0/3 with its closing line
# ("knotflow: N finished, M skipped ...") in its output, the file $2. Status 0 without that line
# is a launch that failed (srun 22.05 reports a failed step launch with status 0). Status 75
# (KF_EXIT_RESUBMIT): stopped by SIGTERM or SIGINT (a time limit, scancel) after each running
# case's last frame: not ended, the follow-up goes on (docs/robustness.md); so does any other
# status (mpirun signalled itself may report 1).
KF_EXIT_RESUBMIT=75
kf_sweep_ended() {
  local status="$1" out="$2"
  (( status == KF_EXIT_RESUBMIT )) && return 1
  (( status == 2 )) && return 0
  (( status == 0 || status == 3 )) && grep -qE '^knotflow: [0-9]+ finished, [0-9]+ skipped' "${out}"
}
