#!/usr/bin/env python3
"""Fallback pFUnit 4 preprocessor for knotflow (Python 3, standard library only).

Two sub-commands:

  funitproc.py preprocess <file.pf> <out.F90>
      Copy the test module through, turning directive lines (@test, @mpitest, @before, @after,
      @disable) into comments and each ``@assertX(args)`` on line n into
      ``call assertX(args, location=SourceLocation('file.pf', n)); if (anyExceptions()) return``
      (on the assertion's last line, so that line numbers stay those of the .pf file; a
      ``# 1 "file.pf"`` marker makes compiler messages point at the .pf file).

  funitproc.py driver [--mpi [--np <n>]] --name <exe> -o <driver.F90> <file.pf>...
      Write the program that runs every test of the given files (one PASS/FAIL line per test,
      failures with file:line, expected and actual values, then ``N passed, N failed``; it
      stops with code 2 when anything failed).

The accepted syntax is the subset described in tests/README.md, which real pFUnit 4 also
accepts.  Anything else that looks like a directive is rejected with file:line and a reason.
"""

import argparse
import os
import re
import sys

DIRECTIVE_RE = re.compile(r"^(\s*)@(\w+)\s*(\((.*)\))?\s*(!.*)?$")
ASSERT_START_RE = re.compile(r"^(\s*)@(assert\w+)\s*\(", re.IGNORECASE)
MODULE_RE = re.compile(r"^\s*module\s+(\w+)\s*(!.*)?$", re.IGNORECASE)
SUBROUTINE_RE = re.compile(
    r"^\s*(?:(?:recursive|impure|pure|elemental|non_recursive|module)\s+)*"
    r"subroutine\s+(\w+)\s*(\(([^)]*)\))?", re.IGNORECASE)
PRIVATE_RE = re.compile(r"^\s*private\s*(!.*)?$", re.IGNORECASE)

# Procedure names pFUnit's generated code reserves (see the project's PFUNIT.md).
RESERVED = {"cases", "suite", "t", "testparameter", "testparameters", "iparam", "icase"}
MAX_TEST_NAME = 40


class PfError(Exception):
    """A problem in a .pf file, reported as file:line: message."""


def split_comment(line):
    """Split a free-form line into (code, comment) at the first '!' outside quotes."""
    quote = None
    for i, ch in enumerate(line):
        if quote:
            if ch == quote:
                quote = None
        elif ch in ("'", '"'):
            quote = ch
        elif ch == "!":
            return line[:i], line[i:]
    return line, ""


def is_blank_or_comment(line):
    return split_comment(line)[0].strip() == ""


def parse_options(text):
    """Parse directive options such as 'npes=[1,2], ifdef=NAME' or 'disable'."""
    opts = {}
    if not text:
        return opts
    npes = re.search(r"npes\s*=\s*\[([^\]]*)\]", text, re.IGNORECASE)
    if npes:
        try:
            opts["npes"] = [int(v) for v in npes.group(1).split(",") if v.strip()]
        except ValueError:
            raise PfError("npes must be a list of integers, e.g. npes=[1,2]")
        text = text[:npes.start()] + text[npes.end():]
    for item in text.split(","):
        item = item.strip()
        if not item:
            continue
        if "=" in item:
            key, value = (s.strip() for s in item.split("=", 1))
            opts[key.lower()] = value
        else:
            opts[item.lower()] = True
    return opts


class PfFile:
    """What the driver needs from one .pf file."""

    def __init__(self, path):
        self.path = path
        self.fname = os.path.basename(path)
        self.base = os.path.splitext(self.fname)[0]
        self.module = None
        self.tests = []          # dicts: name, kind, npes, ifdef, ifndef, disabled, line
        self.before = None       # (name, takes_this)
        self.after = None
        self.private_default = False
        self.lines_out = []
        self._parse()

    def error(self, lineno, msg):
        return PfError(f"{self.path}:{lineno}: {msg}")

    def _parse(self):
        with open(self.path, encoding="utf-8") as handle:
            lines = handle.read().split("\n")
        if lines and lines[-1] == "":
            lines.pop()

        out = [f'# 1 "{os.path.abspath(self.path)}"']
        pending = None           # (directive, options, line) waiting for its subroutine
        disable_next = False
        in_type = 0
        seen_contains = False
        i = 0
        while i < len(lines):
            line = lines[i]
            lineno = i + 1
            code = split_comment(line)[0]

            astart = ASSERT_START_RE.match(line)
            if astart:
                # Gather continuation lines (comment-only lines may sit in between).
                j = i
                while split_comment(lines[j])[0].rstrip().endswith("&"):
                    j += 1
                    while j < len(lines) and is_blank_or_comment(lines[j]):
                        j += 1
                    if j >= len(lines):
                        raise self.error(lineno, "assertion continued past the end of file")
                block = lines[i:j + 1]
                block[0] = ASSERT_START_RE.sub(
                    lambda m: f"{m.group(1)}call {m.group(2)}(", block[0], count=1)
                last_code, last_comment = split_comment(block[-1])
                last_code = last_code.rstrip()
                if not last_code.endswith(")"):
                    raise self.error(j + 1, "assertion must end with ')'")
                location = f"location=SourceLocation('{self.fname}', {lineno})"
                joined = " ".join(split_comment(b)[0] for b in block)
                inner = joined[joined.index("(") + 1:joined.rindex(")")]
                sep = ", " if inner.strip() else ""
                block[-1] = (f"{last_code[:-1]}{sep}{location}); if (anyExceptions()) return"
                             + (f" {last_comment}" if last_comment else ""))
                out.extend(block)
                i = j + 1
                continue

            directive = DIRECTIVE_RE.match(line)
            if directive:
                name = directive.group(2).lower()
                if name not in ("test", "mpitest", "before", "after", "disable"):
                    raise self.error(lineno, f"unsupported directive '@{directive.group(2)}' "
                                             "(the fallback runner knows @test, @mpitest, "
                                             "@before, @after, @disable and @assert...)")
                if pending:
                    raise self.error(lineno, f"directive follows '@{pending[0]}' of line "
                                             f"{pending[2]} without a subroutine in between")
                try:
                    opts = parse_options(directive.group(4))
                except PfError as exc:
                    raise self.error(lineno, str(exc))
                if name == "disable":
                    disable_next = True
                else:
                    pending = (name, opts, lineno)
                out.append(directive.group(1) + "!" + line.lstrip())
                i += 1
                continue

            if code.lstrip().startswith("@"):
                raise self.error(lineno, "malformed directive line")

            if pending and code.strip():
                sub = SUBROUTINE_RE.match(code)
                if not sub:
                    raise self.error(lineno, f"'@{pending[0]}' (line {pending[2]}) must be "
                                             "followed by a subroutine statement")
                self._register(pending, sub, lineno, disable_next)
                pending = None
                disable_next = False

            mod = MODULE_RE.match(code)
            if mod and mod.group(1).lower() != "procedure" and self.module is None:
                self.module = mod.group(1)
                if self.module.lower() != self.base.lower():
                    raise self.error(lineno, f"module '{self.module}' must be named like the "
                                             f"file ('{self.base}'), as pFUnit requires")
            stripped = code.strip().lower()
            if re.match(r"^type\b(?!\s*\()", stripped) and not stripped.startswith("type is"):
                in_type += 1
            elif re.match(r"^end\s*type\b", stripped):
                in_type = max(0, in_type - 1)
            elif stripped == "contains" and in_type == 0:
                seen_contains = True
            if PRIVATE_RE.match(code) and in_type == 0 and not seen_contains:
                self.private_default = True

            out.append(line)
            i += 1

        if pending:
            raise self.error(pending[2], f"'@{pending[0]}' is not followed by a subroutine")
        if self.module is None:
            raise self.error(1, "no 'module <name>' statement found")
        if not self.tests:
            raise self.error(1, "no @test or @mpitest found")
        self.lines_out = out

    def _register(self, pending, sub, lineno, disabled):
        kind, opts, dline = pending
        name = sub.group(1)
        args = (sub.group(3) or "").strip()
        if name.lower() in RESERVED:
            raise self.error(lineno, f"procedure name '{name}' is reserved by pFUnit")
        if kind in ("before", "after"):
            if getattr(self, kind) is not None:
                raise self.error(dline, f"more than one @{kind} in this module")
            setattr(self, kind, (name, bool(args)))
            return
        if len(name) > MAX_TEST_NAME:
            raise self.error(lineno, f"test name '{name}' is longer than {MAX_TEST_NAME} "
                                     "characters")
        if kind == "test" and args:
            raise self.error(lineno, f"@test procedure '{name}' must take no arguments "
                                     "(MPI tests use @mpitest)")
        if kind == "mpitest":
            if not args:
                raise self.error(lineno, f"@mpitest procedure '{name}' must take 'this'")
            if "npes" not in opts or not opts["npes"]:
                raise self.error(dline, "@mpitest needs npes=[...]")
            if any(n < 1 for n in opts["npes"]):
                raise self.error(dline, "npes values must be positive")
        if "disable" in opts:
            disabled = True
        self.tests.append(dict(name=name, kind=kind, npes=opts.get("npes", []),
                               ifdef=opts.get("ifdef"), ifndef=opts.get("ifndef"),
                               disabled=disabled, line=lineno))


def write_if_changed(path, text):
    """Write text unless the file already holds it; then only refresh its time stamp, so
    that the build tool sees the output as up to date."""
    if os.path.exists(path):
        with open(path, encoding="utf-8") as handle:
            if handle.read() == text:
                os.utime(path, None)
                return
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w", encoding="utf-8") as handle:
        handle.write(text)


def cmd_preprocess(pf_path, out_path):
    pf = PfFile(pf_path)
    if pf.private_default:
        print(f"funitproc: note: {pf_path}: module is private by default; tests and "
              "@before/@after procedures must be public (pFUnit needs that too)",
              file=sys.stderr)
    write_if_changed(out_path, "\n".join(pf.lines_out) + "\n")


def fstr(text):
    """A Fortran character literal."""
    return "'" + text.replace("'", "''") + "'"


def cmd_driver(name, out_path, pf_paths, mpi, np_max=None):
    pfs = [PfFile(p) for p in pf_paths]
    modules = [pf.module.lower() for pf in pfs]
    if len(set(modules)) != len(modules):
        raise PfError("the same test module appears twice in one test executable")
    uses, body = [], []
    for k, pf in enumerate(pfs, start=1):
        aliases = []
        before = after = None
        if pf.before:
            before = f"pf{k}_before"
            aliases.append(f"{before} => {pf.before[0]}")
        if pf.after:
            after = f"pf{k}_after"
            aliases.append(f"{after} => {pf.after[0]}")
        for t, test in enumerate(pf.tests, start=1):
            alias = f"pf{k}_t{t}"
            aliases.append(f"{alias} => {test['name']}")
            if np_max and any(n > np_max for n in test["npes"]):
                raise PfError(f"{pf.path}:{test['line']}: {test['name']} asks for npes="
                              f"{test['npes']} but the test runs on {np_max} processes "
                              "(raise MPI_PES)")
            if test["kind"] == "mpitest" and not mpi:
                raise PfError(f"{pf.path}:{test['line']}: @mpitest needs an MPI test "
                              "(register it with MPI_PES <n>)")
            guard_open, guard_close = [], []
            if test["ifdef"]:
                guard_open.append(f"#ifdef {test['ifdef']}")
                guard_close.insert(0, "#endif")
            if test["ifndef"]:
                guard_open.append(f"#ifndef {test['ifndef']}")
                guard_close.insert(0, "#endif")
            body.extend(guard_open)
            suite, tname = fstr(pf.module), fstr(test["name"])
            if test["disabled"]:
                body.append(f"  ! {test['name']} is disabled (@disable)")
            elif not mpi:
                args = [suite, tname, alias]
                if before:
                    args.append(f"setup={before}")
                if after:
                    args.append(f"teardown={after}")
                body.append(f"  call funit_run_test({', '.join(args)})")
            else:
                fix = []
                for role, alias_f, info in (("setup", before, pf.before),
                                            ("teardown", after, pf.after)):
                    if alias_f:
                        takes_this = info[1]
                        fix.append(f"{role}{'' if takes_this else '_plain'}={alias_f}")
                if test["kind"] == "mpitest":
                    npes = ", ".join(str(n) for n in test["npes"])
                    args = [suite, tname, alias, f"[{npes}]"] + fix
                    body.append(f"  call pfunit_run_mpi_test({', '.join(args)})")
                else:
                    fix = [f for f in fix if "_plain=" in f]
                    args = [suite, tname, alias] + fix
                    body.append(f"  call pfunit_run_serial_test({', '.join(args)})")
            body.extend(guard_close)
        uses.append(f"  use {pf.module}, only: " + ", &\n      ".join(aliases))

    prog = re.sub(r"\W", "_", name)
    if not re.match(r"[A-Za-z]", prog):
        prog = "t_" + prog
    lines = [f"! Generated by tests/pfunit_fallback/funitproc.py for test '{name}': do not edit.",
             f"program {prog}_driver"]
    if mpi:
        lines.append("  use pfunit, only: pfunit_mpi_init, pfunit_mpi_finalize, "
                     "pfunit_run_mpi_test, pfunit_run_serial_test")
    else:
        lines.append("  use funit, only: funit_run_test, funit_summary, funit_counts")
    lines += uses
    lines.append("  implicit none")
    if mpi:
        lines += ["  logical :: failed", "", "  call pfunit_mpi_init()"]
        lines += body
        lines += ["  call pfunit_mpi_finalize(failed)", "  if (failed) stop 2"]
    else:
        lines += ["  integer :: n_passed, n_failed", ""]
        lines += body
        lines += ["  call funit_summary()", "  call funit_counts(n_passed, n_failed)",
                  "  if (n_failed > 0) stop 2"]
    lines.append(f"end program {prog}_driver")
    write_if_changed(out_path, "\n".join(lines) + "\n")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    pre = sub.add_parser("preprocess", help="turn one .pf file into a .F90 file")
    pre.add_argument("pf")
    pre.add_argument("out")
    drv = sub.add_parser("driver", help="write the driver program for a set of .pf files")
    drv.add_argument("--mpi", action="store_true", help="MPI driver (uses module pfunit)")
    drv.add_argument("--name", required=True, help="test (executable) name")
    drv.add_argument("--np", type=int, default=None,
                     help="number of MPI processes the test is run with (checks npes)")
    drv.add_argument("-o", "--output", required=True)
    drv.add_argument("pf", nargs="+")
    args = parser.parse_args(argv)
    try:
        if args.command == "preprocess":
            cmd_preprocess(args.pf, args.out)
        else:
            cmd_driver(args.name, args.output, args.pf, args.mpi, args.np)
    except PfError as exc:
        print(f"funitproc: error: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:
        print(f"funitproc: error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
