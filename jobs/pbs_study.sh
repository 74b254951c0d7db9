#!/bin/bash
# Analyse the reference-study sweeps under PBS (after they ran with jobs/pbs_sweep.sh):
#   qsub [-v HYDRO=multipole] jobs/pbs_study.sh
# Runs scripts/reproduce.sh --no-run on the job's ranks: k_f of every frame, knot matrices, and the
# comparison with the study in results/reproduction[_multipole]/. jobs/submit_study.sh submits the
# two sweeps and this job in one go. Resumable: stored k_f and knot matrices are reused.
# ---- edit these for your site ------------------------------------------------------------
#PBS -N knotflow-study
#PBS -A CHANGE_ME
#PBS -q workq
#PBS -l select=1:ncpus=16:mpiprocs=16
#PBS -l walltime=04:00:00
#PBS -j oe
HYDRO="${HYDRO:-rpy}"
KNOTFLOW_DIR="${KNOTFLOW_DIR:-${PBS_O_WORKDIR:-$PWD}}"
MODULES="${MODULES:-}"
# --------------------------------------------------------------------------------------------
set -euo pipefail
if [[ -n "${MODULES}" ]]; then
  # shellcheck disable=SC2086  # word splitting of the module list is intended
  module load ${MODULES}
fi
cd "${KNOTFLOW_DIR}"
nranks=1
if [[ -n "${PBS_NODEFILE:-}" && -r "${PBS_NODEFILE}" ]]; then
  nranks=$(wc -l < "${PBS_NODEFILE}")
fi
export HDF5_USE_FILE_LOCKING=FALSE KNOTFLOW_NO_INSTALL=1 KNOTFLOW_NP="${nranks}"
exec bash scripts/reproduce.sh --hydro "${HYDRO}" --no-run
