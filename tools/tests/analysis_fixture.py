"""Test fixtures: /analysis groups in the schema knotflow-analyze writes (docs/analysis.md).

The package never writes /analysis (its one writer is the Fortran tool); these writers only let
the tests give the readers a stored analysis without running knotflow-analyze.
"""

import h5py
import numpy as np

from knotflow_tools.knots import KNOT_TYPES


def _replace(group, name, data, **kw):
    if name in group:
        del group[name]
    return group.create_dataset(name, data=data, **kw)


def write_knots(path, frame_index, time, kf, spectrum, dominant, closures, seed,
                tool="knotflow-analyze") -> None:
    """Write /analysis/knots (replacing an existing one)."""
    with h5py.File(path, "a") as f:
        g = f.require_group("analysis").require_group("knots")
        _replace(g, "frame_index", np.asarray(frame_index, dtype=np.int64))
        _replace(g, "time", np.asarray(time, dtype=float))
        _replace(g, "kf", np.asarray(kf, dtype=float))
        ds = _replace(g, "spectrum", np.asarray(spectrum, dtype=float).reshape(len(kf), -1))
        ds.attrs["types"] = np.array(KNOT_TYPES, dtype=h5py.string_dtype())
        _replace(g, "dominant", np.array(dominant, dtype=h5py.string_dtype()))
        g.attrs["closures"] = int(closures)
        g.attrs["seed"] = int(seed)
        g.attrs["tool"] = tool


def write_events(path, events, low, high) -> None:
    """Write /analysis/events from a list of transitions.Event."""
    with h5py.File(path, "a") as f:
        g = f.require_group("analysis").require_group("events")
        _replace(g, "kind", np.array([e.kind for e in events], dtype=h5py.string_dtype()))
        _replace(g, "time", np.array([e.time for e in events], dtype=float))
        _replace(g, "frame_index", np.array([e.index for e in events], dtype=np.int64))
        g.attrs["low"] = float(low)
        g.attrs["high"] = float(high)


def write_knot_matrix(path, frame, mat, closures, min_length, time) -> None:
    """Write /analysis/knot_matrix/frame_<frame>."""
    with h5py.File(path, "a") as f:
        g = f.require_group("analysis").require_group("knot_matrix")
        ds = _replace(g, f"frame_{int(frame)}", np.asarray(mat, dtype=float))
        ds.attrs["closures"] = int(closures)
        ds.attrs["min_length"] = int(min_length)
        ds.attrs["time"] = float(time)


def write_modes(path, modes, case_mode) -> None:
    """Write /analysis/shape/mode and its case_mode attribute."""
    with h5py.File(path, "a") as f:
        g = f.require_group("analysis").require_group("shape")
        _replace(g, "mode", np.asarray(modes, dtype=np.int32))
        g.attrs["case_mode"] = int(case_mode)
