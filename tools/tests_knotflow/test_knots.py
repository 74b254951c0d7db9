"""knotflow.knots / knotted_fraction / knot_spectrum against knotflow-analyze on a coordinate file."""

import json

import numpy as np
import pytest

import knotflow

from conftest import run, write_coordinates


def cli_knots(path: str, closures: int, seed: int) -> dict:
    return json.loads(run("knotflow-analyze", path, "--closures", str(closures), "--seed", str(seed),
                          "--json", "--per-closure"))


@pytest.mark.parametrize("seed", [1, 20261205, 2**40 + 7])
def test_knotted_fraction_equals_program(tmp_path, trefoil, seed):
    path = write_coordinates(tmp_path / "trefoil.xyz", trefoil)
    expected = cli_knots(path, 1000, seed)
    k = knotflow.knots(trefoil, closures=1000, seed=seed)
    assert knotflow.knotted_fraction(trefoil, closures=1000, seed=seed) == expected["kf"]
    assert k.kf == expected["kf"]
    assert k.spectrum == expected["spectrum"]
    assert knotflow.knot_spectrum(trefoil, closures=1000, seed=seed) == expected["spectrum"]
    assert k.dominant == expected["dominant"]
    assert list(k.per_closure) == expected["per_closure"]
    # k_f is the fraction of closures that are not the unknot
    assert k.kf == sum(t != "0_1" for t in k.per_closure) / 1000
    assert 0.0 < k.kf < 1.0


def test_defaults_are_the_programs(tmp_path, trefoil):
    """No closures and seed given: knotflow-analyze's defaults."""
    path = write_coordinates(tmp_path / "trefoil.xyz", trefoil)
    expected = json.loads(run("knotflow-analyze", path, "--json"))
    k = knotflow.knots(trefoil)
    assert (k.closures, k.seed) == (expected["closures"], expected["seed"])
    assert k.kf == expected["kf"]


def test_straight_chain_is_unknotted():
    r = np.zeros((30, 3))
    r[:, 0] = np.arange(30.0)
    k = knotflow.knots(r, closures=50, seed=3)
    assert k.kf == 0.0
    assert k.spectrum["0_1"] == 1.0
    assert k.dominant == "0_1"


def test_spectrum_keys_are_the_library_types(trefoil):
    types = knotflow.knot_types()
    assert types[0] == "0_1" and types[-1] == "other" and "3_1" in types
    assert tuple(knotflow.knot_spectrum(trefoil, closures=20, seed=1)) == types
