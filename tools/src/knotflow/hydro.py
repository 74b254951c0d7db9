"""Hydrodynamic models: mobility, velocities, strain disturbance and stresslet (src/capi/kf_capi_hydro).

Units of PHYSICS.md: bead diameter 1, an isolated bead has mobility 1/3 (force unit
pi eta d^2 gamma_dot, time unit 1/gamma_dot).
"""

from __future__ import annotations

import ctypes
from types import TracebackType

import numpy as np
import numpy.typing as npt

from knotflow._library import (
    MESSAGE_LENGTH,
    KnotflowError,
    c_double_value,
    c_int_value,
    check,
    defaults,
    library,
    like_positions,
    message_buffer,
    names,
    positions_array,
    tensor_array,
)

#: The simple shear v0 = (z, 0, 0): its velocity gradient and rate of strain.
SHEAR_GRADIENT = ((0.0, 0.0, 1.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
SHEAR_STRAIN = ((0.0, 0.0, 0.5), (0.0, 0.0, 0.0), (0.5, 0.0, 0.0))


def model_names() -> tuple[str, ...]:
    """The hydrodynamic models the library knows (the &hydro group's names)."""
    return names(1)


def overlap_rules() -> tuple[str, ...]:
    """The overlap rules the library knows (&hydro overlap)."""
    return names(2)


class Model:
    """A hydrodynamic model of the library, built once and used for many configurations.

    Args:
        model: one of :func:`model_names` (``'none'``, ``'rpy'``, ``'multipole'``).
        order: multipole order L (1..8; at most 6 with lubrication).
        lubrication: the two-sphere lubrication corrections (multipole).
        eps_lub: the shift of overlapping pairs (the overlap rule evaluates a pair with r <= 1 at
            1 + eps_lub), 0 < eps_lub < 0.5; None: knotflow-mobility's
            default (:func:`default_eps_lub`).
        overlap: the overlap rule (one of :func:`overlap_rules`; only ``'pair'`` for none/rpy).
        overlap_time: the ``'relax'`` rule's time; None: the &hydro default.

    The values are checked by the library (the &hydro group's validation); a refused one raises
    :class:`KnotflowError` with its message. The model holds a factorisation: one Model must not
    be used by two threads at once; different Models may (the library keeps no global state
    and the calls release the GIL). Free it with :meth:`close` (or a ``with`` block); it is also
    freed when garbage-collected. ``last_seconds`` is the library's own wall time of the last
    :meth:`mobility` call.
    """

    def __init__(self, model: str = "multipole", order: int = 2, lubrication: bool = True,
                 eps_lub: float | None = None, overlap: str = "pair",
                 overlap_time: float | None = None) -> None:
        self._handle = ctypes.c_void_p()
        self.last_seconds = 0.0
        if not isinstance(model, str):
            raise KnotflowError(f"model = {model!r}: expected a name (one of {', '.join(model_names())})")
        if not isinstance(overlap, str):
            raise KnotflowError(f"overlap = {overlap!r}: expected a name "
                                f"(one of {', '.join(overlap_rules())})")
        lmax = c_int_value(order, "order")
        eps = defaults()[2] if eps_lub is None else c_double_value(eps_lub, "eps_lub")
        otime = defaults()[3] if overlap_time is None else c_double_value(overlap_time, "overlap_time")
        name_b, rule_b = model.encode(), overlap.encode()
        buf = message_buffer()
        status = library().knotflow_model_create(
            name_b, len(name_b), lmax, int(bool(lubrication)), eps, rule_b, len(rule_b), otime,
            ctypes.byref(self._handle), buf, MESSAGE_LENGTH)
        check(status, buf)

    def close(self) -> None:
        """Free the library's model (idempotent)."""
        if getattr(self, "_handle", None) is not None and self._handle.value:
            library().knotflow_model_free(ctypes.byref(self._handle))

    def __del__(self) -> None:
        # at interpreter exit the module's globals may be gone already: the process frees all
        try:
            self.close()
        except Exception:
            pass

    def __enter__(self) -> Model:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()

    def _live(self) -> ctypes.c_void_p:
        if not self._handle.value:
            raise KnotflowError("the model was closed")
        return self._handle

    @property
    def label(self) -> str:
        """The library's description of the model, e.g. ``'multipole L=2 lubrication'``."""
        buf = message_buffer()
        check(library().knotflow_model_label(self._live(), buf, MESSAGE_LENGTH), buf)
        return buf.value.decode()

    def mobility(self, positions: npt.ArrayLike) -> np.ndarray:
        """The 3N x 3N translational mobility of torque-free beads at ``positions`` (N x 3).

        Element [3i + a, 3j + b] is velocity component a of bead i per force component b on
        bead j (0-based); equal to ``knotflow-mobility --output mobility``.
        """
        r = positions_array(positions)
        n = len(r)
        mu = np.empty((3 * n, 3 * n), order="F")
        seconds = ctypes.c_double()
        buf = message_buffer()
        check(library().knotflow_model_mobility(self._live(), n, r, mu, ctypes.byref(seconds), buf,
                                                MESSAGE_LENGTH), buf)
        self.last_seconds = seconds.value
        return mu

    def velocities(self, positions: npt.ArrayLike, forces: npt.ArrayLike,
                   gradient: npt.ArrayLike = SHEAR_GRADIENT) -> np.ndarray:
        """Bead velocities (N x 3): G r + mu F + C:E in the linear flow v0 = G r.

        ``gradient`` is the traceless velocity gradient G[i, j] = d v0_i / d r_j (default: the
        simple shear v0 = (z, 0, 0)); E is its symmetric part. These are knotflow's equations
        of motion for the given forces, with the model's overlap rule.
        """
        r = positions_array(positions)
        f = like_positions(forces, len(r), "forces")
        g = tensor_array(gradient, "gradient")
        u = np.empty_like(r)
        buf = message_buffer()
        check(library().knotflow_model_velocities(self._live(), len(r), r, f, g, u, buf, MESSAGE_LENGTH), buf)
        return u

    def disturbance(self, positions: npt.ArrayLike, strain: npt.ArrayLike = SHEAR_STRAIN) -> np.ndarray:
        """C:E (N x 3): the velocities of force-free, torque-free beads minus the ambient flow.

        ``strain``: the symmetric traceless rate of strain E (default: that of the simple shear,
        as ``knotflow-mobility --output shear``).
        """
        r = positions_array(positions)
        e = tensor_array(strain, "strain")
        u = np.empty_like(r)
        buf = message_buffer()
        check(library().knotflow_model_disturbance(self._live(), len(r), r, e, u, buf, MESSAGE_LENGTH), buf)
        return u

    def stresslet(self, positions: npt.ArrayLike, forces: npt.ArrayLike,
                  strain: npt.ArrayLike = SHEAR_STRAIN) -> np.ndarray:
        """The sum of the beads' hydrodynamic stresslets (3 x 3, units pi eta d^3).

        Beads at ``positions`` carrying ``forces`` in the rate of strain ``strain``; an isolated
        force-free bead gives (5/6) E.
        """
        r = positions_array(positions)
        f = like_positions(forces, len(r), "forces")
        e = tensor_array(strain, "strain")
        s = np.empty((3, 3), order="F")
        buf = message_buffer()
        check(library().knotflow_model_stresslet(self._live(), len(r), r, f, e, s, buf, MESSAGE_LENGTH), buf)
        return s


def default_eps_lub() -> float:
    """knotflow-mobility's default eps_lub (the library's)."""
    return defaults()[2]


def mobility(positions: npt.ArrayLike, model: str = "multipole", order: int = 2, lubrication: bool = True,
             eps_lub: float | None = None, overlap: str = "pair",
             overlap_time: float | None = None) -> np.ndarray:
    """The 3N x 3N translational mobility of beads at ``positions`` (an N x 3 array).

    Equal, bit for bit, to ``knotflow-mobility FILE --model M --order L --lubrication on|off
    --eps-lub X --output mobility``. The model arguments are those of :class:`Model`; for many
    configurations build one :class:`Model` and call its ``mobility``.
    """
    with Model(model, order, lubrication, eps_lub, overlap, overlap_time) as m:
        return m.mobility(positions)


def velocities(positions: npt.ArrayLike, forces: npt.ArrayLike, gradient: npt.ArrayLike = SHEAR_GRADIENT,
               model: str = "multipole", order: int = 2, lubrication: bool = True,
               eps_lub: float | None = None, overlap: str = "pair",
               overlap_time: float | None = None) -> np.ndarray:
    """Bead velocities G r + mu F + C:E (N x 3) for ``forces`` in the flow of ``gradient``.

    See :meth:`Model.velocities`; the model arguments are those of :class:`Model`.
    """
    with Model(model, order, lubrication, eps_lub, overlap, overlap_time) as m:
        return m.velocities(positions, forces, gradient)


def shear_disturbance(positions: npt.ArrayLike, model: str = "multipole", order: int = 2,
                      lubrication: bool = True, eps_lub: float | None = None) -> np.ndarray:
    """The disturbance C:E (N x 3) of free beads in the simple shear v0 = (z, 0, 0).

    Equal to ``knotflow-mobility --output shear``.
    """
    with Model(model, order, lubrication, eps_lub) as m:
        return m.disturbance(positions, SHEAR_STRAIN)
