"""Independent models in threads at the same time give what they give one after another
(the C layer has no global state; ctypes releases the GIL during the calls)."""

from concurrent.futures import ThreadPoolExecutor

import numpy as np

import knotflow


def configurations(n_conf: int, n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(7)
    out = []
    for _ in range(n_conf):
        r = np.zeros((n, 3))
        r[:, 0] = 1.3 * np.arange(n)
        out.append(r + 0.1 * rng.normal(size=(n, 3)))
    return out


def test_models_in_threads(trefoil):
    confs = configurations(4, 30) + [trefoil]
    specs = [("multipole", 2, True), ("multipole", 3, False), ("rpy", 2, False), ("multipole", 1, True)]
    serial = {(s, k): knotflow.mobility(c, *s) for s in specs for k, c in enumerate(confs)}

    def work(spec):
        with knotflow.Model(*spec) as m:
            return {(spec, k): m.mobility(c) for _ in range(2) for k, c in enumerate(confs)}

    with ThreadPoolExecutor(max_workers=len(specs)) as pool:
        results = list(pool.map(work, specs))
    for res in results:
        for key, mu in res.items():
            assert np.array_equal(mu, serial[key]), key


def test_knots_in_threads(trefoil):
    seeds = [1, 2, 3, 4, 5, 6]
    serial = [knotflow.knots(trefoil, closures=200, seed=s).per_closure for s in seeds]
    with ThreadPoolExecutor(max_workers=3) as pool:
        threaded = list(pool.map(lambda s: knotflow.knots(trefoil, closures=200, seed=s).per_closure, seeds))
    assert threaded == serial
