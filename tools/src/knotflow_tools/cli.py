"""Console scripts: knotflow-kf, knotflow-plot, knotflow-report."""

from __future__ import annotations

import argparse
import json
import math
import sys

import numpy as np

from . import add_version_option, knots


def _kf_parser():
    p = argparse.ArgumentParser(
        prog="knotflow-kf",
        description="Knotted fraction, knot spectrum and knot matrix of an open chain "
                    "(text coordinate file or HDF5 case file).")
    add_version_option(p)
    p.add_argument("chain", help="text file (x y z per line) or .h5 case file")
    p.add_argument("--frame", type=int, default=-1,
                   help="frame of a .h5 case file (0-based; negative from the end; default last)")
    p.add_argument("--closures", type=int, default=1000, help="number of random closures")
    p.add_argument("--seed", type=int, default=1, help="random seed")
    p.add_argument("--matrix", action="store_true", help="compute the knot matrix")
    p.add_argument("--min-length", type=int, default=10,
                   help="shortest subchain of the knot matrix (beads)")
    p.add_argument("--matrix-closures", type=int, default=None,
                   help="closures per subchain of the knot matrix (default: --closures)")
    p.add_argument("--matrix-stride", type=int, default=1,
                   help="compute K only on a grid of this stride (others NaN)")
    p.add_argument("--closure-points", metavar="FILE",
                   help="use these closure points (absolute coordinates) instead of random ones")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--per-closure", action="store_true", help="list the type of every closure")
    return p


def _nan_to_none(mat):
    return [[None if (isinstance(v, float) and math.isnan(v)) else v for v in row]
            for row in np.asarray(mat, dtype=float).tolist()]


def main_kf(argv=None) -> int:
    """knotflow-kf entry point."""
    args = _kf_parser().parse_args(argv)
    from .io import read_frame, read_xyz
    try:
        if args.chain.endswith((".h5", ".hdf5")):
            r = read_frame(args.chain, args.frame)
        else:
            r = read_xyz(args.chain)
        points = read_xyz(args.closure_points) if args.closure_points else None
    except (OSError, ValueError, KeyError, IndexError) as exc:
        print(f"knotflow-kf: error: {exc}", file=sys.stderr)
        return 2
    if args.closures < 1 and points is None:
        print("knotflow-kf: error: --closures must be >= 1", file=sys.stderr)
        return 2
    try:
        res = knots.analyze_chain(r, closures=args.closures, seed=args.seed, points=points)
    except ValueError as exc:
        print(f"knotflow-kf: error: {args.chain}: {exc}", file=sys.stderr)
        return 2
    mat = None
    core = None
    slip = False
    if args.matrix:
        mc = args.matrix_closures or args.closures
        mat = knots.knot_matrix(r, closures=mc, seed=args.seed, min_length=args.min_length,
                                stride=args.matrix_stride)
        core = knots.knot_core(mat)
        slip = knots.is_slipknot(mat, res.kf)
    if args.json:
        out = {"n_beads": int(len(r)), "closures": res.closures, "seed": args.seed,
               "kf": res.kf, "spectrum": res.spectrum, "dominant": res.dominant}
        if args.per_closure:
            out["per_closure"] = res.per_closure
        if args.matrix:
            out["matrix"] = _nan_to_none(mat)
        out["knot_core"] = list(core) if core is not None else None
        out["slipknot"] = slip
        print(json.dumps(out))
        return 0
    print(f"n_beads {len(r)}  closures {res.closures}  seed {args.seed}")
    print(f"kf {res.kf:.6f}")
    print("spectrum " + " ".join(f"{k}:{v:.4f}" for k, v in res.spectrum.items()))
    print(f"dominant {res.dominant}")
    if args.per_closure:
        print("per_closure " + " ".join(res.per_closure))
    if args.matrix:
        print(f"knot_core {core[0]} {core[1]}" if core else "knot_core none")
        print(f"slipknot {'yes' if slip else 'no'}")
        for row in np.asarray(mat):
            print(" ".join("nan" if math.isnan(v) else f"{v:.3f}" for v in row))
    return 0


def main_plot(argv=None) -> int:
    """knotflow-plot entry point."""
    p = argparse.ArgumentParser(prog="knotflow-plot",
                                description="Figures of a knotflow case file.")
    add_version_option(p)
    p.add_argument("case", help="HDF5 case file")
    p.add_argument("--out", default=None, help="output directory (default: <case>_plots)")
    p.add_argument("--closures", type=int, default=200,
                   help="closures per frame when k_f is computed (no /analysis)")
    p.add_argument("--stride", type=int, default=0,
                   help="analyse every stride-th frame (0: automatic, at most 100 frames)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--matrix-frames", type=int, nargs="*", default=[],
                   help="frames whose knot matrix is computed (if not stored)")
    p.add_argument("--matrix-closures", type=int, default=50)
    p.add_argument("--matrix-stride", type=int, default=4)
    p.add_argument("--min-length", type=int, default=10)
    p.add_argument("--recompute", action="store_true",
                   help="ignore the stored k_f, events and knot matrices (modes always come "
                        "from /analysis)")
    p.add_argument("--movie", action="store_true", help="also write an animation")
    p.add_argument("--movie-stride", type=int, default=1)
    args = p.parse_args(argv)
    from .analysis import analyze_case
    from .io import read_case
    from .plot import plot_case
    try:
        case = read_case(args.case)
    except (OSError, KeyError, ValueError) as exc:
        print(f"knotflow-plot: error: {exc}", file=sys.stderr)
        return 2
    if case.nframes == 0:
        print("knotflow-plot: error: the case has no frames", file=sys.stderr)
        return 2
    ana = analyze_case(case, closures=args.closures, stride=args.stride, seed=args.seed,
                       matrix_frames=args.matrix_frames, matrix_closures=args.matrix_closures,
                       matrix_stride=args.matrix_stride, min_length=args.min_length,
                       use_stored=not args.recompute)
    out = args.out or (args.case.rsplit(".", 1)[0] + "_plots")
    files = plot_case(case, ana, out, movie=args.movie, movie_stride=args.movie_stride)
    for f in files:
        print(f)
    return 0


def main_report(argv=None) -> int:
    """knotflow-report entry point."""
    p = argparse.ArgumentParser(prog="knotflow-report",
                                description="Report (markdown + html) of a sweep directory.")
    add_version_option(p)
    p.add_argument("sweep_dir")
    p.add_argument("--closures", type=int, default=200)
    p.add_argument("--stride", type=int, default=0,
                   help="analyse every stride-th frame (0: automatic, at most 100 frames)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--movie", action="store_true",
                   help="(default) a movie of each case, linked from the report")
    p.add_argument("--no-movie", action="store_true", help="no movies")
    p.add_argument("--movie-frames", type=int, default=40,
                   help="at most this many frames per movie (stride raised; default 40)")
    p.add_argument("--no-viewer", action="store_true",
                   help="no interactive 3-D viewer in report.html")
    args = p.parse_args(argv)
    import os

    from .report import build_report
    if not os.path.isdir(args.sweep_dir):
        print(f"knotflow-report: error: not a directory: {args.sweep_dir}", file=sys.stderr)
        return 2
    res = build_report(args.sweep_dir, closures=args.closures, stride=args.stride,
                       seed=args.seed, movie=not args.no_movie,
                       movie_max_frames=args.movie_frames, viewer=not args.no_viewer)
    print(res["md"])
    print(res["html"])
    return 0


if __name__ == "__main__":
    sys.exit(main_kf())
