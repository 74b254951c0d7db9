"""The reference study side by side with our runs: trefoil Table 2 and candy-cane modes/slipknots.

`knotflow-study --trefoil DIR --candycane DIR [--ensemble DIR] --out DIR` reads the case files of
the sweeps (inputs/trefoil_table2*.nml, inputs/candycane*.nml) after `knotflow-analyze` has
filled their /analysis groups, and writes into --out figures, `results.md` (the tables quoted in
docs/REPRODUCTION.md), `results.json` and two small per-frame CSV files:
`trefoil_kf.csv` (case, t, k_f: one row per case and frame with k_f) and `candycane_shape.csv`
(case, t, R_g, a, b, c, theta, phi, close_pairs, k_f; k_f empty on frames without it).
Nothing is recomputed that /analysis already holds; k_f is computed here only for files without
/analysis/knots.

Every trefoil table counts the re-knottings (knot events after an untying) per case and in
total, against the study's 13 in 4 of 29 simulations. Per sweep, results.md has the overlap
statistics, headed by the overlap rule each case ran with (run diagnostics), and the run
records (/runs: commit, wall time, load) of every case. A sweep may be running: cases not
'finished' are included, marked with their status and the time reached, and the tables say how
many cases are finished.

`--samples DIR ...` (perturbed Table 2 samples) adds Table 2 as probabilities with exact 95 %
intervals and the scores of the study's table and of 'never'; `--rotations DIR ...` (candy-canes
from many starts) adds the per-A fractions in modes I and II with intervals, the late shape
distributions and the close-pair ratio A = 1 / A = 3 per `--window` (study_statistics);
with `--same-starts DIR ...` (the same starts run with another model) both models side by side,
start by start.

`--rpy-trefoil JSON` and `--rpy-candycane JSON` take the results.json of an earlier
knotflow-study run with RPY + excluded volume (its "trefoil" part, resp. its "candycane" and
"ensemble" parts); results.md then has three-column tables (the study, this run's directories
= knotflow multipole, knotflow RPY + EV) and results.json a "comparison" part.

`--select-frames CASE` prints the frames for the knot-matrix screen of CASE (every 50th frame,
or with `--every-time T` the frames at the multiples of T time units, plus the last frame and
the 5 frames with the most close pairs).

The parts: `study_rows` reads the cases into rows, `study_slipknots` holds the slipknot search,
`study_compare` the three-column comparison and `study_reference` the study's numbers; this
module writes the figures, tables and files.

Slipknots: the candidates of that screen are recomputed and checked by scripts/reproduce.sh
(files in <out>/confirm: `study_slipknots.confirm_path`); the rule that confirms one is
`study_slipknots.confirmation_verdict` (docs/analysis.md, "Slipknot confirmation"), and
`candycane_slipknots.png` shows the confirmed frames or, without one, the frame that went
furthest, labelled not confirmed. A sweep directory without case files is named in results.md
("no case files in DIR") and skipped.
"""

from __future__ import annotations

import decimal
import json
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from . import study_statistics  # noqa: E402
from .atomic import save_figure, write_text  # noqa: E402
from .campaign import find_ledger_cases, load_case, sample_start  # noqa: E402
from .io import find_case_files, write_xyz  # noqa: E402
from .plot import _draw_chain  # noqa: E402
from .study_compare import candycane_comparison, trefoil_comparison  # noqa: E402
from .study_reference import STUDY_REKNOT_EVENTS, STUDY_REKNOT_SIMULATIONS, STUDY_TREFOIL_CASES  # noqa: E402
from .study_rows import (  # noqa: E402
    agreement_text,
    agrees,
    candycane_rows,
    close_pair_ratio,
    finished,
    finished_line,
    fmt,
    reknot_totals,
    reknottings,
    status_text,
    trefoil_rows,
    utk,
)
from .study_slipknots import SLIPKNOT_FIGURE, load_json, plot_slipknots, slipknot_caption, slipknot_tables  # noqa: E402

ENSEMBLE_KF_FIGURE = "candycane_ensemble_kf.png"


def time_frames(time, every_time):
    """Frames of the time axis `time` (increasing) at the multiples of `every_time` (> 0) in
    [time[0], time[-1]]: the frame nearest to each multiple, each frame once."""
    if not every_time > 0:
        raise ValueError(f"--every-time {every_time:g} is not allowed (a positive number)")
    t = np.asarray(time, dtype=float)
    first, last = math.ceil(t[0] / every_time - 1e-9), math.floor(t[-1] / every_time + 1e-9)
    marks = np.arange(first, last + 1) * every_time
    return sorted({int(np.argmin(np.abs(t - m))) for m in marks})


def entangled_frames(path, every=50, extra=5, gap=20, every_time=None):
    """Frames for knot matrices: every `every`-th frame (or with `every_time` the frames at the
    multiples of `every_time` time units, `time_frames`) and the last one, plus the `extra`
    frames with the most close pairs, at least `gap` frames from each other."""
    case = load_case(path)
    cp = np.asarray(case.observables.get("close_pairs", np.zeros(case.nframes)))
    sel = (list(range(0, case.nframes, every)) if every_time is None
           else time_frames(case.time, every_time))
    if case.nframes and sel[-1] != case.nframes - 1:
        sel.append(case.nframes - 1)
    # A ledger keeps the positions of some frames only: the others cannot be chosen.
    kept = np.isfinite(case.positions[:, 0, 0])
    sel = [k for k in sel if kept[k]]
    chosen = []
    for k in np.argsort(-cp, kind="stable"):
        if len(chosen) >= extra or cp[k] <= 0:
            break
        if kept[k] and all(abs(int(k) - c) >= gap for c in chosen) and int(k) not in sel:
            chosen.append(int(k))
    return sorted(sel + chosen)


# ------------------------------------------------------------------------------------------ figures

def plot_trefoil_grid(rows, path):
    a_vals = sorted({r["A"] for r in rows})
    o_vals = sorted({r["orientation"] for r in rows})
    fig, axes = plt.subplots(len(a_vals), len(o_vals), figsize=(2.6 * len(o_vals), 1.5 * len(a_vals)),
                             sharex=True, sharey=True, constrained_layout=True, squeeze=False)
    for ax in axes.flat:
        ax.set_axis_off()
    for r in rows:
        ax = axes[a_vals.index(r["A"]), o_vals.index(r["orientation"])]
        ax.set_axis_on()
        ax.axhspan(0.1, 0.9, color="0.93", zorder=0)
        ax.plot(r["time"], r["kf"], color="k", lw=0.7)
        for kind, t in r["events"]:
            ax.axvline(t, color="tab:red" if kind == "unknot" else "tab:green", lw=0.9, ls="--")
        mark = " [study: U->K]" if r["study_transition"] else ""
        if not finished(r):
            mark += f" [{r['status']}, t = {r['t_reached']:g}]"
        col = "tab:red" if r["unknot_then_knot"] != r["study_transition"] else "k"
        ax.set_title(f"A={r['A']:g} {r['orientation']}{mark}", fontsize=8, color=col)
        ax.set_ylim(-0.05, 1.05)
        ax.tick_params(labelsize=7)
    for ax in axes[-1, :]:
        ax.set_xlabel("t", fontsize=8)
    fig.suptitle("Open trefoils, N = 99: k_f(t) (dashed: red unknot, green knot events; "
                 "red title: differs from the study; a case not finished shows its status and "
                 "the time reached)", fontsize=9)
    save_figure(fig, path, dpi=100)
    plt.close(fig)
    return path


def plot_candycane_shapes(rows, path):
    panels = [("rg", "$R_g$"), ("a", "a"), ("b", "b"), ("c", "c"), ("theta", r"$\theta$"),
              ("phi", r"$\varphi$"), ("close_pairs", "close pairs")]
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 12), sharex=True, constrained_layout=True)
    for r in rows:
        o = r["_ana"].observables
        t = r["_case"].time
        for ax, (k, lab) in zip(axes, panels):
            ax.plot(t, o[k], lw=0.8, label=f"A = {r['A']:g}")
            ax.set_ylabel(lab)
    axes[0].legend(fontsize=8, ncol=len(rows))
    axes[-1].set_xlabel(r"time $\dot\gamma t$")
    fig.suptitle("Candy-cane, N = 152: shape (as Fig. 2b of the study)", fontsize=10)
    save_figure(fig, path, dpi=100)
    plt.close(fig)
    return path


def _draw_kf(ax, series, legend_size):
    """Whole-chain k_f(t) of each (label, time, k_f) of `series` on the axes `ax`."""
    for label, t, kf in series:
        ax.plot(t, kf, lw=0.8, label=label)
    ax.set_ylim(-0.03, 1.03)
    ax.set_ylabel("$k_f$ (whole chain)")
    ax.legend(fontsize=legend_size)


def plot_candycane_kf(rows, path):
    fig, ax = plt.subplots(figsize=(9, 3), constrained_layout=True)
    _draw_kf(ax, [(f"A = {r['A']:g}", r["_ana"].time, r["_ana"].kf) for r in rows], 8)
    ax.set_xlabel(r"time $\dot\gamma t$")
    save_figure(fig, path, dpi=100)
    plt.close(fig)
    return path


def ensemble_kf_series(rows, ensemble):
    """Per bending stiffness A of the rotations `ensemble` (ascending): (label, time, k_f) of
    the candy-cane sweep's case of that A in `rows` (labelled as the seeded rotation) and then
    of each rotation, in their order; a case not finished says so in its label. An A of `rows`
    without rotations has no panel."""
    def series(r, what=""):
        notes = [n for n in (what, "" if finished(r) else status_text(r)) if n]
        label = f"{r['case']} ({', '.join(notes)})" if notes else r["case"]
        return label, r["_ana"].time, r["_ana"].kf

    panels = {}
    for a in sorted({r["A"] for r in ensemble}):
        panels[a] = ([series(r, "seeded rotation") for r in rows if r["A"] == a]
                     + [series(r) for r in ensemble if r["A"] == a])
    return panels


def plot_ensemble_kf(rows, ensemble, path):
    """candycane_ensemble_kf.png: whole-chain k_f(t) of every rotation, one panel per A."""
    panels = ensemble_kf_series(rows, ensemble)
    if not panels:
        return None
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.6 * len(panels)), sharex=True,
                             squeeze=False, constrained_layout=True)
    for ax, (a, series) in zip(axes[:, 0], panels.items()):
        _draw_kf(ax, series, 7)
        ax.set_title(f"Candy-cane A = {a:g}: the random rotations", fontsize=9)
    axes[-1, 0].set_xlabel(r"time $\dot\gamma t$")
    save_figure(fig, path, dpi=100)
    plt.close(fig)
    return path


def plot_candycane_snapshots(rows, path, times=(0, 250, 500, 1000, 2000)):
    fig = plt.figure(figsize=(3 * len(times), 3 * len(rows)), constrained_layout=True)
    for i, r in enumerate(rows):
        case = r["_case"]
        for j, t in enumerate(times):
            k = int(np.argmin(np.abs(case.time - t)))
            ax = fig.add_subplot(len(rows), len(times), i * len(times) + j + 1, projection="3d")
            _draw_chain(ax, case.positions[k])
            ax.set_title(f"A = {r['A']:g}, t = {case.time[k]:g}", fontsize=9)
    save_figure(fig, path, dpi=90)
    plt.close(fig)
    return path


def plot_matrices(rows, path, per_case=3):
    """The knot matrices with the largest subchain K of each case."""
    chosen = []
    for r in rows:
        ms = sorted(r["matrices"], key=lambda m: -m["max_K"])[:per_case]
        chosen += [(r, m) for m in ms]
    if not chosen:
        return None
    ncol = per_case
    nrow = math.ceil(len(chosen) / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.4 * ncol, 3.2 * nrow), constrained_layout=True,
                             squeeze=False)
    for ax in axes.flat:
        ax.set_axis_off()
    for ax, (r, m) in zip(axes.flat, chosen):
        ax.set_axis_on()
        mat = r["_case"].knot_matrices[m["frame"]]
        im = ax.imshow(np.where(np.isfinite(mat), mat, np.nan).T, origin="lower", vmin=0, vmax=1,
                       cmap="viridis")
        ax.set_title(f"A = {r['A']:g}, t = {m['time']:g}\nwhole k_f = {m['whole_kf']:.2f}, "
                     f"max K = {m['max_K']:.2f}", fontsize=8)
        ax.set_xlabel("i", fontsize=8)
        ax.set_ylabel("j", fontsize=8)
    fig.colorbar(im, ax=axes, shrink=0.6, label="K(i, j)")
    save_figure(fig, path, dpi=100)
    plt.close(fig)
    return path


# ------------------------------------------------------------------------------------------- tables

def _star(row) -> str:
    """'*' after a case that has not finished (its result may still change)."""
    return "" if finished(row) else "*"


def _reknot_line(tot) -> str:
    return (f"Unknot-then-knot events (re-knottings: knot events after an untying): "
            f"{tot['events']} in {tot['simulations']} of {tot['cases']} simulations (the study: "
            f"{STUDY_REKNOT_EVENTS} in {STUDY_REKNOT_SIMULATIONS} of {STUDY_TREFOIL_CASES}).")


def trefoil_tables(rows):
    a_vals = sorted({r["A"] for r in rows})
    o_vals = sorted({r["orientation"] for r in rows})
    by = {(r["A"], r["orientation"]): r for r in rows}
    out = ["### Unknot-then-knot transitions, ours vs the study (Table 2)", "",
           finished_line(rows, STUDY_TREFOIL_CASES), "",
           "Cell: ours / study; `U->K` an unknot-then-knot transition, `-` none; "
           "**bold** where they differ. Every case starts as an open trefoil (knotted); an "
           "untying is k_f falling below 0.1, a re-knotting k_f rising above 0.9 afterwards.", "",
           "| A | " + " | ".join(o_vals) + " |", "|---|" + "---|" * len(o_vals)]
    for a in a_vals:
        cells = []
        for o in o_vals:
            r = by.get((a, o))
            if r is None:
                cells.append(" ")
                continue
            ours = utk(r)
            study = "U->K" if r["study_transition"] else "-"
            cell = f"{ours}{_star(r)} / {study}"
            cells.append(cell if ours == study else f"**{cell}**")
        out.append(f"| {a:g} | " + " | ".join(cells) + " |")
    out += ["", f"Agreement: {agreement_text(rows)}.", "", _reknot_line(reknot_totals(rows)), "",
            "### Every trefoil case", "",
            "| case | status | k_f(0) | events (time) | re-knottings | final k_f | final state | "
            "mode | study U->K |",
            "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ev = ", ".join(f"{k} {t:g}" for k, t in r["events"]) or "none"
        out.append(f"| {r['case']} | {status_text(r)} | {r['kf0']:.2f} | {ev} | "
                   f"{reknottings(r['events'])} | {r['final_kf']:.2f} | {r['final_state']} | "
                   f"{r['mode']} | {'yes' if r['study_transition'] else 'no'} |")
    return out, sum(agrees(r) for r in rows), len(rows)


def min_distance_text(d) -> str:
    """A smallest distance rounded down to 5 decimals, so that an overlap (below d = 1) never
    prints as 1; '-' when not recorded (None or negative)."""
    if d is None or d < 0:
        return "-"
    return str(decimal.Decimal(repr(d)).quantize(decimal.Decimal("1e-5"), rounding=decimal.ROUND_FLOOR))


def overlap_heading(rows) -> str:
    """The heading of the overlap statistics, naming the overlap rule(s) the cases ran with by
    their scene names (only 'bwe' is the study's BWE rule)."""
    rules = sorted({r.get("overlap_rule") for r in rows} - {None})
    without = any(r.get("overlap_rule") is None for r in rows)
    parts = [f"overlap = '{x}'" for x in rules] + (["a model without an overlap rule"] if without else [])
    return "#### Overlap statistics (" + "; ".join(parts) + ")"


def overlap_table(rows) -> list:
    """Overlap statistics of every case (the run diagnostics' totals); the min distance
    rounded down (min_distance_text)."""
    out = ["| case | status | overlap episodes | mean duration | max duration | "
           "max overlapping pairs | min distance | strand passages |",
           "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        d = r["overlap"]
        if d is None:
            out.append(f"| {r['case']} | {status_text(r)} | not recorded | | | | | |")
            continue
        out.append(f"| {r['case']} | {status_text(r)} | {d.get('overlap_episodes', '-')} | "
                   f"{fmt(d.get('overlap_mean_duration'), '.2f')} | "
                   f"{fmt(d.get('overlap_max_duration'), '.2f')} | "
                   f"{d.get('max_overlapping_pairs', '-')} | {min_distance_text(d.get('min_distance'))} | "
                   f"{d.get('strand_passages', '-')} |")
    if any(r["overlap"] and r["overlap"]["source"] == "checkpoint" for r in rows):
        out += ["", "A case not finished: its totals from the state in its newest checkpoint "
                "(the frames read)."]
    return out


def _hours(seconds, unknown=0) -> str:
    return f"{seconds / 3600:.2f} h" + (f" (+ {unknown} segment(s) not recorded)" if unknown else "")


def _blas_text(summary) -> str:
    """The BLAS kernels of a case's runs_summary, and how many segments did not record them."""
    known = ", ".join(summary.get("blas", []))
    unknown = summary.get("blas_unknown", 0)
    if not unknown:
        return known
    missing = f"{unknown} segment(s) not recorded"
    return f"{known} (+ {missing})" if known else missing


def runs_table(rows) -> list:
    """Run records of every case (commit, BLAS kernels, wall time, time-weighted mean load,
    segments) and the sum over the cases with records."""
    out = ["| case | status | commit(s) | BLAS | total wall time | mean load (time-weighted) | "
           "segments |",
           "|---|---|---|---|---|---|---|"]
    recorded = [r["runs"] for r in rows if r["runs"] is not None]
    for r in rows:
        s = r["runs"]
        if s is None:
            out.append(f"| {r['case']} | {status_text(r)} | not recorded | | | | |")
            continue
        out.append(f"| {r['case']} | {status_text(r)} | {', '.join(s['commits'])} | "
                   f"{_blas_text(s)} | {_hours(s['wall_seconds'], s['wall_unknown'])} | "
                   f"{fmt(s['mean_load'], '.2f')} | "
                   f"{s['segments']} |")
    if recorded:
        weight = sum(s["load_seconds"] for s in recorded)
        load = (sum(s["mean_load"] * s["load_seconds"] for s in recorded if s["mean_load"] is not None)
                / weight) if weight > 0 else None
        wall = _hours(sum(s["wall_seconds"] for s in recorded),
                      sum(s["wall_unknown"] for s in recorded))
        out.append(f"| all ({len(recorded)} of {len(rows)} cases recorded) | | | | {wall} | "
                   f"{fmt(load, '.2f')} | "
                   f"{sum(s['segments'] for s in recorded)} |")
    return out


def sweep_records(rows) -> list:
    """The overlap statistics and run records sections of a sweep."""
    return ([overlap_heading(rows), ""] + overlap_table(rows)
            + ["", "#### Runs", ""] + runs_table(rows) + [""])


def candycane_tables(rows):
    out = ["### Candy-cane cases (late = second half of the frames read)", "",
           finished_line(rows), "",
           "| A | status | close pairs (mean, all t) | close pairs (late) | R_g (late) | "
           "a, b, c (late) | mean abs cos theta (late) | frames in mode I / II (late) | "
           "case mode | max k_f | mean k_f |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(
            f"| {r['A']:g} | {status_text(r)} | {r['close_pairs_mean']:.2f} | "
            f"{r['close_pairs_late']:.2f} | "
            f"{r['rg_late']:.2f} | {r['a_late']:.1f}, {r['b_late']:.1f}, {r['c_late']:.1f} | "
            f"{r['abs_cos_theta_late']:.2f} | {fmt(r['mode_I_late'])} / {fmt(r['mode_II_late'])} | "
            f"{r['case_mode']} | {r['max_kf']:.3f} | {r['mean_kf']:.4f} |")
    ratio, ratio_late = close_pair_ratio(rows), close_pair_ratio(rows, "close_pairs_late")
    if ratio is not None:
        out += ["", f"Close pairs A = 1 / A = 3: {ratio:.1f} (whole run), "
                f"{fmt(ratio_late, '.1f')} (late)."]
    return out + [""] + slipknot_tables(rows)


def ensemble_tables(rows):
    """Candy-canes with several random rotations: every case, then mean and range per A."""
    out = ["### Candy-cane ensemble (several random rotations; late = second half of the run)", "",
           finished_line(rows), "",
           "| case | status | close pairs (all t) | close pairs (late) | R_g (late) | c (late) | "
           "mean abs cos theta (late) | mode I / II frames (late) | max k_f |",
           "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['case']} | {status_text(r)} | {r['close_pairs_mean']:.2f} | "
                   f"{r['close_pairs_late']:.2f} | "
                   f"{r['rg_late']:.1f} | {r['c_late']:.2f} | {r['abs_cos_theta_late']:.2f} | "
                   f"{fmt(r['mode_I_late'])} / {fmt(r['mode_II_late'])} | {r['max_kf']:.2f} |")
    out += ["", "| A | cases | close pairs, all t: mean (min-max) | mean abs cos theta, late: mean "
            "(min-max) | cases with theta mostly along vorticity (late mean abs cos > 0.7) |",
            "|---|---|---|---|---|"]
    for a in sorted({r["A"] for r in rows}):
        g = [r for r in rows if r["A"] == a]
        cp = [r["close_pairs_mean"] for r in g]
        ct = [r["abs_cos_theta_late"] for r in g]
        out.append(f"| {a:g} | {len(g)} | {np.mean(cp):.2f} ({min(cp):.2f}-{max(cp):.2f}) | "
                   f"{np.mean(ct):.2f} ({min(ct):.2f}-{max(ct):.2f}) | "
                   f"{sum(c > 0.7 for c in ct)} of {len(g)} |")
    return out


# ------------------------------------------------------------------------ per-frame CSV files

def write_trefoil_csv(rows, path):
    """trefoil_kf.csv: case, t, k_f (one line per case and frame with k_f)."""
    lines = ["case,t,k_f\n"]
    for r in rows:
        for t, k in zip(r["time"], r["kf"]):
            lines.append(f"{r['case']},{t:.6g},{k:.4g}\n")
    write_text(path, "".join(lines))
    return path


CANDYCANE_CSV = ("rg", "a", "b", "c", "theta", "phi", "close_pairs")


def write_candycane_csv(rows, path):
    """candycane_shape.csv: case, t, R_g, a, b, c, theta, phi, close_pairs, k_f (one line per
    case and frame; k_f empty on a frame without it)."""
    lines = ["case,t,R_g,a,b,c,theta,phi,close_pairs,k_f\n"]
    for r in rows:
        case, ana = r["_case"], r["_ana"]
        kf = dict(zip((int(k) for k in ana.frame_index), ana.kf))
        o = ana.observables
        for k, t in enumerate(case.time):
            vals = ",".join(f"{float(o[name][k]):.6g}" for name in CANDYCANE_CSV)
            kk = f"{kf[k]:.4g}" if k in kf else ""
            lines.append(f"{r['case']},{t:.6g},{vals},{kk}\n")
    write_text(path, "".join(lines))
    return path


def _public(rows, drop=("time", "kf")):
    return [{k: v for k, v in r.items() if not k.startswith("_") and k not in drop} for r in rows]


def no_case_files(directory) -> str:
    """The line of results.md for a sweep directory without case files."""
    return f"no case files in {directory}"


def write_study(trefoil_dir, candycane_dir, out, closures=200, ensemble_dir=None,
                rpy_trefoil=None, rpy_candycane=None, ledger_matrices=None, samples_dirs=None,
                rotation_dirs=None, window=250.0, same_starts=None, scene_defaults=None):
    """Write figures, results.md, results.json and the per-frame CSV files into `out`.
    rpy_trefoil, rpy_candycane: `load_rpy` of earlier RPY + EV results (or None): three-column
    comparison tables and a "comparison" part in results.json. A sweep directory without case
    files gets the line `no_case_files` in its section (and in results.json under "missing")
    and nothing else. ledger_matrices: the knot matrices of the cases of a case ledger
    (campaign.ledger_case). samples_dirs: sweeps of perturbed Table 2 samples, rotation_dirs:
    sweeps of candy-canes from many starts (study_statistics; `window` the width of the
    close-pair ratio's time windows; `same_starts`: sweeps of the same starts with another
    model, compared start by start; `scene_defaults`: campaign.scene_defaults, for the samples'
    integration paths)."""
    confirm_dir = os.path.join(out, "confirm")
    os.makedirs(out, exist_ok=True)
    md = ["# knotflow-study: generated results", ""]
    if trefoil_dir or candycane_dir:
        md += [f"Trefoil sweep: `{trefoil_dir}`; candy-cane sweep: `{candycane_dir}`.", ""]
    result = {}
    comparison = {}
    cane_rows = []  # the candy-cane sweep's rows, beside the rotations in their k_f figure
    # A directory of case files, or one sweep of a case ledger (campaign.py).
    files = {d: find_case_files(d) or find_ledger_cases(d)
             for d in (trefoil_dir, candycane_dir, ensemble_dir) if d}
    missing = [d for d, f in files.items() if not f]
    if missing:
        result["missing"] = [no_case_files(d) for d in missing]
    ensemble = candycane_rows(files[ensemble_dir], closures) if ensemble_dir else []
    if trefoil_dir and not files[trefoil_dir]:
        md += ["## Trefoils (Table 2)", "", no_case_files(trefoil_dir), ""]
    elif trefoil_dir:
        rows = trefoil_rows(files[trefoil_dir], closures)
        plot_trefoil_grid(rows, os.path.join(out, "trefoil_kf_grid.png"))
        write_trefoil_csv(rows, os.path.join(out, "trefoil_kf.csv"))
        lines, agree, total = trefoil_tables(rows)
        md += ["## Trefoils (Table 2)", "", "![k_f(t) of every case](trefoil_kf_grid.png)", ""] + lines + [""]
        if rpy_trefoil is not None:
            lines, comparison["trefoil"] = trefoil_comparison(rows, rpy_trefoil["trefoil"])
            md += lines + [""]
        md += sweep_records(rows)
        result["trefoil"] = {"agree": agree, "total": total, "agreement": agreement_text(rows),
                             "reknottings": reknot_totals(rows),
                             "cases": _public(rows)}
    if candycane_dir and not files[candycane_dir]:
        md += ["## Candy-cane", "", no_case_files(candycane_dir), ""]
    elif candycane_dir:
        rows = cane_rows = candycane_rows(files[candycane_dir], closures, confirm_dir,
                                          ledger_matrices)
        figs = [plot_candycane_shapes(rows, os.path.join(out, "candycane_shape.png")),
                plot_candycane_kf(rows, os.path.join(out, "candycane_kf.png")),
                plot_candycane_snapshots(rows, os.path.join(out, "candycane_snapshots.png")),
                plot_matrices(rows, os.path.join(out, "candycane_knot_matrices.png"))]
        write_candycane_csv(rows, os.path.join(out, "candycane_shape.csv"))
        md += ["## Candy-cane", ""]
        md += [f"![{os.path.basename(f)}]({os.path.basename(f)})" for f in figs if f] + [""]
        md += candycane_tables(rows) + [""]
        slip = plot_slipknots(rows, os.path.join(out, SLIPKNOT_FIGURE), confirm_dir)
        if slip:
            md += [f"![{SLIPKNOT_FIGURE}]({SLIPKNOT_FIGURE})", "",
                   f"`{SLIPKNOT_FIGURE}`: " + slipknot_caption(rows), ""]
        if rpy_candycane is not None:
            lines, comparison["candycane"] = candycane_comparison(rows, ensemble, rpy_candycane)
            md += lines + [""]
        md += sweep_records(rows)
        result["candycane"] = _public(rows)
    if ensemble_dir and not files[ensemble_dir]:
        md += ["## Candy-cane ensemble", "", no_case_files(ensemble_dir), ""]
    elif ensemble_dir:
        md += ["## Candy-cane ensemble", ""]
        fig = plot_ensemble_kf(cane_rows, ensemble, os.path.join(out, ENSEMBLE_KF_FIGURE))
        if fig:
            md += [f"![{ENSEMBLE_KF_FIGURE}]({ENSEMBLE_KF_FIGURE})", ""]
        md += ensemble_tables(ensemble) + [""]
        md += sweep_records(ensemble)
        result["ensemble"] = _public(ensemble)
    if samples_dirs:
        lines, result["samples"] = samples_section(samples_dirs, closures, scene_defaults)
        md += lines
    if rotation_dirs:
        lines, result["rotations"] = rotations_section(rotation_dirs, closures, window,
                                                       same_starts)
        md += lines
    if comparison:
        result["comparison"] = comparison
    write_text(os.path.join(out, "results.md"), "\n".join(md) + "\n")
    write_text(os.path.join(out, "results.json"), json.dumps(result, indent=1))
    return result


def _sweep_files(dirs) -> list:
    """Case files or ledger entries of several sweep directories."""
    return [f for d in dirs for f in (find_case_files(d) or find_ledger_cases(d))]


def _probabilities(rows):
    """Table 2 as probabilities over `rows`: per-cell probabilities, the scores and the table."""
    cells = study_statistics.cell_probabilities(rows)
    scores = study_statistics.table2_scores(cells)
    return cells, scores, study_statistics.probability_table(cells, scores) + [""]


def samples_section(dirs, closures=200, defaults=None):
    """Markdown and the results.json part of Table 2 as probabilities (study_statistics); when
    the samples ran on more than one integration path (campaign.integration_path, `defaults`
    for scenes written before a variable existed), the table is pooled over them and repeated
    for each path ("by_path"); when some were continued from the case ledger
    (campaign.continued_at), it is repeated without them ("uninterrupted"); then every
    sample's events, one line each ("per_sample", study_statistics.sample_events)."""
    rows = trefoil_rows(_sweep_files(dirs), closures, defaults)
    cells, scores, table = _probabilities(rows)
    paths: dict = {}
    for r in rows:
        paths.setdefault(r["path"], []).append(r)
    lines = ["## Table 2 as probabilities", "", f"Sweeps: {', '.join(f'`{d}`' for d in dirs)}.",
             "", finished_line(rows), ""]
    if len(paths) > 1:
        lines += [f"The samples ran on {len(paths)} integration paths (below, each apart); this "
                  "table pools them.", ""]
    lines += table
    part = {"cells": cells, "scores": scores, "level": study_statistics.LEVEL}
    if len(paths) > 1:
        part["by_path"] = []
        lines += ["### By integration path", ""]
        for path, group in sorted(paths.items(), key=lambda kv: str(kv[0])):
            c, sc, table = _probabilities(group)
            lines += [f"#### {path or 'no scene text'}", "", finished_line(group), ""] + table
            part["by_path"].append({"path": path, "cells": c, "scores": sc})
    continued = [r for r in rows if r["continued_at"]]
    if continued:
        whole = [r for r in rows if not r["continued_at"]]
        c, sc, table = _probabilities(whole)
        names = ", ".join(f"{r['case']} (t = {', '.join(f'{t:g}' for t in r['continued_at'])})"
                          for r in continued)
        lines += ["### Without the samples continued from the case ledger", "",
                  f"{len(continued)} of the samples were continued from the case ledger on "
                  f"another machine: {names}. A continuation starts its stepper afresh from the "
                  "ledger's frame (without the step-size history), a disturbance at the level of "
                  "the integration tolerance at that time, larger than the samples' start "
                  "perturbation; so the table above pools two kinds of sample, and this one "
                  "holds only the samples run in one piece (or resumed from their own "
                  "checkpoints, which keep the stepper's state; an iterative solver's warm start "
                  "begins afresh there, a difference within its tolerance).", "",
                  finished_line(whole), ""] + table
        part["uninterrupted"] = {"continued": [{"case": r["case"], "at": r["continued_at"]}
                                               for r in continued],
                                 "cells": c, "scores": sc}
    part["per_sample"] = study_statistics.sample_events(rows)
    lines += ["### Each sample", ""] + study_statistics.sample_table(part["per_sample"]) + [""]
    lines += sweep_records(rows)
    return lines, part


def _start(row):
    """The start of a candy-cane row (campaign.sample_start of its scene; the case alone
    without a scene text)."""
    scene = row["_case"].attrs.get("scene")
    if not isinstance(scene, str) or not scene:
        return ("case", row["case"])
    return sample_start(scene)


def rotations_section(dirs, closures=200, window=250.0, same_starts=None):
    """Markdown and the results.json part of the candy-canes from many starts per A; with
    `same_starts` (sweeps of the same starts run with another model) also both models side by
    side per start (study_statistics.paired_starts)."""
    rows = candycane_rows(_sweep_files(dirs), closures)
    stats = study_statistics.mode_statistics(rows)
    windows = study_statistics.close_pair_ratio_windows(rows, window)
    lines = ["## Candy-canes from many starts, per bending stiffness", "",
             f"Sweeps: {', '.join(f'`{d}`' for d in dirs)}.", "", finished_line(rows), "",
             f"Late = second half of each run. Intervals: exact for fractions of cases, "
             f"percentile bootstrap over cases ({study_statistics.BOOTSTRAP_SAMPLES} resamples, "
             f"seed {study_statistics.BOOTSTRAP_SEED}) for fractions of frames.", ""]
    lines += study_statistics.mode_table(stats) + [""]
    if windows:
        lines += [f"Close-pair ratio A = 1 / A = 3 per window of {window:g} time units (mean over "
                  "the cases of each A):", ""] + study_statistics.ratio_table(windows) + [""]
    part = {"per_A": stats, "close_pair_windows": windows,
            "bootstrap": {"samples": study_statistics.BOOTSTRAP_SAMPLES,
                          "seed": study_statistics.BOOTSTRAP_SEED}}
    if same_starts:
        from .rheology import models_text
        other = candycane_rows(_sweep_files(same_starts), closures)
        paired = study_statistics.paired_starts(rows, other, _start)
        lines += ["### The same starts with another model", "",
                  f"Other sweeps: {', '.join(f'`{d}`' for d in same_starts)}. Starts matched by "
                  "the chain, its stiffness, the flow and the seed where it draws the start "
                  "(campaign.sample_start); finished cases only.", ""]
        lines += study_statistics.paired_table(
            paired, models_text([r["_case"] for r in rows]),
            models_text([r["_case"] for r in other])) + [""]
        part["same_starts"] = {"sweeps": list(same_starts),
                               **{k: v for k, v in paired.items() if k != "pairs"},
                               "pairs": [{**p, "start": str(p["start"])} for p in paired["pairs"]]}
    lines += sweep_records(rows)
    return lines, part


def write_frame(path, frame, xyz, core_of=None) -> None:
    """Frame `frame` of case file `path` as a coordinate file `xyz` (knotflow-study
    --write-frame); with `core_of` (a knotflow-analyze --matrix --json file of that frame) only
    the beads i..j of its knot core."""
    case = load_case(path)
    r = case.positions[frame]
    if not np.all(np.isfinite(r)):
        raise ValueError(f"{path}: frame {frame} (t = {case.time[frame]:g}) is not kept in the "
                         "case ledger (its positions_every and the newest frame are)")
    comment = f"{case.name} frame {frame} t = {case.time[frame]:g}"
    if core_of is not None:
        core = load_json(core_of).get("knot_core")
        if not core:
            raise ValueError(f"{core_of}: no knot core (knot_core is null)")
        i, j = int(core[0]), int(core[1])
        if not 0 <= i < j < len(r):
            raise ValueError(f"{core_of}: knot core [{i}, {j}] outside the {len(r)} beads of "
                             f"{path} frame {frame}")
        r, comment = r[i:j + 1], comment + f" beads {i}-{j} (knot core)"
    write_xyz(xyz, r, comment=comment)
