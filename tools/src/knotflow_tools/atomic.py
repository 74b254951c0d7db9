"""Writing output files whole or not at all, never through a planted link.

Every file a tool writes (reports, figures, XDMF, movies, ledger entries, coordinate files) goes
through here: the content is written into a new temporary file in the target's directory,
created exclusively (``tempfile.mkstemp``: ``O_CREAT | O_EXCL | O_NOFOLLOW``, a name of its
own, so neither an existing file nor a symbolic link planted under a predictable name is ever
opened), flushed and synced, and only then renamed over the target (``os.replace``: a link at
the target is replaced by the file, what it pointed to is not touched). When anything fails (a
full disk, a file size limit, a writer that stops) the temporary file is removed, the target is
left as it was, and a :class:`WriteError` names the target and the operating system's reason.
The Fortran programs do the same (kf_fs: write_file_atomic).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from typing import Any

#: Longest part of the target's name kept in a temporary name (a file name has 255 bytes).
_STEM = 100


class WriteError(OSError):
    """A file could not be written: ``str()`` names the file and the reason."""

    def __init__(self, path: str, reason: str):
        super().__init__(f"cannot write {path}: {reason}")
        self.path = path
        self.reason = reason

    def __str__(self) -> str:
        return str(self.args[0])


def _reason(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    return str(exc) or type(exc).__name__


def _mode() -> int:
    """0666 less the umask: the mode ``open()`` would give a new file."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


@contextlib.contextmanager
def replacing(path: str) -> Iterator[str]:
    """Yield the name of a new, empty temporary file beside ``path`` for a writer that takes a
    file name (matplotlib, ffmpeg); when the block ends without an exception the file is synced
    and renamed over ``path``. The temporary name keeps the suffix of ``path`` (writers choose
    the format by it). On an exception the temporary file is removed and ``path`` left as it
    was; an ``OSError`` becomes a :class:`WriteError` naming ``path``."""
    path = os.fspath(path)
    directory = os.path.dirname(path) or "."
    base = os.path.basename(path)
    suffix = os.path.splitext(base)[1]
    try:
        fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".{base[:_STEM]}.", suffix=f".tmp{suffix}")
    except OSError as exc:
        raise WriteError(path, _reason(exc)) from exc
    try:
        try:
            os.fchmod(fd, _mode())
        finally:
            os.close(fd)
        yield tmp
        _sync(tmp)
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.remove(tmp)
        if isinstance(exc, OSError) and not isinstance(exc, WriteError):
            raise WriteError(path, _reason(exc)) from exc
        raise
    _sync_directory(directory)


def _sync(path: str) -> None:
    """fsync a closed file: a full disk may show only here (delayed allocation)."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _sync_directory(directory: str) -> None:
    """Best effort: make the rename last a crash (some file systems refuse to sync a directory)."""
    with contextlib.suppress(OSError):
        fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def write_bytes(path: str, data: bytes) -> None:
    """Write ``data`` as the whole content of ``path`` (see the module)."""
    with replacing(path) as tmp:
        # O_NOFOLLOW: the file this process just created, not a link put in its place since
        fd = os.open(tmp, os.O_WRONLY | os.O_NOFOLLOW)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)


def write_text(path: str, text: str) -> None:
    """Write ``text`` (UTF-8) as the whole content of ``path`` (see the module)."""
    write_bytes(path, text.encode("utf-8"))


def save_figure(fig: Any, path: str, **kwargs: Any) -> None:
    """``fig.savefig(path, **kwargs)`` through a temporary file (see the module); the format
    is that of the suffix of ``path`` unless ``format`` is given."""
    kwargs.setdefault("format", os.path.splitext(os.fspath(path))[1][1:] or None)
    with replacing(path) as tmp:
        fig.savefig(tmp, **kwargs)
