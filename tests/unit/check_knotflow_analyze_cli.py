"""Regression checks of the knotflow-analyze command line (coordinate-file mode; the case mode
of a table of frame rows, by the rule of docs/analysis.md "Modes").

usage: check_knotflow_analyze_cli.py <knotflow-analyze executable> <work dir>
"""
import json
import math
import os
import subprocess
import sys


def run(exe, *args):
    return subprocess.run([exe, *args], capture_output=True, text=True, timeout=120)


def main():
    exe, work = sys.argv[1], sys.argv[2]
    os.makedirs(work, exist_ok=True)
    chain = os.path.join(work, 'trefoil.xyz')
    pts = os.path.join(work, 'points.xyz')
    # an open torus trefoil, opened at its outermost point (t = 0)
    with open(chain, 'w') as f:
        f.write('# open torus trefoil\n\n')
        for i in range(1, 120):
            t = 2 * math.pi * i / 120
            f.write('%r %r %r\n' % ((2 + math.cos(3 * t)) * math.cos(2 * t),
                                    (2 + math.cos(3 * t)) * math.sin(2 * t), math.sin(3 * t)))
    # closure points far out in +x: the closure triangle meets no strand, so each is a trefoil
    with open(pts, 'w') as f:
        for k in range(5):
            f.write('%r %r %r\n' % (30.0, -3.0 + 1.5 * k, 0.5 * k - 1.0))
    p = run(exe, chain, '--closure-points', pts, '--json', '--per-closure')
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert d['n_beads'] == 119 and d['closures'] == 5, d
    assert d['per_closure'] == ['3_1'] * 5, d['per_closure']
    assert d['kf'] == 1.0 and d['dominant'] == '3_1' and d['knot_core'] is None
    p = run(exe, chain, '--closures', '300', '--seed', '5', '--json')
    d = json.loads(p.stdout)
    assert abs(sum(d['spectrum'].values()) - 1) < 1e-12 and d['seed'] == 5 and d['closures'] == 300
    assert abs(d['kf'] - (1 - d['spectrum']['0_1'])) < 1e-12
    assert run(exe, chain, '--closures', '300', '--seed', '5', '--json').stdout == p.stdout
    # bad input: one error line, non-zero exit
    for args, word in [(['--closures', 'x'], '--closures'), (['--min-length', '1'], '--min-length'),
                       (['--bogus'], '--bogus'), (['--seed'], '--seed'), (['--stride', '2'], '--stride')]:
        p = run(exe, chain, *args)
        lines = p.stderr.strip().splitlines()
        assert p.returncode != 0 and len(lines) == 1 and word in lines[0], (args, p.stderr)
    p = run(exe, os.path.join(work, 'missing.xyz'))
    assert p.returncode != 0 and 'missing.xyz' in p.stderr
    check_case_file(exe, work)
    print('knotflow-analyze CLI checks passed')


def check_case_file(exe, work):
    """A case file written with h5py: /analysis follows the schema, the trajectory is untouched,
    a rerun resumes, bad input leaves /analysis as it was."""
    try:
        import h5py
        import numpy as np
    except ImportError:
        print('h5py not available: case-file checks skipped')
        return
    path = os.path.join(work, 'case.h5')
    nf, n = 6, 59
    pos = np.zeros((nf, n, 3))
    for k in range(nf):
        for i in range(n):
            t = 2 * math.pi * (i + 1) / 60
            c, s = math.cos(0.3 * k), math.sin(0.3 * k)
            x, y, z = (2 + math.cos(3 * t)) * math.cos(2 * t), (2 + math.cos(3 * t)) * math.sin(2 * t), math.sin(3 * t)
            pos[k, i] = (c * x - s * y, s * x + c * y, z)
    pos[3] = [[1.02 * i, 0.1 * math.sin(i), 0.0] for i in range(n)]   # an unknotted frame
    with h5py.File(path, 'w') as f:
        f.attrs['status'] = 'finished'
        f.create_dataset('frames/time', data=np.arange(nf) * 0.5, maxshape=(None,), chunks=True)
        f.create_dataset('frames/positions', data=pos, maxshape=(None, n, 3), chunks=True)
    args = ['--closures', '60', '--matrix-frames', 'last', '--matrix-closures', '5', '--min-length', '20']
    p = run(exe, path, *args)
    assert p.returncode == 0, p.stderr
    assert '6 new' in p.stdout, p.stdout
    with h5py.File(path) as f:
        assert np.array_equal(f['frames/positions'][:], pos)
        kn = f['analysis/knots']
        assert list(kn['frame_index'][:]) == list(range(nf)) and kn.attrs['closures'] == 60
        assert kn['spectrum'].shape == (nf, 10)
        assert [x.decode() for x in kn['spectrum'].attrs['types']] == \
            '0_1 3_1 4_1 5_1 5_2 6_1 6_2 6_3 7_1 other'.split()
        kf = kn['kf'][:]
        assert kf[3] == 0.0 and min(kf[[0, 1, 2, 4, 5]]) > 0.8, kf
        assert [x.decode() for x in f['analysis/events/kind'][:]] == ['unknot', 'knot']
        assert list(f['analysis/events/frame_index'][:]) == [3, 4]
        km = f['analysis/knot_matrix/frame_5']
        assert km.shape == (n, n) and km.attrs['min_length'] == 20
        assert np.isnan(km[5, 0]) and np.isnan(km[0, 10]) and not np.isnan(km[0, 58])
        assert f['analysis/shape/mode'].shape == (nf,)
    p = run(exe, path, *args)
    assert p.returncode == 0 and '0 new' in p.stdout, p.stdout
    p = run(exe, path, '--json')
    assert p.returncode != 0 and '--json' in p.stderr
    p = run(exe, path, '--matrix-frames', '99')
    assert p.returncode != 0 and '--matrix-frames' in p.stderr and len(p.stderr.strip().splitlines()) == 1
    with h5py.File(path) as f:
        assert 'analysis/knots/kf' in f and 'analysis/knot_matrix/frame_5' in f
    check_python_reads(path)
    check_mode_two(exe, work)
    check_bad_frames(exe, work, pos)
    check_reuse(exe, work, pos)
    for opt in ('--help', '--version'):
        p = run(exe, opt)
        assert p.returncode == 0 and 'knotflow-analyze' in p.stdout and 'Backtrace' not in p.stderr, (opt, p)


def check_python_reads(path):
    """The Python tools read /analysis as knotflow-analyze wrote it (and write nothing)."""
    import h5py
    import numpy as np
    from knotflow_tools import analysis, io
    with open(path, 'rb') as fh:
        before = fh.read()
    case = io.read_case(path)
    ana = analysis.analyze_case(case)
    with h5py.File(path, 'r') as f:
        g = f['analysis']
        assert ana.kf_source == 'stored'
        assert np.array_equal(ana.kf, g['knots/kf'][:]) and np.array_equal(ana.frame_index, g['knots/frame_index'][:])
        assert ana.dominant == [x.decode() for x in g['knots/dominant'][:]]
        assert [(e.kind, e.index, e.time) for e in ana.events] == \
            [(k.decode(), int(i), float(t)) for k, i, t in zip(g['events/kind'][:], g['events/frame_index'][:],
                                                            g['events/time'][:])]
        assert np.array_equal(ana.modes, g['shape/mode'][:]) and ana.case_mode == g['shape'].attrs['case_mode']
        assert np.array_equal(ana.knot_matrices[5], g['knot_matrix/frame_5'][:], equal_nan=True)
    with open(path, 'rb') as fh:
        assert fh.read() == before, 'the Python tools changed the case file'


def check_mode_two(exe, work):
    """A flat arc 40 long along the flow x and 2 high along the gradient z (beads about 1.03
    apart), drifting in z: mode II in every frame and as a case, as knotflow-analyze writes it
    and the Python tools read it."""
    import h5py
    import numpy as np
    from knotflow_tools import analysis, io
    path = os.path.join(work, 'arc.h5')
    x = np.linspace(-20.0, 20.0, 40)
    pos = np.array([np.stack([x, 0 * x, 2 * (1 - (x / 20) ** 2) + 0.1 * k], axis=1) for k in range(8)])
    with h5py.File(path, 'w') as f:
        f.attrs['status'] = 'finished'
        f.create_dataset('frames/time', data=np.arange(8.0))
        f.create_dataset('frames/positions', data=pos)
    p = run(exe, path, '--closures', '20')
    assert p.returncode == 0, p.stderr
    with h5py.File(path, 'r') as f:
        assert list(f['analysis/shape/mode'][:]) == [2] * 8 and f['analysis/shape'].attrs['case_mode'] == 2
    ana = analysis.analyze_case(io.read_case(path))
    assert list(ana.modes) == [2] * 8 and ana.case_mode == 2


def check_bad_frames(exe, work, pos):
    """A frame holding NaN, and damaged data (a Fletcher-32 chunk that fails its checksum): one
    error line naming the file, the frame or dataset and the cause, non-zero exit status, and
    no /analysis written."""
    import h5py
    import numpy as np
    nf, n = pos.shape[:2]
    bad = pos.copy()
    bad[4, 10, 2] = np.nan
    path = os.path.join(work, 'nan.h5')
    with h5py.File(path, 'w') as f:
        f.attrs['status'] = 'finished'
        f.create_dataset('frames/time', data=np.arange(nf) * 0.5, maxshape=(None,), chunks=True)
        f.create_dataset('frames/positions', data=bad, maxshape=(None, n, 3), chunks=True)
    p = run(exe, path, '--closures', '10')
    lines = p.stderr.strip().splitlines()
    assert p.returncode != 0 and len(lines) == 1, p.stderr
    assert "nan.h5': frame 4 (t = 2.00000) holds 1 non-finite coordinates" in lines[0], lines[0]
    with h5py.File(path) as f:
        assert 'analysis' not in f
    path = os.path.join(work, 'damaged.h5')
    with h5py.File(path, 'w') as f:
        f.attrs['status'] = 'finished'
        f.create_dataset('frames/time', data=np.arange(nf) * 0.5, maxshape=(None,), chunks=True)
        f.create_dataset('frames/positions', data=pos, maxshape=(None, n, 3), chunks=(2, n, 3),
                         fletcher32=True)
        info = f['frames/positions'].id.get_chunk_info(1)
    with open(path, 'r+b') as fh:
        fh.seek(info.byte_offset + 100)
        fh.write(b'\x7f' * 8)
    p = run(exe, path, '--closures', '10')
    lines = p.stderr.strip().splitlines()
    assert p.returncode != 0 and len(lines) == 1, p.stderr
    assert "/frames/positions" in lines[0] and 'damaged.h5' in lines[0] and 'checksum mismatch' in lines[0], lines[0]


def check_reuse(exe, work, pos):
    """--reuse OLD.h5 (an earlier copy of the case file): k_f of the frames whose time and
    positions are the same in both is taken from OLD, every other frame is computed, and the
    result is the one of an analysis from scratch, bit for bit. OLD's frame 2 is another chain
    (unknotted, where the file's is a trefoil) and its frame 3 has another time: only frames 0
    and 1 are taken. Other closures take nothing; bad usage is refused before anything is
    written."""
    import shutil
    import h5py
    import numpy as np

    def case(path, times, frames):
        with h5py.File(path, 'w') as f:
            f.attrs['status'] = 'running'
            f.create_dataset('frames/time', data=times, maxshape=(None,), chunks=True)
            f.create_dataset('frames/positions', data=frames, maxshape=(None,) + frames.shape[1:], chunks=True)

    nf = pos.shape[0]
    times = np.arange(nf) * 0.5
    old_pos = pos[:4].copy()
    old_pos[2] = pos[3]
    old_times = times[:4].copy()
    old_times[3] += 0.1
    old, new, scratch = (os.path.join(work, f'{x}.h5') for x in ('reuse_old', 'reuse_new', 'reuse_scratch'))
    case(old, old_times, old_pos)
    case(new, times, pos)
    shutil.copy(new, scratch)
    assert run(exe, old, '--closures', '60').returncode == 0
    with h5py.File(old, 'r') as f:
        old_kf = f['analysis/knots/kf'][:]
    p = run(exe, scratch, '--closures', '60')
    assert p.returncode == 0, p.stderr
    with h5py.File(scratch, 'r') as f:
        want = {k: f['analysis/knots/' + k][:] for k in ('kf', 'spectrum', 'frame_index')}
    assert old_kf[2] == 0.0 and want['kf'][2] > 0.8, (old_kf, want['kf'])   # frame 2 differs
    for bad_args, word in [(['--reuse', old, '--force'], '--force'),
                           (['--reuse', os.path.join(work, 'absent.h5')], 'absent.h5'),
                           (['--reuse', new], '--reuse'),
                           (['--reuse', old, scratch], 'one case file')]:
        p = run(exe, new, '--closures', '60', *bad_args)
        lines = p.stderr.strip().splitlines()
        assert p.returncode == 2 and len(lines) == 1 and word in lines[0], (bad_args, p.stderr)
    with h5py.File(new, 'r') as f:
        assert 'analysis' not in f
    p = run(exe, new, '--closures', '60', '--reuse', old)
    assert p.returncode == 0, p.stderr
    assert f'{nf} frames ({nf - 2} new)' in p.stdout and 'k_f of 2 frame(s) taken from' in p.stdout, p.stdout
    with h5py.File(new, 'r') as f:
        for k, v in want.items():
            assert np.array_equal(f['analysis/knots/' + k][:], v), (k, f['analysis/knots/' + k][:], v)
    os.remove(new)
    case(new, times, pos)
    p = run(exe, new, '--closures', '50', '--reuse', old)
    assert p.returncode == 0 and f'({nf} new)' in p.stdout and 'k_f of 0 frame(s)' in p.stdout, p.stdout


def check_case_mode_table(exe, work):
    """The case mode of frame rows (a case ledger's CSV): only the second half of the frames
    counts; at least half of them (integer half) must be classified; the more frequent mode wins,
    I on a tie; mode I only if phi, unwrapped, ends higher than it starts over that half."""
    header = "t,kf,rg,mode,close_pairs,phi"

    def table(name, modes, phis, extra=None):
        path = os.path.join(work, name + ".csv")
        with open(path, "w") as f:
            f.write(header + "\n")
            for k, (m, p) in enumerate(zip(modes, phis)):
                f.write(f"{k},nan,3.5,{m},4,{p!r}\n")
            if extra:
                f.write(extra)
        return path

    up = [0.3 * k for k in range(10)]
    down = [-x for x in up]
    cases = [("rolling", [1] * 10, up, 1), ("against_shear", [1] * 10, down, 0),
             ("tumbling", [0] * 5 + [2] * 5, [1.5] * 10, 2),
             ("too_few", [0] * 8 + [1, 0], up, 0), ("tie", [0] * 6 + [1, 2, 1, 2], up, 1),
             ("early_only", [2] * 5 + [0] * 5, [1.5] * 10, 0),
             ("wrapped", [1] * 10, [(0.9 * k + math.pi) % (2 * math.pi) - math.pi for k in range(10)], 1)]
    for name, modes, phis, expected in cases:
        p = run(exe, table(name, modes, phis), "--json")
        assert p.returncode == 0, (name, p.stderr)
        d = json.loads(p.stdout)
        assert d["case_mode"] == expected and d["frames"] == 10, (name, d)
    for name, extra, text in (("nan_mode", "10,nan,3.5,nan,4,0.1\n", "row 11: mode NaN"),
                              ("mode_3", "10,nan,3.5,3,4,0.1\n", "allowed: mode 0, 1 or 2"),
                              ("short_row", "10,nan,3.5,1\n", "line 12: 4 fields, the header has 6"),
                              ("not_number", "10,nan,3.5,1,4,x\n", "column 'phi': 'x' is not a number")):
        p = run(exe, table(name, [1] * 10, up, extra))
        lines = p.stderr.strip().splitlines()
        assert p.returncode == 2 and len(lines) == 1 and text in lines[0], (name, p.stderr)
    path = os.path.join(work, "no_phi.csv")
    with open(path, "w") as f:
        f.write("t,mode\n0,1\n")
    p = run(exe, path)
    assert p.returncode == 2 and "no column 'phi'" in p.stderr, p.stderr
    p = run(exe, table("extra_option", [1] * 10, up), "--stride", "2")
    assert p.returncode == 2 and "read alone" in p.stderr, p.stderr
    p = run(exe, table("counts", [0] * 4 + [2] * 2 + [1] * 4, up), "--json")
    d = json.loads(p.stdout)
    assert d["mode_frames"] == [4, 4, 2] and d["late_mode_frames"] == [0, 4, 1], d


def check_elongation(exe, work):
    """--elongation: the frame modes classified again from the shape columns with another a/b
    threshold. A coil along the vorticity (theta 0.2, 5 close pairs) with a = 2 b and phi rising
    is mode I from a threshold of 2 down and no mode above; its stored mode column (all 0) is
    then ignored. The finished candy-canes of the committed case ledger classified again with
    the rule's own threshold 3 from their rows (7 digits) give the modes knotflow-analyze stored
    from the full-precision case files (the mode column)."""
    path = os.path.join(work, "coil.csv")
    with open(path, "w") as f:
        f.write("t,a,b,c,theta,phi,close_pairs,mode\n")
        for k in range(10):
            f.write(f"{k},4,2,0.9,0.2,{0.3 * k!r},5,0\n")
    for value, case, frames in (("1.5", 1, [0, 10, 0]), ("2", 1, [0, 10, 0]), ("2.01", 0, [10, 0, 0]),
                                ("3", 0, [10, 0, 0])):
        p = run(exe, path, "--elongation", value, "--json")
        assert p.returncode == 0, (value, p.stderr)
        d = json.loads(p.stdout)
        assert d["case_mode"] == case and d["mode_frames"] == frames and float(d["elongation"]) == float(value), d
    p = run(exe, path, "--elongation", "1.5")
    assert "case mode 1" in p.stdout and "classified again with a/b >= 1.5" in p.stdout, p.stdout
    for value in ("0.99", "nan", "inf", "x", "-2"):
        p = run(exe, path, "--elongation", value)
        lines = p.stderr.strip().splitlines()
        assert p.returncode == 2 and len(lines) == 1 and f'--elongation: invalid value "{value}"' in lines[0] \
            and "a number >= 1" in lines[0], (value, p.stderr)
    bad = os.path.join(work, "coil_bad.csv")
    for name, row, text in (("nan", "10,4,2,nan,0.2,0.1,5,0", "c NaN"),
                            ("negative", "10,4,-2,0.9,0.2,0.1,5,0", "b -2.0"),
                            ("fraction", "10,4,2,0.9,0.2,0.1,2.5,0", "close_pairs 2.5")):
        with open(path) as f, open(bad, "w") as g:
            g.write(f.read() + row + "\n")
        p = run(exe, bad, "--elongation", "2")
        lines = p.stderr.strip().splitlines()
        assert p.returncode == 2 and len(lines) == 1 and "row 11" in lines[0] and text in lines[0] \
            and "close_pairs a whole number >= 0" in lines[0], (name, p.stderr)
    with open(os.path.join(work, "chain.xyz"), "w") as f:
        f.write("0 0 0\n1 0 0\n2 0 0\n")
    p = run(exe, os.path.join(work, "chain.xyz"), "--elongation", "2")
    assert p.returncode == 2 and "applies to a table of frame rows" in p.stderr, p.stderr
    ledger = os.path.join(os.path.dirname(__file__), "..", "..", "docs", "reproduction_multipole", "ledger")
    for case in ("candycane_multipole/A1.00", "candycane_multipole/A1.40", "candycane_seeds_multipole/A1.00_s1",
                 "candycane_seeds_multipole/A1.00_s2", "candycane_epslub_multipole/A1.00"):
        rows = os.path.join(ledger, case + ".csv")
        with open(rows) as f:
            header = f.readline().strip().split(",")
            stored = [int(float(line.split(",")[header.index("mode")])) for line in f]
        p = run(exe, rows, "--elongation", "3", "--json")
        assert p.returncode == 0, (case, p.stderr)
        d = json.loads(p.stdout)
        late = stored[len(stored) // 2:]
        assert d["frames"] == len(stored) == 2001, (case, d)
        assert d["mode_frames"] == [stored.count(m) for m in range(3)], (case, d)
        assert d["late_mode_frames"] == [late.count(m) for m in range(3)], (case, d)


if __name__ == '__main__':
    main()
    check_case_mode_table(sys.argv[1], sys.argv[2])
    check_elongation(sys.argv[1], sys.argv[2])
