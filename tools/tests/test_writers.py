"""The tools' writers (issue 37): names from files are data, never paths (knotflow-campaign
digest, B); every file is written whole or not at all and never through a planted link (A, E):
knotflow_tools.atomic, knotflow-xdmf, knotflow-report and knotflow-movie on a full disk; a
damaged /analysis is an error, not an absent analysis (D)."""

import contextlib
import os
import shutil
import subprocess

import h5py
import numpy as np
import pytest

from knotflow_tools import atomic, campaign, cli, io, names, xdmf

from conftest import unknotting_trefoil_frames, write_case

NAMES_FILE = os.path.join(os.path.dirname(__file__), "..", "..", "tests", "data", "case_names.txt")


def _bytes(path):
    with open(path, "rb") as fh:
        return fh.read()


def _shared_names():
    with open(NAMES_FILE, encoding="utf-8") as fh:
        rows = [line.rstrip("\n").split(" ", 1) for line in fh if line.strip() and line[0] != "#"]
    return [(verdict, name) for verdict, name in rows]


@pytest.mark.parametrize("verdict,name", _shared_names())
def test_case_name_rule_shared_with_fortran(verdict, name):
    """The list the Fortran rule (tests/unit/test_case_names.pf) is tested against."""
    assert verdict in ("good", "bad")
    assert (names.case_name_problem(name) is None) == (verdict == "good"), name


def test_case_name_reasons_in_the_fortran_words():
    assert names.case_name_problem("x" * 101) == "longer than 100 characters"
    assert names.case_name_problem("..") == "it starts with '.'"
    assert names.case_name_problem("a/b") == "the character '/' at position 2"
    assert names.case_name_problem("") == "an empty name"


def _analysed_case(path, case_name):
    p = write_case(path, unknotting_trefoil_frames(4), attrs={"case_name": case_name})
    with h5py.File(p, "r+") as f:
        g = f.create_group("analysis/knots")
        g.attrs["closures"] = np.int64(10)
        g["frame_index"] = np.arange(4, dtype=np.int64)
        g["time"] = np.arange(4.0)
        g["kf"] = np.array([0.9, 0.5, 0.1, 0.0])
    return str(p)


@pytest.mark.parametrize("bad", ["../../escaped", "/tmp/knotflow_escaped_abs", "..", ".hidden"])
def test_digest_takes_no_path_from_a_case_name(tmp_path, bad):
    """A case file whose case_name attribute is a path or a hidden name is refused, and nothing
    is written (before: owned.csv/owned.json written wherever the name pointed, exit 0)."""
    ledger = tmp_path / "a" / "b" / "ledger"
    path = _analysed_case(tmp_path / "c.h5", bad)
    with pytest.raises(ValueError, match="case name .* refused"):
        campaign.digest(path, str(ledger), "cc", 10)
    assert not (tmp_path / "a").exists()
    assert not os.path.exists("/tmp/knotflow_escaped_abs.json")


def test_atomic_write_replaces_a_link(tmp_path):
    victim = tmp_path / "victim"
    victim.write_text("VICTIM")
    for name in ("out.txt", "fig.png"):
        (tmp_path / name).symlink_to(victim)
    atomic.write_text(str(tmp_path / "out.txt"), "new")
    assert victim.read_text() == "VICTIM"
    assert not (tmp_path / "out.txt").is_symlink() and (tmp_path / "out.txt").read_text() == "new"
    import matplotlib.pyplot as plt
    fig = plt.figure()
    atomic.save_figure(fig, str(tmp_path / "fig.png"), dpi=20)
    plt.close(fig)
    assert victim.read_text() == "VICTIM"
    assert (tmp_path / "fig.png").read_bytes()[:4] == b"\x89PNG"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.png", "out.txt", "victim"]


def test_xdmf_replaces_links(tmp_path):
    """knotflow-xdmf wrote '<case>.xdmf2.tmp<pid>', a name known in advance, and followed a link
    planted there."""
    case = write_case(tmp_path / "c.h5", unknotting_trefoil_frames(3))
    victim = tmp_path / "victim"
    victim.write_text("VICTIM")
    out = xdmf.xdmf_path(str(case))
    os.symlink(victim, out)
    os.symlink(victim, f"{out}.tmp{os.getpid()}")
    assert xdmf.write_xdmf(str(case)) == out
    assert victim.read_text() == "VICTIM"
    assert not os.path.islink(out) and b"<Xdmf" in _bytes(out)


@pytest.fixture
def full_disk(tmp_path):
    """A directory on a 256 kB tmpfs (mounted as root only), and a function that fills it."""
    mount = tmp_path / "full"
    mount.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs",
                                            str(mount)], capture_output=True).returncode != 0:
        pytest.skip("a full disk needs a tmpfs, which only root can mount")

    def fill():
        fd = os.open(mount / "filler", os.O_WRONLY | os.O_CREAT)
        with contextlib.suppress(OSError):
            while True:
                os.write(fd, b"\0" * 1024)
        os.close(fd)

    try:
        yield mount, fill
    finally:
        subprocess.run(["umount", str(mount)], check=False)


def _leftovers(directory):
    return [n for _, _, files in os.walk(directory) for n in files if ".tmp" in n]


def test_full_disk_keeps_old_files(full_disk, tmp_path, capsys):
    mount, fill = full_disk
    case = str(write_case(mount / "c.h5", unknotting_trefoil_frames(4)))
    old_text = mount / "kept.txt"
    atomic.write_text(str(old_text), "old content\n")
    assert xdmf.write_xdmf(case) == xdmf.xdmf_path(case)
    old_xdmf = _bytes(xdmf.xdmf_path(case))
    fill()
    with pytest.raises(atomic.WriteError, match=f"cannot write {old_text}: No space left on device"):
        atomic.write_text(str(old_text), "new content " * 1000)
    assert old_text.read_text() == "old content\n"
    # knotflow-xdmf: one error line naming the file and the reason, the old file kept
    capsys.readouterr()
    assert cli.main_xdmf([case]) == cli.EXIT_USAGE
    err = capsys.readouterr().err
    assert err.strip() == (f"knotflow-xdmf: error: {case}: cannot write {xdmf.xdmf_path(case)}: "
                           "No space left on device"), err
    assert _bytes(xdmf.xdmf_path(case)) == old_xdmf
    assert _leftovers(mount) == []


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg not installed: MP4 not tested")
def test_movie_on_a_full_disk(full_disk, capsys):
    """knotflow-movie on a full disk: one error line naming the movie and ffmpeg's reason, exit
    status 2, no 0-byte .mp4 and no temporary file (before: a 47-line traceback, a 0-byte .mp4)."""
    mount, fill = full_disk
    case = str(write_case(mount / "m.h5", unknotting_trefoil_frames(4)))
    fill()
    out = mount / "m.mp4"
    capsys.readouterr()
    assert cli.main_movie([case, "--out", str(out)]) == cli.EXIT_USAGE
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert lines[-1] == (f"knotflow-movie: error: cannot write {out}: No space left on device "
                         "(ffmpeg, exit status 1)"), err[-2000:]
    assert not out.exists()
    assert _leftovers(mount) == []


def test_report_on_a_full_disk(full_disk, capsys):
    mount, fill = full_disk
    sweep = mount / "sweep"
    sweep.mkdir()
    write_case(sweep / "c.h5", unknotting_trefoil_frames(4))
    fill()
    capsys.readouterr()
    assert cli.main_report([str(sweep), "--no-movie", "--closures", "5"]) == cli.EXIT_USAGE
    err = capsys.readouterr().err
    assert "error: cannot write " + str(sweep) in err and "No space left on device" in err, err
    assert _leftovers(mount) == []
    assert not (sweep / "report").exists() or any((sweep / "report").rglob("*"))


def test_damaged_analysis_is_not_taken_for_none(tmp_path):
    """An /analysis whose object header is damaged (a kill of an old knotflow-analyze while it
    wrote) made h5py's get() return None: the tools then said 'not analysed'."""
    path = _analysed_case(tmp_path / "d.h5", "d")
    with h5py.File(path, "r") as f:
        addr = h5py.h5o.get_info(f["analysis"].id).addr
    data = bytearray(_bytes(path))
    data[addr:addr + 16] = b"\xff" * 16
    with open(path, "wb") as fh:
        fh.write(bytes(data))
    with pytest.raises(ValueError, match=r"/analysis cannot be read .* knotflow-analyze --force"):
        io.read_case(path)


def test_report_lists_a_hidden_case(tmp_path):
    """A case file named '.hidden.h5' (case_name '.hidden', which knotflow now refuses) was left
    out of the report in silence; now it is listed as refused, beside the good case."""
    from knotflow_tools.report import build_report
    write_case(tmp_path / "c.h5", unknotting_trefoil_frames(4))
    write_case(tmp_path / ".hidden.h5", unknotting_trefoil_frames(4), attrs={"case_name": ".hidden"})
    res = build_report(str(tmp_path), closures=5, movie=False, viewer=False)
    by_file = {r["file"]: r for r in res["rows"]}
    assert sorted(by_file) == [".hidden.h5", "c.h5"]
    assert "case name '.hidden' refused" in by_file[".hidden.h5"]["status"]
    assert by_file["c.h5"]["status"] == "finished"
