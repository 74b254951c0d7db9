"""Interactive 3-D viewer of a case for report.html (plotly, works offline).

Per case: the chain in a cube of equal axis scales (rotate with the mouse, zoom with the
wheel), coloured by halves like the figures (first half blue, second orange, bead 0 a black
square), arrows for the flow (x) and vorticity (y) directions, a time slider over the stored
frames (at most ``max_frames``, evenly strided) and, in the title, the frame's time and k_f
(of the latest analysed frame at or before it; none without an analysis).  The plotly.js
library is embedded once in the page (``plotly_js_tag``): no network at view time.
"""

from __future__ import annotations

import html as _html

import numpy as np

from .analysis import kf_label
from .io import Case
from .movie import COL_FIRST, COL_SECOND, movie_frames

# matplotlib's tab:blue and tab:orange, the colours of the figures and the movie
COLOURS = {"tab:blue": "#1f77b4", "tab:orange": "#ff7f0e"}
VIEWER_MAX_FRAMES = 60


def plotly_js_tag() -> str:
    """A <script> element with the whole plotly.js library (about 4.8 MB), for offline use."""
    from plotly.offline import get_plotlyjs
    return "<script type='text/javascript'>" + get_plotlyjs() + "</script>"


def _title(case, fi, kf):
    t = float(case.time[fi])
    return f"{_html.escape(case.name)}: frame {fi}, t = {t:.4g}, {kf_label(kf, t)}"


def viewer_figure(case: Case, kf=None, max_frames: int = VIEWER_MAX_FRAMES):
    """The plotly figure: traces 0-2 (halves, bead 0) change with the slider's frame."""
    import plotly.graph_objects as go
    frames = movie_frames(case.nframes, max_frames=max_frames)
    if not frames:
        raise ValueError("the case has no frames")
    n = case.positions.shape[1]
    h = n // 2
    centred = {fi: case.positions[fi] - case.positions[fi].mean(axis=0) for fi in frames}
    half = 1.05 * max(1.0, max(float(np.abs(r).max()) for r in centred.values()))
    beads = np.arange(n)

    def chain(fi):
        r = centred[fi]
        return [go.Scatter3d(x=r[: h + 1, 0], y=r[: h + 1, 1], z=r[: h + 1, 2],
                             mode="lines+markers", name=f"beads 0-{h}",
                             line={"color": COLOURS[COL_FIRST], "width": 6},
                             marker={"size": 3, "color": COLOURS[COL_FIRST]},
                             hovertext=[f"bead {i}" for i in beads[: h + 1]], hoverinfo="text"),
                go.Scatter3d(x=r[h:, 0], y=r[h:, 1], z=r[h:, 2], mode="lines+markers",
                             name=f"beads {h}-{n - 1}",
                             line={"color": COLOURS[COL_SECOND], "width": 6},
                             marker={"size": 3, "color": COLOURS[COL_SECOND]},
                             hovertext=[f"bead {i}" for i in beads[h:]], hoverinfo="text"),
                go.Scatter3d(x=r[:1, 0], y=r[:1, 1], z=r[:1, 2], mode="markers",
                             name="bead 0", marker={"size": 5, "color": "black",
                                                    "symbol": "square"},
                             hoverinfo="name")]

    # direction arrows along the bottom edges nearest to the default camera (from +x +y +z)
    o = np.array([0.2, 0.2, -0.95]) * half
    length = 0.6 * half
    arrows = []
    for axis_k, label, colour in ((0, "flow x", "#d62728"), (1, "vorticity y", "#2ca02c")):
        tip = o.copy()
        tip[axis_k] += length
        arrows.append(go.Scatter3d(x=[o[0], tip[0]], y=[o[1], tip[1]], z=[o[2], tip[2]],
                                   mode="lines+text", text=["", label],
                                   textposition="top center", textfont={"color": colour},
                                   line={"color": colour, "width": 7},
                                   name=label.replace(" ", " (") + ")", hoverinfo="name"))
        direction = np.zeros(3)
        direction[axis_k] = 1.0
        arrows.append(go.Cone(x=[tip[0]], y=[tip[1]], z=[tip[2]], u=[direction[0]],
                              v=[direction[1]], w=[direction[2]], sizemode="absolute",
                              sizeref=0.12 * half, anchor="tip", showscale=False,
                              colorscale=[[0, colour], [1, colour]], hoverinfo="skip"))
    fig = go.Figure(data=chain(frames[0]) + arrows)
    fig.frames = [go.Frame(name=str(fi), data=chain(fi), traces=[0, 1, 2],
                           layout={"title": {"text": _title(case, fi, kf)}})
                  for fi in frames]
    axis = {"range": [-half, half], "autorange": False, "zeroline": False}
    steps = [{"method": "animate", "label": f"{float(case.time[fi]):.4g}",
              "args": [[str(fi)], {"mode": "immediate", "frame": {"duration": 0, "redraw": True},
                                   "transition": {"duration": 0}}]}
             for fi in frames]
    fig.update_layout(
        title={"text": _title(case, frames[0], kf), "font": {"size": 14}},
        scene={"xaxis": dict(axis, title="x (flow)"), "yaxis": dict(axis, title="y (vorticity)"),
               "zaxis": dict(axis, title="z (gradient)"), "aspectmode": "cube"},
        sliders=[{"active": 0, "steps": steps, "currentvalue": {"prefix": "t = "},
                  "pad": {"t": 10}, "len": 0.95, "x": 0.025}],
        width=720, height=640, margin={"l": 0, "r": 0, "t": 50, "b": 20},
        legend={"x": 0.0, "y": 1.0}, uirevision="keep")
    return fig


def viewer_html(case: Case, kf=None, div_id: str = "viewer",
                max_frames: int = VIEWER_MAX_FRAMES) -> str:
    """An HTML fragment (a div and a script) of the viewer; needs ``plotly_js_tag`` once on
    the page."""
    fig = viewer_figure(case, kf=kf, max_frames=max_frames)
    return fig.to_html(full_html=False, include_plotlyjs=False, div_id=div_id,
                       auto_play=False, config={"displaylogo": False})
