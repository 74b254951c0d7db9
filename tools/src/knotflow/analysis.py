"""Knots and shape of a chain (src/capi/kf_capi_knots, kf_capi_shape): the library's code, as
knotflow-analyze and knotflow use it."""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from knotflow._library import (
    MESSAGE_LENGTH,
    KnotflowError,
    c_double_value,
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
          stream: int = 0, points: npt.ArrayLike | None = None) -> Knots:
    """Knot analysis of the open chain at ``positions`` (N x 3, N >= 2) by stochastic closure.

    ``closures`` points (default: knotflow-analyze's, 1000) on the sphere of radius 10 R_g are
    drawn from the stream (``seed``, ``stream``) (default seed: knotflow-analyze's); each is joined
    to both ends and the closed polygon classified. ``stream`` 0 is what knotflow-analyze uses
    for a coordinate file (``--closures C --seed S``); frame k of a case file uses stream k.
    ``points`` (C x 3, absolute coordinates) replaces the random closure points (then
    ``closures`` = C and ``stream`` is not used; ``seed`` still draws the projections), as
    knotflow-analyze ``--closure-points FILE``.
    """
    r = positions_array(positions)
    sd = int64_value(default_seed() if seed is None else seed, "seed")
    st = int64_value(stream, "stream")
    types = knot_types()
    kf, dominant, seconds = ctypes.c_double(), ctypes.c_int(), ctypes.c_double()
    spectrum = np.zeros(len(types))
    buf = message_buffer()
    if points is not None:
        pts = positions_array(points, "points")
        nc = len(pts)
        if closures is not None and c_int_value(closures, "closures") != nc:
            raise KnotflowError(f"closures = {closures} but {nc} closure points given")
        per_closure = np.zeros(max(nc, 1), dtype=np.int32)
        check(library().knotflow_knots_at_points(len(r), r, nc, pts, sd, ctypes.byref(kf), spectrum,
                                                 ctypes.byref(dominant), per_closure, ctypes.byref(seconds),
                                                 buf, MESSAGE_LENGTH), buf)
    else:
        nc = default_closures() if closures is None else c_int_value(closures, "closures")
        per_closure = np.zeros(max(nc, 1), dtype=np.int32)
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


def matrix_defaults() -> tuple[int, int]:
    """knotflow-analyze's defaults of the knot matrix: (closures per subchain, shortest subchain)."""
    closures, min_length = ctypes.c_int(), ctypes.c_int()
    library().knotflow_matrix_defaults(ctypes.byref(closures), ctypes.byref(min_length))
    return closures.value, min_length.value


@dataclass(frozen=True, eq=False)
class KnotMatrix:
    """The knot matrix of an open chain (:func:`knot_matrix`).

    Attributes:
        matrix: K, shape (N, N): ``matrix[i, j]`` is k_f of the subchain i..j (0-based, i < j);
            NaN where not computed (j <= i, shorter than ``min_length``, off the ``stride`` grid).
        core: the knot core, the shortest subchain (i, j) with K >= 0.5 (the lowest i on a
            tie), or None.
        slipknot: a knot core while the whole chain's k_f (``kf_whole``) is below 0.1; None
            when ``kf_whole`` was not given.
        closures, seed, min_length, stride: how it was computed.
        seconds: the library's wall time.
    """

    matrix: np.ndarray
    core: tuple[int, int] | None
    slipknot: bool | None
    closures: int
    seed: int
    min_length: int
    stride: int
    seconds: float


def knot_matrix(positions: npt.ArrayLike, closures: int | None = None, seed: int | None = None,
                min_length: int | None = None, stride: int = 1,
                kf_whole: float | None = None) -> KnotMatrix:
    """The knot matrix of the open chain at ``positions`` (N x 3, N >= 2), as knotflow-analyze
    ``--matrix --matrix-closures C --min-length M --seed S`` computes it.

    Each subchain i..j with at least ``min_length`` beads (default 10) is closed ``closures``
    times (default 100) on the sphere of its own centre and R_g, drawing from its own stream
    (``seed``, i*65536 + j + 1): an entry does not depend on which others are computed.
    ``stride`` > 1 computes only i and j on the grid 0, stride, 2 stride, ... (and j = N-1).
    ``kf_whole`` (the whole chain's k_f, e.g. :func:`knotted_fraction`) decides ``slipknot``.
    """
    r = positions_array(positions)
    mc, ml = matrix_defaults()
    nc = mc if closures is None else c_int_value(closures, "closures")
    length = ml if min_length is None else c_int_value(min_length, "min_length")
    step = c_int_value(stride, "stride")
    sd = int64_value(default_seed() if seed is None else seed, "seed")
    whole = np.nan if kf_whole is None else c_double_value(kf_whole, "kf_whole")
    if kf_whole is not None and not np.isfinite(whole):
        raise KnotflowError(f"kf_whole = {kf_whole!r}: expected a finite number")
    mat = np.zeros((len(r), len(r)), order="F")
    core = np.zeros(2, dtype=np.int32)
    found, slip, seconds = ctypes.c_int(), ctypes.c_int(), ctypes.c_double()
    buf = message_buffer()
    check(library().knotflow_knot_matrix(len(r), r, nc, sd, length, step, whole, mat, core,
                                         ctypes.byref(found), ctypes.byref(slip), ctypes.byref(seconds), buf,
                                         MESSAGE_LENGTH), buf)
    return KnotMatrix(matrix=np.ascontiguousarray(mat),
                      core=(int(core[0]), int(core[1])) if found.value else None,
                      slipknot=None if kf_whole is None else bool(slip.value),
                      closures=nc, seed=sd, min_length=length, stride=step, seconds=seconds.value)


def knot_core(matrix: npt.ArrayLike) -> tuple[int, int] | None:
    """The knot core of a knot matrix (N x N, as :func:`knot_matrix` or knotflow-analyze's
    ``/analysis/knot_matrix`` hold it): the shortest subchain (i, j), i < j, with K >= 0.5, the
    lowest i on a tie; None when there is none. NaN entries and those with j <= i are skipped.
    """
    try:
        mat = np.array(matrix, dtype=np.float64, order="F", copy=True)
    except (TypeError, ValueError) as exc:
        raise KnotflowError(f"matrix: not an array of numbers ({exc})") from None
    if mat.ndim != 2 or mat.shape[0] != mat.shape[1]:
        raise KnotflowError(f"matrix: expected a square (N, N) array, got shape {mat.shape}")
    n = c_int_value(mat.shape[0], "matrix size")
    core = np.zeros(2, dtype=np.int32)
    found = ctypes.c_int()
    buf = message_buffer()
    check(library().knotflow_knot_core(n, mat, core, ctypes.byref(found), buf, MESSAGE_LENGTH), buf)
    return (int(core[0]), int(core[1])) if found.value else None


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
