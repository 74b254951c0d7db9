"""Transition detection from k_f(t) with hysteresis (shared conventions).

State 'knotted' when k_f > high, 'unknotted' when k_f < low, unchanged in between.  The initial
state is that of the first frame outside the band; events are the state changes: 'unknot' at the
first frame where a knotted state turns unknotted, 'knot' the reverse.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

LOW = 0.1
HIGH = 0.9


@dataclass
class Event:
    """One state change."""

    kind: str        # 'unknot' or 'knot'
    index: int       # position in the k_f series
    time: float


def states(kf, low: float = LOW, high: float = HIGH) -> list:
    """Hysteresis state per frame: 'knotted', 'unknotted' or None before the first decision."""
    out = []
    state = None
    for v in np.asarray(kf, dtype=float):
        if v > high:
            state = "knotted"
        elif v < low:
            state = "unknotted"
        out.append(state)
    return out


def detect_events(kf, time=None, low: float = LOW, high: float = HIGH) -> list:
    """Events of the k_f series (time defaults to the index)."""
    if not low < high:
        raise ValueError("need low < high")
    kf = np.asarray(kf, dtype=float)
    time = np.arange(len(kf), dtype=float) if time is None else np.asarray(time, dtype=float)
    events = []
    prev = None
    for k, st in enumerate(states(kf, low, high)):
        if prev is not None and st != prev:
            events.append(Event("unknot" if st == "unknotted" else "knot", k, float(time[k])))
        prev = st
    return events


def final_state(kf, low: float = LOW, high: float = HIGH):
    """State after the last frame ('knotted', 'unknotted' or None)."""
    st = states(kf, low, high)
    return st[-1] if st else None


def unknot_then_knot(events) -> bool:
    """True if an 'unknot' event is followed (later) by a 'knot' event."""
    seen_unknot = False
    for ev in events:
        if ev.kind == "unknot":
            seen_unknot = True
        elif ev.kind == "knot" and seen_unknot:
            return True
    return False
