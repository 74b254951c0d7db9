"""Bad arguments raise KnotflowError with the library's message; the interpreter lives on."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest

import knotflow
from knotflow import KnotflowError

GOOD = np.array([[0.0, 0.0, 0.0], [1.2, 0.0, 0.0], [2.4, 0.3, 0.0]])


@pytest.mark.parametrize("positions",
                         [np.zeros((4, 2)), np.zeros(9), np.zeros((2, 3, 1)), "abc", [[1, 2], [3]]])
def test_wrong_shape(positions):
    for call in (knotflow.mobility, knotflow.knotted_fraction, knotflow.shape):
        with pytest.raises(KnotflowError, match="positions"):
            call(positions)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_coordinate(bad):
    r = GOOD.copy()
    r[1, 2] = bad
    # the library names the bead (1-based) and the call
    with pytest.raises(KnotflowError, match=r"knotflow_model_mobility: bead 2 \(1-based\) has a non-finite"):
        knotflow.mobility(r)
    with pytest.raises(KnotflowError, match=r"knotflow_knots: bead 2 \(1-based\) has a non-finite"):
        knotflow.knotted_fraction(r, closures=10, seed=1)
    with pytest.raises(KnotflowError, match=r"knotflow_shape: bead 2 \(1-based\)"):
        knotflow.shape(r)


@pytest.mark.parametrize("span", [1.0e300, 1.0e154])
def test_beads_too_far_apart(span):
    """Beads whose squared distances overflow (a coordinate ranging over sqrt(huge/3) = 7.741e153
    d or more) are refused before anything is computed: k_f used to come out as an unknot and
    the forces as NaN, with no error."""
    r = GOOD.copy()
    r[2, 0] = span
    rule = r"are too far apart: their squared distances overflow \(allowed: each coordinate " \
           r"ranging over less than 7\.741E\+153 d\)"
    for call, name in ((lambda: knotflow.mobility(r), "knotflow_model_mobility"),
                       (lambda: knotflow.knotted_fraction(r, closures=10, seed=1), "knotflow_knots"),
                       (lambda: knotflow.knot_matrix(r, closures=2, seed=1, min_length=2),
                        "knotflow_knot_matrix"),
                       (lambda: knotflow.chain_forces(r), "knotflow_chain_forces"),
                       (lambda: knotflow.shape(r), "knotflow_shape")):
        with pytest.raises(KnotflowError, match=name + ": the beads " + rule):
            call()
    # just inside the limit the same beads are accepted (the forces of a bond 7.7e153 long)
    r[2, 0] = 7.7e153
    forces, _ = knotflow.chain_forces(r, bending=False)
    assert np.all(np.isfinite(forces))


def test_too_few_beads():
    # k_f needs a chain: the knot code's own limit and message
    with pytest.raises(KnotflowError, match="the chain has 1 bead\\(s\\), at least 2 are needed"):
        knotflow.knotted_fraction(GOOD[:1], closures=10, seed=1)
    with pytest.raises(KnotflowError, match="the chain has 0 bead\\(s\\)"):
        knotflow.knots(np.zeros((0, 3)), closures=10, seed=1)
    # a mobility needs at least one bead (one alone is Stokes' sphere: test_mobility)
    with pytest.raises(KnotflowError, match="0 bead\\(s\\) given, at least 1 needed"):
        knotflow.mobility(np.zeros((0, 3)))
    with pytest.raises(KnotflowError, match="at least 2 needed"):
        knotflow.shape(GOOD[:1])


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"model": "stokeslet"}, "&hydro: model = 'stokeslet' is not allowed \\(one of none, rpy, multipole\\)"),
    ({"model": "m" * 100}, "&hydro: model = 'm+' is not allowed \\(one of none, rpy, multipole\\)"),
    ({"model": 3}, "model = 3: expected a name"),
    ({"order": 0}, "&hydro: order = 0 is not allowed \\(an integer from 1 to 8\\)"),
    ({"order": 9}, "&hydro: order = 9 is not allowed"),
    ({"order": 7}, "&hydro: order = 7 is not allowed \\(at most 6 with lubrication"),
    ({"order": 2.5}, "order = 2.5: expected an integer"),
    ({"order": True}, "order = True: expected an integer"),
    ({"order": 2**40}, "out of the range of a C int"),
    ({"eps_lub": -1.0}, "&hydro: eps_lub = -1.0 is not allowed \\(a number in \\(0, 0.5\\)\\)"),
    ({"eps_lub": 0.5}, "&hydro: eps_lub = 0.5 is not allowed"),
    ({"eps_lub": 0.0}, "&hydro: eps_lub = 0.0 is not allowed \\(a number in \\(0, 0.5\\)\\)"),
    ({"eps_lub": float("nan")}, "eps_lub"),
    ({"overlap": "glue"}, "&hydro: overlap = 'glue' is not allowed \\(one of pair, separate, relax, bwe\\)"),
    ({"overlap_time": 1.0}, "overlap_time = 1.0 is not allowed \\(only with overlap = 'relax'"),
    ({"model": "rpy", "lubrication": False, "overlap": "separate"}, "the rule is for the multipole model"),
])
def test_bad_model(kwargs, message):
    with pytest.raises(KnotflowError, match=message):
        knotflow.mobility(GOOD, **kwargs)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"closures": 0}, "the number of closures must be >= 1, got 0"),
    ({"closures": -5}, "the number of closures must be >= 1, got -5"),
    ({"closures": 1.5}, "closures = 1.5: expected an integer"),
    ({"seed": 2**64}, "seed = 18446744073709551616: expected a 64-bit integer"),
    ({"seed": "1"}, "seed = '1': expected a 64-bit integer"),
    ({"stream": -1}, "stream = -1 \\(must be >= 0\\)"),
])
def test_bad_knot_arguments(kwargs, message):
    with pytest.raises(KnotflowError, match=message):
        knotflow.knots(GOOD, **kwargs)


def test_status_tells_refusal_from_failure():
    with pytest.raises(KnotflowError) as refused:
        knotflow.Model(order=0)
    assert refused.value.status == 1
    # overlapping beads beyond what the multipole system supports: the library fails (2)
    with pytest.raises(KnotflowError, match="Cholesky") as failed:
        knotflow.mobility(np.zeros((3, 3)) + np.arange(3)[:, None] * 0.1)
    assert failed.value.status == 2


def test_interpreter_survives_every_refusal():
    """The bad calls in a fresh interpreter, which must then go on and exit normally."""
    code = textwrap.dedent("""
        import numpy as np, knotflow
        bad = [lambda: knotflow.mobility(np.full((3, 3), np.nan)),
               lambda: knotflow.mobility(np.zeros((0, 3))),
               lambda: knotflow.mobility(np.zeros((5, 3))),
               lambda: knotflow.Model('nope'),
               lambda: knotflow.Model(order=-3),
               lambda: knotflow.knotted_fraction(np.zeros((1, 3))),
               lambda: knotflow.knots(np.eye(3), closures=0),
               lambda: knotflow.knot_matrix(np.full((4, 3), np.nan)),
               lambda: knotflow.knot_matrix(np.eye(3), min_length=-7),
               lambda: knotflow.knot_core(np.zeros((2, 5))),
               lambda: knotflow.run_scene('/nonexistent/scene.nml'),
               lambda: knotflow.scene_cases('/dev/null'),
               lambda: knotflow.read_case('/nonexistent/case.h5'),
               lambda: knotflow.read_case('/dev/null'),
               lambda: knotflow.read_case('/')]
        n = 0
        for call in bad:
            try:
                call()
            except knotflow.KnotflowError:
                n += 1
        print('refused', n)
    """)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "refused 15"
