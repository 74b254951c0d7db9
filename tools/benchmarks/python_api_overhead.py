#!/usr/bin/env python3
"""Overhead of the knotflow package's calls against the library's own work (docs/python-api.md).

For the mobility of the N = 99 open trefoil (multipole L = 2 with lubrication) and its k_f from
1000 closures: the wall time of the Python call and the library's wall time of the same
evaluation, measured inside the Fortran call (prepare + mobility matrix; the closure analysis),
as the median of --repeats calls; the overhead is their difference over the library's time.
`knotflow.mobility` (which builds and frees a model at every call) and `Model.mobility` (a
model kept) are both timed. Prints the 1-minute load average with the results. Not part of the
test suite.

    python tools/benchmarks/python_api_overhead.py [--repeats 7]
"""

import argparse
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests"))

import knotflow  # noqa: E402

from helpers import open_trefoil  # noqa: E402


def timed(call):
    start = time.perf_counter()
    result = call()
    return time.perf_counter() - start, result


def report(what, python_s, library_s):
    """Median and minimum (the least disturbed by other load) of both times, and the overhead
    (python - library) / library of each."""
    for stat in (statistics.median, min):
        py, lib = stat(python_s), stat(library_s)
        print(f"{what:42s} {stat.__name__:6s} python {py * 1e3:9.3f} ms  library {lib * 1e3:9.3f} ms  "
              f"overhead {100.0 * (py - lib) / lib:6.2f} %")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    r = open_trefoil()
    print(f"knotflow library: {knotflow._library.loaded_path()}")
    print(f"load average (1 min) before: {os.getloadavg()[0]:.2f}; N = {len(r)}")

    with knotflow.Model("multipole", order=2, lubrication=True) as model:
        model.mobility(r)  # first call: work arrays
        py, lib = [], []
        for _ in range(args.repeats):
            t, _ = timed(lambda: model.mobility(r))
            py.append(t)
            lib.append(model.last_seconds)
    report("Model.mobility (L=2 + lubrication)", py, lib)

    # the function builds and frees a model at every call: the library's time of the evaluation
    # is that of a kept model, measured alternately with it
    py, lib = [], []
    with knotflow.Model("multipole", order=2, lubrication=True) as model:
        for _ in range(args.repeats):
            py.append(timed(lambda: knotflow.mobility(r, model="multipole", order=2, lubrication=True))[0])
            model.mobility(r)
            lib.append(model.last_seconds)
    report("knotflow.mobility (model built per call)", py, lib)

    py, lib = [], []
    for k in range(args.repeats):
        t, res = timed(lambda k=k: knotflow.knots(r, closures=1000, seed=1000 + k))
        py.append(t)
        lib.append(res.seconds)
    report("knotflow.knots (1000 closures)", py, lib)
    print(f"load average (1 min) after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
