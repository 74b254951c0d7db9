"""Every console script of knotflow_tools (``[project.scripts]`` in tools/pyproject.toml) and
what they share: the parser with ``--version``, the error line and the exit status.

The other modules are libraries: functions that take values, return results and raise on bad
input. A ``main_*`` function here parses its command line, calls them and prints. Every script
exits with status 0 when done and ``EXIT_USAGE`` (2) on a usage error (argparse's own, or a
refused option value) and on refused input (a file that cannot be read, damaged or non-finite
data, a bad value: ``OSError``, ``KeyError``, ``ValueError``), which is one line
``<prog>: error: <what>`` on standard error and no traceback. Anything else is a failure of the
tool itself: Python's traceback and exit status 1.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Callable, Sequence

import numpy as np

import knotflow

from . import __version__

#: Exit status of a usage error or refused input (as argparse's own usage errors).
EXIT_USAGE = 2
#: What a tool raises for input it refuses: an unreadable file, damaged data, a bad value.
INPUT_ERRORS: tuple[type[Exception], ...] = (OSError, KeyError, ValueError)

Argv = Sequence[str] | None


def make_parser(prog: str, description: str) -> argparse.ArgumentParser:
    """An argument parser with ``--version`` ('<prog> <version>' on standard output, exit 0)."""
    p = argparse.ArgumentParser(prog=prog, description=description)
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    return p


def error_line(prog: str, message: object) -> int:
    """Print '<prog>: error: <message>' on standard error; return ``EXIT_USAGE``."""
    print(f"{prog}: error: {message}", file=sys.stderr)
    return EXIT_USAGE


def run_reporting_errors(prog: str, body: Callable[[Argv], int], argv: Argv = None,
                         errors: tuple[type[Exception], ...] = INPUT_ERRORS) -> int:
    """``body(argv)`` for a console script: refused input (``errors``) becomes one error line and
    exit status ``EXIT_USAGE``."""
    try:
        return body(argv)
    except errors as exc:
        return error_line(prog, exc)


def add_seed_option(p) -> None:
    """--seed of the random closures, defaulting to the library's seed (knotflow-analyze's)."""
    p.add_argument("--seed", type=int, default=knotflow.default_seed(),
                   help="seed of the random closures (default %(default)s, knotflow-analyze's)")


# ------------------------------------------------------------------------------ knotflow-kf

def _kf_parser():
    p = make_parser("knotflow-kf",
                    "Knotted fraction, knot spectrum and knot matrix of an open chain "
                    "(text coordinate file or HDF5 case file).")
    p.add_argument("chain", help="text file (x y z per line) or .h5 case file")
    p.add_argument("--frame", type=int, default=-1,
                   help="frame of a .h5 case file (0-based; negative from the end; default last)")
    p.add_argument("--closures", type=int, default=1000, help="number of random closures")
    add_seed_option(p)
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


def main_kf(argv: Argv = None) -> int:
    """knotflow-kf entry point."""
    return run_reporting_errors("knotflow-kf", _kf, argv, INPUT_ERRORS + (IndexError,))


def _kf(argv: Argv) -> int:
    args = _kf_parser().parse_args(argv)
    from .io import read_frame, read_xyz
    if args.chain.endswith((".h5", ".hdf5")):
        r = read_frame(args.chain, args.frame)
    else:
        r = read_xyz(args.chain)
    points = read_xyz(args.closure_points) if args.closure_points else None
    if args.closures < 1 and points is None:
        raise ValueError("--closures must be >= 1")
    # the library's knot code (knotflow.knots, knotflow.knot_matrix: knotflow-analyze's)
    try:
        res = knotflow.knots(r, closures=None if points is not None else args.closures, seed=args.seed,
                             points=points)
    except ValueError as exc:
        raise ValueError(f"{args.chain}: {exc}") from exc
    mat = None
    core = None
    slip = False
    if args.matrix:
        mc = args.matrix_closures or args.closures
        km = knotflow.knot_matrix(r, closures=mc, seed=args.seed, min_length=args.min_length,
                                  stride=args.matrix_stride, kf_whole=res.kf)
        mat, core, slip = km.matrix, km.core, bool(km.slipknot)
    if args.json:
        out = {"n_beads": int(len(r)), "closures": res.closures, "seed": args.seed,
               "kf": res.kf, "spectrum": res.spectrum, "dominant": res.dominant}
        if args.per_closure:
            out["per_closure"] = list(res.per_closure)
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


# ---------------------------------------------------------------------------- knotflow-plot

def main_plot(argv: Argv = None) -> int:
    """knotflow-plot entry point."""
    return run_reporting_errors("knotflow-plot", _plot, argv)


def _plot(argv: Argv) -> int:
    p = make_parser("knotflow-plot", "Figures of a knotflow case file.")
    p.add_argument("case", help="HDF5 case file")
    p.add_argument("--out", default=None, help="output directory (default: <case>_plots)")
    p.add_argument("--closures", type=int, default=200,
                   help="closures per frame when k_f is computed (no /analysis)")
    p.add_argument("--stride", type=int, default=0,
                   help="analyse every stride-th frame (0: automatic, at most 100 frames)")
    add_seed_option(p)
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
    case = read_case(args.case)
    if case.nframes == 0:
        raise ValueError("the case has no frames")
    ana = analyze_case(case, closures=args.closures, stride=args.stride, seed=args.seed,
                       matrix_frames=args.matrix_frames, matrix_closures=args.matrix_closures,
                       matrix_stride=args.matrix_stride, min_length=args.min_length,
                       use_stored=not args.recompute)
    out = args.out or (args.case.rsplit(".", 1)[0] + "_plots")
    files = plot_case(case, ana, out, movie=args.movie, movie_stride=args.movie_stride)
    for f in files:
        print(f)
    return 0


# -------------------------------------------------------------------------- knotflow-report

def main_report(argv: Argv = None) -> int:
    """knotflow-report entry point."""
    return run_reporting_errors("knotflow-report", _report, argv)


def _report(argv: Argv) -> int:
    p = make_parser("knotflow-report", "Report (markdown + html) of a sweep directory.")
    p.add_argument("sweep_dir")
    p.add_argument("--closures", type=int, default=200)
    p.add_argument("--stride", type=int, default=0,
                   help="analyse every stride-th frame (0: automatic, at most 100 frames)")
    add_seed_option(p)
    p.add_argument("--movie", action="store_true",
                   help="(default) a movie of each case, linked from the report")
    p.add_argument("--no-movie", action="store_true", help="no movies")
    p.add_argument("--movie-frames", type=int, default=40,
                   help="at most this many frames per movie (stride raised; default 40)")
    p.add_argument("--no-viewer", action="store_true",
                   help="no interactive 3-D viewer in report.html")
    args = p.parse_args(argv)
    from .report import build_report
    if not os.path.isdir(args.sweep_dir):
        raise ValueError(f"not a directory: {args.sweep_dir}")
    res = build_report(args.sweep_dir, closures=args.closures, stride=args.stride,
                       seed=args.seed, movie=not args.no_movie,
                       movie_max_frames=args.movie_frames, viewer=not args.no_viewer)
    print(res["md"])
    print(res["html"])
    return 0



# ------------------------------------------------------------------ knotflow-stress-summary

def main_stress_summary(argv: Argv = None) -> int:
    """knotflow-stress-summary entry point."""
    return run_reporting_errors("knotflow-stress-summary", _stress_summary, argv)


def _stress_summary(argv: Argv) -> int:
    p = make_parser("knotflow-stress-summary",
                    "Table of stress runs: wall time, steps, rejections, strand passages, "
                    "overlaps, distances, bond strain, status (Markdown).")
    p.add_argument("inputs", nargs="+", help="case files or directories holding them")
    p.add_argument("--wall-times", help="file of 'case seconds' lines (scripts/stress.sh)")
    p.add_argument("--output", "-o", help="write the table (with a header) here as well")
    p.add_argument("--title", default="knotflow stress runs", help="heading of the output file")
    args = p.parse_args(argv)
    from . import stress
    files = stress.case_files(args.inputs)
    if not files:
        raise ValueError("no case files in " + " ".join(args.inputs))
    wall = stress.read_wall_times(args.wall_times) if args.wall_times else {}
    rows = []
    for path in files:
        try:
            rows.append(stress.summarise_case(path, wall))
        except INPUT_ERRORS as exc:
            raise ValueError(f"{path}: {exc}") from exc
    table = stress.format_table(rows)
    print(table, end="")
    if args.output:
        stress.write_summary(args.output, args.title, table)
    return 0


# -------------------------------------------------------------------------- knotflow-study

def main_study(argv: Argv = None) -> int:
    """knotflow-study entry point: a file that cannot be read (damaged, non-finite frames) is an
    error naming it."""
    return run_reporting_errors("knotflow-study", _study, argv)


def _scene_reference(p, path) -> dict:
    """The program's scene defaults (campaign.scene_defaults) from the file of
    `knotflow --scene-reference` output at path; an unreadable file or one without scene
    variables is refused (parser p)."""
    from . import campaign
    try:
        with open(path, encoding="utf-8") as fh:
            defaults = campaign.scene_defaults(fh.read())
    except (OSError, UnicodeDecodeError) as e:
        p.error(f"--scene-reference {path}: {e}")
    if not defaults:
        p.error(f"--scene-reference {path}: no scene variables in it "
                "(expected the output of knotflow --scene-reference)")
    return defaults


def _study(argv: Argv) -> int:
    from . import study, study_compare, study_slipknots
    p = make_parser("knotflow-study", (study.__doc__ or "").splitlines()[0])
    p.add_argument("--trefoil", help="output directory of inputs/trefoil_table2*.nml")
    p.add_argument("--candycane", help="output directory of inputs/candycane*.nml")
    p.add_argument("--ensemble", help="output directory of inputs/candycane_seeds.nml (optional)")
    p.add_argument("--samples", nargs="+", metavar="DIR",
                   help="sweeps of perturbed Table 2 samples (several per cell): Table 2 as "
                   "probabilities with exact 95 %% intervals and the scores of the study's "
                   "table and of 'never' (study_statistics); pooled and per integration path "
                   "when the samples ran on more than one (campaign.integration_path)")
    p.add_argument("--scene-reference", metavar="FILE",
                   help="with --samples: what `knotflow --scene-reference` printed; a scene "
                   "written by a knotflow before one of the integration path's variables "
                   "existed takes its default from it (without: the variable is named as "
                   "missing, and that scene's path differs from those that hold it)")
    p.add_argument("--rotations", nargs="+", metavar="DIR",
                   help="sweeps of candy-canes from many starts: case and frame fractions in "
                   "modes I and II per A with 95 %% intervals, late shape distributions, and "
                   "the close-pair ratio A = 1 / A = 3 per --window")
    p.add_argument("--same-starts", nargs="+", metavar="DIR",
                   help="with --rotations: sweeps of the same starts run with another model "
                   "(matched by chain, stiffness, flow and drawing seed): both models' case "
                   "modes, late mode fractions and shapes side by side, start by start")
    p.add_argument("--window", type=float, default=250.0,
                   help="with --rotations: the width of the close-pair ratio's time windows")
    p.add_argument("--out", default="docs/reproduction",
                   help="where figures, results.md, results.json, trefoil_kf.csv and "
                   "candycane_shape.csv go")
    p.add_argument("--closures", type=int, default=200,
                   help="closures per frame where /analysis/knots is missing")
    p.add_argument("--rpy-trefoil", metavar="RESULTS_JSON",
                   help="results.json of an earlier knotflow-study run of the RPY + EV trefoils "
                   "(its \"trefoil\" part): three-column tables (the study, this run, RPY + EV) "
                   "and a \"comparison\" part in results.json; needs --trefoil")
    p.add_argument("--rpy-candycane", metavar="RESULTS_JSON",
                   help="results.json of an earlier knotflow-study run of the RPY + EV "
                   "candy-canes (its \"candycane\" and \"ensemble\" parts): three-column "
                   "tables as --rpy-trefoil; needs --candycane")
    p.add_argument("--select-frames", metavar="CASE",
                   help="print the frames to give knotflow-analyze --matrix-frames for CASE "
                   "(every 50th, or those of --every-time, the last and the 5 with most close "
                   "pairs) and exit")
    p.add_argument("--every-time", type=float, metavar="T",
                   help="with --select-frames: the frames at the multiples of T time units of "
                   "the case's time axis instead of every 50th frame (issue 11: T = 10)")
    p.add_argument("--slip-candidates", metavar="CASE",
                   help="print the frames of CASE whose stored knot matrix looks like a slipknot")
    p.add_argument("--core-candidates", metavar="CASE",
                   help="print the candidates of CASE whose knot matrix recomputed in "
                   "--confirm-dir (CASE_frameK.json) is still a slipknot: their knot core goes "
                   "to the check with 1000 closures")
    p.add_argument("--confirm-dir", metavar="DIR",
                   help="with --core-candidates: the directory of the recomputed matrices "
                   "(<out>/confirm)")
    p.add_argument("--ledger-matrices", metavar="DIR",
                   help="the knot matrices of the cases of a case ledger (CASE_frameK.json; "
                   "scripts/reproduce.sh --ledger writes them)")
    p.add_argument("--write-frame", nargs=3, metavar=("CASE", "FRAME", "XYZ"),
                   help="write frame FRAME of CASE as a coordinate file and exit")
    p.add_argument("--core-of", metavar="JSON",
                   help="with --write-frame: only the beads of the knot core of JSON (the "
                   "knotflow-analyze --matrix --json output of that frame)")
    args = p.parse_args(argv)
    if bool(args.core_candidates) != bool(args.confirm_dir):
        p.error("--core-candidates CASE and --confirm-dir DIR go together")
    if args.core_of and not args.write_frame:
        p.error("--core-of JSON needs --write-frame CASE FRAME XYZ")
    if args.core_candidates:
        frames = study_slipknots.core_candidates(args.core_candidates, args.confirm_dir,
                                                 args.ledger_matrices)
        print(" ".join(str(k) for k in frames))
        return 0
    if args.every_time is not None and not args.select_frames:
        p.error("--every-time T needs --select-frames CASE")
    if args.every_time is not None and not (math.isfinite(args.every_time) and args.every_time > 0):
        p.error(f"--every-time {args.every_time:g} is not allowed (a positive number)")
    if args.slip_candidates:
        print(" ".join(str(k) for k in study_slipknots.slip_candidates(args.slip_candidates,
                                                                       args.ledger_matrices)))
        return 0
    if args.write_frame:
        path, frame, xyz = args.write_frame
        study.write_frame(path, int(frame), xyz, args.core_of)
        return 0
    if args.select_frames:
        print(",".join(str(k) for k in study.entangled_frames(args.select_frames,
                                                              every_time=args.every_time)))
        return 0
    if not (args.trefoil or args.candycane or args.ensemble or args.samples or args.rotations):
        p.error("give --trefoil DIR, --candycane DIR, --ensemble DIR, --samples DIR ... "
                "and/or --rotations DIR ...")
    if not (math.isfinite(args.window) and args.window > 0):
        p.error(f"--window {args.window:g} is not allowed (a positive number)")
    if args.same_starts and not args.rotations:
        p.error("--same-starts needs --rotations DIR ... (the starts it is compared with)")
    if args.scene_reference and not args.samples:
        p.error("--scene-reference FILE needs --samples DIR ...")
    for d in (args.trefoil, args.candycane, args.ensemble, *(args.samples or []),
              *(args.rotations or []), *(args.same_starts or [])):
        if d and not os.path.isdir(d):
            p.error(f"directory not found: {d}")
    if args.rpy_trefoil and not args.trefoil:
        p.error("--rpy-trefoil needs --trefoil DIR (the run it is compared with)")
    if args.rpy_candycane and not args.candycane:
        p.error("--rpy-candycane needs --candycane DIR (the run it is compared with)")
    # the earlier results and the defaults are read before anything is written
    defaults = None
    if args.scene_reference:
        defaults = _scene_reference(p, args.scene_reference)
    rpy_trefoil = study_compare.load_rpy(args.rpy_trefoil, ("trefoil",)) if args.rpy_trefoil else None
    rpy_candycane = (study_compare.load_rpy(args.rpy_candycane, ("candycane", "ensemble"))
                     if args.rpy_candycane else None)
    res = study.write_study(args.trefoil, args.candycane, args.out, args.closures, args.ensemble,
                            rpy_trefoil, rpy_candycane, args.ledger_matrices,
                            samples_dirs=args.samples, rotation_dirs=args.rotations,
                            window=args.window, same_starts=args.same_starts,
                            scene_defaults=defaults)
    if "trefoil" in res:
        t, k = res["trefoil"], res["trefoil"]["reknottings"]
        print(f"trefoils: {t['agreement']} agree with the study on "
              f"unknot-then-knot transitions; {k['events']} re-knottings in {k['simulations']} "
              f"of {k['cases']} cases; {k['finished']} finished")
    print(f"wrote {os.path.join(args.out, 'results.md')}")
    return 0


# ---------------------------------------------------------------- knotflow-accuracy-report

def main_accuracy_report(argv: Argv = None) -> int:
    """knotflow-accuracy-report entry point."""
    return run_reporting_errors("knotflow-accuracy-report", _accuracy_report, argv)


def _accuracy_report(argv: Argv) -> int:
    from . import accuracy
    p = make_parser("knotflow-accuracy-report",
                    "docs/accuracy.md and figures from the CSV tables of knotflow-accuracy.")
    p.add_argument("results", nargs="?", default=None,
                   help="directory written by knotflow-accuracy --out")
    p.add_argument("--reuse", default=None, metavar="DIR",
                   help="only replace the reuse section of the report by the outputs of "
                   "knotflow-bench-reuse in DIR (scripts/bench_reuse.sh)")
    p.add_argument("--stiffness", default=None, metavar="DIR",
                   help="only replace the section on the step-size limit (stiffness) of the "
                   "report by the knotflow-bench-reuse stiffness outputs in DIR")
    p.add_argument("--markdown", default="docs/accuracy.md", help="report file to write")
    p.add_argument("--figures", default="docs/figures", help="directory of the PNG figures")
    p.add_argument("--readme", default=None,
                   help="Markdown page (docs/models.md) whose block between %s and %s is replaced "
                   "by the summary"
                   % (accuracy.BEGIN, accuracy.END))
    args = p.parse_args(argv)
    if args.reuse is not None:
        accuracy.update_reuse(args.markdown, args.reuse)
        print("wrote the reuse section of %s" % args.markdown)
        return 0
    if args.stiffness is not None:
        accuracy.update_stiffness(args.markdown, args.stiffness, args.figures)
        print("wrote the stiffness section of %s and its figure in %s" % (args.markdown,
                                                                        args.figures))
        return 0
    if args.results is None:
        p.error("the results directory is required (or --reuse DIR)")
    res = accuracy.build_report(args.results, args.markdown, args.figures, args.readme)
    print(res["summary"])
    print("wrote %s and %d figure(s) in %s" % (res["markdown"], len(res["figures"]),
                                                args.figures))
    return 0


# --------------------------------------------------------------------------- knotflow-xdmf

def main_xdmf(argv: Argv = None) -> int:
    """knotflow-xdmf entry point: every case file is tried; a refused one is an error line."""
    from .xdmf import write_xdmf
    p = make_parser("knotflow-xdmf",
                    "Write an XDMF file <case>.xdmf2 beside each case file for ParaView "
                    "(File > Open: its 'Xdmf Reader') and VisIt (open as type Xdmf); it points "
                    "into the case file, copying no data.")
    p.add_argument("cases", nargs="+", help="HDF5 case files")
    p.add_argument("--out", default=None,
                   help="output file (only with one case file; default <case>.xdmf2)")
    args = p.parse_args(argv)
    if args.out and len(args.cases) != 1:
        return error_line("knotflow-xdmf", "--out needs exactly one case file")
    status = 0
    for path in args.cases:
        try:
            print(write_xdmf(path, args.out))
        except INPUT_ERRORS as exc:
            status = error_line("knotflow-xdmf", f"{path}: {exc}")
    return status


# -------------------------------------------------------------------------- knotflow-movie

def main_movie(argv: Argv = None) -> int:
    """knotflow-movie entry point (a failing encoder, RuntimeError, is an error line too)."""
    return run_reporting_errors("knotflow-movie", _movie, argv, INPUT_ERRORS + (RuntimeError,))


def _movie(argv: Argv) -> int:
    p = make_parser("knotflow-movie",
                    "Movie of a case file: the chain in 3-D (equal axis scales, halves "
                    "coloured, flow and vorticity directions marked) beside k_f(t) and the "
                    "shape panels with a moving time marker. MP4 with ffmpeg, else GIF.")
    p.add_argument("case", help="HDF5 case file")
    p.add_argument("--out", default=None,
                   help="output file, .mp4 or .gif (default <case>.mp4 beside the case)")
    p.add_argument("--first", type=int, default=0, help="first frame (negative: from the end)")
    p.add_argument("--last", type=int, default=None, help="last frame (default: the last)")
    p.add_argument("--stride", type=int, default=1, help="every stride-th frame")
    p.add_argument("--max-frames", type=int, default=0,
                   help="raise the stride so that at most this many frames remain (0: no cap)")
    p.add_argument("--fps", type=int, default=10, help="frames per second")
    p.add_argument("--elev", type=float, default=20.0, help="view elevation (degrees)")
    p.add_argument("--azim", type=float, default=-60.0, help="view azimuth (degrees)")
    p.add_argument("--width", type=int, default=960, help="width in pixels (made even)")
    p.add_argument("--height", type=int, default=540, help="height in pixels (made even)")
    p.add_argument("--gif", action="store_true", help="write an animated GIF (Pillow)")
    p.add_argument("--closures", type=int, default=0,
                   help="without /analysis: compute k_f on the movie frames with this many "
                        "closures (default 0: no k_f panel)")
    p.add_argument("--knot-core", action="store_true",
                   help="highlight the knot core of the latest stored knot matrix at or before "
                        "each frame (/analysis/knot_matrix)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = p.parse_args(argv)
    from .io import read_case
    from .movie import case_kf, movie_frames, render_movie
    case = read_case(args.case)
    frames = movie_frames(case.nframes, args.first, args.last, args.stride, args.max_frames)
    if not frames:
        raise ValueError("the case has no frames")
    kf = case_kf(case, args.closures, frames)
    out = args.out or (os.path.splitext(args.case)[0] + (".gif" if args.gif else ".mp4"))
    print(render_movie(case, out, frames, kf=kf, fps=args.fps, width=args.width,
                       height=args.height, elev=args.elev, azim=args.azim,
                       fmt="gif" if args.gif else None, progress=not args.no_progress,
                       knot_core=args.knot_core))
    return 0


# ----------------------------------------------------------------------- knotflow-rheology

def main_rheology(argv: Argv = None) -> int:
    """knotflow-rheology entry point."""
    return run_reporting_errors("knotflow-rheology", _rheology, argv)


def _rheology(argv: Argv) -> int:
    from . import rheology
    p = make_parser("knotflow-rheology",
                    "The fibre's viscosity and normal-stress coefficients in knotted against "
                    "unknotted intervals and in shape modes I against II (docs/RHEOLOGY.md).")
    p.add_argument("--knots", nargs="+", default=[], metavar="DIR",
                   help="sweep directories compared knotted against unknotted")
    p.add_argument("--modes", nargs="+", default=[], metavar="DIR",
                   help="sweep directories compared mode I against mode II")
    p.add_argument("--out", default="rheology", help="where rheology.md, .json and figures go")
    p.add_argument("--t-from", type=float, default=0.0, help="leave out frames before this time")
    p.add_argument("--threshold", type=float, default=rheology.KNOT_THRESHOLD,
                   help="knotted when k_f >= this (default 0.5)")
    p.add_argument("--hysteresis", type=float, nargs=2, metavar=("LOW", "HIGH"),
                   help="instead of --threshold: the hysteresis states of k_f (e.g. 0.1 0.9)")
    p.add_argument("--samples", type=int, default=200000,
                   help="random sign assignments of the test above 16 cases")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--finished", action="store_true",
                   help="only finished cases (a campaign still running has partial ones)")
    args = p.parse_args(argv)
    if not (args.knots or args.modes):
        p.error("give --knots DIR and/or --modes DIR")
    for d in args.knots + args.modes:
        if not os.path.isdir(d):
            p.error(f"directory not found: {d}")
    if not 0.0 < args.threshold <= 1.0:
        p.error(f"--threshold {args.threshold:g} is not allowed (a number in (0, 1])")
    if args.hysteresis and not 0.0 <= args.hysteresis[0] < args.hysteresis[1] <= 1.0:
        p.error("--hysteresis LOW HIGH needs 0 <= LOW < HIGH <= 1")
    if args.samples < 1:
        p.error(f"--samples {args.samples} is not allowed (a positive integer)")
    res = rheology.write_rheology(args.knots, args.modes, args.out, args.t_from, args.threshold,
                                  tuple(args.hysteresis) if args.hysteresis else None,
                                  args.samples, args.seed, args.finished)
    for line in rheology.summary_lines(res):
        print(line)
    print(f"wrote {os.path.join(args.out, 'rheology.md')}")
    return 0


# ------------------------------------------------------------------------ knotflow-campaign

def main_campaign(argv: Argv = None) -> int:
    """knotflow-campaign entry point."""
    return run_reporting_errors("knotflow-campaign", _campaign, argv)


def _case_offsets(args) -> list:
    """The time offset of each of args.cases (--offset, default 0), with --from and --to checked."""
    offsets = args.offset or [0.0] * len(args.cases)
    if len(offsets) != len(args.cases):
        raise ValueError(f"--offset: {len(offsets)} value(s) for {len(args.cases)} case(s)")
    if not all(math.isfinite(x) for x in offsets + [args.t_from or 0.0, args.t_to or 0.0]):
        raise ValueError("--offset, --from and --to need finite values")
    return offsets


def _window_table(args) -> list:
    """The lines of `knotflow-campaign windows`: cases interleaved window by window."""
    from . import campaign, shape
    rows = []
    for k, (path, offset) in enumerate(zip(args.cases, _case_offsets(args))):
        case = campaign.load_case(path)
        label = f"{os.path.basename(os.path.dirname(path))}/{case.name}"
        for w in shape.window_means(case.time, case.observables, args.width,
                                    campaign.frame_kf(case), case.modes, offset, args.t_from,
                                    args.t_to):
            rows.append((w["t0"], k, label, w))
    head = ("| window | case | frames | R_g | a | b | c | a/b | min b/c | mean abs(cos theta) "
            "| close pairs | k_f mean | k_f max | mode I | mode II |")
    lines = [head, "|" + "---|" * head.count(" | ") + "---|"]
    for t0, _, label, w in sorted(rows, key=lambda r: (r[0], r[1])):
        vals = [f"{w[c]:.2f}" if c in ("c", "a_over_b", "abs_cos_theta", "kf_mean", "kf_max")
                else f"{w[c]:.1f}" for c in shape.WINDOW_COLUMNS[1:11]]
        modes = ["-" if math.isnan(w[c]) else str(w[c]) for c in ("mode_1", "mode_2")]
        lines.append(f"| {t0:g}-{w['t1']:g} | {label} | {w['frames']} | " + " | ".join(vals + modes)
                     + " |")
    return lines


def _shape_map(args) -> str:
    """`knotflow-campaign shapes`: the frames of cases in the plane of b/c and a/b (a PNG)."""
    from . import campaign, plot, shape
    series = []
    for path, offset in zip(args.cases, _case_offsets(args)):
        case = campaign.load_case(path)
        label = f"{os.path.basename(os.path.dirname(path))}/{case.name}"
        ab, bc = shape.frame_ratios(case.time, case.observables, offset, args.t_from, args.t_to)
        if len(ab) == 0:
            raise ValueError(f"{path}: no frame in the time range")
        series.append((label, ab, bc))
    span = (f"t = {'start' if args.t_from is None else format(args.t_from, 'g')}–"
            f"{'end' if args.t_to is None else format(args.t_to, 'g')}")
    return plot.plot_shape_map(series, args.out, f"shape of every frame, {span}")


def _campaign(argv: Argv) -> int:
    from . import campaign
    p = make_parser("knotflow-campaign",
                    "The case ledger of a campaign that outlives its machine: small committed "
                    "files per case (frame rows, newest frame, run records) and what to run "
                    "next from them (scripts/campaign.sh, docs/analysis.md).")
    sub = p.add_subparsers(dest="command", required=True)
    pl = sub.add_parser("plan", help="print 'case action scene' for each case of a sweep")
    pl.add_argument("--scenes", required=True, help="the sweep's scenes (knotflow --write-scenes)")
    dg = sub.add_parser("digest", help="add analysed case files (copies) to the ledger")
    dg.add_argument("files", nargs="+", metavar="CASE.h5")
    dg.add_argument("--copies", required=True,
                    help="the directory the files are copied into, mirroring --results")
    dg.add_argument("--closures", type=int, required=True,
                    help="closures per frame the files were analysed with")
    dg.add_argument("--positions-every", type=float, default=0.0, metavar="T",
                    help="keep the positions of the frames at multiples of T (0: only the newest)")
    dg.add_argument("--scene-reference", metavar="FILE",
                    help="what `knotflow --scene-reference` printed (the defaults of the program "
                    "that ran the files): a variable written in one scene only is the same as "
                    "its default (a variable added by a later version)")
    st = sub.add_parser("status", help="one line per case of the ledger's sweeps, then one per "
                        "sweep (cases, measured rate, time left) and one for the campaign")
    st.add_argument("--scenes", metavar="DIR",
                    help="the campaign's scenes (DIR/<sweep>/<case>.nml, knotflow --write-scenes):"
                    " count the cases not started and the time they need")
    st.add_argument("--scene-reference", metavar="FILE",
                    help="what `knotflow --scene-reference` printed: completes the variables an "
                    "older scene did not write when a sweep without a rate of its own takes that "
                    "of sweeps with alike scenes")
    st.add_argument("--markdown", action="store_true",
                    help="one markdown table row per sweep instead (for a document)")
    md = sub.add_parser("mode", help="record a case's mode: knotflow-analyze <case>.csv --json")
    md.add_argument("--case", required=True)
    md.add_argument("--analyze-json", required=True, metavar="TEXT",
                    help="what knotflow-analyze LEDGER/SWEEP/CASE.csv --json printed")
    md.add_argument("--sweep", required=True, help="the sweep's name")
    wn = sub.add_parser("windows", help="means of the shape observables, k_f and the per-frame "
                        "modes over consecutive time windows of cases (a markdown table, one "
                        "row per window and case)")
    wn.add_argument("cases", nargs="+", metavar="CASE",
                    help="ledger entries (<ledger>/<sweep>/<case>.json) or case files (.h5)")
    wn.add_argument("--width", type=float, required=True, help="the window length")
    wn.add_argument("--from", dest="t_from", type=float, metavar="T",
                    help="the first window's start (default: each case's first time rounded "
                    "down to a multiple of --width)")
    sm = sub.add_parser("shapes", help="the frames of cases in the plane of b/c and a/b, with "
                        "the thresholds of the mode rule (a PNG): how far from each mode")
    sm.add_argument("--out", required=True, metavar="PNG", help="the figure to write")
    sm.add_argument("cases", nargs="+", metavar="CASE",
                    help="ledger entries (<ledger>/<sweep>/<case>.json) or case files (.h5)")
    for q in (wn, sm):
        q.add_argument("--offset", type=float, nargs="+", metavar="T",
                       help="added to each case's time (one value per case; default 0): a run "
                       "started from a frame of another at its time")
        q.add_argument("--to", dest="t_to", type=float, metavar="T",
                       help="the last time included (default: each case's last)")
    sm.add_argument("--from", dest="t_from", type=float, metavar="T",
                    help="the first time included (default: each case's first)")
    for q in (pl, dg, st, md):
        q.add_argument("--ledger", required=True, help="the ledger directory")
    for q in (pl, dg):
        q.add_argument("--sweep", required=True, help="the sweep's name (inputs/<sweep>.nml)")
        q.add_argument("--results", required=True, help="the sweep outputs' parent directory")
    args = p.parse_args(argv)
    if args.command == "plan":
        for name, action, scene in campaign.plan(args.scenes, args.results, args.ledger,
                                                 args.sweep):
            print(name, action, scene or "-")
    elif args.command == "digest":
        if args.closures < 1 or not args.positions_every >= 0.0:
            p.error("--closures needs a positive integer, --positions-every T >= 0")
        defaults = _scene_reference(p, args.scene_reference) if args.scene_reference else {}
        for f in args.files:
            source = os.path.join(args.results, os.path.relpath(f, args.copies))
            e = campaign.digest(f, args.ledger, args.sweep, args.closures,
                                args.positions_every, source, defaults)
            print(f"{args.sweep}/{e['case']}: {e['status']}, t = {e['t_reached']:g} of "
                  f"{e['t_end']:g}, {len(e['segments'])} segment(s)")
    elif args.command == "windows":
        for line in _window_table(args):
            print(line)
    elif args.command == "shapes":
        print(_shape_map(args))
    elif args.command == "mode":
        e = campaign.set_case_mode(args.ledger, args.sweep, args.case, args.analyze_json)
        print(f"{args.sweep}/{args.case}: case mode {e['case_mode']['mode']} of "
              f"{e['case_mode']['frames']} frames")
    else:
        if args.scenes is not None and not os.path.isdir(args.scenes):
            p.error(f"--scenes {args.scenes}: not a directory")
        defaults = None
        if args.scene_reference is not None:
            defaults = _scene_reference(p, args.scene_reference)
        render = campaign.status_markdown if args.markdown else campaign.status_lines
        for line in render(args.ledger, args.scenes, defaults):
            print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main_kf())
