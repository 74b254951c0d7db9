"""The fibre's rheological series (``/frames/stresslet``, written with ``&output stresslet``):
running and late-time averages of the intrinsic-viscosity-form shear viscosity and the normal
stress difference coefficients psi1, psi2 (normalisation in docs/case-file.md: far-apart free beads
give a viscosity of 5/2)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .atomic import save_figure, write_text
from .io import VISCOSITY_PARTS

SERIES = ("viscosity", "psi1", "psi2")


def running_mean(values) -> np.ndarray:
    """Cumulative mean of a per-frame series: element k is the mean of frames 0..k."""
    v = np.asarray(values, dtype=float)
    return np.cumsum(v) / np.arange(1, len(v) + 1)


def late_time_mean(time, values, t_from):
    """(mean, standard deviation, number of frames) of the frames at t >= t_from; (nan, nan,
    0) when there are none."""
    t = np.asarray(time, dtype=float)
    v = np.asarray(values, dtype=float)[t >= t_from]
    if len(v) == 0:
        return float("nan"), float("nan"), 0
    return float(v.mean()), float(v.std()), int(len(v))


def rheology_summary(case, t_from) -> dict | None:
    """Late-time statistics {name: (mean, std, frames)} of the case's viscosity, psi1, psi2
    from t_from on; None for a file without the stresslet."""
    if not case.stresslet:
        return None
    return {k: late_time_mean(case.time, case.stresslet[k], t_from)
            for k in SERIES if k in case.stresslet}


# ------------------------------------------------------------------ knotted/unknotted, modes I/II

#: Frame classes. A frame is knotted when k_f >= KNOT_THRESHOLD (no hysteresis by default);
#: modes are those of kf_modes (/analysis/shape/mode: 1 mode I, 2 mode II, 0 neither).
KNOTTED, UNKNOTTED, MODE_I, MODE_II, EXCLUDED = "knotted", "unknotted", "mode I", "mode II", None
KNOT_THRESHOLD = 0.5


def knot_classes(kf, threshold=KNOT_THRESHOLD, hysteresis=None) -> list:
    """Class of each frame from its k_f: KNOTTED when k_f >= threshold, else UNKNOTTED. With
    hysteresis = (low, high) instead the state of `transitions.states` (knotted above high,
    unknotted below low, unchanged in between; frames before the first decision EXCLUDED)."""
    kf = np.asarray(kf, dtype=float)
    if hysteresis is None:
        return [KNOTTED if v >= threshold else UNKNOTTED for v in kf]
    from .transitions import states
    low, high = hysteresis
    return states(kf, low, high)


def mode_classes(modes) -> list:
    """Class of each frame from its shape mode: MODE_I, MODE_II, or EXCLUDED (mode 0)."""
    names = {1: MODE_I, 2: MODE_II}
    return [names.get(int(m), EXCLUDED) for m in np.asarray(modes)]


def intervals(classes) -> list:
    """Maximal runs of consecutive frames of one class: (class, first, stop) with frames
    first..stop-1; runs of EXCLUDED frames are left out (they still separate intervals)."""
    out = []
    start = 0
    for k in range(1, len(classes) + 1):
        if k == len(classes) or classes[k] != classes[start]:
            if classes[start] is not EXCLUDED:
                out.append((classes[start], start, k))
            start = k
    return out


def class_statistics(values, classes, names) -> dict:
    """Per class name: frames, intervals, mean and standard deviation over its frames, and the
    mean and standard deviation of its interval means (each interval one number)."""
    v = np.asarray(values, dtype=float)
    runs = intervals(classes)
    out = {}
    for name in names:
        sel = np.array([c == name for c in classes], dtype=bool)
        means = np.array([v[a:b].mean() for c, a, b in runs if c == name])
        out[name] = {
            "frames": int(sel.sum()), "intervals": int(len(means)),
            "mean": float(v[sel].mean()) if sel.any() else float("nan"),
            "std": float(v[sel].std()) if sel.any() else float("nan"),
            "interval_mean": float(means.mean()) if len(means) else float("nan"),
            "interval_std": float(means.std()) if len(means) else float("nan"),
        }
    return out


def sign_flip_test(differences, exact_up_to=16, samples=200000, seed=1) -> float:
    """Two-sided p-value of the mean of independent per-case differences under the null that
    each difference is as likely positive as negative (a sign-flip permutation test): the
    fraction of sign assignments whose |mean| >= the observed |mean|. Exact enumeration of all
    2^n assignments for n <= exact_up_to, otherwise `samples` random ones, (count + 1) /
    (samples + 1). nan for no differences."""
    d = np.asarray(differences, dtype=float)
    n = len(d)
    if n == 0:
        return float("nan")
    observed = abs(d.mean()) * (1.0 - 1e-12)
    if n <= exact_up_to:
        k = np.arange(2 ** n)[:, None]
        signs = 1.0 - 2.0 * ((k >> np.arange(n)[None, :]) & 1)
        return float(np.mean(np.abs(signs @ d) / n >= observed))
    rng = np.random.default_rng(seed)
    signs = rng.choice((-1.0, 1.0), size=(samples, n))
    return float((np.sum(np.abs(signs @ d) / n >= observed) + 1) / (samples + 1))


#: The two comparisons: name -> (classes compared, first minus second).
COMPARISONS = {"knot": (KNOTTED, UNKNOTTED), "mode": (MODE_I, MODE_II)}


def case_classes(case, by, t_from=0.0, threshold=KNOT_THRESHOLD, hysteresis=None):
    """(frame indices, classes) of the case's frames at t >= t_from that have a class source:
    by 'knot' the frames of /analysis/knots (k_f), by 'mode' those of /analysis/shape/mode. A
    file without that analysis is a ValueError naming it and what to run."""
    if by == "knot":
        if case.knots is None:
            raise ValueError(f"{case.path}: no /analysis/knots (run knotflow-analyze on it first)")
        frames = np.asarray(case.knots["frame_index"], dtype=np.int64)
        classes = knot_classes(case.knots["kf"], threshold, hysteresis)
    elif by == "mode":
        if case.modes is None or len(case.modes) != case.nframes:
            raise ValueError(f"{case.path}: no /analysis/shape/mode for every frame (run "
                             "knotflow-analyze on it first)")
        frames = np.arange(case.nframes)
        classes = mode_classes(case.modes)
    else:
        raise ValueError(f"unknown comparison '{by}' (allowed: {', '.join(COMPARISONS)})")
    keep = (frames < case.nframes) & (case.time[np.minimum(frames, case.nframes - 1)] >= t_from)
    return frames[keep], [c for c, k in zip(classes, keep) if k]


def case_series(cases) -> tuple:
    """The series to compare: SERIES, and the viscosity's hydrodynamic and elastic parts
    (io.VISCOSITY_PARTS) when every case has them (case files with both tensors, ledgers of
    version 2)."""
    split = all(c.stresslet and all(k in c.stresslet and np.any(np.isfinite(c.stresslet[k]))
                                    for k in VISCOSITY_PARTS) for c in cases)
    return SERIES + VISCOSITY_PARTS if cases and split else SERIES


def compare_case(case, by, t_from=0.0, threshold=KNOT_THRESHOLD, hysteresis=None,
                 series=SERIES) -> dict:
    """One case: per series (SERIES, or case_series) the class statistics (class_statistics)
    and the difference of the frame means, first class minus second (COMPARISONS; nan unless
    both classes occur)."""
    if not case.stresslet:
        raise ValueError(f"{case.path}: no /frames/stresslet (run the scene with "
                         "&output stresslet = .true.)")
    first, second = COMPARISONS[by]
    frames, classes = case_classes(case, by, t_from, threshold, hysteresis)
    cell, label = case_cell(case)
    row = {"case": case.name, "A": case.bending_a, "orientation": case.orientation,
           "cell": cell, "cell_label": label,
           "time": case.time[frames], "classes": classes, "series": {},
           "values": {name: np.asarray(case.stresslet[name])[frames] for name in series}}
    if by == "knot":
        row["kf"] = np.asarray(case.knots["kf"])[np.isin(case.knots["frame_index"], frames)]
    for name in series:
        stats = class_statistics(row["values"][name], classes, (first, second))
        stats["difference"] = stats[first]["mean"] - stats[second]["mean"]
        row["series"][name] = stats
    return row


def case_cell(case) -> tuple:
    """(cell, label) of a case: campaign.sample_cell of its scene (the start and the model, the
    perturbation's seed left out), or the case alone when it has no scene text."""
    from .campaign import CELL_VARIABLES, sample_cell
    scene = case.attrs.get("scene")
    if not isinstance(scene, str) or not scene:
        return ("case", case.name), case.name
    cell = sample_cell(scene)
    value = dict(zip(CELL_VARIABLES, cell))
    parts = [str(value[("chain", "shape")]), f"A = {float(value[('forces', 'bending_a')] or 0.0):g}"]
    if value[("chain", "shape")] == "trefoil":
        parts.append(f"orientation {value[('chain', 'orientation')]}")
    if value[("chain", "shape")] == "candycane" and value[("chain", "candycane_rotation")] != "random":
        parts.append(f"tilt {float(value[('chain', 'tilt_deg')]):g}°")
    if cell[-1] is not None:
        parts.append(f"seed {cell[-1]}")
    return cell, ", ".join(parts)


def compare_cases(rows, by, samples=200000, seed=1) -> dict:
    """Across cases, per series: the frames and intervals of each class with the mean and
    standard deviation over all their frames; the cases in which both classes occur, the mean
    and standard deviation of their per-case differences and the sign-flip p-value of that mean
    (sign_flip_test: the cases are independent runs, the frames of one case are not); the same
    over cells (cell_differences: the samples of one cell share their early frames, so only
    cells are independent) and over stiffnesses."""
    first, second = COMPARISONS[by]
    out = {}
    for name in (rows[0]["series"] if rows else SERIES):
        pooled: dict[str, Any] = {}
        for cls in (first, second):
            vals = [case_values(r, name, cls) for r in rows]
            v = np.concatenate(vals) if vals else np.zeros(0)
            pooled[cls] = {"frames": int(len(v)),
                           "intervals": int(sum(r["series"][name][cls]["intervals"] for r in rows)),
                           "cases": int(sum(len(x) > 0 for x in vals)),
                           "mean": float(v.mean()) if len(v) else float("nan"),
                           "std": float(v.std()) if len(v) else float("nan")}
        d = np.array([r["series"][name]["difference"] for r in rows], dtype=float)
        d = d[np.isfinite(d)]
        pooled["paired_cases"] = int(len(d))
        pooled["difference_mean"] = float(d.mean()) if len(d) else float("nan")
        pooled["difference_std"] = float(d.std(ddof=1)) if len(d) > 1 else float("nan")
        pooled["positive"] = int((d > 0).sum())
        pooled["p_value"] = sign_flip_test(d, samples=samples, seed=seed)
        c = np.array([x[2] for x in cell_differences(rows, name, first, second)], dtype=float)
        pooled["cells"] = len({r["cell"] for r in rows})
        pooled["paired_cells"] = int(len(c))
        pooled["cell_difference_mean"] = float(c.mean()) if len(c) else float("nan")
        pooled["cell_difference_std"] = float(c.std(ddof=1)) if len(c) > 1 else float("nan")
        pooled["cell_positive"] = int((c > 0).sum())
        pooled["cell_p_value"] = sign_flip_test(c, samples=samples, seed=seed)
        s = stiffness_differences(rows, name, first, second)
        pooled["paired_stiffnesses"] = int(len(s))
        pooled["stiffness_difference_mean"] = float(s.mean()) if len(s) else float("nan")
        pooled["stiffness_difference_std"] = float(s.std(ddof=1)) if len(s) > 1 else float("nan")
        pooled["stiffness_positive"] = int((s > 0).sum())
        pooled["stiffness_p_value"] = sign_flip_test(s, samples=samples, seed=seed)
        out[name] = pooled
    return out


def pooled_differences(rows, name, first, second, key) -> list:
    """Per group of rows with one `key(row)` (in the order of first appearance) in whose cases
    both classes occur: (the group's first row, its number of cases, the mean of series `name`
    over the frames of class `first` of all the group's cases minus that over the frames of
    class `second`)."""
    out = []
    for k in dict.fromkeys(key(r) for r in rows):
        same = [r for r in rows if key(r) == k]
        v1 = np.concatenate([case_values(r, name, first) for r in same])
        v2 = np.concatenate([case_values(r, name, second) for r in same])
        if len(v1) and len(v2):
            out.append((same[0], len(same), float(v1.mean() - v2.mean())))
    return out


def cell_differences(rows, name, first, second) -> list:
    """Per cell (compare_case's "cell", in the order of first appearance) in whose cases both
    classes occur: (label, samples, Δ_cell) as pooled_differences. The samples of a cell are
    pooled: they start a perturbation apart and share their early frames, so they are not
    independent of each other; cells are."""
    return [(r["cell_label"], n, d)
            for r, n, d in pooled_differences(rows, name, first, second, lambda r: r["cell"])]


def stiffness_differences(rows, name, first, second) -> np.ndarray:
    """Per bending stiffness A (in increasing order) at which both classes occur, over all the
    cases of that A (orientations, seeds): the mean of series `name` over the frames of class
    `first` minus that over the frames of class `second`. Compares a chain that stays knotted
    with its siblings that untied, which the per-case differences cannot."""
    rows = sorted(rows, key=lambda r: r["A"])
    return np.array([d for _, _, d in pooled_differences(rows, name, first, second,
                                                         lambda r: r["A"])], dtype=float)


def case_values(row, name, cls) -> np.ndarray:
    """The values of series `name` over the frames of class `cls` of one compare_case row."""
    return np.asarray(row["values"][name])[[c == cls for c in row["classes"]]]


# ------------------------------------------------------------------------- tables, figures, CLI

LABELS = {"viscosity": "viscosity", "psi1": "psi1", "psi2": "psi2",
          "viscosity_hydrodynamic": "viscosity (hydrodynamic part)",
          "viscosity_elastic": "viscosity (elastic part)"}


def _g(v, spec=".3g"):
    return "–" if v is None or not np.isfinite(v) else format(v, spec)


def comparison_tables(rows, summary, by) -> list:
    """Markdown lines: the per-case table and the across-cases table of one comparison."""
    first, second = COMPARISONS[by]
    names = list(summary)
    out = [f"Per case ({first} − {second}: difference of the frame means; frames / intervals of "
           "each class):", "",
           f"| case | {first} frames / intervals | {second} frames / intervals | "
           + " | ".join(f"{LABELS[s]} {first} | {LABELS[s]} {second} | Δ {LABELS[s]}"
                        for s in names) + " |",
           "|---|---|---|" + "---|---|---|" * len(names)]
    for r in rows:
        st = r["series"][names[0]]
        cells = [r["case"], f"{st[first]['frames']} / {st[first]['intervals']}",
                 f"{st[second]['frames']} / {st[second]['intervals']}"]
        for s in names:
            x = r["series"][s]
            cells += [f"{_g(x[first]['mean'])} ± {_g(x[first]['std'], '.2g')}",
                      f"{_g(x[second]['mean'])} ± {_g(x[second]['std'], '.2g')}",
                      _g(x["difference"])]
        out.append("| " + " | ".join(cells) + " |")
    out += ["", "All cases (mean ± standard deviation over the frames of each class; Δ: mean ± "
            "standard deviation over the cases in which both classes occur of the per-case "
            "differences; p: two-sided sign-flip test of the mean Δ over those cases):", "",
            f"| series | {first}: cases / intervals / frames | {first} mean ± sd | "
            f"{second}: cases / intervals / frames | {second} mean ± sd | cases with both | "
            "Δ mean ± sd | Δ > 0 in | p |", "|---|---|---|---|---|---|---|---|---|"]
    for s in names:
        x = summary[s]
        a, b = x[first], x[second]
        out.append(
            f"| {LABELS[s]} | {a['cases']} / {a['intervals']} / {a['frames']} | "
            f"{_g(a['mean'])} ± {_g(a['std'], '.2g')} | {b['cases']} / {b['intervals']} / "
            f"{b['frames']} | {_g(b['mean'])} ± {_g(b['std'], '.2g')} | {x['paired_cases']} | "
            f"{_g(x['difference_mean'])} ± {_g(x['difference_std'], '.2g')} | "
            f"{x['positive']} of {x['paired_cases']} | {_g(x['p_value'], '.2g')} |")
    per_cell = {s: cell_differences(rows, s, first, second) for s in names}
    out += ["", f"By cell (a start and a model; its samples, which differ only by the "
            f"perturbation's seed and share their early frames, pooled: Δ_cell is the mean over "
            f"the {first} frames minus the mean over the {second} frames of all the cell's "
            "cases; cells are independent, samples of one cell are not):", "",
            "| cell | samples | " + " | ".join(f"Δ_cell {LABELS[s]}" for s in names) + " |",
            "|---|---|" + "---|" * len(names)]
    for k, (label, count, _) in enumerate(per_cell[names[0]]):
        out.append(f"| {label} | {count} | "
                   + " | ".join(_g(per_cell[s][k][2]) for s in names) + " |")
    out += ["", "| series | cells / with both | Δ_cell mean ± sd | Δ_cell > 0 in | p |",
            "|---|---|---|---|---|"]
    for s in names:
        x = summary[s]
        out.append(f"| {LABELS[s]} | {x['cells']} / {x['paired_cells']} | "
                   f"{_g(x['cell_difference_mean'])} ± {_g(x['cell_difference_std'], '.2g')} | "
                   f"{x['cell_positive']} of {x['paired_cells']} | {_g(x['cell_p_value'], '.2g')} |")
    out += ["", f"By bending stiffness (Δ_A: mean over the {first} frames minus mean over the "
            f"{second} frames of all the cases with stiffness A; mean ± standard deviation over "
            "the stiffnesses at which both occur; p: sign-flip test over them):", "",
            "| series | stiffnesses with both | Δ_A mean ± sd | Δ_A > 0 in | p |",
            "|---|---|---|---|---|"]
    for s in names:
        x = summary[s]
        out.append(f"| {LABELS[s]} | {x['paired_stiffnesses']} | "
                   f"{_g(x['stiffness_difference_mean'])} ± "
                   f"{_g(x['stiffness_difference_std'], '.2g')} | {x['stiffness_positive']} of "
                   f"{x['paired_stiffnesses']} | {_g(x['stiffness_p_value'], '.2g')} |")
    return out


def plot_against_kf(rows, path, series=("viscosity", "psi1")):
    """Each series against k_f: every frame of every case (grey) and the mean over the frames
    in k_f bins of width 0.1 (black, ± the standard deviation)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(series), figsize=(4.2 * len(series), 3.2),
                             constrained_layout=True, squeeze=False)
    kf = np.concatenate([r["kf"] for r in rows])
    edges = np.linspace(0.0, 1.0, 11)
    mid = 0.5 * (edges[1:] + edges[:-1])
    which = np.clip(np.digitize(kf, edges) - 1, 0, len(mid) - 1)
    for ax, s in zip(axes[0], series):
        v = np.concatenate([r["values"][s] for r in rows])
        ax.plot(kf, v, ".", color="0.6", ms=1.5, alpha=0.4, rasterized=True)
        m = np.array([v[which == k].mean() if (which == k).any() else np.nan
                      for k in range(len(mid))])
        e = np.array([v[which == k].std() if (which == k).any() else np.nan
                      for k in range(len(mid))])
        ax.errorbar(mid, m, yerr=e, color="k", marker="o", ms=3, lw=1, capsize=2)
        ax.axvline(KNOT_THRESHOLD, color="tab:red", lw=0.8, ls="--")
        lo, hi = np.nanpercentile(v, [1, 99])
        ax.set_ylim(lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo))
        ax.set_xlabel("$k_f$")
        ax.set_ylabel(LABELS[s])
    save_figure(fig, path, dpi=80)
    plt.close(fig)
    return path


def plot_series(rows, path, name="viscosity"):
    """The series against time for every case (grey), its knotted frames marked (red)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8.4, 3.0), constrained_layout=True)
    for r in rows:
        t, v = r["time"], r["values"][name]
        ax.plot(t, v, color="0.6", lw=0.5)
        k = np.array([c == KNOTTED for c in r["classes"]], dtype=bool)
        ax.plot(t[k], v[k], ".", color="tab:red", ms=1.5)
    ax.set_xscale("symlog", linthresh=10.0)
    ax.set_xlabel(r"time $\dot\gamma t$ (linear below 10, logarithmic above)")
    ax.set_ylabel(LABELS[name])
    ax.set_title(f"{LABELS[name]} of every case; red: knotted frames", fontsize=9)
    save_figure(fig, path, dpi=80)
    plt.close(fig)
    return path


def plot_against_mode(cases, path, series=("viscosity", "psi1"), t_from=0.0):
    """Box plots of each series per case for the frames at t >= t_from in mode I, mode II and
    neither (/analysis/shape/mode)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(series), figsize=(4.2 * len(series), 3.2),
                             constrained_layout=True, squeeze=False)
    groups = ((1, "I"), (2, "II"), (0, "–"))
    for ax, s in zip(axes[0], series):
        data, labels = [], []
        for case in cases:
            late = case.time >= t_from
            for m, lab in groups:
                sel = late & (np.asarray(case.modes) == m)
                if sel.any():
                    data.append(np.asarray(case.stresslet[s])[sel])
                    labels.append(f"A={_g(case.bending_a, 'g')}\n{lab}")
        ax.boxplot(data, showfliers=False)
        ax.set_xticks(range(1, len(labels) + 1), labels, fontsize=7)
        ax.set_ylabel(LABELS[s])
        ax.set_xlabel("case and shape mode (– : neither)")
    save_figure(fig, path, dpi=80)
    plt.close(fig)
    return path


def models_text(cases) -> str:
    """The hydrodynamic models (and, for the multipole model, the overlap rules by their scene
    names) of the cases, with how many cases ran with each."""
    from collections import Counter

    def name(case):
        model = str(case.attrs.get("hydro.model", "?"))
        if model == "multipole" and case.attrs.get("hydro.overlap") is not None:
            return f"multipole with overlap = '{case.attrs['hydro.overlap']}'"
        return model
    return ", ".join(f"{m} ({n} case{'s' if n > 1 else ''})"
                     for m, n in sorted(Counter(name(c) for c in cases).items()))


def _jsonable(rows, summary):
    return {"cases": [{"case": r["case"], "A": r["A"], "orientation": r["orientation"],
                       "cell": r["cell_label"], "series": r["series"]} for r in rows],
            "all": summary}


def write_rheology(knot_dirs, mode_dirs, out, t_from=0.0, threshold=KNOT_THRESHOLD,
                   hysteresis=None, samples=200000, seed=1, finished_only=False) -> dict:
    """Both comparisons for the cases of the given sweep directories (case files, or one sweep
    of a case ledger: its `<case>.json` entries, campaign.ledger_case, whose frame rows hold k_f,
    the mode and the stresslet's series): rheology.md, rheology.json and the figures in out.
    `finished_only`: leave out the cases whose status is not 'finished' (named in rheology.md)."""
    import json
    import os

    from .campaign import find_ledger_cases, load_case
    from .io import find_case_files
    os.makedirs(out, exist_ok=True)
    rule = (f"knotted when k_f >= {threshold:g} (no hysteresis)" if hysteresis is None else
            f"hysteresis: knotted above {hysteresis[1]:g}, unknotted below {hysteresis[0]:g}, "
            "unchanged in between, undecided frames before the first decision left out")
    md = ["# knotflow-rheology: does a knot change the fluid?", "",
          f"Frames at t >= {t_from:g}. Knot rule: {rule}. Modes: /analysis/shape/mode (kf_modes); "
          "frames in neither mode are left out of the mode comparison. Intervals: maximal runs "
          "of consecutive analysed frames of one class.", ""]
    result = {"t_from": t_from, "threshold": threshold, "hysteresis": hysteresis}
    for by, dirs, title in (("knot", knot_dirs, "Knotted and unknotted intervals"),
                            ("mode", mode_dirs, "Modes I and II")):
        files = [f for d in dirs for f in (find_case_files(d) or find_ledger_cases(d))]
        if not files:
            continue
        cases = [load_case(f) for f in files]
        cases = [c for c in cases if c.nframes > 0]
        left_out = [c.name for c in cases if c.status != "finished"] if finished_only else []
        if finished_only:
            cases = [c for c in cases if c.status == "finished"]
        if not cases:
            continue
        names = case_series(cases)
        rows = [compare_case(c, by, t_from, threshold, hysteresis, names) for c in cases]
        summary = compare_cases(rows, by, samples, seed)
        md += [f"## {title}", "", f"Cases: {', '.join(f'`{d}`' for d in dirs)}.", "",
               f"Models: {models_text(cases)}.", ""]
        if left_out:
            md += [f"Left out, not finished: {', '.join(left_out)}.", ""]
        md += comparison_tables(rows, summary, by) + [""]
        if by == "knot":
            series = plot_series(rows, os.path.join(out, "rheology_time.png"))
            md += [f"![viscosity against time]({os.path.basename(series)})", ""]
            fig = plot_against_kf(rows, os.path.join(out, "rheology_vs_kf.png"))
        else:
            fig = plot_against_mode(cases, os.path.join(out, "rheology_vs_mode.png"),
                                    t_from=t_from)
        md += [f"![{title}]({os.path.basename(fig)})", ""]
        result[by] = _jsonable(rows, summary)
    write_text(os.path.join(out, "rheology.md"), "\n".join(md) + "\n")
    write_text(os.path.join(out, "rheology.json"), json.dumps(result, indent=1, default=float))
    return result


def summary_lines(result) -> list:
    """One line per comparison of write_rheology's result: the viscosity difference of the
    paired cases and of the paired cells, with their p-values."""
    lines = []
    for by in COMPARISONS:
        if by in result:
            x = result[by]["all"]["viscosity"]
            first, second = COMPARISONS[by]
            lines.append(f"{first} - {second}: viscosity difference {_g(x['difference_mean'])} "
                         f"over {x['paired_cases']} case(s), p = {_g(x['p_value'], '.2g')}; "
                         f"{_g(x['cell_difference_mean'])} over {x['paired_cells']} cell(s), "
                         f"p = {_g(x['cell_p_value'], '.2g')}")
    return lines
