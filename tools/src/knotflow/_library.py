"""Loading the shared library ``libknotflow_capi`` (src/capi) and calling it safely.

The library is looked for, in this order: at the path in the environment variable
``KNOTFLOW_LIBRARY``; next to this package (a wheel carries it there); in
``<sys.prefix>/lib/knotflow`` (scripts/build.sh links the build's library into its virtual
environment); in the build tree of the source checkout this package lives in (``build/lib``).
Every call goes through :func:`check`, which turns a non-zero status into a
:class:`KnotflowError` carrying the library's message. Arguments are converted here (arrays of
the right shape and type, integers that fit a C int); what their values may be is the
library's to decide, so its messages reach the caller.
"""

from __future__ import annotations

import ctypes
import os
import sys
from pathlib import Path

import numpy as np
import numpy.typing as npt

LIBRARY_ENV = "KNOTFLOW_LIBRARY"
LIBRARY_FILE = "libknotflow_capi.so"
#: Length of the message buffer given to every call.
MESSAGE_LENGTH = 1024

#: Status codes of the C interface (kf_capi_status).
STATUS_OK = 0
STATUS_INVALID_ARGUMENT = 1
STATUS_FAILED = 2

_C_INT_MIN, _C_INT_MAX = -(2**31), 2**31 - 1


class KnotflowError(ValueError):
    """An error of the knotflow library or an argument it refuses; the message says which.

    ``status`` is the library's status code (1: an argument refused before any work, 2: a
    failure of the library), or 1 for an argument refused before the call (wrong shape or type).
    """

    def __init__(self, message: str, status: int = STATUS_INVALID_ARGUMENT) -> None:
        super().__init__(message)
        self.status = status


def candidate_paths() -> list[Path]:
    """Where the library is looked for, in order."""
    paths = []
    env = os.environ.get(LIBRARY_ENV)
    if env:
        paths.append(Path(env))
    here = Path(__file__).resolve().parent
    paths.append(here / LIBRARY_FILE)
    paths.append(Path(sys.prefix) / "lib" / "knotflow" / LIBRARY_FILE)
    # tools/src/knotflow -> the source checkout's default build tree
    paths.append(here.parents[2] / "build" / "lib" / LIBRARY_FILE)
    return paths


_DOUBLES_C = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
_DOUBLES_F = np.ctypeslib.ndpointer(dtype=np.float64, flags="F_CONTIGUOUS")
_INTS = np.ctypeslib.ndpointer(dtype=np.int32, flags="C_CONTIGUOUS")
_I, _D, _I64, _P = ctypes.c_int, ctypes.c_double, ctypes.c_int64, ctypes.c_void_p
_STR = ctypes.c_char_p

#: argtypes of every function of the C interface (restype int unless listed in _VOID).
_SIGNATURES: dict[str, list[object]] = {
    "knotflow_names": [_I, _STR, _I],
    "knotflow_defaults": [ctypes.POINTER(_I), ctypes.POINTER(_I64), ctypes.POINTER(_D), ctypes.POINTER(_D),
                          ctypes.POINTER(_I)],
    "knotflow_model_create": [_STR, _I, _I, _I, _D, _STR, _I, _D, ctypes.POINTER(_P), _STR, _I],
    "knotflow_model_free": [ctypes.POINTER(_P)],
    "knotflow_model_label": [_P, _STR, _I],
    "knotflow_model_mobility": [_P, _I, _DOUBLES_C, _DOUBLES_F, ctypes.POINTER(_D), _STR, _I],
    "knotflow_model_velocities": [_P, _I, _DOUBLES_C, _DOUBLES_C, _DOUBLES_F, _DOUBLES_C, _STR, _I],
    "knotflow_model_disturbance": [_P, _I, _DOUBLES_C, _DOUBLES_F, _DOUBLES_C, _STR, _I],
    "knotflow_model_stresslet": [_P, _I, _DOUBLES_C, _DOUBLES_C, _DOUBLES_F, _DOUBLES_F, _STR, _I],
    "knotflow_chain_forces": [_I, _DOUBLES_C, _D, _I, _D, _I, _D, _I, _D, _D, _DOUBLES_C, _DOUBLES_C,
                              ctypes.POINTER(_D), _STR, _I],
    "knotflow_forces_defaults": [ctypes.POINTER(_I), ctypes.POINTER(_D), ctypes.POINTER(_I),
                                 ctypes.POINTER(_D), ctypes.POINTER(_I), ctypes.POINTER(_D),
                                 ctypes.POINTER(_D)],
    "knotflow_knots": [_I, _DOUBLES_C, _I, _I64, _I64, ctypes.POINTER(_D), _DOUBLES_C, ctypes.POINTER(_I),
                       _INTS, ctypes.POINTER(_D), _STR, _I],
    "knotflow_shape": [_I, _DOUBLES_C, _DOUBLES_C, ctypes.POINTER(_I), _STR, _I],
    "knotflow_knots_at_points": [_I, _DOUBLES_C, _I, _DOUBLES_C, _I64, ctypes.POINTER(_D), _DOUBLES_C,
                                 ctypes.POINTER(_I), _INTS, ctypes.POINTER(_D), _STR, _I],
    "knotflow_knot_matrix": [_I, _DOUBLES_C, _I, _I64, _I, _I, _D, _DOUBLES_F, _INTS, ctypes.POINTER(_I),
                             ctypes.POINTER(_I), ctypes.POINTER(_D), _STR, _I],
    "knotflow_matrix_defaults": [ctypes.POINTER(_I), ctypes.POINTER(_I)],
    "knotflow_knot_core": [_I, _DOUBLES_F, _INTS, ctypes.POINTER(_I), _STR, _I],
    "knotflow_scene_cases": [_STR, _I, _STR, _I, ctypes.POINTER(_I), _STR, _I, ctypes.POINTER(_I), _STR, _I],
    "knotflow_run_scene": [_STR, _I, _STR, _I, _I, _I, _INTS, _STR, _I, _STR, _I],
    "knotflow_case_size": [_STR, _I, ctypes.POINTER(_I), ctypes.POINTER(_I), _STR, _I],
    "knotflow_read_case": [_STR, _I, _I, _I, _DOUBLES_C, _DOUBLES_C, _DOUBLES_C, _INTS, _STR, _I, _STR, _I],
    "knotflow_case_message_length": [],
    "knotflow_request_stop": [],
    "knotflow_clear_stop": [],
}
_VOID = {"knotflow_defaults", "knotflow_forces_defaults", "knotflow_model_free", "knotflow_matrix_defaults",
         "knotflow_request_stop", "knotflow_clear_stop"}

_loaded: ctypes.CDLL | None = None
_loaded_path: Path | None = None


def library() -> ctypes.CDLL:
    """The loaded library (loaded on first use, with every function's signature declared)."""
    global _loaded, _loaded_path
    if _loaded is not None:
        return _loaded
    tried = []
    for path in candidate_paths():
        if not path.is_file():
            tried.append(f"{path} (absent)")
            continue
        try:
            lib = ctypes.CDLL(str(path))
        except OSError as exc:
            tried.append(f"{path} ({exc})")
            continue
        for name, args in _SIGNATURES.items():
            fn = getattr(lib, name)
            fn.argtypes = args
            fn.restype = None if name in _VOID else ctypes.c_int
        _loaded, _loaded_path = lib, path
        return lib
    raise KnotflowError(
        "the knotflow shared library was not found; build it (bash scripts/build.sh, target knotflow_capi) "
        f"or set {LIBRARY_ENV}. Tried: " + "; ".join(tried))


def loaded_path() -> Path:
    """The path the library was loaded from (loading it first)."""
    library()
    assert _loaded_path is not None
    return _loaded_path


def message_buffer() -> ctypes.Array[ctypes.c_char]:
    """A fresh buffer for the library's message."""
    return ctypes.create_string_buffer(MESSAGE_LENGTH)


def check(status: int, buf: ctypes.Array[ctypes.c_char]) -> None:
    """Raise KnotflowError with the library's message when status is not 0."""
    if status != STATUS_OK:
        raise KnotflowError(buf.value.decode(errors="replace"), status)


def names(kind: int) -> tuple[str, ...]:
    """The library's name list `kind` (1 models, 2 overlap rules, 3 knot types, 4 case statuses)."""
    buf = message_buffer()
    check(library().knotflow_names(kind, buf, MESSAGE_LENGTH), buf)
    return tuple(buf.value.decode().split())


def defaults() -> tuple[int, int, float, float, int]:
    """(closures, seed, eps_lub, overlap_time, number of knot types): the library's defaults."""
    closures, seed, eps, otime, ntypes = _I(), _I64(), _D(), _D(), _I()
    library().knotflow_defaults(ctypes.byref(closures), ctypes.byref(seed), ctypes.byref(eps),
                                ctypes.byref(otime), ctypes.byref(ntypes))
    return closures.value, seed.value, eps.value, otime.value, ntypes.value


def c_int_value(value: object, what: str) -> int:
    """`value` as a Python int that fits a C int (bool and non-integers refused)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise KnotflowError(f"{what} = {value!r}: expected an integer")
    if not _C_INT_MIN <= int(value) <= _C_INT_MAX:
        raise KnotflowError(f"{what} = {value!r}: out of the range of a C int")
    return int(value)


def int64_value(value: object, what: str) -> int:
    """`value` as a Python int that fits a 64-bit signed integer (bool and non-integers refused)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not -(2**63) <= value < 2**63:
        raise KnotflowError(f"{what} = {value!r}: expected a 64-bit integer")
    return int(value)


def c_double_value(value: object, what: str) -> float:
    """`value` as a Python float (a real number; its range is the library's to check)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise KnotflowError(f"{what} = {value!r}: expected a number")
    return float(value)


def positions_array(positions: npt.ArrayLike, what: str = "positions") -> np.ndarray:
    """`positions` as a C-contiguous float64 (N, 3) array (a copy); only the shape is checked
    here, the number of beads and the values by the library."""
    try:
        r = np.array(positions, dtype=np.float64, order="C", copy=True)
    except (TypeError, ValueError) as exc:
        raise KnotflowError(f"{what}: not an array of numbers ({exc})") from None
    if r.ndim != 2 or r.shape[1] != 3:
        raise KnotflowError(f"{what}: expected an (N, 3) array, got shape {r.shape}")
    if r.shape[0] > _C_INT_MAX // 3:
        raise KnotflowError(f"{what}: {r.shape[0]} beads, more than a C int can count")
    return r


def like_positions(values: npt.ArrayLike, n: int, what: str) -> np.ndarray:
    """`values` (forces) as a C-contiguous float64 (n, 3) array."""
    v = positions_array(values, what)
    if v.shape[0] != n:
        raise KnotflowError(f"{what}: expected shape ({n}, 3) like the positions, got {v.shape}")
    return v


def tensor_array(values: npt.ArrayLike, what: str) -> np.ndarray:
    """A 3 x 3 tensor as a Fortran-ordered float64 array (element [i, j] is T_ij)."""
    try:
        t = np.array(values, dtype=np.float64, order="F", copy=True)
    except (TypeError, ValueError) as exc:
        raise KnotflowError(f"{what}: not an array of numbers ({exc})") from None
    if t.shape != (3, 3):
        raise KnotflowError(f"{what}: expected a 3 x 3 array, got shape {t.shape}")
    return t
