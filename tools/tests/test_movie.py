"""Movies: frame selection, MP4 decoded by ffprobe, the GIF fallback, the command."""

import io as _io
import json
import os
import shutil
import subprocess

import analysis_fixture as fixture
import numpy as np
import pytest

from knotflow_tools import cli, io, movie

from conftest import unknotting_trefoil_frames, write_case

needs_ffmpeg = pytest.mark.skipif(
    shutil.which("ffmpeg") is None or shutil.which("ffprobe") is None,
    reason="ffmpeg/ffprobe not installed (Debian: apt-get install ffmpeg): MP4 not tested")


def _probe(path):
    out = subprocess.run(["ffprobe", "-v", "error", "-select_streams", "v:0", "-count_frames",
                          "-show_entries", "stream=nb_read_frames,width,height,codec_name,"
                          "pix_fmt:format=duration", "-of", "json", str(path)],
                         check=True, capture_output=True, text=True).stdout
    data = json.loads(out)
    return data["streams"][0], float(data["format"]["duration"])


def test_movie_frames():
    assert movie.movie_frames(10) == list(range(10))
    assert movie.movie_frames(10, first=2, last=8, stride=3) == [2, 5, 8]
    assert movie.movie_frames(10, first=-3) == [7, 8, 9]
    assert movie.movie_frames(100, max_frames=10) == list(range(0, 100, 10))
    assert movie.movie_frames(10, last=50) == list(range(10))
    assert movie.movie_frames(0) == []
    with pytest.raises(ValueError, match="stride"):
        movie.movie_frames(10, stride=0)
    with pytest.raises(ValueError, match="empty"):
        movie.movie_frames(10, first=5, last=2)


@needs_ffmpeg
def test_mp4_decoded_by_ffprobe(tmp_path):
    path = write_case(tmp_path / "m.h5", unknotting_trefoil_frames(6),
                      time=np.linspace(0, 10, 6))
    case = io.read_case(path)
    stream = _io.StringIO()
    out = movie.render_movie(case, tmp_path / "m.mp4", frames=[0, 1, 2, 3, 4], fps=5,
                             width=321, height=181, kf=(case.time, np.linspace(1, 0, 6)),
                             stream=stream)
    assert out == str(tmp_path / "m.mp4")
    info, duration = _probe(out)
    assert info["codec_name"] == "h264" and info["pix_fmt"] == "yuv420p"
    assert int(info["nb_read_frames"]) == 5
    assert (info["width"], info["height"]) == (320, 180)          # made even
    assert duration == pytest.approx(1.0, abs=0.05)                # 5 frames at 5 fps
    assert "[##############################] 5/5 frames" in stream.getvalue()


def test_gif_when_ffmpeg_is_missing(tmp_path, monkeypatch):
    from PIL import Image
    path = write_case(tmp_path / "g.h5", unknotting_trefoil_frames(4))
    monkeypatch.setattr(movie, "have_ffmpeg", lambda: False)
    stream = _io.StringIO()
    out = movie.render_movie(io.read_case(path), tmp_path / "g.mp4", frames=[0, 2, 3], fps=4,
                             width=200, height=120, stream=stream)
    assert out == str(tmp_path / "g.gif")
    assert "ffmpeg not found" in stream.getvalue()
    with Image.open(out) as im:
        assert im.n_frames == 3 and im.size == (200, 120)


def test_movie_command(tmp_path, capsys):
    path = write_case(tmp_path / "c.h5", unknotting_trefoil_frames(8))
    fixture.write_knots(path, [0, 7], [0.0, 7.0], [0.9, 0.0], np.zeros((2, 10)), ["3_1", "0_1"],
                   10, 1)
    args = [str(path), "--first", "1", "--last", "5", "--stride", "2", "--fps", "3",
            "--width", "240", "--height", "160", "--elev", "30", "--azim", "10"]
    assert cli.main_movie(args + ["--gif"]) == 0
    captured = capsys.readouterr()
    assert captured.out.strip() == str(tmp_path / "c.gif")
    assert "3/3 frames" in captured.err                           # the progress bar
    if shutil.which("ffprobe") and shutil.which("ffmpeg"):
        assert cli.main_movie(args + ["--no-progress"]) == 0
        assert capsys.readouterr().err == ""
        info, duration = _probe(tmp_path / "c.mp4")
        assert int(info["nb_read_frames"]) == 3 and duration == pytest.approx(1.0, abs=0.05)
    assert cli.main_movie([str(path), "--stride", "0"]) == 2
    assert "stride" in capsys.readouterr().err


def test_knot_core_highlight(tmp_path):
    frames = unknotting_trefoil_frames(6)
    path = write_case(tmp_path / "k.h5", frames)
    n = frames.shape[1]
    mat = np.full((n, n), np.nan)
    mat[0, n - 1] = 1.0
    mat[5, 40] = 0.9                              # the shortest knotted subchain
    mat[6, 20] = 0.2
    fixture.write_knot_matrix(path, 2, mat, 10, 10, 2.0)
    case = io.read_case(path)
    assert movie.knot_cores(case) == {2: (5, 40)}
    mf = movie.MovieFigure(case, range(6), cores=movie.knot_cores(case), width=320, height=200)
    try:
        assert mf.core_at(1) is None and mf.core_at(2) == (5, 40, 2) and mf.core_at(5)
        mf.draw(1)
        assert len(mf.core.get_data_3d()[0]) == 0
        mf.draw(4)
        r = case.positions[4] - case.positions[4].mean(axis=0)
        assert np.allclose(np.array(mf.core.get_data_3d()).T, r[5:41])
        assert "knot core: beads 5-40 (knot matrix of frame 2)" in mf.title.get_text()
    finally:
        mf.close()
    out = movie.render_movie(case, tmp_path / "k.gif", frames=[1, 3], width=160, height=120,
                             knot_core=True, progress=False)
    assert os.path.getsize(out) > 1000


def test_report_survives_a_failing_movie(tmp_path, monkeypatch, capsys):
    from knotflow_tools import report
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    write_case(sweep / "f.h5", unknotting_trefoil_frames(3))

    def broken(*args, **kwargs):
        raise RuntimeError("ffmpeg exploded")

    monkeypatch.setattr(movie, "render_movie", broken)
    res = report.build_report(str(sweep), closures=5, viewer=False)
    assert not any("movie" in f for f in res["rows"][0]["figures"])
    assert "movie of f not written: ffmpeg exploded" in capsys.readouterr().err
