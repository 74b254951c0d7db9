"""knotflow.mobility and knotflow.Model against knotflow-mobility (the same library code).

knotflow-mobility prints every entry with 17 significant digits, which reads back as the same
double: the matrices must be equal bit for bit.
"""

import numpy as np
import pytest

import knotflow

from conftest import run, write_coordinates


def cli_mobility(path: str, *options: str) -> np.ndarray:
    return np.array([[float(x) for x in line.split()] for line in
                     run("knotflow-mobility", path, *options, "--output", "mobility").splitlines()])


@pytest.mark.parametrize(("model", "order", "lubrication"), [
    ("multipole", 2, True), ("multipole", 2, False), ("multipole", 3, True), ("multipole", 1, True),
    ("rpy", 2, False), ("none", 2, False)])
def test_mobility_equals_program(tmp_path, cluster, model, order, lubrication):
    path = write_coordinates(tmp_path / "r.xyz", cluster)
    expected = cli_mobility(path, "--model", model, "--order", str(order),
                            "--lubrication", "on" if lubrication else "off")
    got = knotflow.mobility(cluster, model=model, order=order, lubrication=lubrication)
    assert got.shape == (3 * len(cluster), 3 * len(cluster))
    assert np.array_equal(got, expected)


def test_trefoil_l2_lubrication_equals_program(tmp_path, trefoil):
    """The issue's case: N = 99, L = 2 with lubrication, the program's defaults and options."""
    path = write_coordinates(tmp_path / "trefoil.xyz", trefoil)
    expected = cli_mobility(path, "--model", "multipole", "--order", "2", "--lubrication", "on")
    got = knotflow.mobility(trefoil, model="multipole", order=2, lubrication=True)
    assert np.array_equal(got, expected)
    assert np.array_equal(got, got.T)


def test_eps_lub_reaches_the_model(tmp_path, cluster):
    """A non-default eps_lub changes the overlapping pair's blocks, as --eps-lub does."""
    path = write_coordinates(tmp_path / "r.xyz", cluster)
    expected = cli_mobility(path, "--eps-lub", "0.01")
    got = knotflow.mobility(cluster, eps_lub=0.01)
    assert np.array_equal(got, expected)
    assert not np.array_equal(got, knotflow.mobility(cluster))


def test_one_bead_is_stokes():
    """An isolated bead: mu = I/3 in the project's units, for every model (the multipole one
    through a Cholesky solve, so to rounding)."""
    for model in knotflow.model_names():
        got = knotflow.mobility([[1.0, 2.0, 3.0]], model=model)
        assert np.allclose(got, np.eye(3) / 3.0, rtol=0.0, atol=1e-15), model


def test_model_reused_for_many_configurations(cluster, trefoil):
    """One Model, configurations of different sizes in turn: each as from a fresh model."""
    with knotflow.Model("multipole", 2, True) as m:
        assert m.label == "multipole L=2 lubrication"
        a = m.mobility(trefoil)
        b = m.mobility(cluster)
        c = m.mobility(trefoil)
    assert np.array_equal(a, c)
    assert np.array_equal(b, knotflow.mobility(cluster))
    with pytest.raises(knotflow.KnotflowError, match="closed"):
        m.mobility(cluster)


def test_shear_disturbance_equals_program(tmp_path, cluster):
    path = write_coordinates(tmp_path / "r.xyz", cluster)
    expected = np.array([[float(x) for x in line.split()] for line in
                         run("knotflow-mobility", path, "--output", "shear").splitlines()])
    assert np.array_equal(knotflow.shear_disturbance(cluster), expected)
