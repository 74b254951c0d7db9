"""What the reference study states, each number with where it is stated: the trefoils of its
Table 2 and its candy-cane findings (knotflow-study compares the runs with these)."""

from __future__ import annotations

#: Table 2 of the reference study: the cases whose k_f went unknotted and then knotted again.
#: Every other case of the table had no such transition.
STUDY_TRANSITIONS = {("b", 1.4), ("c", 2.1), ("c", 2.2), ("c", 2.3)}

#: The study's Table 2: 29 simulations, with 13 unknot-then-knot events in 4 of them (the four
#: cases of STUDY_TRANSITIONS) -- as issue 11 quotes the study.
STUDY_TREFOIL_CASES, STUDY_REKNOT_EVENTS, STUDY_REKNOT_SIMULATIONS = 29, 13, 4

#: The study reports tumbling (mode II) for its stiff candy-canes, and no mode for the stiff
#: trefoils (A >= 2.2) of Table 2: the trefoil comparison counts ours and names that gap.
STUDY_STIFF_A, STUDY_STIFF_MODE = 2.2, "not reported (tumbling is reported for stiff candy-canes)"

#: The study's candy-canes (docs/REPRODUCTION.md, "Candy-cane, RPY + EV", "What does not"):
#: A = 1 coils and rolls about the vorticity axis (mode I), A = 3 stays open and tumbles (mode II);
#: about 4 times more close pairs at A = 1 than at A = 3; a slipknot found at A = 1.4 and one
#: described visually at A = 3; whole-chain k_f about 0 (the summary table). The mode at A = 1.4
#: and the close-pair numbers per A are not stated there.
STUDY_CANDYCANE_A = (1.0, 1.4, 3.0)
STUDY_CANDYCANE_MODES = {1.0: "I", 3.0: "II"}
STUDY_CLOSE_PAIR_RATIO = "about 4"
STUDY_SLIPKNOT_A = {1.4}
STUDY_VISUAL_SLIPKNOT_A = {3.0}
STUDY_WHOLE_KF = "about 0"


def case_key(a, o):
    """(orientation, A) as a key that does not depend on how A was written."""
    return (str(o), round(float(a), 6))


def in_study(a, o) -> bool:
    """Did the study see an unknot-then-knot transition in case (A, orientation)?"""
    return any(case_key(a, o) == case_key(sa, so) for so, sa in STUDY_TRANSITIONS)
