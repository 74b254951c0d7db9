"""Summary table of stress runs (scripts/stress.sh, docs/stability.md).

One row per case file: wall time (from the stress script's wall-time file, when given), accepted
steps and rejections, the time reached, and the run diagnostics the program records
(diagnostics.* root attributes: strand passages, overlap episodes and their mean/maximum
duration, the largest number of overlapping pairs, the smallest non-bonded distance, the largest
bond strain), and the final status. Files written without diagnostics get the geometric columns
from their frames instead (marked "f": sampled at frames, not at every step) and "n/a" for the
step-resolved counters.
"""

from __future__ import annotations

import glob
import os
from typing import Any

import h5py
import numpy as np

from . import io
from .atomic import write_text

COLUMNS = (
    ("case", "case"),
    ("wall_s", "wall [s]"),
    ("steps", "steps"),
    ("rejected", "rejected"),
    ("t", "t reached / t_end"),
    ("strand_passages", "strand passages"),
    ("first_passage_time", "first passage t"),
    ("overlap_episodes", "overlap episodes"),
    ("overlap_mean_duration", "mean overlap duration"),
    ("overlap_max_duration", "max overlap duration"),
    ("max_overlapping_pairs", "max overlapping pairs"),
    ("min_distance", "min distance"),
    ("max_bond_strain", "max bond strain"),
    ("status", "status"),
)


def read_wall_times(path) -> dict:
    """Wall times written by scripts/stress.sh: one 'case seconds' per line ('#' comments)."""
    times = {}
    with open(path) as f:
        for line in f:
            fields = line.split("#", 1)[0].split()
            if len(fields) >= 2:
                times[fields[0]] = float(fields[1])
    return times


def frame_geometry(positions, bond_length):
    """Max overlapping pairs (any i < j closer than 1), min distance over |i - j| > 1 and max
    bond strain |l - l0|/l0, over the frames (nframes, N, 3)."""
    n = positions.shape[1]
    i, j = np.triu_indices(n, 1)
    far = (j - i) > 1
    max_pairs, dmin, strain = 0, np.inf, 0.0
    for r in positions:
        d = np.linalg.norm(r[i] - r[j], axis=1)
        max_pairs = max(max_pairs, int((d < 1.0).sum()))
        if far.any():
            dmin = min(dmin, float(d[far].min()))
        if n > 1:
            bonds = np.linalg.norm(np.diff(r, axis=0), axis=1)
            strain = max(strain, float(np.abs(bonds - bond_length).max() / bond_length))
    return max_pairs, (dmin if np.isfinite(dmin) else None), strain


def summarise_case(path, wall_times=None) -> dict:
    """The row of one case file."""
    case = io.read_case(path)
    a = case.attrs
    name = case.name
    row: dict[str, Any] = {"case": name, "file": str(path), "status": case.status}
    row["wall_s"] = (wall_times or {}).get(name)
    integ = {}
    with h5py.File(path, "r") as h:
        if "frames/integrator" in h:
            for k in ("steps", "rejected"):
                if k in h["frames/integrator"]:
                    v = h["frames/integrator"][k][()]
                    integ[k] = int(v[-1]) if len(v) else 0
    row["steps"] = integ.get("steps")
    row["rejected"] = integ.get("rejected")
    t_end = a.get("integrator.t_end")
    t_last = float(case.time[-1]) if len(case.time) else None
    row["t_reached"] = t_last
    row["t_end"] = float(t_end) if t_end is not None else None
    row["t"] = "%s / %s" % (_fmt(t_last), _fmt(row["t_end"]))
    totals = case.diagnostic_totals
    if totals:
        row["source"] = "steps"
        for k in io.DIAGNOSTIC_TOTALS:
            row[k] = totals.get(k)
    else:
        row["source"] = "frames"
        l0 = float(a.get("chain.bond_length", 1.02))
        pairs, dmin, strain = frame_geometry(case.positions, l0)
        row.update({"strand_passages": None, "first_passage_time": None,
                    "overlap_episodes": None, "overlap_mean_duration": None,
                    "overlap_max_duration": None, "max_overlapping_pairs": pairs,
                    "min_distance": dmin, "max_bond_strain": strain})
    return row


def _fmt(v) -> str:
    if v is None:
        return "n/a"
    if isinstance(v, (bool, np.bool_)):
        return str(v)
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        v = float(v)
        if v == int(v) and abs(v) < 1e9:
            return str(int(v))
        if 1e-3 <= abs(v) < 1e5:
            return "%.4g" % v
        return "%.3e" % v
    return str(v)


def format_table(rows) -> str:
    """Markdown table of the rows (frame-sampled values marked "f")."""
    geometric = ("max_overlapping_pairs", "min_distance", "max_bond_strain")
    lines = ["| " + " | ".join(title for _, title in COLUMNS) + " |",
             "|" + "---|" * len(COLUMNS)]
    for row in rows:
        cells = []
        for key, _ in COLUMNS:
            text = _fmt(row.get(key))
            if key == "first_passage_time" and row.get(key) is not None and row[key] < 0:
                text = "none"
            if row.get("source") == "frames" and key in geometric and text != "n/a":
                text += " f"
            cells.append(text.replace("|", "/"))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def case_files(inputs) -> list:
    """Case files named, or found (*.h5) in the directories named, sorted by name."""
    files = []
    for item in inputs:
        if os.path.isdir(item):
            files.extend(sorted(glob.glob(os.path.join(item, "*.h5"))))
        else:
            files.append(item)
    return files


def write_summary(path, title, table) -> None:
    """The table of format_table with a heading and a note on its columns, into path."""
    note = ("Values marked f are sampled at frames (the file has no run diagnostics); "
            "durations in time units 1/shear rate; strain |l - l0|/l0; overlapping pairs: "
            "any i < j closer than d = 1; min distance over |i - j| > 1.\n")
    write_text(path, "# %s\n\n%s\n%s" % (title, table, note))
