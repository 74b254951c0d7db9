#!/usr/bin/env bash
# Build knotflow (Release) and run a parameter sweep under MPI, then the report tool.
#   scripts/run.sh [sweep.nml]      (default: inputs/sweep.nml)
# Works from any directory (a relative sweep path is taken relative to the current
# directory); the program runs in the repository root.  Re-running resumes the sweep
# (the program skips finished cases).
#
# Environment: KNOTFLOW_NP (MPI ranks, default 2), KNOTFLOW_JOBS (build jobs, default 2),
#              KNOTFLOW_OUTPUT_DIR (sweep output directory for the report; default: the one
#              knotflow resolves from the namelist), KNOTFLOW_PYTHON, KNOTFLOW_NO_INSTALL=1.
set -euo pipefail
caller_dir="$(pwd)"
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

sweep="${1:-$KF_ROOT/inputs/sweep.nml}"
case "$sweep" in
  /*) ;;
  *) sweep="$caller_dir/$sweep" ;;
esac
[ -f "$sweep" ] || kf_die "sweep file not found: $sweep"
np="$(kf_ranks)"

cd "$KF_ROOT"
kf_ensure_system_packages
kf_ensure_python
kf_build "$KF_ROOT/build" Release

# every program of the build is in build/bin
exe="$KF_ROOT/build/bin/knotflow"
[ -x "$exe" ] || kf_die "the knotflow executable was not built ($exe)"

# At the end: where the results are and how to reach the Python commands from a new shell.
kf_where_tools() {
  local bin
  bin="$(dirname "$KF_PY")"
  echo
  if [ -n "${1:-}" ]; then
    kf_log "done. Results: $1"
  else
    kf_log "done."
  fi
  if [ -n "${1:-}" ] && [ -f "$1/report/report.html" ]; then
    echo "    report:  $1/report/report.html   (movies in report/figures/, <case>.xdmf2 for ParaView)"
  fi
  echo "    The Python commands (knotflow-report, knotflow-movie, knotflow-xdmf, knotflow-plot,"
  echo "    knotflow-kf, ...) are in $bin. In a new shell, either"
  echo "        source $bin/activate"
  echo "    or put them on PATH:"
  echo "        export PATH=\"$bin:\$PATH\""
}

kf_mpirun_flags
# Where the sweep writes its cases: KNOTFLOW_OUTPUT_DIR, else the directory knotflow itself
# resolves (&output directory, or its default), from the first line of a dry run.
outdir="${KNOTFLOW_OUTPUT_DIR:-}"
if [ -z "$outdir" ]; then
  outdir="$(mpirun -n 1 "${KF_MPIRUN_FLAGS[@]}" "$exe" "$sweep" --dry-run \
            | sed -n 's/^knotflow .*, output in //p' | head -n 1)"
fi
kf_log "mpirun -n $np ${KF_MPIRUN_FLAGS[*]} $exe $sweep"
mpirun -n "$np" "${KF_MPIRUN_FLAGS[@]}" "$exe" "$sweep"

if [ -z "$outdir" ]; then
  kf_log "no output directory known (set KNOTFLOW_OUTPUT_DIR): report skipped"
  kf_where_tools ""
  exit 0
fi
case "$outdir" in
  /*) ;;
  *) outdir="$KF_ROOT/$outdir" ;;
esac
# The Fortran analysis tool fills /analysis in every case file (knots, events, modes, spectra,
# the knot matrix of the last frame); it resumes, so re-running is cheap.
analyze="$KF_ROOT/build/bin/knotflow-analyze"
shopt -s nullglob
cases=("$outdir"/*.h5)
if [ -x "$analyze" ] && [ "${#cases[@]}" -gt 0 ]; then
  kf_log "knotflow-analyze on ${#cases[@]} case file(s)"
  mpirun -n "$np" "${KF_MPIRUN_FLAGS[@]}" "$analyze" "${cases[@]}" --stride 10 --matrix-frames last
fi

if command -v knotflow-report >/dev/null 2>&1; then
  kf_log "knotflow-report $outdir (tables, figures, a movie and an interactive 3-D view per case, XDMF files)"
  knotflow-report "$outdir"
else
  kf_log "knotflow-report not installed: report skipped (results in $outdir)"
fi
kf_where_tools "$outdir"
