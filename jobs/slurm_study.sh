#!/bin/bash
# Analyse the reference-study sweeps under SLURM (after they ran with jobs/slurm_sweep.sh):
#   sbatch jobs/slurm_study.sh [rpy|multipole]
# Runs scripts/reproduce.sh --no-run on the job's ranks: k_f of every frame, knot matrices, and the
# comparison with the study in results/reproduction[_multipole]/. jobs/submit_study.sh submits the
# two sweeps and this job in one go. Resumable: stored k_f and knot matrices are reused.
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
MODULES="${MODULES:-}"
# --------------------------------------------------------------------------------------------
set -euo pipefail
if [[ -n "${MODULES}" ]]; then
  # shellcheck disable=SC2086  # word splitting of the module list is intended
  module load ${MODULES}
fi
cd "${KNOTFLOW_DIR}"
export HDF5_USE_FILE_LOCKING=FALSE KNOTFLOW_NO_INSTALL=1 KNOTFLOW_NP="${SLURM_NTASKS:-1}"
exec bash scripts/reproduce.sh --hydro "${HYDRO}" --no-run
