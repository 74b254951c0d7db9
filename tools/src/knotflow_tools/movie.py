"""Movies of a case: the chain in 3-D beside k_f(t) and the shape panels, as MP4 or GIF.

The chain is drawn with equal axis scales (a cube of fixed size about the centre of mass, so
the zoom does not change during the movie), the first half of the beads blue and the second
orange (the study's colouring), the first bead a black square, arrows marking the flow
direction x and the vorticity direction y, and optionally the knot core of the stored knot
matrices as a grey band.  Beside it: k_f(t) (when known) and the shape panels
(R_g and the semi-axes a, b, c; the angles theta and phi), each with a marker at the frame's
time.  MP4 (H.264, yuv420p) is written with ffmpeg when it is on PATH; otherwise, or with
``fmt="gif"``, an animated GIF with Pillow.
"""

from __future__ import annotations

import errno
import os
import shutil
import subprocess
import sys
import time as _time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .analysis import kf_label, observables_of  # noqa: E402
from .atomic import WriteError, replacing  # noqa: E402
from .io import Case  # noqa: E402

COL_FIRST = "tab:blue"      #: first half of the chain
COL_SECOND = "tab:orange"   #: second half of the chain
MOVIE_FORMATS = ("mp4", "gif")


def have_ffmpeg() -> bool:
    """Whether ffmpeg is on PATH (MP4 output)."""
    return shutil.which("ffmpeg") is not None


def movie_frames(nframes: int, first: int = 0, last: int | None = None, stride: int = 1,
                 max_frames: int = 0) -> list:
    """Frame indices ``first..last`` (inclusive; negative from the end) every ``stride``;
    with ``max_frames > 0`` the stride is raised so that at most that many frames remain."""
    if nframes <= 0:
        return []
    first = first % nframes if first < 0 else first
    last = nframes - 1 if last is None else (last % nframes if last < 0 else last)
    last = min(last, nframes - 1)
    if stride < 1:
        raise ValueError(f"stride must be >= 1 (got {stride})")
    if first > last:
        raise ValueError(f"empty frame range: first {first} > last {last}")
    count = last - first + 1
    if max_frames > 0:
        stride = max(stride, -(-count // max_frames))
    return list(range(first, last + 1, stride))


class Progress:
    """A text progress bar on a stream (carriage returns on a terminal, else a few lines)."""

    def __init__(self, total: int, label: str, stream=None, width: int = 30):
        self.total = max(1, total)
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.width = width
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.start = _time.monotonic()
        self._last_tenth = -1

    def update(self, done: int) -> None:
        frac = done / self.total
        tenth = int(frac * 10)
        if not self.tty and tenth == self._last_tenth and done != self.total:
            return
        self._last_tenth = tenth
        fill = int(round(frac * self.width))
        bar = "#" * fill + "-" * (self.width - fill)
        text = (f"{self.label} [{bar}] {done}/{self.total} frames "
                f"{_time.monotonic() - self.start:.1f} s")
        self.stream.write(("\r" + text) if self.tty else text + "\n")
        if self.tty and done == self.total:
            self.stream.write("\n")
        self.stream.flush()


def _cube(positions, frames):
    """Half width of the cube that holds every selected frame about its centre of mass."""
    half = 1.0
    for fi in frames:
        r = positions[fi]
        half = max(half, float(np.max(np.abs(r - r.mean(axis=0)))))
    return 1.05 * half


def _even(v: int) -> int:
    return max(16, int(v) // 2 * 2)


def _draw_directions(ax, half):
    """Arrows for the flow (x) and vorticity (y) directions, in the lower corner of the cube."""
    o = np.array([-half, -half, -half]) * 0.95
    length = 0.45 * half
    ax.quiver(*o, length, 0, 0, color="tab:red", lw=1.6, arrow_length_ratio=0.25)
    ax.quiver(*o, 0, length, 0, color="tab:green", lw=1.6, arrow_length_ratio=0.25)
    ax.text(o[0] + 1.1 * length, o[1], o[2], "flow x", color="tab:red", fontsize=7)
    ax.text(o[0], o[1] + 1.1 * length, o[2], "vorticity y", color="tab:green", fontsize=7)


class MovieFigure:
    """The movie's figure; ``draw(fi)`` updates it to frame fi."""

    def __init__(self, case: Case, frames, kf=None, width: int = 960, height: int = 540,
                 elev: float = 20.0, azim: float = -60.0, dpi: int = 100, cores=None):
        self.case = case
        self.cores = dict(sorted((cores or {}).items()))
        self.frames = list(frames)
        self.dpi = dpi
        self.fig = plt.figure(figsize=(width / dpi, height / dpi), dpi=dpi)
        obs = observables_of(case)
        t = case.time
        top = 0.86 if self.cores else 0.93           # room for a two-line title
        gs = self.fig.add_gridspec(3, 2, width_ratios=(1.25, 1.0), left=0.0, right=0.97,
                                   top=top, bottom=0.1, hspace=0.35, wspace=0.12)
        ax3 = self.fig.add_subplot(gs[:, 0], projection="3d")
        self.ax3 = ax3
        self.half = _cube(case.positions, self.frames)
        ax3.set_box_aspect((1, 1, 1))
        ax3.set_xlim(-self.half, self.half)
        ax3.set_ylim(-self.half, self.half)
        ax3.set_zlim(-self.half, self.half)
        ax3.view_init(elev=elev, azim=azim)
        ax3.set_xlabel("x (flow)", fontsize=7, labelpad=-8)
        ax3.set_ylabel("y (vorticity)", fontsize=7, labelpad=-8)
        ax3.set_zlabel("z (gradient)", fontsize=7, labelpad=-8)
        ax3.tick_params(labelsize=6, pad=-3)
        _draw_directions(ax3, self.half)
        n = case.positions.shape[1]
        self.h = n // 2
        r = self._centred(self.frames[0])
        (self.l1,) = ax3.plot(*r[: self.h + 1].T, "-o", ms=2.0, lw=1.4, color=COL_FIRST)
        (self.l2,) = ax3.plot(*r[self.h:].T, "-o", ms=2.0, lw=1.4, color=COL_SECOND)
        (self.b0,) = ax3.plot(*r[:1].T, "s", ms=4.5, color="k")
        (self.core,) = ax3.plot([], [], [], "-", lw=7, color="0.15", alpha=0.35, zorder=0)
        self.title = self.fig.suptitle("", fontsize=9)
        self.markers = []
        panels = []
        if kf is not None and len(kf[0]):
            panels.append(("kf", kf))
        panels.append(("size", None))
        panels.append(("angles", None))
        panels = panels[:3]
        axes = [self.fig.add_subplot(gs[k, 1]) for k in range(len(panels))]
        for ax, (kind, data) in zip(axes, panels):
            if kind == "kf":
                ax.plot(data[0], data[1], "-", color="k", lw=1.0)
                ax.axhspan(0.1, 0.9, color="0.92", zorder=0)
                ax.set_ylim(-0.03, 1.05)
                ax.set_ylabel("$k_f$", fontsize=8)
            elif kind == "size":
                ax.plot(t, obs["rg"], color="k", lw=1.0, label="$R_g$")
                for key, col in (("a", "tab:blue"), ("b", "tab:orange"), ("c", "tab:green")):
                    ax.plot(t, obs[key], color=col, lw=0.9, label=key)
                ax.legend(fontsize=6, ncol=4, loc="upper left", frameon=False)
                ax.set_ylabel("size", fontsize=8)
            else:
                ax.plot(t, obs["theta"], color="tab:purple", lw=1.0, label=r"$\theta$")
                ax.plot(t, obs["phi"], ".", ms=1.5, color="tab:brown", label=r"$\phi$")
                ax.set_ylim(-np.pi, np.pi)
                ax.legend(fontsize=6, ncol=2, loc="upper left", frameon=False)
                ax.set_ylabel("angle", fontsize=8)
            ax.tick_params(labelsize=6)
            ax.set_xlim(t[0], t[-1] if t[-1] > t[0] else t[0] + 1.0)
            self.markers.append(ax.axvline(t[self.frames[0]], color="tab:red", lw=1.2))
        if axes:
            axes[-1].set_xlabel(r"time $\dot\gamma t$", fontsize=8)
        self.kf = kf

    def _centred(self, fi):
        r = self.case.positions[fi]
        return r - r.mean(axis=0)

    def core_at(self, fi: int):
        """(i, j, matrix frame) of the knot core of the latest stored knot matrix at or before
        frame fi, or None (no matrix yet, or unknotted)."""
        found = None
        for mf, core in self.cores.items():
            if mf > fi:
                break
            found = (core[0], core[1], mf) if core is not None else None
        return found

    def draw(self, fi: int) -> None:
        r = self._centred(fi)
        self.l1.set_data_3d(*r[: self.h + 1].T)
        self.l2.set_data_3d(*r[self.h:].T)
        self.b0.set_data_3d(*r[:1].T)
        core = self.core_at(fi)
        if core is not None:
            self.core.set_data_3d(*r[core[0]: core[1] + 1].T)
        else:
            self.core.set_data_3d([], [], [])
        t = float(self.case.time[fi])
        for m in self.markers:
            m.set_xdata([t, t])
        kf_text = ""
        if self.kf is not None and len(self.kf[0]):
            kf_text = ",  " + kf_label(self.kf, t, sub="$_f$")
        core_text = (f"\nknot core: beads {core[0]}-{core[1]} (knot matrix of frame {core[2]})"
                     if core is not None else "")
        self.title.set_text(f"{self.case.name}: frame {fi}, t = {t:.4g}{kf_text}{core_text}")

    def close(self):
        plt.close(self.fig)


def knot_cores(case: Case) -> dict:
    """Stored knot matrix frame -> its knot core (i, j), or None when no subchain is knotted
    (the library's knot core: knotflow.knot_core)."""
    import knotflow
    return {int(fi): knotflow.knot_core(mat) for fi, mat in case.knot_matrices.items()}


def render_movie(case: Case, out, frames=None, kf=None, fps: int = 10, width: int = 960,
                 height: int = 540, elev: float = 20.0, azim: float = -60.0,
                 fmt: str | None = None, progress: bool = True, stream=None,
                 knot_core: bool = False) -> str:
    """Render the movie of ``frames`` (default: all) to ``out``; returns the written path.

    ``kf`` is ``(time, kf)`` of the analysed frames (or None: no k_f panel).  ``fmt`` is
    ``"mp4"`` or ``"gif"``; by default the suffix of ``out`` decides, and MP4 falls back to GIF
    (suffix changed) when ffmpeg is missing.  ``knot_core``: highlight the knot core (shortest
    knotted subchain) of the latest stored knot matrix (``/analysis/knot_matrix``) at or before
    each frame."""
    from matplotlib import animation
    frames = list(range(case.nframes)) if frames is None else list(frames)
    if not frames:
        raise ValueError("no frames to render")
    if fps < 1:
        raise ValueError(f"fps must be >= 1 (got {fps})")
    out = str(out)
    base, ext = os.path.splitext(out)
    fmt = fmt or (ext[1:].lower() if ext[1:].lower() in MOVIE_FORMATS else "mp4")
    if fmt not in MOVIE_FORMATS:
        raise ValueError(f"unknown movie format {fmt!r}; valid: {', '.join(MOVIE_FORMATS)}")
    if fmt == "mp4" and not have_ffmpeg():
        print("knotflow movie: ffmpeg not found, writing an animated GIF instead "
              "(Debian: apt-get install ffmpeg)", file=stream or sys.stderr)
        fmt = "gif"
    out = f"{base}.{fmt}"
    width, height = _even(width), _even(height)
    mf = MovieFigure(case, frames, kf=kf, width=width, height=height, elev=elev, azim=azim,
                     cores=knot_cores(case) if knot_core else None)
    writer: animation.AbstractMovieWriter
    if fmt == "mp4":
        writer = animation.FFMpegWriter(fps=fps, codec="libx264",
                                        extra_args=["-pix_fmt", "yuv420p", "-preset", "fast"])
    else:
        writer = animation.PillowWriter(fps=fps)
    bar = Progress(len(frames), os.path.basename(out), stream) if progress else None
    try:
        os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
        # written to a temporary file renamed when complete (knotflow_tools.atomic): a movie
        # that cannot be written (full disk) leaves the old one, or none, and names the reason
        with replacing(out) as tmp:
            try:
                with writer.saving(mf.fig, tmp, dpi=mf.dpi):
                    for k, fi in enumerate(frames):
                        mf.draw(fi)
                        writer.grab_frame()
                        if bar:
                            bar.update(k + 1)
            except subprocess.CalledProcessError as exc:
                raise WriteError(out, _encoder_reason(exc)) from exc
    finally:
        mf.close()
    return out


#: The operating system's reasons a write fails, as ffmpeg prints them (strerror).
_WRITE_REASONS = tuple(os.strerror(e) for e in (errno.ENOSPC, errno.EFBIG, errno.EDQUOT, errno.EIO,
                                                errno.EACCES, errno.EROFS))


def _encoder_reason(exc: subprocess.CalledProcessError) -> str:
    """Why the encoder failed: the operating system's reason when ffmpeg names one (e.g. 'No
    space left on device'), else ffmpeg's last line on stderr, with its exit status."""
    err = exc.stderr or b""
    text = err.decode(errors="replace") if isinstance(err, bytes) else str(err)
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    named = [r for line in lines for r in _WRITE_REASONS if r in line]
    if named:
        return f"{named[-1]} (ffmpeg, exit status {exc.returncode})"
    return (f"{lines[-1]} (ffmpeg, exit status {exc.returncode})" if lines
            else f"ffmpeg exited with status {exc.returncode}")


def case_kf(case: Case, closures: int = 0, frames=None, seed: int | None = None):
    """(time, k_f) from /analysis/knots, or computed with ``closures`` on ``frames``
    (``closures`` 0: None)."""
    if case.knots is not None and len(case.knots["kf"]):
        order = np.argsort(case.knots["time"])
        return case.knots["time"][order], case.knots["kf"][order]
    if closures <= 0:
        return None
    from .analysis import knot_series
    frames = list(range(case.nframes)) if frames is None else list(frames)
    kf, _, _ = knot_series(case.positions, frames, closures, seed)
    return case.time[frames], kf


