"""Reading knotflow case files (HDF5) and text coordinate files.

/analysis is read here and written only by the Fortran tool knotflow-analyze (docs/analysis.md).
"""

from __future__ import annotations

import errno
import fcntl
import glob
import os
import re
import stat
from dataclasses import dataclass, field

import h5py
import numpy as np

from .atomic import write_text
from .knots import KNOT_TYPES

OBSERVABLES = ("rg", "a", "b", "c", "theta", "phi", "close_pairs")
# Run diagnostics (optional: files written without them have neither): per-frame datasets in
# /frames/diagnostics and run totals as root attributes "diagnostics.<name>".
DIAGNOSTICS = ("strand_passages", "overlapping_pairs", "overlap_episodes", "min_distance",
               "max_bond_strain")
# The fibre's stresslet (optional, &output stresslet): /frames/stresslet/{hydrodynamic, elastic}
# (nframes, 3, 3) and {viscosity, psi1, psi2} (nframes,), units and normalisation in docs/case-file.md.
STRESSLET = ("hydrodynamic", "elastic", "viscosity", "psi1", "psi2")
# The viscosity's two parts, derived on reading from the two tensors of a case in simple shear
# (viscosity = 6 (S^hyd_xz + S^el_xz) / (N gamma_dot), kf_rheology): the hydrodynamic part and
# the elastic (Kramers-Kirkwood) part.
VISCOSITY_PARTS = ("viscosity_hydrodynamic", "viscosity_elastic")
DIAGNOSTIC_TOTALS = ("strand_passages", "first_passage_time", "overlap_episodes",
                     "overlap_mean_duration", "overlap_max_duration", "max_overlapping_pairs",
                     "min_distance", "max_bond_strain")
# Run records (optional): /runs holds one entry per run segment (a start or a resume) as 1-D
# datasets of equal length: name -> kind ("s" string, "i" integer, "f" float; NaN = unknown).
RUN_FIELDS = {"commit": "s", "started": "s", "host": "s", "blas": "s", "ranks": "i", "threads": "i",
              "t_start": "f", "t_end": "f", "steps": "i", "wall_seconds": "f",
              "load_start": "f", "load_mean": "f"}
#: Run fields a file may lack (from the schema that added them on): read as None.
OPTIONAL_RUN_FIELDS = ("blas",)   # schema 5


def _attr(value):
    """h5py attribute value as a plain Python value (bytes -> str, 0-d arrays -> scalars,
    one-element string arrays -> str; Fortran blank padding stripped)."""
    if isinstance(value, bytes):
        return value.decode("utf-8", errors="replace").rstrip(" \x00")
    if isinstance(value, np.ndarray):
        if value.dtype.kind in ("S", "O", "U"):
            items = [v.decode() if isinstance(v, bytes) else str(v) for v in value.ravel()]
            return items[0].strip() if value.size == 1 and value.ndim <= 1 else items
        if value.ndim == 0:
            return value.item()
        return value
    if isinstance(value, np.generic):
        return value.item()
    return value


def _strings(ds) -> list:
    return [(v.decode() if isinstance(v, bytes) else str(v)).rstrip(" \x00") for v in ds[()]]


@dataclass
class Case:
    """Contents of one case file (only what the tools use)."""

    path: str
    attrs: dict
    time: np.ndarray
    positions: np.ndarray                      # (nframes, N, 3)
    observables: dict = field(default_factory=dict)
    knots: dict | None = None                  # /analysis/knots
    events: dict | None = None                 # /analysis/events
    knot_matrices: dict = field(default_factory=dict)   # frame index -> (N, N)
    modes: np.ndarray | None = None
    case_mode: int | None = None
    diagnostics: dict | None = None            # /frames/diagnostics: name -> (nframes,)
    diagnostic_totals: dict | None = None      # diagnostics.* root attributes, without prefix
    stresslet: dict | None = None              # /frames/stresslet: name -> (nframes[, 3, 3])
    diagnostic_totals_source: str = ""         # "attributes" or "checkpoint" (running case)
    runs: list = field(default_factory=list)   # /runs: one dict per run segment (RUN_FIELDS)
    stepper_state: dict | None = None          # running case: checkpoint_stepper_state

    @property
    def name(self) -> str:
        return str(self.attrs.get("case_name", self.path))

    @property
    def status(self) -> str:
        return str(self.attrs.get("status", "unknown"))

    @property
    def bending_a(self):
        return self.attrs.get("forces.bending_a")

    @property
    def orientation(self):
        return self.attrs.get("chain.orientation")

    @property
    def nframes(self) -> int:
        return len(self.time)


#: Largest ratio of raw to stored bytes accepted for compressed data (deflate's is 1032); the
#: same limit as the Fortran readers (kf_h5, check_declared_size). docs/inputs.md.
MAX_COMPRESSION = 1100.0
#: Filters that do not compress (their data takes at least its raw size in the file).
_NON_COMPRESSING = (h5py.h5z.FILTER_FLETCHER32, h5py.h5z.FILTER_SHUFFLE)

_FILE_TYPES = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
               (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
               (stat.S_ISSOCK, "a socket"))


def check_regular_file(path, what: str) -> None:
    """A ValueError unless `path` (symbolic links followed) is a regular file: a FIFO would
    block the open forever, a device such as /dev/zero never ends. A missing file is left to
    the caller's open."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return
    if stat.S_ISREG(mode):
        return
    kind = next((name for test, name in _FILE_TYPES if test(mode)), "not a regular file")
    raise ValueError(f"{path}: the {what} is {kind}: only a regular file is read")


def physical_memory() -> int:
    """Bytes of physical memory of this machine (0 when unknown)."""
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError):
        return 0


def check_declared_size(path, ds, whole: bool = True) -> None:
    """The shape dataset `ds` declares must fit its file and (a whole read) this machine's
    memory, checked before anything is read: without a compressing filter its bytes may
    exceed the file's size by at most one entry along its first dimension (a frame being
    written when a run stopped), with one by at most MAX_COMPRESSION times the file's size.
    A ValueError names the file, the dataset and the shape (a 139 kB file declaring
    (10^8, 99, 3) reals is refused instead of crashing the reader)."""
    if ds.shape is None or len(ds.shape) == 0:
        return
    declared = float(ds.dtype.itemsize) * float(np.prod([float(n) for n in ds.shape]))
    entry = declared / max(1.0, float(ds.shape[0]))
    plist = ds.id.get_create_plist()
    compressed = any(plist.get_filter(k)[0] not in _NON_COMPRESSING
                     for k in range(plist.get_nfilters()))
    try:
        file_bytes = os.path.getsize(path)
    except OSError:
        file_bytes = -1
    shape = ", ".join(str(n) for n in ds.shape)
    if file_bytes >= 0:
        allowed = (MAX_COMPRESSION if compressed else 1.0) * file_bytes + entry
        if declared > allowed:
            held = " compressed" if compressed else ""
            raise ValueError(f"{path}: {ds.name} declares shape ({shape}) of {declared:.3g} "
                             f"bytes, more than the {file_bytes}-byte file can hold{held} "
                             "(a damaged or forged file; refused before reading)")
    memory = physical_memory()
    if whole and memory > 0 and declared > memory:
        raise ValueError(f"{path}: {ds.name} declares shape ({shape}) of {declared:.3g} bytes, "
                         f"more than the {memory} bytes of memory of this machine "
                         "(refused before reading)")


def _read(path, ds):
    """All of dataset ds (its declared size checked first, check_declared_size); a read that
    fails (a Fletcher-32 checksum mismatch in damaged data, an I/O error) becomes a
    ValueError naming the file and the dataset."""
    check_declared_size(path, ds)
    try:
        return ds[()]
    except OSError as exc:
        missing = _missing_filters(ds)
        if missing:
            raise ValueError(f"{path}: {ds.name}: cannot read: it needs the HDF5 filter "
                             f"{', '.join(missing)}, which this HDF5 library does not have (the "
                             "file is not damaged; read it where that filter is installed)") from exc
        raise ValueError(f"{path}: {ds.name}: cannot read (damaged data: checksum mismatch or "
                         f"I/O error: {exc})") from exc


def check_frames(path, time, positions) -> None:
    """Every frame time and coordinate must be finite: a ValueError names the file, the first
    bad frame (0-based), its time and the cause. A NaN frame would otherwise give wrong
    results in silence (k_f = 1 for a chain whose k_f is 0.87)."""
    bad_t = ~np.isfinite(time)
    bad_r = ~np.isfinite(positions).reshape(len(positions), -1).all(axis=1)
    bad = np.flatnonzero(bad_t[:len(bad_r)] | bad_r)
    if len(bad):
        k = int(bad[0])
        if bad_r[k]:
            count = int((~np.isfinite(positions[k])).sum())
            cause = f"{count} non-finite coordinates (NaN or Inf)"
        else:
            cause = "a non-finite time"
        more = f"; {len(bad) - 1} more bad frames" if len(bad) > 1 else ""
        raise ValueError(f"{path}: frame {k} (t = {time[k]:g}): {cause}{more}")


def newest_checkpoint(f):
    """The newest checkpoint group of the open case file `f` (None: no checkpoint). Files of
    schema 3 have two slots written alternately (/checkpoint/slot0, slot1; a slot's frame count
    is written last, so the one with the larger count is whole); older files one /checkpoint."""
    if "checkpoint" not in f:
        return None
    groups = [f["checkpoint"][s] for s in ("slot0", "slot1") if s in f["checkpoint"]]
    groups.append(f["checkpoint"])
    counted = [g for g in groups if "nframes" in g]
    return max(counted, key=lambda g: int(g["nframes"][()])) if counted else None


def checkpoint_frames(f):
    """Frames the newest checkpoint of the open case file `f` counts (None: no checkpoint).
    Frames beyond it were being written when the run stopped."""
    g = newest_checkpoint(f)
    return None if g is None else int(g["nframes"][()])


def checkpoint_stepper_state(f, time_last: float, positions_last) -> dict | None:
    """The time stepper's state in the newest checkpoint of the open case file `f` when that
    checkpoint is the frame (time_last, positions_last) to the bit (the last frame read): the
    checkpoint's time ("time", on the case file's clock), the method's name and the state's
    arrays (kf_stepper get_state: "reals", "ints"), from which another run continues exactly
    (&chain stepper_state, knotflow-campaign plan). None without a checkpoint, without a stepper
    state in it (files written before it existed) or when it is another frame."""
    g = newest_checkpoint(f)
    if g is None or "stepper" not in g or "time" not in g or "positions" not in g:
        return None
    st = g["stepper"]
    if "reals" not in st or "ints" not in st or "name" not in st.attrs:
        return None
    t = float(g["time"][()])
    r = np.asarray(g["positions"][()], dtype=float)
    if t != float(time_last) or r.shape != np.shape(positions_last) or not np.array_equal(r, positions_last):
        return None
    return {"time": t, "method": str(_attr(st.attrs["name"])),
            "reals": [float(x) for x in np.asarray(st["reals"][()], dtype=float)],
            "ints": [int(x) for x in np.asarray(st["ints"][()], dtype=np.int64)]}


def checkpoint_diagnostic_totals(f):
    """The run totals of the diagnostics (the names of DIAGNOSTIC_TOTALS) from the state the
    newest checkpoint of `f` holds (None: no checkpoint with diagnostics): the totals of the
    frames that checkpoint counts. The root attributes diagnostics.* are rewritten with every
    frame before the checkpoint, so in a running case they may count one frame more than the
    frames read. Layout of the state (kf_run_diagnostics, get_state): counters = [strand
    passages, episodes started, episodes completed, max overlapping pairs, ongoing episodes],
    values = [first passage time, sum and max of completed durations, smallest squared
    distance (|i - j| > 1; huge when none), max bond strain]."""
    g = newest_checkpoint(f)
    if g is None or "diagnostics" not in g:
        return None
    c = np.asarray(g["diagnostics"]["counters"][()], dtype=np.int64)
    v = np.asarray(g["diagnostics"]["values"][()], dtype=float)
    if c.shape != (5,) or v.shape != (5,):
        return None
    return {"strand_passages": int(c[0]), "first_passage_time": float(v[0]),
            "overlap_episodes": int(c[1]),
            "overlap_mean_duration": float(v[1] / c[2]) if c[2] > 0 else 0.0,
            "overlap_max_duration": float(v[2]), "max_overlapping_pairs": int(c[3]),
            "min_distance": float(np.sqrt(v[3])) if v[3] < np.finfo(float).max else -1.0,
            "max_bond_strain": float(v[4])}


def read_runs(path, f) -> list:
    """The run records of the open case file `f` (/runs, RUN_FIELDS): one dict per run segment,
    [] without /runs; a field of OPTIONAL_RUN_FIELDS the file lacks is None. A ValueError names
    the file and the dataset that is missing, not 1-D, of the wrong kind or of another length
    than the others."""
    if "runs" not in f:
        return []
    g = f["runs"]
    if not isinstance(g, h5py.Group):
        raise ValueError(f"{path}: /runs is not a group")
    columns = {}
    for name, kind in RUN_FIELDS.items():
        if name in OPTIONAL_RUN_FIELDS and name not in g:
            continue
        if name not in g or not isinstance(g[name], h5py.Dataset):
            raise ValueError(f"{path}: no dataset /runs/{name} (a run record needs "
                             + ", ".join(RUN_FIELDS) + ")")
        ds = g[name]
        if ds.ndim != 1:
            raise ValueError(f"{path}: /runs/{name} has {ds.ndim} dimensions, expected 1")
        is_string = ds.dtype.kind in ("S", "O", "U")
        if (kind == "s") != is_string or (kind == "i" and ds.dtype.kind not in "iu") \
                or (kind == "f" and ds.dtype.kind not in "fiu"):
            want = {"s": "strings", "i": "integers", "f": "numbers"}[kind]
            raise ValueError(f"{path}: /runs/{name} holds {ds.dtype}, expected {want}")
        if is_string:
            columns[name] = _strings(ds)
        else:
            data = np.asarray(_read(path, ds))
            columns[name] = [int(x) for x in data] if kind == "i" else [float(x) for x in data]
    lengths = {name: len(col) for name, col in columns.items()}
    if len(set(lengths.values())) > 1:
        raise ValueError(f"{path}: the /runs datasets have different lengths ("
                         + ", ".join(f"{k} {n}" for k, n in lengths.items()) + ")")
    n = next(iter(lengths.values()))
    return [{name: columns[name][k] if name in columns else None for name in RUN_FIELDS}
            for k in range(n)]


def open_case(path):
    """The case file `path` opened read-only with h5py; a file HDF5 cannot open is a ValueError
    naming it and telling why (missing, a directory, empty, not HDF5, truncated or damaged);
    a FIFO or a device is refused before it is opened (check_regular_file)."""
    if not os.path.isdir(path):
        check_regular_file(path, "case file")
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        if not os.path.exists(path):
            why = "no such file"
        elif os.path.isdir(path):
            why = "it is a directory"
        elif not os.access(path, os.R_OK):
            why = f"not readable: {os.strerror(errno.EACCES)}"
        elif _locked_by_writer(path):
            why = ("it is open for writing in another process, which holds its HDF5 file lock "
                   "(a knotflow run still writing it, or a viewer): wait for it or close it there")
        elif os.path.getsize(path) == 0:
            why = "an empty file, not HDF5"
        else:
            with open(path, "rb") as fh:
                head = fh.read(8)
            why = ("an HDF5 file that is truncated or damaged" if head == b"\x89HDF\r\n\x1a\n"
                   else "not an HDF5 file")
        detail = " ".join(str(exc).split())
        raise ValueError(f"{path}: cannot open as a case file ({why}: {detail})") from None


def _locked_by_writer(path) -> bool:
    """Does another process hold an exclusive lock on ``path`` (HDF5 takes one for a file it
    opens for writing)? A shared lock that cannot be had says so."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    except OSError:
        return False
    finally:
        os.close(fd)
    return False


def _missing_filters(ds) -> list:
    """The filters of a dataset's pipeline this HDF5 library does not have, as 'name (id)'."""
    plist = ds.id.get_create_plist()
    missing = []
    for k in range(plist.get_nfilters()):
        fid, _, _, name = plist.get_filter(k)
        if not h5py.h5z.filter_avail(fid):
            missing.append(f"'{name.decode(errors='replace')}' (id {fid})")
    return missing


def _frame_dataset(path, fr, name, ndim):
    """The numbers of /frames/<name> (an array of `ndim` dimensions), or a ValueError."""
    if name not in fr or not isinstance(fr[name], h5py.Dataset):
        raise ValueError(f"{path}: no dataset /frames/{name} (not a knotflow case file)")
    ds = fr[name]
    if ds.dtype.kind not in "fiu":
        raise ValueError(f"{path}: /frames/{name} holds {ds.dtype}, not numbers")
    if ds.ndim != ndim:
        raise ValueError(f"{path}: /frames/{name} has {ds.ndim} dimensions, expected {ndim}")
    return np.asarray(_read(path, ds), dtype=float)


def viscosity_parts(stresslet: dict, attrs: dict, n_beads: int) -> dict:
    """VISCOSITY_PARTS of a stresslet read from a case file: {} unless it holds both tensors
    and the flow is simple shear of a rate other than 0."""
    rate = attrs.get("flow.shear_rate")
    if (attrs.get("flow.flow_type") != "shear" or not rate or n_beads < 1
            or not {"hydrodynamic", "elastic"} <= stresslet.keys()):
        return {}
    scale = 6.0 / (n_beads * float(rate))
    return {name: scale * np.asarray(stresslet[part])[:, 0, 2]
            for name, part in zip(VISCOSITY_PARTS, ("hydrodynamic", "elastic"))}


def read_case(path) -> Case:
    """Read a case file; missing optional parts are left empty. The frames are read up to those
    the newest checkpoint counts (a frame beyond it was being written when the run stopped).
    A ValueError names the file and the problem: a file that cannot be opened, no /frames
    group, /frames/time or /frames/positions missing, not numbers or unreadable (damaged data),
    positions not of shape (frames, beads, 3) or of fewer than 2 beads, time and positions of
    different lengths (without a checkpoint), no frame, a frame with a non-finite time or
    coordinate (naming the frame), times that do not increase."""
    with open_case(path) as f:
        attrs = {k: _attr(v) for k, v in f.attrs.items()}
        if "frames" not in f or not isinstance(f["frames"], h5py.Group):
            raise ValueError(f"{path}: no /frames group (not a knotflow case file)")
        fr = f["frames"]
        time = _frame_dataset(path, fr, "time", 1)
        pos = _frame_dataset(path, fr, "positions", 3)
        if pos.shape[2] != 3:
            raise ValueError(f"{path}: /frames/positions has shape {pos.shape}, expected "
                             "(frames, beads, 3)")
        if pos.shape[1] < 2:
            raise ValueError(f"{path}: /frames/positions holds {pos.shape[1]} bead(s) per frame, "
                             "a chain needs at least 2")
        counted = checkpoint_frames(f)
        if counted is None and len(time) != len(pos):
            raise ValueError(f"{path}: /frames/time and /frames/positions have different lengths "
                             f"({len(time)} and {len(pos)} frames)")
        n = min(len(time), len(pos), len(time) if counted is None else counted)
        if n < 1:
            raise ValueError(f"{path}: no complete frame (/frames is empty)")
        time, pos = time[:n], pos[:n]
        check_frames(path, time, pos)
        back = np.nonzero(~(np.diff(time) > 0))[0]
        if len(back):
            kb = int(back[0]) + 1
            raise ValueError(f"{path}: frame {kb} (t = {time[kb]:g}) is not after frame {kb - 1} "
                             f"(t = {time[kb - 1]:g}): times must increase")
        obs = {}
        if "observables" in fr:
            for k in OBSERVABLES:
                if k in fr["observables"]:
                    obs[k] = np.asarray(_read(path, fr["observables"][k]))[:n]
        case = Case(path=str(path), attrs=attrs, time=time, positions=pos, observables=obs)
        if "diagnostics" in fr:
            g = fr["diagnostics"]
            case.diagnostics = {k: np.asarray(_read(path, g[k]))[:n] for k in DIAGNOSTICS if k in g}
        if "stresslet" in fr:
            g = fr["stresslet"]
            case.stresslet = {k: np.asarray(_read(path, g[k]))[:n] for k in STRESSLET if k in g}
            case.stresslet.update(viscosity_parts(case.stresslet, attrs, pos.shape[1]))
        totals = {k: attrs["diagnostics." + k] for k in DIAGNOSTIC_TOTALS
                  if "diagnostics." + k in attrs}
        ckpt_totals = checkpoint_diagnostic_totals(f) if case.status != "finished" else None
        if ckpt_totals is not None:
            case.diagnostic_totals, case.diagnostic_totals_source = ckpt_totals, "checkpoint"
        elif totals:
            case.diagnostic_totals, case.diagnostic_totals_source = totals, "attributes"
        case.runs = read_runs(path, f)
        if case.status != "finished":
            case.stepper_state = checkpoint_stepper_state(f, time[-1], pos[-1])
        if "analysis" in f:
            try:
                _read_analysis(f["analysis"], case)
            except (OSError, KeyError, RuntimeError) as exc:
                # a damaged /analysis is never taken for a missing one
                raise ValueError(f"{path}: /analysis cannot be read ({exc}): it is damaged, e.g. by "
                                 "a knotflow-analyze run of an older version killed while it wrote "
                                 f"it; run knotflow-analyze --force {path}") from exc
    return case


def _read_analysis(an, case: Case) -> None:
    """/analysis of a case file into ``case``; every group listed is read (h5py's ``in`` takes a
    group it cannot read for an absent one, so every member and the members of its groups are
    opened first: a damaged one raises here)."""
    members = [an[name] for name in list(an.keys())]
    for member in members:
        if isinstance(member, h5py.Group):
            [member[sub] for sub in list(member.keys())]   # noqa: B018 (opened to check)
    if "knots" in an:
        g = an["knots"]
        case.knots = {
            "frame_index": np.asarray(g["frame_index"][()], dtype=np.int64),
            "time": np.asarray(g["time"][()], dtype=float),
            "kf": np.asarray(g["kf"][()], dtype=float),
            "spectrum": np.asarray(g["spectrum"][()], dtype=float)
            if "spectrum" in g else None,
            "types": _attr(g["spectrum"].attrs["types"])
            if "spectrum" in g and "types" in g["spectrum"].attrs else list(KNOT_TYPES),
            "dominant": _strings(g["dominant"]) if "dominant" in g else None,
            "attrs": {k: _attr(v) for k, v in g.attrs.items()},
        }
    if "events" in an:
        g = an["events"]
        case.events = {
            "kind": _strings(g["kind"]) if "kind" in g else [],
            "time": np.asarray(g["time"][()], dtype=float) if "time" in g else None,
            "frame_index": np.asarray(g["frame_index"][()], dtype=np.int64)
            if "frame_index" in g else None,
            "attrs": {k: _attr(v) for k, v in g.attrs.items()},
        }
    if "knot_matrix" in an:
        for name, ds in an["knot_matrix"].items():
            if name.startswith("frame_"):
                case.knot_matrices[int(name[6:])] = np.asarray(ds[()], dtype=float)
    if "shape" in an and "mode" in an["shape"]:
        case.modes = np.asarray(an["shape"]["mode"][()], dtype=np.int32)
        for holder in (an["shape"]["mode"], an["shape"]):
            if "case_mode" in holder.attrs:
                case.case_mode = int(_attr(holder.attrs["case_mode"]))
                break


def read_frame(path, frame: int = -1) -> np.ndarray:
    """Positions (N, 3) of one frame of a case file (negative = from the end)."""
    case = read_case(path)
    return case.positions[frame]


#: A number of a coordinate file: the whole item, nothing else (docs/inputs.md; the Fortran
#: reader kf_text_coords applies the same rule). float() alone would take '1_0', 'inf', 'nan'.
_NUMBER_RE = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


def _visible(text: str) -> str:
    """text with characters outside printable ASCII shown (<TAB>, <0xNN>), at most 80."""
    out = "".join("<TAB>" if c == "\t" else "<CR>" if c == "\r"
                  else c if " " <= c <= "~" else f"<0x{ord(c):02X}>" if ord(c) < 256
                  else f"<U+{ord(c):04X}>" for c in text)
    return out if len(out) <= 80 else out[:80] + "..."


def read_xyz(path) -> np.ndarray:
    """Points (n, 3) of a text coordinate file (docs/inputs.md): blanks are spaces, tabs and
    carriage returns; blank lines and lines whose first item starts with '#' are ignored; a
    UTF-8 byte-order mark is skipped; every other line holds exactly three whole, finite
    numbers. A ValueError names the file, the line and the item."""
    check_regular_file(path, "coordinate file")
    pts = []
    with open(path, encoding="utf-8-sig", newline="\n") as fh:
        for lineno, line in enumerate(fh, 1):
            parts = line.replace("\t", " ").replace("\r", " ").replace("\n", " ").split(" ")
            parts = [p for p in parts if p]
            if not parts or parts[0].startswith("#"):
                continue
            if len(parts) > 3:
                raise ValueError(f"{path}:{lineno}: expected 3 numbers, found a fourth item "
                                 f"'{_visible(parts[3])}'")
            if len(parts) != 3:
                raise ValueError(f"{path}:{lineno}: expected 3 numbers, got {len(parts)}")
            for k, item in enumerate(parts, 1):
                if not _NUMBER_RE.fullmatch(item):
                    raise ValueError(f"{path}:{lineno}: not a number: item {k} '{_visible(item)}' "
                                     "(allowed: [+-]digits[.digits][e[+-]digits], finite)")
            xyz = [float(x) for x in parts]
            if not all(np.isfinite(xyz)):
                raise ValueError(f"{path}:{lineno}: non-finite coordinate in '{_visible(line.strip())}'")
            pts.append(xyz)
    if not pts:
        raise ValueError(f"{path}: no coordinates (every line is blank or a comment)")
    return np.array(pts, dtype=float).reshape(-1, 3)


def write_xyz(path, r, comment: str | None = None) -> None:
    """Write points (n, 3) as a text coordinate file (whole or not at all: knotflow_tools.atomic)."""
    lines = [f"# {line}\n" for line in (comment or "").splitlines()]
    lines += [f"{p[0]:.17g} {p[1]:.17g} {p[2]:.17g}\n" for p in np.asarray(r, dtype=float)]
    write_text(path, "".join(lines))


def find_case_files(sweep_dir) -> list:
    """Case files (*.h5) in the sweep directory and its immediate subdirectories, hidden ones
    ('.name.h5') included: none is left out in silence (a hidden case name is then refused)."""
    files = []
    for pattern in ("*.h5", ".*.h5", os.path.join("*", "*.h5"), os.path.join("*", ".*.h5")):
        files += glob.glob(os.path.join(glob.escape(str(sweep_dir)), pattern))
    return sorted(set(f for f in files if os.sep + "report" + os.sep not in f))
