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


def chain_forces(positions: npt.ArrayLike, bond_length: float = 1.0, springs: bool = True,
                 spring_k: float = 500.0, bending: bool = True, bending_a: float = 2.2,
                 excluded_volume: bool = False, ev_strength: float = 100.0, ev_range: float = 1.0,
                 external_force: npt.ArrayLike = (0.0, 0.0, 0.0)) -> tuple[np.ndarray, float]:
    """The force on each bead (N x 3) and the potential energy of the chain at ``positions``.

    The terms and parameters are the &forces group's (PHYSICS.md section 2; the defaults here
    are its defaults): springs U = (k/2) sum (l_i - l0)^2, bending U = (A/(2 l0)) sum beta_i^2,
    the soft excluded volume U = (ev_strength/2)(ev_range - r)^2 for |i - j| > 1, and the same
    external force on every bead (not in the energy). The library validates the values as the
    scene does.
    """
    r = positions_array(positions)
    ext = np.array(external_force, dtype=np.float64).reshape(-1)
    if ext.shape != (3,):
        raise KnotflowError(f"external_force = {external_force!r}: expected 3 numbers")
    values = {name: c_double_value(v, name) for name, v in
              {"bond_length": bond_length, "spring_k": spring_k, "bending_a": bending_a,
               "ev_strength": ev_strength, "ev_range": ev_range}.items()}
    f = np.empty_like(r)
    energy = ctypes.c_double()
    buf = message_buffer()
    check(library().knotflow_chain_forces(
        len(r), r, values["bond_length"], int(bool(springs)), values["spring_k"], int(bool(bending)),
        values["bending_a"], int(bool(excluded_volume)), values["ev_strength"], values["ev_range"],
        np.ascontiguousarray(ext), f, ctypes.byref(energy), buf, MESSAGE_LENGTH), buf)
    return f, energy.value
