#!/usr/bin/env bash
# Reproduce the reference study: run its sweeps (scripts/study_sweeps.sh: trefoil Table 2, 29
# cases, N = 99; the candy-cane, A = 1, 1.4, 3, N = 152; and more below), analyse them, and
# write the comparison.
#   scripts/reproduce.sh [--hydro rpy|multipole] [--no-run] [--no-extras] [--no-build]
#                        [--results DIR] [--ledger DIR] [--quick] [--list-sweeps]
#
#   --hydro rpy        (default) inputs/trefoil_table2.nml and inputs/candycane.nml:
#                      RPY + excluded volume, about 30 s per trefoil case on one core.
#   --hydro multipole  the campaign of issue 11 with the study's model (multipole L = 2 +
#                      lubrication): inputs/trefoil_table2_multipole.nml, candycane_multipole.nml
#                      and candycane_seeds_multipole.nml (A = 1, 3 from two further rotations:
#                      part of this study, not an extra) and the probes
#                      candycane_epslub_multipole.nml (A = 1 with eps_lub = 1e-2) and
#                      candycane_order3_multipole.nml (A = 1 with L = 3 from t = 1100); hours
#                      per case (a cluster job: jobs/README.md).
#   --no-run           only analyse what the sweeps already wrote (e.g. after cluster jobs).
#   --no-extras        (rpy) skip the two checks beyond the study's inputs: the candy-cane with 5
#                      random rotations (inputs/candycane_seeds.nml) and Table 2 with the open
#                      trefoil whose k_f(0) = 0.98 (inputs/trefoil_table2_p24.nml).
#   --ledger DIR       (multipole) analyse the case ledger DIR (scripts/campaign.sh:
#                      docs/reproduction_multipole/ledger) instead of case files: its rows hold
#                      k_f of every frame and the shapes; here only the knot matrices of the
#                      candy-canes' kept frames (every 10 time units) and the slipknot check
#                      are computed, into results/reproduction_multipole/ledger_matrices.
#                      Implies --no-run.
#   --no-build         install and build nothing: use the existing build (KNOTFLOW_BUILD_DIR,
#                      default build/) and its Python tools (<build>/venv); a batch job's way.
#   --results DIR      the sweeps' output directories are DIR/<sweep> (default results; a
#                      shortened study of jobs/submit_study.sh has its own), the comparison goes
#                      to DIR/reproduction[_multipole].
#   --quick            a trial of the workflow (with a shortened study): 20 closures per frame,
#                      5 per subchain for knot matrices and 100 for the slipknot check; the
#                      numbers are then too noisy to compare with the study.
#   --list-sweeps      print the sweeps of --hydro (and --no-extras), "ROLE SWEEP" a line, and exit.
#
# Analysis (knotflow-analyze fills /analysis of every case file; knotflow-study compares):
#                      rpy                            multipole (as the study)
#   k_f per frame      200 closures, every frame      1000 closures, every frame
#                      (ensemble: 100, every 2nd)     (rotations and probe too)
#   knot matrices      trefoils: last frame, 100 closures per subchain (both)
#                      candy-canes: 20 per subchain at the frames of knotflow-study
#                      --select-frames: every 50th   --every-time 10: every 10 time units
#                      (and the last frame and the 5 most entangled frames, both)
#   slipknots          candidates of the screen recomputed with 100 closures per subchain; the
#                      knot core of those still slipknots and the whole chain with 1000 closures
#                      (seed 1973): confirmed by the rule of docs/analysis.md (both)
#   comparison         results/reproduction[_multipole]/; multipole: the rotations as --ensemble,
#                      and the RPY results beside it (--rpy-trefoil docs/reproduction_p24/results.json
#                      --rpy-candycane docs/reproduction/results.json) when both files are there;
#                      each probe on its own as a candy-cane sweep (no knot matrices) in
#                      results/reproduction_multipole_<probe sweep>/.
# Cost of the multipole analysis, measured with build/bin/knotflow-analyze on one rank (CPU
# time; load 4.2-4.9 on 2 cores, wall time twice that): k_f with 1000 closures 38 s for a
# trefoil case (N = 99, 1001 frames: 29 cases 18 min) and 0.066 s per candy-cane frame (N = 152,
# frames to t = 432 of the running A = 1 case; 2001 frames: 2.2 min a case, 7 cases 15 min); a
# candy-cane knot matrix 3.8 s with 20 closures per subchain (the most entangled frame so far,
# 44 close pairs) and 19 s with 100. About 206 matrices per candy-cane: 13 min a case, 40 min for
# three. In all about 1.3 h of one core plus 19 s per slipknot candidate (and for one still a
# slipknot at 100 per subchain, its core and whole chain with 1000 closures: 0.8 s wall for a
# 65-bead subchain of the A = 1 run, load 2.3); knotflow-analyze
# shares the closures of every frame and matrix among its ranks (RPY: docs/REPRODUCTION.md).
#
# Re-running continues: finished cases are skipped, killed ones resumed, and knotflow-analyze
# reuses the k_f and knot matrices it already stored. Output: results/<sweep>/ (case files,
# report/) and results/reproduction[_multipole]/ (figures, results.md, results.json).
# Environment: KNOTFLOW_NP (MPI ranks, default 2), KNOTFLOW_NO_INSTALL=1 (see scripts/lib.sh),
# KNOTFLOW_BUILD_DIR, KNOTFLOW_LAUNCHER (the command that starts an MPI program, e.g.
# "srun --mpi=pmix" in a SLURM job; default mpirun -n KNOTFLOW_NP).
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=scripts/study_sweeps.sh
source "$KF_ROOT/scripts/study_sweeps.sh"

hydro=rpy
run=1
extras=1
build=1
results=results
ledger=""
quick=0
list=0
while [ $# -gt 0 ]; do
  case "$1" in
    --hydro) [ $# -ge 2 ] || kf_die "--hydro needs a value (rpy or multipole)"; hydro="$2"; shift 2 ;;
    --no-run) run=0; shift ;;
    --no-extras) extras=0; shift ;;
    --no-build) build=0; shift ;;
    --quick) quick=1; shift ;;
    --list-sweeps) list=1; shift ;;
    --results) [ $# -ge 2 ] || kf_die "--results needs a directory"; results="$2"; shift 2 ;;
    --ledger) [ $# -ge 2 ] || kf_die "--ledger needs a directory"; ledger="$2"; run=0; shift 2 ;;
    *) kf_die "unknown argument '$1' (allowed: --hydro rpy|multipole, --no-run, --no-extras, --no-build, --results DIR, --ledger DIR, --quick, --list-sweeps)" ;;
  esac
done
# The study's sweeps and their roles (scripts/study_sweeps.sh: the list jobs/submit_study.sh
# submits too).
if [ "$list" = 1 ]; then
  kf_study_sweeps "$hydro" "$extras"
  exit
fi
kf_study_arrays "$hydro" "$extras" || exit 1
if [ -n "$ledger" ]; then
  [ "$hydro" = multipole ] || kf_die "--ledger DIR is the multipole campaign's (give --hydro multipole)"
  [ -d "$ledger" ] || kf_die "--ledger $ledger: no such directory"
fi
# Closures per frame (trefoils and candy-canes; the ensemble, with its frame stride:
# scripts/study_sweeps.sh, kf_study_closures), per
# subchain of a knot matrix (trefoil last frame, candy-cane frames, slipknot candidates), of the
# slipknot check (knot core and whole chain, with its own seed), and
# the options of knotflow-study --select-frames (the candy-cane frames with knot matrices).
case "$hydro" in
  rpy) suffix="" select=() ;;
  multipole) suffix="_multipole" select=(--every-time 10) ;;
esac
read -r closures _ < <(kf_study_closures "$hydro" trefoil)
read -r ens_closures ens_stride < <(kf_study_closures "$hydro" ensemble)
mat_trefoil=100 mat_cane=20 mat_confirm=100 kf_confirm=1000 seed_confirm=1973
if [ "$quick" = 1 ]; then closures=20 ens_closures=20 mat_trefoil=5 mat_cane=5 mat_confirm=5 kf_confirm=100; fi
np="$(kf_ranks)"

cd "$KF_ROOT"
if [ "$build" = 1 ]; then
  kf_ensure_system_packages
  kf_ensure_python
  kf_build "$KF_BUILD_DIR" Release
else
  [ -d "$KF_BUILD_DIR/venv/bin" ] && PATH="$KF_BUILD_DIR/venv/bin:$PATH"
  for exe in "$KF_BUILD_DIR/bin/knotflow" "$KF_BUILD_DIR/bin/knotflow-analyze"; do
    [ -x "$exe" ] || kf_die "--no-build: $exe not found (build first: KNOTFLOW_BUILD_DIR=$KF_BUILD_DIR bash scripts/build.sh)"
  done
  command -v knotflow-study >/dev/null 2>&1 \
    || kf_die "--no-build: knotflow-study not found in $KF_BUILD_DIR/venv (bash scripts/build.sh installs it)"
fi
if [ -n "${KNOTFLOW_LAUNCHER:-}" ]; then
  # shellcheck disable=SC2206  # the launcher is a command with its options
  mpi=(${KNOTFLOW_LAUNCHER})
else
  kf_mpirun_flags
  mpi=(mpirun -n "$np" "${KF_MPIRUN_FLAGS[@]}")
fi
analyze="$KF_BUILD_DIR/bin/knotflow-analyze"

# Sweeps: name of the input (inputs/<name>.nml) = name of the output directory (results/<name>).
if [ "$run" = 1 ]; then
  for sweep in "${KF_STUDY_SWEEPS[@]}"; do
    kf_log "knotflow inputs/$sweep.nml on $np rank(s)"
    # A failed case (exit 3) is reported in the summary; the others are still analysed.
    "${mpi[@]}" "$KF_BUILD_DIR/bin/knotflow" "inputs/$sweep.nml" || [ $? -eq 3 ]
  done
fi

shopt -s nullglob
declare -A dir_of=()   # role -> output directory, for the sweeps with case files
declare -A empty_of=() # role -> output directory, for the sweeps there without case files
probe_dirs=()          # the probes' directories with case files (a role with several sweeps)
out="$results/reproduction$suffix"
mats="$out/ledger_matrices"
for i in "${!KF_STUDY_SWEEPS[@]}"; do
  role="${KF_STUDY_ROLES[i]}" sweep="${KF_STUDY_SWEEPS[i]}"
  if [ -n "$ledger" ]; then
    # The ledger's rows hold k_f of every frame and the shapes; the candy-canes' knot matrices
    # are computed from the frames it keeps.
    files=("$ledger/$sweep"/*.json)
    if [ "${#files[@]}" -eq 0 ]; then
      kf_log "no ledger entries in $ledger/$sweep: not analysed"
      continue
    fi
    if [ "$role" = probe ]; then probe_dirs+=("$ledger/$sweep"); else dir_of[$role]="$ledger/$sweep"; fi
    [ "$role" = candycane ] || continue
    mkdir -p "$mats"
    for f in "${files[@]}"; do
      name="$(basename "$f" .json)"
      frames="$(knotflow-study --select-frames "$f" "${select[@]}")"
      kf_log "knotflow-analyze: knot matrices of $name (ledger), frames $frames"
      for k in ${frames//,/ }; do
        [ -s "$mats/${name}_frame$k.json" ] && continue
        knotflow-study --write-frame "$f" "$k" "$mats/${name}_frame$k.xyz"
        "${mpi[@]}" "$analyze" "$mats/${name}_frame$k.xyz" --matrix --matrix-closures "$mat_cane" --json > "$mats/${name}_frame$k.json.tmp"
        mv "$mats/${name}_frame$k.json.tmp" "$mats/${name}_frame$k.json"
      done
    done
    continue
  fi
  files=("$results/$sweep"/*.h5)
  if [ "${#files[@]}" -eq 0 ]; then
    kf_log "no case files in $results/$sweep: not analysed"
    [ -d "$results/$sweep" ] && empty_of[$role]="$results/$sweep"
    continue
  fi
  if [ "$role" = probe ]; then probe_dirs+=("$results/$sweep"); else dir_of[$role]="$results/$sweep"; fi
  case "$role" in
    trefoil|trefoil_p24)
      # k_f of every frame, knot matrix of the last frame.
      kf_log "knotflow-analyze: ${#files[@]} case(s) of $results/$sweep"
      "${mpi[@]}" "$analyze" "${files[@]}" --closures "$closures" --stride 1 --matrix-frames last --matrix-closures "$mat_trefoil" ;;
    candycane)
      # k_f of every frame and knot matrices (mat_cane closures per subchain) of the frames
      # knotflow-study selects: the slipknot search.
      for f in "${files[@]}"; do
        frames="$(knotflow-study --select-frames "$f" "${select[@]}")"
        kf_log "knotflow-analyze $f (knot matrices of frames $frames)"
        "${mpi[@]}" "$analyze" "$f" --closures "$closures" --stride 1 --matrix-frames "$frames" --matrix-closures "$mat_cane"
      done ;;
    ensemble)
      for f in "${files[@]}"; do
        kf_log "knotflow-analyze $f (ensemble: $ens_closures closures, frame stride $ens_stride)"
        "${mpi[@]}" "$analyze" "$f" --closures "$ens_closures" --stride "$ens_stride"
      done ;;
    probe)
      read -r probe_closures probe_stride < <(kf_study_closures "$hydro" probe)
      [ "$quick" = 1 ] && probe_closures=20
      for f in "${files[@]}"; do
        kf_log "knotflow-analyze $f (probe: $probe_closures closures, frame stride $probe_stride)"
        "${mpi[@]}" "$analyze" "$f" --closures "$probe_closures" --stride "$probe_stride"
      done ;;
    *) kf_die "scripts/study_sweeps.sh: role '$role' of $sweep has no analysis here" ;;
  esac
done

# Slipknot candidates of the screen (20 closures per subchain: its largest K over ~10^4
# subchains is biased upwards) are recomputed with mat_confirm closures per subchain; where that
# is still a slipknot, its knot core and the whole chain get kf_confirm closures, with a seed
# other than the default so that the sample is independent of the one that selected them;
# knotflow-study applies the rule (docs/analysis.md, "Slipknot confirmation"). Files in
# $out/confirm, reused by a rerun: <case>_frame<k>.json (matrix), _core.json, _whole.json.
mkdir -p "$out/confirm"
lm=()
[ -n "$ledger" ] && lm=(--ledger-matrices "$mats")
ext=h5
[ -n "$ledger" ] && ext=json
for f in ${dir_of[candycane]:+"${dir_of[candycane]}"/*.$ext}; do
  name="$(basename "$f" ".$ext")"
  base="$out/confirm/$name"
  for k in $(knotflow-study --slip-candidates "$f" "${lm[@]}"); do
    json="${base}_frame$k.json"
    [ -s "$json" ] && continue
    kf_log "slipknot candidate $name frame $k: knot matrix with $mat_confirm closures per subchain"
    knotflow-study --write-frame "$f" "$k" "${base}_frame$k.xyz"
    "${mpi[@]}" "$analyze" "${base}_frame$k.xyz" --matrix --matrix-closures "$mat_confirm" --json > "$json.tmp"
    mv "$json.tmp" "$json"
  done
  for k in $(knotflow-study --core-candidates "$f" --confirm-dir "$out/confirm" "${lm[@]}"); do
    [ -s "${base}_frame${k}_core.json" ] && [ -s "${base}_frame${k}_whole.json" ] && continue
    kf_log "slipknot candidate $name frame $k: knot core and whole chain with $kf_confirm closures"
    [ -s "${base}_frame$k.xyz" ] || knotflow-study --write-frame "$f" "$k" "${base}_frame$k.xyz"
    knotflow-study --write-frame "$f" "$k" "${base}_frame${k}_core.xyz" --core-of "${base}_frame$k.json"
    for part in core whole; do
      xyz="${base}_frame${k}_core.xyz"
      [ "$part" = whole ] && xyz="${base}_frame$k.xyz"
      "${mpi[@]}" "$analyze" "$xyz" --closures "$kf_confirm" --seed "$seed_confirm" --json > "${base}_frame${k}_$part.json.tmp"
      mv "${base}_frame${k}_$part.json.tmp" "${base}_frame${k}_$part.json"
    done
  done
done
kf_log "knotflow-study -> $out"
# A sweep directory without case files goes to knotflow-study too: results.md says "no case
# files in DIR" there (a sweep not started, without a directory, is left out).
[ "${#dir_of[@]}" -gt 0 ] || kf_die "no case files in any sweep under $results: nothing to compare"
args=(--closures "$closures" "${lm[@]}")
for role in trefoil candycane ensemble; do
  dir="${dir_of[$role]:-${empty_of[$role]:-}}"
  [ -n "$dir" ] && args+=("--$role" "$dir")
done
# The multipole study beside the RPY one (three columns: the study, multipole, RPY), when the
# RPY comparisons are there: Table 2 with the same trefoil (k_f(0) = 0.98), and the candy-canes
# (each only with its sweep: knotflow-study refuses a comparison without it).
if [ "$hydro" = multipole ] && [ -f docs/reproduction_p24/results.json ] && [ -f docs/reproduction/results.json ]; then
  for role in trefoil candycane; do
    rpy=docs/reproduction_p24/results.json
    [ "$role" = candycane ] && rpy=docs/reproduction/results.json
    if [ -n "${dir_of[$role]:-}${empty_of[$role]:-}" ]; then args+=("--rpy-$role" "$rpy"); fi
  done
fi
knotflow-study "${args[@]}" --out "$out"
# Each probe on its own, as a candy-cane sweep (shape panels, modes, k_f; no knot matrices), to
# set beside the candy-cane of the same A in reproduction_multipole.
for dir in "${probe_dirs[@]}"; do
  read -r probe_closures _ < <(kf_study_closures "$hydro" probe)
  [ "$quick" = 1 ] && probe_closures=20
  kf_log "knotflow-study -> ${out}_$(basename "$dir") (a probe)"
  knotflow-study --candycane "$dir" --closures "$probe_closures" --out "${out}_$(basename "$dir")"
done
if [ -n "${dir_of[trefoil_p24]:-}" ]; then
  kf_log "knotflow-study -> ${out}_p24 (the open trefoil with k_f(0) = 0.98)"
  knotflow-study --trefoil "${dir_of[trefoil_p24]}" --out "${out}_p24"
fi
