"""knotflow-study: the Table 2 comparison and the slipknot scan on constructed inputs."""

import numpy as np

from knotflow_tools import study


class _FakeCase:
    def __init__(self, mats, time):
        self.knot_matrices = mats
        self.time = np.asarray(time, dtype=float)


def _row(a, o, utk):
    return {"case": f"A{a}_or{o}", "A": a, "orientation": o, "unknot_then_knot": utk,
            "study_transition": study._in_study(a, o), "kf0": 0.9, "final_kf": 1.0,
            "final_state": "knotted", "mode": "I", "events": []}


def test_study_table_marks_exactly_the_four_cases():
    assert study._in_study(1.4, "b") and study._in_study(2.1, "c")
    assert study._in_study(2.2, "c") and study._in_study(2.3, "c")
    assert not study._in_study(1.4, "c") and not study._in_study(2.2, "b")


def test_agreement_counts_matches_and_bolds_differences():
    rows = [_row(1.4, "b", True), _row(1.4, "c", False), _row(2.2, "c", False), _row(3.0, "a", True)]
    lines, agree, total = study.trefoil_tables(rows)
    assert (agree, total) == (2, 4)
    text = "\n".join(lines)
    assert "**- / U->K**" in text          # (c, 2.2): the study has one, we do not
    assert "**U->K / -**" in text          # (a, 3): we have one, the study does not


def test_slipknot_scan_finds_core_and_flags_slipknot():
    n = 60
    mat = np.full((n, n), np.nan)
    iu = np.triu_indices(n, 10)
    mat[iu] = 0.0
    # subchains containing beads 10..40 are knotted (K = 1), except the whole chain (0, 59)
    for i, j in zip(*iu):
        if i <= 10 and j >= 40 and not (i == 0 and j == n - 1):
            mat[i, j] = 1.0
    case = _FakeCase({5: mat, 7: np.where(np.isfinite(mat), 0.0, np.nan)}, np.arange(10) * 2.0)
    scan = study.slipknot_scan(case, np.array([0.0, 18.0]), np.array([0.0, 0.0]))
    by_frame = {m["frame"]: m for m in scan}
    assert by_frame[5]["slipknot"] and by_frame[5]["knot_core"] == [10, 40]
    assert by_frame[5]["time"] == 10.0 and by_frame[5]["max_K"] == 1.0
    assert not by_frame[7]["slipknot"] and by_frame[7]["knot_core"] is None
    # the same matrix with a knotted whole chain is a knot, not a slipknot
    scan = study.slipknot_scan(case, np.array([0.0, 18.0]), np.array([1.0, 1.0]))
    assert not any(m["slipknot"] for m in scan)
