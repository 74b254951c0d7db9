"""docs/python-api.md: its example runs, and its API reference is the docstrings' (generated)."""

import re
from pathlib import Path

from knotflow import reference

PAGE = Path(__file__).resolve().parents[2] / "docs" / "python-api.md"


def test_example_runs(capsys):
    """Every ```python block of the page, in order, in one namespace (its asserts check it)."""
    blocks = re.findall(r"^```python\n(.*?)^```$", PAGE.read_text(encoding="utf-8"), flags=re.S | re.M)
    assert len(blocks) >= 5
    namespace: dict = {}
    for k, block in enumerate(blocks):
        exec(compile(block, f"{PAGE.name} block {k + 1}", "exec"), namespace)  # noqa: S102
    out = capsys.readouterr().out
    # what the comments promise
    assert "multipole L=2 lubrication\n" in out
    assert "&hydro: order = 9 is not allowed (an integer from 1 to 8)\n" in out


def test_reference_is_generated():
    page = PAGE.read_text(encoding="utf-8")
    assert page == reference.page_with_reference(page), \
        "docs/python-api.md: regenerate with python -m knotflow.reference docs/python-api.md"
