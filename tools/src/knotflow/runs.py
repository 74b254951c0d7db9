"""Runs of scene files and their case files (src/capi/kf_capi_run): the library's case runner
and case-file reader, in this process.

The HDF5 library these calls use is not thread-safe: the calls of this module hold one lock
(:data:`HDF5_LOCK`), so threads calling them take turns (the hydrodynamic and knot functions do
not take it).
"""

from __future__ import annotations

import ctypes
import os
import threading
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from knotflow._library import KnotflowError, check, library, message_buffer, names

#: Serialises every call of this module into the library (HDF5 is not thread-safe).
HDF5_LOCK = threading.Lock()

#: How often run_scene's calling thread wakes to take a KeyboardInterrupt (seconds).
_POLL_SECONDS = 0.2

#: Length of the buffer for the file's status text.
_STATE_LENGTH = 1024


def _path_bytes(path: str | os.PathLike[str], what: str) -> bytes:
    """`path` as the bytes the library takes (refused: not a path, empty, a NUL character)."""
    try:
        raw = os.fsencode(path)
    except TypeError:
        raise KnotflowError(f"{what} = {path!r}: expected a path (str or os.PathLike)") from None
    if not raw:
        raise KnotflowError(f"{what}: an empty path")
    if b"\0" in raw:
        raise KnotflowError(f"{what} = {path!r}: a path cannot hold a NUL character")
    if len(raw) > 2**31 - 2:
        raise KnotflowError(f"{what}: a path longer than a C int can count")
    return raw


def _output_bytes(output_dir: str | os.PathLike[str] | None) -> bytes:
    return b"" if output_dir is None else _path_bytes(output_dir, "output_dir")


def _scene_cases(scene: bytes, outdir: bytes) -> tuple[Path, ...]:
    """The case files of the scene (read and checked by the library; nothing written). Caller
    holds HDF5_LOCK."""
    lib = library()
    ncases, needed = ctypes.c_int(), ctypes.c_int()
    size = 4096
    for _ in range(2):
        files = ctypes.create_string_buffer(size)
        buf = message_buffer()
        status = lib.knotflow_scene_cases(scene, len(scene), outdir, len(outdir), ctypes.byref(ncases), files,
                                          size, ctypes.byref(needed), buf, len(buf))
        if status != 0 and needed.value > size:
            size = needed.value
            continue
        check(status, buf)
        return tuple(Path(os.fsdecode(line)) for line in files.value.split(b"\n"))
    raise KnotflowError("knotflow_scene_cases: the list of case files did not fit")  # pragma: no cover


def scene_cases(scene: str | os.PathLike[str],
                output_dir: str | os.PathLike[str] | None = None) -> tuple[Path, ...]:
    """The case files a run of the scene file ``scene`` writes, one per case of its ``&sweep``.

    The scene is read and checked as the program ``knotflow`` checks it (its values, the
    resources, the models); a bad scene raises :class:`KnotflowError` naming the file, group,
    variable and value. ``output_dir`` replaces the scene's ``&output directory``. Nothing is
    written.
    """
    scene_b, outdir_b = _path_bytes(scene, "scene"), _output_bytes(output_dir)
    with HDF5_LOCK:
        return _scene_cases(scene_b, outdir_b)


@dataclass(frozen=True)
class Run:
    """The outcome of :func:`run_scene`.

    Attributes:
        scene: the scene file.
        case_files: each case's case file, in the order of the cases.
        statuses: each case's outcome: ``'finished'``, ``'skipped'`` (finished before, not run
            again), ``'stopped'`` or ``'failed'``.
        messages: each case's one-line message from the library.
    """

    scene: Path
    case_files: tuple[Path, ...]
    statuses: tuple[str, ...]
    messages: tuple[str, ...]

    def read(self, case: int = 0) -> Case:
        """The case file of case ``case`` (0-based) read back: :func:`read_case`."""
        return read_case(self.case_files[case])


def run_scene(scene: str | os.PathLike[str], output_dir: str | os.PathLike[str] | None = None,
              verbose: bool = False) -> Run:
    """Run every case of the scene file ``scene`` in this process, as ``knotflow SCENE`` does.

    The library's case runner (no subprocess): the scene is checked first (a bad scene raises
    :class:`KnotflowError` naming file, group, variable and value, and nothing is written); the
    output directory (the scene's ``&output directory``, or ``output_dir``; a relative path is
    taken from the current directory) is made and locked during the run; each case is run,
    resumed from its checkpoint, or skipped when its case file is finished. The case files are
    those of the program for the same scene, frame for frame. ``verbose`` prints the library's
    progress lines. A case that fails raises :class:`KnotflowError` with its message (the other
    cases have run). Returns the :class:`Run` (its case files: :func:`read_case`).

    Ctrl-C (KeyboardInterrupt in the calling thread) stops the run as SIGINT stops the program:
    the running case after the frame it is computing, which is written with its checkpoint, and
    no case after it; then the KeyboardInterrupt is raised (a further Ctrl-C waits for that frame
    too). The same call again resumes.
    """
    scene_b, outdir_b = _path_bytes(scene, "scene"), _output_bytes(output_dir)
    lib = library()
    with HDF5_LOCK:
        files = _scene_cases(scene_b, outdir_b)
        n = len(files)
        statuses = np.full(n, -1, dtype=np.int32)
        # each message cut to the library's length, with a line end, and the final NUL
        room = n * (lib.knotflow_case_message_length() + 1) + 1
        messages = ctypes.create_string_buffer(room)
        buf = message_buffer()
        done: list[int] = []
        # The run goes on in a thread of its own, so that this one can take Ctrl-C and ask the
        # library to stop after the current frame (a C call holds KeyboardInterrupt back).
        lib.knotflow_clear_stop()
        worker = threading.Thread(
            target=lambda: done.append(lib.knotflow_run_scene(
                scene_b, len(scene_b), outdir_b, len(outdir_b), int(verbose), n, statuses, messages,
                room, buf, len(buf))),
            name="knotflow.run_scene", daemon=True)
        worker.start()
        try:
            while worker.is_alive():
                worker.join(_POLL_SECONDS)
        except KeyboardInterrupt:
            lib.knotflow_request_stop()
            while worker.is_alive():   # a further Ctrl-C waits too: the frame is being written
                try:
                    worker.join()
                except KeyboardInterrupt:
                    continue
            lib.knotflow_clear_stop()
            raise
        check(done[0], buf)
    texts = messages.value.decode(errors="replace").split("\n")
    words = names(4)   # the library's case statuses, by code
    return Run(scene=Path(os.fsdecode(scene_b)), case_files=files,
               statuses=tuple(words[s] for s in statuses.tolist()),
               messages=tuple(texts + [""] * (n - len(texts))))


@dataclass(frozen=True, eq=False)
class Case:
    """A case file read back by the library (:func:`read_case`).

    Attributes:
        path: the case file.
        status: the file's status: ``'finished'``, ``'running'`` (interrupted, or still being
            written) or ``'failed: <reason>'``.
        time: the frame times, shape (F,).
        positions: the bead positions of every frame, shape (F, N, 3).
        observables: the shape observables of every frame (``/frames/observables``): ``rg``,
            ``a``, ``b``, ``c``, ``theta``, ``phi`` (float64, shape (F,)) and ``close_pairs``
            (int32, shape (F,)).
    """

    path: Path
    status: str
    time: np.ndarray
    positions: np.ndarray
    observables: dict[str, np.ndarray]

    @property
    def nframes(self) -> int:
        """The number of complete frames F."""
        return int(self.time.shape[0])

    @property
    def n_beads(self) -> int:
        """The number of beads N."""
        return int(self.positions.shape[1])


#: The floating-point observables of a frame, in the library's order.
OBSERVABLE_NAMES = ("rg", "a", "b", "c", "theta", "phi")


def read_case(path: str | os.PathLike[str]) -> Case:
    """Read the case file ``path`` with the library's reader (as knotflow-analyze reads it).

    The complete frames: those the newest checkpoint counts (a frame being written when a run
    stopped is left out). A missing file, a damaged one, or one that is not a knotflow case file
    (no ``/frames``, positions not (F, N, 3), non-finite values, times not increasing) raises
    :class:`KnotflowError` naming the file and the problem.
    """
    raw = _path_bytes(path, "path")
    lib = library()
    nframes, nbeads = ctypes.c_int(), ctypes.c_int()
    with HDF5_LOCK:
        buf = message_buffer()
        check(lib.knotflow_case_size(raw, len(raw), ctypes.byref(nframes), ctypes.byref(nbeads), buf,
                                     len(buf)), buf)
        f, n = nframes.value, nbeads.value
        t = np.zeros(f)
        r = np.zeros((f, n, 3))
        obs = np.zeros((6, f))
        pairs = np.zeros(f, dtype=np.int32)
        state = ctypes.create_string_buffer(_STATE_LENGTH)
        buf = message_buffer()
        check(lib.knotflow_read_case(raw, len(raw), f, n, t, r, obs, pairs, state, _STATE_LENGTH, buf,
                                     len(buf)), buf)
    observables = {name: obs[k].copy() for k, name in enumerate(OBSERVABLE_NAMES)}
    observables["close_pairs"] = pairs
    return Case(path=Path(os.fsdecode(raw)), status=state.value.decode(errors="replace"), time=t,
                positions=r, observables=observables)
