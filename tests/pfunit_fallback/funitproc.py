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
accepts.  Anything else that looks like a directive is rejected with file:line and a reason,
and so is what real pFUnit 4.12 does not compile although a lenient preprocessor could:

  - an ``@assert...`` continued over several lines (pFUnit parses one line only);
  - a comment after an ``@assert...(...)`` (pFUnit then passes the line through unchanged);
  - an array where pFUnit takes a scalar: ``@assertTrue``, ``@assertFalse``, ``@assertIsNaN``,
    ``@assertIsFinite`` given an array section (``x(:)``, ``a(1:3, 2)``), an array constructor
    (``[a, b]``) or a name declared as an array in the procedure or the module, outside any
    function call.  Detected syntactically: an array made by a function (``abs(x)``) or held in
    a component (``s%values``) is not seen;
  - in a module that uses ``pfunit`` (which re-exports the ``mpi`` module): ``use mpi_f08``
    without ``only:``, an MPI name imported from ``mpi_f08`` without a rename, and a local
    entity or procedure named ``MPI_...`` / ``PMPI_...`` (the names ``mpi`` exports);
  - in a module that uses ``funit`` without ``only:``, a module entity or procedure named like
    one that module itself exports (FUNIT_EXPORTS: ``run``, ``initialize``, ...): real pFUnit
    4.12 stops with "Procedure 'run' at (1) is already defined".
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

# The highest rank of the (first) argument pFUnit 4.12's assertions take (AssertBasic:
# assertTrue_/assertTrue_1d_, assertFalse_/assertFalse_1d_; assertIsNaN and assertIsFinite
# for single and double precision scalars only).
MAX_RANK = {"asserttrue": 1, "assertfalse": 1, "assertisnan": 0, "assertisfinite": 0}
# The names module funit of pFUnit 4.12 declares public itself (src/funit/FUnit.F90); a module
# procedure or module variable of the same name in a module that does `use funit` without
# `only:` does not compile.
FUNIT_EXPORTS = ("run", "initialize", "generic_run", "finalize", "loadtests_interface", "stub")
IDENT_RE = re.compile(r"[A-Za-z]\w*")
DECL_RE = re.compile(
    r"^\s*(?:real|integer|logical|complex|character|double\s+precision|type\s*\(|class\s*\()"
    r"[^:]*::(.*)$", re.IGNORECASE)
PROC_START_RE = re.compile(
    r"^\s*(?:(?:recursive|impure|pure|elemental|non_recursive|module)\s+)*"
    r"(?:(?:real|integer|logical|complex|character|type\s*\([^)]*\))(?:\s*\([^)]*\))?\s+)?"
    r"(subroutine|function)\s+(\w+)", re.IGNORECASE)
USE_RE = re.compile(r"^\s*use\s*(?:,\s*\w+\s*)?(?:::)?\s*(\w+)\s*(,\s*only\s*:(.*))?$",
                    re.IGNORECASE)
MPI_NAME_RE = re.compile(r"^p?mpi_", re.IGNORECASE)

# Procedure names pFUnit's generated code reserves (see the project's PFUNIT.md).
RESERVED = {"cases", "suite", "t", "testparameter", "testparameters", "iparam", "icase"}
MAX_TEST_NAME = 40


class PfError(Exception):
    """A problem in a .pf file, reported as file:line: message."""


def code_chars(text):
    """(index, character, nesting depth in () and []) of every character outside quotes."""
    quote, depth = None, 0
    for i, ch in enumerate(text):
        if quote:
            if ch == quote:
                quote = None
        elif ch in ("'", '"'):
            quote = ch
        else:
            depth -= ch in ")]"
            yield i, ch, depth
            depth += ch in "(["


def split_comment(line):
    """Split a free-form line into (code, comment) at the first '!' outside quotes."""
    for i, ch, _ in code_chars(line):
        if ch == "!":
            return line[:i], line[i:]
    return line, ""


def split_top(text, sep=","):
    """Split at `sep` outside parentheses, brackets and quotes."""
    cuts = [i for i, ch, depth in code_chars(text) if ch == sep and depth == 0]
    return [text[a + 1:b] for a, b in zip([-1] + cuts, cuts + [len(text)])]


def top_colons(subscripts):
    """How many subscripts of a subscript list are ranges (hold a colon at their own level)."""
    return sum(any(ch == ":" and depth == 0 for _, ch, depth in code_chars(part))
               for part in split_top(subscripts))


def array_rank_at_top(expr, decls):
    """(rank, what) of the highest-rank array in `expr` outside any function call, found
    syntactically, or (0, None).

    `decls` maps the names declared in the procedure and the module (lower case) to their
    rank (0: scalar). An array section counts with its number of ranges (a name declared as a
    scalar takes a substring instead), an array constructor as rank 1, a name declared as an
    array with its rank. Whatever sits inside the arguments of a call (all(...), size(...)),
    an array made by a function and a component (s%values) are not seen.
    """
    expr = re.sub(r"'[^']*'|\"[^\"]*\"", "''", expr)
    best = (0, None)
    i, n = 0, len(expr)
    while i < n:
        if expr[i] == "[" or expr.startswith("(/", i):
            close = expr.find("]" if expr[i] == "[" else "/)", i)
            best = max(best, (1, "an array constructor"), key=lambda b: b[0])
            i = n if close < 0 else close + 1
            continue
        m = IDENT_RE.match(expr, i)
        if not m:
            i += 1                  # operators, literals, a grouping parenthesis: look inside
            continue
        name = m.group(0)
        j = m.end()
        while j < n and expr[j] == " ":
            j += 1
        paren = j < n and expr[j] == "("
        close = matching_paren(expr, j) if paren else j - 1
        if i > 0 and (expr[i - 1].isalnum() or expr[i - 1] in "_%."):
            # .and., a kind suffix, 1e5, a component (with its subscripts or arguments)
            i = close + 1 if paren and expr[i - 1] == "%" else m.end()
            continue
        component = expr[close + 1:close + 2] == "%"
        rank = decls.get(name.lower())
        if paren:
            ranges = top_colons(expr[j + 1:close])
            if ranges and rank != 0 and not component:
                what = f"the array section '{name}({expr[j + 1:close].strip()})'"
                best = max(best, (ranges, what), key=lambda b: b[0])
            i = close + 1           # an element, a substring or a call: its arguments are inside
            continue
        if rank and not component:
            best = max(best, (rank, f"the array '{name}' (rank {rank})"), key=lambda b: b[0])
        i = m.end()
    return best


def matching_paren(text, start):
    depth = 0
    for k in range(start, len(text)):
        if text[k] == "(":
            depth += 1
        elif text[k] == ")":
            depth -= 1
            if depth == 0:
                return k
    return len(text) - 1


def declared_names(statement):
    """{name: rank} for the entities a type declaration statement declares (lower case)."""
    m = DECL_RE.match(statement)
    if not m:
        return {}
    attrs = statement[:statement.index("::")]
    dim = re.search(r"\bdimension\s*\(", attrs, re.IGNORECASE)
    whole = len(split_top(attrs[dim.end():matching_paren(attrs, dim.end() - 1)])) if dim else 0
    names = {}
    for ent in split_top(m.group(1)):
        ent = ent.split("=", 1)[0].strip()
        e = IDENT_RE.match(ent)
        if not e:
            continue
        rest = ent[e.end():].lstrip()
        if rest.startswith("*"):                   # character(len) form: c*10
            rest = re.sub(r"^\*\s*(\(\*\)|\d+)", "", rest).lstrip()
        if rest.startswith("("):
            names[e.group(0).lower()] = len(split_top(rest[1:matching_paren(rest, 0)]))
        else:
            names[e.group(0).lower()] = whole
    return names


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
        module_decls, proc_decls = {}, {}   # name -> is an array
        mpi_names = []           # (line, name) of every declared entity and procedure
        module_entities = []     # (line, name) of module variables and procedures
        uses = []                # (line, module, only-list or None)
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
                last_code, last_comment = split_comment(line)
                last_code = last_code.rstrip()
                if last_code.endswith("&"):
                    raise self.error(lineno, "an @assert must be on one line: real pFUnit 4.12 "
                                             "does not join continuation lines")
                if not last_code.endswith(")"):
                    raise self.error(lineno, "assertion must end with ')'")
                if last_comment:
                    raise self.error(lineno, "no comment after an @assert...(...): real pFUnit "
                                             "4.12 then leaves the line as it is and it does "
                                             "not compile")
                args = last_code[last_code.index("(") + 1:-1]
                kind = astart.group(2).lower()
                if kind in MAX_RANK and args.strip():
                    rank, what = array_rank_at_top(split_top(args)[0],
                                                   {**module_decls, **proc_decls})
                    if rank > MAX_RANK[kind]:
                        takes = "a scalar" if MAX_RANK[kind] == 0 else "a scalar or a 1-D array"
                        raise self.error(lineno, f"@{astart.group(2)} takes {takes}, not {what} "
                                                 "(real pFUnit 4.12 has no such version; use "
                                                 "@assertTrue(all(...)))")
                code = ASSERT_START_RE.sub(lambda m: f"{m.group(1)}call {m.group(2)}(",
                                           last_code, count=1)
                location = f"location=SourceLocation('{self.fname}', {lineno})"
                sep = ", " if args.strip() else ""
                out.append(f"{code[:-1]}{sep}{location}); if (anyExceptions()) return")
                i += 1
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

            # Declarations (joined over continuation lines), procedures and use statements,
            # for the scalar and name-clash rules.
            statement, k = code, i
            while statement.rstrip().endswith("&") and k + 1 < len(lines):
                k += 1
                statement = statement.rstrip()[:-1] + " " + split_comment(lines[k])[0].lstrip().lstrip("&")
            proc = PROC_START_RE.match(statement)
            if proc and not re.match(r"^\s*end\b", statement, re.IGNORECASE):
                proc_decls = {}
                mpi_names.append((lineno, proc.group(2)))
                module_entities.append((lineno, proc.group(2)))
            names = declared_names(statement)
            if not seen_contains:
                module_entities.extend((lineno, n) for n in names)
            (proc_decls if seen_contains else module_decls).update(names)
            mpi_names.extend((lineno, n) for n in names)
            use = USE_RE.match(statement)
            if use:
                uses.append((lineno, use.group(1).lower(), use.group(3)))

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
        if any(module == "pfunit" for _, module, _ in uses):
            self._check_mpi_clashes(uses, mpi_names)
        if any(module == "funit" and only is None for _, module, only in uses):
            for lineno, name in module_entities:
                if name.lower() in FUNIT_EXPORTS:
                    raise self.error(lineno, f"'{name}' is a name module funit exports, and this "
                                             "module uses funit without 'only:': real pFUnit "
                                             f"4.12 stops with \"Procedure '{name}' is already "
                                             "defined\"; rename it")
        if self.module is None:
            raise self.error(1, "no 'module <name>' statement found")
        if not self.tests:
            raise self.error(1, "no @test or @mpitest found")
        self.lines_out = out

    def _check_mpi_clashes(self, uses, names):
        """Module pfunit re-exports module mpi: its MPI_* / PMPI_* names must not meet others."""
        why = ("real pFUnit's module pfunit re-exports module mpi, so the name would be "
               "ambiguous")
        for lineno, module, only in uses:
            if module != "mpi_f08":
                continue
            if only is None:
                raise self.error(lineno, f"'use mpi_f08' without 'only:' beside 'use pfunit': "
                                         f"{why}; import with renames "
                                         "(f08_comm => MPI_Comm)")
            for item in split_top(only):
                item = item.strip()
                local = item.split("=>", 1)[0].strip()
                if MPI_NAME_RE.match(local):
                    raise self.error(lineno, f"'{item}' imported from mpi_f08 beside "
                                             f"'use pfunit': {why}; rename it on import "
                                             f"(f08_{local.split('_', 1)[1].lower()} => {local})")
        for lineno, name in names:
            if MPI_NAME_RE.match(name):
                raise self.error(lineno, f"'{name}' is named like an MPI entity in a module "
                                         f"that uses pfunit: {why}")

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
