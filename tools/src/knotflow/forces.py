"""Chain forces (src/capi/kf_capi_forces): springs, bending, excluded volume, external force."""

from __future__ import annotations

import ctypes

import numpy as np
import numpy.typing as npt

from knotflow._library import (
    MESSAGE_LENGTH,
    KnotflowError,
    c_double_value,
    check,
    library,
    message_buffer,
    positions_array,
)


def forces_defaults() -> dict[str, bool | float]:
    """The &forces group's defaults (the library's): springs, spring_k, bending, bending_a,
    excluded_volume, ev_strength, ev_range."""
    springs, bending, ev = ctypes.c_int(), ctypes.c_int(), ctypes.c_int()
    k, a, strength, rng = ctypes.c_double(), ctypes.c_double(), ctypes.c_double(), ctypes.c_double()
    library().knotflow_forces_defaults(ctypes.byref(springs), ctypes.byref(k), ctypes.byref(bending),
                                       ctypes.byref(a), ctypes.byref(ev), ctypes.byref(strength),
                                       ctypes.byref(rng))
    return {"springs": bool(springs.value), "spring_k": k.value, "bending": bool(bending.value),
            "bending_a": a.value, "excluded_volume": bool(ev.value), "ev_strength": strength.value,
            "ev_range": rng.value}


def chain_forces(positions: npt.ArrayLike, bond_length: float = 1.0, springs: bool | None = None,
                 spring_k: float | None = None, bending: bool | None = None, bending_a: float | None = None,
                 excluded_volume: bool | None = None, ev_strength: float | None = None,
                 ev_range: float | None = None,
                 external_force: npt.ArrayLike = (0.0, 0.0, 0.0)) -> tuple[np.ndarray, float]:
    """The force on each bead (N x 3) and the potential energy of the chain at ``positions``.

    The terms and parameters are the &forces group's (PHYSICS.md section 2); an argument left at
    None takes the group's default (:func:`forces_defaults`): springs U = (k/2) sum (l_i - l0)^2
    with l0 = ``bond_length``, bending U = (A/(2 l0)) sum beta_i^2, the soft excluded volume
    U = (ev_strength/2)(ev_range - r)^2 for |i - j| > 1, and the same external force on every
    bead (not in the energy). The library validates the values as it validates a scene's.
    """
    r = positions_array(positions)
    ext = np.array(external_force, dtype=np.float64).reshape(-1)
    if ext.shape != (3,):
        raise KnotflowError(f"external_force = {external_force!r}: expected 3 numbers")
    given = {"springs": springs, "spring_k": spring_k, "bending": bending, "bending_a": bending_a,
             "excluded_volume": excluded_volume, "ev_strength": ev_strength, "ev_range": ev_range}
    p = forces_defaults()
    p.update({k: v for k, v in given.items() if v is not None})
    v = {name: c_double_value(p[name], name) for name in ("spring_k", "bending_a", "ev_strength", "ev_range")}
    l0 = c_double_value(bond_length, "bond_length")
    f = np.empty_like(r)
    energy = ctypes.c_double()
    buf = message_buffer()
    check(library().knotflow_chain_forces(
        len(r), r, l0, int(bool(p["springs"])), v["spring_k"], int(bool(p["bending"])), v["bending_a"],
        int(bool(p["excluded_volume"])), v["ev_strength"], v["ev_range"], np.ascontiguousarray(ext), f,
        ctypes.byref(energy), buf, MESSAGE_LENGTH), buf)
    return f, energy.value
