#!/usr/bin/env python3
"""Timing of k_f (1000 closures, N = 99 open trefoil) and of a knot matrix (N = 152 frame).

Compares knotflow_tools (Python), topoly (if installed) and the Fortran `knotflow-analyze`
(if found on PATH or in build/bin of the checkout).  Not part of the test suite.

    python tools/benchmarks/bench_knots.py [--closures 1000] [--matrix-closures 20]
                                           [--matrix-stride 4] [--skip-matrix]
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests"))

from knotflow_tools import io, knots  # noqa: E402

from helpers import open_trefoil  # noqa: E402


def candy_cane_knotted():
    """N = 152 test frame: the open trefoil (99 beads) continued by a straight 53-bead rod."""
    r = open_trefoil()
    d = r[-1] - r[-2]
    d /= np.linalg.norm(d)
    rod = r[-1] + 1.02 * np.arange(1, 54)[:, None] * d
    return np.vstack([r, rod])


def find_fortran():
    exe = shutil.which("knotflow-analyze")
    if exe:
        return exe
    root = os.path.abspath(os.path.join(HERE, "..", ".."))
    p = os.path.join(root, "build", "bin", "knotflow-analyze")
    return p if os.path.isfile(p) and os.access(p, os.X_OK) else None


def timed(fn):
    t = time.perf_counter()
    out = fn()
    return time.perf_counter() - t, out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--closures", type=int, default=1000)
    ap.add_argument("--matrix-closures", type=int, default=20)
    ap.add_argument("--matrix-stride", type=int, default=4)
    ap.add_argument("--min-length", type=int, default=10)
    ap.add_argument("--skip-matrix", action="store_true")
    args = ap.parse_args()
    r99 = open_trefoil()
    r152 = candy_cane_knotted()
    rows = []
    dt, res = timed(lambda: knots.analyze_chain(r99, args.closures, seed=1))
    rows.append(("knotflow_tools", f"k_f N=99 x {args.closures}", dt, f"kf={res.kf:.3f}"))
    if not args.skip_matrix:
        dt, mat = timed(lambda: knots.knot_matrix(r152, args.matrix_closures, seed=1,
                                                  min_length=args.min_length,
                                                  stride=args.matrix_stride))
        rows.append(("knotflow_tools", f"matrix N=152 stride {args.matrix_stride} x "
                     f"{args.matrix_closures}", dt, f"core={knots.knot_core(mat)}"))
    try:
        import topoly
        from topoly.params import Closure
        chain = r99.tolist()
        dt, out = timed(lambda: topoly.alexander(chain, closure=Closure.ONE_POINT,
                                                 tries=args.closures, hide_trivial=False,
                                                 run_parallel=False))
        rows.append(("topoly", f"k_f N=99 x {args.closures}", dt, str(out)))
        if not args.skip_matrix:
            dt, out = timed(lambda: topoly.alexander(
                r152.tolist(), closure=Closure.ONE_POINT, tries=args.matrix_closures,
                matrix=True, matrix_density=args.matrix_stride, run_parallel=False))
            rows.append(("topoly", f"matrix N=152 density {args.matrix_stride} x "
                         f"{args.matrix_closures}", dt, f"{len(out)} entries"))
    except ImportError:
        rows.append(("topoly", "not installed", float("nan"), ""))
    exe = find_fortran()
    if exe:
        with tempfile.TemporaryDirectory() as tmp:
            f99 = os.path.join(tmp, "c99.xyz")
            f152 = os.path.join(tmp, "c152.xyz")
            io.write_xyz(f99, r99)
            io.write_xyz(f152, r152)
            dt, out = timed(lambda: subprocess.run(
                [exe, f99, "--closures", str(args.closures), "--json"], capture_output=True,
                text=True, check=False))
            try:
                kf = json.loads(out.stdout)["kf"]
                note = f"kf={kf:.3f}"
            except (ValueError, KeyError):
                note = f"rc={out.returncode}"
            rows.append(("knotflow-analyze", f"k_f N=99 x {args.closures}", dt, note))
            if not args.skip_matrix:
                dt, out = timed(lambda: subprocess.run(
                    [exe, f152, "--closures", str(args.matrix_closures), "--matrix",
                     "--min-length", str(args.min_length), "--json"], capture_output=True,
                    text=True, check=False))
                rows.append(("knotflow-analyze", f"matrix N=152 full x {args.matrix_closures}",
                             dt, f"rc={out.returncode}"))
    else:
        rows.append(("knotflow-analyze", "not found", float("nan"), ""))
    for tool, what, dt, note in rows:
        print(f"{tool:18s} {what:40s} {dt:9.2f} s  {note}")


if __name__ == "__main__":
    main()
