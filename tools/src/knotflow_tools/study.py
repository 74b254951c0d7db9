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
statistics under BWE (run diagnostics) and the run records (/runs: commit, wall time, load) of
every case. A sweep may be running: cases not 'finished' are included, marked with their status
and the time reached, and the tables say how many cases are finished.

`--rpy-trefoil JSON` and `--rpy-candycane JSON` take the results.json of an earlier
knotflow-study run with RPY + excluded volume (its "trefoil" part, resp. its "candycane" and
"ensemble" parts); results.md then has three-column tables (the study, this run's directories
= knotflow multipole, knotflow RPY + EV) and results.json a "comparison" part.

`--select-frames CASE` prints the frames for the knot-matrix screen of CASE (every 50th frame,
or with `--every-time T` the frames at the multiples of T time units, plus the last frame and
the 5 frames with the most close pairs).

Slipknots: the candidates of that screen are recomputed and checked by scripts/reproduce.sh
(files in <out>/confirm: `confirm_path`); the rule that confirms one is `confirmation_verdict`
(docs/analysis.md, "Slipknot confirmation"), and `candycane_slipknots.png` shows the confirmed
frames or, without one, the frame that went furthest, labelled not confirmed. A sweep directory
without case files is named in results.md ("no case files in DIR") and skipped.
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
from .knots import knot_core  # noqa: E402
from .plot import _draw_chain, mode_name  # noqa: E402
from .report import find_case_files  # noqa: E402
from .transitions import states  # noqa: E402

#: Table 2 of the reference study: the cases whose k_f went unknotted and then knotted again.
#: Every other case of the table had no such transition.
STUDY_TRANSITIONS = {("b", 1.4), ("c", 2.1), ("c", 2.2), ("c", 2.3)}
#: The study's Table 2: 29 simulations, with 13 unknot-then-knot events in 4 of them (the four
#: cases of STUDY_TRANSITIONS) -- as issue 11 quotes the study.
STUDY_TREFOIL_CASES, STUDY_REKNOT_EVENTS, STUDY_REKNOT_SIMULATIONS = 29, 13, 4
#: The study's stiff trefoils (A >= 2.2) tumble (mode II): docs/REPRODUCTION.md, Summary.
STUDY_STIFF_A, STUDY_STIFF_MODE = 2.2, "tumble (mode II)"
#: The study's candy-canes (docs/REPRODUCTION.md, "Candy-cane", "What does not"): A = 1 coils and
#: rolls about the vorticity axis (mode I), A = 3 stays open and tumbles (mode II); about 4 times
#: more close pairs at A = 1 than at A = 3; a slipknot found at A = 1.4; whole-chain k_f about 0
#: (Summary). The mode at A = 1.4 and the close-pair numbers per A are not stated there.
STUDY_CANDYCANE_A = (1.0, 1.4, 3.0)
STUDY_CANDYCANE_MODES = {1.0: "I", 3.0: "II"}
STUDY_CLOSE_PAIR_RATIO = "about 4"
STUDY_SLIPKNOT_A = {1.4}
STUDY_WHOLE_KF = "about 0"
#: Slipknot threshold on the knot matrix and whole-chain threshold (docs/analysis.md).
SLIP_K, SLIP_WHOLE = 0.5, 0.1


def _key(a, o):
    return (str(o), round(float(a), 6))


def _in_study(a, o) -> bool:
    return any(_key(a, o) == _key(sa, so) for so, sa in STUDY_TRANSITIONS)


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
    case = read_case(path)
    cp = np.asarray(case.observables.get("close_pairs", np.zeros(case.nframes)))
    sel = (list(range(0, case.nframes, every)) if every_time is None
           else time_frames(case.time, every_time))
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


def reknottings(events) -> int:
    """Knot events that follow an untying (the study's unknot-then-knot events) in `events`,
    a list of (kind, time) or [kind, time] in time order."""
    seen_unknot, count = False, 0
    for kind, _t in events:
        if kind == "unknot":
            seen_unknot = True
        elif kind == "knot" and seen_unknot:
            count += 1
    return count


def status_of(case) -> dict:
    """Status, target t_end (the case's integrator.t_end; None when not recorded) and the time
    reached (the last frame read)."""
    t_end = case.attrs.get("integrator.t_end")
    return {"status": case.status, "model": str(case.attrs.get("hydro.model", "?")),
            "t_end": None if t_end is None else float(t_end),
            "t_reached": float(case.time[-1])}


def finished(row) -> bool:
    """Has the case of `row` (a row here or a case of an earlier results.json) finished?"""
    return row.get("status", "finished") == "finished"


def status_text(row) -> str:
    """'finished', or e.g. 'running, t = 408 of 2000' (never a running case's t as its end)."""
    if finished(row):
        return "finished"
    reached = row.get("t_reached", row.get("t_end"))
    of = "" if row.get("t_end") is None else f" of {row['t_end']:g}"
    return f"{row['status']}, t = {reached:g}{of}"


def overlap_stats(case) -> dict | None:
    """The run totals of the diagnostics under BWE (io.DIAGNOSTIC_TOTALS; a running case's from
    its newest checkpoint), None when the case file has none."""
    if case.diagnostic_totals is None:
        return None
    return {**case.diagnostic_totals, "source": case.diagnostic_totals_source}


def runs_summary(runs) -> dict | None:
    """The run records of a case (io.RUN_FIELDS per segment) summed: commits in order of first
    use, total wall time of the segments that record one (a NaN wall time is counted in
    `wall_unknown`), mean load weighted by wall time over the segments with a known load (None
    when none is known), segments, t range. None without records."""
    if not runs:
        return None
    commits: list = []
    for r in runs:
        if r["commit"] not in commits:
            commits.append(r["commit"])
    wall = float(sum(r["wall_seconds"] for r in runs if math.isfinite(r["wall_seconds"])))
    known = [r for r in runs if math.isfinite(r["load_mean"]) and math.isfinite(r["wall_seconds"])]
    weight = float(sum(r["wall_seconds"] for r in known))
    load = float(sum(r["load_mean"] * r["wall_seconds"] for r in known) / weight) if weight > 0 \
        else None
    return {"commits": commits, "wall_seconds": wall,
            "wall_unknown": sum(not math.isfinite(r["wall_seconds"]) for r in runs),
            "mean_load": load, "load_seconds": weight, "segments": len(runs),
            "t_start": float(min(r["t_start"] for r in runs)),
            "t_end": float(max(r["t_end"] for r in runs))}


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
            "case": case.name, "A": a, "orientation": o, **status_of(case),
            "kf0": float(ana.kf[0]), "final_kf": ana.final_kf,
            "final_state": ana.final_state or "undecided",
            "events": [[k, t] for k, t in events], "reknottings": reknottings(events),
            "unknot_then_knot": utk, "t_unknot": t_unknot, "t_reknot": t_reknot,
            "study_transition": _in_study(a, o), "mode": mode_name(ana.case_mode),
            "overlap": overlap_stats(case), "runs": runs_summary(case.runs),
            "time": ana.time.tolist(), "kf": ana.kf.tolist(), "kf_source": ana.kf_source,
        })
    rows.sort(key=lambda r: (r["A"], r["orientation"]))
    return rows


def slipknot_scan(case, kf_time, kf, confirm_dir=None):
    """Per stored knot matrix: whole-chain k_f at that frame, max K, knot core, slipknot flag.

    The matrices of the scan use few closures per subchain (20), so their largest entry over
    ~10^4 subchains is biased upwards: a frame flagged here is a candidate. Where `confirm_dir`
    holds the files of its confirmation (`confirmation`) their numbers are added."""
    out = []
    for frame, mat in sorted(case.knot_matrices.items()):
        t = float(case.time[frame])
        kw = float(np.interp(t, kf_time, kf)) if len(kf) else float("nan")
        kmax, core = _max_and_core(mat)
        entry = {"frame": int(frame), "time": t, "whole_kf": kw, "max_K": kmax,
                 "knot_core": core, "slipknot": bool(kmax >= SLIP_K and kw < SLIP_WHOLE)}
        if confirm_dir:
            entry.update(confirmation(confirm_dir, getattr(case, "name", "case"), frame))
        out.append(entry)
    return out


def _max_and_core(mat):
    """Largest finite entry of a knot matrix (-1 without one) and its knot core ([i, j], the
    shortest subchain with K >= SLIP_K, smallest i on a tie, as knots.knot_core and the Fortran
    kf_knot_matrix; None without one)."""
    finite = np.where(np.isfinite(mat), mat, -1.0)
    core = knot_core(finite, SLIP_K)
    return float(finite.max()) if finite.size else -1.0, None if core is None else list(core)


# ------------------------------------------------------------------ slipknot confirmation

#: One-sided error level of the slipknot confirmation (docs/analysis.md, "Slipknot
#: confirmation"): the core's k_f must exceed SLIP_K and the whole chain's stay below SLIP_WHOLE
#: at this level (exact binomial, Clopper-Pearson bounds).
CONFIRM_ALPHA = 1e-3
#: Closures of the knot core and the whole chain in the check (scripts/reproduce.sh kf_confirm).
CONFIRM_CLOSURES = 1000
#: Verdicts of the slipknot search (`slip_verdict`); NOT_CONFIRMED is followed by the reason.
CONFIRMED, REJECTED, UNCHECKED = ("confirmed", "not a slipknot with more closures per subchain",
                                  "core not checked")
NOT_RECOMPUTED, NO_CANDIDATE, NOT_CONFIRMED = "not recomputed", "-", "not confirmed: "
#: The parts of a candidate's confirmation in the confirm directory: `<case>_frame<k><suffix>`.
#: "matrix": `knotflow-analyze FRAME.xyz --matrix --json` (100 closures per subchain); "core":
#: `knotflow-analyze CORE.xyz --closures 1000 --json` of the knot core's beads; "whole": the same
#: for the whole chain; "frame"/"core_xyz": the coordinate files they read.
CONFIRM_PARTS = {"matrix": ".json", "core": "_core.json", "whole": "_whole.json",
                 "frame": ".xyz", "core_xyz": "_core.xyz"}


def confirm_path(confirm_dir, case_name, frame, part="matrix"):
    """The file of `part` (CONFIRM_PARTS) of the confirmation of frame `frame` of a case."""
    return os.path.join(confirm_dir, f"{case_name}_frame{int(frame)}{CONFIRM_PARTS[part]}")


def _log_binom_pmf(k, n, p):
    if p <= 0.0:
        return 0.0 if k == 0 else -math.inf
    if p >= 1.0:
        return 0.0 if k == n else -math.inf
    return (math.lgamma(n + 1) - math.lgamma(k + 1) - math.lgamma(n - k + 1)
            + k * math.log(p) + (n - k) * math.log1p(-p))


def binomial_tail(x, n, p) -> float:
    """P(X >= x) for X ~ Binomial(n, p) (a sum of the probabilities in log space)."""
    if x <= 0:
        return 1.0
    if x > n:
        return 0.0
    logs = [_log_binom_pmf(k, n, p) for k in range(x, n + 1)]
    top = max(logs)
    if top == -math.inf:
        return 0.0
    return min(1.0, math.exp(top) * math.fsum(math.exp(v - top) for v in logs))


def _solve(f, target):
    """The p in [0, 1] with f(p) = target for f increasing in p (bisection to 1e-12)."""
    lo, hi = 0.0, 1.0
    while hi - lo > 1e-12:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) < target else (lo, mid)
    return 0.5 * (lo + hi)


def lower_bound(x, n, alpha=CONFIRM_ALPHA) -> float:
    """One-sided Clopper-Pearson lower bound of a binomial p after x successes in n trials:
    the p with P_p(X >= x) = alpha (0 for x = 0). P(bound > p) <= alpha for every p."""
    return 0.0 if x <= 0 else _solve(lambda p: binomial_tail(x, n, p), alpha)


def upper_bound(x, n, alpha=CONFIRM_ALPHA) -> float:
    """One-sided Clopper-Pearson upper bound: the p with P_p(X <= x) = alpha (1 for x = n)."""
    return 1.0 if x >= n else 1.0 - lower_bound(n - x, n, alpha)


def kf_estimate(kf, closures, alpha=CONFIRM_ALPHA) -> dict:
    """k_f from `closures` independent closures: value, binomial standard error
    sqrt(k_f (1 - k_f) / closures), knotted closures and the one-sided bounds at level alpha."""
    n = int(closures)
    if n < 1 or not 0.0 <= kf <= 1.0:
        raise ValueError(f"k_f {kf} from {closures} closures is not allowed (0 <= k_f <= 1, "
                         "closures >= 1)")
    x = int(round(kf * n))
    return {"kf": x / n, "se": math.sqrt(x / n * (1 - x / n) / n), "knotted": x, "closures": n,
            "lower": lower_bound(x, n, alpha), "upper": upper_bound(x, n, alpha)}


def confirm_counts(closures, alpha=CONFIRM_ALPHA) -> tuple:
    """(fewest knotted closures of the core, most of the whole chain) that `confirmation_verdict`
    accepts with `closures` closures: the smallest x with P_{SLIP_K}(X >= x) < alpha and the
    largest with P_{SLIP_WHOLE}(X <= x) < alpha (-1 when none)."""
    n = int(closures)
    core = next((x for x in range(n + 1) if binomial_tail(x, n, SLIP_K) < alpha), n + 1)
    whole = -1
    while whole < n and 1.0 - binomial_tail(whole + 2, n, SLIP_WHOLE) < alpha:
        whole += 1
    return core, whole


def confirmation_verdict(core, whole) -> tuple:
    """(confirmed, why not) of a candidate from the k_f estimates (`kf_estimate`) of its knot
    core and of its whole chain: confirmed when the core's lower bound exceeds SLIP_K and the
    whole chain's upper bound is below SLIP_WHOLE ('' then)."""
    reasons = []
    if not core["lower"] > SLIP_K:
        reasons.append(f"core k_f lower bound {core['lower']:.3f} <= {SLIP_K}")
    if not whole["upper"] < SLIP_WHOLE:
        reasons.append(f"whole-chain k_f upper bound {whole['upper']:.3f} >= {SLIP_WHOLE}")
    return (not reasons, "; ".join(reasons))


def _load_json(path):
    with open(path, encoding="utf-8") as fh:
        d = json.load(fh)
    if not isinstance(d, dict) or "kf" not in d:
        raise ValueError(f"{path}: not the JSON of knotflow-analyze --json (no \"kf\")")
    return d


def json_matrix(d) -> np.ndarray:
    """The knot matrix of a knotflow-analyze --matrix --json object (NaN for null)."""
    return np.array([[np.nan if v is None else v for v in row] for row in d["matrix"]],
                    dtype=float)


def confirmation(confirm_dir, case_name, frame) -> dict:
    """What the confirm directory holds on frame `frame` of a case, as entries of the slipknot
    scan: `recomputed_*` (the knot matrix with more closures per subchain: max K, core, whole
    k_f, and `recomputed_slipknot` when its max K >= SLIP_K and whole k_f < SLIP_WHOLE), then,
    for a frame recomputed as a slipknot, `core_*` and `check_whole_*` (k_f, standard error,
    bounds, closures of the knot core and of the whole chain) with `confirmed_slipknot` and
    `verdict` (`confirmation_verdict`). {} when nothing is there."""
    path = confirm_path(confirm_dir, case_name, frame)
    if not os.path.isfile(path):
        return {}
    d = _load_json(path)
    kmax, core = _max_and_core(json_matrix(d))
    out = {"recomputed_whole_kf": float(d["kf"]), "recomputed_max_K": kmax,
           "recomputed_core": core,
           "recomputed_slipknot": bool(kmax >= SLIP_K and d["kf"] < SLIP_WHOLE)}
    if not out["recomputed_slipknot"]:
        out["verdict"] = REJECTED
        return out
    parts = [confirm_path(confirm_dir, case_name, frame, p) for p in ("core", "whole")]
    if not all(os.path.isfile(p) for p in parts):
        out["verdict"] = UNCHECKED
        return out
    est = [_load_json(p) for p in parts]
    c, w = (kf_estimate(float(e["kf"]), int(e["closures"])) for e in est)
    out.update({f"core_{k}": v for k, v in c.items()})
    out["core_beads"] = core
    out.update({f"check_whole_{k}": v for k, v in w.items()})
    ok, why = confirmation_verdict(c, w)
    out["confirmed_slipknot"], out["verdict"] = ok, CONFIRMED if ok else NOT_CONFIRMED + why
    return out


def slip_candidates(path):
    """Frames whose stored (screening) knot matrix looks like a slipknot."""
    case = read_case(path)
    ana = analyze_case(case)
    return [m["frame"] for m in slipknot_scan(case, ana.time, ana.kf) if m["slipknot"]]


def core_candidates(path, confirm_dir):
    """Frames of the case file `path` whose recomputed knot matrix (in `confirm_dir`) is still
    a slipknot: their knot core goes to the check with more closures."""
    name = read_case(path).name
    return [k for k in slip_candidates(path)
            if confirmation(confirm_dir, name, k).get("recomputed_slipknot")]


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
            "case": case.name, "A": float(case.bending_a), **status_of(case),
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
            "overlap": overlap_stats(case), "runs": runs_summary(case.runs),
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


def slipknot_figure_frames(rows, most=4):
    """The frames the slipknot figure shows: the confirmed slipknots (up to `most`, largest core
    lower bound first), or else the one frame that went furthest in the search (core checked,
    then still a slipknot with more closures per subchain, then recomputed, then a candidate of
    the screen, then any screened frame; the largest K within a stage). [(row, entry)]."""
    found = [(r, m) for r in rows for m in r["matrices"]]
    confirmed = [rm for rm in found if slip_verdict(rm[1]) == CONFIRMED]
    if confirmed:
        return sorted(confirmed, key=lambda rm: -rm[1]["core_lower"])[:most]

    def rank(rm):
        m = rm[1]
        if "core_lower" in m:
            return (4, m["core_lower"])
        if "recomputed_max_K" in m:
            return (3 if m["recomputed_slipknot"] else 2, m["recomputed_max_K"])
        return (1 if m["slipknot"] else 0, m["max_K"])

    return [max(found, key=rank)] if found else []


def _shown_matrix(r, m, confirm_dir):
    """The knot matrix of the figure (the recomputed one when there, else the screen's), its
    knot core and a label of where it comes from."""
    path = confirm_path(confirm_dir, r["case"], m["frame"]) if confirm_dir else None
    if path and os.path.isfile(path):
        return json_matrix(_load_json(path)), m["recomputed_core"], "recomputed"
    return r["_case"].knot_matrices[m["frame"]], m["knot_core"], "screen"


#: The slipknot figure of knotflow-study --out.
SLIPKNOT_FIGURE = "candycane_slipknots.png"


def slipknot_caption(rows) -> str:
    """What the slipknot figure shows (results.md)."""
    chosen = slipknot_figure_frames(rows)
    if chosen and slip_verdict(chosen[0][1]) == CONFIRMED:
        return (f"the {len(chosen)} confirmed slipknot frame(s) with the largest core k_f: knot "
                "matrix (red circle: the knot core) and the chain with the core in red.")
    return ("no slipknot confirmed; the frame that went furthest in the search, labelled NOT "
            "CONFIRMED with the reason: knot matrix (red circle: its knot core) and the chain "
            "with the core in red.")


def plot_slipknots(rows, path, confirm_dir=None):
    """One row per frame of `slipknot_figure_frames`: its knot matrix with the knot core marked
    beside the chain in 3-D with the core's beads highlighted, titled with the verdict; None
    without a screened frame."""
    chosen = slipknot_figure_frames(rows)
    if not chosen:
        return None
    fig = plt.figure(figsize=(9.5, 4.8 * len(chosen)), constrained_layout=True)
    for k, (r, m) in enumerate(chosen):
        mat, core, source = _shown_matrix(r, m, confirm_dir)
        ax = fig.add_subplot(len(chosen), 2, 2 * k + 1)
        im = ax.imshow(np.where(np.isfinite(mat), mat, np.nan), vmin=0, vmax=1, cmap="viridis")
        if core is not None:
            ax.plot(core[1], core[0], "o", mfc="none", mec="tab:red", ms=9, mew=1.5)
        ax.set_xlabel("end bead j", fontsize=8)
        ax.set_ylabel("start bead i", fontsize=8)
        verdict = slip_verdict(m)
        if verdict == NO_CANDIDATE:
            verdict = (f"no candidate: max K = {m['max_K']:.2f}, whole k_f = "
                       f"{m['whole_kf']:.2f}")
        head = ("SLIPKNOT confirmed" if verdict == CONFIRMED else
                f"NOT CONFIRMED ({verdict.removeprefix(NOT_CONFIRMED)})")
        ax.set_title(f"{r['case']} (A = {r['A']:g}), t = {m['time']:g}: knot matrix ({source})",
                     fontsize=8)
        fig.colorbar(im, ax=ax, shrink=0.8, label="K(i, j)")
        ax3 = fig.add_subplot(len(chosen), 2, 2 * k + 2, projection="3d")
        lines = [head]
        if "core_kf" in m:
            lines.append(f"core {core[0]}-{core[1]}: k_f = {m['core_kf']:.3f} +- "
                         f"{m['core_se']:.3f} ({m['core_closures']} closures)")
            lines.append(f"whole chain: k_f = {m['check_whole_kf']:.3f} +- "
                         f"{m['check_whole_se']:.3f}")
        elif core is not None:
            lines.append(f"core {core[0]}-{core[1]} (red), whole k_f = {m['whole_kf']:.2f}")
        elif m["knot_core"] is not None:     # recomputed without a core: the screen's
            core = m["knot_core"]
            ax.plot(core[1], core[0], "o", mfc="none", mec="tab:red", ms=9, mew=1.5)
            lines.append(f"screen core {core[0]}-{core[1]} (red): K {m['max_K']:.2f}; "
                         f"recomputed max K {m['recomputed_max_K']:.2f}")
        _draw_chain(ax3, r["_case"].positions[m["frame"]], core=core)
        ax3.set_title("\n".join(lines), fontsize=8, color="k" if verdict == CONFIRMED
                      else "tab:red")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


# ------------------------------------------------------------------------------------------- tables

def _f(v, spec=".2f"):
    return "-" if v is None else format(v, spec)


def _star(row) -> str:
    """'*' after a case that has not finished (its result may still change)."""
    return "" if finished(row) else "*"


def _utk(row) -> str:
    return "U->K" if row["unknot_then_knot"] else "-"


def reknot_totals(rows) -> dict:
    """Re-knottings of a trefoil sweep: events, simulations with at least one, cases, finished."""
    counts = [reknottings(r["events"]) for r in rows]
    return {"events": sum(counts), "simulations": sum(c > 0 for c in counts),
            "cases": len(rows), "finished": sum(finished(r) for r in rows)}


def _finished_line(rows, of=None) -> str:
    of = len(rows) if of is None else of
    text = f"{sum(finished(r) for r in rows)} of {of} cases finished"
    if len(rows) != of:
        text += f" ({len(rows)} present)"
    if all(finished(r) for r in rows):
        return text + "."
    return text + ("; a case not finished is marked (`*` in a grid, its status and the time "
                   "reached in a table): its results may still change.")


def _reknot_line(tot) -> str:
    return (f"Unknot-then-knot events (re-knottings: knot events after an untying): "
            f"{tot['events']} in {tot['simulations']} of {tot['cases']} simulations (the study: "
            f"{STUDY_REKNOT_EVENTS} in {STUDY_REKNOT_SIMULATIONS} of {STUDY_TREFOIL_CASES}).")


def trefoil_tables(rows):
    a_vals = sorted({r["A"] for r in rows})
    o_vals = sorted({r["orientation"] for r in rows})
    by = {(r["A"], r["orientation"]): r for r in rows}
    out = ["### Unknot-then-knot transitions, ours vs the study (Table 2)", "",
           _finished_line(rows, STUDY_TREFOIL_CASES), "",
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
            ours = _utk(r)
            study = "U->K" if r["study_transition"] else "-"
            total += 1
            agree += ours == study
            cell = f"{ours}{_star(r)} / {study}"
            cells.append(cell if ours == study else f"**{cell}**")
        out.append(f"| {a:g} | " + " | ".join(cells) + " |")
    out += ["", f"Agreement: {agree} of {total} cases.", "", _reknot_line(reknot_totals(rows)), "",
            "### Every trefoil case", "",
            "| case | status | k_f(0) | events (time) | re-knottings | final k_f | final state | "
            "mode | study U->K |",
            "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ev = ", ".join(f"{k} {t:g}" for k, t in r["events"]) or "none"
        out.append(f"| {r['case']} | {status_text(r)} | {r['kf0']:.2f} | {ev} | "
                   f"{reknottings(r['events'])} | {r['final_kf']:.2f} | {r['final_state']} | "
                   f"{r['mode']} | {'yes' if r['study_transition'] else 'no'} |")
    return out, agree, total


def overlap_table(rows) -> list:
    """Overlap statistics under BWE of every case (the run diagnostics' totals)."""
    out = ["| case | status | overlap episodes | mean duration | max duration | "
           "max overlapping pairs | min distance | strand passages |",
           "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        d = r["overlap"]
        if d is None:
            out.append(f"| {r['case']} | {status_text(r)} | not recorded | | | | | |")
            continue
        out.append(f"| {r['case']} | {status_text(r)} | {d.get('overlap_episodes', '-')} | "
                   f"{_f(d.get('overlap_mean_duration'), '.2f')} | "
                   f"{_f(d.get('overlap_max_duration'), '.2f')} | "
                   f"{d.get('max_overlapping_pairs', '-')} | {_f(d.get('min_distance'), '.4f')} | "
                   f"{d.get('strand_passages', '-')} |")
    if any(r["overlap"] and r["overlap"]["source"] == "checkpoint" for r in rows):
        out += ["", "A case not finished: its totals from the state in its newest checkpoint "
                "(the frames read)."]
    return out


def _hours(seconds, unknown=0) -> str:
    return f"{seconds / 3600:.2f} h" + (f" (+ {unknown} segment(s) not recorded)" if unknown else "")


def runs_table(rows) -> list:
    """Run records of every case (commit, wall time, time-weighted mean load, segments) and
    the sum over the cases with records."""
    out = ["| case | status | commit(s) | total wall time | mean load (time-weighted) | segments |",
           "|---|---|---|---|---|---|"]
    recorded = [r["runs"] for r in rows if r["runs"] is not None]
    for r in rows:
        s = r["runs"]
        if s is None:
            out.append(f"| {r['case']} | {status_text(r)} | not recorded | | | |")
            continue
        out.append(f"| {r['case']} | {status_text(r)} | {', '.join(s['commits'])} | "
                   f"{_hours(s['wall_seconds'], s['wall_unknown'])} | "
                   f"{_f(s['mean_load'], '.2f')} | "
                   f"{s['segments']} |")
    if recorded:
        weight = sum(s["load_seconds"] for s in recorded)
        load = (sum(s["mean_load"] * s["load_seconds"] for s in recorded if s["mean_load"] is not None)
                / weight) if weight > 0 else None
        wall = _hours(sum(s["wall_seconds"] for s in recorded),
                      sum(s["wall_unknown"] for s in recorded))
        out.append(f"| all ({len(recorded)} of {len(rows)} cases recorded) | | | {wall} | "
                   f"{_f(load, '.2f')} | "
                   f"{sum(s['segments'] for s in recorded)} |")
    return out


def sweep_records(rows) -> list:
    """The overlap statistics and run records sections of a sweep."""
    return (["#### Overlap statistics under BWE", ""] + overlap_table(rows)
            + ["", "#### Runs", ""] + runs_table(rows) + [""])


def close_pair_ratio(rows, key="close_pairs_mean"):
    """Mean of `key` over the cases with A = 1 over that with A = 3 (None without either or
    with none at A = 3)."""
    a1 = [r[key] for r in rows if abs(r["A"] - 1.0) < 1e-9]
    a3 = [r[key] for r in rows if abs(r["A"] - 3.0) < 1e-9]
    if not (a1 and a3) or np.mean(a3) <= 0:
        return None
    return float(np.mean(a1) / np.mean(a3))


def candycane_tables(rows):
    out = ["### Candy-cane cases (late = second half of the frames read)", "",
           _finished_line(rows), "",
           "| A | status | close pairs (mean, all t) | close pairs (late) | R_g (late) | "
           "a, b, c (late) | mean abs cos theta (late) | frames in mode I / II (late) | "
           "case mode | max k_f | mean k_f |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(
            f"| {r['A']:g} | {status_text(r)} | {r['close_pairs_mean']:.2f} | "
            f"{r['close_pairs_late']:.2f} | "
            f"{r['rg_late']:.2f} | {r['a_late']:.1f}, {r['b_late']:.1f}, {r['c_late']:.1f} | "
            f"{r['abs_cos_theta_late']:.2f} | {_f(r['mode_I_late'])} / {_f(r['mode_II_late'])} | "
            f"{r['case_mode']} | {r['max_kf']:.3f} | {r['mean_kf']:.4f} |")
    ratio, ratio_late = close_pair_ratio(rows), close_pair_ratio(rows, "close_pairs_late")
    if ratio is not None:
        out += ["", f"Close pairs A = 1 / A = 3: {ratio:.1f} (whole run), "
                f"{_f(ratio_late, '.1f')} (late)."]
    return out + [""] + slipknot_tables(rows)


def slipknot_tables(rows) -> list:
    """The slipknot search of the candy-canes: the screen per case, then every candidate
    recomputed with its confirmation (docs/analysis.md, "Slipknot confirmation")."""
    out = ["### Knot matrices (slipknot search)", "",
           f"Slipknot: some K(i, j) >= {SLIP_K} while the whole chain has k_f < {SLIP_WHOLE}. "
           "Screening (scripts/reproduce.sh): 20 closures per subchain on the frames of "
           "`knotflow-study --select-frames` (every 50th frame, or every T time units with "
           "--every-time T, the last and the 5 most entangled frames); candidates recomputed "
           "with 100 closures per subchain; where that is still a slipknot, its knot core "
           "(shortest subchain with K >= 0.5) and the whole chain are checked with 1000 "
           f"closures: confirmed when the core's k_f exceeds {SLIP_K} and the whole chain's is "
           f"below {SLIP_WHOLE}, each at the one-sided level {CONFIRM_ALPHA:g} (exact binomial "
           "bounds, docs/analysis.md; with {1} closures: at least {0[0]} knotted closures of "
           "the core, at most {0[1]} of the whole chain).".format(
               confirm_counts(CONFIRM_CLOSURES), CONFIRM_CLOSURES), "",
           "| A | frames screened | frames with max K >= 0.5 | candidates (t) | "
           "largest K in the screen (t, whole k_f, core) | recomputed | still slipknots | "
           "confirmed |",
           "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ms = r["matrices"]
        if not ms:
            out.append(f"| {r['A']:g} | 0 | - | - | - | - | - | - |")
            continue
        n = _cc_numbers(r)
        best = max(ms, key=lambda m: m["max_K"])
        core = "-" if best["knot_core"] is None else f"{best['knot_core'][0]}-{best['knot_core'][1]}"
        slip_times = ", ".join(format(m["time"], "g") for m in ms if m["slipknot"]) or "none"
        out.append(f"| {r['A']:g} | {len(ms)} | {sum(m['max_K'] >= SLIP_K for m in ms)} | "
                   f"{slip_times} | {best['max_K']:.2f} (t = {best['time']:g}, "
                   f"{best['whole_kf']:.2f}, {core}) | {n['slip_recomputed']} | "
                   f"{n['slip_passed']} | {n['slip_confirmed']} |")
    checked = [(r, m) for r in rows for m in r["matrices"] if "recomputed_max_K" in m]
    if not checked:
        return out + ["", "No candidate recomputed."]
    out += ["", "Every candidate recomputed (k_f +- its binomial standard error; in brackets the "
            f"one-sided bound at level {CONFIRM_ALPHA:g}: lower for the core, upper for the "
            "whole chain):", "",
            "| A | t | frame | screen max K | 100 per subchain: max K, core, whole k_f | "
            "core k_f (1000) | whole k_f (1000) | verdict |",
            "|---|---|---|---|---|---|---|---|"]
    for r, m in checked:
        core = m["recomputed_core"]
        core = "-" if core is None else f"{core[0]}-{core[1]}"
        ck = (f"{m['core_kf']:.3f} +- {m['core_se']:.3f} [>= {m['core_lower']:.3f}]"
              if "core_kf" in m else "-")
        wk = (f"{m['check_whole_kf']:.3f} +- {m['check_whole_se']:.3f} "
              f"[<= {m['check_whole_upper']:.3f}]" if "check_whole_kf" in m else "-")
        out.append(f"| {r['A']:g} | {m['time']:g} | {m['frame']} | {m['max_K']:.2f} | "
                   f"{m['recomputed_max_K']:.2f}, {core}, {m['recomputed_whole_kf']:.3f} | "
                   f"{ck} | {wk} | {slip_verdict(m)} |")
    return out


def slip_verdict(m) -> str:
    """The state of a scan entry in the slipknot search: CONFIRMED, 'not confirmed: <why>',
    REJECTED (by the recomputed matrix), UNCHECKED (core not checked yet), NOT_RECOMPUTED (a
    candidate of the screen) or NO_CANDIDATE. An entry of an earlier results.json
    with only `confirmed_max_K` (the 100-closure recomputation, before the core check) is
    reported by that recomputation."""
    if "verdict" in m:
        return m["verdict"]
    if "confirmed_max_K" in m:
        return UNCHECKED if m.get("confirmed_slipknot") else REJECTED
    return NOT_RECOMPUTED if m["slipknot"] else NO_CANDIDATE


def ensemble_tables(rows):
    """Candy-canes with several random rotations: every case, then mean and range per A."""
    out = ["### Candy-cane ensemble (several random rotations; late = second half of the run)", "",
           _finished_line(rows), "",
           "| case | status | close pairs (all t) | close pairs (late) | R_g (late) | c (late) | "
           "mean abs cos theta (late) | mode I / II frames (late) | max k_f |",
           "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['case']} | {status_text(r)} | {r['close_pairs_mean']:.2f} | "
                   f"{r['close_pairs_late']:.2f} | "
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


# ------------------------------------------------------------------ three-column comparison

#: What the comparison needs of each case of an earlier results.json (--rpy-trefoil: its
#: "trefoil" part, --rpy-candycane: its "candycane" and "ensemble" parts).
RPY_TREFOIL_KEYS = ("case", "A", "orientation", "events", "unknot_then_knot", "final_state",
                    "mode")
RPY_CANDYCANE_KEYS = ("case", "A", "close_pairs_mean", "close_pairs_late", "case_mode", "max_kf",
                      "matrices")
RPY_ENSEMBLE_KEYS = ("case", "A", "close_pairs_mean", "close_pairs_late", "case_mode")
#: Column heads of the comparison; the middle one names this run's hydrodynamic model.
STUDY_HEAD, RPY_HEAD = "the study", "knotflow RPY + EV"


def _json_cases(path, doc, part, keys):
    """The list of cases of `part` of results.json `doc`, each holding `keys`, or a ValueError."""
    if part not in doc:
        raise ValueError(f"{path}: no \"{part}\" part (a knotflow-study results.json of that sweep "
                         "is needed)")
    cases = doc[part]["cases"] if part == "trefoil" and isinstance(doc[part], dict) \
        and "cases" in doc[part] else doc[part]
    if not isinstance(cases, list) or not cases:
        raise ValueError(f"{path}: the \"{part}\" part holds no cases")
    for k, c in enumerate(cases):
        missing = [key for key in keys if not isinstance(c, dict) or key not in c]
        if missing:
            raise ValueError(f"{path}: \"{part}\" case {k}: no " + ", ".join(missing))
    return cases


def load_rpy(path, parts):
    """The parts (a tuple of "trefoil", "candycane", "ensemble") of the results.json at `path`
    as {part: list of cases}; a ValueError (one line) names the file and the problem when it is
    missing, unreadable, not JSON or lacks a part or a needed value."""
    keys = {"trefoil": RPY_TREFOIL_KEYS, "candycane": RPY_CANDYCANE_KEYS,
            "ensemble": RPY_ENSEMBLE_KEYS}
    if not os.path.isfile(path):
        raise ValueError(f"{path}: no such file")
    try:
        with open(path, encoding="utf-8") as fh:
            doc = json.load(fh)
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: cannot read: {exc}") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not JSON: {exc}") from None
    if not isinstance(doc, dict):
        raise ValueError(f"{path}: not a knotflow-study results.json (no object at the top)")
    return {part: _json_cases(path, doc, part, keys[part]) for part in parts}


def model_head(rows) -> str:
    """'knotflow <model>' for the hydrodynamic model(s) of this run's cases."""
    return "knotflow " + "/".join(sorted({str(r.get("model", "?")) for r in rows}))


def _row3(label, study, ours, rpy) -> str:
    return f"| {label} | {study} | {ours} | {rpy} |"


def _head3(first, ours_head) -> list:
    return [f"| {first} | {STUDY_HEAD} | {ours_head} | {RPY_HEAD} |", "|---|---|---|---|"]


def _bold_if(text, differs) -> str:
    return f"**{text}**" if differs else text


def _summary(rows) -> dict:
    """Counts of one model's trefoil cases: agreement, re-knottings, final states, modes."""
    tot = reknot_totals(rows)
    stiff = [r for r in rows if r["A"] >= STUDY_STIFF_A - 1e-9]
    return {**tot, "agree": sum(_utk(r) == ("U->K" if _in_study(r["A"], r["orientation"]) else "-")
                                for r in rows),
            "final_states": {s: sum(r["final_state"] == s for r in rows)
                             for s in ("knotted", "unknotted", "undecided")},
            "modes": {m: sum(r["mode"] == m for r in rows) for m in ("I", "II", "-", "?")},
            "stiff_mode_II": [sum(r["mode"] == "II" for r in stiff), len(stiff)]}


def trefoil_comparison(rows, rpy):
    """Markdown lines and the "comparison" part of the trefoils: the study, this run (rows) and
    the RPY + EV cases of an earlier results.json (rpy)."""
    head = model_head(rows)
    ours = {_key(r["A"], r["orientation"]): r for r in rows}
    theirs = {_key(r["A"], r["orientation"]): r for r in rpy}
    keys = sorted(set(ours) | set(theirs), key=lambda k: (k[1], k[0]))
    a_vals = sorted({k[1] for k in keys})
    o_vals = sorted({k[0] for k in keys})
    cells = []
    for o, a in keys:
        study = "U->K" if _in_study(a, o) else "-"
        cells.append({"A": a, "orientation": o, "study": study,
                      "ours": _utk(ours[o, a]) if (o, a) in ours else None,
                      "ours_finished": finished(ours[o, a]) if (o, a) in ours else None,
                      "rpy": _utk(theirs[o, a]) if (o, a) in theirs else None})
    by = {(c["A"], c["orientation"]): c for c in cells}
    out = ["### The study, " + head + " and " + RPY_HEAD + ": Table 2", "",
           f"{head}: " + _finished_line(rows, STUDY_TREFOIL_CASES), "",
           f"Cell: {STUDY_HEAD} / {head} / {RPY_HEAD}; `U->K` an unknot-then-knot transition, "
           "`-` none, `?` not run; **bold** where a model differs from the study.", "",
           "| A | " + " | ".join(o_vals) + " |", "|---|" + "---|" * len(o_vals)]
    for a in a_vals:
        line = []
        for o in o_vals:
            c = by.get((a, o))
            if c is None:
                line.append(" ")
                continue
            mine = "?" if c["ours"] is None else c["ours"] + ("" if c["ours_finished"] else "*")
            other = "?" if c["rpy"] is None else c["rpy"]
            line.append(" / ".join([c["study"],
                                    _bold_if(mine, c["ours"] not in (None, c["study"])),
                                    _bold_if(other, c["rpy"] not in (None, c["study"]))]))
        out.append(f"| {a:g} | " + " | ".join(line) + " |")
    sm, sr = _summary(rows), _summary(rpy)

    def states(s):
        f = s["final_states"]
        return f"{f['knotted']} / {f['unknotted']} / {f['undecided']}"

    def modes(s):
        m = s["modes"]
        return f"{m['I']} / {m['II']} / {m['-']}" + (f" (? {m['?']})" if m["?"] else "")

    out += ["", *_head3("", head),
            _row3("cases finished", STUDY_TREFOIL_CASES,
                  f"{sm['finished']} of {STUDY_TREFOIL_CASES}", f"{sr['finished']} of {sr['cases']}"),
            _row3("cells agreeing with the study", "-", f"{sm['agree']} of {sm['cases']}",
                  f"{sr['agree']} of {sr['cases']}"),
            _row3("unknot-then-knot events", STUDY_REKNOT_EVENTS, sm["events"], sr["events"]),
            _row3("simulations with one or more",
                  f"{STUDY_REKNOT_SIMULATIONS} of {STUDY_TREFOIL_CASES}",
                  f"{sm['simulations']} of {sm['cases']}", f"{sr['simulations']} of {sr['cases']}"),
            _row3("final state knotted / unknotted / undecided", "not stated", states(sm),
                  states(sr)),
            _row3("case mode I / II / neither", "not stated", modes(sm), modes(sr)),
            _row3(f"stiff trefoils (A >= {STUDY_STIFF_A:g}) in mode II", STUDY_STIFF_MODE,
                  "{} of {}".format(*sm["stiff_mode_II"]), "{} of {}".format(*sr["stiff_mode_II"])),
            "", "Every case:", "",
            f"| case | status ({head}) | study U->K | {head}: events | re-knottings | final state "
            f"| mode | {RPY_HEAD}: events | re-knottings | final state | mode |",
            "|---|---|---|---|---|---|---|---|---|---|---|"]
    for o, a in keys:
        r, q = ours.get((o, a)), theirs.get((o, a))
        name = (r or q)["case"]

        def part(x):
            if x is None:
                return "not run | | |"
            ev = ", ".join(f"{k} {t:g}" for k, t in x["events"]) or "none"
            return f"{ev} | {reknottings(x['events'])} | {x['final_state']} | {x['mode']} |"

        out.append(f"| {name} | {'-' if r is None else status_text(r)} | "
                   f"{'yes' if _in_study(a, o) else 'no'} | {part(r)} {part(q)}")
    doc = {"columns": [STUDY_HEAD, head, RPY_HEAD], "cells": cells,
           "study": {"cases": STUDY_TREFOIL_CASES, "events": STUDY_REKNOT_EVENTS,
                     "simulations": STUDY_REKNOT_SIMULATIONS,
                     "transitions": sorted([o, a] for o, a in STUDY_TRANSITIONS),
                     "stiff_mode": STUDY_STIFF_MODE},
           "ours": sm, "rpy": sr}
    return out, doc


def _by_a(rows, a):
    return [r for r in rows if abs(r["A"] - a) < 1e-9]


def _cc_numbers(r) -> dict:
    """What the candy-cane comparison takes of one case (a row here or of a results.json)."""
    ms = r["matrices"]
    return {"case": r["case"], "status": r.get("status", "finished"),
            "t_reached": r.get("t_reached", r.get("t_end")), "t_end": r.get("t_end"),
            "case_mode": r["case_mode"], "close_pairs_mean": r["close_pairs_mean"],
            "close_pairs_late": r["close_pairs_late"], "max_kf": r["max_kf"],
            "frames_screened": len(ms), "slip_candidates": sum(m["slipknot"] for m in ms),
            "slip_recomputed": sum("recomputed_max_K" in m or "confirmed_max_K" in m for m in ms),
            "slip_passed": sum(slip_verdict(m) not in (NO_CANDIDATE, NOT_RECOMPUTED, REJECTED)
                               for m in ms),
            "slip_confirmed": sum(slip_verdict(m) == CONFIRMED for m in ms)}


def _slip_text(n) -> str:
    if not n["frames_screened"]:
        return "none screened"
    if not n["slip_recomputed"]:
        return f"{n['slip_candidates']} candidates, none recomputed ({n['frames_screened']} frames)"
    return (f"{n['slip_candidates']} candidates, {n['slip_recomputed']} recomputed, "
            f"{n.get('slip_passed', 0)} still slipknots, {n['slip_confirmed']} confirmed "
            f"({n['frames_screened']} frames)")


def _mode_counts(rows) -> dict:
    return {m: sum(r["case_mode"] == m for r in rows) for m in ("I", "II", "-", "?")}


def _mode_text(counts) -> str:
    return (f"{counts['I']} / {counts['II']} / {counts['-']}"
            + (f" (? {counts['?']})" if counts["?"] else ""))


def candycane_comparison(rows, ensemble, rpy):
    """Markdown lines and the "comparison" part of the candy-canes: the study, this run (rows,
    ensemble: the --ensemble cases or []) and the RPY + EV cases of an earlier results.json
    (rpy: its "candycane" and "ensemble" lists)."""
    head = model_head(rows)
    r_cc, r_en = rpy["candycane"], rpy["ensemble"]
    a_vals = sorted({round(float(a), 6) for a in STUDY_CANDYCANE_A}
                    | {round(r["A"], 6) for r in rows + r_cc})
    out = ["### The study, " + head + " and " + RPY_HEAD + ": candy-canes", "",
           f"{head}: " + _finished_line(rows) + " Several cases of one A are listed in turn; "
           "late = second half of the frames read.", "", *_head3("A: quantity", head)]

    def join(ns, fmt):
        return ", ".join(fmt(n) for n in ns) or "not run"

    per_a = []
    for a in a_vals:
        g = [_cc_numbers(r) for r in _by_a(rows, a)]
        q = [_cc_numbers(r) for r in _by_a(r_cc, a)]
        study = {"case_mode": STUDY_CANDYCANE_MODES.get(a),
                 "slipknot": "found" if any(abs(a - x) < 1e-9 for x in STUDY_SLIPKNOT_A) else None,
                 "whole_kf": STUDY_WHOLE_KF}
        entry = {"A": a, "study": study, "ours": g, "rpy": q}
        items = [
            ("status", "-", join(g, status_text), join(q, status_text)),
            ("case mode", study["case_mode"] or "not stated", join(g, lambda n: n["case_mode"]),
             join(q, lambda n: n["case_mode"])),
            ("close pairs, mean over all t", "not stated",
             join(g, lambda n: f"{n['close_pairs_mean']:.2f}"),
             join(q, lambda n: f"{n['close_pairs_mean']:.2f}")),
            ("close pairs, mean over late t", "not stated",
             join(g, lambda n: f"{n['close_pairs_late']:.2f}"),
             join(q, lambda n: f"{n['close_pairs_late']:.2f}")),
            ("whole-chain max k_f", STUDY_WHOLE_KF, join(g, lambda n: f"{n['max_kf']:.3f}"),
             join(q, lambda n: f"{n['max_kf']:.3f}")),
            ("slipknots", study["slipknot"] or "not stated", join(g, _slip_text),
             join(q, _slip_text)),
        ]
        if _by_a(ensemble, a) or _by_a(r_en, a):
            entry["ours_rotations_modes"] = _mode_counts(_by_a(ensemble, a)) if ensemble else None
            entry["rpy_rotations_modes"] = _mode_counts(_by_a(r_en, a))
            items.append(("rotations: case mode I / II / neither", "-",
                          _mode_text(entry["ours_rotations_modes"]) if ensemble else "not run",
                          _mode_text(entry["rpy_rotations_modes"])))
        out += [_row3(f"{a:g}: {label}", s, m, r) for label, s, m, r in items]
        per_a.append(entry)
    ratios = {"all_t": [close_pair_ratio(rows), close_pair_ratio(r_cc)],
              "late_t": [close_pair_ratio(rows, "close_pairs_late"),
                         close_pair_ratio(r_cc, "close_pairs_late")],
              "rotations_all_t": [close_pair_ratio(ensemble) if ensemble else None,
                                  close_pair_ratio(r_en)]}
    labels = {"all_t": "all t", "late_t": "late t", "rotations_all_t": "all t, mean over rotations"}
    for k, (m, r) in ratios.items():
        mine = "not run" if k == "rotations_all_t" and not ensemble else _f(m, ".1f")
        out.append(_row3(f"close pairs A = 1 / A = 3, {labels[k]}", STUDY_CLOSE_PAIR_RATIO,
                         mine, _f(r, ".1f")))
    doc = {"columns": [STUDY_HEAD, head, RPY_HEAD], "per_A": per_a,
           "close_pair_ratio": {k: {"study": STUDY_CLOSE_PAIR_RATIO, "ours": m, "rpy": r}
                                for k, (m, r) in ratios.items()}}
    return out, doc


# ------------------------------------------------------------------------ per-frame CSV files

def write_trefoil_csv(rows, path):
    """trefoil_kf.csv: case, t, k_f (one line per case and frame with k_f)."""
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("case,t,k_f\n")
        for r in rows:
            for t, k in zip(r["time"], r["kf"]):
                fh.write(f"{r['case']},{t:.6g},{k:.4g}\n")
    return path


CANDYCANE_CSV = ("rg", "a", "b", "c", "theta", "phi", "close_pairs")


def write_candycane_csv(rows, path):
    """candycane_shape.csv: case, t, R_g, a, b, c, theta, phi, close_pairs, k_f (one line per
    case and frame; k_f empty on a frame without it)."""
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("case,t,R_g,a,b,c,theta,phi,close_pairs,k_f\n")
        for r in rows:
            case, ana = r["_case"], r["_ana"]
            kf = dict(zip((int(k) for k in ana.frame_index), ana.kf))
            o = ana.observables
            for k, t in enumerate(case.time):
                vals = ",".join(f"{float(o[name][k]):.6g}" for name in CANDYCANE_CSV)
                kk = f"{kf[k]:.4g}" if k in kf else ""
                fh.write(f"{r['case']},{t:.6g},{vals},{kk}\n")
    return path


def _public(rows, drop=("time", "kf")):
    return [{k: v for k, v in r.items() if not k.startswith("_") and k not in drop} for r in rows]


def no_case_files(directory) -> str:
    """The line of results.md for a sweep directory without case files."""
    return f"no case files in {directory}"


def write_study(trefoil_dir, candycane_dir, out, closures=200, ensemble_dir=None,
                rpy_trefoil=None, rpy_candycane=None):
    """Write figures, results.md, results.json and the per-frame CSV files into `out`.
    rpy_trefoil, rpy_candycane: `load_rpy` of earlier RPY + EV results (or None): three-column
    comparison tables and a "comparison" part in results.json. A sweep directory without case
    files gets the line `no_case_files` in its section (and in results.json under "missing")
    and nothing else."""
    confirm_dir = os.path.join(out, "confirm")
    os.makedirs(out, exist_ok=True)
    md = ["# knotflow-study: generated results", "",
          f"Trefoil sweep: `{trefoil_dir}`; candy-cane sweep: `{candycane_dir}`.", ""]
    result = {}
    comparison = {}
    files = {d: find_case_files(d) for d in (trefoil_dir, candycane_dir, ensemble_dir) if d}
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
        result["trefoil"] = {"agree": agree, "total": total, "reknottings": reknot_totals(rows),
                             "cases": _public(rows)}
    if candycane_dir and not files[candycane_dir]:
        md += ["## Candy-cane", "", no_case_files(candycane_dir), ""]
    elif candycane_dir:
        rows = candycane_rows(files[candycane_dir], closures, confirm_dir)
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
        md += ["## Candy-cane ensemble", ""] + ensemble_tables(ensemble) + [""]
        md += sweep_records(ensemble)
        result["ensemble"] = _public(ensemble)
    if comparison:
        result["comparison"] = comparison
    with open(os.path.join(out, "results.md"), "w", encoding="utf-8") as fh:
        fh.write("\n".join(md) + "\n")
    with open(os.path.join(out, "results.json"), "w", encoding="utf-8") as fh:
        json.dump(result, fh, indent=1)
    return result


def write_frame(path, frame, xyz, core_of=None) -> None:
    """Frame `frame` of case file `path` as a coordinate file `xyz` (knotflow-study
    --write-frame); with `core_of` (a knotflow-analyze --matrix --json file of that frame) only
    the beads i..j of its knot core."""
    case = read_case(path)
    r = case.positions[frame]
    comment = f"{case.name} frame {frame} t = {case.time[frame]:g}"
    if core_of is not None:
        core = _load_json(core_of).get("knot_core")
        if not core:
            raise ValueError(f"{core_of}: no knot core (knot_core is null)")
        i, j = int(core[0]), int(core[1])
        if not 0 <= i < j < len(r):
            raise ValueError(f"{core_of}: knot core [{i}, {j}] outside the {len(r)} beads of "
                             f"{path} frame {frame}")
        r, comment = r[i:j + 1], comment + f" beads {i}-{j} (knot core)"
    write_xyz(xyz, r, comment=comment)
