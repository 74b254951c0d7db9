#!/usr/bin/env python3
"""Check the fallback runner's report for a .pf file whose tests must fail.

usage: check_failing_output.py <pf file> <command...>

Runs the command and requires: a non-zero exit status; the line after every comment line
"! expect-fail" of the .pf file reported as "<file>.pf:<line>:"; the line after a comment line
"! must-not-run" not reported;
one FAIL line per test that has an expect-fail line, one PASS line per other test; and the
closing line "<passed> passed, <failed> failed" with those counts.
"""
import os
import re
import subprocess
import sys


def main():
    pf_path, command = sys.argv[1], sys.argv[2:]
    fname = os.path.basename(pf_path)
    with open(pf_path, encoding="utf-8") as handle:
        lines = handle.read().split("\n")

    expect, forbid, tests = [], [], {}
    current = None
    for n, line in enumerate(lines, start=1):
        match = re.match(r"\s*(?:recursive\s+)?subroutine\s+(\w+)", line, re.IGNORECASE)
        if match and n > 1 and re.match(r"\s*@(mpi)?test", lines[n - 2], re.IGNORECASE):
            current = match.group(1)
            tests[current] = False
        mark = line.strip()
        if mark.startswith("! expect-fail"):
            expect.append(n + 1)
            tests[current] = True
        if mark.startswith("! must-not-run"):
            forbid.append(n + 1)

    proc = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True, check=False)
    out = proc.stdout
    print(out)
    problems = []
    if proc.returncode == 0:
        problems.append("exit status 0, expected non-zero")
    for n in expect:
        if f"{fname}:{n}:" not in out:
            problems.append(f"failure at {fname}:{n} not reported")
    for n in forbid:
        if f"{fname}:{n}:" in out:
            problems.append(f"{fname}:{n} ran after a failing assertion")
    for name, fails in tests.items():
        tag = "FAIL" if fails else "PASS"
        if not re.search(rf"^{tag} \S+::{name}(\[.*\])?$", out, re.MULTILINE):
            problems.append(f"no '{tag} ...::{name}' line")
    n_fail = sum(tests.values())
    n_pass = len(tests) - n_fail
    summary = f"{n_pass} passed, {n_fail} failed"
    if not re.search(rf"^{summary}$", out, re.MULTILINE):
        problems.append(f"closing line '{summary}' missing")
    for problem in problems:
        print("check_failing_output: " + problem)
    print(f"check_failing_output: {len(expect)} expected failures, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
