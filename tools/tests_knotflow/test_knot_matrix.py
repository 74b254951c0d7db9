"""knotflow.knot_matrix / knot_core / knots(points=...) against knotflow-analyze on a coordinate
file (to the last bit), the numpy oracle (knotflow_tools.knots, statistically: another random
stream) and the definition (stride: the full matrix's entries on the grid)."""

import json
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import knotflow
from knotflow import KnotflowError
from knotflow_tools import knots as oracle

from conftest import run, write_coordinates
from helpers import open_from_closed, open_trefoil, torus_knot


def cli_matrix(path: str, *args: str) -> dict:
    return json.loads(run("knotflow-analyze", path, "--json", "--matrix", *args))


def slipknot_chain() -> np.ndarray:
    """A knotted open trefoil (35 beads) followed by its own path retraced 0.05 away: the whole
    chain is unknotted, its first half knotted (a slipknot)."""
    t = open_trefoil(35)
    return np.vstack([t, t[::-1] + np.array([0.0, 0.0, 0.05])])


@pytest.mark.parametrize(("seed", "closures", "min_length"), [(1, 6, 20), (20261205, 3, 28)])
def test_knot_matrix_equals_program(tmp_path, seed, closures, min_length):
    r = slipknot_chain()
    path = write_coordinates(tmp_path / "slip.xyz", r)
    expected = cli_matrix(path, "--matrix-closures", str(closures), "--min-length", str(min_length),
                          "--seed", str(seed), "--closures", "200")
    km = knotflow.knot_matrix(r, closures=closures, seed=seed, min_length=min_length,
                              kf_whole=knotflow.knotted_fraction(r, closures=200, seed=seed))
    want = np.array([[np.nan if v is None else v for v in row] for row in expected["matrix"]])
    assert km.matrix.shape == (len(r), len(r))
    assert np.array_equal(km.matrix, want, equal_nan=True)
    assert km.core == (tuple(expected["knot_core"]) if expected["knot_core"] else None)
    assert km.slipknot == expected["slipknot"]
    assert (km.closures, km.seed, km.min_length, km.stride) == (closures, seed, min_length, 1)
    # the definition: NaN exactly where j - i + 1 < min_length (and below the diagonal), and the
    # entries are fractions of the closures
    i, j = np.indices(want.shape)
    assert np.array_equal(np.isnan(km.matrix), (j <= i) | (j - i + 1 < min_length))
    done = km.matrix[~np.isnan(km.matrix)]
    assert np.array_equal(done * closures, np.round(done * closures))
    # the constructed slipknot: a knotted subchain, an unknotted whole
    assert km.core is not None and km.slipknot is True


def test_defaults_are_the_programs(tmp_path):
    r = open_trefoil()[:16]
    path = write_coordinates(tmp_path / "t.xyz", r)
    expected = cli_matrix(path)
    km = knotflow.knot_matrix(r)
    want = np.array([[np.nan if v is None else v for v in row] for row in expected["matrix"]])
    assert np.array_equal(km.matrix, want, equal_nan=True)
    assert (km.closures, km.min_length) == knotflow.matrix_defaults() == (100, 10)
    assert km.seed == knotflow.default_seed() == expected["seed"]
    assert km.slipknot is None


def test_stride_gives_the_full_matrix_on_its_grid():
    """Each subchain draws from its own stream: the strided matrix is the full one on the grid
    (i and j multiples of the stride, or j = N - 1), NaN elsewhere."""
    r = slipknot_chain()
    n = len(r)
    full = knotflow.knot_matrix(r, closures=3, seed=3, min_length=8).matrix
    strided = knotflow.knot_matrix(r, closures=3, seed=3, min_length=8, stride=4).matrix
    grid_i = np.arange(n) % 4 == 0
    grid_j = grid_i | (np.arange(n) == n - 1)
    on = grid_i[:, None] & grid_j[None, :]
    assert np.array_equal(strided[on], full[on], equal_nan=True)
    assert np.isnan(strided[~on]).all()
    assert np.isfinite(strided[on]).sum() > 20


def test_agrees_with_the_numpy_oracle():
    """The numpy knot matrix (another random stream) computes the same quantity: the entries
    agree within the binomial spread of 100 closures, NaN at the same places."""
    r = open_from_closed(torus_knot(2, 3, 40, R=2.0, r=0.8), 1)
    lib = knotflow.knot_matrix(r, closures=100, seed=5, min_length=10, stride=6).matrix
    ref = oracle.knot_matrix(r, closures=100, seed=5, min_length=10, stride=6)
    assert np.array_equal(np.isnan(lib), np.isnan(ref))
    both = ~np.isnan(lib)
    assert both.sum() >= 15
    # |difference| of two fractions of 100 closures: at most 4.5 standard deviations of 0.07
    assert np.max(np.abs(lib[both] - ref[both])) <= 0.32
    assert lib[0, len(r) - 1] > 0.5 and ref[0, len(r) - 1] > 0.5
    assert knotflow.knot_core(lib) == lib_core(lib) and knotflow.knot_core(ref) == oracle.knot_core(ref)


def lib_core(mat: np.ndarray):
    """The knot core by its definition (shortest subchain with K >= 0.5, lowest i on a tie)."""
    best = None
    for i in range(len(mat)):
        for j in range(i + 1, len(mat)):
            if mat[i, j] >= 0.5 and (best is None or j - i < best[1] - best[0]):
                best = (i, j)
    return best


def test_knot_core_of_given_matrices():
    mat = np.full((6, 6), np.nan)
    assert knotflow.knot_core(mat) is None
    mat[0, 5] = 0.9
    mat[1, 4] = 0.5
    mat[2, 5] = 0.7      # as short as 1..4: the lower i wins
    mat[3, 4] = 0.49
    mat[4, 1] = 1.0      # below the diagonal: not a subchain
    assert knotflow.knot_core(mat) == (1, 4) == oracle.knot_core(np.triu(np.nan_to_num(mat, nan=0.0), 1))
    assert knotflow.knot_core(np.zeros((0, 0))) is None
    with pytest.raises(KnotflowError, match="square"):
        knotflow.knot_core(np.zeros((3, 4)))
    with pytest.raises(KnotflowError, match="square"):
        knotflow.knot_core(np.zeros(4))


def test_closure_points_equal_program(tmp_path):
    r = open_from_closed(torus_knot(2, 3, 24, R=2.0, r=0.8), 1)
    gap, com = 0.5 * (r[0] + r[-1]), r.mean(axis=0)
    pts = np.array([com + 40 * (gap - com), com + 50 * (gap - com), com + 30 * (com - gap)])
    path = write_coordinates(tmp_path / "chain.xyz", r)
    ppath = write_coordinates(tmp_path / "points.xyz", pts)
    expected = json.loads(run("knotflow-analyze", path, "--closure-points", ppath, "--seed", "9", "--json",
                              "--per-closure"))
    k = knotflow.knots(r, points=pts, seed=9)
    assert k.kf == expected["kf"] and list(k.per_closure) == expected["per_closure"]
    assert k.closures == 3 and k.per_closure[:2] == ("3_1", "3_1")


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"closures": 0}, r"closures = 0 \(must be >= 1\)"),
    ({"min_length": 1}, "min_length must be >= 2, got 1"),
    ({"stride": 0}, "stride must be >= 1, got 0"),
    ({"closures": 2.5}, "closures = 2.5: expected an integer"),
    ({"seed": "x"}, "seed = 'x': expected a 64-bit integer"),
    ({"kf_whole": float("nan")}, "kf_whole = nan: expected a finite number"),
])
def test_bad_matrix_arguments(kwargs, message):
    with pytest.raises(KnotflowError, match=message):
        knotflow.knot_matrix(open_trefoil(40), **kwargs)


def test_bad_matrix_chains():
    with pytest.raises(KnotflowError, match=r"1 bead\(s\) given, at least 2 needed"):
        knotflow.knot_matrix(np.zeros((1, 3)))
    with pytest.raises(KnotflowError, match="expected an \\(N, 3\\) array"):
        knotflow.knot_matrix(np.zeros((5, 2)))
    r = open_trefoil(40)
    r[3, 1] = np.nan
    with pytest.raises(KnotflowError, match=r"knotflow_knot_matrix: bead 4 \(1-based\) has a non-finite"):
        knotflow.knot_matrix(r)
    with pytest.raises(KnotflowError, match="at least 1 needed"):
        knotflow.knots(open_trefoil(40), points=np.zeros((0, 3)))
    with pytest.raises(KnotflowError, match="non-finite"):
        knotflow.knots(open_trefoil(40), points=np.array([[np.inf, 0.0, 0.0]]))
    with pytest.raises(KnotflowError, match="closures = 5 but 1 closure points given"):
        knotflow.knots(open_trefoil(40), closures=5, points=np.array([[50.0, 0.0, 0.0]]))
    # two beads: no subchain of min_length 10, every entry NaN, no core
    km = knotflow.knot_matrix(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]))
    assert np.isnan(km.matrix).all() and km.core is None


def test_matrices_in_threads():
    r = slipknot_chain()
    seeds = [1, 2, 3, 4]
    serial = [knotflow.knot_matrix(r, closures=2, seed=s, stride=5).matrix for s in seeds]
    with ThreadPoolExecutor(max_workers=4) as pool:
        threaded = list(pool.map(lambda s: knotflow.knot_matrix(r, closures=2, seed=s, stride=5).matrix,
                                 seeds))
    for a, b in zip(serial, threaded, strict=True):
        assert np.array_equal(a, b, equal_nan=True)
