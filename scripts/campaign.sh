#!/usr/bin/env bash
# The multipole campaign of the study (scripts/study_sweeps.sh) on a machine that may not last:
# what each case needs is kept in the case ledger (docs/reproduction_multipole/ledger, small
# committed text files: knotflow-campaign, docs/analysis.md "The case ledger"), and the next
# machine goes on from it.
#   scripts/campaign.sh [--set study|ensembles] [--workers N] [--digest] [--digest-every MIN]
#                       [--start-before TIME] [--no-run] [--workdir DIR] [--ledger DIR]
#
#   --set       which sweeps: `study` (default) the multipole study of scripts/study_sweeps.sh,
#               inputs/<sweep>.nml, ledger docs/reproduction_multipole/ledger, the sweeps
#               interleaved; `ensembles` the RPY + EV ensembles of issue 36 of
#               scripts/ensemble_sweeps.sh, inputs/ensembles/<sweep>.nml, ledger
#               docs/ensembles/ledger, the sweeps one after the other in the listed order (the
#               most informative first; within a sweep the order of its &sweep lists).
#
#   (default)   run: each case of every sweep as a single-case scene (knotflow --write-scenes),
#               N processes of one rank each (default KNOTFLOW_NP, 2) taking the cases in
#               turn: first those with progress (a case file here, or the ledger), then the
#               others (the sweeps interleaved or in sequence, --set; within a sweep in the
#               order of its cases). A case whose file is here resumes it; a case
#               the ledger has but this machine does not is continued from the ledger's newest
#               frame (results/<sweep>/continued/<case>_from<T>). Runs until every case has
#               finished; killing it loses nothing but the frames since the last digest.
#   --digest    then (with --no-run: only) add every case file here to the ledger: a copy,
#               k_f of every frame (knotflow-analyze, closures of scripts/study_sweeps.sh; the
#               frames unchanged since the last digest's copy are taken from it, not recomputed),
#               knotflow-campaign digest; a file unchanged since its last digest is skipped.
#               Run it before the machine goes (it may run beside the campaign: it reads
#               copies), then commit the ledger.
#   --digest-every  while the workers run, also digest every MIN minutes (decimals allowed; one at a
#               time, in the background of the run), so that a machine that goes without
#               warning loses at most MIN minutes of progress when the ledger lives on storage
#               that outlasts it (the repository's checkout); commit the ledger as before.
#   --start-before  a worker starts no case at or after TIME (anything `date -d` reads, e.g.
#               '01:00' or '2026-12-08 01:00 UTC'; refused when it reads none), and stops: for a
#               machine or a batch job that ends at a known time, so that no case is cut there and
#               later continued from the ledger (a continuation restarts the stepper: another kind
#               of sample, docs/running.md). The cases running at TIME go on to their end.
#   --workdir   where knotflow runs (default: the repository): the case files go where the
#               inputs say, DIR/results/<sweep>/ (and DIR/inputs, if missing, becomes a link to
#               the repository's inputs, for their coordinate files); --ledger: default the
#               set's ledger in the repository (above).
# Positions kept in the ledger: the candy-canes and the probe every 10 time units (the knot
# matrices of the slipknot search, snapshots), the further rotations (and the ensembles'
# candy-canes) every 50, the trefoils every 100; every case's newest frame at full precision.
# Needs a build (scripts/build.sh; KNOTFLOW_BUILD_DIR) and its Python tools; installs nothing.
# The whole script is one block that bash reads before it runs any of it, so editing this file
# (a checkout updated) while a campaign runs for hours does not change the running one.
{
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=scripts/study_sweeps.sh
source "$KF_ROOT/scripts/study_sweeps.sh"
# shellcheck source=scripts/ensemble_sweeps.sh
source "$KF_ROOT/scripts/ensemble_sweeps.sh"

run=1
digest=0
digest_every=0   # minutes, as given (0: no periodic digest)
start_before=    # seconds since the epoch (empty: no limit)
digest_period=0  # the same in whole seconds
workdir="$KF_ROOT"
set_name=study
ledger=
workers="$(kf_ranks)"
while [ $# -gt 0 ]; do
  case "$1" in
    --workers)
      if [ $# -lt 2 ] || ! [[ "$2" =~ ^[1-9][0-9]*$ ]]; then kf_die "--workers needs a positive integer"; fi
      workers="$2"; shift 2 ;;
    --digest) digest=1; shift ;;
    --digest-every)
      [[ "${2:-}" =~ ^[0-9]+(\.[0-9]+)?$ ]] && digest_period="$(awk -v m="$2" 'BEGIN {printf "%d", m * 60 + 0.5}')"
      if [ "$digest_period" -lt 1 ]; then
        kf_die "--digest-every needs a number of minutes, at least 1 s (0.0167): got '${2:-}'"
      fi
      digest_every="$2"; shift 2 ;;
    --start-before)
      [ $# -ge 2 ] || kf_die "--start-before needs a time (anything 'date -d' reads)"
      start_before="$(date -d "$2" +%s 2>/dev/null)" \
        || kf_die "--start-before '$2': not a time that 'date -d' reads (e.g. '01:00' or '2026-12-08 01:00 UTC')"
      shift 2 ;;
    --no-run) run=0; shift ;;
    --workdir) [ $# -ge 2 ] || kf_die "--workdir needs a directory"; workdir="$2"; shift 2 ;;
    --ledger) [ $# -ge 2 ] || kf_die "--ledger needs a directory"; ledger="$2"; shift 2 ;;
    --set)
      case "${2:-}" in study|ensembles) set_name="$2" ;; *) kf_die "--set needs study or ensembles: got '${2:-}'" ;; esac
      shift 2 ;;
    *) kf_die "unknown argument '$1' (allowed: --set study|ensembles, --workers N, --digest, --digest-every MIN, --start-before TIME, --no-run, --workdir DIR, --ledger DIR)" ;;
  esac
done
# The set: its sweeps (KF_STUDY_ROLES, KF_STUDY_SWEEPS), inputs, default ledger, the closures of
# a role, the order of the queue (interleaved: rank within its sweep; sequential: sweep, then rank).
case "$set_name" in
  study)
    kf_study_arrays multipole 1 || exit 1
    inputs="$KF_ROOT/inputs"
    : "${ledger:=$KF_ROOT/docs/reproduction_multipole/ledger}"
    set_closures() { kf_study_closures multipole "$1"; }
    sequential=0 ;;
  ensembles)
    kf_ensemble_arrays
    inputs="$KF_ROOT/inputs/ensembles"
    : "${ledger:=$KF_ROOT/docs/ensembles/ledger}"
    set_closures() { kf_ensemble_closures "$1"; }
    sequential=1 ;;
esac
[ -d "$KF_BUILD_DIR/venv/bin" ] && PATH="$KF_BUILD_DIR/venv/bin:$PATH"
knotflow="$(cd "$KF_BUILD_DIR" && pwd)/bin/knotflow"
analyze="$(cd "$KF_BUILD_DIR" && pwd)/bin/knotflow-analyze"
for exe in "$knotflow" "$analyze"; do
  [ -x "$exe" ] || kf_die "$exe not found (build first: bash scripts/build.sh)"
done
command -v knotflow-campaign >/dev/null 2>&1 || kf_die "knotflow-campaign not found (bash scripts/build.sh installs it)"
mkdir -p "$workdir/results" "$ledger"
ledger="$(cd "$ledger" && pwd)"
# Everything from here on in the work directory: the inputs' output directories are relative.
# Their coordinate files are relative to the repository's top (where they are run by hand): in
# another work directory a link inputs -> the repository's inputs resolves them.
[ -e "$workdir/inputs" ] || ln -s "$KF_ROOT/inputs" "$workdir/inputs"
cd "$workdir"
results=results
# The scene variables' defaults of the program that runs the cases: a continuation run by a
# later version writes the variables added since with their defaults (knotflow-campaign digest
# --scene-reference).
mkdir -p "$results"
"$knotflow" --scene-reference >"$results/scene-reference.md"

# One line "sweep case action scene" per case still to run, cases with progress first.
queue() {
  local i sweep
  mkdir -p "$results/scenes"
  for i in "${!KF_STUDY_SWEEPS[@]}"; do
    sweep="${KF_STUDY_SWEEPS[i]}"
    # rank = the case's number in its sweep (knotflow lists "case K: NAME ..."), so that a
    # sweep runs in the order of its &sweep lists (plan lists the cases by name)
    "$knotflow" "$inputs/$sweep.nml" --write-scenes "$results/scenes/$sweep" \
      | awk '$1 == "case" {sub(":", "", $2); print $2, $3}' >"$results/scenes/$sweep.order"
    knotflow-campaign plan --scenes "$results/scenes/$sweep" --results "$results" \
      --ledger "$ledger" --sweep "$sweep" \
      | awk -v s="$sweep" -v base="$((sequential * i * 100000))" \
          'NR == FNR {rank[$2] = $1; next} $2 != "finished" {print base + rank[$1], s, $0}' \
          "$results/scenes/$sweep.order" -
  done | while read -r rank sweep case action scene; do
    progress=1
    [ "$action" = continue ] || [ -e "$results/$sweep/$case.h5" ] || [ -e "$ledger/$sweep/$case.json" ] || progress=2
    printf '%s %s %s %s %s %s\n' "$progress" "$rank" "$sweep" "$case" "$action" "$scene"
  done | sort -k1,1n -k2,2n -s | cut -d' ' -f3-
}

worker() {
  local id="$1" sweep case action scene status
  while read -r sweep case action scene; do
    if [ -n "$start_before" ] && [ "$(date +%s)" -ge "$start_before" ]; then
      kf_log "worker $id: no case starts at or after $(date -u -d "@$start_before" '+%Y-%m-%d %H:%M:%S UTC') (--start-before); worker stops"
      break
    fi
    mkdir "$results/claims/$sweep.$case" 2>/dev/null || continue
    kf_log "worker $id: $sweep/$case ($action: $scene)"
    status=0
    "$knotflow" "$scene" >>"$results/campaign_$sweep.$case.log" 2>&1 || status=$?
    if [ "$status" = 75 ]; then
      # stopped by SIGTERM/SIGINT after its last frame (docs/robustness.md): the next run of
      # this script resumes it; this worker takes no further case
      kf_log "worker $id: $sweep/$case stopped by a signal (status 75), resumed by the next run; worker stops"
      break
    fi
    [ "$status" = 0 ] \
      || kf_log "worker $id: $sweep/$case exited with status $status (see $results/campaign_$sweep.$case.log)"
  done <"$results/queue.txt"
}

# Add every case file here to the ledger (--digest).
digest_all() {
  shopt -s nullglob
  copies="$results/ledger_copies"
  for i in "${!KF_STUDY_SWEEPS[@]}"; do
    role="${KF_STUDY_ROLES[i]}" sweep="${KF_STUDY_SWEEPS[i]}"
    read -r closures stride < <(set_closures "$role")
    [ "$stride" = 1 ] || kf_die "$sweep: the ledger takes k_f of every frame (stride $stride)"
    case "$role" in
      candycane|probe) every=10 ;;
      ensemble) every=50 ;;
      *) every=100 ;;
    esac
    for f in "$results/$sweep"/*.h5 "$results/$sweep"/continued/*.h5; do
      rel="${f#"$results"/}"
      base="$(basename "$f" .h5)"
      name="${base%_from*}"
      # A file unchanged (size, modification time to the ns) since its last digest into this
      # ledger is not copied and analysed again: a finished case costs one digest, not one per
      # digest. The stamp is taken before the copy, so a write during the copy makes it stale.
      stamp="$(stat -c '%s %.9Y' "$f") $ledger"
      if [ -f "$copies/$rel.digested" ] && [ "$(cat "$copies/$rel.digested")" = "$stamp" ] \
          && [ -f "$ledger/$sweep/$name.json" ]; then
        kf_log "unchanged since its last digest: $f"
        continue
      fi
      mkdir -p "$copies/$(dirname "$rel")"
      # The copy of the last digest (analysed) lends the k_f of the frames the file still holds
      # unchanged (knotflow-analyze --reuse): a digest computes only the frames added since.
      reuse=()
      [ -f "$copies/$rel" ] && reuse=(--reuse "$copies/$rel")
      cp "$f" "$copies/$rel.new.h5"
      # A file killed before its first frame was whole has nothing to digest (the next run
      # starts it again).
      if ! "$analyze" "$copies/$rel.new.h5" --closures "$closures" --stride 1 "${reuse[@]}"; then
        kf_log "not digested: $f (knotflow-analyze refused it, above)"
        continue
      fi
      mv "$copies/$rel.new.h5" "$copies/$rel"
      if ! knotflow-campaign digest "$copies/$rel" --copies "$copies" --results "$results" \
          --ledger "$ledger" --sweep "$sweep" --closures "$closures" --positions-every "$every" \
          --scene-reference "$results/scene-reference.md"; then
        kf_log "not digested: $f (above)"
        continue
      fi
      # The case mode of all its rows (a continuation's file holds only its own frames).
      if knotflow-campaign mode --ledger "$ledger" --sweep "$sweep" --case "$name" \
          --analyze-json "$("$analyze" "$ledger/$sweep/$name.csv" --json)"; then
        printf '%s\n' "$stamp" >"$copies/$rel.digested"
      else
        kf_log "case mode of $sweep/$name not recorded (above)"
      fi
    done
  done
  scenes=()
  [ -d "$results/scenes" ] && scenes=(--scenes "$results/scenes")
  knotflow-campaign status --ledger "$ledger" "${scenes[@]}" --scene-reference "$results/scene-reference.md"
}

# --digest-every: a digest every $digest_every minutes until the file $1 appears (checked every
# second, so the run ends soon after its workers, never in the middle of a digest); a failed
# digest is logged and the next one tried.
digest_loop() {
  local stop="$1" waited=0
  while [ ! -e "$stop" ]; do
    sleep 1
    waited=$((waited + 1))
    if [ "$waited" -lt "$digest_period" ] || [ -e "$stop" ]; then continue; fi
    waited=0
    kf_log "periodic digest (every $digest_every min), log in $results/campaign_digest.log"
    ( digest_all ) >>"$results/campaign_digest.log" 2>&1 \
      || kf_log "periodic digest failed (see $results/campaign_digest.log); next in $digest_every min"
  done
}

if [ "$run" = 1 ]; then
  export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
  rm -rf "$results/claims"
  mkdir -p "$results/claims"
  queue >"$results/queue.txt"
  kf_log "$(wc -l <"$results/queue.txt") case(s) to run, $workers worker(s); queue in $results/queue.txt"
  pids=()
  for w in $(seq 1 "$workers"); do
    worker "$w" &
    pids+=($!)
  done
  loop=
  rm -f "$results/digest_loop.stop"
  if [ "$digest_period" -gt 0 ]; then
    digest_loop "$results/digest_loop.stop" &
    loop=$!
  fi
  for p in "${pids[@]}"; do wait "$p"; done
  if [ -n "$loop" ]; then
    touch "$results/digest_loop.stop"
    wait "$loop" || true
  fi
fi

if [ "$digest" = 1 ]; then
  digest_all
fi
exit
}
