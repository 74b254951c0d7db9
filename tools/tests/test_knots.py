"""Knot detection: closed and opened knots, unknots, degenerate inputs, knot matrix."""

import numpy as np
import pytest

from knotflow_tools import knots as K

from helpers import figure_eight, knot_5_2, open_from_closed, open_trefoil, random_walk, torus_knot

CLOSED = [("3_1", torus_knot(2, 3, 120)), ("3_1", torus_knot(3, 2, 120)),
          ("5_1", torus_knot(2, 5, 150)), ("4_1", figure_eight(150)), ("5_2", knot_5_2(200)),
          ("7_1", torus_knot(2, 7, 200))]


@pytest.mark.parametrize("expected,poly", CLOSED)
def test_closed_knots(expected, poly):
    assert K.classify_polygon(poly, np.random.default_rng(3)) == expected


@pytest.mark.parametrize("expected,poly", CLOSED)
def test_invariants_without_reduction_and_mirror(expected, poly):
    rng = np.random.default_rng(4)
    full = K.alexander_invariants(poly, rng, reduce=False)
    mirror = K.alexander_invariants(poly * np.array([1.0, 1.0, -1.0]), rng)
    assert K.classify_invariants(*full) == expected
    assert K.classify_invariants(*mirror) == expected


def test_invariant_values_from_alexander_polynomials():
    # Delta_3_1 = t^2 - t + 1, Delta_4_1 = -t^2 + 3t - 1, Delta_5_2 = 2t^2 - 3t + 2
    polys = {"3_1": [1, -1, 1], "4_1": [-1, 3, -1], "5_1": [1, -1, 1, -1, 1],
             "5_2": [2, -3, 2], "6_1": [-2, 5, -2], "7_1": [1, -1, 1, -1, 1, -1, 1]}
    for name, c in polys.items():
        d1 = abs(np.polyval(c, -1))
        d2 = abs(np.polyval(c, -2))
        assert K.classify_invariants(d1, d2) == name


def test_stick_numbers_respected_by_reduction():
    # minimal stick numbers: 3_1 needs 6 segments, 4_1 needs 7; reduction cannot go below
    assert len(K.reduce_polygon(torus_knot(2, 3, 200))) >= 6
    assert len(K.reduce_polygon(figure_eight(200))) >= 7
    # an unknotted circle reduces to a triangle
    t = np.linspace(0, 2 * np.pi, 50, endpoint=False)
    circle = np.stack([np.cos(t), np.sin(t), 0.1 * np.sin(3 * t)], axis=1)
    assert len(K.reduce_polygon(circle)) == 3


@pytest.mark.parametrize("expected,poly", CLOSED[:5])
def test_tightly_closed_open_knots_every_closure(expected, poly):
    """Chains with a one-bond gap on the outside of the knot.

    Every closure point in the cone (30 degrees) around the outward direction through the gap
    gives the knot's type; random closures over the whole sphere mostly do (segments from the
    gap to points on the far side can cross the knot and change the type).
    """
    r = open_from_closed(poly, 1)
    com = r.mean(axis=0)
    out = 0.5 * (r[0] + r[-1]) - com
    out /= np.linalg.norm(out)
    rng = np.random.default_rng(11)
    u = K.marsaglia_sphere(400, rng)
    u = u[u @ out > np.cos(np.pi / 6)][:25]
    pts = com + 10 * K.radius_of_gyration(r) * u
    res = K.analyze_chain(r, points=pts)
    assert res.closures >= 10
    assert res.per_closure == [expected] * res.closures
    res = K.analyze_chain(r, closures=40, seed=11)
    assert res.dominant == expected
    assert res.spectrum[expected] >= 0.75


def test_open_trefoil_reference_chain():
    r = open_trefoil()
    assert r.shape == (99, 3)
    bonds = np.linalg.norm(np.diff(r, axis=0), axis=1)
    assert 1.0178 < bonds.min() and bonds.max() < 1.0200
    # Default (last point removed): our measurement is k_f = 0.849 with 1000 closures;
    # PHYSICS.md 5 gives 0.83 - 1.0 depending on the removed point.
    res = K.analyze_chain(r, closures=300, seed=2)
    assert res.dominant == "3_1"
    assert 0.80 <= res.kf <= 0.90
    assert set(res.per_closure) <= {"0_1", "3_1"}
    # an interior point removed: k_f close to the study's 0.98
    res_mid = K.analyze_chain(open_trefoil(50), closures=300, seed=2)
    assert 0.92 <= res_mid.kf <= 1.0


def test_straight_and_planar_and_walk_unknots():
    straight = np.stack([np.arange(20.0), np.zeros(20), np.zeros(20)], axis=1)
    s = np.linspace(0, 6 * np.pi, 60)
    spiral = np.stack([(1 + 0.3 * s) * np.cos(s), (1 + 0.3 * s) * np.sin(s), np.zeros(60)],
                      axis=1)
    # a walk monotone in x: every closure has one maximum and one minimum of x -> unknot
    rng = np.random.default_rng(5)
    steps = rng.normal(size=(59, 3))
    steps[:, 0] = np.abs(steps[:, 0]) + 0.05
    mono = np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])
    for r in (straight, spiral, mono):
        res = K.analyze_chain(r, closures=60, seed=1)
        assert res.kf == 0.0
        assert res.dominant == "0_1"


def test_short_random_walk_mostly_unknotted():
    res = K.analyze_chain(random_walk(12, seed=3), closures=50, seed=1)
    # 12-bead walks are essentially always unknotted (a 3_1 needs 6 sticks plus closure)
    assert res.kf <= 0.1


def test_degenerate_inputs():
    # collinear beads, repeated points, N = 2 and N = 3
    line = np.stack([np.linspace(0, 5, 6), np.zeros(6), np.zeros(6)], axis=1)
    rep = np.repeat(torus_knot(2, 3, 60)[:58], 2, axis=0)
    assert K.analyze_chain(line, closures=10).kf == 0.0
    res = K.analyze_chain(rep, closures=10, seed=4)
    assert res.dominant == "3_1"
    assert K.analyze_chain(np.zeros((2, 3)) + [[0, 0, 0], [1, 0, 0]], closures=5).kf == 0.0
    tri = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0]])
    assert K.analyze_chain(tri, closures=20).kf == 0.0
    # a closure point that lies on the chain's line
    assert K.analyze_chain(line, points=np.array([[10.0, 0, 0], [2.5, 0, 0]])).kf == 0.0


def test_marsaglia_closure_points_on_sphere():
    rng = np.random.default_rng(0)
    r = random_walk(30, seed=1)
    pts = K.closure_points(r, 4000, rng)
    rad = np.linalg.norm(pts - r.mean(axis=0), axis=1)
    assert np.allclose(rad, 10.0 * K.radius_of_gyration(r))
    u = (pts - r.mean(axis=0)) / rad[:, None]
    # uniform on the sphere: <u> = 0, <u_k^2> = 1/3 (statistical tolerance ~ 5 sigma)
    assert np.all(np.abs(u.mean(axis=0)) < 5 * np.sqrt(1 / 3 / 4000))
    assert np.allclose((u ** 2).mean(axis=0), 1 / 3, atol=5 * np.sqrt(4 / 45 / 4000))


def test_reproducible_with_seed():
    r = open_trefoil()
    a = K.analyze_chain(r, closures=40, seed=9)
    b = K.analyze_chain(r, closures=40, seed=9)
    assert a.per_closure == b.per_closure and a.kf == b.kf
    pa = K.closure_points(r, 5, np.random.default_rng(9))
    pb = K.closure_points(r, 5, np.random.default_rng(10))
    assert not np.allclose(pa, pb)


def test_explicit_closure_points():
    r = open_from_closed(torus_knot(2, 3, 80), 1)
    # a point just beyond the gap closes the trefoil; spectrum follows the given points only
    gap_mid = 0.5 * (r[0] + r[-1])
    res = K.analyze_chain(r, points=np.array([gap_mid, gap_mid * 1.0001]))
    assert res.closures == 2 and res.per_closure == ["3_1", "3_1"]


def test_bareiss_determinant():
    rng = np.random.default_rng(1)
    for n in range(1, 7):
        m = rng.integers(-5, 6, size=(n, n))
        assert K.bareiss_det(m.tolist()) == int(round(np.linalg.det(m)))
    assert K.bareiss_det([[0, 1], [1, 0]]) == -1
    assert K.bareiss_det([]) == 1
    # exact for huge entries where floating point fails
    big = [[10 ** 20 + 1, 10 ** 20], [10 ** 20, 10 ** 20 - 1]]
    assert K.bareiss_det(big) == -1


def slipknot_chain():
    """Open trefoil followed by its own copy, offset slightly, traversed back (a hairpin).

    The whole chain is unknotted (it bounds a thin ribbon), the first half is knotted.
    """
    p = open_from_closed(torus_knot(2, 3, 30, R=2.0, r=0.8), 2)
    back = (p + np.array([0.0, 0.0, 0.06]))[::-1]
    return np.vstack([p, back]), len(p)


def test_slipknot_found_by_knot_matrix():
    r, half = slipknot_chain()
    whole = K.analyze_chain(r, closures=60, seed=1)
    assert whole.kf < 0.1
    mat = K.knot_matrix(r, closures=12, seed=2, min_length=8, stride=3)
    assert np.isnan(mat[1, 2]) and np.isnan(mat[5, 3])
    core = K.knot_core(mat)
    assert core is not None
    i, j = core
    # the core lies within the first strand or within its (also knotted) returning copy
    assert (j <= half + 2 or i >= half - 3) and j - i >= 5
    assert mat[0, 27] >= 0.5
    assert K.is_slipknot(mat, whole.kf)
    # the open trefoil alone is a knot, not a slipknot
    assert not K.is_slipknot(mat, 0.95)


def test_reduction_and_projection_do_not_change_invariants_random_polygons():
    """Random polygons (mostly knotted): reduced and unreduced polygons, seen along different
    random directions, give identical invariant pairs."""
    nontrivial = 0
    for seed in range(10):
        rng = np.random.default_rng(100 + seed)
        poly = rng.normal(size=(30, 3))
        a = K.alexander_invariants(poly, np.random.default_rng(1))
        b = K.alexander_invariants(poly, np.random.default_rng(2), reduce=False)
        assert a == b
        nontrivial += a != (1, 1)
    assert nontrivial >= 3
