"""Fixtures of the knotflow package's tests: the programs to compare with, test chains.

The programs are taken from ``KNOTFLOW_BIN_DIR`` (ctest sets it to the build's bin directory),
else from the source checkout's ``build/bin``. The library is the one the package finds
(ctest sets ``KNOTFLOW_LIBRARY`` to the build's).
"""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from helpers import open_trefoil  # noqa: E402


def program(name: str) -> str:
    """Path of the knotflow program `name` (its absence fails the test: nothing is skipped)."""
    bindir = os.environ.get("KNOTFLOW_BIN_DIR") or str(Path(__file__).resolve().parents[2] / "build" / "bin")
    path = Path(bindir) / name
    assert path.is_file(), f"{name} not found in {bindir} (build it, or set KNOTFLOW_BIN_DIR)"
    return str(path)


def run(name: str, *args: str) -> str:
    """Standard output of the program `name` with `args` (a non-zero exit fails the test)."""
    done = subprocess.run([program(name), *args], capture_output=True, text=True, check=False)
    assert done.returncode == 0, f"{name} {' '.join(args)}: exit {done.returncode}: {done.stderr}"
    return done.stdout


def write_coordinates(path: Path, r: np.ndarray) -> str:
    """r (N x 3) as a coordinate file ("x y z" per line) with every double written exactly."""
    path.write_text("".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in np.asarray(r, dtype=float).tolist()))
    return str(path)


@pytest.fixture
def trefoil() -> np.ndarray:
    """The open trefoil of PHYSICS.md 5 (99 beads, unit bonds): knotted, with close pairs."""
    return open_trefoil()


@pytest.fixture
def cluster() -> np.ndarray:
    """12 beads of a random walk with bonds from overlap (0.97, which BWE clamps) through near
    contact (1.001, 1.05) to 1.5 apart: every regime of the pair corrections."""
    rng = np.random.default_rng(20261205)
    bonds = [1.0, 0.97, 1.001, 1.05, 1.5, 1.0, 1.2, 1.01, 1.0, 1.3, 1.02]
    r = np.zeros((len(bonds) + 1, 3))
    for i, b in enumerate(bonds):
        while True:  # a step that keeps every earlier bead but the last >= 1.1 away
            step = rng.normal(size=3)
            r[i + 1] = r[i] + b * step / np.linalg.norm(step)
            if i == 0 or np.linalg.norm(r[: i] - r[i + 1], axis=1).min() >= 1.1:
                break
    return r
