#!/usr/bin/env python3
"""The layering of knotflow's sources: no module cycle, no folder cycle.

Usage: check_layers.py SRC_DIR PY_PACKAGE_DIR... [--report]
       check_layers.py --self-test

Fortran (SRC_DIR, e.g. src/): every module (`module`, `submodule`) and program is read with
its `use` statements (comments and continuation lines handled; `.f90`, `.F90`, `.fypp`,
`.f90.in`). A module's folder is its file's directory below SRC_DIR; a `serial/` directory
holds build alternatives of its parent's modules and counts as its parent. The rule
(docs/architecture.md, "Layers"):

1. no module cycle (A uses B uses ... uses A);
2. the folders form layers: the graph "folder F uses folder G" (some module of F uses some
   module of G) has no cycle, in particular no folder pair depends both ways.

Each Python package (PY_PACKAGE_DIR, e.g. tools/src/knotflow_tools, tools/src/knotflow): every
import of a module of the package, at module level and inside functions, is an edge; rule 1 holds for it too.

A failure prints the offending chain of modules (for a folder cycle: each folder edge with one
module edge that makes it). The only exceptions are the folder edges listed in
FOLDER_EXCEPTIONS below, each with its reason; they are printed on every run. The script also
prints the library's depth: the number of modules on the longest chain of `use` through the
library (programs in app/ not counted). Exit status 0 when the rules hold, 1 otherwise.
"""

from __future__ import annotations

import ast
import re
import sys
from collections.abc import Iterable
from pathlib import Path

#: Folder edges (user folder, used folder) allowed for now; each is printed on every run.
#: Nothing else may be excepted: remove an entry when its cause is gone.
FOLDER_EXCEPTIONS: dict[tuple[str, str], str] = {}

FORTRAN_SUFFIXES = (".f90", ".F90", ".fypp", ".f90.in")
RE_MODULE = re.compile(r"^\s*module\s+(?!procedure\b|function\b|subroutine\b)(\w+)\s*$", re.I)
RE_SUBMODULE = re.compile(r"^\s*submodule\s*\(\s*(\w+)\s*(?::\s*(\w+))?\s*\)\s*(\w+)", re.I)
RE_PROGRAM = re.compile(r"^\s*program\s+(\w+)\s*$", re.I)
RE_USE = re.compile(r"^\s*use\b\s*(?:,\s*(intrinsic|non_intrinsic)\s*)?(?:::)?\s*(\w+)", re.I)


def strip_comment(line: str) -> str:
    """The line without its `!` comment (a `!` inside a quoted string is kept)."""
    quote = ""
    for i, ch in enumerate(line):
        if quote:
            if ch == quote:
                quote = ""
        elif ch in "'\"":
            quote = ch
        elif ch == "!":
            return line[:i]
    return line


def logical_lines(text: str) -> Iterable[str]:
    """Fortran statements: comments removed, `&` continuations joined, `;` split;
    preprocessor and fypp directive lines skipped."""
    pending = ""
    for raw in text.splitlines():
        if raw.lstrip().startswith(("#", "@:")):
            continue
        line = strip_comment(raw).rstrip()
        if pending:
            line = line.lstrip()
            if line.startswith("&"):
                line = line[1:]
        if line.endswith("&"):
            pending += line[:-1]
            continue
        yield from (pending + line).split(";")
        pending = ""
    if pending:
        yield pending


def folder_of(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root).parent.parts)
    if parts and parts[-1] == "serial":
        parts.pop()
    return "/".join(parts) or "."


def read_fortran(root: Path) -> tuple[dict[str, str], dict[str, set[str]], set[str]]:
    """(unit -> folder, unit -> units it uses (within the sources), program names)."""
    folder: dict[str, str] = {}
    uses: dict[str, set[str]] = {}
    programs: set[str] = set()
    files = sorted(p for p in root.rglob("*") if p.is_file() and p.name.endswith(FORTRAN_SUFFIXES))
    for path in files:
        unit = ""
        for stmt in logical_lines(path.read_text(encoding="utf-8", errors="replace")):
            m = RE_MODULE.match(stmt)
            s = RE_SUBMODULE.match(stmt)
            p = RE_PROGRAM.match(stmt)
            if m or p:
                unit = (m or p).group(1).lower()  # type: ignore[union-attr]
                if p:
                    programs.add(unit)
            elif s:
                unit = s.group(3).lower()
                uses.setdefault(unit, set()).add((s.group(2) or s.group(1)).lower())
            else:
                u = RE_USE.match(stmt)
                if u and unit and (u.group(1) or "").lower() != "intrinsic":
                    uses.setdefault(unit, set()).add(u.group(2).lower())
                continue
            f = folder_of(path, root)
            if unit in folder and folder[unit] != f:
                raise SystemExit(f"module {unit} is defined in two folders: {folder[unit]}, {f}")
            folder[unit] = f
            uses.setdefault(unit, set())
    # only units of the sources (intrinsic and library modules: hdf5, mpi_f08, ... left out)
    return folder, {u: {v for v in vs if v in folder and v != u} for u, vs in uses.items()}, programs


def read_python(pkg: Path) -> dict[str, set[str]]:
    """module -> modules of the package it imports (anywhere in the module)."""
    name = pkg.name
    modules = {p.stem for p in pkg.glob("*.py")}
    uses: dict[str, set[str]] = {}
    for path in sorted(pkg.glob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        deps: set[str] = set()
        for node in ast.walk(tree):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level == 1:
                    base = f"{name}.{base}" if base else name
                if base == name:  # from . import x, y
                    targets = [f"{name}.{a.name}" for a in node.names]
                else:
                    targets = [base]
            for t in targets:
                parts = t.split(".")
                if parts[0] == name and len(parts) > 1 and parts[1] in modules:
                    deps.add(parts[1])
        deps.discard(path.stem)
        uses[path.stem] = deps
    return uses


def find_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """One cycle, as a closed chain [a, b, ..., a], in each strongly connected part of the
    graph that has more than one node (Tarjan's algorithm, then a path back to the start)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    parts: list[list[str]] = []

    def strong(n: str) -> None:
        index[n] = low[n] = len(index)
        stack.append(n)
        on_stack.add(n)
        for m in sorted(graph.get(n, ())):
            if m not in index:
                strong(m)
                low[n] = min(low[n], low[m])
            elif m in on_stack:
                low[n] = min(low[n], index[m])
        if low[n] == index[n]:
            part: list[str] = []
            while True:
                m = stack.pop()
                on_stack.discard(m)
                part.append(m)
                if m == n:
                    break
            if len(part) > 1:
                parts.append(sorted(part))

    sys.setrecursionlimit(10000)
    for n in sorted(graph):
        if n not in index:
            strong(n)
    cycles = []
    for part in sorted(parts):
        members, start = set(part), part[0]
        # breadth-first from start back to start within the part: a shortest cycle through it
        previous: dict[str, str] = {}
        frontier, found = [start], ""
        while frontier and not found:
            following = []
            for n in frontier:
                for m in sorted(graph.get(n, ())):
                    if m == start:
                        found = n
                        break
                    if m in members and m not in previous:
                        previous[m] = n
                        following.append(m)
                if found:
                    break
            frontier = following
        chain = [start]
        n = found
        while n != start:
            chain.append(n)
            n = previous[n]
        cycles.append([start] + chain[1:][::-1] + [start])
    return cycles


def longest_chain(graph: dict[str, set[str]], nodes: set[str]) -> list[str]:
    """The longest chain of nodes (user first) within `nodes` of an acyclic graph."""
    best: dict[str, list[str]] = {}

    def chain(n: str) -> list[str]:
        if n not in best:
            tails = [chain(m) for m in sorted(graph.get(n, ())) if m in nodes]
            best[n] = [n] + max(tails, key=len, default=[])
        return best[n]

    return max((chain(n) for n in sorted(nodes)), key=len, default=[])


def self_test() -> int:
    """The checker on small made-up trees whose answer is known by construction: a clean
    three-layer tree passes with depth 3; a module cycle, a folder pair used both ways through
    acyclic modules, a three-folder cycle, a Python cycle through an import inside a function
    each fail and name their chain."""
    import contextlib
    import io
    import tempfile

    def run(files: dict[str, str]) -> tuple[int, str]:
        with tempfile.TemporaryDirectory() as tmp:
            root = Path(tmp)
            for name, text in files.items():
                (root / name).parent.mkdir(parents=True, exist_ok=True)
                (root / name).write_text(text, encoding="utf-8")
            (root / "pkg").mkdir(exist_ok=True)
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                rc = main([str(root / "src"), str(root / "pkg")])
            return rc, out.getvalue()

    def mod(name: str, *used: str) -> str:
        lines = [f"module {name}"] + [f"  use {u}, only: x ! use {name}" for u in used]
        return "\n".join(lines + ["  implicit none", f"end module {name}", ""])

    clean = {"src/a/m1.f90": mod("m1"), "src/b/m2.f90": mod("m2", "m1", "iso_fortran_env"),
             "src/c/m3.f90": mod("m3", "m2") + "module procedure foo\n",
             "src/b/serial/m4.f90": mod("m4", "m1"),
             "src/app/p.f90": "program p\n  use m3\nend program p\n",
             "pkg/x.py": "from . import y\n", "pkg/y.py": "import os\n"}
    cases = [
        ("clean", clean, 0, ["library depth: 3 modules: m3 (c) -> m2 (b) -> m1 (a)"]),
        ("module cycle", {**clean, "src/a/m1.f90": mod("m1", "m3")}, 1,
         ["FAIL: Fortran module cycle: m1 -> m3 -> m2 -> m1"]),
        ("folder pair", {**clean, "src/a/m5.f90": mod("m5", "m4")}, 1,
         ["FAIL: folders a and b use each other", "FAIL: folder cycle: a -> b -> a"]),
        ("folder cycle", {**clean, "src/a/m5.f90": mod("m5", "m3")}, 1,
         ["FAIL: folder cycle: a -> c -> b -> a", "a -> c: m5 uses m3"]),
        ("continued use", {**clean, "src/a/m1.f90": "module m1\n  use &\n    & m3\nend module\n"},
         1, ["FAIL: Fortran module cycle"]),
        ("python cycle", {**clean, "pkg/y.py": "def f():\n    from .x import g\n"}, 1,
         ["FAIL: Python import cycle in pkg: x -> y -> x"]),
    ]
    bad = 0
    for label, files, want_rc, wants in cases:
        rc, out = run(files)
        missing = [w for w in wants if w not in out]
        if rc != want_rc or missing:
            bad += 1
            print(f"self-test {label}: exit {rc} (want {want_rc}); missing {missing}\n{out}")
        else:
            print(f"self-test {label}: ok")
    return 1 if bad else 0


def main(argv: list[str]) -> int:
    if argv == ["--self-test"]:
        return self_test()
    args = [a for a in argv if not a.startswith("--")]
    if len(args) < 2:
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    src, packages = Path(args[0]), [Path(a) for a in args[1:]]
    report = "--report" in argv
    failed = False

    folder, uses, programs = read_fortran(src)
    cycles = find_cycles(uses)
    for cycle in cycles:
        failed = True
        print("FAIL: Fortran module cycle: " + " -> ".join(cycle))

    # folder graph, with one module edge as the witness of each folder edge
    witness: dict[tuple[str, str], tuple[str, str]] = {}
    for u in sorted(uses):
        for v in sorted(uses[u]):
            fu, fv = folder[u], folder[v]
            if fu != fv:
                witness.setdefault((fu, fv), (u, v))
    for edge, why in FOLDER_EXCEPTIONS.items():
        if edge in witness:
            u, v = witness[edge]
            print(f"EXCEPTION (temporary): folder {edge[0]} uses {edge[1]} ({u} uses {v}): {why}")
        else:
            print(f"note: the exception {edge[0]} -> {edge[1]} is no longer needed: remove it")
    folders: dict[str, set[str]] = {}
    for fu, fv in witness:
        if (fu, fv) not in FOLDER_EXCEPTIONS:
            folders.setdefault(fu, set()).add(fv)
    for (fu, fv) in sorted(witness):
        if fu < fv and (fv, fu) in witness:
            excepted = (fu, fv) in FOLDER_EXCEPTIONS or (fv, fu) in FOLDER_EXCEPTIONS
            if not excepted:
                failed = True
                a, b = witness[(fu, fv)], witness[(fv, fu)]
                print(f"FAIL: folders {fu} and {fv} use each other: "
                      f"{a[0]} ({fu}) uses {a[1]} ({fv}); {b[0]} ({fv}) uses {b[1]} ({fu})")
    for fcycle in find_cycles(folders):
        failed = True
        print("FAIL: folder cycle: " + " -> ".join(fcycle))
        for fu, fv in zip(fcycle, fcycle[1:]):
            u, v = witness[(fu, fv)]
            print(f"  {fu} -> {fv}: {u} uses {v}")

    if not cycles:
        library = {u for u in folder if u not in programs}
        chain = longest_chain(uses, library)
        print(f"library depth: {len(chain)} modules: " + " -> ".join(
            f"{m} ({folder[m]})" for m in chain))
    if report:
        print("folder dependencies (user -> used):")
        for fu, fv in sorted(witness):
            u, v = witness[(fu, fv)]
            print(f"  {fu} -> {fv}   (e.g. {u} uses {v})")

    for pkg in packages:
        pyuses = read_python(pkg)
        pcycles = find_cycles(pyuses)
        for pcycle in pcycles:
            failed = True
            print(f"FAIL: Python import cycle in {pkg.name}: " + " -> ".join(pcycle))
        if not pcycles:
            pchain = longest_chain(pyuses, set(pyuses))
            print(f"Python package {pkg.name} depth: {len(pchain)} modules: " + " -> ".join(pchain))

    print("architecture layers: " + ("FAILED" if failed else "ok"))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
