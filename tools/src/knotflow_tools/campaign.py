"""A long campaign that outlives the machine it runs on: the case ledger.

A sweep whose cases run for longer than a machine is kept (a session, a cluster allocation, a
scratch file system that is purged) loses its case files with the machine. The ledger keeps what
the study needs of each case in small text files that are committed, and what is needed to go on:

    LEDGER/<sweep>/<case>.json            status, time reached and the frame there at full
                                          precision (where to go on: one record, written last,
                                          so the two always agree), the time stepper's state
                                          at that frame while the case runs (`stepper_state`:
                                          the case file's newest checkpoint's, when it is that
                                          frame), the case's scene, its segments (file, time
                                          offset, run records, overlap totals, whether it
                                          started from a stepper state)
    LEDGER/<sweep>/<case>.csv             one row per frame: FRAME_COLUMNS (time of the whole
                                          case, k_f of knotflow-analyze, shape, mode, overlaps,
                                          stresslet and its elastic part of the viscosity; 7
                                          significant digits)
    LEDGER/<sweep>/<case>.positions.tNNNNN.gz
                                          frames every `positions_every` time units (4 decimals;
                                          columns t x y z, a frame's beads in order), one file
                                          per POSITIONS_CHUNK time units from NNNNN (gzip without
                                          a time stamp: a finished chunk never changes, so the
                                          history does not grow with it): snapshots, knot
                                          matrices, slipknot confirmation

`digest` adds an analysed case file (a copy, after knotflow-analyze) to the ledger. `plan`
says for each case of a sweep what to run next: nothing (finished), the case's own scene
(`knotflow --write-scenes`; it starts the case or resumes its file on this machine), or, when
the ledger is ahead of this machine, a continuation: the case's scene started from
the ledger's newest frame for the time still to run, written as `<case>_from<T>` (T: the time
reached), with the stepper's state at that frame where the ledger has it (`<case>_from<T>.state.h5`,
`&chain stepper_state`).
Simple shear v0 = (z, 0, 0) does not depend on time, so a continuation with the stepper's state
computes what the case's own resume would: the stepper goes on with its step size, error history
and FSAL stage; what a resume also starts afresh (a multipole model's reuse or iterative
reference) does here too, and an overlap episode open at T is counted as two. Without a state
(an entry digested before states were kept, or whose newest checkpoint was not its newest frame)
the stepper starts afresh at dt_initial: another trajectory within the integration tolerance
(`continued_at`). The rows of a continuation are the ledger's rows from T on, at time T + t.
"""

from __future__ import annotations

import glob
import gzip
import io as _io
import json
import math
import os
import re

import h5py
import numpy as np

from .atomic import write_bytes
from .atomic import write_text as _write_text
from .io import RUN_FIELDS, open_case, read_case, read_runs, write_xyz
from .names import check_case_name

#: Version 2 added the column viscosity_elastic; entries of version 1 are read with it NaN.
LEDGER_VERSION = 2
READ_VERSIONS = (1, 2)
FRAME_COLUMNS = ("t", "kf", "rg", "a", "b", "c", "theta", "phi", "close_pairs", "mode",
                 "overlapping_pairs", "min_distance", "strand_passages",
                 "viscosity", "psi1", "psi2", "viscosity_elastic")
#: The columns of a version 1 ledger (FRAME_COLUMNS without those added since).
FRAME_COLUMNS_V1 = FRAME_COLUMNS[:16]
#: Times of two segments closer than this (in units of 1/shear rate) are the same time.
TIME_TOLERANCE = 1e-6
#: Time units of kept positions per file.
POSITIONS_CHUNK = 200.0
_CONTINUATION = re.compile(r"^(?P<case>.+)_from(?P<t>[0-9]+(?:\.[0-9]+)?)$")


def continuation_name(case: str, t: float) -> str:
    """Case name of the continuation of `case` from time `t` (e.g. A1.00_from1200)."""
    return f"{case}_from{t:g}"


def split_name(name: str) -> tuple[str, float]:
    """(case, time offset) of a case file's name: a continuation's or (name, 0)."""
    m = _CONTINUATION.match(name)
    return (m["case"], float(m["t"])) if m else (name, 0.0)


def continued_at(case) -> list:
    """The times at which a case (io.Case of a case file or of a ledger entry) was continued
    from the case ledger (its segments `<case>_from<T>`, or a case file of such a segment)
    without the stepper's state: there its stepper started afresh from the ledger's frame,
    without the step-size history of the uninterrupted run. Empty for a case run in one piece,
    resumed from its own checkpoint or continued from the ledger's stepper state (`&chain
    stepper_state`: both keep the stepper's state)."""
    at = case.attrs.get("continued_at")
    if at is not None:
        return [float(t) for t in at]
    name = case.attrs.get("case_name")
    t = split_name(name)[1] if isinstance(name, str) else 0.0
    return [t] if t > 0.0 and not from_state(case.attrs.get("scene")) else []


def from_state(scene) -> bool:
    """Whether a scene text started its run from a stepper state (a non-empty `&chain
    stepper_state`)."""
    if not isinstance(scene, str) or not scene:
        return False
    return bool(_scene_value(scene, "chain", "stepper_state"))


def _paths(ledger: str, sweep: str, case: str) -> dict:
    base = os.path.join(ledger, sweep, case)
    return {k: base + ext for k, ext in (("json", ".json"), ("csv", ".csv"),
                                         ("positions", ".positions"))}


def _chunk_files(ledger: str, sweep: str, case: str) -> list:
    base = _paths(ledger, sweep, case)["positions"]
    return sorted(glob.glob(glob.escape(base) + ".t[0-9][0-9][0-9][0-9][0-9].gz"))


def load(ledger: str, sweep: str, case: str) -> dict | None:
    """The ledger entry of a case (its JSON), None when the ledger has none."""
    path = _paths(ledger, sweep, case)["json"]
    if not os.path.exists(path):
        return None
    with open(path, encoding="utf-8") as fh:
        entry = json.load(fh)
    if entry.get("ledger_version") not in READ_VERSIONS:
        raise ValueError(f"{path}: ledger_version {entry.get('ledger_version')!r} "
                         f"(this tool reads {', '.join(map(str, READ_VERSIONS))})")
    return entry


def read_rows(ledger: str, sweep: str, case: str) -> np.ndarray:
    """The frame rows (frames, len(FRAME_COLUMNS)) of a case; empty without any."""
    path = _paths(ledger, sweep, case)["csv"]
    if not os.path.exists(path):
        return np.zeros((0, len(FRAME_COLUMNS)))
    with open(path, encoding="utf-8") as fh:
        header = fh.readline().strip().split(",")
    if tuple(header) not in (FRAME_COLUMNS, FRAME_COLUMNS_V1):
        raise ValueError(f"{path}: columns {header}, expected {list(FRAME_COLUMNS)} "
                         f"(or, version 1, {list(FRAME_COLUMNS_V1)})")
    rows = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    if len(header) < len(FRAME_COLUMNS):
        pad = np.full((len(rows), len(FRAME_COLUMNS) - len(header)), np.nan)
        rows = np.hstack([rows.reshape(len(rows), len(header)), pad])
    return rows


def read_positions(ledger: str, sweep: str, case: str) -> tuple[np.ndarray, np.ndarray]:
    """Times (k,) and positions (k, N, 3) of the frames the ledger keeps."""
    entry = load(ledger, sweep, case)
    files = _chunk_files(ledger, sweep, case)
    if entry is None or not files:
        return np.zeros(0), np.zeros((0, 0, 3))
    n = int(entry["n_beads"])
    parts = []
    for path in files:
        data = np.loadtxt(path, ndmin=2)
        if data.shape[1] != 4 or len(data) % n:
            raise ValueError(f"{path}: {data.shape} is not rows of t x y z, {n} beads per frame")
        parts.append(data.reshape(-1, n, 4))
    data = np.concatenate(parts)
    return data[:, 0, 0], data[:, :, 1:]


def _write_positions(ledger: str, sweep: str, case: str, times, frames) -> None:
    """The kept frames (times, frames (k, N, 3)) into their chunk files, each rewritten only
    when its bytes change; chunk files of no kept frame are removed."""
    base = _paths(ledger, sweep, case)["positions"]
    keys = [int(t // POSITIONS_CHUNK) * int(POSITIONS_CHUNK) for t in times]
    wanted = {}
    for key in sorted(set(keys)):
        buf = _io.StringIO()
        block = [np.column_stack([np.full(len(r), t), r])
                 for t, r, k in zip(times, frames, keys) if k == key]
        np.savetxt(buf, np.vstack(block), fmt="%.4f")
        data = gzip.compress(buf.getvalue().encode(), mtime=0)
        path = f"{base}.t{key:05d}.gz"
        wanted[path] = True
        if os.path.exists(path):
            with open(path, "rb") as fh:
                if fh.read() == data:
                    continue
        write_bytes(path, data)
    for path in _chunk_files(ledger, sweep, case):
        if path not in wanted:
            os.remove(path)


def _column(values, n) -> np.ndarray:
    return np.full(n, np.nan) if values is None else np.asarray(values, dtype=float)[:n]


def frame_kf(case) -> np.ndarray | None:
    """k_f of every frame of a case (/analysis/knots; NaN at the frames not analysed), None
    when the case has no /analysis/knots."""
    if case.knots is None:
        return None
    kf = np.full(case.nframes, np.nan)
    kf[np.asarray(case.knots["frame_index"], dtype=int)] = case.knots["kf"]
    return kf


def frame_rows(case, offset: float) -> np.ndarray:
    """FRAME_COLUMNS of every frame of an analysed case (k_f and modes from /analysis; NaN
    where the file has none), at time offset + t."""
    n = case.nframes
    kf = frame_kf(case)
    if kf is None:
        raise ValueError(f"{case.path}: no /analysis/knots (run knotflow-analyze first)")
    obs = case.observables
    diag = case.diagnostics or {}
    st = case.stresslet or {}
    modes = case.modes if case.modes is not None and len(case.modes) == n else None
    cols = [offset + case.time, kf] + [_column(obs.get(k), n) for k in FRAME_COLUMNS[2:9]]
    cols.append(_column(modes, n))
    cols += [_column(diag.get(k), n) for k in ("overlapping_pairs", "min_distance",
                                               "strand_passages")]
    cols += [_column(st.get(k), n) for k in ("viscosity", "psi1", "psi2", "viscosity_elastic")]
    return np.column_stack(cols)


def _rows_text(rows: np.ndarray) -> str:
    lines = [",".join(FRAME_COLUMNS)]
    for r in rows:
        lines.append(",".join("nan" if not math.isfinite(v) else f"{v:.7g}" for v in r))
    return "\n".join(lines) + "\n"


def _json_value(v):
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, (np.floating, np.integer)):
        return _json_value(v.item())
    return v


def digest(path: str, ledger: str, sweep: str, closures: int, positions_every: float = 0.0,
           source: str | None = None, defaults: dict | None = None) -> dict:
    """Add an analysed case file (`path`; `source`: where the file it copies runs, recorded
    as the segment's file) to the ledger and return the case's entry.

    Refused (ValueError, nothing written): k_f not from `closures` closures per frame, a file
    that would leave a gap or rewrite an earlier segment than the newest, another scene (a new
    segment's scene against the ledger's, `same_scene`; `defaults` from `scene_defaults`), a
    case name that is not a case name by the scene's rule (knotflow_tools.names): the ledger's
    file names are derived from it, so it must not be a path."""
    case = read_case(path)
    name, offset = split_name(check_case_name(case.name, f"{path}: attribute case_name"))
    entry = load(ledger, sweep, name)
    if case.knots is None:
        raise ValueError(f"{path}: no /analysis/knots (run knotflow-analyze first)")
    got = case.knots["attrs"].get("closures")
    if got is None or int(got) != closures:
        raise ValueError(f"{path}: k_f from {got} closures per frame, the ledger takes {closures} "
                         "(knotflow-analyze --closures)")
    if len(case.knots["frame_index"]) != case.nframes:
        raise ValueError(f"{path}: k_f of {len(case.knots['frame_index'])} of "
                         f"{case.nframes} frames (knotflow-analyze --stride 1)")
    runs = case.runs or []
    ident = {"file": source or path, "case_name": case.name,
             "started": runs[0]["started"] if runs else ""}
    segments = [] if entry is None else entry["segments"]
    same = [k for k, s in enumerate(segments)
            if s["case_name"] == ident["case_name"] and s["started"] == ident["started"]]
    if same and same[0] != len(segments) - 1:
        raise ValueError(f"{path}: segment {same[0] + 1} of {len(segments)} in the ledger; only "
                         "the newest segment can be extended")
    if not same:
        reached = 0.0 if entry is None else float(entry["t_reached"])
        if abs(offset - reached) > TIME_TOLERANCE or (entry is None and offset != 0.0):
            raise ValueError(f"{path}: starts at t = {offset:g}, the ledger of {sweep}/{name} "
                             f"reaches t = {reached:g}: a segment must go on where it ends")
    if entry is not None and segments and not same:
        differ = scene_differences(entry["scene"], str(case.attrs.get("scene", "")), defaults or {})
        if differ:
            raise ValueError(f"{path}: another scene than the ledger's {sweep}/{name}: "
                             + "; ".join(differ))
    p = _paths(ledger, sweep, name)
    os.makedirs(os.path.dirname(p["json"]), exist_ok=True)
    old = read_rows(ledger, sweep, name)
    new = frame_rows(case, offset)
    rows = np.vstack([old[old[:, 0] < new[0, 0] - TIME_TOLERANCE], new])
    t_end_case = float(case.attrs.get("integrator.t_end", math.nan)) + offset
    segment = {**ident, "t_offset": offset, "t_first": float(new[0, 0]),
               "t_last": float(new[-1, 0]), "status": case.status,
               "from_state": from_state(case.attrs.get("scene")),
               "git_hash": str(case.attrs.get("git_hash", "")),
               "runs": [{k: _json_value(r.get(k)) for k in RUN_FIELDS} for r in runs],
               "diagnostic_totals": {k: _json_value(v)
                                     for k, v in (case.diagnostic_totals or {}).items()}}
    segments = segments[:same[0]] if same else list(segments)
    segments.append(segment)
    t_end = entry["t_end"] if entry is not None else t_end_case
    # Finished: the file is, or its rows reach t_end (a run killed while it was being marked
    # finished has every frame; there is nothing left to run).
    finished = case.status == "finished" or float(rows[-1, 0]) >= t_end - TIME_TOLERANCE
    scene = entry["scene"] if entry is not None else str(case.attrs.get("scene", ""))
    entry = {"ledger_version": LEDGER_VERSION, "sweep": sweep, "case": name,
             "status": "finished" if finished else "running",
             "t_end": t_end,
             "t_reached": float(rows[-1, 0]), "n_beads": int(case.positions.shape[1]),
             "kf_closures": closures, "positions_every": positions_every,
             "last_frame": [[float(x) for x in r] for r in case.positions[-1]],
             "scene": scene, "segments": segments}
    st = case.stepper_state
    if not finished and st is not None and abs(offset + st["time"] - entry["t_reached"]) <= TIME_TOLERANCE:
        entry["stepper_state"] = {"t": entry["t_reached"], "t_local": st["time"],
                                  "method": st["method"], "reals": st["reals"], "ints": st["ints"]}
    # Positions: the kept frames before this segment, then this segment's.
    kept_t, kept = read_positions(ledger, sweep, name)
    chosen = _every(new[:, 0], positions_every) if positions_every > 0 else []
    keep = kept_t < new[0, 0] - TIME_TOLERANCE
    times = list(kept_t[keep]) + [float(new[k, 0]) for k in chosen]
    frames = list(kept[keep]) + [case.positions[k] for k in chosen]
    if times:
        _write_positions(ledger, sweep, name, times, frames)
    _write_text(p["csv"], _rows_text(rows))
    _write_text(p["json"], json.dumps(entry, indent=1) + "\n")
    return entry


def _every(times: np.ndarray, every: float) -> list:
    """Indices of the frames at the multiples of `every` (and the last frame)."""
    ratio = times / every
    idx = [k for k, r in enumerate(ratio) if abs(r - round(r)) < TIME_TOLERANCE / every]
    if len(times) and (not idx or idx[-1] != len(times) - 1):
        idx.append(len(times) - 1)
    return idx


def scene_defaults(reference: str) -> dict:
    """{(group, variable): default} from the Markdown of `knotflow --scene-reference` (its
    sections "## `&group`" and table rows "| `variable` | `default` | ..."): the defaults of
    the program that wrote it, the one source of them."""
    out: dict = {}
    group = None
    for line in reference.splitlines():
        m = re.match(r"## `&(\w+)`", line)
        if m:
            group = m.group(1)
            continue
        m = re.match(r"\| `(\w+)` \| `([^`]*)` \|", line)
        if m and group:
            out[(group, m.group(1))] = m.group(2)
    return out


def _scene_values(text: str) -> dict:
    """{(group, variable): value text} of a scene text (one `variable = value` a line, as
    knotflow writes scenes; a line without `=` continues the value before it), without what a
    continuation changes: &chain, &output, t_end and dt_initial."""
    out: dict = {}
    for group, body in re.findall(r"&(\w+)\n(.*?)\n/", text, flags=re.S):
        if group in ("chain", "output"):
            continue
        key = None
        for line in body.splitlines():
            m = re.match(r"\s*(\w+)\s*=\s*(.*)$", line)
            if m:
                key = (group, m.group(1))
                out[key] = m.group(2).strip()
            elif key is not None and line.strip():
                out[key] += " " + line.strip()
    for key in [k for k in out if k[1] in ("t_end", "dt_initial")]:
        del out[key]
    return out


def _same_value(a: str, b: str) -> bool:
    """Two value texts of one variable are the same value: numbers (also lists of them, in any
    of Fortran's real formats) to 1e-12 relative, anything else as text without quotes, spaces
    and case."""
    def numbers(v):
        try:
            return [float(x.replace("d", "e").replace("D", "e")) for x in v.rstrip(",").split(",")]
        except ValueError:
            return None
    na, nb = numbers(a), numbers(b)
    if na is not None and nb is not None:
        return len(na) == len(nb) and all(math.isclose(x, y, rel_tol=1e-12, abs_tol=0.0)
                                          for x, y in zip(na, nb))
    def norm(v):
        return v.replace("'", "").replace('"', "").replace(" ", "").lower()
    return norm(a) == norm(b)


def scene_differences(ledger_scene: str, case_scene: str, defaults: dict) -> list:
    """What makes a new segment's scene another scene than the ledger's (empty: the same),
    each as '&group variable: ledger value, segment value'; &chain, &output, t_end and
    dt_initial are what a continuation changes and are not compared. A variable written in one
    text only (a scene variable added to, or written by, a later version of the program) is
    the same when its value is the program's default (`defaults`, `scene_defaults`): the older
    text ran with that value."""
    a, b = _scene_values(ledger_scene), _scene_values(case_scene)
    out = []
    for key in sorted(set(a) | set(b)):
        va, vb = a.get(key), b.get(key)
        if va is not None and vb is not None:
            same = _same_value(va, vb)
        else:
            d = defaults.get(key)
            written = va if va is not None else vb
            same = d is not None and written is not None and _same_value(written, d)
        if not same:
            out.append(f"&{key[0]} {key[1]}: {va if va is not None else '(not written)'}, "
                       f"{vb if vb is not None else '(not written)'}")
    return out


def _scene_setting(group: str, var: str):
    """The line `var = value` of group &group of a scene text (kf_scene_items: scene_text):
    group 1 is the text before it from the group's start, group 2 the value."""
    return re.compile(rf"(&{group}\n(?:(?!/\n).*\n)*?)\s*{var} = ([^\n]*)\n")


def continuation_scene(entry: dict, coordinate_file: str, directory: str,
                       state_file: str | None = None) -> str:
    """The scene that continues a ledger case from its newest frame (`coordinate_file`, a copy
    of the entry's last_frame) for the time still to run, into `directory`; with `state_file`
    (`write_state_file`) from the stepper's state at that frame (`&chain stepper_state`), so
    that it goes on as the case's own resume would. The &chain perturbation is set to 0: a
    sample's displacement belongs to its start, and the frame already holds it (knotflow
    displaces a file's beads too when perturbation > 0)."""
    text = entry["scene"]
    t_reached, t_end = float(entry["t_reached"]), float(entry["t_end"])
    if not t_end - t_reached > TIME_TOLERANCE:
        raise ValueError(f"{entry['sweep']}/{entry['case']}: nothing left to run "
                         f"(t = {t_reached:g} of {t_end:g})")

    def setting(txt, group, var, value):
        pat = _scene_setting(group, var)
        if not pat.search(txt):
            raise ValueError(f"{entry['case']}: the ledger's scene has no &{group} {var}")
        return pat.sub(lambda m: m.group(1) + f"  {var} = {value}\n", txt, count=1)

    text = setting(text, "chain", "shape", "'file'")
    text = setting(text, "chain", "coordinate_file", f"'{coordinate_file}'")
    if state_file is not None:
        if _scene_setting("chain", "stepper_state").search(text):
            text = setting(text, "chain", "stepper_state", f"'{state_file}'")
        else:   # a scene written before the variable existed
            text = re.sub(r"(&chain\n(?:(?!/\n).*\n)*?)(/\n)",
                          lambda m: m.group(1) + f"  stepper_state = '{state_file}'\n" + m.group(2),
                          text, count=1)
    if _scene_setting("chain", "perturbation").search(text):
        text = setting(text, "chain", "perturbation", "0.0")
    text = setting(text, "integrator", "t_end", f"{t_end - t_reached:.17g}")
    text = setting(text, "output", "directory", f"'{directory}'")
    text = setting(text, "output", "case_name",
                   f"'{continuation_name(entry['case'], t_reached)}'")
    return (f"! {entry['sweep']}/{entry['case']} from t = {t_reached:g} to {t_end:g} "
            "(knotflow-campaign plan)\n" + text)


def plan(scenes_dir: str, results: str, ledger: str, sweep: str) -> list:
    """What to run next for each case of a sweep, in the order of its scenes
    (`knotflow --write-scenes` into scenes_dir): a list of (case, action, scene path or None),
    action 'finished', 'run' (the case's scene: starts it, or resumes its file here) or
    'continue' (a continuation scene, written to results/<sweep>/continued/)."""
    names = sorted(f[:-4] for f in os.listdir(scenes_dir) if f.endswith(".nml"))
    out: list[tuple[str, str, str | None]] = []
    for name in names:
        scene = os.path.join(scenes_dir, name + ".nml")
        check_case_name(name, scene)
        entry = load(ledger, sweep, name)
        if entry is None:
            out.append((name, "run", scene))
            continue
        if entry["status"] == "finished":
            out.append((name, "finished", None))
            continue
        here = [s for s in entry["segments"][-1:]
                if os.path.exists(s["file"]) and _started(s["file"]) == s["started"]]
        if here:   # the newest segment's file is on this machine: resume it
            last = entry["segments"][-1]
            own = last["case_name"] == name
            out.append((name, "run", scene if own else _continuation_path(results, sweep, last)))
            continue
        cdir = os.path.join(results, sweep, "continued")
        os.makedirs(cdir, exist_ok=True)
        cname = continuation_name(name, float(entry["t_reached"]))
        xyz = os.path.abspath(os.path.join(cdir, cname + ".xyz"))
        write_xyz(xyz, np.asarray(entry["last_frame"], dtype=float),
                  comment=f"{sweep}/{name} at t = {entry['t_reached']:.17g} (the case ledger)")
        state = None
        if usable_state(entry):
            state = os.path.abspath(os.path.join(cdir, cname + ".state.h5"))
            write_state_file(state, entry)
        path = os.path.join(cdir, cname + ".nml")
        _write_text(path, continuation_scene(entry, xyz, cdir, state))
        out.append((name, "continue", path))
    return out


def usable_state(entry: dict) -> bool:
    """Whether a running ledger entry's stepper state (`digest`: the newest checkpoint's, kept
    when it is the newest frame) continues it: of the entry's newest frame and of the stepper
    its scene runs (an entry digested before states were kept has none: it is continued from
    its frame alone, the stepper afresh)."""
    st = entry.get("stepper_state")
    return (st is not None and abs(float(st["t"]) - float(entry["t_reached"])) <= TIME_TOLERANCE
            and st["method"] == _scene_value(entry["scene"], "integrator", "method"))


def write_state_file(path: str, entry: dict) -> None:
    """The stepper state file of a ledger entry's newest frame (the layout knotflow reads,
    kf_stepper_state_file): /time on the clock of the segment it comes from, /positions (the
    entry's last_frame), /stepper/reals, /stepper/ints and the method's name. Made in memory
    and written whole (knotflow_tools.atomic)."""
    st = entry["stepper_state"]
    image = _io.BytesIO()
    with h5py.File(image, "w") as h:
        h["time"] = float(st["t_local"])
        h["positions"] = np.asarray(entry["last_frame"], dtype=np.float64)
        g = h.create_group("stepper")
        g["reals"] = np.asarray(st["reals"], dtype=np.float64)
        g["ints"] = np.asarray(st["ints"], dtype=np.int64)
        g.attrs["name"] = st["method"]
    write_bytes(path, image.getvalue())


def _continuation_path(results: str, sweep: str, segment: dict) -> str:
    name = check_case_name(segment["case_name"], f"ledger of {sweep}: segment {segment.get('file')}")
    return os.path.join(results, sweep, "continued", name + ".nml")


def _started(path: str) -> str:
    """`started` of the first /runs record of a case file ("" when unreadable): only /runs is
    read, not the frames."""
    try:
        with open_case(path) as f:
            runs = read_runs(path, f)
    except (OSError, ValueError):
        return ""
    return runs[0]["started"] if runs else ""


def _run_totals(entry: dict) -> tuple[float, float, float, str]:
    """Of a case's runs: their wall seconds; the wall seconds and the wall-weighted load sum of
    those that recorded a load (their mean load is the ratio); their commits."""
    runs = [r for s in entry["segments"] for r in s["runs"]]
    loaded = [(r["wall_seconds"], r["load_mean"]) for r in runs
              if r["wall_seconds"] and r["load_mean"] is not None]
    return (sum(r["wall_seconds"] or 0.0 for r in runs), sum(w for w, _ in loaded),
            sum(w * x for w, x in loaded), ",".join(dict.fromkeys(str(r["commit"])[:7] for r in runs)))


def _ratio(a: float, b: float) -> float:
    return a / b if b > 0.0 else math.nan


def _known_blas(run: dict) -> bool:
    return run.get("blas") not in (None, "unknown", "")


def _newest_kernels_rate(runs: list) -> tuple[str, float, float, float, float] | None:
    """(kernels, wall seconds, time units, wall-weighted load sum, wall with a load) of the runs
    that ran on the BLAS kernels of the newest run that recorded its kernels (`started` is ISO
    8601 UTC, so it sorts by time), None when no run recorded them or those runs covered no time.
    A sweep's rate is taken from these, because the kernels change the speed several-fold
    (docs/models.md) and a campaign's older runs may have had slower ones."""
    known = [r for r in runs if _known_blas(r) and r.get("started")]
    if not known:
        return None
    kernels = max(known, key=lambda r: str(r["started"]))["blas"]
    same = [r for r in known if r["blas"] == kernels and r.get("wall_seconds")
            and r.get("t_end") is not None and r.get("t_start") is not None]
    span = sum(float(r["t_end"]) - float(r["t_start"]) for r in same)
    if span <= 0.0:
        return None
    loaded = [(r["wall_seconds"], r["load_mean"]) for r in same if r.get("load_mean") is not None]
    return (str(kernels), sum(r["wall_seconds"] for r in same), span,
            sum(w * x for w, x in loaded), sum(w for w, _ in loaded))


def _alike(scene_a: str, scene_b: str, defaults: dict) -> bool:
    """Two scenes whose cases cost alike per time unit: the same chain shape and number of
    beads and the same hydrodynamics, integration, flow and forces but for the bending
    stiffness (`scene_differences` with `defaults`; the chain's orientation, seed and
    perturbation, its stiffness and the output may differ)."""
    for var in ("shape", "n_beads"):
        if _scene_value(scene_a, "chain", var) != _scene_value(scene_b, "chain", var):
            return False
    return all(d.startswith("&forces bending_a:")
               for d in scene_differences(scene_a, scene_b, defaults))


def status(ledger: str, scenes: str | None = None, defaults: dict | None = None) -> dict:
    """Where a campaign stands, from its ledger: "cases", per case of the ledger (sweep, case,
    status, t_reached, t_end, segments, wall seconds and mean load of its runs, weighted by wall
    time, commits); "sweeps", per sweep (cases, finished, running and, with `scenes`, the
    campaign's scene directories <scenes>/<sweep>/<case>.nml, not started; the running cases
    with their time; its measured rate: wall seconds of its runs per time unit reached, at their
    mean load, only the runs on the newest BLAS kernels when runs recorded them,
    _newest_kernels_rate; the wall seconds one worker still needs at that rate, NaN without a
    rate); "campaign" (with `scenes`): cases, finished, seconds left, whether every sweep with
    time left had a rate. A sweep with time left and no rate of its own takes the pooled rate
    of the sweeps with one whose scenes are alike (`_alike`, with `defaults` from
    `scene_defaults` completing variables an older scene did not write); "rate_from" names
    them (empty: its own rate or none)."""
    out: dict = {"cases": [], "sweeps": [], "campaign": None}
    defaults = defaults or {}
    # sweeps with a rate of their own: {sweep: (scene, [wall, time units, load x wall, loaded
    # wall], kernels)}; per sweep of out["sweeps"], its time left and scene
    measured: dict = {}
    left_and_scene: list = []
    sweeps = {d for d in os.listdir(ledger) if os.path.isdir(os.path.join(ledger, d))}
    if scenes is not None:
        sweeps |= {d for d in os.listdir(scenes) if os.path.isdir(os.path.join(scenes, d))}
    left_total, counted, cases_total, finished_total = 0.0, True, 0, 0
    for sweep in sorted(sweeps):
        names = set()
        if os.path.isdir(os.path.join(ledger, sweep)):
            names |= {f[:-5] for f in os.listdir(os.path.join(ledger, sweep)) if f.endswith(".json")}
        scene_dir = os.path.join(scenes, sweep) if scenes is not None else None
        if scene_dir is not None and os.path.isdir(scene_dir):
            names |= {f[:-4] for f in os.listdir(scene_dir) if f.endswith(".nml")}
        count = {"finished": 0, "running": 0, "not started": 0}
        wall_sum = loaded_sum = load_sum = t_sum = t_left = 0.0
        scene = None
        sweep_runs: list = []
        running = []
        for name in sorted(names):
            e = load(ledger, sweep, name)
            if e is None:   # a scene without a ledger entry
                with open(os.path.join(str(scene_dir), name + ".nml"), encoding="utf-8") as fh:
                    text = fh.read()
                t_end = _scene_value(text, "integrator", "t_end")
                scene = scene or text
                count["not started"] += 1
                t_left += float(t_end) if t_end is not None else math.nan
                continue
            scene = scene or e.get("scene")
            wall, loaded, load_w, commits = _run_totals(e)
            sweep_runs += [r for seg in e["segments"] for r in seg["runs"]]
            count[e["status"]] = count.get(e["status"], 0) + 1
            wall_sum, loaded_sum, load_sum = wall_sum + wall, loaded_sum + loaded, load_sum + load_w
            t_sum += float(e["t_reached"])
            if e["status"] != "finished":
                t_left += max(float(e["t_end"]) - float(e["t_reached"]), 0.0)
                running.append((e["case"], float(e["t_reached"])))
            out["cases"].append({"sweep": sweep, "case": e["case"], "status": e["status"],
                                 "t_reached": float(e["t_reached"]), "t_end": float(e["t_end"]),
                                 "segments": len(e["segments"]), "wall": wall,
                                 "load": _ratio(load_w, loaded), "commits": commits})
        cases_total += len(names)
        finished_total += count["finished"]
        newest = _newest_kernels_rate(sweep_runs)
        kernels = ""
        if newest is not None:
            kernels, wall_sum, t_sum, load_sum, loaded_sum = newest
        rate = left = load_rate = math.nan
        if wall_sum > 0.0 and t_sum > 0.0:
            rate, load_rate = wall_sum / t_sum, _ratio(load_sum, loaded_sum)
            left = rate * t_left
            if scene is not None:
                measured[sweep] = (scene, [wall_sum, t_sum, load_sum, loaded_sum], kernels)
        out["sweeps"].append({"sweep": sweep, "cases": len(names), "finished": count["finished"],
                              "running": running, "not_started": count["not started"],
                              "rate": rate, "load": load_rate, "kernels": kernels,
                              "left": left, "rate_from": []})
        left_and_scene.append((t_left, scene))
    for w, (t_left, scene) in zip(out["sweeps"], left_and_scene):
        if math.isnan(w["rate"]) and t_left > 0.0 and scene is not None:
            donors = [d for d in sorted(measured) if _alike(scene, measured[d][0], defaults)]
            if donors:
                wall, span, load_w, loaded = (sum(x) for x in zip(*(measured[d][1] for d in donors)))
                kernels = ", ".join(sorted({measured[d][2] for d in donors if measured[d][2]}))
                w.update(rate=wall / span, load=_ratio(load_w, loaded), kernels=kernels,
                         left=wall / span * t_left, rate_from=donors)
        if not math.isnan(w["left"]):
            left_total += w["left"]
        else:
            counted = counted and t_left == 0.0
    if scenes is not None:
        out["campaign"] = {"cases": cases_total, "finished": finished_total, "left": left_total,
                           "counted": counted}
    return out


def status_lines(ledger: str, scenes: str | None = None, defaults: dict | None = None) -> list:
    """`status` as text: one line per case of the ledger, then one per sweep (cases finished,
    running and, with `scenes`, not started; rate and time left) and, with `scenes`, a last
    line for the whole campaign."""
    st = status(ledger, scenes, defaults)
    lines = [f"{c['sweep']}/{c['case']}: {c['status']}, t = {c['t_reached']:g} of "
             f"{c['t_end']:g}, {c['segments']} segment(s), wall {c['wall'] / 3600:.2f} h, load "
             f"{c['load']:.1f}, commits {c['commits']}" for c in st["cases"]]
    for w in st["sweeps"]:
        text = (f"{w['sweep']}: {w['finished']} of {w['cases']} finished, {len(w['running'])} "
                "running" + (f", {w['not_started']} not started" if scenes is not None else ""))
        if math.isnan(w["rate"]):
            text += "; no rate measured yet"
        else:
            if w["rate_from"]:
                text += (f"; no rate measured yet, at that of {', '.join(w['rate_from'])} (alike "
                         "scenes):")
            else:
                text += ";"
            text += (f" {w['rate']:.2f} s of wall per time unit (load {w['load']:.1f}"
                     + (f", runs with {w['kernels']}" if w["kernels"] else "") + "): "
                     f"about {w['left'] / 3600:.1f} h of one worker left")
        lines.append(text)
    c = st["campaign"]
    if c is not None:
        lines.append(f"campaign: {c['finished']} of {c['cases']} cases finished; {_left_text(c)}")
    return lines


def status_markdown(ledger: str, scenes: str | None = None, defaults: dict | None = None) -> list:
    """`status` as a markdown table, one row per sweep (the running cases with the time they
    reached), and, with `scenes`, a line for the whole campaign: what a document shows."""
    st = status(ledger, scenes, defaults)
    lines = ["| sweep | cases | finished | running (time reached) | not started | wall time per "
             "time unit, s (load) | left, hours of one worker |", "|---|---|---|---|---|---|---|"]
    for w in st["sweeps"]:
        running = ", ".join(f"{c} (t = {t:g})" for c, t in w["running"]) or "-"
        ns = str(w["not_started"]) if scenes is not None else "?"
        rate = "-" if math.isnan(w["rate"]) else f"{w['rate']:.2f} ({w['load']:.1f})"
        if w["rate_from"]:
            rate += f", that of {', '.join(f'`{d}`' for d in w['rate_from'])}"
        left = "-" if math.isnan(w["left"]) else f"{w['left'] / 3600:.1f}"
        lines.append(f"| `{w['sweep']}` | {w['cases']} | {w['finished']} | {running} | {ns} "
                     f"| {rate} | {left} |")
    c = st["campaign"]
    if c is not None:
        lines += ["", f"All: {c['finished']} of {c['cases']} cases finished, {_left_text(c)}."]
    return lines


def _left_text(campaign: dict) -> str:
    """The time a campaign (`status`'s "campaign") still needs, as both renderings say it."""
    return (f"about {campaign['left'] / 3600:.1f} h of one worker left at the measured rates"
            + ("" if campaign["counted"] else " (sweeps without a measured rate not counted)"))


def set_case_mode(ledger: str, sweep: str, case: str, analyze_json: str) -> dict:
    """Record the case mode of a case's frame rows, as `knotflow-analyze <case>.csv --json`
    printed it (the one implementation of the rule), with the number of rows it saw; a mode
    of other rows than the ledger's now is refused."""
    entry = load(ledger, sweep, case)
    if entry is None:
        raise ValueError(f"{ledger}/{sweep}/{case}: no ledger entry")
    got = json.loads(analyze_json)
    rows = len(read_rows(ledger, sweep, case))
    if got.get("frames") != rows or got.get("case_mode") not in (0, 1, 2):
        raise ValueError(f"{sweep}/{case}: case mode {got.get('case_mode')!r} of "
                         f"{got.get('frames')} frames; the ledger has {rows} rows")
    entry["case_mode"] = {"mode": got["case_mode"], "frames": rows}
    _write_text(_paths(ledger, sweep, case)["json"], json.dumps(entry, indent=1) + "\n")
    return entry


def find_ledger_cases(sweep_dir: str) -> list:
    """The ledger entries (<case>.json) of a ledger's sweep directory."""
    if not os.path.isdir(sweep_dir):
        return []
    return sorted(os.path.join(sweep_dir, f) for f in os.listdir(sweep_dir) if f.endswith(".json"))


def _scene_value(scene: str, group: str, var: str):
    m = _scene_setting(group, var).search(scene)
    if m is None:
        return None
    return _value(m.group(2))


def _value(text: str):
    """A scene value's text as a str (quoted), a number or, failing both, the text."""
    v = text.strip()
    if v.startswith("'"):
        return v.strip("'")
    try:
        return float(v) if any(c in v for c in ".eE") else int(v)
    except ValueError:
        return v


#: What makes a start (scene group, variable): the chain, its stiffness and the flow. Cases that
#: agree on these (and on &chain's seed where it draws the start: `sample_start`) start alike,
#: whatever model then runs them.
START_VARIABLES = (("chain", "shape"), ("chain", "n_beads"), ("chain", "orientation"),
                   ("chain", "trefoil_removed_point"), ("chain", "bond_length"),
                   ("chain", "coordinate_file"), ("chain", "straight_direction"),
                   ("chain", "candycane_rotation"), ("chain", "tilt_deg"),
                   ("chain", "perturbation"), ("forces", "bending_a"), ("flow", "flow_type"),
                   ("flow", "shear_rate"), ("flow", "velocity_gradient"))
#: What makes a start and a model: cases that agree on all of these sample one cell. The
#: integrator's settings are not among them (samples of a cell may run on different steppers at
#: one tolerance) and neither is &chain's seed, which sample_cell adds where it draws the start
#: itself.
CELL_VARIABLES = START_VARIABLES + (
    ("forces", "springs"), ("forces", "spring_k"), ("forces", "bending"),
    ("forces", "excluded_volume"), ("forces", "ev_strength"), ("forces", "ev_range"),
    ("forces", "external_force"), ("hydro", "model"), ("hydro", "order"), ("hydro", "lubrication"),
    ("hydro", "eps_lub"), ("hydro", "overlap"), ("hydro", "overlap_time"))


def _drawn_seed(scene: str):
    """&chain's seed where it draws the start itself (a random chain, a candy-cane with a random
    rotation: kf_chain_shapes), else None (there it draws only the start's perturbation)."""
    shape = _scene_value(scene, "chain", "shape")
    rotation = _scene_value(scene, "chain", "candycane_rotation")
    drawn = shape == "random" or (shape == "candycane" and rotation == "random")
    return _scene_value(scene, "chain", "seed") if drawn else None


def sample_start(scene: str) -> tuple:
    """The start a case runs from: the values of START_VARIABLES in its scene text and the seed
    where it draws the start (`_drawn_seed`); the same for one start run with two models."""
    return tuple(_scene_value(scene, g, v) for g, v in START_VARIABLES) + (_drawn_seed(scene),)


def sample_cell(scene: str) -> tuple:
    """The cell a case samples: the values of CELL_VARIABLES in its scene text, and &chain's
    seed only where the seed draws the start itself (`_drawn_seed`); elsewhere the seed draws
    only the start's perturbation, so the cases of one cell start a perturbation apart and share
    their early frames."""
    return tuple(_scene_value(scene, g, v) for g, v in CELL_VARIABLES) + (_drawn_seed(scene),)


#: What makes a case's integration path (scene group, variable): the stepper, its tolerance and
#: how the model's velocities are solved. Samples of one cell (CELL_VARIABLES) may differ in it.
PATH_VARIABLES = (("integrator", "method"), ("integrator", "tolerance"),
                  ("integrator", "jacobian_steps"), ("hydro", "update"),
                  ("hydro", "solver_tolerance"), ("hydro", "jacobian_order"))


def integration_path(scene: str, defaults: dict | None = None) -> str:
    """The integration path of a case by its scene names (PATH_VARIABLES as written in its scene
    text), e.g. "method = 'ros34pw2', tolerance = 0.0001, jacobian_steps = 1, ...". A variable
    the scene does not hold (written by a knotflow before the variable existed) takes its value
    from `defaults` (`scene_defaults`: the program's defaults, as the digest's scene comparison)
    or, without one there, is named as missing. The Rosenbrock variables (jacobian_steps,
    jacobian_order) only with a linearly implicit method, solver_tolerance only with update
    'iterative': elsewhere nothing reads them."""
    method = _scene_value(scene, "integrator", "method")
    update = _scene_value(scene, "hydro", "update")
    known = defaults or {}
    parts = []
    for group, var in PATH_VARIABLES:
        if var in ("jacobian_steps", "jacobian_order") and not str(method).startswith("ros"):
            continue
        if var == "solver_tolerance" and update != "iterative":
            continue
        v = _scene_value(scene, group, var)
        if v is None and (group, var) in known:
            v = _value(known[(group, var)])
        if v is None:
            parts.append(f"{var} not in the scene")
        else:
            parts.append(f"{var} = {v!r}" if isinstance(v, str) else f"{var} = {v:g}")
    return ", ".join(parts)


def combined_totals(segments: list) -> dict | None:
    """The overlap and passage totals of a case run in segments: sums, extremes, the mean
    duration weighted by episodes, the first passage at the case's time (None without any)."""
    tots = [(s["t_offset"], s["diagnostic_totals"]) for s in segments if s["diagnostic_totals"]]
    if not tots:
        return None
    out = {"strand_passages": sum(d.get("strand_passages") or 0 for _, d in tots),
           "overlap_episodes": sum(d.get("overlap_episodes") or 0 for _, d in tots),
           "overlap_max_duration": max(d.get("overlap_max_duration") or 0.0 for _, d in tots),
           "max_overlapping_pairs": max(d.get("max_overlapping_pairs") or 0 for _, d in tots),
           "max_bond_strain": max(d.get("max_bond_strain") or 0.0 for _, d in tots)}
    eps = out["overlap_episodes"]
    out["overlap_mean_duration"] = (sum((d.get("overlap_mean_duration") or 0.0)
                                        * (d.get("overlap_episodes") or 0) for _, d in tots) / eps
                                    if eps else 0.0)
    dists = [d["min_distance"] for _, d in tots if (d.get("min_distance") or -1.0) >= 0.0]
    out["min_distance"] = min(dists) if dists else -1.0
    first = [o + d["first_passage_time"] for o, d in tots if (d.get("strand_passages") or 0) > 0]
    out["first_passage_time"] = first[0] if first else tots[0][1].get("first_passage_time")
    return out


def ledger_case(path: str, matrices_dir: str | None = None):
    """A case of the ledger (`<case>.json`) as an io.Case for the study's analysis: the frame
    rows as time, observables, k_f (/analysis/knots), modes, diagnostics and stresslet; the run
    records of every segment at the case's time; overlap totals combined over the segments;
    the case mode recorded by `set_case_mode` when it saw the rows there are now (else none).
    Positions exist only for the frames the ledger keeps (the multiples of `positions_every`
    and the newest frame, full precision); the others are NaN. Knot matrices: those of
    `matrices_dir`, `<case>_frame<k>.json` (knotflow-analyze FRAME.xyz --matrix --json of the
    kept frame k; scripts/reproduce.sh --ledger computes them)."""
    from .io import Case
    sweep_dir, name = os.path.split(path[:-5])
    ledger, sweep = os.path.split(sweep_dir)
    entry = load(ledger, sweep, name)
    if entry is None:
        raise ValueError(f"{path}: no ledger entry")
    rows = read_rows(ledger, sweep, name)
    col = {c: k for k, c in enumerate(FRAME_COLUMNS)}
    t = rows[:, 0]
    n = int(entry["n_beads"])
    pos = np.full((len(t), n, 3), np.nan)
    kept_t, kept = read_positions(ledger, sweep, name)
    for tk, r in zip(kept_t, kept):
        k = int(np.argmin(np.abs(t - tk)))
        if abs(t[k] - tk) <= TIME_TOLERANCE:
            pos[k] = r
    pos[-1] = np.asarray(entry["last_frame"], dtype=float)
    scene = entry["scene"]
    attrs = {"case_name": name, "status": entry["status"], "n_beads": n, "scene": scene,
             "integrator.t_end": float(entry["t_end"]), "ledger": path,
             "continued_at": [float(sg["t_offset"]) for sg in entry["segments"]
                              if sg["case_name"] != name and not sg.get("from_state")]}
    for key, group, var in (("forces.bending_a", "forces", "bending_a"),
                            ("chain.orientation", "chain", "orientation"),
                            ("chain.seed", "chain", "seed"), ("chain.shape", "chain", "shape"),
                            ("hydro.model", "hydro", "model"), ("hydro.overlap", "hydro", "overlap")):
        attrs[key] = _scene_value(scene, group, var)
    case = Case(path=path, attrs=attrs, time=t, positions=pos,
                observables={k: rows[:, col[k]] for k in FRAME_COLUMNS[2:9]})
    case.knots = {"frame_index": np.arange(len(t), dtype=np.int64), "time": t,
                  "kf": rows[:, col["kf"]], "spectrum": None, "types": None, "dominant": None,
                  "attrs": {"closures": entry["kf_closures"], "tool": "knotflow-campaign"}}
    modes = rows[:, col["mode"]]
    if np.all(np.isfinite(modes)):
        case.modes = modes.astype(np.int32)
    cm = entry.get("case_mode")
    if cm and cm.get("frames") == len(t):
        case.case_mode = int(cm["mode"])
    case.diagnostics = {k: rows[:, col[k]] for k in ("overlapping_pairs", "min_distance",
                                                     "strand_passages")}
    case.stresslet = {k: rows[:, col[k]] for k in ("viscosity", "psi1", "psi2")}
    elastic = rows[:, col["viscosity_elastic"]]
    if np.any(np.isfinite(elastic)):
        case.stresslet.update({"viscosity_elastic": elastic,
                               "viscosity_hydrodynamic": rows[:, col["viscosity"]] - elastic})
    case.diagnostic_totals = combined_totals(entry["segments"])
    case.diagnostic_totals_source = "ledger"
    case.runs = []
    for s in entry["segments"]:
        for r in s["runs"]:
            rr = {k: (math.nan if v is None and RUN_FIELDS[k] == "f" else v) for k, v in r.items()}
            rr["t_start"] += s["t_offset"]
            rr["t_end"] += s["t_offset"]
            case.runs.append(rr)
    if matrices_dir and os.path.isdir(matrices_dir):
        pat = re.compile(rf"^{re.escape(name)}_frame([0-9]+)\.json$")
        for f in sorted(os.listdir(matrices_dir)):
            m = pat.match(f)
            if m:
                with open(os.path.join(matrices_dir, f), encoding="utf-8") as fh:
                    rows_k = json.load(fh)["matrix"]
                case.knot_matrices[int(m[1])] = np.array(
                    [[np.nan if x is None else x for x in r] for r in rows_k], dtype=float)
    return case


def load_case(path: str, matrices_dir: str | None = None):
    """A case file (io.read_case) or a ledger entry (`<case>.json`, ledger_case)."""
    if str(path).endswith(".json"):
        return ledger_case(str(path), matrices_dir)
    return read_case(path)
