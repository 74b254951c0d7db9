"""The reference study side by side with our runs: trefoil Table 2 and candy-cane modes/slipknots.

`knotflow-study --trefoil DIR --candycane DIR --out DIR` reads the case files of the two sweeps
(inputs/trefoil_table2.nml, inputs/candycane.nml) after `knotflow-analyze` has filled their
/analysis groups, and writes figures, `results.md` (the tables quoted in docs/REPRODUCTION.md)
and `results.json`. Nothing is recomputed that /analysis already holds; k_f is computed here only
for files without /analysis/knots.
"""

from __future__ import annotations

import json
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .analysis import analyze_case  # noqa: E402
from .io import read_case, write_xyz  # noqa: E402
from .plot import _draw_chain, mode_name  # noqa: E402
from .report import find_case_files  # noqa: E402
from .transitions import states  # noqa: E402

#: Table 2 of the reference study: the cases whose k_f went unknotted and then knotted again.
#: Every other case of the table had no such transition.
STUDY_TRANSITIONS = {("b", 1.4), ("c", 2.1), ("c", 2.2), ("c", 2.3)}
#: Slipknot threshold on the knot matrix and whole-chain threshold (docs/analysis.md).
SLIP_K, SLIP_WHOLE = 0.5, 0.1


def _key(a, o):
    return (str(o), round(float(a), 6))


def _in_study(a, o) -> bool:
    return any(_key(a, o) == _key(sa, so) for so, sa in STUDY_TRANSITIONS)


def entangled_frames(path, every=50, extra=5, gap=20):
    """Frames for knot matrices: every `every`-th frame plus the `extra` frames with the most close
    pairs, at least `gap` frames from each other and from the regular ones."""
    case = read_case(path)
    cp = np.asarray(case.observables.get("close_pairs", np.zeros(case.nframes)))
    sel = list(range(0, case.nframes, every))
    if case.nframes and sel[-1] != case.nframes - 1:
        sel.append(case.nframes - 1)
    chosen = []
    for k in np.argsort(-cp, kind="stable"):
        if len(chosen) >= extra or cp[k] <= 0:
            break
        if all(abs(int(k) - c) >= gap for c in chosen) and int(k) not in sel:
            chosen.append(int(k))
    return sorted(sel + chosen)


def history(time, kf, knotted_at_start):
    """Events of k_f(t) with the hysteresis of `transitions` and a given initial state.

    The open trefoil starts as a trefoil (k_f(0) about 0.8-0.9, inside the hysteresis band), so the
    first frame below the band is already an untying: the sweep report, which takes the state of
    the first frame outside the band as the initial one, does not count it as an event."""
    prev = "knotted" if knotted_at_start else "unknotted"
    events = []
    for k, st in enumerate(states(kf)):
        if st is not None and st != prev:
            events.append(("unknot" if st == "unknotted" else "knot", float(time[k])))
            prev = st
    return events


def _late(t, frac=0.5):
    """Mask of the second half of the run (after the transient)."""
    return t >= t[0] + frac * (t[-1] - t[0])


def trefoil_rows(files, closures=200):
    rows = []
    for path in files:
        case = read_case(path)
        if case.nframes == 0:
            continue
        ana = analyze_case(case, closures=closures)
        a, o = float(case.bending_a), str(case.orientation)
        events = history(ana.time, ana.kf, knotted_at_start=ana.kf[0] >= 0.5)
        t_unknot = next((t for k, t in events if k == "unknot"), None)
        t_reknot = None if t_unknot is None else next(
            (t for k, t in events if k == "knot" and t > t_unknot), None)
        utk = t_reknot is not None
        rows.append({
            "case": case.name, "A": a, "orientation": o, "status": case.status,
            "t_end": float(case.time[-1]), "kf0": float(ana.kf[0]), "final_kf": ana.final_kf,
            "final_state": ana.final_state or "undecided",
            "events": [[k, t] for k, t in events],
            "unknot_then_knot": utk, "t_unknot": t_unknot, "t_reknot": t_reknot,
            "study_transition": _in_study(a, o), "mode": mode_name(ana.case_mode),
            "time": ana.time.tolist(), "kf": ana.kf.tolist(), "kf_source": ana.kf_source,
        })
    rows.sort(key=lambda r: (r["A"], r["orientation"]))
    return rows


def slipknot_scan(case, kf_time, kf, confirm_dir=None):
    """Per stored knot matrix: whole-chain k_f at that frame, max K, knot core, slipknot flag.

    The matrices of the scan use few closures per subchain (20), so their largest entry over
    ~10^4 subchains is biased upwards. Where `confirm_dir` holds `<case>_frame<k>.json` (the
    `knotflow-analyze --matrix --json` output of that frame with more closures) its max K, core
    and slipknot flag are reported as `confirmed_*`."""
    out = []
    for frame, mat in sorted(case.knot_matrices.items()):
        t = float(case.time[frame])
        kw = float(np.interp(t, kf_time, kf)) if len(kf) else float("nan")
        finite = np.where(np.isfinite(mat), mat, -1.0)
        kmax = float(finite.max())
        core = None
        ii, jj = np.nonzero(finite >= SLIP_K)
        if len(ii):
            lengths = jj - ii
            m = int(np.argmin(lengths))
            core = [int(ii[m]), int(jj[m])]
        entry = {"frame": int(frame), "time": t, "whole_kf": kw, "max_K": kmax,
                 "knot_core": core, "slipknot": bool(kmax >= SLIP_K and kw < SLIP_WHOLE)}
        conf = _confirmation(confirm_dir, case, frame)
        if conf is not None:
            entry.update(conf)
        out.append(entry)
    return out


def confirm_path(confirm_dir, case_name, frame):
    return os.path.join(confirm_dir, f"{case_name}_frame{int(frame)}.json")


def _confirmation(confirm_dir, case, frame):
    if not confirm_dir:
        return None
    path = confirm_path(confirm_dir, getattr(case, "name", "case"), frame)
    if not os.path.isfile(path):
        return None
    with open(path, encoding="utf-8") as fh:
        d = json.load(fh)
    mat = np.array([[np.nan if v is None else v for v in row] for row in d["matrix"]], dtype=float)
    kmax = float(np.nanmax(mat))
    return {"confirmed_whole_kf": float(d["kf"]), "confirmed_max_K": kmax,
            "confirmed_core": d.get("knot_core"),
            "confirmed_slipknot": bool(kmax >= SLIP_K and d["kf"] < SLIP_WHOLE)}


def slip_candidates(path):
    """Frames whose stored (screening) knot matrix looks like a slipknot."""
    case = read_case(path)
    ana = analyze_case(case)
    return [m["frame"] for m in slipknot_scan(case, ana.time, ana.kf) if m["slipknot"]]


def candycane_rows(files, closures=200, confirm_dir=None):
    rows = []
    for path in files:
        case = read_case(path)
        if case.nframes == 0:
            continue
        ana = analyze_case(case, closures=closures)
        o = ana.observables
        t = case.time
        late = _late(t)
        modes = case.modes if case.modes is not None else ana.modes
        modes = np.asarray(modes)
        rows.append({
            "case": case.name, "A": float(case.bending_a), "status": case.status,
            "t_end": float(t[-1]),
            "close_pairs_mean": float(np.mean(o["close_pairs"])),
            "close_pairs_late": float(np.mean(o["close_pairs"][late])),
            "rg_late": float(np.mean(o["rg"][late])),
            "a_late": float(np.mean(o["a"][late])), "b_late": float(np.mean(o["b"][late])),
            "c_late": float(np.mean(o["c"][late])),
            "abs_cos_theta_late": float(np.mean(np.abs(np.cos(o["theta"][late])))),
            "mode_I_late": float(np.mean(modes[late] == 1)) if len(modes) == len(t) else None,
            "mode_II_late": float(np.mean(modes[late] == 2)) if len(modes) == len(t) else None,
            "case_mode": mode_name(ana.case_mode),
            "max_kf": float(np.max(ana.kf)), "mean_kf": float(np.mean(ana.kf)),
            "matrices": slipknot_scan(case, ana.time, ana.kf, confirm_dir),
            "_case": case, "_ana": ana,
        })
    rows.sort(key=lambda r: r["A"])
    return rows


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
        col = "tab:red" if r["unknot_then_knot"] != r["study_transition"] else "k"
        ax.set_title(f"A={r['A']:g} {r['orientation']}{mark}", fontsize=8, color=col)
        ax.set_ylim(-0.05, 1.05)
        ax.tick_params(labelsize=7)
    for ax in axes[-1, :]:
        ax.set_xlabel("t", fontsize=8)
    fig.suptitle("Open trefoils, N = 99: k_f(t) (dashed: red unknot, green knot events; "
                 "red title: differs from the study)", fontsize=9)
    fig.savefig(path, dpi=100)
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
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def plot_candycane_kf(rows, path):
    fig, ax = plt.subplots(figsize=(9, 3), constrained_layout=True)
    for r in rows:
        ax.plot(r["_ana"].time, r["_ana"].kf, lw=0.8, label=f"A = {r['A']:g}")
    ax.set_ylim(-0.03, 1.03)
    ax.set_xlabel(r"time $\dot\gamma t$")
    ax.set_ylabel("$k_f$ (whole chain)")
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=100)
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
    fig.savefig(path, dpi=90)
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
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


# ------------------------------------------------------------------------------------------- tables

def _f(v, spec=".2f"):
    return "-" if v is None else format(v, spec)


def trefoil_tables(rows):
    a_vals = sorted({r["A"] for r in rows})
    o_vals = sorted({r["orientation"] for r in rows})
    by = {(r["A"], r["orientation"]): r for r in rows}
    out = ["### Unknot-then-knot transitions, ours vs the study (Table 2)", "",
           "Cell: ours / study; `U->K` an unknot-then-knot transition, `-` none; "
           "**bold** where they differ. Every case starts as an open trefoil (knotted); an "
           "untying is k_f falling below 0.1, a re-knotting k_f rising above 0.9 afterwards.", "",
           "| A | " + " | ".join(o_vals) + " |", "|---|" + "---|" * len(o_vals)]
    agree = total = 0
    for a in a_vals:
        cells = []
        for o in o_vals:
            r = by.get((a, o))
            if r is None:
                cells.append(" ")
                continue
            ours = "U->K" if r["unknot_then_knot"] else "-"
            study = "U->K" if r["study_transition"] else "-"
            total += 1
            agree += ours == study
            cell = f"{ours} / {study}"
            cells.append(cell if ours == study else f"**{cell}**")
        out.append(f"| {a:g} | " + " | ".join(cells) + " |")
    out += ["", f"Agreement: {agree} of {total} cases.", "",
            "### Every trefoil case", "",
            "| case | k_f(0) | events (time) | final k_f | final state | mode | study U->K |",
            "|---|---|---|---|---|---|---|"]
    for r in rows:
        ev = ", ".join(f"{k} {t:g}" for k, t in r["events"]) or "none"
        out.append(f"| {r['case']} | {r['kf0']:.2f} | {ev} | {r['final_kf']:.2f} | "
                   f"{r['final_state']} | {r['mode']} | {'yes' if r['study_transition'] else 'no'} |")
    return out, agree, total


def candycane_tables(rows):
    out = ["### Candy-cane cases (late = second half of the run)", "",
           "| A | close pairs (mean, all t) | close pairs (late) | R_g (late) | a, b, c (late) | "
           "mean abs cos theta (late) | frames in mode I / II (late) | case mode | max k_f | mean k_f |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(
            f"| {r['A']:g} | {r['close_pairs_mean']:.2f} | {r['close_pairs_late']:.2f} | "
            f"{r['rg_late']:.2f} | {r['a_late']:.1f}, {r['b_late']:.1f}, {r['c_late']:.1f} | "
            f"{r['abs_cos_theta_late']:.2f} | {_f(r['mode_I_late'])} / {_f(r['mode_II_late'])} | "
            f"{r['case_mode']} | {r['max_kf']:.3f} | {r['mean_kf']:.4f} |")
    a1 = next((r for r in rows if abs(r["A"] - 1.0) < 1e-9), None)
    a3 = next((r for r in rows if abs(r["A"] - 3.0) < 1e-9), None)
    if a1 and a3 and a3["close_pairs_mean"] > 0:
        out += ["", f"Close pairs A = 1 / A = 3: {a1['close_pairs_mean'] / a3['close_pairs_mean']:.1f} "
                f"(whole run), {a1['close_pairs_late'] / max(a3['close_pairs_late'], 1e-12):.1f} (late)."]
    out += ["", "### Knot matrices (slipknot search)", "",
            f"Slipknot: some K(i, j) >= {SLIP_K} while the whole chain has k_f < {SLIP_WHOLE}. "
            "Screening: 20 closures per subchain on every 50th frame and the 5 most entangled "
            "frames; candidates recomputed with 100 closures per subchain (and 1000 for the whole "
            "chain) where listed.", "",
            "| A | frames screened | frames with max K >= 0.5 | candidates (t) | "
            "largest K in the screen (t, whole k_f, core) | candidates recomputed: t, max K, slipknot |",
            "|---|---|---|---|---|---|"]
    for r in rows:
        ms = r["matrices"]
        if not ms:
            out.append(f"| {r['A']:g} | 0 | - | - | - | - |")
            continue
        knotted = [m for m in ms if m["max_K"] >= SLIP_K]
        slips = [m for m in ms if m["slipknot"]]
        best = max(ms, key=lambda m: m["max_K"])
        core = "-" if best["knot_core"] is None else f"{best['knot_core'][0]}-{best['knot_core'][1]}"
        slip_times = ", ".join(format(m["time"], "g") for m in slips) or "none"
        conf = "; ".join(f"t = {m['time']:g}: {m['confirmed_max_K']:.2f}, "
                         f"{'yes' if m['confirmed_slipknot'] else 'no'}"
                         for m in ms if "confirmed_max_K" in m) or "-"
        out.append(f"| {r['A']:g} | {len(ms)} | {len(knotted)} | {slip_times} | "
                   f"{best['max_K']:.2f} (t = {best['time']:g}, {best['whole_kf']:.2f}, {core}) | "
                   f"{conf} |")
    return out


def ensemble_tables(rows):
    """Candy-canes with several random rotations: every case, then mean and range per A."""
    out = ["### Candy-cane ensemble (several random rotations; late = second half of the run)", "",
           "| case | close pairs (all t) | close pairs (late) | R_g (late) | c (late) | "
           "mean abs cos theta (late) | mode I / II frames (late) | max k_f |",
           "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['case']} | {r['close_pairs_mean']:.2f} | {r['close_pairs_late']:.2f} | "
                   f"{r['rg_late']:.1f} | {r['c_late']:.2f} | {r['abs_cos_theta_late']:.2f} | "
                   f"{_f(r['mode_I_late'])} / {_f(r['mode_II_late'])} | {r['max_kf']:.2f} |")
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


def write_study(trefoil_dir, candycane_dir, out, closures=200, ensemble_dir=None):
    confirm_dir = os.path.join(out, "confirm")
    os.makedirs(out, exist_ok=True)
    md = ["# knotflow-study: generated results", "",
          f"Trefoil sweep: `{trefoil_dir}`; candy-cane sweep: `{candycane_dir}`.", ""]
    result = {}
    if trefoil_dir:
        rows = trefoil_rows(find_case_files(trefoil_dir), closures)
        plot_trefoil_grid(rows, os.path.join(out, "trefoil_kf_grid.png"))
        lines, agree, total = trefoil_tables(rows)
        md += ["## Trefoils (Table 2)", "", "![k_f(t) of every case](trefoil_kf_grid.png)", ""] + lines + [""]
        result["trefoil"] = {"agree": agree, "total": total,
                             "cases": [{k: v for k, v in r.items() if k not in ("time", "kf")}
                                       for r in rows]}
    if candycane_dir:
        rows = candycane_rows(find_case_files(candycane_dir), closures, confirm_dir)
        figs = [plot_candycane_shapes(rows, os.path.join(out, "candycane_shape.png")),
                plot_candycane_kf(rows, os.path.join(out, "candycane_kf.png")),
                plot_candycane_snapshots(rows, os.path.join(out, "candycane_snapshots.png")),
                plot_matrices(rows, os.path.join(out, "candycane_knot_matrices.png"))]
        md += ["## Candy-cane", ""]
        md += [f"![{os.path.basename(f)}]({os.path.basename(f)})" for f in figs if f] + [""]
        md += candycane_tables(rows) + [""]
        result["candycane"] = [{k: v for k, v in r.items() if not k.startswith("_")} for r in rows]
    if ensemble_dir:
        rows = candycane_rows(find_case_files(ensemble_dir), closures)
        md += ["## Candy-cane ensemble", ""] + ensemble_tables(rows) + [""]
        result["ensemble"] = [{k: v for k, v in r.items() if not k.startswith("_")} for r in rows]
    with open(os.path.join(out, "results.md"), "w", encoding="utf-8") as fh:
        fh.write("\n".join(md) + "\n")
    with open(os.path.join(out, "results.json"), "w", encoding="utf-8") as fh:
        json.dump(result, fh, indent=1)
    return result


def write_frame(path, frame, xyz) -> None:
    """Frame `frame` of case file `path` as a coordinate file `xyz` (knotflow-study
    --write-frame)."""
    case = read_case(path)
    write_xyz(xyz, case.positions[frame], comment=f"{case.name} frame {frame} "
              f"t = {case.time[frame]:g}")
