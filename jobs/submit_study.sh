#!/bin/bash
# Submit the whole reproduction of the reference study: the trefoil Table 2 sweep (29 cases), the
# candy-cane sweep (3 cases), and the analysis job that waits for both.
#   bash jobs/submit_study.sh slurm|pbs [rpy|multipole]
# One rank per case: 29 + 3 ranks run every case at once. With multipole (L = 2 + lubrication) a
# trefoil case takes hours and a candy-cane case about a day: raise the walltime in the sweep
# scripts or set MAX_RESUBMITS (jobs/README.md); unfinished cases resume on re-submission.
set -euo pipefail
scheduler="${1:-}"
hydro="${2:-rpy}"
case "${hydro}" in
  rpy) suffix="" ;;
  multipole) suffix="_multipole" ;;
  *) echo "ERROR: hydro '${hydro}' is unknown (allowed: rpy, multipole)" >&2; exit 1 ;;
esac
cd "$(dirname "${BASH_SOURCE[0]}")/.."
case "${scheduler}" in
  slurm)
    a=$(sbatch --parsable --ntasks-per-node=29 jobs/slurm_sweep.sh "inputs/trefoil_table2${suffix}.nml")
    b=$(sbatch --parsable --ntasks-per-node=3 jobs/slurm_sweep.sh "inputs/candycane${suffix}.nml")
    c=$(sbatch --parsable --dependency="afterany:${a}:${b}" jobs/slurm_study.sh "${hydro}")
    ;;
  pbs)
    a=$(qsub -l select=1:ncpus=29:mpiprocs=29 -v "SWEEP=inputs/trefoil_table2${suffix}.nml" jobs/pbs_sweep.sh)
    b=$(qsub -l select=1:ncpus=3:mpiprocs=3 -v "SWEEP=inputs/candycane${suffix}.nml" jobs/pbs_sweep.sh)
    c=$(qsub -W "depend=afterany:${a}:${b}" -v "HYDRO=${hydro}" jobs/pbs_study.sh)
    ;;
  *) echo "usage: bash jobs/submit_study.sh slurm|pbs [rpy|multipole]" >&2; exit 1 ;;
esac
echo "submitted: trefoil sweep ${a}, candy-cane sweep ${b}, analysis ${c} (runs after both)"
