"""Sweep report: per-case table, a Table-2-like grid A x orientation, late-time rheology of the
cases with a stresslet, figures (md + html)."""

from __future__ import annotations

import contextlib
import html
import json
import os
import sys

from .analysis import analyze_case
from .atomic import write_text
from .io import find_case_files, read_case
from .names import check_case_name
from .plot import mode_name, plot_case
from .rheology import rheology_summary
from .xdmf import write_xdmf, xdmf_path


def _read_summary(sweep_dir):
    for name in ("summary.json", "summary.txt"):
        p = os.path.join(sweep_dir, name)
        if os.path.isfile(p):
            with open(p, encoding="utf-8") as fh:
                text = fh.read()
            if name.endswith(".json"):
                try:
                    text = json.dumps(json.loads(text), indent=2)
                except json.JSONDecodeError:
                    pass
            return name, text
    return None, None


def _state_name(state) -> str:
    return {"knotted": "knotted", "unknotted": "unknotted"}.get(state, "undecided")


def build_report(sweep_dir, closures: int = 200, stride: int = 0, seed: int | None = None,
                 movie: bool = True, movie_max_frames: int = 40, viewer: bool = True) -> dict:
    """Analyse every case of sweep_dir and write report/report.md and report/report.html,
    with a movie of each case (at most ``movie_max_frames`` frames, 640 x 360), an XDMF file
    beside each case file and (``viewer``) an interactive 3-D viewer per case in the HTML."""
    outdir = os.path.join(sweep_dir, "report")
    figdir = os.path.join(outdir, "figures")
    made = [d for d in (outdir, figdir) if not os.path.isdir(d)]
    os.makedirs(figdir, exist_ok=True)
    try:
        return _build_report(sweep_dir, outdir, figdir, closures, stride, seed, movie,
                             movie_max_frames, viewer)
    except BaseException:
        # a report that could not be written (a full disk) leaves no empty directory behind
        for d in reversed(made):
            with contextlib.suppress(OSError):
                os.rmdir(d)
        raise


def _build_report(sweep_dir, outdir, figdir, closures, stride, seed, movie, movie_max_frames,
                  viewer) -> dict:
    rows = []
    for path in find_case_files(sweep_dir):
        try:
            case = read_case(path)
            check_case_name(case.name, f"{path}: attribute case_name")
        except (OSError, KeyError, ValueError, TypeError, RuntimeError, MemoryError) as exc:
            # whatever a bad file holds, the good cases are reported and the bad one listed
            rows.append({"file": os.path.basename(path), "name": os.path.basename(path),
                         "A": None, "orientation": None, "status": f"unreadable: {exc}",
                         "final_kf": None, "final_state": "-", "transitions": "-",
                         "events": 0, "unknot_then_knot": False, "mode": "-",
                         "strand_passages": None, "overlap_episodes": None, "figures": [],
                         "xdmf": None, "viewer": None, "rheology": None})
            continue
        if case.nframes == 0:
            ana = None
        else:
            ana = analyze_case(case, closures=closures, stride=stride, seed=seed)
        figs = plot_case(case, ana, figdir, movie=movie, movie_max_frames=movie_max_frames,
                         movie_size=(640, 360)) if ana is not None else []
        xdmf_file = _xdmf_beside(path, outdir)
        view = None
        if viewer and ana is not None:
            try:
                from .viewer import viewer_html
                view = viewer_html(case, kf=(ana.time, ana.kf), div_id=f"viewer-{len(rows)}")
            except ImportError as exc:          # plotly missing: the report without views
                print(f"knotflow-report: no 3-D view ({exc}); pip install plotly",
                      file=sys.stderr)
        kinds = [e.kind for e in ana.events] if ana else []
        utk = any(kinds[k] == "unknot" and "knot" in kinds[k + 1:] for k in range(len(kinds)))
        rows.append({
            "file": os.path.basename(path), "name": case.name, "A": case.bending_a,
            "orientation": case.orientation, "status": case.status,
            "final_kf": ana.final_kf if ana else None,
            "final_state": _state_name(ana.final_state) if ana else "-",
            "transitions": ("yes" if ana.has_transitions else "no") if ana else "-",
            "events": len(ana.events) if ana else 0, "unknot_then_knot": utk,
            "mode": mode_name(ana.case_mode) if ana else "-",
            "strand_passages": _total(case, "strand_passages"),
            "overlap_episodes": _total(case, "overlap_episodes"),
            "figures": [os.path.relpath(f, outdir) for f in figs],
            "xdmf": os.path.relpath(xdmf_file, outdir) if xdmf_file else None,
            "viewer": view,
            "rheology": (rheology_summary(case, 0.5 * case.time[-1])
                         if case.nframes else None),
        })
    summary_name, summary = _read_summary(sweep_dir)
    md = _markdown(sweep_dir, rows, summary_name, summary)
    write_text(os.path.join(outdir, "report.md"), md)
    write_text(os.path.join(outdir, "report.html"), _html(sweep_dir, rows, summary_name, summary))
    return {"rows": rows, "md": os.path.join(outdir, "report.md"),
            "html": os.path.join(outdir, "report.html")}


def _xdmf_beside(path, outdir):
    """Write the case's XDMF file beside it (in the report directory if that fails)."""
    try:
        return write_xdmf(path)
    except OSError:
        pass
    except (KeyError, ValueError):
        return None
    try:
        alt = os.path.join(outdir, os.path.basename(xdmf_path(path)))
        return write_xdmf(path, alt)
    except (OSError, KeyError, ValueError):
        return None


def _total(case, name):
    """A run total of the case's diagnostics (an int), or None for a file without them."""
    totals = case.diagnostic_totals or {}
    return int(totals[name]) if name in totals else None


def _fmt(v, spec=".3f"):
    if v is None:
        return "-"
    if isinstance(v, float):
        return format(v, spec)
    return str(v)


COLUMNS = ("case", "A", "orientation", "status", "final k_f", "final state", "transitions",
           "events", "unknot then knot", "mode", "strand passages", "overlap episodes")


def _row_cells(r):
    return [r["name"], _fmt(r["A"], "g"), _fmt(r["orientation"]), r["status"],
            _fmt(r["final_kf"]), r["final_state"], r["transitions"], str(r["events"]),
            "yes" if r["unknot_then_knot"] else "no", r["mode"], _fmt(r["strand_passages"]),
            _fmt(r["overlap_episodes"])]


def _grid(rows):
    a_vals = sorted({r["A"] for r in rows if r["A"] is not None})
    o_vals = sorted({str(r["orientation"]) for r in rows if r["orientation"] is not None})
    cells = {}
    for r in rows:
        if r["A"] is None or r["orientation"] is None:
            continue
        cells.setdefault((r["A"], str(r["orientation"])), []).append(
            f"{r['transitions']} / {r['final_state']} / {r['mode']}")
    return a_vals, o_vals, cells


RHEOLOGY_COLUMNS = ("case", "viscosity", "psi1", "psi2", "frames")


def _rheology_cells(r):
    """Late-time mean +- standard deviation of the case's viscosity, psi1, psi2 and the number
    of frames averaged (None for a case without the stresslet)."""
    rh = r.get("rheology")
    if not rh:
        return None
    return [r["name"]] + [f"{rh[k][0]:.4g} ± {rh[k][1]:.2g}" for k in ("viscosity", "psi1", "psi2")] \
        + [str(rh["viscosity"][2])]


RHEOLOGY_NOTE = ("Late-time means ± standard deviations over the frames of the second half of "
                 "each run (t ≥ t_last/2) of the fibre's intrinsic-viscosity-form shear viscosity "
                 "and normal-stress coefficients (/frames/stresslet; docs/case-file.md).")


def _markdown(sweep_dir, rows, summary_name, summary) -> str:
    out = [f"# knotflow sweep report: {sweep_dir}", "",
           f"{len(rows)} case files. Transitions use the hysteresis thresholds 0.1 / 0.9 on k_f.",
           "", "## Cases", "", "| " + " | ".join(COLUMNS) + " |",
           "|" + "---|" * len(COLUMNS)]
    for r in rows:
        out.append("| " + " | ".join(c.replace("|", "/") for c in _row_cells(r)) + " |")
    a_vals, o_vals, cells = _grid(rows)
    out += ["", "## Grid A x orientation (transitions / final state / mode)", ""]
    if a_vals and o_vals:
        out.append("| A | " + " | ".join(o_vals) + " |")
        out.append("|---|" + "---|" * len(o_vals))
        for a in a_vals:
            out.append(f"| {a:g} | " + " | ".join("; ".join(cells.get((a, o), ["-"]))
                                                  for o in o_vals) + " |")
    else:
        out.append("(no cases with both forces.bending_a and chain.orientation)")
    rheo = [c for c in (_rheology_cells(r) for r in rows) if c]
    if rheo:
        out += ["", "## Rheology", "", RHEOLOGY_NOTE, "", "| " + " | ".join(RHEOLOGY_COLUMNS) + " |",
                "|" + "---|" * len(RHEOLOGY_COLUMNS)]
        out += ["| " + " | ".join(c) + " |" for c in rheo]
    if summary is not None:
        out += ["", f"## Sweep summary ({summary_name})", "", "```", summary.rstrip(), "```"]
    out += ["", "## Figures", "",
            "report.html has an interactive 3-D view of each case (rotate, zoom, time slider).",
            ""]
    for r in rows:
        if r["figures"] or r["xdmf"]:
            out.append(f"### {r['name']}")
            out.append("")
            if r["xdmf"]:
                out += [f"ParaView / VisIt: open [{os.path.basename(r['xdmf'])}]({r['xdmf']})"
                        " (XDMF, points into the case file)", ""]
            for f in r["figures"]:
                if f.endswith(".png") or f.endswith(".gif"):
                    out.append(f"![{os.path.basename(f)}]({f})")
                elif f.endswith(".mp4"):
                    out.append(f"- movie: [{os.path.basename(f)}]({f})")
                else:
                    out.append(f"- [{os.path.basename(f)}]({f})")
            out.append("")
    return "\n".join(out) + "\n"


def _html(sweep_dir, rows, summary_name, summary) -> str:
    e = html.escape
    plotly_js = ""
    if any(r.get("viewer") for r in rows):
        from .viewer import plotly_js_tag
        plotly_js = plotly_js_tag()
    out = ["<!DOCTYPE html><html><head><meta charset='utf-8'>", plotly_js,
           f"<title>knotflow sweep report: {e(str(sweep_dir))}</title>",
           "<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}"
           "td,th{border:1px solid #999;padding:3px 8px}img{max-width:900px;display:block;"
           "margin:0.5em 0}</style></head><body>",
           f"<h1>knotflow sweep report: {e(str(sweep_dir))}</h1>",
           f"<p>{len(rows)} case files. Transitions use the hysteresis thresholds 0.1 / 0.9 on"
           " k<sub>f</sub>.</p>", "<h2>Cases</h2><table><tr>"
           + "".join(f"<th>{e(c)}</th>" for c in COLUMNS) + "</tr>"]
    for r in rows:
        out.append("<tr>" + "".join(f"<td>{e(c)}</td>" for c in _row_cells(r)) + "</tr>")
    out.append("</table>")
    a_vals, o_vals, cells = _grid(rows)
    out.append("<h2>Grid A &times; orientation (transitions / final state / mode)</h2>")
    if a_vals and o_vals:
        out.append("<table><tr><th>A</th>" + "".join(f"<th>{e(o)}</th>" for o in o_vals)
                   + "</tr>")
        for a in a_vals:
            out.append(f"<tr><th>{a:g}</th>" + "".join(
                f"<td>{e('; '.join(cells.get((a, o), ['-'])))}</td>" for o in o_vals) + "</tr>")
        out.append("</table>")
    else:
        out.append("<p>(no cases with both forces.bending_a and chain.orientation)</p>")
    rheo = [c for c in (_rheology_cells(r) for r in rows) if c]
    if rheo:
        out.append(f"<h2>Rheology</h2><p>{e(RHEOLOGY_NOTE)}</p><table><tr>"
                   + "".join(f"<th>{e(c)}</th>" for c in RHEOLOGY_COLUMNS) + "</tr>")
        out += ["<tr>" + "".join(f"<td>{e(c)}</td>" for c in cells) + "</tr>" for cells in rheo]
        out.append("</table>")
    if summary is not None:
        out.append(f"<h2>Sweep summary ({e(summary_name)})</h2><pre>{e(summary)}</pre>")
    out.append("<h2>Figures</h2>")
    for r in rows:
        if r["figures"] or r["xdmf"] or r.get("viewer"):
            out.append(f"<h3>{e(str(r['name']))}</h3>")
            if r.get("viewer"):
                out.append("<p>Interactive 3-D view: drag to rotate, scroll to zoom, move the "
                           "time slider; the title gives the frame's time and k<sub>f</sub>."
                           "</p>")
                out.append(f"<div class='viewer'>{r['viewer']}</div>")
            if r["xdmf"]:
                out.append(f"<p>ParaView / VisIt: open <a href='{e(r['xdmf'])}'>"
                           f"{e(os.path.basename(r['xdmf']))}</a> (XDMF, points into the case"
                           " file)</p>")
            for f in r["figures"]:
                if f.endswith(".png") or f.endswith(".gif"):
                    out.append(f"<img src='{e(f)}' alt='{e(os.path.basename(f))}'>")
                elif f.endswith(".mp4"):
                    out.append(f"<video controls preload='metadata' width='640' src='{e(f)}'>"
                               f"</video><p>movie: <a href='{e(f)}'>{e(os.path.basename(f))}"
                               "</a></p>")
                else:
                    out.append(f"<p><a href='{e(f)}'>{e(os.path.basename(f))}</a></p>")
    out.append("</body></html>")
    return "\n".join(out) + "\n"
