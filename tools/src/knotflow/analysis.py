"""Knots and shape of a chain (src/capi/kf_capi_knots, kf_capi_shape): the library's code, as
knotflow-analyze and knotflow use it."""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from knotflow._library import (
    MESSAGE_LENGTH,
    c_int_value,
    check,
    defaults,
    int64_value,
    library,
    message_buffer,
    names,
    positions_array,
)


def knot_types() -> tuple[str, ...]:
    """The knot types of a spectrum, in the library's order (``'0_1'`` first, ``'other'`` last)."""
    return names(3)


def default_closures() -> int:
    """knotflow-analyze's default number of closures."""
    return defaults()[0]


def default_seed() -> int:
    """knotflow-analyze's default seed of the closure points."""
    return defaults()[1]


@dataclass(frozen=True)
class Knots:
    """The closures of one open chain.

    Attributes:
        kf: the knotted fraction (fraction of non-trivial closures).
        spectrum: the fraction of each knot type (keys in the order of :func:`knot_types`).
        dominant: the most frequent type (the first in table order on a tie).
        per_closure: the type of each closure, in order.
        closures, seed, stream: how the closure points were drawn.
        seconds: the library's wall time of the analysis.
    """

    kf: float
    spectrum: dict[str, float]
    dominant: str
    per_closure: tuple[str, ...]
    closures: int
    seed: int
    stream: int
    seconds: float


def knots(positions: npt.ArrayLike, closures: int | None = None, seed: int | None = None,
          stream: int = 0) -> Knots:
    """Knot analysis of the open chain at ``positions`` (N x 3, N >= 2) by stochastic closure.

    ``closures`` points (default: knotflow-analyze's, 1000) on the sphere of radius 10 R_g are
    drawn from the stream (``seed``, ``stream``) (default seed: knotflow-analyze's); each is joined
    to both ends and the closed polygon classified. ``stream`` 0 is what knotflow-analyze uses
    for a coordinate file (``--closures C --seed S``); frame k of a case file uses stream k.
    """
    r = positions_array(positions)
    nc = default_closures() if closures is None else c_int_value(closures, "closures")
    sd = int64_value(default_seed() if seed is None else seed, "seed")
    st = int64_value(stream, "stream")
    types = knot_types()
    kf, dominant, seconds = ctypes.c_double(), ctypes.c_int(), ctypes.c_double()
    spectrum = np.zeros(len(types))
    per_closure = np.zeros(max(nc, 1), dtype=np.int32)
    buf = message_buffer()
    check(library().knotflow_knots(len(r), r, nc, sd, st, ctypes.byref(kf), spectrum,
                                   ctypes.byref(dominant), per_closure, ctypes.byref(seconds), buf,
                                   MESSAGE_LENGTH), buf)
    return Knots(kf=kf.value, spectrum=dict(zip(types, spectrum.tolist(), strict=True)),
                 dominant=types[dominant.value - 1],
                 per_closure=tuple(types[k - 1] for k in per_closure[:nc]),
                 closures=nc, seed=sd, stream=st, seconds=seconds.value)


def knotted_fraction(positions: npt.ArrayLike, closures: int | None = None, seed: int | None = None,
                     stream: int = 0) -> float:
    """k_f of the open chain at ``positions``: knotflow-analyze's ``kf`` for the same closures and seed.

    See :func:`knots`.
    """
    return knots(positions, closures, seed, stream).kf


def knot_spectrum(positions: npt.ArrayLike, closures: int | None = None, seed: int | None = None,
                  stream: int = 0) -> dict[str, float]:
    """The fraction of closures of each knot type (knotflow-analyze's ``spectrum``). See :func:`knots`."""
    return knots(positions, closures, seed, stream).spectrum


@dataclass(frozen=True)
class Shape:
    """Shape observables of one configuration (PHYSICS.md section 6; knotflow's frame observables).

    Attributes:
        rg: radius of gyration.
        a, b, c: semi-axes sqrt(3 lambda_k) of the gyration tensor, a >= b >= c.
        theta: angle of the principal axis from the vorticity axis y, in [0, pi].
        phi: angle of its projection on the xz-plane from z, in (-pi, pi].
        close_pairs: pairs |i - j| > 1 closer than 1.05.
    """

    rg: float
    a: float
    b: float
    c: float
    theta: float
    phi: float
    close_pairs: int


def shape(positions: npt.ArrayLike) -> Shape:
    """Shape observables of the chain at ``positions`` (N x 3, N >= 2), as knotflow records them."""
    r = positions_array(positions)
    values = np.zeros(6)
    close = ctypes.c_int()
    buf = message_buffer()
    check(library().knotflow_shape(len(r), r, values, ctypes.byref(close), buf, MESSAGE_LENGTH), buf)
    rg, a, b, c, theta, phi = values.tolist()
    return Shape(rg=rg, a=a, b=b, c=c, theta=theta, phi=phi, close_pairs=close.value)
