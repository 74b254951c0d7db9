#!/usr/bin/env bash
# Accuracy and cost of the adaptive reuse of the multipole many-body part (&hydro update =
# 'adaptive') against the exact solve at every stage ('stage'): knotflow-bench-reuse on the
# study's model (L = 2 + lubrication, overlap = 'relax' as the campaign), one core, into
# $KNOTFLOW_REUSE_OUT (default build/accuracy/reuse), then the section between the reuse markers
# of docs/accuracy.md.
# A science command (about 1.5 h of one core), not a test.
#
#   bash scripts/bench_reuse.sh [part ...]     parts: velocity trajectory speed overlaps
#                                              scaling profile stiffness compare case threads (default:
#                                              all but stiffness, compare, case and threads)
#   stiffness: which limit sets dopri45's step (|lambda_max| h of mu dF/dr at every trial step)
#   along the trefoil (t = 0-50) and a candy-cane window (t = 800 of the campaign run, 20 units),
#   into $out/stiffness and the stiffness section of docs/accuracy.md (about 45 min of one core)
#   compare: 'stage', 'adaptive' and 'iterative' in one run (t = 0-10) on the trefoil and on a
#   random self-avoiding chain (N = 60, A = 1.3): docs/accuracy.md, "Exact at every stage by
#   iteration" (about 25 min of one core)
#   rosenbrock: the Rosenbrock-W steppers ros34pw2 and ros34pw3 against dopri45 (t = 0-10,
#   tolerance 1e-4) on the trefoil and the random chain (N = 60, A = 1.3) with the study's model
#   (dopri45 'stage', the reference, and 'iterative'; each Rosenbrock method 'iterative' with a new
#   mobility every step and with it kept jacobian_steps = 4 steps) and on the trefoil with RPY:
#   docs/accuracy.md, "A linearly implicit stepper" and "A fourth-order Rosenbrock-W method"
#   (about 35 min of one core)
#   case, case-candycane: a whole reference case on one core, the trefoil (N = 99, orientation
#   c, A = 2.2, t_end = 1000) or the seeded candy-cane (N = 152, A = 1, t_end = 2000), with the
#   path of KNOTFLOW_CASE_UPDATE and KNOTFLOW_CASE_METHOD (default 'iterative' and 'ros34pw2');
#   wall and processor seconds into $out/case_<shape>_<update>_<method>.txt (docs/accuracy.md,
#   "A whole case"). Resumable: run again after an interruption (a kill, a reboot) and the case
#   continues from its checkpoint; every segment's wall and processor seconds, load and commit go
#   to <dir>/segments.txt and the summary sums them (KNOTFLOW_CASE_FRESH=1 starts over)
#   threads: both cores for one case (OpenMP pair loops + OpenBLAS, 1 against 2 threads): one
#   evaluation at N = 99 and 152, and 'stage' and 'iterative' on the trefoil t = 0-10, into
#   $out/threads_trefoil.txt (docs/multipole.md, "Both cores for one case"; about 6 min on a
#   quiet machine). The machine is shared: it first waits up to KNOTFLOW_QUIET_WAIT seconds
#   (default 600) for a 1-minute load average below KNOTFLOW_QUIET_LOAD (default 0.5), then
#   runs anyway; every figure carries the load average at its start.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cd "$KF_ROOT"
kf_ensure_system_packages
kf_ensure_python
kf_build "$KF_ROOT/build" Release knotflow-bench-reuse knotflow

exe="$KF_ROOT/build/bin/knotflow-bench-reuse"
out="${KNOTFLOW_REUSE_OUT:-$KF_ROOT/build/accuracy/reuse}"
mkdir -p "$out"
parts=("$@")
[ "${#parts[@]}" -eq 0 ] && parts=(velocity trajectory speed overlaps scaling profile)
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1

bench() {  # bench NAME ARGS...: one measurement into $out/NAME.txt
  local name="$1"; shift
  kf_log "knotflow-bench-reuse $* > $out/$name.txt"
  "$exe" "$@" > "$out/$name.txt.part"
  echo "loadavg_end = $(cat /proc/loadavg 2>/dev/null || echo unknown)" >> "$out/$name.txt.part"
  mv "$out/$name.txt.part" "$out/$name.txt"
}

for part in "${parts[@]}"; do
  case "$part" in
    velocity)
      bench velocity_trefoil velocity --config trefoil --t-end 10
      bench velocity_coil velocity --config coil --t-end 4
      bench velocity_collapse velocity --config inputs/configs/candycane_A1_t250.xyz --t-end 30 --every 4 ;;
    trajectory) bench trajectory_trefoil trajectory --config trefoil --t-end 10 ;;
    speed) bench speed_trefoil speed --config trefoil --t-end 50 ;;
    rosenbrock)
      bench rosenbrock_trefoil rosenbrock --config trefoil --t-end 10 --rosenbrock-stage no
      bench rosenbrock_random60 rosenbrock --config random60 --t-end 10 --rosenbrock-stage no
      bench rosenbrock_trefoil_rpy rosenbrock --config trefoil --t-end 10 --model rpy --overlap pair ;;
    compare)
      bench compare_trefoil compare --config trefoil --t-end 10
      bench compare_random60 compare --config random60 --t-end 10 ;;
    overlaps)
      bench overlaps_coil_eps1e-2 overlaps --config coil --t-end 4 --eps-lub 1e-2
      bench overlaps_coil_eps1e-4 overlaps --config coil --t-end 4 --eps-lub 1e-4 ;;
    scaling) bench scaling scaling --t-end 1 ;;
    profile) bench profile_trefoil rigid --config trefoil ;;
    stiffness)
      mkdir -p "$out/stiffness"
      bench stiffness/stiffness_trefoil stiffness --config trefoil --t-end 50 --table "$out/stiffness/stiffness_trefoil.dat"
      bench stiffness/stiffness_candycane_t800 stiffness --config inputs/configs/candycane_A1_multipole_t800.xyz \
        --t-end 20 --table "$out/stiffness/stiffness_candycane_t800.dat"
      for tol in 1e-3 1e-5; do   # does the step follow the tolerance (accuracy) or not (stability)?
        bench stiffness/stiffness_trefoil_tol$tol stiffness --config trefoil --t-end 10 \
          --tolerance $tol --table "$out/stiffness/stiffness_trefoil_tol$tol.dat"
        bench stiffness/stiffness_candycane_t800_tol$tol stiffness \
          --config inputs/configs/candycane_A1_multipole_t800.xyz --t-end 3 --tolerance $tol \
          --table "$out/stiffness/stiffness_candycane_t800_tol$tol.dat"
      done ;;
    threads)
      wait_s="${KNOTFLOW_QUIET_WAIT:-600}"; quiet="${KNOTFLOW_QUIET_LOAD:-0.5}"; waited=0
      while [ "$waited" -lt "$wait_s" ] && \
            awk -v q="$quiet" '{ exit !($1 >= q) }' /proc/loadavg; do
        sleep 15; waited=$((waited + 15))
      done
      kf_log "threads: load average $(cut -d' ' -f1-3 /proc/loadavg) after waiting ${waited} s"
      # both cores: the BLAS and OpenMP thread counts are set by the program, not the environment
      (unset OPENBLAS_NUM_THREADS OMP_NUM_THREADS; bench threads_trefoil threads --config trefoil --t-end 10) ;;
    case | case-candycane)
      # A whole reference case on one core with the path of KNOTFLOW_CASE_UPDATE (default
      # 'iterative') and KNOTFLOW_CASE_METHOD (default 'ros34pw2'): the trefoil (orientation c,
      # A = 2.2, t_end = 1000) or the seeded candy-cane (A = 1, t_end = 2000); the study's model
      # (L = 2 + lubrication, overlap 'relax' as the study inputs, tolerance 1e-4). Wall and
      # processor seconds and the load average at both ends into $out/<name>.txt.
      # KNOTFLOW_CASE_JACOBIAN_ORDER and KNOTFLOW_CASE_JACOBIAN_STEPS (default 0 and 4, the
      # scene defaults): &hydro jacobian_order and &integrator jacobian_steps;
      # KNOTFLOW_CASE_SOLVER_TOLERANCE (default: not given, the scene default): &hydro
      # solver_tolerance ('iterative' only).
      update="${KNOTFLOW_CASE_UPDATE:-iterative}" method="${KNOTFLOW_CASE_METHOD:-ros34pw2}"
      jorder="${KNOTFLOW_CASE_JACOBIAN_ORDER:-0}" jsteps="${KNOTFLOW_CASE_JACOBIAN_STEPS:-4}"
      stol="${KNOTFLOW_CASE_SOLVER_TOLERANCE:-}" stol_line=""
      if [ "$part" = case ]; then
        name="case_trefoil_${update}_${method}"
        chain="shape = 'trefoil', orientation = 'c'" a=2.2 t_end=1000.0
      else
        name="case_candycane_${update}_${method}"
        chain="shape = 'candycane', seed = 20150509" a=1.0 t_end=2000.0
      fi
      if [ "$jorder" != 0 ] || [ "$jsteps" != 4 ]; then name="${name}_jorder${jorder}_jsteps${jsteps}"; fi
      if [ -n "$stol" ]; then name="${name}_st${stol}" stol_line=", solver_tolerance = $stol"; fi
      dir="$out/$name"
      scene=$(cat <<NML
&chain
  $chain
/
&forces
  bending_a = $a
/
&hydro
  model = 'multipole', order = 2, lubrication = .true., update = '$update', overlap = 'relax',
  jacobian_order = $jorder$stol_line
/
&integrator
  method = '$method', t_end = $t_end, tolerance = 1.0e-4, jacobian_steps = $jsteps
/
&output
  directory = '$dir', case_name = '$name', progress_interval = 300
/
NML
)
      # resume when the same scene ran here before (its checkpoint is in $dir), else start over
      if [ "${KNOTFLOW_CASE_FRESH:-0}" = 1 ] || [ ! -f "$dir/case.nml" ] \
         || [ "$(cat "$dir/case.nml")" != "$scene" ]; then
        rm -rf "$dir"; mkdir -p "$dir"
        printf '%s\n' "$scene" > "$dir/case.nml"
        kf_log "a whole reference case on one core (taskset -c 0): $dir"
      else
        kf_log "resuming the whole reference case in $dir (segments so far: $(grep -c '^segment' "$dir/segments.txt" 2>/dev/null || echo 0))"
      fi
      commit=$(git -C "$KF_ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
      if tail -n 1 "$dir/segments.txt" 2>/dev/null | grep -q 'exit = finished$'; then
        kf_log "already finished: $out/$name.txt"; cat "$out/$name.txt"; continue
      fi
      # a segment killed with its shell (a reboot, the end of a session) left its last sample
      if [ -f "$dir/running.txt" ]; then
        echo "segment $(cat "$dir/running.txt"); exit = killed (figures of its last sample, at most a minute old)" \
          >> "$dir/segments.txt"
        rm -f "$dir/running.txt"
      fi
      load0=$(cat /proc/loadavg) start=$(date +%s)
      status=finished
      /usr/bin/time -f '%e %U %S' -o "$dir/time.txt" \
        taskset -c 0 "$KF_ROOT/build/bin/knotflow" "$dir/case.nml" >> "$dir/log.txt" 2>&1 &
      tpid=$!
      (  # every 30 s: the processor seconds of the run so far, kept in case the shell is killed
        tick=$(getconf CLK_TCK)
        while kill -0 "$tpid" 2>/dev/null; do
          sleep 30
          kpid=$(pgrep -P "$tpid" | head -n 1) || continue
          read -r -a st < "/proc/$kpid/stat" 2>/dev/null || continue
          printf 'wall_s = %s processor_s = %s user + %s system; loadavg_start = %s; loadavg_end = %s; commit = %s\n' \
            "$(( $(date +%s) - start ))" "$(awk -v t="${st[13]}" -v c="$tick" 'BEGIN { printf "%.2f", t / c }')" \
            "$(awk -v t="${st[14]}" -v c="$tick" 'BEGIN { printf "%.2f", t / c }')" "$load0" \
            "$(cat /proc/loadavg)" "$commit" > "$dir/running.txt.part"
          mv "$dir/running.txt.part" "$dir/running.txt"
        done ) &
      spid=$!
      # a TERM or INT (Ctrl-C) to this script goes on to the run, which stops after its frame and
      # checkpoint; the segment is recorded either way
      trap 'kill -TERM "$(pgrep -P "$tpid" | head -n 1)" 2>/dev/null || true' TERM INT
      while kill -0 "$tpid" 2>/dev/null; do wait "$tpid" || true; done
      rc=0; wait "$tpid" || rc=$?
      trap - TERM INT
      case "$rc" in 0) ;; 75) status=stopped ;; *) status="failed (exit $rc)" ;; esac
      kill "$spid" 2>/dev/null || true
      wait "$spid" 2>/dev/null || true
      rm -f "$dir/running.txt" "$dir/running.txt.part"
      read -r wall user sys < <(tail -n 1 "$dir/time.txt")
      echo "segment wall_s = $wall processor_s = $user user + $sys system; loadavg_start = $load0;" \
           "loadavg_end = $(cat /proc/loadavg); commit = $commit; exit = $status" >> "$dir/segments.txt"
      { echo "part = $part"; echo "update = $update"; echo "method = $method"; echo "t_end = $t_end";
        echo "jacobian_order = $jorder"; echo "jacobian_steps = $jsteps"; echo "overlap = relax";
        echo "solver_tolerance = ${stol:-default}";
        awk '/^segment/ { w += $4; p += $7 + $10; n++ }
             END { printf "segments = %d\nwall_s = %.1f\nprocessor_s = %.1f (user + system, summed over the segments)\n", n, w, p }' \
          "$dir/segments.txt"
        echo "status of the last segment = $status (per segment: $dir/segments.txt; log: $dir/log.txt)"; } > "$out/$name.txt"
      cat "$out/$name.txt" ;;
    *) kf_die "unknown part '$part' (velocity trajectory speed overlaps scaling profile stiffness compare rosenbrock case case-candycane threads)" ;;
  esac
done

reuse=0; stiffness=0
for part in "${parts[@]}"; do
  case "$part" in
    stiffness) stiffness=1 ;;
    compare | threads | rosenbrock | case | case-candycane) ;;   # their sections of the docs are written by hand from $out/*.txt
    *) reuse=1 ;;
  esac
done
if [ "$reuse" = 1 ]; then
  kf_log "knotflow-accuracy-report --reuse $out --markdown docs/accuracy.md"
  knotflow-accuracy-report --reuse "$out" --markdown "$KF_ROOT/docs/accuracy.md"
fi
if [ "$stiffness" = 1 ]; then
  kf_log "knotflow-accuracy-report --stiffness $out/stiffness --markdown docs/accuracy.md"
  knotflow-accuracy-report --stiffness "$out/stiffness" --markdown "$KF_ROOT/docs/accuracy.md" \
    --figures "$KF_ROOT/docs/figures"
fi
