"""The study's questions as statistics over samples (issue 36): Table 2 as probabilities of an
unknot-then-knot transition per cell, scored against the study's table and the trivial "never"
predictor, and the candy-cane's modes per bending stiffness over ensembles of starts.

Intervals are exact (Clopper-Pearson) for proportions of cases; a fraction of frames is averaged
per case first (frames of one trajectory are correlated) and its interval is a percentile
bootstrap over the cases with a recorded seed. Every function takes the rows of `study_rows`
(`trefoil_rows`, `candycane_rows`), so a sweep of case files and a sweep of a case ledger give
the same numbers.
"""

from __future__ import annotations

import math

import numpy as np

from .study_reference import in_study
from .study_rows import late_mask

#: The confidence level of every interval here.
LEVEL = 0.95
#: Bootstrap resamples and their seed (recorded in the output).
BOOTSTRAP_SAMPLES, BOOTSTRAP_SEED = 10000, 20261205


def binomial_cdf(k: int, n: int, p: float) -> float:
    """P(X <= k) for X ~ Binomial(n, p), summed exactly in log space."""
    if k < 0:
        return 0.0
    if k >= n:
        return 1.0
    if p <= 0.0:
        return 1.0
    if p >= 1.0:
        return 0.0
    logs = [math.lgamma(n + 1) - math.lgamma(i + 1) - math.lgamma(n - i + 1)
            + i * math.log(p) + (n - i) * math.log1p(-p) for i in range(k + 1)]
    top = max(logs)
    return min(1.0, math.exp(top) * sum(math.exp(x - top) for x in logs))


def _bisect(f, lo=0.0, hi=1.0, iterations=200) -> float:
    """The root of a function increasing from f(lo) < 0 to f(hi) > 0."""
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        if f(mid) < 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def clopper_pearson(k: int, n: int, level: float = LEVEL) -> tuple[float, float]:
    """The exact (Clopper-Pearson) interval of a binomial proportion k/n: the lower end is the p
    with P(X >= k | p) = (1 - level)/2 (0 when k = 0), the upper the p with
    P(X <= k | p) = (1 - level)/2 (1 when k = n)."""
    if not (0 <= k <= n and n >= 1):
        raise ValueError(f"need 0 <= k <= n and n >= 1 (got k = {k}, n = {n})")
    alpha = 0.5 * (1.0 - level)
    lo = 0.0 if k == 0 else _bisect(lambda p: (1.0 - binomial_cdf(k - 1, n, p)) - alpha)
    hi = 1.0 if k == n else _bisect(lambda p: alpha - binomial_cdf(k, n, p))
    return lo, hi


def bootstrap_mean_interval(values, level: float = LEVEL, samples: int = BOOTSTRAP_SAMPLES,
                            seed: int = BOOTSTRAP_SEED) -> tuple[float, float]:
    """Percentile bootstrap interval of the mean of `values` (one value per case)."""
    v = np.asarray(values, dtype=float)
    if v.size == 0:
        return math.nan, math.nan
    rng = np.random.default_rng(seed)
    means = v[rng.integers(0, v.size, size=(samples, v.size))].mean(axis=1)
    q = 0.5 * (1.0 - level)
    return float(np.quantile(means, q)), float(np.quantile(means, 1.0 - q))


# ----------------------------------------------------------------------- Table 2 as probabilities

def cell_probabilities(rows) -> list:
    """Per cell (A, orientation) of the trefoil samples: the samples, those with an
    unknot-then-knot transition, the probability with its exact interval, the untie and
    re-knot times of the samples, how long each first re-knotting held ("held": [time, lasted
    to the end], in the order of the re-knot times; rows of an older results.json without it
    give none), the samples whose final state is knotted, and what Table 2 says. Only finished
    samples count."""
    cells: dict = {}
    for r in rows:
        if r.get("status", "finished") != "finished":
            continue
        cells.setdefault((round(float(r["A"]), 6), str(r["orientation"])), []).append(r)
    out = []
    for (a, o), g in sorted(cells.items()):
        k = sum(bool(r["unknot_then_knot"]) for r in g)
        lo, hi = clopper_pearson(k, len(g))
        out.append({"A": a, "orientation": o, "samples": len(g), "transitions": k,
                    "probability": k / len(g), "interval": [lo, hi],
                    "t_unknot": sorted(r["t_unknot"] for r in g if r["t_unknot"] is not None),
                    "t_reknot": sorted(r["t_reknot"] for r in g if r["t_reknot"] is not None),
                    "never_untied": sum(r["t_unknot"] is None for r in g),
                    "held": [[h, lasted] for _t, h, lasted in sorted(
                        (r["t_reknot"], r["reknot_held"], bool(r["reknot_lasted"])) for r in g
                        if r.get("reknot_held") is not None)],
                    "ends_knotted": sum(r.get("final_state") == "knotted" for r in g),
                    "study": in_study(a, o), "uncertain": 0 < k < len(g)})
    return out


def brier_score(cells, forecast) -> float:
    """The Brier score (mean squared difference between forecast probability and outcome, over
    every sample of every cell; 0 is perfect) of `forecast(cell) -> probability`."""
    total, count = 0.0, 0
    for c in cells:
        f = float(forecast(c))
        total += c["transitions"] * (f - 1.0) ** 2 + (c["samples"] - c["transitions"]) * f ** 2
        count += c["samples"]
    return total / count if count else math.nan


def log_score(cells, forecast, floor: float = 0.01) -> float:
    """Mean log-likelihood per sample of the outcomes under `forecast(cell) -> probability`, the
    probabilities kept in [floor, 1 - floor] (a forecast of 0 or 1 that is contradicted once
    would otherwise score minus infinity). Higher is better."""
    total, count = 0.0, 0
    for c in cells:
        f = min(max(float(forecast(c)), floor), 1.0 - floor)
        total += c["transitions"] * math.log(f) + (c["samples"] - c["transitions"]) * math.log1p(-f)
        count += c["samples"]
    return total / count if count else math.nan


def table2_scores(cells, floor: float = 0.01) -> dict:
    """Table 2 (a transition where the study saw one, none elsewhere) and the trivial predictor
    'never a transition' scored on the samples with the Brier and the floored log score."""
    def study(c):
        return 1.0 if c["study"] else 0.0

    def never(c):
        return 0.0
    return {"brier": {"table2": brier_score(cells, study), "never": brier_score(cells, never)},
            "log": {"table2": log_score(cells, study, floor), "never": log_score(cells, never, floor),
                    "floor": floor},
            "samples": sum(c["samples"] for c in cells), "cells": len(cells)}


def probability_table(cells, scores) -> list:
    """Markdown of Table 2 as probabilities and its scores."""
    def times(ts):
        return ", ".join(f"{t:g}" for t in ts) if ts else "-"

    def held(hs):
        return ", ".join(f"{t:g}{'+' if lasted else ''}" for t, lasted in hs) if hs else "-"
    out = ["| A | orientation | samples | transitions | probability (95 % interval) | Table 2 | "
           "untie times | re-knot times | re-knot held for | ends knotted | never untied |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for c in cells:
        lo, hi = c["interval"]
        p = f"{c['probability']:.2f} ({lo:.2f}-{hi:.2f})"
        if c["uncertain"]:
            p = f"**{p}**"
        out.append(f"| {c['A']:g} | {c['orientation']} | {c['samples']} | {c['transitions']} | {p} | "
                   f"{'U->K' if c['study'] else '-'} | {times(c['t_unknot'])} | "
                   f"{times(c['t_reknot'])} | {held(c.get('held', []))} | "
                   f"{c.get('ends_knotted', '-')} | {c['never_untied']} |")
    b, lg = scores["brier"], scores["log"]
    out += ["", f"Scores over {scores['samples']} samples in {scores['cells']} cells (Brier: lower "
            f"is better; log: mean log-likelihood per sample, probabilities kept in "
            f"[{lg['floor']:g}, {1 - lg['floor']:g}], higher is better):", "",
            "| predictor | Brier | log score |", "|---|---|---|",
            f"| the study's Table 2 | {b['table2']:.4f} | {lg['table2']:.4f} |",
            f"| never a transition | {b['never']:.4f} | {lg['never']:.4f} |", "",
            "Bold: a genuinely uncertain cell (some samples re-knot, some do not). Re-knot held "
            "for: the time from a sample's first re-knotting (k_f above the upper threshold "
            "after an untying) to its next untying (below the lower one), or with + to its last "
            "frame, still knotted; ends knotted: the samples whose last frame is in the knotted "
            "state of that rule."]
    return out


def sample_events(rows) -> list:
    """Per finished trefoil sample, in the order of cell and case name: its k_f events (the
    hysteresis rule of `transitions`: [kind, time] in time order), the largest k_f after its
    first untying (None when it never untied), its last k_f and state, and the times it was
    continued from the case ledger at (campaign.continued_at)."""
    out = []
    for r in sorted((r for r in rows if r.get("status", "finished") == "finished"),
                    key=lambda r: (float(r["A"]), str(r["orientation"]), str(r["case"]))):
        after = None
        if r["t_unknot"] is not None:
            t, kf = np.asarray(r["time"], dtype=float), np.asarray(r["kf"], dtype=float)
            after = float(np.max(kf[t >= r["t_unknot"]]))
        out.append({"case": r["case"], "A": float(r["A"]), "orientation": str(r["orientation"]),
                    "events": [[str(k), float(t)] for k, t in r["events"]],
                    "max_kf_after_untie": after, "final_kf": float(r["final_kf"]),
                    "final_state": r["final_state"],
                    "continued_at": [float(t) for t in r.get("continued_at") or []]})
    return out


def sample_table(samples) -> list:
    """Markdown of `sample_events`: one line per sample."""
    def events(ev):
        return ", ".join(f"{'untied' if k == 'unknot' else 'knotted'} {t:g}" for k, t in ev) or "-"
    out = ["| case | A | orientation | events | largest k_f after the first untying | last k_f | "
           "last state | continued from the ledger at |", "|---|---|---|---|---|---|---|---|"]
    for s in samples:
        after = "-" if s["max_kf_after_untie"] is None else f"{s['max_kf_after_untie']:.2f}"
        cont = ", ".join(f"t = {t:g}" for t in s["continued_at"]) or "-"
        out.append(f"| {s['case']} | {s['A']:g} | {s['orientation']} | {events(s['events'])} | "
                   f"{after} | {s['final_kf']:.2f} | {s['final_state']} | {cont} |")
    out += ["", "Events: the frames where k_f first falls below the lower threshold (untied) or "
            "rises above the upper one (knotted) after being on the other side, the hysteresis "
            "rule of the table above; a sample that unties and re-knots more than once lists "
            "every event."]
    return out


# ------------------------------------------------------------------ candy-canes by stiffness

def _late(case_row):
    """The late frames' observables of a candy-cane row (second half, as candycane_rows)."""
    case = case_row["_case"]
    t = np.asarray(case.time)
    late = late_mask(t)
    o = case.observables
    return t[late], {k: np.asarray(o[k])[late] for k in ("a", "b", "c", "theta", "phi", "close_pairs")}


def phi_rate(t, phi) -> float:
    """The mean rate of the angle phi (its unwrapped change over the time span)."""
    if len(t) < 2 or t[-1] <= t[0]:
        return math.nan
    u = np.unwrap(np.asarray(phi, dtype=float))
    return float((u[-1] - u[0]) / (t[-1] - t[0]))


#: The late means of a candy-cane case (late_means), in the order of the tables.
LATE_MEANS = ("a_over_b", "b_over_c", "abs_cos_theta", "phi_rate", "close_pairs")


def late_means(row) -> dict:
    """A candy-cane row's late frames: the means of a/b, b/c, |cos theta| and the close pairs,
    and the rate of phi."""
    t, o = _late(row)
    return {"a_over_b": float(np.mean(o["a"] / o["b"])), "b_over_c": float(np.mean(o["b"] / o["c"])),
            "abs_cos_theta": float(np.mean(np.abs(np.cos(o["theta"])))),
            "phi_rate": phi_rate(t, o["phi"]), "close_pairs": float(np.mean(o["close_pairs"]))}


def mode_statistics(rows) -> list:
    """Per bending stiffness A of candy-cane rows (finished cases): the fraction of cases whose
    case mode is I and II (exact intervals), the mean over cases of the fraction of late frames
    in mode I and II (bootstrap intervals over cases), and per-case late means of a/b, b/c,
    |cos theta|, the rate of phi and the close pairs (median and range over the cases)."""
    out = []
    done = [r for r in rows if r.get("status", "finished") == "finished"]
    for a in sorted({round(float(r["A"]), 6) for r in done}):
        g = [r for r in done if round(float(r["A"]), 6) == a]
        n = len(g)
        entry: dict = {"A": a, "cases": n}
        for m in ("I", "II"):
            k = sum(r["case_mode"] == m for r in g)
            entry[f"case_mode_{m}"] = {"cases": k, "fraction": k / n,
                                       "interval": list(clopper_pearson(k, n))}
            fr = [r[f"mode_{m}_late"] for r in g if r.get(f"mode_{m}_late") is not None]
            entry[f"frames_mode_{m}"] = {"mean": float(np.mean(fr)) if fr else math.nan,
                                         "interval": list(bootstrap_mean_interval(fr)),
                                         "cases": len(fr)}
        per_case: dict[str, list[float]] = {k: [] for k in LATE_MEANS}
        for r in g:
            if "_case" not in r:
                continue
            for k, v in late_means(r).items():
                per_case[k].append(v)
        entry["late_per_case"] = {
            k: ({"median": float(np.median(v)), "min": float(np.min(v)), "max": float(np.max(v))}
                if v else None) for k, v in per_case.items()}
        out.append(entry)
    return out


def close_pair_ratio_windows(rows, width: float, a_num: float = 1.0, a_den: float = 3.0) -> list:
    """The close-pair ratio A = a_num / A = a_den per time window [t0, t0 + width): the mean over
    the cases of each A of their mean close pairs in the window; nan where a side has no frame."""
    def series(a):
        return [r["_case"] for r in rows if abs(float(r["A"]) - a) < 1e-9 and "_case" in r]
    num, den = series(a_num), series(a_den)
    if not num or not den:
        return []
    t_max = min(max(float(c.time[-1]) for c in num), max(float(c.time[-1]) for c in den))
    def window_mean(cases, t0):
        means = []
        for c in cases:
            t = np.asarray(c.time)
            sel = (t >= t0) & (t < t0 + width)
            if np.any(sel):
                means.append(float(np.mean(np.asarray(c.observables["close_pairs"])[sel])))
        return float(np.mean(means)) if means else math.nan
    out = []
    t0 = 0.0
    while t0 < t_max:
        n, d = window_mean(num, t0), window_mean(den, t0)
        out.append({"t_from": t0, "t_to": t0 + width, "numerator": n, "denominator": d,
                    "ratio": n / d if d > 0 else math.nan})
        t0 += width
    return out


def mode_table(stats) -> list:
    """Markdown of mode_statistics."""
    def frac(e):
        lo, hi = e["interval"]
        return f"{e['cases']} ({e['fraction']:.2f}, {lo:.2f}-{hi:.2f})"

    def frames(e):
        lo, hi = e["interval"]
        return "-" if math.isnan(e["mean"]) else f"{e['mean']:.3f} ({lo:.3f}-{hi:.3f})"

    def spread(e, spec=".2f"):
        return "-" if e is None else f"{e['median']:{spec}} ({e['min']:{spec}}-{e['max']:{spec}})"
    out = ["| A | cases | case mode I: cases (fraction, 95 % interval) | case mode II | "
           "late frames in mode I: mean over cases (95 % bootstrap interval) | late frames in "
           "mode II | a/b late: median over cases (range) | b/c late | abs cos theta late | "
           "phi rate late | close pairs late |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for s in stats:
        lc = s["late_per_case"]
        out.append(f"| {s['A']:g} | {s['cases']} | {frac(s['case_mode_I'])} | "
                   f"{frac(s['case_mode_II'])} | {frames(s['frames_mode_I'])} | "
                   f"{frames(s['frames_mode_II'])} | {spread(lc['a_over_b'])} | "
                   f"{spread(lc['b_over_c'])} | {spread(lc['abs_cos_theta'])} | "
                   f"{spread(lc['phi_rate'], '.3f')} | {spread(lc['close_pairs'])} |")
    return out


def ratio_table(windows) -> list:
    """Markdown of close_pair_ratio_windows."""
    out = ["| window | close pairs A = 1 | close pairs A = 3 | ratio |", "|---|---|---|---|"]
    for w in windows:
        out.append(f"| {w['t_from']:g}-{w['t_to']:g} | {w['numerator']:.2f} | "
                   f"{w['denominator']:.2f} | {w['ratio']:.2f} |")
    return out


# ------------------------------------------------------------------ one start, two models

def paired_starts(rows, other_rows, key) -> dict:
    """Candy-canes run from the same starts with two models (finished cases of both): the pairs
    whose `key(row)` (the start: campaign.sample_start of the scene) agree, each with both rows'
    case modes, late frame fractions in modes I and II and late_means; per A the pairs, in how
    many the case mode is the same, and the mean over the pairs of this model's late mode I and
    II fractions minus the other's; the finished cases without a partner on either side."""
    done = [r for r in rows if r.get("status", "finished") == "finished"]
    other = {key(r): r for r in other_rows if r.get("status", "finished") == "finished"}
    pairs, unmatched = [], 0
    for r in done:
        o = other.get(key(r))
        if o is None:
            unmatched += 1
            continue
        pair = {"A": float(r["A"]), "start": key(r)[-1], "case": r.get("case"),
                "other_case": o.get("case")}
        for side, row in (("this", r), ("other", o)):
            pair[side] = {"case_mode": row["case_mode"], "mode_I_late": row.get("mode_I_late"),
                          "mode_II_late": row.get("mode_II_late"),
                          **(late_means(row) if "_case" in row else {})}
        pairs.append(pair)
    pairs.sort(key=lambda p: (p["A"], str(p["start"])))
    matched_other = {key(r) for r in done} & set(other)
    per_a = []
    for a in sorted({p["A"] for p in pairs}):
        g = [p for p in pairs if p["A"] == a]
        entry: dict = {"A": a, "pairs": len(g),
                       "same_case_mode": sum(p["this"]["case_mode"] == p["other"]["case_mode"]
                                             for p in g)}
        for m in ("I", "II"):
            d = [p["this"][f"mode_{m}_late"] - p["other"][f"mode_{m}_late"] for p in g
                 if p["this"][f"mode_{m}_late"] is not None
                 and p["other"][f"mode_{m}_late"] is not None]
            entry[f"mode_{m}_late_difference"] = float(np.mean(d)) if d else math.nan
        per_a.append(entry)
    return {"pairs": pairs, "per_A": per_a, "unmatched": unmatched,
            "unmatched_other": len(other) - len(matched_other)}


def paired_table(paired, this: str, other: str) -> list:
    """Markdown of paired_starts: one row per start (this / other), then one per A."""
    def two(p, k, spec=".3f"):
        def fmt(v):
            if v is None or (isinstance(v, float) and math.isnan(v)):
                return "-"
            return v if isinstance(v, str) else f"{v:{spec}}"
        return f"{fmt(p['this'].get(k))} / {fmt(p['other'].get(k))}"
    out = [f"Each start run with {this} and with {other} (this / other; late = second half of "
           "each run):", "",
           "| A | start (seed) | case mode | late frames in mode I | late frames in mode II | "
           "a/b late | b/c late | abs cos theta late | close pairs late |",
           "|---|---|---|---|---|---|---|---|---|"]
    for p in paired["pairs"]:
        out.append(f"| {p['A']:g} | {p['start']} | {two(p, 'case_mode')} | "
                   f"{two(p, 'mode_I_late')} | {two(p, 'mode_II_late')} | "
                   f"{two(p, 'a_over_b', '.2f')} | {two(p, 'b_over_c', '.2f')} | "
                   f"{two(p, 'abs_cos_theta', '.2f')} | {two(p, 'close_pairs', '.2f')} |")
    out += ["", "| A | starts | same case mode | late mode I: this − other (mean) | "
            "late mode II: this − other (mean) |", "|---|---|---|---|---|"]
    for e in paired["per_A"]:
        out.append(f"| {e['A']:g} | {e['pairs']} | {e['same_case_mode']} of {e['pairs']} | "
                   f"{e['mode_I_late_difference']:+.3f} | {e['mode_II_late_difference']:+.3f} |")
    out += ["", f"Finished cases without a partner: {paired['unmatched']} here, "
            f"{paired['unmatched_other']} in the other sweeps."]
    return out
