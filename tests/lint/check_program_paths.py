"""Every program path the scripts and documents name is one the build makes.

Scripts and pages reach the programs as <build directory>/bin/<program> (scripts/lib.sh:
$KF_BUILD_DIR/bin). This check fails on a path under a build directory that is not in bin/
(build/knotflow, build/src/app/knotflow-analyze: layouts of older builds) and on a program
name under bin/ that the build in BIN_DIR does not have.
Usage: check_program_paths.py SOURCE_DIR BIN_DIR
"""
import os
import re
import sys

root, bindir = sys.argv[1], sys.argv[2]
BUILD = r"(?:\$KF_BUILD_DIR|\$\{KF_BUILD_DIR\}|\$\{?KNOTFLOW_BUILD_DIR\}?|\bbuild(?:-[a-z]+)?)"
IN_BIN = re.compile(BUILD + r"/bin/(knotflow[A-Za-z0-9_-]*)")
ELSEWHERE = re.compile(BUILD + r"/(?!bin/|venv/|lib/|tests/|docs/|Testing/)"
                       r"(?:[A-Za-z0-9_.-]+/)*(knotflow[A-Za-z0-9_-]*)\b(?![./])")


def sources():
    for sub in ("scripts", "docs", "tests/jobs", "tests/regression"):
        top = os.path.join(root, sub)
        for dirpath, _, names in os.walk(top):
            for name in names:
                if name.endswith((".sh", ".md", ".py")) and "ledger" not in dirpath:
                    yield os.path.join(dirpath, name)
    for name in ("README.md", "tools/README.md"):
        yield os.path.join(root, name)


def main() -> int:
    programs = set(os.listdir(bindir))
    bad = []
    for path in sources():
        with open(path, encoding="utf-8", errors="replace") as fh:
            for k, line in enumerate(fh, 1):
                for m in IN_BIN.finditer(line):
                    if m.group(1) not in programs:
                        bad.append(f"{path}:{k}: {m.group(0)}: no program {m.group(1)} in {bindir}")
                for m in ELSEWHERE.finditer(line):
                    bad.append(f"{path}:{k}: {m.group(0)}: programs are in <build>/bin/")
    for b in bad:
        print(b)
    print(f"{len(bad)} bad program path(s); programs in {bindir}: {len(programs)}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
