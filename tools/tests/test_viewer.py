"""Interactive 3-D viewer: the plotly figure, report.html offline, and a real headless browser."""

import os
import re

import analysis_fixture as fixture
import numpy as np
import pytest

from knotflow_tools import io, viewer
from knotflow_tools.report import build_report

from conftest import unknotting_trefoil_frames, write_case

PROBE = os.path.join(os.path.dirname(__file__), "data", "viewer_probe.html")


def _case(tmp_path, nframes=6, analysed=True):
    path = write_case(tmp_path / "v_A1_b.h5", unknotting_trefoil_frames(nframes),
                      time=np.linspace(0.0, 10.0, nframes))
    if analysed:
        fixture.write_knots(path, [0, nframes - 1], [0.0, 10.0], [0.9, 0.05],
                       np.zeros((2, 10)), ["3_1", "0_1"], 10, 1)
    return path


def test_viewer_figure(tmp_path):
    case = io.read_case(_case(tmp_path, nframes=9))
    fig = viewer.viewer_figure(case, kf=(case.knots["time"], case.knots["kf"]), max_frames=5)
    assert [f.name for f in fig.frames] == ["0", "2", "4", "6", "8"]
    assert "k<sub>f</sub> = 0.900" in fig.frames[0].layout.title.text
    assert "frame 8, t = 10, k<sub>f</sub> = 0.050" in fig.frames[-1].layout.title.text
    # frames between analysed ones: k_f of the latest analysed frame, with its time
    assert fig.frames[1].layout.title.text.endswith("frame 2, t = 2.5, k<sub>f</sub> = 0.900 "
                                                    "(at t = 0)")
    scene = fig.layout.scene
    assert scene.aspectmode == "cube"
    assert tuple(scene.xaxis.range) == tuple(scene.yaxis.range) == tuple(scene.zaxis.range)
    assert len(fig.layout.sliders[0].steps) == 5
    # the chain traces of a frame are the frame's beads about their centre of mass
    r = case.positions[4] - case.positions[4].mean(axis=0)
    n = len(r)
    assert np.allclose(fig.frames[2].data[0].x, r[: n // 2 + 1, 0])
    assert np.allclose(fig.frames[2].data[1].z, r[n // 2:, 2])
    nokf = viewer.viewer_figure(case, kf=None)
    assert "not analysed" in nokf.layout.title.text


def test_report_viewer_is_offline(tmp_path):
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    _case(sweep)
    build_report(str(sweep), closures=10, movie=False)
    text = (sweep / "report" / "report.html").read_text()
    assert "id=\"viewer-0\"" in text and "Plotly.newPlot" in text
    assert len(text) > 3_000_000                       # plotly.js embedded
    assert not re.search(r"<script[^>]+src=", text)   # no external script (no CDN)


READY_JS = """
new Promise(function (resolve, reject) {
  var tries = 0;
  var timer = setInterval(function () {
    var gd = document.getElementById("viewer-0");
    var ok = gd && gd._fullLayout && gd.querySelector(".slider-rail-touch-rect") &&
             gd._transitionData && gd._transitionData._frames &&
             gd._transitionData._frames.length > 0 && gd.querySelector("canvas");
    if (!ok) { if (++tries > 600) { clearInterval(timer); reject("no viewer"); } return; }
    clearInterval(timer);
    // show only this viewer, at the top of the page
    var keep = gd.closest(".viewer");
    Array.prototype.forEach.call(document.body.children, function (el) {
      if (el !== keep && el.tagName !== "SCRIPT") el.style.display = "none"; });
    window.scrollTo(0, 0);
    setTimeout(function () {
      var r = gd.querySelector(".slider-rail-touch-rect").getBoundingClientRect();
      resolve({title: gd._fullLayout.title.text, railRight: r.right, railY: r.top + r.height / 2,
               eye: gd._fullLayout.scene.camera.eye});
    }, 1000);
  }, 50);
})
"""

CHANGED_JS = """
new Promise(function (resolve) {
  var gd = document.getElementById("viewer-0"), polls = 0;
  var timer = setInterval(function () {
    var now = gd._fullLayout.title.text;
    if (now !== %s || ++polls > 200) {
      clearInterval(timer);
      setTimeout(function () { resolve(now); }, 1000);   // let WebGL draw the new frame
    }
  }, 50);
})
"""


def _chain_pixels(png):
    """Mask of the pixels of the chain's colours (blue, orange) in the 3-D scene area."""
    from PIL import Image
    with Image.open(png) as im:
        a = np.asarray(im.convert("RGB"), dtype=int)
    a = a[200:580, 150:700]                      # the scene, below the legend, above the slider
    mask = np.zeros(a.shape[:2], dtype=bool)
    for rgb in ((0x1f, 0x77, 0xb4), (0xff, 0x7f, 0x0e)):
        mask |= (np.abs(a - np.array(rgb)).sum(axis=2) < 40)
    return mask


def test_viewer_in_headless_chromium(tmp_path):
    """report.html in a real browser: the chain is drawn on the 3-D canvas, a click on the time
    slider shows another frame (title with its k_f, different pixels), a drag rotates."""
    import json

    from browser import Browser, find_chromium
    exe = find_chromium()
    if exe is None:
        pytest.skip("Chromium not installed (Debian: apt-get install chromium): the viewer was "
                    "not opened in a browser")
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    _case(sweep)
    build_report(str(sweep), closures=10, movie=False)
    b = Browser(exe, width=760, height=700)
    try:
        b.goto((sweep / "report" / "report.html").as_uri())
        info = b.evaluate(READY_JS)
        assert info["title"] == "v_A1_b: frame 0, t = 0, k<sub>f</sub> = 0.900"
        b.screenshot(tmp_path / "still.png")
        b.click(info["railRight"] - 3, info["railY"])              # the slider's last step
        moved = b.evaluate(CHANGED_JS % json.dumps(info["title"]))
        assert moved == "v_A1_b: frame 5, t = 10, k<sub>f</sub> = 0.050"
        b.screenshot(tmp_path / "moved.png")
        # drag on the scene: the camera turns
        b.call("Input.dispatchMouseEvent", {"type": "mousePressed", "x": 380, "y": 350,
                                            "button": "left", "clickCount": 1})
        for k in range(1, 6):
            b.call("Input.dispatchMouseEvent", {"type": "mouseMoved", "x": 380 + 30 * k,
                                                "y": 350, "button": "left"})
        b.call("Input.dispatchMouseEvent", {"type": "mouseReleased", "x": 530, "y": 350,
                                            "button": "left", "clickCount": 1})
        eye = b.evaluate("document.getElementById('viewer-0')._fullLayout.scene.camera.eye")
    finally:
        b.close()
    a, m = _chain_pixels(tmp_path / "still.png"), _chain_pixels(tmp_path / "moved.png")
    assert a.sum() > 300 and m.sum() > 300, (a.sum(), m.sum())     # the chain is drawn
    assert (a ^ m).sum() > 300, (a ^ m).sum()                      # and moved with the slider
    assert eye != info["eye"]                                       # rotated by the drag
