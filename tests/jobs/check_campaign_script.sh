#!/bin/bash
# scripts/campaign.sh end to end on small sweeps put where the multipole study's inputs are
# (RPY + excluded volume, seconds; the script does not depend on the model):
#   0. --start-before a time already past runs no case; a time `date -d` cannot read is refused;
#   1. the campaign with 2 workers is killed (its process group) once the candy-cane A1.00 has
#      passed t = 8; `--no-run --digest` puts every case file into the ledger (k_f of every
#      frame with the study's 1000 closures);
#   2. the machine is lost (results/ deleted); the campaign runs again with --digest: its queue
#      continues A1.00 from the ledger (the other cases: those the ledger has finished are not
#      run again, the rest start), every case finishes, and the ledger holds every frame of
#      every case once (A1.00 in two segments, the second one `A1.00_from<T>`);
#      knotflow-study reads the ledger's sweep directories as it reads case files, and
#      scripts/reproduce.sh --ledger computes the candy-cane's knot matrices from its kept frames
#      and compares the probe (candycane_epslub_multipole) on its own;
#   3. a third run has nothing to do and changes no ledger row;
#   4. --digest-every: the probe's ledger entry is removed and its case run again (no --digest)
#      by a knotflow that waits 15 s after the case before it exits; the digest every 3 s puts
#      the finished case into the ledger while the run goes on, and the run ends with its worker;
#   5. a digest skips a file unchanged since its last digest (the ledger stays as it is) and
#      digests it again once it has changed (touched), taking the k_f of its unchanged frames
#      from the last digest's copy (knotflow-analyze --reuse: no frame computed again);
#   6. --workdir elsewhere: the second probe (candycane_order3_multipole, a chain from a
#      coordinate file named relative to the repository's top, as inputs/ does) runs there
#      through the link DIR/inputs the script makes, and is digested into the ledger again.
# Exit status 77 (ctest: skipped) without the system's numpy/h5py/matplotlib for the tools.
# Usage: check_campaign_script.sh SOURCE_DIR BUILD_DIR WORKDIR
set -uo pipefail
src="$(cd "$1" && pwd)" build="$(cd "$2" && pwd)" work="$3"
fail() { echo "FAIL: $*" >&2; exit 1; }
rm -rf "${work}"
# shellcheck source=tests/jobs/project_copy.sh
source "${src}/tests/jobs/project_copy.sh"
kf_project_copy "${src}" "${build}" "${work}"
py="${proj}/build/venv/bin/python"
cd "${proj}" || fail "no project directory"
kf_small_sweep trefoil_table2_multipole "shape = 'trefoil'" "&sweep orientation = 'a', 'c' /" 3.0
kf_small_sweep candycane_multipole "shape = 'candycane'" "&sweep bending_a = 1.0 /" 20.0
kf_small_sweep candycane_seeds_multipole "shape = 'candycane'" "&sweep bending_a = 1.0, 3.0, seed = 1 /" 2.0
kf_small_sweep candycane_epslub_multipole "shape = 'candycane'" "&sweep bending_a = 1.0 /" 2.0
mkdir -p inputs/configs
awk 'BEGIN { for (i = 0; i < 30; i++) printf "%.4f 0.0 %.4f\n", 1.02 * i, 0.3 * sin(i / 3.0) }' \
  >inputs/configs/small_chain.xyz
kf_small_sweep candycane_order3_multipole "shape = 'file', coordinate_file = 'inputs/configs/small_chain.xyz'" \
  "&sweep bending_a = 1.0 /" 2.0
ledger="docs/reproduction_multipole/ledger"

# 0. --start-before: a time already past starts no case (every worker stops at once); a time
#    that `date -d` cannot read is refused before anything runs.
bash scripts/campaign.sh --workers 2 --start-before '1 minute ago' >"${work}/run0.log" 2>&1 \
  || fail "campaign.sh --start-before in the past: $(tail -n 5 "${work}/run0.log")"
[ "$(grep -c 'no case starts at or after' "${work}/run0.log")" = 2 ] \
  || fail "--start-before in the past: both workers should stop: $(tail -n 5 "${work}/run0.log")"
if compgen -G "results/*/*.h5" >/dev/null; then fail "--start-before in the past: a case started"; fi
if bash scripts/campaign.sh --start-before 'no such time' >"${work}/bad0.log" 2>&1; then
  fail "--start-before 'no such time' accepted"
fi
grep -q "not a time that 'date -d' reads" "${work}/bad0.log" || fail "--start-before refusal: $(cat "${work}/bad0.log")"

# 1. Killed part-way, digested.
setsid bash scripts/campaign.sh --workers 2 >"${work}/run1.log" 2>&1 &
pgid=$!
reached() {   # the time of the newest frame of a case file, 0 without one
  "$py" - "$1" <<'PY' 2>/dev/null || echo 0
import sys, h5py
with h5py.File(sys.argv[1], "r", locking=False) as h:
    print(float(h["frames/time"][-1]) if "frames/time" in h else 0.0)
PY
}
# Its progress lines (one per frame) say when it has passed t = 8.
for _ in $(seq 1 1200); do
  grep -Eq "case A1.00: t = ([89]|1[0-9])\.000 " results/campaign_candycane_multipole.A1.00.log 2>/dev/null && break
  sleep 0.1
done
kill -KILL -- "-${pgid}" 2>/dev/null
wait "${pgid}" 2>/dev/null
t_kill="$(reached results/candycane_multipole/A1.00.h5)"
"$py" -c "import sys; sys.exit(0 if 8 <= float('$t_kill') < 20 else 1)" \
  || fail "the campaign was not killed part-way (A1.00 at t = $t_kill): $(tail -n 5 "${work}/run1.log")"
bash scripts/campaign.sh --no-run --digest >"${work}/digest1.log" 2>&1 \
  || fail "campaign.sh --no-run --digest: $(tail -n 5 "${work}/digest1.log")"
grep -q "candycane_multipole/A1.00: running" "${work}/digest1.log" || fail "A1.00 not in the ledger as running: $(cat "${work}/digest1.log")"

# 2. The machine is lost: go on from the ledger.
rm -rf results
bash scripts/campaign.sh --workers 2 --digest >"${work}/run2.log" 2>&1 \
  || fail "campaign.sh --digest after the loss: $(tail -n 10 "${work}/run2.log")"
grep -q "candycane_multipole/A1.00 (continue: results/candycane_multipole/continued/A1.00_from" "${work}/run2.log" \
  || fail "A1.00 was not continued from the ledger: $(cat "${work}/run2.log")"
grep -q "^campaign: 7 of 7 cases finished; about 0.0 h of one worker left" "${work}/run2.log" \
  || fail "knotflow-campaign status after the campaign: $(tail -n 8 "${work}/run2.log")"
"$py" - "$ledger" <<'PY' || fail "the ledger after the loss is not the whole campaign"
import sys
import numpy as np
from knotflow_tools import campaign
ledger = sys.argv[1]
cases = {"trefoil_table2_multipole": {"ora": 3.0, "orc": 3.0},
         "candycane_multipole": {"A1.00": 20.0},
         "candycane_seeds_multipole": {"A1.00_s1": 2.0, "A3.00_s1": 2.0},
         "candycane_epslub_multipole": {"A1.00": 2.0}, "candycane_order3_multipole": {"A1.00": 2.0}}
for sweep, names in cases.items():
    for name, t_end in names.items():
        e = campaign.load(ledger, sweep, name)
        assert e is not None and e["status"] == "finished", (sweep, name, e)
        rows = campaign.read_rows(ledger, sweep, name)
        assert np.array_equal(rows[:, 0], np.arange(t_end + 1)), (sweep, name, rows[:, 0])
        assert np.all(np.isfinite(rows[:, 1])) and e["kf_closures"] == 1000, (sweep, name)
        assert e["case_mode"]["frames"] == len(rows), (sweep, name, e.get("case_mode"))
e = campaign.load(ledger, "candycane_multipole", "A1.00")
assert len(e["segments"]) == 2 and e["segments"][1]["case_name"].startswith("A1.00_from"), e
assert e["segments"][1]["t_offset"] == e["segments"][0]["t_last"] >= 8, e["segments"]
t, pos = campaign.read_positions(ledger, "candycane_multipole", "A1.00")
assert np.array_equal(t, [0.0, 10.0, 20.0]) and pos.shape == (3, 152, 3), (t, pos.shape)
PY

# The study's comparison straight from the ledger (knotflow-study on its sweep directories).
"${proj}/build/venv/bin/knotflow-study" --trefoil "${ledger}/trefoil_table2_multipole" \
  --candycane "${ledger}/candycane_multipole" --ensemble "${ledger}/candycane_seeds_multipole" \
  --closures 1000 --out "${work}/study" >"${work}/study.log" 2>&1 \
  || fail "knotflow-study on the ledger: $(tail -n 5 "${work}/study.log")"
"$py" - "${work}/study/results.json" <<'PY' || fail "knotflow-study's results from the ledger"
import json, sys
r = json.load(open(sys.argv[1]))
assert [c["case"] for c in r["trefoil"]["cases"]] == ["ora", "orc"], r["trefoil"]["cases"]
assert all(c["status"] == "finished" and c["t_reached"] == 3.0 for c in r["trefoil"]["cases"])
assert [c["case"] for c in r["candycane"]] == ["A1.00"] and r["candycane"][0]["t_reached"] == 20.0
assert [c["case"] for c in r["ensemble"]] == ["A1.00_s1", "A3.00_s1"], r["ensemble"]
PY

# The multipole study's analysis from the ledger (scripts/reproduce.sh --ledger): knot matrices
# of the candy-cane's kept frames (t = 0, 10, 20), the slipknot screen on them.
KNOTFLOW_NP=1 KNOTFLOW_NO_INSTALL=1 bash scripts/reproduce.sh --hydro multipole --ledger "${ledger}" \
  --no-build >"${work}/reproduce.log" 2>&1 || fail "reproduce.sh --ledger: $(tail -n 10 "${work}/reproduce.log")"
"$py" - results/reproduction_multipole <<'PY' || fail "reproduce.sh --ledger: not the ledger's analysis"
import json, os, sys
out = sys.argv[1]
r = json.load(open(os.path.join(out, "results.json")))
m = r["candycane"][0]["matrices"]
assert [e["frame"] for e in m] == [0, 10, 20] and [e["time"] for e in m] == [0.0, 10.0, 20.0], m
assert all(0.0 <= e["max_K"] <= 1.0 for e in m), m
assert sorted(os.listdir(os.path.join(out, "ledger_matrices"))) == sorted(
    f"A1.00_frame{k}.{x}" for k in (0, 10, 20) for x in ("json", "xyz")), os.listdir(out)
# the probe on its own, from its ledger sweep, without knot matrices
p = json.load(open(out + "_candycane_epslub_multipole/results.json"))
assert [c["case"] for c in p["candycane"]] == ["A1.00"] and p["candycane"][0]["t_reached"] == 2.0, p
PY

# 3. Nothing left to do; the ledger stays as it is.
before="$(cat "${ledger}"/*/*.csv | md5sum)"
bash scripts/campaign.sh --workers 2 >"${work}/run3.log" 2>&1 || fail "a third campaign.sh: $(tail -n 5 "${work}/run3.log")"
grep -q "^==> 0 case(s) to run" "${work}/run3.log" || fail "a finished campaign ran again: $(cat "${work}/run3.log")"
[ "$(cat "${ledger}"/*/*.csv | md5sum)" = "${before}" ] || fail "the ledger changed without a run"
# 4. A digest every 3 s while the run goes on.
rm -rf results "${ledger}/candycane_epslub_multipole"
slow="${work}/slow_build"
mkdir -p "${slow}/bin"
ln -s "${proj}/build/venv" "${slow}/venv"
ln -s "${proj}/build/bin/knotflow-analyze" "${slow}/bin/knotflow-analyze"
cat >"${slow}/bin/knotflow" <<EOF
#!/bin/bash
"${proj}/build/bin/knotflow" "\$@"
status=\$?
case " \$* " in *" --write-scenes "*) ;; *) sleep 15 ;; esac
exit \$status
EOF
chmod +x "${slow}/bin/knotflow"
KNOTFLOW_BUILD_DIR="${slow}" bash scripts/campaign.sh --workers 1 --digest-every 0.05 >"${work}/run4.log" 2>&1 \
  || fail "campaign.sh --digest-every: $(tail -n 5 "${work}/run4.log")"
grep -q "^==> 1 case(s) to run" "${work}/run4.log" || fail "not the probe alone: $(cat "${work}/run4.log")"
grep -q "periodic digest (every 0.05 min)" "${work}/run4.log" || fail "no periodic digest: $(cat "${work}/run4.log")"
"$py" - "$ledger" <<'PY' || fail "the periodic digest did not put the probe into the ledger: $(cat results/campaign_digest.log)"
import sys
from knotflow_tools import campaign
e = campaign.load(sys.argv[1], "candycane_epslub_multipole", "A1.00")
assert e is not None and e["status"] == "finished", e
assert len(campaign.read_rows(sys.argv[1], "candycane_epslub_multipole", "A1.00")) == 3
PY
KNOTFLOW_BUILD_DIR="${slow}" bash scripts/campaign.sh --digest-every 0 >"${work}/bad.log" 2>&1 \
  && fail "--digest-every 0 accepted"
grep -q "digest-every needs a number of minutes" "${work}/bad.log" || fail "--digest-every 0: $(cat "${work}/bad.log")"

# 5. A digest skips the files unchanged since their last digest, and only those.
bash scripts/campaign.sh --no-run --digest >"${work}/digest5a.log" 2>&1 \
  || fail "campaign.sh --no-run --digest (5): $(tail -n 5 "${work}/digest5a.log")"
files="$(find results -path results/ledger_copies -prune -o -name '*.h5' -print | sort)"
[ "$(wc -l <<<"${files}")" -eq 1 ] || fail "step 5 expects the probe's file alone: ${files}"
before="$(cat "${ledger}"/*/*.csv "${ledger}"/*/*.json | md5sum)"
bash scripts/campaign.sh --no-run --digest >"${work}/digest5b.log" 2>&1 \
  || fail "campaign.sh --no-run --digest (5, again): $(tail -n 5 "${work}/digest5b.log")"
grep -qx "==> unchanged since its last digest: ${files}" "${work}/digest5b.log" \
  || fail "an unchanged file was digested again: $(cat "${work}/digest5b.log")"
[ "$(cat "${ledger}"/*/*.csv "${ledger}"/*/*.json | md5sum)" = "${before}" ] \
  || fail "skipping an unchanged file changed the ledger"
touch "${files}"
bash scripts/campaign.sh --no-run --digest >"${work}/digest5c.log" 2>&1 \
  || fail "campaign.sh --no-run --digest (5, touched): $(tail -n 5 "${work}/digest5c.log")"
grep -q "unchanged since its last digest" "${work}/digest5c.log" \
  && fail "a changed file was skipped: $(cat "${work}/digest5c.log")"
grep -q "^candycane_epslub_multipole/A1.00: finished" "${work}/digest5c.log" \
  || fail "the changed file was not digested: $(cat "${work}/digest5c.log")"
# ... from the copy of the last digest: its frames are the same, so none is computed again
if ! grep -q "A1.00.h5.new.h5: 3 frames (0 new)" "${work}/digest5c.log" \
    || ! grep -q "k_f of 3 frame(s) taken from .*candycane_epslub_multipole/A1.00.h5$" "${work}/digest5c.log"; then
  fail "the digest of the touched file computed k_f again: $(cat "${work}/digest5c.log")"
fi

# 6. Another work directory: its inputs link resolves the probe's coordinate file.
rm -rf "${ledger}/candycane_order3_multipole"
bash scripts/campaign.sh --workers 1 --digest --workdir "${work}/elsewhere" >"${work}/run6.log" 2>&1 \
  || fail "campaign.sh --workdir: $(tail -n 5 "${work}/run6.log")"
[ "$(readlink "${work}/elsewhere/inputs")" = "${proj}/inputs" ] || fail "no link ${work}/elsewhere/inputs -> ${proj}/inputs"
grep -q "^==> 1 case(s) to run" "${work}/run6.log" || fail "not the second probe alone: $(cat "${work}/run6.log")"
[ -f "${work}/elsewhere/results/candycane_order3_multipole/A1.00.h5" ] || fail "the probe did not run in the work directory"
grep -q "^candycane_order3_multipole/A1.00: finished, t = 2 of 2" "${work}/run6.log" \
  || fail "the probe run elsewhere is not in the ledger: $(cat "${work}/run6.log")"

echo "campaign.sh: killed at t = ${t_kill}, continued from the ledger on a new results directory, every case finished once; a digest every 3 s during a run; unchanged files skipped; a chain from a coordinate file in another work directory"
