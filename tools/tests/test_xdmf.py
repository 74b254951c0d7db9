"""XDMF beside a case file: structure (resolved here with h5py) and VTK's XDMF reader."""

import os
import xml.etree.ElementTree as ET

import analysis_fixture as fixture
import h5py
import numpy as np
import pytest

from knotflow_tools import cli, xdmf

from conftest import unknotting_trefoil_frames, write_case


def _resolve(item, root, base):
    """Value of a DataItem (XML, HDF, HyperSlab, Reference) of the files we write."""
    if item.get("Reference") == "XML":
        name = item.text.split('"')[1]
        target = [d for d in root.find("Domain").findall("DataItem") if d.get("Name") == name]
        assert len(target) == 1
        return _resolve(target[0], root, base)
    dims = [int(d) for d in item.get("Dimensions").split()]
    if item.get("ItemType") == "HyperSlab":
        sel, data = list(item)
        start, stride, count = np.array(sel.text.split(), dtype=int).reshape(3, -1)
        arr = _resolve(data, root, base)
        idx = tuple(slice(s, s + c * st, st) for s, st, c in zip(start, stride, count))
        return arr[idx].reshape(dims)
    if item.get("Format") == "XML":
        return np.array(item.text.split(), dtype=float).reshape(dims)
    assert item.get("Format") == "HDF"
    fname, path = item.text.strip().split(":")
    with h5py.File(os.path.join(base, fname), "r") as f:
        arr = f[path][()]
    assert list(arr.shape) == dims
    return arr


def test_xdmf_points_into_the_case_file(tmp_path):
    frames = unknotting_trefoil_frames(5)
    path = write_case(tmp_path / "c1.h5", frames, time=np.linspace(0, 8, 5))
    fixture.write_knots(path, [0, 2, 4], [0.0, 4.0, 8.0], [0.9, 0.5, 0.0],
                   np.zeros((3, 10)), ["3_1", "3_1", "0_1"], 10, 1)
    out = xdmf.write_xdmf(path)
    assert out == str(tmp_path / "c1.xdmf2")
    root = ET.parse(out).getroot()
    # no data copied: inline items are integer lists (connectivity, bead index, slab bounds)
    for item in root.iter("DataItem"):
        if item.get("Format") == "XML":
            assert item.get("NumberType") == "Int" and "." not in item.text
    assert root.get("Version") == "2.0"
    steps = root.find("Domain/Grid").findall("Grid")
    assert len(steps) == 5
    n = frames.shape[1]
    for k, g in enumerate(steps):
        assert float(g.find("Time").get("Value")) == 2.0 * k
        topo = g.find("Topology")
        assert topo.get("TopologyType") == "Polyline" and topo.get("NodesPerElement") == str(n)
        assert np.array_equal(_resolve(topo[0], root, str(tmp_path)),
                              np.arange(n).reshape(1, n))
        pts = _resolve(g.find("Geometry")[0], root, str(tmp_path))
        assert np.array_equal(pts, frames[k])
        att = {a.get("Name"): a for a in g.findall("Attribute")}
        assert att["bead"].get("Center") == "Node" and att["rg"].get("Center") == "Grid"
        assert {"a", "b", "c", "theta", "phi", "close_pairs", "time"} <= set(att)
        # k_f: the latest analysed frame at or before k (sample and hold)
        kf = _resolve(att["kf"][0], root, str(tmp_path))[0]
        assert kf == {0: 0.9, 1: 0.9, 2: 0.5, 3: 0.5, 4: 0.0}[k]
    with h5py.File(path, "r") as f:
        assert set(f) == {"frames", "checkpoint", "analysis"}   # the case file is untouched


def test_xdmf_without_analysis_and_partial_frames(tmp_path):
    frames = unknotting_trefoil_frames(4)
    path = write_case(tmp_path / "c2.h5", frames, observables=False)
    with h5py.File(path, "a") as f:
        f["checkpoint/nframes"][()] = 3            # a 4th frame written but not committed
    root = xdmf.build_xdmf(path).getroot()
    steps = root.find("Domain/Grid").findall("Grid")
    assert len(steps) == 3
    assert {a.get("Name") for a in steps[0].findall("Attribute")} == {"bead", "half", "time"}


def test_xdmf_command(tmp_path, capsys):
    path = write_case(tmp_path / "c3.h5", unknotting_trefoil_frames(3))
    assert cli.main_xdmf([str(path), "--out", str(tmp_path / "sub.xdmf")]) == 0
    assert capsys.readouterr().out.strip() == str(tmp_path / "sub.xdmf")
    assert cli.main_xdmf([str(tmp_path / "missing.h5")]) == 2
    assert "missing.h5" in capsys.readouterr().err


def test_xdmf_read_by_vtk(tmp_path):
    """VTK's XDMF reader (the one ParaView offers as 'Xdmf Reader'), an independent reader."""
    vtk_xdmf = pytest.importorskip("vtkmodules.vtkIOXdmf2",
                                   reason="vtk (pip install vtk) not installed: XDMF not "
                                          "read back by VTK")
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkLogger, vtkObject
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline as sddp
    vtkObject.GlobalWarningDisplayOff()
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    frames = unknotting_trefoil_frames(6)
    times = np.linspace(0.0, 5.0, 6)
    path = write_case(tmp_path / "v.h5", frames, time=times)
    fixture.write_knots(path, [0, 5], [0.0, 5.0], [0.8, 0.1], np.zeros((2, 10)), ["3_1", "0_1"],
                   10, 1)
    reader = vtk_xdmf.vtkXdmfReader()
    reader.SetFileName(xdmf.write_xdmf(path))
    reader.UpdateInformation()
    steps = reader.GetOutputInformation(0).Get(sddp.TIME_STEPS())
    assert np.allclose(steps, times)
    n = frames.shape[1]
    for k in (0, 3, 5):
        reader.UpdateTimeStep(steps[k])
        grid = reader.GetOutputDataObject(0)
        assert grid.GetNumberOfPoints() == n and grid.GetNumberOfCells() == 1
        assert grid.GetCellType(0) == 4 and grid.GetCell(0).GetNumberOfPoints() == n  # polyline
        assert np.allclose(vtk_to_numpy(grid.GetPoints().GetData()), frames[k])
        assert np.array_equal(vtk_to_numpy(grid.GetPointData().GetArray("bead")), np.arange(n))
        fd = grid.GetFieldData()
        assert vtk_to_numpy(fd.GetArray("time"))[0] == times[k]
        assert vtk_to_numpy(fd.GetArray("kf"))[0] == (0.1 if k == 5 else 0.8)
        assert fd.GetArray("rg") is not None and fd.GetArray("close_pairs") is not None


_PARAVIEW_SCRIPT = r"""
import json, sys
from paraview.simple import OpenDataFile
from paraview import servermanager as sm
r = OpenDataFile(sys.argv[1])          # the reader ParaView picks for the file name
out = {"reader": r.GetXMLName(), "steps": list(r.TimestepValues), "frames": []}
for t in out["steps"]:
    r.UpdatePipeline(t)
    d = sm.Fetch(r)
    if d.IsA("vtkMultiBlockDataSet"):
        d = d.GetBlock(0)
    fd = d.GetFieldData()
    out["frames"].append({
        "points": d.GetNumberOfPoints(), "cells": d.GetNumberOfCells(),
        "cell_type": d.GetCellType(0), "cell_points": d.GetCell(0).GetNumberOfPoints(),
        "xyz": [list(d.GetPoint(i)) for i in range(d.GetNumberOfPoints())],
        "bead_last": d.GetPointData().GetArray("bead").GetValue(d.GetNumberOfPoints() - 1),
        "kf": fd.GetArray("kf").GetValue(0), "rg": fd.GetArray("rg").GetValue(0)})
print("RESULT" + json.dumps(out))
"""


def _paraview_python():
    import shutil
    import subprocess
    for exe in ("pvpython", "/usr/bin/python3"):
        path = shutil.which(exe)
        if path and subprocess.run([path, "-c", "import paraview.simple"],
                                   capture_output=True).returncode == 0:
            return path
    return None


def test_xdmf_opened_by_paraview(tmp_path):
    """ParaView itself (pvpython, or Debian's python3-paraview) opens <case>.xdmf2."""
    import json
    import subprocess
    py = _paraview_python()
    if py is None:
        pytest.skip("ParaView's Python not found (Debian: apt-get install python3-paraview): "
                    "XDMF not opened by ParaView")
    frames = unknotting_trefoil_frames(3)
    path = write_case(tmp_path / "p.h5", frames, time=[0.0, 0.5, 1.0])
    fixture.write_knots(path, [0, 2], [0.0, 1.0], [0.75, 0.25], np.zeros((2, 10)), ["3_1", "0_1"],
                   10, 1)
    script = tmp_path / "pv.py"
    script.write_text(_PARAVIEW_SCRIPT)
    env = dict(os.environ, PYTHONPATH="", PYTHONNOUSERSITE="1")
    run = subprocess.run([py, str(script), xdmf.write_xdmf(path)], capture_output=True,
                         text=True, env=env, timeout=300)
    lines = [ln for ln in run.stdout.splitlines() if ln.startswith("RESULT")]
    assert run.returncode == 0 and lines, run.stderr[-2000:]
    out = json.loads(lines[0][6:])
    assert out["reader"] == "XdmfReader" and out["steps"] == [0.0, 0.5, 1.0]
    n = frames.shape[1]
    for k, fr in enumerate(out["frames"]):
        assert (fr["points"], fr["cells"], fr["cell_type"], fr["cell_points"]) == (n, 1, 4, n)
        assert np.allclose(fr["xyz"], frames[k]) and fr["bead_last"] == n - 1
        assert fr["kf"] == (0.25 if k == 2 else 0.75)
