"""The tools' environment made by scripts/lib.sh (build/venv) takes nothing from the system's
site-packages: a package of the base Python (Debian's python3-matplotlib 3.6.3, installed for the
scheduler jobs) shadowed the pinned one there (its mpl_toolkits.mplot3d imported
matplotlib.tri.triangulation, which the pinned matplotlib no longer has: '3d' was no valid
projection and knotflow-report failed)."""

import os
import sys

import pytest

STAMP = os.path.join(sys.prefix, "knotflow-tools.stamp")   # written by scripts/lib.sh


def _lib_sh_venv():
    if sys.prefix == sys.base_prefix or not os.path.isfile(STAMP):
        pytest.skip(f"{sys.prefix} is not a virtual environment made by scripts/lib.sh")


def _inside(path, root):
    path, root = os.path.realpath(path), os.path.realpath(root)
    return path == root or path.startswith(root + os.sep)


def test_pyvenv_cfg_excludes_system_site_packages():
    _lib_sh_venv()
    with open(os.path.join(sys.prefix, "pyvenv.cfg"), encoding="utf-8") as fh:
        cfg = {k.strip().lower(): v.strip().lower()
               for k, _, v in (line.partition("=") for line in fh) if k.strip()}
    assert cfg.get("include-system-site-packages") == "false", cfg


def test_no_site_directory_outside_the_venv():
    _lib_sh_venv()
    foreign = [p for p in sys.path
               if os.path.basename(os.path.normpath(p)) in ("site-packages", "dist-packages")
               and not _inside(p, sys.prefix)]
    assert not foreign, f"sys.path holds site directories of another Python: {foreign}"


def test_matplotlib_3d_from_the_venv():
    _lib_sh_venv()
    import matplotlib
    import mpl_toolkits.mplot3d
    from matplotlib.projections import get_projection_class

    for mod in (matplotlib, mpl_toolkits.mplot3d):
        assert _inside(mod.__file__, sys.prefix), f"{mod.__name__} from {mod.__file__}"
    assert get_projection_class("3d") is mpl_toolkits.mplot3d.Axes3D
