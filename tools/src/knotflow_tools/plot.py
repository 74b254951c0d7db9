"""Figures of one case: k_f(t) with events, shape panels, the rheology (files with the stresslet),
knot matrices, 3D snapshots, movie; and the shape map of several cases (a/b against b/c)."""

from __future__ import annotations

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.cm import ScalarMappable  # noqa: E402

from .analysis import CaseAnalysis  # noqa: E402
from .atomic import save_figure  # noqa: E402
from .io import Case  # noqa: E402
from .rheology import running_mean  # noqa: E402

MODE_NAMES = {0: "-", 1: "I", 2: "II"}


def mode_name(mode: int | None) -> str:
    """'I', 'II', '-' (neither) or '?' (no /analysis/shape: knotflow-analyze not run)."""
    return "?" if mode is None else MODE_NAMES.get(mode, "?")
_COL_FIRST = "tab:blue"
_COL_SECOND = "tab:orange"
_COL_CORE = "tab:red"


def _title(case: Case) -> str:
    a = case.bending_a
    o = case.orientation
    parts = [case.name]
    if a is not None:
        parts.append(f"A = {a:g}")
    if o is not None:
        parts.append(f"orientation {o}")
    return ", ".join(parts)


def plot_kf(case: Case, ana: CaseAnalysis, path) -> str:
    """k_f versus time with the hysteresis band and the events marked."""
    fig, ax = plt.subplots(figsize=(8, 3.5), constrained_layout=True)
    ax.axhspan(ana.low, ana.high, color="0.92", zorder=0, label="hysteresis band")
    ax.plot(ana.time, ana.kf, "-o", ms=2.5, lw=1.2, color="k", label="$k_f$")
    for ev in ana.events:
        col = "tab:red" if ev.kind == "unknot" else "tab:green"
        ax.axvline(ev.time, color=col, ls="--", lw=1.2)
        ax.annotate(ev.kind, (ev.time, 1.02), color=col, ha="center", va="bottom",
                    fontsize=8, annotation_clip=False,
                    bbox={"fc": "white", "ec": "none", "pad": 0.8})
    ax.set_ylim(-0.03, 1.08)
    ax.set_xlabel(r"time $\dot\gamma t$")
    ax.set_ylabel("knotted fraction $k_f$")
    nev = len(ana.events)
    ax.set_title(f"{_title(case)}   ({ana.kf_source} k_f, {nev} event{'s' if nev != 1 else ''})",
                 pad=14, fontsize=10)
    ax.legend(loc="lower left", fontsize=8)
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return str(path)


def plot_shape(case: Case, ana: CaseAnalysis, path) -> str:
    """Panels like Fig. 2b of the reference study: R_g, a, b, c, theta, phi, close pairs."""
    t = case.time
    o = ana.observables
    fig, axes = plt.subplots(5, 1, figsize=(8, 9), sharex=True, constrained_layout=True)
    axes[0].plot(t, o["rg"], color="k")
    axes[0].set_ylabel("$R_g$")
    for key, col in (("a", "tab:blue"), ("b", "tab:orange"), ("c", "tab:green")):
        axes[1].plot(t, o[key], color=col, label=key)
    axes[1].set_ylabel("semi-axes")
    axes[1].legend(loc="upper right", fontsize=8, ncol=3)
    axes[2].plot(t, o["theta"], color="tab:purple")
    axes[2].set_ylabel(r"$\theta$")
    axes[2].set_ylim(0, np.pi)
    axes[2].set_yticks([0, np.pi / 2, np.pi], ["0", r"$\pi/2$", r"$\pi$"])
    axes[3].plot(t, o["phi"], ".", ms=2.5, color="tab:brown")
    axes[3].set_ylabel(r"$\phi$")
    axes[3].set_ylim(-np.pi, np.pi)
    axes[3].set_yticks([-np.pi, -np.pi / 2, 0, np.pi / 2, np.pi],
                       [r"$-\pi$", r"$-\pi/2$", "0", r"$\pi/2$", r"$\pi$"])
    axes[4].step(t, o["close_pairs"], where="post", color="tab:red")
    axes[4].set_ylabel("close pairs")
    axes[4].set_xlabel(r"time $\dot\gamma t$")
    for ev in ana.events:
        for ax in axes:
            ax.axvline(ev.time, color="0.6", ls=":", lw=1)
    axes[0].set_title(f"{_title(case)}   case mode: {mode_name(ana.case_mode)}",
                      fontsize=10)
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return str(path)


_MODE_COLOURS = {0: "0.6", 1: _COL_FIRST, 2: _COL_SECOND}


def plot_rheology(case: Case, ana: CaseAnalysis, path) -> str:
    """The fibre's viscosity and normal-stress coefficients (/frames/stresslet) against time,
    each frame coloured by its shape mode (grey: none, blue: I, orange: II), with running
    means; k_f(t); and the viscosity against k_f at the analysed frames."""
    t = case.time
    st = case.stresslet
    if st is None:
        raise ValueError(f"{case.path}: no /frames/stresslet (run with &output stresslet = .true.)")
    modes = np.asarray(ana.modes) if len(ana.modes) == len(t) else np.zeros(len(t), dtype=int)
    fig = plt.figure(figsize=(8, 10), constrained_layout=True)
    axes = [fig.add_subplot(5, 1, 1)]
    for k in range(1, 4):
        axes.append(fig.add_subplot(5, 1, k + 1, sharex=axes[0]))
    for ax, key, label in ((axes[0], "viscosity", "viscosity"), (axes[1], "psi1", r"$\psi_1$"),
                           (axes[2], "psi2", r"$\psi_2$")):
        v = st[key]
        for m, col in _MODE_COLOURS.items():
            sel = modes == m
            if sel.any():
                ax.plot(t[sel], v[sel], ".", ms=3, color=col,
                        label=f"mode {MODE_NAMES[m]}" if m else "no mode")
        ax.plot(t, running_mean(v), "-", color="k", lw=1.2, label="running mean")
        ax.set_ylabel(label)
    axes[0].legend(loc="upper right", fontsize=8, ncol=4)
    axes[3].plot(ana.time, ana.kf, "-", color="k", lw=1.2)
    axes[3].set_ylabel("$k_f$")
    axes[3].set_xlabel(r"time $\dot\gamma t$")
    for ev in ana.events:
        for ax in axes[:4]:
            ax.axvline(ev.time, color="0.6", ls=":", lw=1)
    ax = fig.add_subplot(5, 1, 5)
    idx = np.asarray(ana.frame_index, dtype=int)
    ax.plot(ana.kf, st["viscosity"][idx], ".", ms=3, color="k")
    ax.set_xlabel("$k_f$")
    ax.set_ylabel("viscosity")
    axes[0].set_title(f"{_title(case)}   intrinsic viscosity form (5/2: free beads)", fontsize=10)
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return str(path)


def plot_knot_matrix(mat: np.ndarray, path, title: str = "") -> str:
    """Heat map of K(i, j) (dark = knotted).  When only a grid of subchains was computed
    (stride > 1), each computed value fills its grid cell; pale blue = not computed."""
    mat = np.asarray(mat, dtype=float)
    n = len(mat)
    fin = np.isfinite(mat)
    rows = np.nonzero(fin.any(axis=1))[0]
    cols = np.nonzero(fin.any(axis=0))[0]
    fig, ax = plt.subplots(figsize=(5.4, 4.6), constrained_layout=True)
    cmap = plt.get_cmap("Greys").with_extremes(bad="#dde8f4")
    im: ScalarMappable
    if len(rows) and len(cols):
        sub = np.ma.masked_invalid(mat[np.ix_(rows, cols)])

        def edges(idx):
            mid = 0.5 * (idx[1:] + idx[:-1]) if len(idx) > 1 else np.zeros(0)
            lo = idx[0] - (mid[0] - idx[0] if len(mid) else 0.5)
            hi = idx[-1] + (idx[-1] - mid[-1] if len(mid) else 0.5)
            return np.concatenate([[lo], mid, [hi]])

        im = ax.pcolormesh(edges(cols.astype(float)), edges(rows.astype(float)), sub,
                           cmap=cmap, vmin=0, vmax=1, shading="flat")
    else:
        im = ax.imshow(np.ma.masked_invalid(mat), cmap=cmap, vmin=0, vmax=1)
    ax.plot([0, n - 1], [0, n - 1], color="0.5", lw=0.8)
    ax.set_xlim(-0.5, n - 0.5)
    ax.set_ylim(n - 0.5, -0.5)
    ax.set_aspect("equal")
    ax.set_facecolor("#dde8f4")
    ax.set_xlabel("end bead j")
    ax.set_ylabel("start bead i")
    ax.set_title(title + "\n(pale blue: not computed)", fontsize=9)
    fig.colorbar(im, ax=ax, label="$k_f$ of subchain i..j")
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return str(path)


def plot_shape_map(series: list, path, title: str = "") -> str:
    """Every frame of each (label, a/b, b/c) of `series` as a point in the plane of b/c and a/b
    (both logarithmic), with the lines that separate the modes of knotflow's rule (a = 3 b;
    mode II asks b >= 2 c) and of its former one (a = 1.5 b), and the band b <= 2 c where the
    cross-section is nearly round, as the study's mode I (a >> b >~ c) has it."""
    fig, ax = plt.subplots(figsize=(6.4, 6.0), layout="constrained")
    ax.axvspan(0.9, 2.0, color="0.9", zorder=0, label="b ≤ 2 c: round cross-section (mode I: b ≳ c)")
    for label, ab, bc in series:
        ax.scatter(np.minimum(bc, 1e3), ab, s=4, alpha=0.35, label=f"{label} ({len(ab)} frames)")
    ax.axhline(3.0, color="k", lw=0.9, label="a = 3 b (knotflow's a ≫ b)")
    ax.axhline(1.5, color="k", lw=0.9, ls="--", label="a = 1.5 b (its former rule)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(left=0.9)
    ax.set_xlabel("b / c")
    ax.set_ylabel("a / b")
    ax.set_title(title, fontsize=9)
    fig.legend(loc="outside lower center", ncols=2, fontsize=7, markerscale=3)
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return str(path)


def _draw_chain(ax, r, core=None):
    """The chain in 3-D (first half blue, second half orange, first bead a black square); with
    core = (i, j) the beads i..j drawn over it in thick red (a knot core)."""
    n = len(r)
    h = n // 2
    ax.plot(r[:h + 1, 0], r[:h + 1, 1], r[:h + 1, 2], "-o", ms=2.5, lw=1.5, color=_COL_FIRST)
    ax.plot(r[h:, 0], r[h:, 1], r[h:, 2], "-o", ms=2.5, lw=1.5, color=_COL_SECOND)
    if core is not None:
        c = r[core[0]:core[1] + 1]
        ax.plot(c[:, 0], c[:, 1], c[:, 2], "-", lw=3.5, color=_COL_CORE)
    ax.scatter(*r[0], color="k", s=25, marker="s")
    ctr = 0.5 * (r.min(axis=0) + r.max(axis=0))
    half = max(np.ptp(r, axis=0).max() / 2, 1.0)
    ax.set_box_aspect((1, 1, 1))      # equal scales: a cube of equal ranges in a cubic box
    ax.set_xlim(ctr[0] - half, ctr[0] + half)
    ax.set_ylim(ctr[1] - half, ctr[1] + half)
    ax.set_zlim(ctr[2] - half, ctr[2] + half)
    ax.set_xlabel("x (flow)")
    ax.set_ylabel("y (vorticity)")
    ax.set_zlabel("z (gradient)")


def plot_snapshots(case: Case, path, frames=None) -> str:
    """3D snapshots (first half blue, second half orange, first bead a black square)."""
    n = case.nframes
    if frames is None:
        frames = sorted(set([0, n // 3, (2 * n) // 3, n - 1]))
    frames = [int(f) % n for f in frames]
    fig = plt.figure(figsize=(3.6 * len(frames), 3.8), constrained_layout=True)
    for k, fi in enumerate(frames):
        ax = fig.add_subplot(1, len(frames), k + 1, projection="3d")
        _draw_chain(ax, case.positions[fi])
        ax.set_title(f"frame {fi}, t = {case.time[fi]:.4g}", fontsize=9)
    fig.suptitle(_title(case), fontsize=10)
    save_figure(fig, path, dpi=100)
    plt.close(fig)
    return str(path)


def make_movie(case: Case, out_base, stride: int = 1, fps: int = 10, kf=None,
               max_frames: int = 0, width: int = 960, height: int = 540,
               progress: bool = False) -> str:
    """Movie of the case (``movie.render_movie``): ``out_base``.mp4 with ffmpeg, else .gif."""
    from .movie import movie_frames, render_movie
    frames = movie_frames(case.nframes, stride=max(1, stride), max_frames=max_frames)
    return render_movie(case, f"{out_base}.mp4", frames, kf=kf, fps=fps, width=width,
                        height=height, progress=progress, knot_core=True)


def plot_case(case: Case, ana: CaseAnalysis, outdir, movie: bool = False,
              movie_stride: int = 1, movie_max_frames: int = 0, movie_size=(960, 540)) -> list:
    """All figures of a case into outdir; returns the written paths."""
    os.makedirs(outdir, exist_ok=True)
    base = os.path.join(outdir, _safe(case.name))
    files = [plot_kf(case, ana, f"{base}_kf.png"), plot_shape(case, ana, f"{base}_shape.png"),
             plot_snapshots(case, f"{base}_snapshots.png")]
    if case.stresslet and all(k in case.stresslet for k in ("viscosity", "psi1", "psi2")):
        files.append(plot_rheology(case, ana, f"{base}_rheology.png"))
    for fi, mat in sorted(ana.knot_matrices.items()):
        files.append(plot_knot_matrix(mat, f"{base}_knot_matrix_{fi}.png",
                                      f"{case.name}: knot matrix, frame {fi}"))
    if movie:
        import subprocess
        import sys
        try:
            files.append(make_movie(case, f"{base}_movie", stride=movie_stride,
                                    kf=(ana.time, ana.kf), max_frames=movie_max_frames,
                                    width=movie_size[0], height=movie_size[1]))
        except (OSError, RuntimeError, ValueError, subprocess.CalledProcessError) as exc:
            print(f"knotflow: movie of {case.name} not written: {exc}", file=sys.stderr)
    return files


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in str(name)) or "case"
