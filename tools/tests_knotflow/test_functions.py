"""Velocities, disturbance, stresslet, chain forces and shape: each against the program, an
exact value, or an independent path of the library."""

import numpy as np
import pytest

import knotflow
from knotflow_tools import shape as numpy_shape

from conftest import run, write_coordinates

SHEAR_G = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
SHEAR_E = 0.5 * (SHEAR_G + SHEAR_G.T)


@pytest.mark.parametrize(("model", "order", "lubrication"), [("multipole", 2, True), ("rpy", 2, False)])
def test_velocities_are_flow_plus_mobility_plus_disturbance(cluster, model, order, lubrication):
    """u = G r + mu F + C:E with mu and C:E from the program-equal functions."""
    f = np.random.default_rng(3).normal(size=cluster.shape)
    u = knotflow.velocities(cluster, f, SHEAR_G, model=model, order=order, lubrication=lubrication)
    mu = knotflow.mobility(cluster, model=model, order=order, lubrication=lubrication)
    ce = knotflow.shear_disturbance(cluster, model=model, order=order, lubrication=lubrication)
    expected = cluster @ SHEAR_G.T + (mu @ f.ravel()).reshape(-1, 3) + ce
    assert np.allclose(u, expected, rtol=0.0, atol=1e-12 * np.abs(expected).max())


def test_quiescent_free_beads_do_not_move(cluster):
    assert np.array_equal(knotflow.velocities(cluster, np.zeros_like(cluster), np.zeros((3, 3))),
                          np.zeros_like(cluster))


def test_disturbance_of_a_general_strain_is_linear(tmp_path, cluster):
    """C:E is linear in E: the disturbance of 2 E_shear + E_ext is 2 (the program's shear
    disturbance) + that of E_ext."""
    e_ext = np.diag([1.0, -0.5, -0.5])
    with knotflow.Model() as m:
        both = m.disturbance(cluster, 2 * SHEAR_E + e_ext)
        ext = m.disturbance(cluster, e_ext)
    path = write_coordinates(tmp_path / "r.xyz", cluster)
    shear = np.array([[float(x) for x in line.split()]
                      for line in run("knotflow-mobility", path, "--output", "shear").splitlines()])
    assert np.allclose(both, 2 * shear + ext, rtol=0.0, atol=1e-13)


def test_stresslet_of_an_isolated_bead():
    """(20/3) pi eta a^3 E = (5/6) E in units of pi eta d^3, whatever force it carries."""
    for model in ("multipole", "rpy"):
        with knotflow.Model(model, lubrication=model == "multipole") as m:
            s = m.stresslet([[0.0, 0.0, 0.0]], [[1.0, -2.0, 0.5]], SHEAR_E)
        assert np.allclose(s, 5.0 / 6.0 * SHEAR_E, rtol=0.0, atol=1e-14), model


@pytest.mark.parametrize("lubrication", [False, True])
def test_stresslet_of_forces_is_reciprocal_to_the_disturbance(cluster, lubrication):
    """Reciprocal theorem: the stresslet due to forces F (no strain) satisfies
    S_F : E' = - sum_j F_j . (C:E')_j for every strain E'; the stresslet is computed from the
    grand resistance (kf_hydro_multipole), the disturbance from the mobility route."""
    f = np.random.default_rng(5).normal(size=cluster.shape)
    with knotflow.Model("multipole", 2, lubrication) as m:
        s = m.stresslet(cluster, f, np.zeros((3, 3)))
        for e in (SHEAR_E, np.diag([1.0, -0.5, -0.5]), np.array([[0, 1, 0], [1, 0, 0], [0, 0, 0.0]])):
            lhs = float(np.sum(s * e))
            rhs = -float(np.sum(f * m.disturbance(cluster, e)))
            assert lhs == pytest.approx(rhs, rel=1e-9, abs=1e-12)
    assert np.allclose(s, s.T, atol=1e-12) and abs(np.trace(s)) < 1e-12


def test_bad_strain_is_refused(cluster):
    with knotflow.Model() as m, pytest.raises(knotflow.KnotflowError, match="symmetric and traceless"):
        m.disturbance(cluster, np.eye(3))


def test_spring_force_exact():
    """Two beads 1.3 apart, rest length 1, springs only: |F| = k 0.3 pulling them together,
    U = (k/2) 0.09."""
    r = np.array([[0.0, 0.0, 0.0], [1.3, 0.0, 0.0]])
    f, u = knotflow.chain_forces(r, bond_length=1.0, springs=True, spring_k=500.0, bending=False)
    assert np.allclose(f, [[150.0, 0, 0], [-150.0, 0, 0]], rtol=1e-14, atol=0.0)
    assert u == pytest.approx(22.5, rel=1e-14)


def test_bending_energy_of_a_right_angle():
    """U = (A / (2 l0)) beta^2 with beta = pi/2 at the middle bead."""
    r = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    _, u = knotflow.chain_forces(r, bond_length=1.0, springs=False, bending=True, bending_a=2.2)
    assert u == pytest.approx(2.2 / 2.0 * (np.pi / 2) ** 2, rel=1e-14)


def test_forces_are_minus_the_energy_gradient(trefoil):
    """Central differences of the energy (springs, bending, excluded volume) at a few beads."""
    r = trefoil[:20] * 0.95
    kw = {"bond_length": 1.0, "excluded_volume": True, "ev_range": 1.5}
    f, _ = knotflow.chain_forces(r, **kw)
    h = 1e-6
    for i in (0, 7, 19):
        for a in range(3):
            rp, rm = r.copy(), r.copy()
            rp[i, a] += h
            rm[i, a] -= h
            grad = (knotflow.chain_forces(rp, **kw)[1] - knotflow.chain_forces(rm, **kw)[1]) / (2 * h)
            assert -grad == pytest.approx(f[i, a], rel=1e-5, abs=1e-5)
    # the external force is added to every bead and is not in the energy
    fe, ue = knotflow.chain_forces(r, external_force=(0.0, 0.0, 2.0), **kw)
    assert np.allclose(fe - f, [0.0, 0.0, 2.0], rtol=0.0, atol=1e-12)
    assert ue == knotflow.chain_forces(r, **kw)[1]


def test_forces_defaults_are_the_scene_defaults():
    d = knotflow.forces_defaults()
    assert d == {"springs": True, "spring_k": 500.0, "bending": True, "bending_a": 2.2,
                 "excluded_volume": False, "ev_strength": 100.0, "ev_range": 1.0}


def test_bad_force_parameters_are_refused():
    r = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    with pytest.raises(knotflow.KnotflowError, match="&forces: spring_k = -1.0 is not allowed"):
        knotflow.chain_forces(r, spring_k=-1.0)
    with pytest.raises(knotflow.KnotflowError, match="forces: bond_length"):
        knotflow.chain_forces(r, bond_length=0.0)
    with pytest.raises(knotflow.KnotflowError, match="external_force"):
        knotflow.chain_forces(r, external_force=(0.0, np.nan, 0.0))


def test_shape_of_a_rod():
    """A straight rod of N beads 1 apart along y: R_g^2 = (N^2 - 1)/12, a = sqrt(3) R_g,
    b = c = 0, principal axis along the vorticity axis (theta = 0 or pi)."""
    n = 11
    r = np.zeros((n, 3))
    r[:, 1] = np.arange(n)
    s = knotflow.shape(r)
    assert s.rg == pytest.approx(np.sqrt((n * n - 1) / 12.0), rel=1e-14)
    assert s.a == pytest.approx(np.sqrt(3.0) * s.rg, rel=1e-14)
    assert s.b == pytest.approx(0.0, abs=1e-7) and s.c == pytest.approx(0.0, abs=1e-7)
    assert min(s.theta, np.pi - s.theta) == pytest.approx(0.0, abs=1e-12)
    assert s.close_pairs == 0


def test_shape_equals_the_numpy_oracle(trefoil, cluster):
    for r in (trefoil, cluster):
        s = knotflow.shape(r)
        o = numpy_shape.compute_shape(r)
        for name in ("rg", "a", "b", "c"):
            assert getattr(s, name) == pytest.approx(getattr(o, name), rel=1e-12), name
        assert s.close_pairs == o.close_pairs
