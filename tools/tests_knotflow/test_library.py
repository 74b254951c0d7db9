"""Where the package finds the shared library, and what it says when it cannot."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

import knotflow
from knotflow import _library

SOURCE = Path(__file__).resolve().parents[1] / "src"


def test_search_order(monkeypatch, tmp_path):
    monkeypatch.setenv(_library.LIBRARY_ENV, str(tmp_path / "x.so"))
    paths = _library.candidate_paths()
    package = Path(_library.__file__).resolve().parent
    assert paths == [tmp_path / "x.so", package / _library.LIBRARY_FILE,
                     Path(sys.prefix) / "lib" / "knotflow" / _library.LIBRARY_FILE,
                     package.parents[2] / "build" / "lib" / _library.LIBRARY_FILE]
    monkeypatch.delenv(_library.LIBRARY_ENV)
    assert _library.candidate_paths() == paths[1:]


def test_not_found_names_every_place(monkeypatch, tmp_path):
    missing = [tmp_path / "a" / _library.LIBRARY_FILE, tmp_path / "b" / _library.LIBRARY_FILE]
    monkeypatch.setattr(_library, "candidate_paths", lambda: missing)
    monkeypatch.setattr(_library, "_loaded", None)
    with pytest.raises(knotflow.KnotflowError, match="shared library was not found") as err:
        _library.library()
    assert all(str(p) in str(err.value) for p in missing)


def test_found_without_environment():
    """As after the README set-up: no KNOTFLOW_LIBRARY, no LD_LIBRARY_PATH. The package must
    load this build's library (ctest gives its path in KNOTFLOW_LIBRARY): scripts/build.sh
    links it into the environment (or the checkout's build/lib has it)."""
    expected = os.environ.get(_library.LIBRARY_ENV)
    assert expected, "run by ctest (python_knotflow), which names this build's library"
    env = {k: v for k, v in os.environ.items() if k not in (_library.LIBRARY_ENV, "LD_LIBRARY_PATH")}
    env["PYTHONPATH"] = str(SOURCE)
    code = ("import knotflow, knotflow._library as L; "
            "print(L.loaded_path().resolve()); print(knotflow.mobility([[0, 0, 0], [2, 0, 0]]).shape)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=False)
    assert done.returncode == 0, done.stderr
    path, shape = done.stdout.split("\n")[:2]
    assert Path(path) == Path(expected).resolve()
    assert shape == "(6, 6)"
