"""The API reference section of docs/python-api.md, generated from the docstrings.

    python -m knotflow.reference                       # prints the Markdown of the section
    python -m knotflow.reference docs/python-api.md    # writes it into the page

tools/tests_knotflow/test_docs_example.py checks that the page holds exactly this text between
its two markers.
"""

from __future__ import annotations

import inspect
import sys

import knotflow

BEGIN = "<!-- generated from the docstrings: python -m knotflow.reference (test_docs_example checks it) -->"
END = "<!-- end of the generated reference -->"


def entry(name: str, obj: object) -> str:
    """The Markdown of one public name: its signature and docstring."""
    if inspect.isclass(obj):
        head = f"### class `knotflow.{name}`"
        if not issubclass(obj, Exception):
            head = f"### class `knotflow.{name}{inspect.signature(obj)}`"
    else:
        head = f"### `knotflow.{name}{inspect.signature(obj)}`"  # type: ignore[arg-type]
    text = [head, "", inspect.cleandoc(obj.__doc__ or ""), ""]
    if inspect.isclass(obj) and not issubclass(obj, Exception):
        for meth, fn in vars(obj).items():
            if meth.startswith("_") or not (inspect.isfunction(fn) or isinstance(fn, property)):
                continue
            sig = "" if isinstance(fn, property) else str(inspect.signature(fn))
            text += [f"#### `{name}.{meth}{sig}`", "", inspect.cleandoc(fn.__doc__ or ""), ""]
    return "\n".join(text)


def reference() -> str:
    """The section's text between the markers (markers excluded)."""
    return "\n".join(entry(name, getattr(knotflow, name)) for name in knotflow.__all__)


def page_with_reference(page: str) -> str:
    """`page` (the text of docs/python-api.md) with the generated section between the markers."""
    head, rest = page.split(BEGIN + "\n", 1)
    _, tail = rest.split(END, 1)
    return head + BEGIN + "\n" + reference() + "\n" + END + tail


def main() -> None:
    if len(sys.argv) > 1:
        with open(sys.argv[1], encoding="utf-8") as f:
            page = f.read()
        with open(sys.argv[1], "w", encoding="utf-8") as f:
            f.write(page_with_reference(page))
    else:
        print(reference())


if __name__ == "__main__":
    main()
