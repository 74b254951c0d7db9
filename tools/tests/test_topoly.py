"""Per-closure comparison with topoly (skipped when topoly is not installed)."""

import numpy as np
import pytest

from knotflow_tools import knots as K

from helpers import figure_eight, open_from_closed, open_trefoil, random_walk, torus_knot

topoly = pytest.importorskip("topoly")
pytestmark = pytest.mark.topoly


def topoly_type(poly):
    from topoly.params import Closure
    pts = [list(map(float, x)) for x in poly] + [list(map(float, poly[0]))]
    res = topoly.alexander(pts, closure=Closure.CLOSED, hide_trivial=False, run_parallel=False,
                           max_cross=60)
    return str(res)


@pytest.mark.parametrize("chain", [open_trefoil(), open_from_closed(torus_knot(2, 5, 80), 1),
                                   open_from_closed(figure_eight(80), 1),
                                   random_walk(60, seed=8, step=1.0)],
                         ids=["trefoil99", "5_1", "4_1", "walk60"])
def test_same_types_on_same_closure_points(chain):
    rng = np.random.default_rng(21)
    pts = K.closure_points(chain, 12, rng)
    compared = 0
    for p in pts:
        poly = K.close_chain(chain, p)
        ours = K.classify_polygon(poly, np.random.default_rng(1))
        theirs = topoly_type(poly)
        if theirs in K.KNOT_TYPES:
            assert ours == theirs
            compared += 1
        else:
            # topoly names a knot outside our table: ours must be non-trivial
            assert theirs != "TMC" and ours != "0_1"
    assert compared >= 8
