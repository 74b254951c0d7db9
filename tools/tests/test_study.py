"""knotflow-study: the Table 2 comparison and the slipknot scan on constructed inputs."""

from types import SimpleNamespace

import numpy as np

from knotflow_tools import study, study_reference, study_rows, study_slipknots


class _FakeCase:
    name = "A1.40"

    def __init__(self, mats, time):
        self.knot_matrices = mats
        self.time = np.asarray(time, dtype=float)


def _row(a, o, utk):
    return {"case": f"A{a}_or{o}", "A": a, "orientation": o, "unknot_then_knot": utk,
            "study_transition": study_reference.in_study(a, o), "kf0": 0.9, "final_kf": 1.0,
            "final_state": "knotted", "mode": "I", "events": []}


def test_study_table_marks_exactly_the_four_cases():
    assert study_reference.in_study(1.4, "b") and study_reference.in_study(2.1, "c")
    assert study_reference.in_study(2.2, "c") and study_reference.in_study(2.3, "c")
    assert not study_reference.in_study(1.4, "c") and not study_reference.in_study(2.2, "b")


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
    scan = study_slipknots.slipknot_scan(case, np.array([0.0, 18.0]), np.array([0.0, 0.0]))
    by_frame = {m["frame"]: m for m in scan}
    assert by_frame[5]["slipknot"] and by_frame[5]["knot_core"] == [10, 40]
    assert by_frame[5]["time"] == 10.0 and by_frame[5]["max_K"] == 1.0
    assert not by_frame[7]["slipknot"] and by_frame[7]["knot_core"] is None
    # the same matrix with a knotted whole chain is a knot, not a slipknot
    scan = study_slipknots.slipknot_scan(case, np.array([0.0, 18.0]), np.array([1.0, 1.0]))
    assert not any(m["slipknot"] for m in scan)


def test_history_counts_the_first_untying_of_a_trefoil():
    t = np.arange(6.0)
    kf = np.array([0.85, 0.5, 0.05, 0.5, 0.95, 0.97])
    # starting knotted: untied at t = 2, knotted again at t = 4
    assert study_rows.history(t, kf, knotted_at_start=True) == [("unknot", 2.0), ("knot", 4.0)]
    # the same series from an unknotted start: only the knotting
    assert study_rows.history(t, kf, knotted_at_start=False) == [("knot", 4.0)]
    # inside the band throughout: nothing happens
    assert study_rows.history(t[:2], kf[:2], knotted_at_start=True) == []


def test_confirmation_with_more_closures_replaces_the_screen(tmp_path):
    import json
    n = 30
    screen = np.full((n, n), np.nan)
    screen[np.triu_indices(n, 10)] = 0.0
    screen[3, 25] = 0.6                    # a noisy screening value above the threshold
    case = _FakeCase({4: screen}, np.arange(6) * 10.0)
    recomputed = np.where(np.isfinite(screen), 0.0, np.nan)
    recomputed[3, 25] = 0.35               # the same subchain with more closures
    doc = {"kf": 0.0, "closures": 1000, "knot_core": None,
           "matrix": [[None if np.isnan(v) else v for v in row] for row in recomputed]}
    with open(study_slipknots.confirm_path(str(tmp_path), "A1.40", 4), "w") as fh:
        json.dump(doc, fh)
    (m,) = study_slipknots.slipknot_scan(case, np.array([0.0, 50.0]), np.zeros(2), str(tmp_path))
    assert m["slipknot"] and m["max_K"] == 0.6
    assert m["recomputed_max_K"] == 0.35 and not m["recomputed_slipknot"]
    assert study_slipknots.slip_verdict(m) == study_slipknots.REJECTED and "confirmed_slipknot" not in m


def _cane(case, a, kf, status="finished"):
    t = np.arange(len(kf), dtype=float)
    return {"case": case, "A": a, "status": status, "t_reached": t[-1], "t_end": 2000.0,
            "_ana": SimpleNamespace(time=t, kf=np.asarray(kf, dtype=float))}


def test_ensemble_kf_series_puts_each_seeded_case_beside_its_rotations(tmp_path):
    rows = [_cane("A1.00", 1.0, [0.0, 0.1]), _cane("A1.40", 1.4, [0.0, 0.0]),
            _cane("A3.00", 3.0, [0.0, 0.8])]
    ensemble = [_cane("A3.00_s1", 3.0, [0.0, 1.0]), _cane("A1.00_s1", 1.0, [0.2, 0.3]),
                _cane("A3.00_s2", 3.0, [0.1], status="running")]
    panels = study.ensemble_kf_series(rows, ensemble)
    # one panel per A of the rotations, ascending; A = 1.4 has no rotation and no panel
    assert list(panels) == [1.0, 3.0]
    assert [s[0] for s in panels[1.0]] == ["A1.00 (seeded rotation)", "A1.00_s1"]
    assert [s[0] for s in panels[3.0]] == ["A3.00 (seeded rotation)", "A3.00_s1",
                                           "A3.00_s2 (running, t = 0 of 2000)"]
    # each series is its case's own k_f(t)
    assert panels[3.0][1][2].tolist() == [0.0, 1.0] and panels[1.0][1][1].tolist() == [0.0, 1.0]
    # without the sweep's cases the rotations stand alone; without rotations there is no figure
    assert [s[0] for s in study.ensemble_kf_series([], ensemble)[1.0]] == ["A1.00_s1"]
    assert study.plot_ensemble_kf(rows, [], str(tmp_path / "none.png")) is None
    path = study.plot_ensemble_kf(rows, ensemble, str(tmp_path / "e.png"))
    assert path == str(tmp_path / "e.png") and (tmp_path / "e.png").stat().st_size > 10000


def test_overlap_table_rounds_the_min_distance_down():
    # An overlap just below d = 1 must not print as 1 (rounding to nearest gave 1.0000 for
    # 0.99998); rounding down keeps the digits that are certain; an unrecorded one is '-'.
    def row(case, dist):
        return {"case": case, "status": "finished", "t_end": 1000.0, "t_reached": 1000.0,
                "overlap": {"source": "file", "overlap_episodes": 1, "overlap_mean_duration": 0.5,
                            "overlap_max_duration": 0.5, "max_overlapping_pairs": 1,
                            "min_distance": dist, "strand_passages": 0}}
    rows = [row("near", 0.999989), row("tiny", 1.0 - 1e-9), row("apart", 1.0213), row("none", -1.0)]
    cells = {line.split(" | ")[0].lstrip("| "): line.split(" | ")[6]
             for line in study.overlap_table(rows)[2:]}
    assert cells == {"near": "0.99998", "tiny": "0.99999", "apart": "1.02130", "none": "-"}
