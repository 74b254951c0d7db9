"""Extreme but legal inputs through the real program (issue 5): A = 0, A = 1e4, N = 2, N = 500,
beads exactly touching (spacing 1.0 = l0), hairpins folded onto themselves (strands 1.0 and 0.5
apart) with rpy and with multipole + lubrication. Each case must either finish (exit 0, status
'finished', every frame finite, the last frame at t_end, bonds within a sane bound) or stop with
exit status 3 and a named reason ('failed: <reason>' in the case file and in summary.json, the
frames written so far finite). Where the file has run diagnostics (diagnostics.* attributes, taken
at every accepted step), their extremes must bound the same quantities computed here from the
frames (a subset of the steps). Never a signal, another exit status, NaN in /frames or a
'finished' case holding garbage.
Usage: check_extreme_inputs.py KNOTFLOW WORKDIR
"""
import json
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

exe, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def write_coords(name, r):
    path = os.path.join(work, name + ".xyz")
    np.savetxt(path, r, fmt="%.17g", header="extreme input " + name)
    return path


def hairpin(n_strand, gap, spacing):
    """Two straight strands of n_strand beads, `gap` apart, joined at one end by a bond of
    length `gap`: bead i and bead 2 n_strand + 1 - i face each other."""
    x = spacing * np.arange(n_strand)
    a = np.c_[x, np.zeros(n_strand), np.zeros(n_strand)]
    b = np.c_[x[::-1], np.full(n_strand, gap), np.zeros(n_strand)]
    return np.vstack([a, b])


# Beads exactly touching: a 3 x 4 x ... lattice walk with unit steps (l0 = 1.0), so bonded beads
# touch and so do many non-bonded ones (exactly 1.0 apart across each fold).
touching = []
for layer in range(2):
    for row in range(3):
        xs = range(5) if (row + layer) % 2 == 0 else range(4, -1, -1)
        for xval in xs:
            touching.append((xval, row if layer == 0 else 2 - row, layer))
touching = np.array(touching, dtype=float)
assert np.allclose(np.linalg.norm(np.diff(touching, axis=0), axis=1), 1.0)

chain_touch = "shape = 'file', coordinate_file = '%s', bond_length = 1.0" % write_coords("touching", touching)
chain_hp10 = "shape = 'file', coordinate_file = '%s'" % write_coords("hairpin10", hairpin(10, 1.0, 1.02))
chain_hp05 = "shape = 'file', coordinate_file = '%s'" % write_coords("hairpin05", hairpin(10, 0.5, 1.02))
mp = "model = 'multipole', order = 2, lubrication = .true."

# name: (chain, forces, hydro, t_end, frame_interval, max bond strain allowed if finished)
cases = {
    "A0": ("shape = 'trefoil'", "bending_a = 0.0", "model = 'rpy'", 2.0, 1.0, 0.2),
    # A = 1e4: the bending force per bead, ~ A theta / l0^2 with bond angles theta up to 0.22,
    # is ~ 2000, above the spring scale k l0 = 510, so O(1) transient strains are physical
    # (0.22 measured at t = 0.1); 1.0 flags a collapsed or doubled bond
    "A1e4": ("shape = 'trefoil'", "bending_a = 1.0e4", "model = 'rpy'", 0.1, 0.05, 1.0),
    "N2": ("shape = 'straight', n_beads = 2, straight_direction = 1, 0, 1", "", "model = 'rpy'",
           5.0, 1.0, 0.2),
    "N500": ("shape = 'random', n_beads = 500", "", "model = 'rpy'", 0.1, 0.05, 0.2),
    "touching_rpy": (chain_touch, "", "model = 'rpy'", 1.0, 0.5, 0.2),
    "touching_mp": (chain_touch, "", mp, 0.5, 0.25, 0.2),
    "hairpin10_rpy": (chain_hp10, "", "model = 'rpy'", 1.0, 0.5, 0.2),
    "hairpin10_mp": (chain_hp10, "", mp, 0.5, 0.25, 0.2),
    # the 0.5 bond at the fold starts at strain 0.5; it relaxes within ~ 3/(2k) = 0.003
    "hairpin05_rpy": (chain_hp05, "", "model = 'rpy'", 1.0, 0.5, 0.2),
    "hairpin05_mp": (chain_hp05, "", mp, 0.5, 0.25, 0.2),
}

failures = []
report = []
for name, (chain, forces, hydro, t_end, fi, strain_max) in cases.items():
    nml = os.path.join(work, name + ".nml")
    with open(nml, "w") as f:
        f.write("&chain %s /\n&forces %s /\n&hydro %s /\n&integrator t_end = %g /\n"
                "&output directory = '%s', case_name = '%s', frame_interval = %g /\n"
                % (chain, forces, hydro, t_end, work, name, fi))
    run = subprocess.run(["env", "OPENBLAS_NUM_THREADS=1", exe, nml], capture_output=True,
                         text=True, timeout=600)
    out = run.stdout + run.stderr
    problems = []
    if run.returncode not in (0, 3):
        problems.append("exit status %d (signal or crash)" % run.returncode)
    h5path = os.path.join(work, name + ".h5")
    status = ""
    if not os.path.exists(h5path):
        problems.append("no case file")
    else:
        with h5py.File(h5path, "r") as h:
            status = h.attrs["status"]
            status = (status.decode() if isinstance(status, bytes) else str(status)).strip()
            pos = h["frames/positions"][:]
            time = h["frames/time"][:]
            l0 = float(h.attrs["chain.bond_length"])
            diag = {k[len("diagnostics."):]: h.attrs[k] for k in h.attrs
                    if k.startswith("diagnostics.")}
        if not np.all(np.isfinite(pos)):
            problems.append("non-finite positions in /frames")
        elif not diag:
            problems.append("no run diagnostics (diagnostics.* attributes) in the case file")
        else:
            # The run diagnostics look at every accepted step, the frames at a subset of them:
            # the step extremes must bound the frame-sampled ones.
            n = pos.shape[1]
            i, j = np.triu_indices(n, 1)
            far = (j - i) > 1
            d = np.linalg.norm(pos[:, i, :] - pos[:, j, :], axis=-1)
            frame_pairs = int((d < 1.0).sum(axis=1).max())
            frame_strain = float((np.abs(np.linalg.norm(np.diff(pos, axis=1), axis=-1) - l0) / l0).max())
            tiny = 1e-9
            if int(diag["max_overlapping_pairs"]) < frame_pairs:
                problems.append("diagnostics.max_overlapping_pairs %d < %d in a frame"
                                % (diag["max_overlapping_pairs"], frame_pairs))
            if far.any() and float(diag["min_distance"]) > d[:, far].min() + tiny:
                problems.append("diagnostics.min_distance %g > %g in a frame"
                                % (diag["min_distance"], d[:, far].min()))
            if float(diag["max_bond_strain"]) < frame_strain - tiny:
                problems.append("diagnostics.max_bond_strain %g < %g in a frame"
                                % (diag["max_bond_strain"], frame_strain))
        if run.returncode == 0:
            if status != "finished":
                problems.append("exit 0 but status %r" % status)
            if abs(time[-1] - t_end) > 1e-9:
                problems.append("last frame at t = %g, not t_end = %g" % (time[-1], t_end))
            strain = np.abs(np.linalg.norm(np.diff(pos[-1], axis=0), axis=1) - l0) / l0
            if strain.max() > strain_max:
                problems.append("finished with bond strain %.3f > %.2f" % (strain.max(), strain_max))
            outcome = "finished t = %g, max bond strain %.2e" % (time[-1], strain.max())
        elif run.returncode == 3:
            reason = status[len("failed:"):].strip() if status.startswith("failed:") else ""
            if not reason:
                problems.append("exit 3 but status %r names no reason" % status)
            with open(os.path.join(work, "summary.json")) as fj:
                summary = json.dumps(json.load(fj))
            if reason and reason[:40] not in summary:
                problems.append("the reason is not in summary.json")
            outcome = "stopped at t = %g: %s" % (time[-1], status)
        else:
            outcome = "exit %d" % run.returncode
    report.append("%-14s %s" % (name, outcome if not problems else "; ".join(problems)))
    if problems:
        failures.append((name, problems, out[-2000:]))

print("\n".join(report))
for name, problems, out in failures:
    print("FAIL %s: %s\n%s" % (name, "; ".join(problems), out))
sys.exit(1 if failures else 0)
