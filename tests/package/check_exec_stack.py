"""Fails when an ELF executable in the given directories asks for an executable stack.

    python3 check_exec_stack.py DIR [DIR ...]

The GNU_STACK program header of each executable (``readelf -lW``) must not carry the E flag.
gfortran gives a program an executable stack when an internal procedure that uses its host's
variables is passed as an argument (a trampoline is written on the stack); the linker then warns
"requires executable stack". Exit status 0 all clean, 1 some executable stack, 77 (skipped)
without readelf.
"""

import os
import shutil
import subprocess
import sys


def is_elf(path: str) -> bool:
    with open(path, "rb") as f:
        return f.read(4) == b"\x7fELF"


def stack_flags(readelf: str, path: str) -> str | None:
    """Flags of the GNU_STACK header ("RW", "RWE"), or None when it has none."""
    out = subprocess.run([readelf, "-lW", path], check=True, capture_output=True, text=True).stdout
    for line in out.splitlines():
        fields = line.split()
        if fields and fields[0] == "GNU_STACK":
            # Type Offset VirtAddr PhysAddr FileSiz MemSiz Flg Align: the flags sit between
            # MemSiz and Align and may be written with spaces ("RW ", "RWE").
            return "".join(fields[6:-1])
    return None


def main(dirs: list[str]) -> int:
    readelf = shutil.which("readelf")
    if readelf is None:
        print("SKIP: readelf not found (binutils); cannot inspect the stack flags")
        return 77
    checked, bad = 0, []
    for d in dirs:
        if not os.path.isdir(d):  # e.g. tests/mpi of a build without MPI
            continue
        for name in sorted(os.listdir(d)):
            path = os.path.join(d, name)
            if not (os.path.isfile(path) and os.access(path, os.X_OK) and is_elf(path)):
                continue
            flags = stack_flags(readelf, path)
            checked += 1
            if flags is None or "E" in flags:
                bad.append(f"{path}: GNU_STACK {flags or 'missing (executable by default)'}")
    if checked == 0:
        print(f"no executables found in {', '.join(dirs)}")
        return 1
    for b in bad:
        print(f"executable stack: {b}")
    print(f"{checked} executable(s) checked, {len(bad)} with an executable stack")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
