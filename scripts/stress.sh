#!/usr/bin/env bash
# Stress runs of the hard regimes (docs/stability.md): build knotflow (Release), run each scene
# of inputs/stress/*.nml (or the scenes named) from scratch with the real program, one case at a
# time on one rank, time it, and tabulate wall time, steps, rejections, strand passages, overlap
# episodes and durations, overlapping pairs, minimum distance, bond strain and final status with
# knotflow-stress-summary into <output>/summary.md.
#   scripts/stress.sh [scene.nml ...]
# The full set takes roughly 30-60 min on one core; do not run it while others need the CPU.
#
# Environment: STRESS_QUICK=1   shortened runs: t_end and frame_interval x 0.05, output in
#                               results/stress-quick (figures of such runs are not the stress
#                               figures; say so when quoting them)
#              STRESS_SCALE=x   any other factor on t_end and frame_interval
#              STRESS_OUTPUT_DIR  output directory (default results/stress or results/stress-quick)
#              KNOTFLOW_JOBS, KNOTFLOW_PYTHON, KNOTFLOW_NO_INSTALL=1 (scripts/lib.sh)
set -euo pipefail
caller_dir="$(pwd)"
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

scale="${STRESS_SCALE:-1}"
default_out="results/stress"
if [ "${STRESS_QUICK:-0}" = 1 ]; then
  scale="${STRESS_SCALE:-0.05}"
  default_out="results/stress-quick"
fi
[[ "$scale" =~ ^[0-9]*\.?[0-9]+([eE][-+]?[0-9]+)?$ ]] || kf_die "STRESS_SCALE must be a positive number (got '$scale')"
outdir="${STRESS_OUTPUT_DIR:-$default_out}"
case "$outdir" in
  /*) ;;
  *) outdir="$KF_ROOT/$outdir" ;;
esac

scenes=()
if [ "$#" -gt 0 ]; then
  for s in "$@"; do
    case "$s" in
      /*) ;;
      *) s="$caller_dir/$s" ;;
    esac
    [ -f "$s" ] || kf_die "scene not found: $s"
    scenes+=("$s")
  done
else
  shopt -s nullglob
  scenes=("$KF_ROOT"/inputs/stress/*.nml)
  shopt -u nullglob
  [ "${#scenes[@]}" -gt 0 ] || kf_die "no scenes in $KF_ROOT/inputs/stress"
fi

cd "$KF_ROOT"
kf_ensure_system_packages
kf_ensure_python
kf_build "$KF_ROOT/build" Release knotflow
exe="$KF_ROOT/build/bin/knotflow"
[ -x "$exe" ] || kf_die "the knotflow executable was not built"
command -v knotflow-stress-summary >/dev/null 2>&1 \
  || kf_die "knotflow-stress-summary not found (the tools package: pip install -e tools)"

mkdir -p "$outdir/scenes"
wall_file="$outdir/wall_times.txt"
[ -f "$wall_file" ] || printf '# case wall_seconds exit_status (scripts/stress.sh, scale %s)\n' "$scale" >"$wall_file"

failed_runs=0
for scene in "${scenes[@]}"; do
  # The scene as run: output directory replaced, t_end and frame_interval scaled.
  run_scene="$outdir/scenes/$(basename "$scene")"
  name="$("$KF_PY" - "$scene" "$run_scene" "$outdir" "$scale" <<'EOF'
import os, re, sys
src, dst, outdir, scale = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
text = open(src).read()
def scaled(m):
    return "%s%.10g" % (m.group(1), float(m.group(2).replace("d", "e").replace("D", "e")) * scale)
num = r"([-+]?[0-9]*\.?[0-9]+(?:[eEdD][-+]?[0-9]+)?)"
for var in ("t_end", "frame_interval"):
    text, n = re.subn(r"(?i)(\b%s\s*=\s*)%s" % (var, num), scaled, text)
    if var == "t_end" and n != 1:
        sys.exit("scene %s: expected one t_end = <number>, found %d" % (src, n))
text, n = re.subn(r"(?i)(\bdirectory\s*=\s*)(['\"]).*?\2", lambda m: m.group(1) + "'" + outdir + "'", text)
if n == 0:
    text = text.rstrip() + "\n&output directory = '%s' /\n" % outdir if "&output" not in text.lower() \
        else re.sub(r"(?i)&output", "&output directory = '%s'," % outdir, text, count=1)
m = re.search(r"(?i)\bcase_name\s*=\s*(['\"])(.*?)\1", text)
name = m.group(2) if m else os.path.splitext(os.path.basename(src))[0]
if not m:
    text = re.sub(r"(?i)&output", "&output case_name = '%s'," % name, text, count=1)
open(dst, "w").write(text)
print(name)
EOF
)" || kf_die "cannot prepare $scene"
  rm -f "$outdir/$name.h5"          # always from scratch (the program would resume otherwise)
  kf_log "stress case $name: $run_scene (scale $scale)"
  start=$(date +%s.%N)
  rc=0
  OPENBLAS_NUM_THREADS=1 "$exe" "$run_scene" || rc=$?
  end=$(date +%s.%N)
  wall=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }')
  # replace this case's line in the wall-time file
  grep -v -E "^$name " "$wall_file" >"$wall_file.tmp" || true
  printf '%s %s %s\n' "$name" "$wall" "$rc" >>"$wall_file.tmp"
  mv "$wall_file.tmp" "$wall_file"
  case "$rc" in
    0) kf_log "stress case $name: finished in $wall s" ;;
    3) kf_log "stress case $name: stopped with a failure (exit 3) after $wall s; see the table" ;;
    *) kf_log "stress case $name: exit status $rc after $wall s (crash?)"; failed_runs=$((failed_runs + 1)) ;;
  esac
done

title="knotflow stress runs (scale $scale of t_end; $(date -u '+%Y-%m-%d %H:%M UTC'))"
knotflow-stress-summary "$outdir" --wall-times "$wall_file" --output "$outdir/summary.md" --title "$title"
kf_log "summary: $outdir/summary.md"
[ "$failed_runs" -eq 0 ] || kf_die "$failed_runs stress case(s) ended with an unexpected exit status"
