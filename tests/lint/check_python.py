"""ruff and mypy on the Python tools, with the configuration of tools/pyproject.toml.

    python3 check_python.py TOOLS_DIR CACHE_DIR

Runs `ruff check` and `mypy` in TOOLS_DIR with the interpreter running this script (the
project's environment, where scripts/lib.sh installs both with the tools' [test] extra).
Exit status 0 clean, 1 findings, 77 (skipped) when ruff or mypy is not installed.
"""

import importlib.util
import os
import subprocess
import sys


def main(tools: str, cache: str) -> int:
    missing = [m for m in ("ruff", "mypy") if importlib.util.find_spec(m) is None]
    if missing:
        print(f"SKIP: {' and '.join(missing)} not installed for {sys.executable} "
              "(scripts/lib.sh installs them: pip install -c tools/constraints.txt -e 'tools[test]')")
        return 77
    status = 0
    for cmd in ([sys.executable, "-m", "ruff", "check", "--cache-dir", os.path.join(cache, "ruff"), "."],
                [sys.executable, "-m", "mypy", "--cache-dir", os.path.join(cache, "mypy")]):
        print("$", " ".join(cmd[1:]), flush=True)
        status |= subprocess.run(cmd, cwd=tools, check=False).returncode != 0
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
