"""Shared fixtures: synthetic case files in the knotflow HDF5 schema."""

import os
import sys

import h5py
import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))

from helpers import tailed_trefoil  # noqa: E402

TYPES = ("0_1", "3_1", "4_1", "5_1", "5_2", "6_1", "6_2", "6_3", "7_1", "other")


def unknotting_trefoil_frames(nframes):
    """Frames going from a tailed open trefoil to a straight chain (linear interpolation)."""
    r0 = tailed_trefoil()
    n = len(r0)
    straight = np.zeros((n, 3))
    straight[:, 0] = 1.02 * np.arange(n)
    straight -= straight.mean(axis=0) - r0.mean(axis=0)
    w = np.linspace(0.0, 1.0, nframes)
    # hold the knot for the first third, then pull it straight
    w = np.clip((w - 0.33) / 0.67, 0.0, 1.0)
    return np.stack([(1 - x) * r0 + x * straight for x in w])


def write_case(path, positions, time=None, attrs=None, observables=True, status="finished"):
    """Write a case file in the documented schema (frames, checkpoint, root attributes)."""
    positions = np.asarray(positions, dtype=float)
    nf, n, _ = positions.shape
    time = np.arange(nf, dtype=float) if time is None else np.asarray(time, dtype=float)
    with h5py.File(path, "w") as f:
        base = {"knotflow_version": "0.1.0", "git_hash": "test", "compiler": "none",
                "compiler_flags": "", "case_name": os.path.basename(path).rsplit(".", 1)[0],
                "status": status, "n_beads": n, "scene": "&chain /", "forces.bending_a": 1.0,
                "chain.orientation": "a", "hydro.model": "rpy", "chain.seed": np.int64(1),
                "chain.rotation": np.eye(3)}
        base.update(attrs or {})
        for k, v in base.items():
            f.attrs[k] = v
        g = f.create_group("frames")
        g.create_dataset("time", data=time, maxshape=(None,), chunks=True)
        g.create_dataset("positions", data=positions, maxshape=(None, n, 3), chunks=True)
        if observables:
            from knotflow_tools.shape import shape_series
            obs = shape_series(positions)
            og = g.create_group("observables")
            for k, v in obs.items():
                og.create_dataset(k, data=v, maxshape=(None,), chunks=True)
        ig = g.create_group("integrator")
        ig.create_dataset("steps", data=np.arange(nf, dtype=np.int64) * 10, maxshape=(None,))
        ig.create_dataset("rejected", data=np.zeros(nf, dtype=np.int64), maxshape=(None,))
        ig.create_dataset("dt", data=np.full(nf, 1e-3), maxshape=(None,))
        c = f.create_group("checkpoint")
        c["time"] = time[-1]
        c["positions"] = positions[-1]
        c["dt"] = 1e-3
        c["steps"] = np.int64(10 * (nf - 1))
        c["rejected"] = np.int64(0)
        c["nframes"] = np.int64(nf)
    return path


@pytest.fixture
def trefoil_case(tmp_path):
    """A small case: 8 frames of a trefoil being pulled straight."""
    return str(write_case(tmp_path / "case_A1_a.h5", unknotting_trefoil_frames(8),
                          time=np.linspace(0.0, 70.0, 8)))
