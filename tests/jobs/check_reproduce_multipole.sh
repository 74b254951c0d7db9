#!/bin/bash
# The analysis of the multipole study (scripts/reproduce.sh --hydro multipole --no-run --no-build,
# as the analysis job runs it) on small case files put where the multipole sweeps write: issue 11
# asks for k_f with 1000 closures on every frame, for the trefoils and for the rotations
# ensemble (candycane_seeds_multipole, part of this study), and the ensemble in the comparison.
#   - every frame of every trefoil and ensemble case has k_f stored with 1000 closures, and each
#     trefoil the knot matrix of its last frame (100 closures per subchain);
#   - the candy-cane has k_f on every frame (1000 closures) and knot matrices (20 closures per
#     subchain) every 10 time units: frames 0, 10, 20 of a run to t = 20 without close pairs;
#   - reproduction_multipole/results.json lists the ensemble's cases and holds the three-column
#     comparison (the RPY results.json of docs/reproduction*); nothing else is analysed;
#   - each probe (candycane_epslub_multipole, candycane_order3_multipole) has k_f on every frame
#     (1000 closures) and its own comparison, reproduction_multipole_<probe>/results.json, as a
#     candy-cane sweep of one case.
# The case files are RPY runs (seconds): the analysis does not depend on the model.
# Exit status 77 (ctest: skipped) without the system's numpy/h5py/matplotlib for the tools.
# Usage: check_reproduce_multipole.sh SOURCE_DIR BUILD_DIR WORKDIR
set -uo pipefail
src="$(cd "$1" && pwd)" build="$(cd "$2" && pwd)" work="$3"
fail() { echo "FAIL: $*" >&2; exit 1; }
rm -rf "${work}"
# shellcheck source=tests/jobs/project_copy.sh
source "${src}/tests/jobs/project_copy.sh"
kf_project_copy "${src}" "${build}" "${work}"
mkdir -p "${proj}/docs/reproduction" "${proj}/docs/reproduction_p24"
cp "${src}/docs/reproduction/results.json" "${proj}/docs/reproduction/"
cp "${src}/docs/reproduction_p24/results.json" "${proj}/docs/reproduction_p24/"
cd "${proj}" || fail "no project directory"
scene() {   # scene SWEEP "chain" "sweep line" T_END: written (kf_small_sweep) and run
  kf_small_sweep "$@"
  build/bin/knotflow "inputs/$1.nml" >"${work}/$1.log" 2>&1 || fail "knotflow inputs/$1.nml: $(tail -n 5 "${work}/$1.log")"
}
scene trefoil_table2_multipole "shape = 'trefoil'" "&sweep orientation = 'a', 'c' /" 3.0
scene candycane_seeds_multipole "shape = 'candycane'" "&sweep bending_a = 1.0, 3.0 /" 2.0
scene candycane_multipole "shape = 'candycane'" "&sweep bending_a = 1.0 /" 20.0
scene candycane_epslub_multipole "shape = 'candycane'" "&sweep bending_a = 1.0 /" 2.0
scene candycane_order3_multipole "shape = 'candycane'" "&sweep bending_a = 1.0 /" 3.0

KNOTFLOW_NP=1 KNOTFLOW_NO_INSTALL=1 bash scripts/reproduce.sh --hydro multipole --no-run --no-build \
  >"${work}/reproduce.log" 2>&1 || fail "reproduce.sh --hydro multipole: $(tail -n 15 "${work}/reproduce.log")"

"${proj}/build/venv/bin/python" - results <<'PY' || fail "the stored analysis is not the multipole study's"
import glob, json, os, sys
import h5py
import numpy as np
res = sys.argv[1]
for sweep, n in (("trefoil_table2_multipole", 2), ("candycane_seeds_multipole", 2),
                 ("candycane_epslub_multipole", 1), ("candycane_order3_multipole", 1)):
    files = sorted(glob.glob(os.path.join(res, sweep, "*.h5")))
    assert len(files) == n, (sweep, files)
    for path in files:
        with h5py.File(path, "r") as h:
            nframes = h["frames/time"].shape[0]
            knots = h["analysis/knots"]
            assert int(knots.attrs["closures"]) == 1000, (path, dict(knots.attrs))
            assert np.array_equal(knots["frame_index"][:], np.arange(nframes)), (path, knots["frame_index"][:])
            if sweep.startswith("trefoil"):
                last = h["analysis/knot_matrix"][f"frame_{nframes - 1}"]
                assert int(last.attrs["closures"]) == 100, (path, dict(last.attrs))
print("stored: 1000 closures on every frame of the trefoils, the ensemble and the probes")
(cane,) = glob.glob(os.path.join(res, "candycane_multipole", "*.h5"))
with h5py.File(cane, "r") as h:
    nframes = h["frames/time"].shape[0]
    assert nframes == 21, nframes
    assert int(h["analysis/knots"].attrs["closures"]) == 1000, dict(h["analysis/knots"].attrs)
    assert np.array_equal(h["analysis/knots/frame_index"][:], np.arange(nframes))
    cp = h["frames/observables/close_pairs"][:]
    assert not np.any(cp > 0), cp   # no entangled frames: the matrices are exactly every 10
    mats = h["analysis/knot_matrix"]
    assert sorted(mats) == ["frame_0", "frame_10", "frame_20"], sorted(mats)
    assert all(int(mats[k].attrs["closures"]) == 20 for k in mats), [dict(mats[k].attrs) for k in mats]
print("candy-cane: 1000 closures on every frame, knot matrices at t = 0, 10, 20")
with open(os.path.join(res, "reproduction_multipole", "results.json")) as f:
    out = json.load(f)
assert len(out.get("ensemble", [])) == 2, out.get("ensemble")
cmp = out.get("comparison", {})
assert set(cmp) == {"trefoil", "candycane"}, sorted(cmp)
assert len(cmp["trefoil"]["columns"]) == 3 and len(cmp["candycane"]["columns"]) == 3, cmp
print("results.json: the ensemble's 2 cases and the three-column comparison")
for name, t_end in (("candycane_epslub_multipole", 2.0), ("candycane_order3_multipole", 3.0)):
    with open(os.path.join(res, f"reproduction_multipole_{name}", "results.json")) as f:
        probe = json.load(f)
    assert [c["case"] for c in probe.get("candycane", [])] == ["A1.00"], (name, probe.get("candycane"))
    assert probe["candycane"][0]["t_reached"] == t_end, (name, probe["candycane"][0]["t_reached"])
    assert "ensemble" not in probe and "trefoil" not in probe, (name, sorted(probe))
print("each probe: its own results.json, one candy-cane case")
PY
! grep -qE "results/(trefoil_table2|candycane|candycane_seeds|trefoil_table2_p24)/" "${work}/reproduce.log" \
  || fail "the multipole analysis looked at RPY sweeps: $(grep -E 'results/(trefoil_table2|candycane)' "${work}/reproduce.log" | head -n 3)"
echo "reproduce.sh --hydro multipole: trefoils, the rotations ensemble and the probes with 1000 closures on every frame"
