"""XDMF description of a case file, for ParaView and VisIt.

The XDMF file (``<case>.xdmf2``, XDMF 2 as read by ParaView's "Xdmf Reader" and VisIt's Xdmf
plugin) is plain XML written beside the case file.  The suffix ``.xdmf2`` makes ParaView open
it with its "Xdmf Reader" without asking: ParaView's Xdmf3 readers (5.11) do not read
``HyperSlab`` items (they abort or return no points).  It copies no data: every time step
is a hyperslab of ``/frames/positions`` (one frame, all beads) and every per-frame value a
one-element hyperslab of its ``/frames/...`` dataset, read from the case file by the viewer.
Only the fixed integer lists (the polyline connectivity and the bead index) are written inline.

Per time step (``Time`` = ``/frames/time[k]``):

- topology: one polyline through the N beads (``Polyline``, N nodes per element, 1 element);
- geometry: ``XYZ``, the hyperslab ``/frames/positions[k, :, :]``;
- point data: ``bead`` (0-based index, int32) and ``half`` (0 for the first half of the chain,
  1 for the second: the colouring of the report's figures);
- field data (``Center="Grid"``, one value per step): ``time``, every ``/frames/observables/*``
  and ``/frames/diagnostics/*`` dataset present (and ``viscosity``, ``psi1``, ``psi2`` of
  ``/frames/stresslet``), and, when ``/analysis/knots`` exists, ``kf``:
  k_f of the latest analysed frame at or before k (absent before the first analysed frame).
"""

from __future__ import annotations

import io
import os
import xml.etree.ElementTree as ET

import h5py
import numpy as np

from .atomic import write_bytes
from .io import check_declared_size, check_regular_file, checkpoint_frames

XDMF_SUFFIX = ".xdmf2"

# numpy dtype kind + size -> (XDMF NumberType, Precision)
_NUMBER_TYPES = {("f", 8): ("Float", "8"), ("f", 4): ("Float", "4"),
                 ("i", 4): ("Int", "4"), ("i", 8): ("Int", "8"),
                 ("u", 4): ("UInt", "4"), ("u", 8): ("UInt", "8")}


def xdmf_path(case_path) -> str:
    """The XDMF file written beside a case file: ``<case>.xdmf2`` (``.h5`` replaced)."""
    base = str(case_path)
    for ext in (".h5", ".hdf5"):
        if base.endswith(ext):
            base = base[: -len(ext)]
            break
    return base + XDMF_SUFFIX


def _number_type(dtype):
    key = (np.dtype(dtype).kind, np.dtype(dtype).itemsize)
    if key not in _NUMBER_TYPES:
        raise ValueError(f"no XDMF number type for dtype {dtype}")
    return _NUMBER_TYPES[key]


def _inline(parent, values, dims, number_type="Int", precision="4"):
    item = ET.SubElement(parent, "DataItem", Dimensions=dims, NumberType=number_type,
                         Precision=precision, Format="XML")
    item.text = " ".join(str(int(v)) for v in values)
    return item


def _ref(parent, name):
    """A reference to the named top-level DataItem of the Domain."""
    item = ET.SubElement(parent, "DataItem", Reference="XML")
    item.text = f'/Xdmf/Domain/DataItem[@Name="{name}"]'
    return item


def _hdf(parent, href, ds):
    nt, prec = _number_type(ds.dtype)
    item = ET.SubElement(parent, "DataItem", Dimensions=" ".join(str(s) for s in ds.shape),
                         NumberType=nt, Precision=prec, Format="HDF")
    item.text = f"{href}:{ds.name}"
    return item


def _slab(parent, href, ds, start, count, dims):
    """A HyperSlab item: ``ds[start : start + count]`` (stride 1), reshaped to ``dims``."""
    item = ET.SubElement(parent, "DataItem", ItemType="HyperSlab", Dimensions=dims,
                         Type="HyperSlab")
    rank = len(ds.shape)
    sel = ET.SubElement(item, "DataItem", Dimensions=f"3 {rank}", NumberType="Int",
                        Precision="8", Format="XML")
    sel.text = " ".join(str(int(v)) for v in (*start, *([1] * rank), *count))
    _hdf(item, href, ds)
    return item


def _frame_count(f) -> int:
    """Frames the file holds completely (as ``io.read_case``: time, positions, checkpoint)."""
    fr = f["frames"]
    n = min(fr["time"].shape[0], fr["positions"].shape[0])
    counted = checkpoint_frames(f)
    if counted is not None:
        n = min(n, counted)
    return n


def _per_frame_datasets(f, nframes) -> list:
    """(name, dataset) of the 1-D numeric per-frame datasets (observables, diagnostics, the
    stresslet's viscosity, psi1, psi2)."""
    out = []
    for group in ("observables", "diagnostics", "stresslet"):
        g = f["frames"].get(group)
        if g is None:
            continue
        for name in sorted(g):
            ds = g[name]
            if (isinstance(ds, h5py.Dataset) and ds.ndim == 1 and ds.shape[0] >= nframes
                    and (np.dtype(ds.dtype).kind, np.dtype(ds.dtype).itemsize) in _NUMBER_TYPES):
                out.append((name, ds))
    return out


def _kf_index(f, nframes):
    """For each frame, the row of /analysis/knots/kf of the latest analysed frame at or before
    it (-1 before the first), or None when the file has no usable /analysis/knots."""
    g = f.get("analysis/knots")
    if g is None or "kf" not in g or "frame_index" not in g:
        return None
    fi = np.asarray(g["frame_index"][()], dtype=np.int64)
    if fi.ndim != 1 or len(fi) == 0 or len(fi) != g["kf"].shape[0]:
        return None
    order = np.argsort(fi, kind="stable")
    pos = np.searchsorted(fi[order], np.arange(nframes), side="right") - 1
    return np.where(pos >= 0, order[np.maximum(pos, 0)], -1)


def build_xdmf(case_path, out_path=None) -> ET.ElementTree:
    """The XDMF tree of a case file (see the module docstring); hrefs are relative to
    ``out_path`` (default: the file beside the case)."""
    case_path = os.path.abspath(str(case_path))
    out_path = os.path.abspath(out_path or xdmf_path(case_path))
    href = os.path.relpath(case_path, os.path.dirname(out_path))
    root = ET.Element("Xdmf", Version="2.0")
    domain = ET.SubElement(root, "Domain")
    check_regular_file(case_path, "case file")
    with h5py.File(case_path, "r") as f:
        pos = f["frames/positions"]
        if pos.ndim != 3 or pos.shape[2] != 3:
            raise ValueError(f"{case_path}: /frames/positions has shape {pos.shape}, "
                             "expected (frames, beads, 3)")
        check_declared_size(case_path, pos, whole=False)
        check_declared_size(case_path, f["frames/time"])
        nframes = _frame_count(f)
        nbeads = pos.shape[1]
        times = np.asarray(f["frames/time"][:nframes], dtype=float)
        name = f.attrs.get("case_name", os.path.basename(case_path))
        name = (name.decode() if isinstance(name, bytes) else str(name)).strip()
        tseries = _per_frame_datasets(f, nframes)
        kf_rows = _kf_index(f, nframes)
        kf_ds = f["analysis/knots/kf"] if kf_rows is not None else None
        beads = np.arange(nbeads)
        half = (beads >= nbeads // 2).astype(int)
        # the fixed lists once, referenced from every step
        for iname, values, dims in (("connectivity", beads, f"1 {nbeads}"),
                                    ("bead", beads, str(nbeads)), ("half", half, str(nbeads))):
            _inline(domain, values, dims).set("Name", iname)
        coll = ET.SubElement(domain, "Grid", Name=name, GridType="Collection",
                             CollectionType="Temporal")
        for k in range(nframes):
            grid = ET.SubElement(coll, "Grid", Name=f"frame_{k}", GridType="Uniform")
            ET.SubElement(grid, "Time", Value=repr(float(times[k])))
            topo = ET.SubElement(grid, "Topology", TopologyType="Polyline",
                                 NodesPerElement=str(nbeads), NumberOfElements="1")
            _ref(topo, "connectivity")
            geo = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
            _slab(geo, href, pos, (k, 0, 0), (1, nbeads, 3), f"{nbeads} 3")
            for aname in ("bead", "half"):
                att = ET.SubElement(grid, "Attribute", Name=aname, AttributeType="Scalar",
                                    Center="Node", Dimensions=str(nbeads))
                _ref(att, aname)
            att = ET.SubElement(grid, "Attribute", Name="time", AttributeType="Scalar",
                                Center="Grid")
            _slab(att, href, f["frames/time"], (k,), (1,), "1")
            for dname, ds in tseries:
                att = ET.SubElement(grid, "Attribute", Name=dname, AttributeType="Scalar",
                                    Center="Grid")
                _slab(att, href, ds, (k,), (1,), "1")
            if kf_rows is not None and kf_rows[k] >= 0:
                att = ET.SubElement(grid, "Attribute", Name="kf", AttributeType="Scalar",
                                    Center="Grid")
                _slab(att, href, kf_ds, (int(kf_rows[k]),), (1,), "1")
    ET.indent(root, space=" ")
    return ET.ElementTree(root)


def write_xdmf(case_path, out_path=None) -> str:
    """Write the XDMF file of a case file (default: beside it, ``<case>.xdmf2``); returns its
    path.  Re-run it after the case file gained frames or /analysis."""
    out_path = out_path or xdmf_path(case_path)
    tree = build_xdmf(case_path, out_path)
    buf = io.BytesIO()
    buf.write(b'<?xml version="1.0" encoding="utf-8"?>\n')
    buf.write(b'<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>\n')
    tree.write(buf, encoding="utf-8", xml_declaration=False)
    buf.write(b"\n")
    write_bytes(out_path, buf.getvalue())
    return str(out_path)


