#!/usr/bin/env bash
# Where the time of whole steps goes: perf (software clock samples; no hardware counters needed)
# of `knotflow` on the study's model (multipole L = 2 + lubrication, overlap 'relax', dopri45 at
# tolerance 1e-4, shear) at N = 99 (the trefoil, orientation c, A = 2.2, from t = 0) and N = 152
# (the collapsed candy-cane of inputs/configs/candycane_A1_multipole_t800.xyz, A = 1), with
# update 'stage' and 'iterative', one thread (OPENBLAS_NUM_THREADS = OMP_NUM_THREADS = 1); and
# trefoil_case: the path of a whole case as README measures it
# (`KNOTFLOW_CASE_JACOBIAN_ORDER=0 KNOTFLOW_CASE_JACOBIAN_STEPS=1
# KNOTFLOW_CASE_SOLVER_TOLERANCE=1e-4 bash scripts/bench_reuse.sh case`: 'iterative' at solver
# tolerance 1e-4 with ros34pw2, the preconditioner's Jacobian renewed every step, a frame with
# its knot analysis every unit time) over t = 0-10, where the phases of a whole step show: the
# Rosenbrock Jacobian, the stepper's LU and the frames.
# For each run: the samples grouped by the phase of the evaluation they fall in (from the call
# chains, perf --call-graph dwarf: the first phase routine found walking from the caller end),
# the self time grouped by kind of code, the 25 hottest symbols, the wall time and the load
# average before and after (docs/multipole.md, "Profile").
# A science command (about 3 min of one core on a quiet machine), not a test.
#
#   bash scripts/profile_steps.sh [run ...]     runs: trefoil_stage trefoil_iterative
#                                               candycane_stage candycane_iterative trefoil_case
#                                               (default: all but trefoil_case)
# Output: $KNOTFLOW_PROFILE_OUT (default build/profile)/<run>.txt; the perf data beside it.
# Environment: KNOTFLOW_PROFILE_T (simulated time per run; default 1 for the trefoil, 0.2 for the
# candy-cane, 10 for trefoil_case), KNOTFLOW_PERF (default perf).
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cd "$KF_ROOT"
kf_ensure_system_packages
kf_ensure_python
kf_build "$KF_ROOT/build" Release knotflow

perf="${KNOTFLOW_PERF:-perf}"
command -v "$perf" >/dev/null 2>&1 || kf_die "perf not found (Debian: linux-perf); set KNOTFLOW_PERF"
out="${KNOTFLOW_PROFILE_OUT:-$KF_ROOT/build/profile}"
mkdir -p "$out"
default_runs=(trefoil_stage trefoil_iterative candycane_stage candycane_iterative)
allowed="${default_runs[*]} trefoil_case"
runs=("$@")
[ "${#runs[@]}" -eq 0 ] && runs=("${default_runs[@]}")
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1

# The samples of `perf script` (one block per sample: the frames from the sampled one to main)
# counted by phase: the phases in the order of the patterns below, each sample in the first
# phase one of its frames matches. dgemm_kernel (assembly code without unwind tables) leaves
# its callers unknown: those samples are counted apart.
phases() {
  awk '
    BEGIN {
      RS = ""
      n = split("frames|jacobian|wmatrix|assemble|gmres|factorise|lubrication|friction|forces|stepper", key, "|")
      pat["frames"] = "kf_frame_records|kf_case_file|kf_case_checkpoint|kf_run_diagnostics|kf_knot_|kf_shape_MOD|H5"
      name["frames"] = "frames: shape, knots, diagnostics, output, checkpoints"
      pat["jacobian"] = "dynamics_jacobian"
      name["jacobian"] = "Rosenbrock Jacobian: the mobility (a factorisation) and mu dF/dr"
      pat["wmatrix"] = "kf_lapack_MOD_lu_"
      name["wmatrix"] = "Rosenbrock LU of I/(h gamma) - J and its solves"
      pat["factorise"] = "system_factorise"
      name["factorise"] = "factorisation of K: p-moment elimination + dpotrf (nr = 16 N at L = 2)"
      pat["gmres"] = "_MOD_gmres|operator_apply|_MOD_precondition|stpsv|dtrsv|dsymv|system_apply"
      name["gmres"] = "GMRES: products with K and the pair blocks, triangular solves"
      pat["assemble"] = "system_assemble|pair_entries|irregular_harmonics"
      name["assemble"] = "assembly of K (pair blocks)"
      pat["lubrication"] = "kf_lubrication_MOD|kf_pair_tensor|kf_pair_blocks|kf_near_contact"
      name["lubrication"] = "lubrication blocks"
      pat["friction"] = "friction_coupling|grand_friction|strain_disturbance|translational_mobility|kf_lapack_MOD|multipole_prepare|corrected_system|iterative_velocities|_MOD_refresh"
      name["friction"] = "friction route: zeta_L, x_L and the 6N x 6N Cholesky/solve/inverse"
      pat["forces"] = "kf_forces|kf_spring|kf_bending|kf_excluded|kf_flow_MOD"
      name["forces"] = "forces and flow"
      pat["stepper"] = "kf_stepper|kf_dynamics|kf_controller|kf_rigid_fit"
      name["stepper"] = "stepper, dynamics, rigid fit (own code)"
    }
    {
      total++
      lines = split($0, f, "\n")
      frames = ""
      for (i = 1; i <= lines; i++) frames = frames " " f[i]
      hit = ""
      for (k = 1; k <= n; k++) if (frames ~ pat[key[k]]) { hit = name[key[k]]; break }
      if (hit == "") {
        if (lines <= 3 && frames ~ /dgemm_kernel/) hit = "dgemm kernel, caller not unwound (level-3 BLAS)"
        else hit = "other (start-up, output, libraries)"
      }
      c[hit]++
    }
    END {
      print "| phase | samples % |"
      print "|---|---|"
      m = 0
      for (h in c) order[++m] = h
      for (i = 1; i <= m; i++) for (j = i + 1; j <= m; j++) if (c[order[j]] > c[order[i]]) { x = order[i]; order[i] = order[j]; order[j] = x }
      for (i = 1; i <= m; i++) printf "| %s | %.1f |\n", order[i], 100 * c[order[i]] / total
      printf "| (samples) | %d |\n", total
    }'
}

# The self time of `perf report` lines ("  12.34%  dso  [.] symbol") summed by category; the
# categories are matched in this order (first match wins).
categorise() {
  awk '
    function cat(dso, sym) {
      if (dso ~ /openblas|blas|lapack/) {
        if (sym ~ /^0x/) return "OpenBLAS, static symbols (kernel helpers: see the phases)"
        if (sym ~ /gemv|symv|trsv|trmv|dot|axpy|scal|copy_k|nrm2|swap|ger/) return "BLAS level 1-2 (matrix-vector products, triangular solves)"
        return "BLAS level 3 and LAPACK kernels (factorisations, inverses, matrix products)"
      }
      if (dso ~ /gomp/) return "OpenMP runtime (libgomp)"
      if (dso !~ /knotflow/) {
        if (dso ~ /kernel/) return "operating system"
        return "other libraries (libc, HDF5, MPI)"
      }
      if (sym ~ /kf_multipole_blocks|kf_solid_harmonics|system_assemble|starts\./) return "many-body assembly (pair blocks)"
      if (sym ~ /kf_lubrication|kf_pair_tensor|kf_near_contact|kf_two_sphere|kf_pair_blocks/) return "lubrication blocks"
      if (sym ~ /kf_hydro_multipole_iterative|system_apply|system_forward|system_backward/) return "GMRES and preconditioner (own code)"
      if (sym ~ /kf_multipole|kf_hydro_multipole|kf_lapack/) return "friction route: copies, permutations (own code)"
      if (sym ~ /kf_rigid_fit/) return "rigid fit"
      if (sym ~ /kf_pair_geometry/) return "pair lists"
      if (sym ~ /kf_forces|kf_spring|kf_bending|kf_excluded|kf_flow|kf_external/) return "forces and flow"
      if (sym ~ /kf_stepper|kf_integrat|kf_dynamics|kf_controller/) return "stepper and dynamics"
      return "other knotflow code"
    }
    /%/ && $1 ~ /%$/ {
      p = $1; sub(/%/, "", p)
      dso = $2; sym = $4
      c = cat(dso, sym); t[c] += p; total += p
    }
    END {
      print "| where | self time % |"
      print "|---|---|"
      n = 0
      for (c in t) { order[++n] = c }
      for (i = 1; i <= n; i++) for (j = i + 1; j <= n; j++) if (t[order[j]] > t[order[i]]) { x = order[i]; order[i] = order[j]; order[j] = x }
      for (i = 1; i <= n; i++) printf "| %s | %.1f |\n", order[i], t[order[i]]
      printf "| (all samples) | %.1f |\n", total
    }'
}

for run in "${runs[@]}"; do
  method=dopri45 update="${run#*_}" hydro_extra="" isteps=""
  case "$run" in
    trefoil_case) shape="shape = 'trefoil', orientation = 'c'"; a=2.2; t_end="${KNOTFLOW_PROFILE_T:-10.0}"
                  method=ros34pw2 update=iterative hydro_extra=", solver_tolerance = 1.0e-4" isteps=", jacobian_steps = 1" ;;
    trefoil_stage | trefoil_iterative) shape="shape = 'trefoil', orientation = 'c'"; a=2.2; t_end="${KNOTFLOW_PROFILE_T:-1.0}" ;;
    candycane_stage | candycane_iterative)
      shape="shape = 'file', coordinate_file = '$KF_ROOT/inputs/configs/candycane_A1_multipole_t800.xyz'"
      a=1.0; t_end="${KNOTFLOW_PROFILE_T:-0.2}" ;;
    *) kf_die "unknown run '$run' ($allowed)" ;;
  esac
  frames="$t_end"
  [ "$run" = trefoil_case ] && frames=1.0
  dir="$out/$run"
  rm -rf "$dir"; mkdir -p "$dir"
  cat > "$dir/scene.nml" <<NML
&chain
  $shape
/
&forces
  spring_k = 500.0, bending_a = $a
/
&flow
  flow_type = 'shear', shear_rate = 1.0
/
&hydro
  model = 'multipole', order = 2, lubrication = .true., update = '$update', overlap = 'relax'$hydro_extra
/
&integrator
  method = '$method', t_end = $t_end, tolerance = 1.0e-4$isteps
/
&output
  directory = '$dir/case', frame_interval = $frames, progress_interval = 0.0
/
NML
  kf_log "perf record: knotflow $dir/scene.nml (t = 0-$t_end)"
  load0=$(cat /proc/loadavg)
  start=$(date +%s.%N)
  "$perf" record -q -o "$dir/perf.data" -e cpu-clock -F 200 --call-graph dwarf,16384 -- \
    "$KF_ROOT/build/bin/knotflow" "$dir/scene.nml" > "$dir/log.txt" 2>&1
  wall=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
  load1=$(cat /proc/loadavg)
  report=$("$perf" report -i "$dir/perf.data" --no-children --sort dso,symbol --stdio -g none \
           --percent-limit 0 2>/dev/null | grep -v '^#')
  { echo "run = $run"; echo "t_end = $t_end"; echo "wall_s = $wall"
    echo "loadavg_start = $load0"; echo "loadavg_end = $load1"
    grep -E "^knotflow: (BLAS|OpenMP)" "$dir/log.txt" || true
    echo; "$perf" script -i "$dir/perf.data" -F ip,sym 2>/dev/null | phases
    echo; echo "$report" | categorise
    echo; echo "hottest symbols:"; echo "$report" | grep '%' | head -25
  } > "$out/$run.txt"
  kf_log "$out/$run.txt"
  cat "$out/$run.txt"
done
