"""The fibre's stresslet series: read when present (cut to the checkpoint's frames), absent
from files without it, and averaged (running and late-time means)."""

import h5py
import numpy as np

from knotflow_tools import io, rheology

from conftest import unknotting_trefoil_frames, write_case


def add_stresslet(path, nframes):
    """/frames/stresslet as knotflow writes it (values made up, known)."""
    k = np.arange(nframes, dtype=float)
    tensor = np.zeros((nframes, 3, 3))
    tensor[:, 0, 2] = tensor[:, 2, 0] = k
    with h5py.File(path, "a") as f:
        g = f["frames"].create_group("stresslet")
        g["hydrodynamic"] = tensor
        g["elastic"] = 2.0 * tensor
        g["viscosity"] = 2.5 + k
        g["psi1"] = -k
        g["psi2"] = 0.5 * k


def test_read_and_average(tmp_path):
    frames = unknotting_trefoil_frames(5)
    plain = write_case(tmp_path / "plain.h5", frames)
    case = io.read_case(plain)
    assert case.stresslet is None and rheology.rheology_summary(case, 0.0) is None
    path = write_case(tmp_path / "stresslet.h5", frames)
    add_stresslet(path, 5)
    with h5py.File(path, "a") as f:            # a killed run: one frame beyond the checkpoint
        f["checkpoint/nframes"][()] = 4
    case = io.read_case(path)
    assert set(case.stresslet) == set(io.STRESSLET)
    assert case.stresslet["hydrodynamic"].shape == (4, 3, 3)
    assert list(case.stresslet["viscosity"]) == [2.5, 3.5, 4.5, 5.5]
    assert np.allclose(rheology.running_mean(case.stresslet["viscosity"]), [2.5, 3.0, 3.5, 4.0])
    t_from = case.time[2]
    summary = rheology.rheology_summary(case, t_from)
    assert summary["viscosity"] == (5.0, 0.5, 2)
    assert summary["psi1"] == (-2.5, 0.5, 2)
    assert rheology.late_time_mean(case.time, case.stresslet["psi2"], case.time[-1] + 1.0)[2] == 0


def test_report_shows_rheology(tmp_path):
    from knotflow_tools import report
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    frames = unknotting_trefoil_frames(4)
    write_case(sweep / "old.h5", frames)
    new = write_case(sweep / "new.h5", frames)
    add_stresslet(new, 4)
    out = report.build_report(str(sweep), closures=10, movie=False, viewer=False)
    rows = {r["name"]: r for r in out["rows"]}
    assert rows["old"]["rheology"] is None
    with h5py.File(new, "r") as f:
        t = f["frames/time"][:]
    late = t >= 0.5 * t[-1]
    v = 2.5 + np.arange(4.0)
    assert rows["new"]["rheology"]["viscosity"] == (v[late].mean(), v[late].std(), int(late.sum()))
    with open(out["md"], encoding="utf-8") as fh:
        md = fh.read()
    with open(out["html"], encoding="utf-8") as fh:
        html = fh.read()
    assert "## Rheology" in md and "| case | viscosity | psi1 | psi2 | frames |" in md
    section = md.split("## Rheology")[1].split("##")[0]
    assert next(line for line in section.splitlines() if line.startswith("| new | ")).endswith(
        "| %d |" % late.sum())
    assert "<h2>Rheology</h2>" in html and "| old | " not in section
    assert any(f.endswith("new_rheology.png") for f in rows["new"]["figures"])
    assert not any(f.endswith("_rheology.png") for f in rows["old"]["figures"])


def test_viscosity_parts_from_the_two_tensors(tmp_path):
    """viscosity = 6 (S^hyd_xz + S^el_xz) / (N gamma_dot) (kf_rheology): the parts are the two
    terms, they add up to the file's viscosity, and they exist only in simple shear."""
    frames = unknotting_trefoil_frames(4)
    n = frames.shape[1]
    shear = {"flow.flow_type": "shear", "flow.shear_rate": 2.0}
    path = write_case(tmp_path / "split.h5", frames, attrs=shear)
    k = np.arange(4, dtype=float)
    hyd, el = np.zeros((4, 3, 3)), np.zeros((4, 3, 3))
    hyd[:, 0, 2] = hyd[:, 2, 0] = 1.0 + k
    el[:, 0, 2] = el[:, 2, 0] = 0.25 * k
    with h5py.File(path, "a") as f:
        g = f["frames"].create_group("stresslet")
        g["hydrodynamic"], g["elastic"] = hyd, el
        g["viscosity"] = 6.0 * (1.0 + 1.25 * k) / (n * 2.0)
        g["psi1"] = g["psi2"] = np.zeros(4)
    s = io.read_case(path).stresslet
    assert np.allclose(s["viscosity_hydrodynamic"], 3.0 * (1.0 + k) / n, rtol=1e-15, atol=0)
    assert np.allclose(s["viscosity_elastic"], 0.75 * k / n, rtol=1e-15, atol=0)
    assert np.allclose(s["viscosity_hydrodynamic"] + s["viscosity_elastic"], s["viscosity"],
                       rtol=1e-15, atol=0)
    with h5py.File(path, "a") as f:
        f.attrs["flow.flow_type"] = "quiescent"
    assert not set(io.VISCOSITY_PARTS) & set(io.read_case(path).stresslet)
    plain = write_case(tmp_path / "plain.h5", frames, attrs=shear)
    add_stresslet(plain, 4)
    with h5py.File(plain, "a") as f:
        del f["frames/stresslet/elastic"]
    assert not set(io.VISCOSITY_PARTS) & set(io.read_case(plain).stresslet)


def test_comparison_reports_the_parts_only_when_every_case_has_them(tmp_path):
    frames = unknotting_trefoil_frames(6)
    shear = {"flow.flow_type": "shear", "flow.shear_rate": 1.0}
    with_parts = write_case(tmp_path / "a.h5", frames, attrs=shear)
    add_stresslet(with_parts, 6)
    without = write_case(tmp_path / "b.h5", frames)
    add_stresslet(without, 6)
    a, b = io.read_case(with_parts), io.read_case(without)
    assert rheology.case_series([a]) == rheology.SERIES + io.VISCOSITY_PARTS
    assert rheology.case_series([a, b]) == rheology.SERIES
    assert rheology.case_series([]) == rheology.SERIES
