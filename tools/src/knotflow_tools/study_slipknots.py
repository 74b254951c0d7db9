"""The slipknot search of knotflow-study: the screen of the stored knot matrices, the
confirmation of a candidate (its recomputed matrix, then its knot core and the whole chain with
more closures, judged by exact binomial bounds: docs/analysis.md, "Slipknot confirmation"),
and the slipknot table and figure of results.md."""

from __future__ import annotations

import json
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import knotflow  # noqa: E402

from .analysis import analyze_case  # noqa: E402
from .atomic import save_figure  # noqa: E402
from .campaign import load_case  # noqa: E402
from .plot import _draw_chain  # noqa: E402

#: Slipknot threshold on the knot matrix and whole-chain threshold (docs/analysis.md).
SLIP_K, SLIP_WHOLE = 0.5, 0.1


def slipknot_scan(case, kf_time, kf, confirm_dir=None):
    """Per stored knot matrix: whole-chain k_f at that frame, max K, knot core, slipknot flag.

    The matrices of the scan use few closures per subchain (20), so their largest entry over
    ~10^4 subchains is biased upwards: a frame flagged here is a candidate. Where `confirm_dir`
    holds the files of its confirmation (`confirmation`) their numbers are added."""
    out = []
    for frame, mat in sorted(case.knot_matrices.items()):
        t = float(case.time[frame])
        kw = float(np.interp(t, kf_time, kf)) if len(kf) else float("nan")
        kmax, core = max_and_core(mat)
        entry = {"frame": int(frame), "time": t, "whole_kf": kw, "max_K": kmax,
                 "knot_core": core, "slipknot": bool(kmax >= SLIP_K and kw < SLIP_WHOLE)}
        if confirm_dir:
            entry.update(confirmation(confirm_dir, getattr(case, "name", "case"), frame))
        out.append(entry)
    return out


def max_and_core(mat):
    """Largest finite entry of a knot matrix (-1 without one) and its knot core ([i, j], the
    shortest subchain with K >= 0.5 (SLIP_K), smallest i on a tie: the library's knot_core,
    kf_knot_matrix; None without one)."""
    finite = np.where(np.isfinite(mat), mat, -1.0)
    core = knotflow.knot_core(finite)
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


def load_json(path):
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
    d = load_json(path)
    kmax, core = max_and_core(json_matrix(d))
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
    est = [load_json(p) for p in parts]
    c, w = (kf_estimate(float(e["kf"]), int(e["closures"])) for e in est)
    out.update({f"core_{k}": v for k, v in c.items()})
    out["core_beads"] = core
    out.update({f"check_whole_{k}": v for k, v in w.items()})
    ok, why = confirmation_verdict(c, w)
    out["confirmed_slipknot"], out["verdict"] = ok, CONFIRMED if ok else NOT_CONFIRMED + why
    return out


def slip_candidates(path, matrices_dir=None):
    """Frames whose stored (screening) knot matrix looks like a slipknot (a ledger entry's: in
    `matrices_dir`)."""
    case = load_case(path, matrices_dir)
    ana = analyze_case(case)
    return [m["frame"] for m in slipknot_scan(case, ana.time, ana.kf) if m["slipknot"]]


def core_candidates(path, confirm_dir, matrices_dir=None):
    """Frames of the case `path` whose recomputed knot matrix (in `confirm_dir`) is still
    a slipknot: their knot core goes to the check with more closures."""
    name = load_case(path, matrices_dir).name
    return [k for k in slip_candidates(path, matrices_dir)
            if confirmation(confirm_dir, name, k).get("recomputed_slipknot")]


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


def slip_counts(matrices) -> dict:
    """The slipknot search of one case in numbers (its scan entries `matrices`, of a row here or
    of an earlier results.json): frames screened, candidates of the screen, recomputed, still
    slipknots after the recomputation, confirmed."""
    ms = matrices
    return {"frames_screened": len(ms), "slip_candidates": sum(m["slipknot"] for m in ms),
            "slip_recomputed": sum("recomputed_max_K" in m or "confirmed_max_K" in m for m in ms),
            "slip_passed": sum(slip_verdict(m) not in (NO_CANDIDATE, NOT_RECOMPUTED, REJECTED)
                               for m in ms),
            "slip_confirmed": sum(slip_verdict(m) == CONFIRMED for m in ms)}


# ------------------------------------------------------------------ table and figure

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
        n = slip_counts(ms)
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
        return json_matrix(load_json(path)), m["recomputed_core"], "recomputed"
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
    save_figure(fig, path, dpi=100)
    plt.close(fig)
    return path
