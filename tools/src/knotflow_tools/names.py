"""The case-name rule: a case name (a case file's ``case_name`` attribute, a ledger's case) is
data, never a path. Output names are derived only from names that pass it; others are refused.

The same rule as the scene's (src/scene/kf_scene_output.f90: case_name_problem): letters,
digits and ``_ . - +`` only, the first a letter, a digit or ``_`` (no hidden name, no ``.`` or
``..``, no option-like ``-x``), at most :data:`CASE_NAME_MAX_LEN` characters. Both are tested
against the same list of names, tests/data/case_names.txt.
"""

from __future__ import annotations

import string

#: Characters a case name may hold.
CASE_NAME_CHARACTERS = frozenset(string.ascii_letters + string.digits + "_.-+")
#: Characters a case name may start with.
CASE_NAME_FIRST = frozenset(string.ascii_letters + string.digits + "_")
#: Longest case name.
CASE_NAME_MAX_LEN = 100


def case_name_problem(name: str) -> str | None:
    """What is wrong with ``name`` by the rule (the words of the Fortran rule), None if nothing."""
    if not name:
        return "an empty name"
    if len(name) > CASE_NAME_MAX_LEN:
        return f"longer than {CASE_NAME_MAX_LEN} characters"
    if name[0] not in CASE_NAME_FIRST:
        return f"it starts with '{name[0]}'"
    for k, c in enumerate(name, start=1):
        if c not in CASE_NAME_CHARACTERS:
            return f"the character {c!r} at position {k}"
    return None


def check_case_name(name: str, where: str) -> str:
    """``name`` if it passes the rule, else a ValueError naming ``where`` it came from."""
    problem = case_name_problem(name)
    if problem is not None:
        raise ValueError(f"{where}: case name {name!r} refused ({problem}; a case name has letters, "
                         f"digits and _ . - + only, starts with a letter, a digit or _ and has at "
                         f"most {CASE_NAME_MAX_LEN} characters)")
    return name
