"""The three-column comparison of knotflow-study (--rpy-trefoil, --rpy-candycane): the study,
this run's model and an earlier RPY + EV run (its results.json), for the trefoils of Table 2 and
the candy-canes, as results.md tables and the "comparison" part of results.json."""

from __future__ import annotations

import json
import os

from .study_reference import (
    STUDY_CANDYCANE_A,
    STUDY_CANDYCANE_MODES,
    STUDY_CLOSE_PAIR_RATIO,
    STUDY_REKNOT_EVENTS,
    STUDY_REKNOT_SIMULATIONS,
    STUDY_SLIPKNOT_A,
    STUDY_STIFF_A,
    STUDY_STIFF_MODE,
    STUDY_TRANSITIONS,
    STUDY_TREFOIL_CASES,
    STUDY_VISUAL_SLIPKNOT_A,
    STUDY_WHOLE_KF,
    case_key,
    in_study,
)
from .study_rows import (
    agreement_text,
    agrees,
    close_pair_ratio,
    finished,
    finished_line,
    fmt,
    reknot_totals,
    reknottings,
    status_text,
    utk,
)
from .study_slipknots import slip_counts

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
    return {**tot, "agree": sum(agrees(r) for r in rows),
            "final_states": {s: sum(r["final_state"] == s for r in rows)
                             for s in ("knotted", "unknotted", "undecided")},
            "modes": {m: sum(r["mode"] == m for r in rows) for m in ("I", "II", "-", "?")},
            "stiff_mode_II": [sum(r["mode"] == "II" for r in stiff), len(stiff)]}


def trefoil_comparison(rows, rpy):
    """Markdown lines and the "comparison" part of the trefoils: the study, this run (rows) and
    the RPY + EV cases of an earlier results.json (rpy)."""
    head = model_head(rows)
    ours = {case_key(r["A"], r["orientation"]): r for r in rows}
    theirs = {case_key(r["A"], r["orientation"]): r for r in rpy}
    keys = sorted(set(ours) | set(theirs), key=lambda k: (k[1], k[0]))
    a_vals = sorted({k[1] for k in keys})
    o_vals = sorted({k[0] for k in keys})
    cells = []
    for o, a in keys:
        study = "U->K" if in_study(a, o) else "-"
        cells.append({"A": a, "orientation": o, "study": study,
                      "ours": utk(ours[o, a]) if (o, a) in ours else None,
                      "ours_finished": finished(ours[o, a]) if (o, a) in ours else None,
                      "rpy": utk(theirs[o, a]) if (o, a) in theirs else None})
    by = {(c["A"], c["orientation"]): c for c in cells}
    out = ["### The study, " + head + " and " + RPY_HEAD + ": Table 2", "",
           f"{head}: " + finished_line(rows, STUDY_TREFOIL_CASES), "",
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
            _row3("cells agreeing with the study", "-", agreement_text(rows), agreement_text(rpy)),
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
                return "not run | | | |"
            ev = ", ".join(f"{k} {t:g}" for k, t in x["events"]) or "none"
            return f"{ev} | {reknottings(x['events'])} | {x['final_state']} | {x['mode']} |"

        out.append(f"| {name} | {'-' if r is None else status_text(r)} | "
                   f"{'yes' if in_study(a, o) else 'no'} | {part(r)} {part(q)}")
    doc = {"columns": [STUDY_HEAD, head, RPY_HEAD], "cells": cells,
           "study": {"cases": STUDY_TREFOIL_CASES, "events": STUDY_REKNOT_EVENTS,
                     "simulations": STUDY_REKNOT_SIMULATIONS,
                     "transitions": sorted([o, a] for o, a in STUDY_TRANSITIONS),
                     "stiff_mode": STUDY_STIFF_MODE},
           "ours": sm, "rpy": sr}
    return out, doc


def _study_slipknot(a):
    """What the study says of a slipknot at bending stiffness `a`: 'found', 'described
    visually' or None (nothing said)."""
    if any(abs(a - x) < 1e-9 for x in STUDY_SLIPKNOT_A):
        return "found"
    if any(abs(a - x) < 1e-9 for x in STUDY_VISUAL_SLIPKNOT_A):
        return "described visually"
    return None


def _by_a(rows, a):
    return [r for r in rows if abs(r["A"] - a) < 1e-9]


def _cc_numbers(r) -> dict:
    """What the candy-cane comparison takes of one case (a row here or of a results.json)."""
    return {"case": r["case"], "status": r.get("status", "finished"),
            "t_reached": r.get("t_reached", r.get("t_end")), "t_end": r.get("t_end"),
            "case_mode": r["case_mode"], "close_pairs_mean": r["close_pairs_mean"],
            "close_pairs_late": r["close_pairs_late"], "max_kf": r["max_kf"],
            **slip_counts(r["matrices"])}


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
           f"{head}: " + finished_line(rows) + " Several cases of one A are listed in turn; "
           "late = second half of the frames read.", "", *_head3("A: quantity", head)]

    def join(ns, fmt):
        return ", ".join(fmt(n) for n in ns) or "not run"

    per_a = []
    for a in a_vals:
        g = [_cc_numbers(r) for r in _by_a(rows, a)]
        q = [_cc_numbers(r) for r in _by_a(r_cc, a)]
        study = {"case_mode": STUDY_CANDYCANE_MODES.get(a),
                 "slipknot": _study_slipknot(a),
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
        mine = "not run" if k == "rotations_all_t" and not ensemble else fmt(m, ".1f")
        out.append(_row3(f"close pairs A = 1 / A = 3, {labels[k]}", STUDY_CLOSE_PAIR_RATIO,
                         mine, fmt(r, ".1f")))
    doc = {"columns": [STUDY_HEAD, head, RPY_HEAD], "per_A": per_a,
           "close_pair_ratio": {k: {"study": STUDY_CLOSE_PAIR_RATIO, "ours": m, "rpy": r}
                                for k, (m, r) in ratios.items()}}
    return out, doc
