"""The cases of a sweep as rows for knotflow-study: status, k_f events and re-knottings of the
trefoils, shape and modes of the candy-canes, overlap statistics and run records, and the small
helpers the tables of results.md share."""

from __future__ import annotations

import math

import numpy as np

from .analysis import analyze_case
from .campaign import continued_at, integration_path, load_case
from .plot import mode_name
from .study_reference import in_study
from .study_slipknots import slipknot_scan
from .transitions import states


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


def first_reknot(events, t_last):
    """The first re-knotting of `events` (kind, time) and how long it held: (t_unknot, t_reknot,
    t_held, lasted) with t_unknot the first untying, t_reknot the first knot event after it,
    t_held the time from it to the next untying or, when there is none, to `t_last` (the last
    frame), and lasted whether the knot still held then; None for what did not happen."""
    t_unknot = next((t for k, t in events if k == "unknot"), None)
    t_reknot = None if t_unknot is None else next(
        (t for k, t in events if k == "knot" and t > t_unknot), None)
    if t_reknot is None:
        return t_unknot, None, None, None
    t_next = next((t for k, t in events if k == "unknot" and t > t_reknot), None)
    lasted = t_next is None
    return t_unknot, t_reknot, (t_last if lasted else t_next) - t_reknot, lasted


def status_of(case) -> dict:
    """Status, target t_end (the case's integrator.t_end; None when not recorded) and the time
    reached (the last frame read)."""
    t_end = case.attrs.get("integrator.t_end")
    return {"status": case.status, "model": str(case.attrs.get("hydro.model", "?")),
            "overlap_rule": overlap_rule(case),
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


def overlap_rule(case) -> str | None:
    """The overlap rule a case ran with, by its scene name (`&hydro overlap`): only the multipole
    model has one; None for the others (and when the case does not record it)."""
    if str(case.attrs.get("hydro.model", "")) != "multipole":
        return None
    rule = case.attrs.get("hydro.overlap")
    return None if rule is None else str(rule)


def overlap_stats(case) -> dict | None:
    """The run totals of the overlap diagnostics (io.DIAGNOSTIC_TOTALS; a running case's from
    its newest checkpoint), None when the case file has none."""
    if case.diagnostic_totals is None:
        return None
    return {**case.diagnostic_totals, "source": case.diagnostic_totals_source}


def runs_summary(runs) -> dict | None:
    """The run records of a case (io.RUN_FIELDS per segment) summed: commits and BLAS kernels in
    order of first use (the kernels of segments that recorded them; `blas_unknown` counts the
    others), total wall time of the segments that record one (a NaN wall time is counted in
    `wall_unknown`), mean load weighted by wall time over the segments with a known load (None
    when none is known), segments, t range. None without records."""
    if not runs:
        return None
    commits: list = []
    for r in runs:
        if r["commit"] not in commits:
            commits.append(r["commit"])
    blas: list = []
    for r in runs:
        if r.get("blas") not in (None, "unknown") and r["blas"] not in blas:
            blas.append(r["blas"])
    wall = float(sum(r["wall_seconds"] for r in runs if math.isfinite(r["wall_seconds"])))
    known = [r for r in runs if math.isfinite(r["load_mean"]) and math.isfinite(r["wall_seconds"])]
    weight = float(sum(r["wall_seconds"] for r in known))
    load = float(sum(r["load_mean"] * r["wall_seconds"] for r in known) / weight) if weight > 0 \
        else None
    return {"commits": commits, "blas": blas,
            "blas_unknown": sum(r.get("blas") in (None, "unknown") for r in runs),
            "wall_seconds": wall,
            "wall_unknown": sum(not math.isfinite(r["wall_seconds"]) for r in runs),
            "mean_load": load, "load_seconds": weight, "segments": len(runs),
            "t_start": float(min(r["t_start"] for r in runs)),
            "t_end": float(max(r["t_end"] for r in runs))}


def late_mask(t, frac=0.5):
    """Mask of the second half of the run (after the transient)."""
    return t >= t[0] + frac * (t[-1] - t[0])


def _analysed(files, closures, matrices_dir=None):
    """(case, its analysis) of every case of `files` with frames: case files, or the entries of
    a case ledger (`<case>.json`, campaign.ledger_case, with the knot matrices of
    `matrices_dir`)."""
    for path in files:
        case = load_case(path, matrices_dir)
        if case.nframes:
            yield case, analyze_case(case, closures=closures)


def _path(case, defaults=None):
    """The integration path of a case (campaign.integration_path of its scene text with the
    program's `defaults`; None without a scene text)."""
    scene = case.attrs.get("scene")
    return integration_path(scene, defaults) if isinstance(scene, str) and scene else None


def trefoil_rows(files, closures=200, defaults=None):
    """One row per trefoil case; `defaults` (campaign.scene_defaults) complete the integration
    path ("path") of scenes written before a variable existed."""
    rows = []
    for case, ana in _analysed(files, closures):
        a, o = float(case.bending_a), str(case.orientation)
        events = history(ana.time, ana.kf, knotted_at_start=ana.kf[0] >= 0.5)
        t_unknot, t_reknot, t_held, lasted = first_reknot(events, float(ana.time[-1]))
        rows.append({
            "case": case.name, "A": a, "orientation": o, **status_of(case),
            "kf0": float(ana.kf[0]), "final_kf": ana.final_kf,
            "final_state": ana.final_state or "undecided",
            "events": [[k, t] for k, t in events], "reknottings": reknottings(events),
            "unknot_then_knot": t_reknot is not None, "t_unknot": t_unknot, "t_reknot": t_reknot,
            "reknot_held": t_held, "reknot_lasted": lasted,
            "study_transition": in_study(a, o), "mode": mode_name(ana.case_mode),
            "overlap": overlap_stats(case), "runs": runs_summary(case.runs),
            "time": ana.time.tolist(), "kf": ana.kf.tolist(), "kf_source": ana.kf_source,
            "path": _path(case, defaults), "continued_at": continued_at(case),
        })
    rows.sort(key=lambda r: (r["A"], r["orientation"]))
    return rows


def candycane_rows(files, closures=200, confirm_dir=None, matrices_dir=None):
    rows = []
    for case, ana in _analysed(files, closures, matrices_dir):
        o = ana.observables
        t = case.time
        late = late_mask(t)
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


def reknot_totals(rows) -> dict:
    """Re-knottings of a trefoil sweep: events, simulations with at least one, cases, finished."""
    counts = [reknottings(r["events"]) for r in rows]
    return {"events": sum(counts), "simulations": sum(c > 0 for c in counts),
            "cases": len(rows), "finished": sum(finished(r) for r in rows)}


def agrees(row) -> bool:
    """Whether a trefoil case has the study's Table 2 outcome (an unknot-then-knot transition or
    none)."""
    return utk(row) == ("U->K" if in_study(row["A"], row["orientation"]) else "-")


def agreement_text(rows) -> str:
    """'a of n cases' agreeing with Table 2; with cases not finished, the finished ones first (a
    running case's outcome may still change): 'a of n finished cases (b of m with those not
    finished)'."""
    done = [r for r in rows if finished(r)]
    n_all = sum(agrees(r) for r in rows)
    if len(done) == len(rows):
        return f"{n_all} of {len(rows)} cases"
    return (f"{sum(agrees(r) for r in done)} of {len(done)} finished cases "
            f"({n_all} of {len(rows)} with those not finished)")


def close_pair_ratio(rows, key="close_pairs_mean"):
    """Mean of `key` over the cases with A = 1 over that with A = 3 (None without either or
    with none at A = 3)."""
    a1 = [r[key] for r in rows if abs(r["A"] - 1.0) < 1e-9]
    a3 = [r[key] for r in rows if abs(r["A"] - 3.0) < 1e-9]
    if not (a1 and a3) or np.mean(a3) <= 0:
        return None
    return float(np.mean(a1) / np.mean(a3))


def fmt(v, spec=".2f"):
    return "-" if v is None else format(v, spec)


def utk(row) -> str:
    return "U->K" if row["unknot_then_knot"] else "-"


def finished_line(rows, of=None) -> str:
    of = len(rows) if of is None else of
    text = f"{sum(finished(r) for r in rows)} of {of} cases finished"
    if len(rows) != of:
        text += f" ({len(rows)} present)"
    if all(finished(r) for r in rows):
        return text + "."
    return text + ("; a case not finished is marked (`*` in a grid, its status and the time "
                   "reached in a table): its results may still change.")
