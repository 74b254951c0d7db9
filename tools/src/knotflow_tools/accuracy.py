"""The accuracy-versus-cost report: turns the CSV tables of ``knotflow-accuracy`` into
docs/accuracy.md (tables), PNG figures and, optionally, the summary block of docs/models.md
(between ``<!-- accuracy:begin -->`` and ``<!-- accuracy:end -->``)."""

from __future__ import annotations

import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .atomic import save_figure, write_text  # noqa: E402

BEGIN = "<!-- accuracy:begin -->"
END = "<!-- accuracy:end -->"
REUSE_BEGIN = "<!-- reuse:begin -->"
REUSE_END = "<!-- reuse:end -->"
STIFFNESS_BEGIN = "<!-- stiffness:begin -->"
STIFFNESS_END = "<!-- stiffness:end -->"
#: Ends the part of docs/accuracy.md that `build_report` writes; what follows it is kept.
GENERATED_END = "<!-- generated:end -->"
TABLES = ("meta.csv", "models.csv", "tolerance.csv", "scaling.csv", "scaling_fit.csv",
          "case_time.csv")
CONFIG_TEXT = {
    "trefoil": "open trefoil (N = 99, orientation a)",
    "coil": "compact coil of the A = 1 candy-cane run (N = 152, t = 306)",
    "loose": "loose chain: the candy-cane initial shape (N = 152)",
}
MARKERS = {"trefoil": "o", "coil": "s", "loose": "^"}


def read_table(directory: str, name: str) -> list[dict]:
    """Rows of DIR/name as dictionaries (an absent file gives no rows)."""
    path = os.path.join(directory, name)
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def label(row: dict) -> str:
    """Short model label: none, rpy, L2, L2+lub."""
    if row["model"] != "multipole":
        return row["model"]
    return "L%s%s" % (row["order"], "+lub" if row["lubrication"] == "1" else "")


def _num(x: str) -> float:
    return float(x)


def fmt_time(seconds: float) -> str:
    """A duration with a sensible unit (µs, ms, s, min, h, d)."""
    if not seconds > 0:
        return "–"
    if seconds < 1e-3:
        return "%.3g µs" % (seconds * 1e6)
    if seconds < 1:
        return "%.3g ms" % (seconds * 1e3)
    if seconds < 120:
        return "%.3g s" % seconds
    if seconds < 7200:
        return "%.3g min" % (seconds / 60)
    if seconds < 3 * 86400:
        return "%.3g h" % (seconds / 3600)
    return "%.3g d" % (seconds / 86400)


def fmt_err(x: float) -> str:
    if x < 0:
        return "failed"
    if x == 0:
        return "0"
    return "%.2e" % x


def _md_table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def summary_table(models: list[dict], case: list[dict]) -> str:
    """One row per model: RMS error per configuration, time per evaluation (trefoil) and the
    wall time of the reference case (measured or extrapolated)."""
    configs = [c for c in CONFIG_TEXT if any(r["config"] == c for r in models)]
    order, seen = [], set()
    for r in models:
        if label(r) not in seen:
            seen.add(label(r))
            order.append(label(r))
    err = {(r["config"], label(r)): _num(r["rms_rel"]) for r in models}
    teval = {label(r): _num(r["t_eval"]) for r in models if r["config"] == "trefoil"}
    wall = {}
    for r in case:
        key = label(r)
        if key not in wall or r["kind"] == "measured":
            wall[key] = (_num(r["wall"]), r["kind"])
    t_end = "%g" % _num(case[0]["t_end"]) if case else "1000"
    header = ["model"] + ["RMS error, %s" % c for c in configs] + [
        "one evaluation (trefoil)", "reference case t_end = %s" % t_end]
    rows = []
    for m in order:
        row = [m] + [fmt_err(err[(c, m)]) if (c, m) in err else "–" for c in configs]
        row.append(fmt_time(teval.get(m, -1.0)))
        if m in wall:
            row.append("%s (%s)" % (fmt_time(wall[m][0]), wall[m][1]))
        else:
            row.append("–")
        rows.append(row)
    return _md_table(header, rows)


def _meta(directory: str) -> dict:
    return {r["key"]: r["value"] for r in read_table(directory, "meta.csv")}


def plot_errors(models: list[dict], path: str) -> None:
    """RMS error against time per evaluation, log-log; marker = configuration, colour = model."""
    fig, ax = plt.subplots(figsize=(7.5, 5), constrained_layout=True)
    labels = []
    for r in models:
        if label(r) not in labels:
            labels.append(label(r))
    cmap = plt.get_cmap("tab20")
    colour = {m: cmap(i % 20) for i, m in enumerate(labels)}
    for r in models:
        e, t = _num(r["rms_rel"]), _num(r["t_eval"])
        if e <= 0 or t <= 0:
            continue
        ax.loglog(t, e, MARKERS.get(r["config"], "x"), color=colour[label(r)], ms=7)
        ax.annotate(label(r), (t, e), xytext=(4, 3), textcoords="offset points", fontsize=6,
                    color="0.3")
    for m in labels:
        ax.plot([], [], "o", color=colour[m], label=m)
    for c, mk in MARKERS.items():
        ax.plot([], [], mk, color="0.4", mfc="none", label=c)
    ax.set_xlabel("time per evaluation [s]")
    ax.set_ylabel("RMS relative velocity error")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2, loc="best")
    save_figure(fig, path, dpi=110)
    plt.close(fig)


def plot_tolerance(tol: list[dict], path: str) -> None:
    """Wall time and trajectory deviation against the tolerance, per model."""
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.8), constrained_layout=True)
    for m in sorted({label(r) for r in tol}):
        rows = sorted((r for r in tol if label(r) == m and r["tolerance"] != r["ref_tolerance"]),
                      key=lambda r: _num(r["tolerance"]))
        x = [_num(r["tolerance"]) for r in rows]
        name = "%s (t_end = %g)" % (m, _num(rows[0]["t_end"])) if rows else m
        a1.loglog(x, [_num(r["wall"]) for r in rows], "o-", label=name)
        dev = [(xx, _num(r["max_deviation"])) for xx, r in zip(x, rows)
               if _num(r["max_deviation"]) > 0]
        a2.loglog([d[0] for d in dev], [d[1] for d in dev], "o-", label=name)
    a1.set_xlabel("tolerance")
    a1.set_ylabel("wall time [s]")
    a2.set_xlabel("tolerance")
    a2.set_ylabel("max bead deviation at t_end [d]")
    for a in (a1, a2):
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=8)
    save_figure(fig, path, dpi=110)
    plt.close(fig)


def plot_scaling(scaling: list[dict], fits: list[dict], path: str) -> None:
    """Time per evaluation against N, log-log, with the fitted exponents."""
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    slope = {label(r): _num(r["exponent"]) for r in fits}
    names = []
    for r in scaling:
        if label(r) not in names:
            names.append(label(r))
    for m in names:
        pts = [(int(r["n"]), _num(r["t_eval"])) for r in scaling
               if label(r) == m and r["status"] == "ok" and _num(r["t_eval"]) > 0]
        text = "%s (N^%.2f)" % (m, slope[m]) if m in slope else m
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", label=text)
    ax.set_xlabel("N (beads)")
    ax.set_ylabel("time per evaluation [s]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    save_figure(fig, path, dpi=110)
    plt.close(fig)


def build_markdown(directory: str, figdir_rel: str) -> tuple[str, str]:
    """docs/accuracy.md text and the summary block text of docs/models.md."""
    meta = _meta(directory)
    models = read_table(directory, "models.csv")
    tol = read_table(directory, "tolerance.csv")
    scaling = read_table(directory, "scaling.csv")
    fits = read_table(directory, "scaling_fit.csv")
    case = read_table(directory, "case_time.csv")
    ref_order = meta.get("ref_order", "?")
    load = meta.get("loadavg_start", "unknown")
    if "loadavg_end" in meta:
        load += "; at the end: %s" % meta["loadavg_end"]
    out = ["# Accuracy versus cost of the hydrodynamic models", "",
           "Generated by `bash scripts/accuracy.sh` (`knotflow-accuracy --all`, then "
           "`knotflow-accuracy-report`) down to the marker `%s`; do not edit that part by "
           "hand. What follows the marker is kept when the report is regenerated: the blocks "
           "of `knotflow-accuracy-report --reuse` and `--stiffness` and the sections written "
           "by hand, each naming the command its figures come from.%s" % (
               GENERATED_END,
               " **Quick run (smoke-test sizes): not the real figures.**"
               if meta.get("quick") == "1" else ""),
           "Timings: one core (OPENBLAS_NUM_THREADS=1) of a shared 2-core machine; load average "
           "at the start of the run: %s (1, 5, 15 min, as in /proc/loadavg). Timings scale with "
           "the load; the errors do not depend on it." % load, ""]
    summary = ""
    if models:
        summary = summary_table(models, case)
        out += ["## Summary", "",
                "RMS relative error of the bead velocities against multipole L = %s with "
                "lubrication, time of one velocity evaluation, and wall time of one "
                "reference-study case (trefoil N = 99, tolerance 1e-4; see the last section)."
                % ref_order,
                "", summary, ""]
        out += ["## Velocity error", "",
                "u_i = dr_i/dt − v0(r_i): the velocity of bead i relative to the ambient shear "
                "v0 = (z, 0, 0) (the force-driven part μF plus the disturbance of the flow), with "
                "springs k = 500, l0 = 1.02, bending A = %s, shear rate 1, eps_lub = 1e-4. Norms: "
                "RMS = sqrt(Σ|u − u_ref|² / Σ|u_ref|²), max = max_i |u_i − u_ref,i| / max_i "
                "|u_ref,i|; 'force' and 'shear' are the RMS errors of the two parts separately. "
                "Reference: multipole L = %s with lubrication; its own convergence is the row "
                "L%s+lub (the difference between L = %s and L = %s); with lubrication the "
                "error alternates with the parity of L on straight chain stretches (missing "
                "three-body terms, docs/multipole.md), so even orders share part of the "
                "reference's bias. Time per evaluation: "
                "median over repeated evaluations (≥ 3 and ≥ 0.5 s, at most 15 s)." % (
                    meta.get("bending_a_models", "?"), ref_order, int(ref_order) - 1
                    if ref_order.isdigit() else "?", int(ref_order) - 1
                    if ref_order.isdigit() else "?", ref_order), ""]
        for c in [c for c in CONFIG_TEXT if any(r["config"] == c for r in models)]:
            rows = [r for r in models if r["config"] == c]
            out += ["### %s" % CONFIG_TEXT[c], "", _md_table(
                ["model", "RMS", "max", "RMS force", "RMS shear", "time per evaluation",
                 "evaluations timed", "status"],
                [[label(r), fmt_err(_num(r["rms_rel"])), fmt_err(_num(r["max_rel"])),
                  fmt_err(_num(r["rms_force"])), fmt_err(_num(r["rms_shear"])),
                  fmt_time(_num(r["t_eval"])), r["n_evals"], r["status"]] for r in rows]), ""]
        out += ["![error versus cost](%s/accuracy_error_cost.png)" % figdir_rel, ""]
    if tol:
        out += ["## Integration tolerance", "",
                "Trefoil (N = 99, orientation a, A = 2.2) from t = 0 to t_end; deviation = "
                "max over beads of |r − r_ref| at t_end against the run at the tightest "
                "tolerance (the row with deviation 0). eps_lub is fixed at 1e-4 so that only "
                "the integration changes.", "",
                _md_table(["model", "t_end", "tolerance", "wall", "steps", "rejected",
                           "evaluations", "max deviation [d]"],
                          [[label(r), "%g" % _num(r["t_end"]), "%.0e" % _num(r["tolerance"]),
                            fmt_time(_num(r["wall"])), r["steps"], r["rejected"],
                            r["evaluations"], fmt_err(_num(r["max_deviation"]))] for r in tol]),
                "", "![tolerance](%s/accuracy_tolerance.png)" % figdir_rel, ""]
    if scaling:
        sizes = sorted({int(r["n"]) for r in scaling})
        names = []
        for r in scaling:
            if label(r) not in names:
                names.append(label(r))
        t = {(label(r), int(r["n"])): r for r in scaling}
        slope = {label(r): r for r in fits}
        table: list[list[str]] = []
        for m in names:
            row = [m]
            for n in sizes:
                cell = t.get((m, n))
                row.append(fmt_time(_num(cell["t_eval"])) if cell and cell["status"] == "ok"
                           else (cell["status"] if cell else "–"))
            f = slope.get(m)
            row.append("%.2f (N = %s–%s)" % (_num(f["exponent"]), f["n_min"], f["n_max"])
                       if f else "–")
            table.append(row)
        out += ["## Scaling with N", "",
                "Time per evaluation for self-avoiding random walks (bond 1.02, non-bonded beads "
                "≥ 1 apart, fixed seed). Sizes predicted (N³ from the previous size) to exceed "
                "the limit per evaluation are skipped. Exponent: least-squares line in log-log "
                "through the (up to) three largest measured sizes.", "",
                _md_table(["model"] + ["N = %d" % n for n in sizes] + ["exponent"], table), "",
                "![scaling](%s/accuracy_scaling.png)" % figdir_rel, ""]
    if case:
        out += ["## What it means: one reference-study case", "",
                "Trefoil N = 99, A = 2.2, orientation c, tolerance 1e-4, t_end = %g. "
                "'measured': the whole case was run. 'extrapolated': (evaluations per unit time, "
                "counted over a short window after a warm-up) × t_end × (median time per "
                "evaluation); the rpy row extrapolated in the same way checks the method "
                "against its measured run." % _num(case[0]["t_end"]), "",
                _md_table(["model", "kind", "wall time", "evaluations per unit time",
                           "time per evaluation", "rate from"],
                          [[label(r), r["kind"], fmt_time(_num(r["wall"])),
                            "%.0f" % _num(r["evals_per_time"]), fmt_time(_num(r["t_eval"])),
                            r["rate_source"]] for r in case]), ""]
    out += [GENERATED_END, ""]
    return "\n".join(out), summary


def kept_part(old: str) -> str:
    """What regenerating the report `old` keeps: everything after its GENERATED_END line (the
    marker alone on a line; the header names it in quotes) or, in a report written before the
    marker existed, from its first reuse or stiffness block on (sections written by hand follow
    those blocks); '' when it has neither."""
    line = "\n%s\n" % GENERATED_END
    i = old.find(line)
    if i >= 0:
        return old[i + len(line):].lstrip("\n")
    starts = [j for j in (old.find(REUSE_BEGIN), old.find(STIFFNESS_BEGIN)) if j >= 0]
    return old[min(starts):] if starts else ""


def replace_block(text: str, block: str, begin: str, end: str, where: str) -> str:
    """`text` with the part between the markers `begin` and `end` replaced by `block`."""
    i, j = text.find(begin), text.find(end)
    if i < 0 or j < i:
        raise ValueError("%s: markers %s ... %s not found" % (where, begin, end))
    return text[:i + len(begin)] + "\n" + block.strip() + "\n" + text[j:]


def update_readme(path: str, block: str) -> None:
    """Replace the text between the accuracy markers of a Markdown page (docs/models.md) by `block`."""
    with open(path) as f:
        text = f.read()
    text = replace_block(text, block, BEGIN, END, path)
    write_text(path, text)


def read_keys(path: str) -> dict:
    """The `key = value` lines of a knotflow-bench-reuse output file."""
    keys = {}
    with open(path) as f:
        for line in f:
            if " = " in line:
                k, v = line.split(" = ", 1)
                keys[k.strip()] = v.strip()
    return keys


def read_reuse(directory: str) -> dict:
    """Every NAME.txt of a knotflow-bench-reuse output directory, by NAME."""
    runs = {}
    if os.path.isdir(directory):
        for name in sorted(os.listdir(directory)):
            if name.endswith(".txt"):
                runs[name[:-4]] = read_keys(os.path.join(directory, name))
    return runs


def _ratio(a: str, b: str) -> str:
    try:
        return "%.2f" % (float(a)/float(b))
    except (ValueError, ZeroDivisionError):
        return "–"


def _overlap_rules(runs: dict) -> str:
    """The &hydro overlap rules the benchmark outputs name ('pair' where a file names none: the
    benchmark had no other rule before it recorded its rule)."""
    rules = sorted({v.get("overlap", "pair") for v in runs.values()})
    return " / ".join("'%s'" % r for r in rules) + (" (by part)" if len(rules) > 1 else "")


def reuse_section(runs: dict) -> str:
    """The docs/accuracy.md section on the adaptive reuse of the multipole many-body part."""
    out = ["## Adaptive reuse of the multipole many-body part (`&hydro update`)", "",
           "Generated by `bash scripts/bench_reuse.sh` (knotflow-bench-reuse, then "
           "`knotflow-accuracy-report --reuse`); one core (OPENBLAS_NUM_THREADS=1), load "
           "averages (1, 5, 15 min) as measured. The study's model: multipole L = 2 + "
           "lubrication, eps_lub = tolerance = 1e-4, overlap rule %s, shear rate 1, "
           "k = 500. 'stage' recomputes the many-body friction at every Runge–Kutta stage "
           "(exact, the reference); 'adaptive' reuses it between refreshes (rigidly rotated with "
           "the chain, extrapolated in time by the order, up to 2, whose measured error is the "
           "smaller) while the lubrication corrections are exact at every stage; the refresh "
           "rule is in docs/multipole.md." % _overlap_rules(runs), ""]
    vel = [(k, v) for k, v in runs.items() if k.startswith("velocity_")]
    if vel:
        rows = []
        for k, v in vel:
            ev = v.get("adaptive.evaluations", "0")
            reused = v.get("adaptive.reused", "0")
            rows.append([v.get("config", k), v.get("t_end", "?"), v.get("checks", "?") + (
                " (every %s)" % v["every"] if v.get("every", "1") != "1" else ""),
                v.get("velocity_rms_max", "?"), v.get("velocity_rms_mean", "?"),
                v.get("velocity_maxnorm_max", "?"),
                "%s of %s" % (v.get("adaptive.refreshes", "?"), ev),
                _ratio(v.get("adaptive.cg_iterations", "0"), reused),
                v.get("adaptive.max_error_ratio", "?"), v.get("loadavg_start", "?")])
        out += ["### Velocity error along real runs", "",
                "The adaptive path integrates (dopri45, tolerance 1e-4) from t = 0 of the "
                "configuration; at each compared stage the exact velocities at the same "
                "positions are computed too. Errors of u = v − v0 relative to the exact ones: "
                "RMS over beads (largest and mean over the stages) and max over beads. "
                "'error / prediction': largest ratio of the measured reuse error at a refresh to "
                "the rule's prediction.", "",
                _md_table(["configuration", "t_end", "stages compared", "RMS (largest)",
                           "RMS (mean)", "max (largest)", "refreshes of evaluations",
                           "CG iterations per reused evaluation", "error / prediction",
                           "load"], rows), ""]
    tr = runs.get("trajectory_trefoil")
    if tr:
        out += ["### Trajectory", "",
                "Trefoil (orientation c, A = 2.2) to t = %s with both paths at tolerance 1e-4: "
                "largest bead deviation **%s d** (adaptive against stage). For scale, the exact "
                "path's own deviation between tolerances 1e-4 and 1e-6: %s d. Wall times: stage "
                "%s s, adaptive %s s, stage at 1e-6 %s s (load %s)." % (
                    tr.get("t_end"), tr.get("deviation_adaptive_vs_stage"),
                    tr.get("deviation_stage_tol1e-4_vs_1e-6"), tr.get("stage.wall_s"),
                    tr.get("adaptive.wall_s"), tr.get("stage_tol1e-6.wall_s"),
                    tr.get("loadavg_start")), ""]
    ov = [(k, v) for k, v in runs.items() if k.startswith("overlaps_")]
    if ov:
        rows = []
        for k, v in ov:
            for p in ("stage", "adaptive"):
                rows.append([k[len("overlaps_"):], p, v.get(p + ".overlap_episodes", "?"),
                             v.get(p + ".mean_duration", "?"), v.get(p + ".max_duration", "?"),
                             v.get(p + ".max_overlapping_pairs", "?"),
                             v.get(p + ".strand_passages", "?"), v.get(p + ".min_distance", "?"),
                             v.get(p + ".wall_s", "?")])
        out += ["### Overlaps (overlap rule %s)" % _overlap_rules(dict(ov)), "",
                "The compact coil (inputs/configs/coil_candycane_A1.xyz, A = 1) to t = 4 at two "
                "values of eps_lub: overlap episodes (started), mean and maximum "
                "duration of the completed ones, most overlapping pairs at once, strand passages, "
                "smallest non-bonded distance.", "",
                _md_table(["scene", "path", "episodes", "mean duration", "max duration",
                           "max overlapping pairs", "strand passages", "min distance",
                           "wall [s]"], rows), ""]
    sp = runs.get("speed_trefoil")
    if sp:
        out += ["### Speed", "",
                "Trefoil (orientation c, A = 2.2, tolerance 1e-4) from t = 0 to %s, both paths "
                "in one run, one core: stage %s s (%s steps), adaptive %s s (%s steps, %s "
                "refreshes of %s evaluations): **%s× less wall time** (load at the start %s, at "
                "the end %s)." % (sp.get("t_end"), sp.get("stage.wall_s"),
                                  sp.get("stage.steps"), sp.get("adaptive.wall_s"),
                                  sp.get("adaptive.steps"), sp.get("adaptive.refreshes"),
                                  sp.get("adaptive.evaluations"),
                                  _ratio(sp.get("stage.wall_s", ""), sp.get("adaptive.wall_s", "")),
                                  sp.get("loadavg_start"), sp.get("loadavg_end")), ""]
    sc = runs.get("scaling")
    if sc:
        sizes = sorted({int(k.split(".")[0][1:]) for k in sc if k.startswith("N") and "." in k})
        rows = [["N = %d" % n, sc.get("N%d.wall_s_per_time" % n, "?"),
                 sc.get("N%d.steps" % n, "?"),
                 "%s of %s" % (sc.get("N%d.refreshes" % n, "?"), sc.get("N%d.evaluations" % n, "?"))]
                for n in sizes]
        out += ["### Cost against N", "",
                "Adaptive path on self-avoiding random chains (fixed seed, A = 2.2) from t = 0 "
                "to %s (the start of a run, where the rule refreshes more often than later: "
                "the calibration needs two refreshes and the extrapolation grows its interval "
                "at most threefold per refresh): wall seconds per unit of simulated time. "
                "Fitted exponent (log-log, N = "
                "%s–%s): **%s** (load %s)." % (sc.get("t_end"), sc.get("exponent_n_min"),
                                              sc.get("exponent_n_max"), sc.get("exponent"),
                                              sc.get("loadavg_start")), "",
                _md_table(["size", "wall s per unit time", "steps", "refreshes of evaluations"],
                          rows), ""]
    pr = runs.get("profile_trefoil")
    if pr:
        rows = []
        for kind, amp in (("rigid", "perturbation"), ("stretch", "amplitude"), ("move", "amplitude")):
            for i in range(1, 5):
                if "%s%d.max_error" % (kind, i) in pr:
                    rows.append([kind, pr.get("%s%d.angle" % (kind, i), "–"),
                                 pr.get("%s%d.%s" % (kind, i, amp), "–"),
                                 pr.get("%s%d.max_error" % (kind, i))])
        out += ["### What limits the reuse", "",
                "The many-body part of the trefoil at t = 0 reused as it is (no extrapolation) at "
                "moved configurations, against the exact velocities there (overlap rule %s: the "
                "rules separate and relax act in the dynamics, outside the model, and would "
                "compare unlike velocities where a move makes beads overlap; max over beads of "
                "|v − v_exact|, forces and flow at the moved configuration): a rigid rotation "
                "(plus a small deformation), every bond stretched by the given relative amount, "
                "every bead moved by the given amount. A rigid motion costs nothing; a bond "
                "length change of 1e-3 already gives a velocity error near the budget, because "
                "the stiff springs (k = 500) turn it into large forces on which the reused "
                "mobility acts. Runge–Kutta stages change bond lengths by about that much, so "
                "the many-body part can be reused only over a few stages at the tolerance."
                % ("'%s'" % pr.get("overlap", "pair")), "",
                _md_table(["motion", "angle", "amplitude", "largest velocity error"], rows), ""]
    ca = runs.get("case_trefoil")
    if ca:
        out += ["### One reference case", "",
                "The whole trefoil case (N = 99, A = 2.2, orientation c, t_end = 1000, tolerance "
                "1e-4) with the adaptive path on one core: status %s; wall time until it ended "
                "%s s (load at the start %s, at the end %s)." % (
                    ca.get("status", "unknown"), ca.get("wall_s"), ca.get("loadavg_start"),
                    ca.get("loadavg_end")), ""]
    return "\n".join(out)


STIFFNESS_FIGURE = "accuracy_stiffness.png"


def read_trials(path: str) -> list[dict]:
    """Rows of a knotflow-bench-reuse stiffness table (--table): one per trial step."""
    names = ("t", "h", "lambda", "lambda_h", "error_over_tol", "accepted", "lanczos_iterations")
    rows = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                rows.append(dict(zip(names, (float(x) for x in line.split()))))
    return rows


def plot_stiffness(tables: dict, boundary: float, path: str) -> None:
    """|lambda_max| h and the scaled error estimate of every trial step, per configuration."""
    fig, axes = plt.subplots(len(tables), 1, figsize=(9, 3.2*len(tables)), squeeze=False,
                             constrained_layout=True)
    for ax, (name, rows) in zip(axes[:, 0], sorted(tables.items())):
        acc = [r for r in rows if r["accepted"] == 1]
        rej = [r for r in rows if r["accepted"] == 0]
        ax.plot([r["t"] for r in acc], [r["lambda_h"] for r in acc], ".", ms=3,
                label="|λ_max| h, accepted")
        ax.plot([r["t"] for r in rej], [r["lambda_h"] for r in rej], "x", ms=5, color="C3",
                label="|λ_max| h, rejected")
        ax.plot([r["t"] for r in acc], [r["error_over_tol"] for r in acc], ".", ms=2,
                color="C2", alpha=0.6, label="error estimate / tolerance")
        ax.axhline(boundary, color="k", lw=0.8, ls="--", label="dopri45 stability boundary")
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("t")
        ax.set_ylim(0, 1.3*boundary)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
    save_figure(fig, path, dpi=110)
    plt.close(fig)


def _median(values: list[float]) -> float:
    v = sorted(values)
    if not v:
        return float("nan")
    return v[len(v)//2] if len(v) % 2 else 0.5*(v[len(v)//2 - 1] + v[len(v)//2])


def window_medians(rows: list[dict], boundary: float, t_lo: float, t_hi: float) -> dict:
    """Medians over the accepted steps that start in [t_lo, t_hi] of a stiffness table: |lambda| h
    over the stability boundary, the error estimate over the tolerance, the step h, and the
    step an accuracy limit alone would allow, h (tol/err)^(1/5) (dopri45's local error ~ h^5;
    indicative only)."""
    acc = [r for r in rows if r["accepted"] == 1 and t_lo <= r["t"] <= t_hi]
    if not acc:
        return {}
    return {"lambda_h_over_boundary": _median([r["lambda_h"]/boundary for r in acc]),
            "error_over_tol": _median([r["error_over_tol"] for r in acc]),
            "h": _median([r["h"] for r in acc]),
            "h_accuracy": _median([r["h"]*max(r["error_over_tol"], 1e-12)**(-0.2)
                                   for r in acc]),
            "steps": len(acc)}


def tolerance_rows(runs: dict, tables: dict, boundary: float) -> list[list[str]]:
    """Per configuration run at several tolerances: the medians over the window all its runs
    cover (from a tenth of the shortest t_end to it) and the exponent p of h ~ tol^p between
    consecutive tolerances (1/5 when accuracy sets the step, 0 when stability does)."""
    import math
    by_config: dict = {}
    for name, v in runs.items():
        key = name[len("stiffness_"):]
        if key in tables:
            # outputs without a tolerance line come from the benchmark before --tolerance,
            # which always ran at 1e-4
            by_config.setdefault(v.get("config", key), []).append(
                (float(v.get("tolerance", "1e-4")), float(v.get("t_end", "0")), key))
    out = []
    for config, items in sorted(by_config.items()):
        if len({tol for tol, _, _ in items}) < 2:
            continue
        t_hi = min(t for _, t, _ in items)
        prev = None
        for tol, _, key in sorted(items):
            m = window_medians(tables[key], boundary, 0.1*t_hi, t_hi)
            if not m:
                continue
            p = "–"
            if prev is not None and prev[0] != tol:
                p = "%.2f" % (math.log(m["h"]/prev[1])/math.log(tol/prev[0]))
            out.append([os.path.basename(config), "%.0e" % tol,
                         "%g–%g" % (0.1*t_hi, t_hi), str(m["steps"]),
                         "%.4f" % m["h"], "%.2f" % m["lambda_h_over_boundary"],
                         "%.3f" % m["error_over_tol"], p])
            prev = (tol, m["h"])
    return out


def stiffness_lines(runs: dict, figure: str | None = None,
                    tables: dict | None = None) -> list[str]:
    """The section on which limit sets the time step (stiffness_* outputs)."""
    st = [(k, v) for k, v in runs.items() if k.startswith("stiffness_")]
    if not st:
        return []
    rows = []
    for k, v in st:
        rows.append([k[len("stiffness_"):], v.get("t_end", "–"), v.get("update", "–"),
                     v.get("steps", "–"), v.get("rejected", "–"),
                     v.get("evaluations_per_time", "–"), v.get("h_mean", "–"),
                     "%s / %s / %s" % (v.get("lambda_min", "–"), v.get("lambda_mean", "–"),
                                       v.get("lambda_max", "–")),
                     v.get("lambda_h_mean_accepted", "–"), v.get("lambda_h_max_accepted", "–"),
                     v.get("accepted_above_0.9_boundary", "–"),
                     v.get("lambda_h_mean_rejected", "–"),
                     v.get("error_over_tol_mean_accepted", "–"), v.get("loadavg_start", "–")])
    out = ["## Which limit sets the time step", "",
           "Generated by `bash scripts/bench_reuse.sh stiffness` (knotflow-bench-reuse "
           "stiffness, then `knotflow-accuracy-report --stiffness`). "
           "dopri45 (tolerance 1e-4) along real runs with the study's model; at every trial step "
           "the stiffest eigenvalue λ_max of μ·∂F/∂r at its start (the exact mobility, the "
           "Jacobian of springs, bending and excluded volume by central differences; Lanczos "
           "iteration, kf_stiffness_probe), its product with the step size h, the embedded error "
           "estimate over the tolerance and the outcome. dopri45 is stable on the negative real "
           "axis up to \\|λh\\| = %s. \\|λ\\| min / mean / max over the trials." % (
               st[0][1].get("stability_boundary", "3.307")), "",
           _md_table(["run", "t_end", "update", "steps", "rejected",
                      "evaluations per unit time", "mean h", "\\|λ_max\\| min / mean / max",
                      "\\|λ\\|h mean (accepted)", "\\|λ\\|h max (accepted)",
                      "accepted with \\|λ\\|h > 0.9 boundary", "\\|λ\\|h mean (rejected)",
                      "error / tol mean (accepted)", "load"], rows), ""]
    if tables:
        boundary = float(st[0][1].get("stability_boundary", "3.307"))
        rows = []
        for name, trials in sorted(tables.items()):
            t_end = float(runs.get("stiffness_" + name, {}).get("t_end", "0"))
            m = window_medians(trials, boundary, 0.1*t_end, t_end)
            if m:
                rows.append([name, "%g–%g" % (0.1*t_end, t_end),
                             "%.2f" % m["lambda_h_over_boundary"],
                             "%.3f" % m["error_over_tol"], "%.4f" % m["h"],
                             "%.4f" % m["h_accuracy"]])
        out += ["Medians over the accepted steps after the first tenth of each window (the "
                "start-up ramp of the step size): \\|λ\\|h over the stability boundary, the "
                "error estimate over the tolerance, the step h, and h·(tol/err)^(1/5), the step "
                "dopri45's local error ∝ h^5 would allow if accuracy alone set it (indicative). "
                "The step controller (PI, safety 0.9, exponents 0.14 and 0.08) settles at an "
                "error estimate of 0.9^(1/0.06) ≈ 0.17 of the tolerance whichever limit binds, "
                "so the error column cannot tell the limits apart; the step's response to the "
                "tolerance can (next table).", "",
                _md_table(["run", "window", "\\|λ\\|h / boundary", "error / tol", "h",
                           "h·(tol/err)^(1/5)"], rows), ""]
        tol_rows = tolerance_rows(runs, tables, boundary)
        if tol_rows:
            out += ["The same configuration at several tolerances (eps_lub fixed at 1e-4), "
                    "medians over the window all its runs cover: the exponent p of h ∝ tol^p "
                    "between consecutive tolerances is 1/5 where accuracy sets the step and 0 "
                    "where stability does.", "",
                    _md_table(["configuration", "tolerance", "window", "steps", "h",
                               "\\|λ\\|h / boundary", "error / tol", "p"], tol_rows), ""]
    if figure:
        out += ["![stiffness](%s)" % figure, ""]
    return out


def update_stiffness(markdown: str, directory: str, figdir: str) -> str:
    """Replace the stiffness block of `markdown` (appended when missing) by the section of the
    knotflow-bench-reuse stiffness outputs in `directory` (NAME.txt keys, NAME.dat rows) and
    write its figure into `figdir`; returns the section."""
    runs = {k: v for k, v in read_reuse(directory).items() if k.startswith("stiffness_")}
    if not runs:
        raise FileNotFoundError("%s: no knotflow-bench-reuse stiffness outputs" % directory)
    tables = {k[len("stiffness_"):]: read_trials(os.path.join(directory, k + ".dat"))
              for k in runs if os.path.exists(os.path.join(directory, k + ".dat"))}
    figure = None
    if tables:
        os.makedirs(figdir, exist_ok=True)
        boundary = float(next(iter(runs.values())).get("stability_boundary", "3.307"))
        plot_stiffness(tables, boundary, os.path.join(figdir, STIFFNESS_FIGURE))
        rel = os.path.relpath(os.path.abspath(figdir),
                              os.path.dirname(os.path.abspath(markdown)))
        figure = os.path.join(rel, STIFFNESS_FIGURE)
    section = "\n".join(stiffness_lines(runs, figure, tables))
    write_block(markdown, section, STIFFNESS_BEGIN, STIFFNESS_END)
    return section


def write_block(markdown: str, section: str, begin: str, end: str) -> None:
    """Put `section` between the markers `begin` and `end` of the file `markdown` (the markers
    appended when missing, the file made when missing)."""
    text = ""
    if os.path.exists(markdown):
        with open(markdown) as f:
            text = f.read()
    if begin not in text:
        text = text.rstrip("\n") + "\n\n%s\n%s\n" % (begin, end)
    text = replace_block(text, section, begin, end, markdown)
    write_text(markdown, text)


def update_reuse(markdown: str, directory: str) -> str:
    """Replace the reuse block of the report `markdown` (appended when missing) by the section
    of the knotflow-bench-reuse outputs in `directory`; returns the section."""
    runs = read_reuse(directory)
    if not runs:
        raise FileNotFoundError("%s: no knotflow-bench-reuse outputs (*.txt)" % directory)
    section = reuse_section(runs)
    write_block(markdown, section, REUSE_BEGIN, REUSE_END)
    return section


def build_report(directory: str, markdown: str, figdir: str, readme: str | None = None) -> dict:
    """Write the markdown report and the figures; update the summary block of docs/models.md if asked."""
    if not os.path.exists(os.path.join(directory, "meta.csv")):
        raise FileNotFoundError("%s: no meta.csv (run knotflow-accuracy first)" % directory)
    os.makedirs(figdir, exist_ok=True)
    os.makedirs(os.path.dirname(os.path.abspath(markdown)), exist_ok=True)
    figures = []
    models = read_table(directory, "models.csv")
    if models:
        figures.append(os.path.join(figdir, "accuracy_error_cost.png"))
        plot_errors(models, figures[-1])
    tol = read_table(directory, "tolerance.csv")
    if tol:
        figures.append(os.path.join(figdir, "accuracy_tolerance.png"))
        plot_tolerance(tol, figures[-1])
    scaling = read_table(directory, "scaling.csv")
    if scaling:
        figures.append(os.path.join(figdir, "accuracy_scaling.png"))
        plot_scaling(scaling, read_table(directory, "scaling_fit.csv"), figures[-1])
    rel = os.path.relpath(os.path.abspath(figdir), os.path.dirname(os.path.abspath(markdown)))
    text, summary = build_markdown(directory, rel)
    old = ""
    if os.path.exists(markdown):
        with open(markdown) as f:
            old = f.read()
    kept = kept_part(old)
    if kept:
        text = text.rstrip("\n") + "\n\n" + kept
    write_text(markdown, text)
    if readme and summary:
        meta = _meta(directory)
        block = ("Measured by `bash scripts/accuracy.sh`%s (load average %s; details and "
                 "figures in [accuracy.md](accuracy.md)):\n\n%s" % (
                     " **--quick: smoke-test sizes, not the real figures**"
                     if meta.get("quick") == "1" else "",
                     meta.get("loadavg_start", "unknown") + (
                         "; at the end %s" % meta["loadavg_end"] if "loadavg_end" in meta
                         else ""), summary))
        update_readme(readme, block)
    return {"markdown": markdown, "figures": figures, "summary": summary}


