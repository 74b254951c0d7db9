"""The constraints file pins every dependency, and an environment installed from it by
scripts/lib.sh has exactly those versions."""

import hashlib
import importlib.metadata as md
import os
import re
import sys

import pytest

try:
    import tomllib
except ModuleNotFoundError:                      # Python < 3.11
    tomllib = None

TOOLS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CONSTRAINTS = os.path.join(TOOLS, "constraints.txt")
PYPROJECT = os.path.join(TOOLS, "pyproject.toml")
STAMP = os.path.join(sys.prefix, "knotflow-tools.stamp")   # written by scripts/lib.sh


def _norm(name):
    return re.sub(r"[-_.]+", "-", name).lower()


def _pins():
    pins = {}
    with open(CONSTRAINTS, encoding="utf-8") as fh:
        for line in fh:
            line = line.split("#", 1)[0].strip()
            if line:
                m = re.fullmatch(r"([A-Za-z0-9_.-]+)==([A-Za-z0-9_.+!-]+)", line)
                assert m, f"constraints.txt: not 'name==version': {line!r}"
                pins[_norm(m.group(1))] = m.group(2)
    return pins


def test_every_dependency_is_pinned():
    if tomllib is None:
        pytest.skip("tomllib needs Python 3.11")
    with open(PYPROJECT, "rb") as fh:
        project = tomllib.load(fh)["project"]
    deps = list(project["dependencies"])
    for extra in project.get("optional-dependencies", {}).values():
        deps += extra
    names = {_norm(re.split(r"[<>=!~;\[ ]", d, maxsplit=1)[0]) for d in deps}
    assert names <= set(_pins()), f"not pinned in constraints.txt: {names - set(_pins())}"


def _digest():
    h = hashlib.sha256()
    for path in (PYPROJECT, CONSTRAINTS):
        with open(path, "rb") as fh:
            h.update(fh.read())
    return h.hexdigest()


def test_environment_matches_the_constraints():
    if not os.path.isfile(STAMP):
        pytest.skip(f"this environment ({sys.prefix}) was not installed by scripts/lib.sh "
                    "(no knotflow-tools.stamp): versions not compared with constraints.txt")
    with open(STAMP, encoding="utf-8") as fh:
        stamp = fh.read().split()
    assert stamp and stamp[0] == _digest(), (
        "tools/pyproject.toml or tools/constraints.txt changed since this environment was "
        "installed: run scripts/test.sh (or scripts/run.sh) again")
    wrong = {}
    for name, version in _pins().items():
        try:
            have = md.version(name)
        except md.PackageNotFoundError:
            have = None
        if have != version:
            wrong[name] = (have, version)
    assert not wrong, f"installed versions differ from constraints.txt (have, pinned): {wrong}"
