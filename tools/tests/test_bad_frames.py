"""Non-finite and damaged frames: an error naming the file, the frame (or dataset) and the
cause in every tool, never a wrong result (a NaN frame used to give k_f = 1.0)."""

import h5py
import numpy as np
import pytest

from knotflow_tools import cli, io, knots
from knotflow_tools.report import build_report

from conftest import unknotting_trefoil_frames, write_case
from helpers import open_trefoil


def nan_case(path, frame=2, nframes=5):
    frames = unknotting_trefoil_frames(nframes)
    frames[frame, 10, 1] = np.nan
    return str(write_case(path, frames, observables=False))


def test_read_case_names_the_nan_frame(tmp_path):
    path = nan_case(tmp_path / "nan.h5")
    with pytest.raises(ValueError, match=r"nan\.h5: frame 2 \(t = 2\): 1 non-finite coordinates"):
        io.read_case(path)


def test_kf_tool_refuses_a_nan_frame(tmp_path, capsys):
    path = nan_case(tmp_path / "nan.h5", frame=4)
    assert cli.main_kf([path, "--closures", "10"]) == 2
    err = capsys.readouterr().err
    assert "knotflow-kf: error: " in err and "nan.h5: frame 4" in err and "non-finite" in err


def test_kf_tool_refuses_nan_in_a_text_file(tmp_path, capsys):
    r = open_trefoil()
    p = tmp_path / "chain.xyz"
    io.write_xyz(p, r)
    lines = p.read_text().splitlines()
    lines[5] = "1.0 nan 2.0"
    p.write_text("\n".join(lines) + "\n")
    assert cli.main_kf([str(p), "--closures", "10"]) == 2
    err = capsys.readouterr().err
    # 'nan' is no number of a coordinate file (docs/inputs.md); 1e999 is one, but not finite
    assert "chain.xyz:6: not a number: item 2 'nan'" in err
    lines[5] = "1.0 2.0 1e999"
    p.write_text("\n".join(lines) + "\n")
    assert cli.main_kf([str(p), "--closures", "10"]) == 2
    err = capsys.readouterr().err
    assert "chain.xyz:6: non-finite coordinate" in err


def test_analyze_chain_refuses_nan():
    r = open_trefoil()
    r[7, 2] = np.inf
    with pytest.raises(ValueError, match="non-finite coordinates \\(first at bead 7\\)"):
        knots.analyze_chain(r, closures=5)


def test_damaged_data_is_an_error(tmp_path):
    path = tmp_path / "damaged.h5"
    frames = unknotting_trefoil_frames(6)
    write_case(path, frames)
    with h5py.File(path, "a") as f:            # as knotflow writes it: Fletcher-32 chunks
        del f["frames/positions"]
        f["frames"].create_dataset("positions", data=frames, maxshape=(None,) + frames.shape[1:],
                                   chunks=(2,) + frames.shape[1:], fletcher32=True)
        info = f["frames/positions"].id.get_chunk_info(1)
    with open(path, "r+b") as fh:
        fh.seek(info.byte_offset + 40)
        fh.write(b"\xff" * 8)
    with pytest.raises(ValueError, match=r"damaged\.h5: /frames/positions: cannot read \(damaged data"):
        io.read_case(str(path))


def test_plot_tool_refuses_a_nan_frame(tmp_path, capsys):
    path = nan_case(tmp_path / "nan.h5")
    assert cli.main_plot([path, "--out", str(tmp_path / "plots")]) == 2
    assert "nan.h5: frame 2" in capsys.readouterr().err


def test_report_lists_the_bad_file_and_reports_the_good(tmp_path):
    write_case(tmp_path / "good.h5", unknotting_trefoil_frames(4))
    nan_case(tmp_path / "bad.h5")
    res = build_report(str(tmp_path), closures=10)
    with open(res["md"], encoding="utf-8") as fh:
        md = fh.read()
    assert "good" in md
    assert "unreadable" in md and "frame 2" in md


def test_stress_and_study_tools_refuse_a_nan_frame(tmp_path, capsys):
    path = nan_case(tmp_path / "nan.h5")
    assert cli.main_stress_summary([path]) == 2
    assert "nan.h5: frame 2" in capsys.readouterr().err
    assert cli.main_study(["--write-frame", path, "0", str(tmp_path / "f.xyz")]) == 2
    assert "knotflow-study: error: " in capsys.readouterr().err
