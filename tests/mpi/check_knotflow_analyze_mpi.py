"""knotflow-analyze with 2 MPI ranks gives exactly the 1-rank results (coordinate file with a knot
matrix, and a case file).

usage: check_knotflow_analyze_mpi.py <knotflow-analyze> <work dir> <mpiexec> [mpiexec flags...]
"""
import json
import math
import os
import shutil
import subprocess
import sys


def main():
    exe, work, mpiexec, flags = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
    os.makedirs(work, exist_ok=True)
    chain = os.path.join(work, 'trefoil.xyz')
    with open(chain, 'w') as f:
        for i in range(1, 50):
            t = 2 * math.pi * i / 50
            f.write('%r %r %r\n' % ((2 + math.cos(3 * t)) * math.cos(2 * t),
                                    (2 + math.cos(3 * t)) * math.sin(2 * t), math.sin(3 * t)))
    args = [chain, '--matrix', '--matrix-closures', '10', '--min-length', '12', '--closures', '100', '--json']
    serial = subprocess.run([exe, *args], capture_output=True, text=True, timeout=300)
    par = subprocess.run([mpiexec, *flags, '-n', '2', exe, *args], capture_output=True, text=True, timeout=300)
    assert serial.returncode == 0 and par.returncode == 0, (serial.stderr, par.stderr)
    a, b = json.loads(serial.stdout), json.loads(par.stdout)
    assert a == b, 'serial and 2-rank JSON differ'
    assert a['knot_core'] is not None
    try:
        import h5py
        import numpy as np
    except ImportError:
        print('h5py not available: case-file check skipped')
        return
    p1, p2 = os.path.join(work, 'c1.h5'), os.path.join(work, 'c2.h5')
    pos = np.array([[[math.cos(0.4 * i + 0.2 * k), math.sin(0.4 * i), 0.15 * i] for i in range(40)]
                    for k in range(5)])
    with h5py.File(p1, 'w') as f:
        f.create_dataset('frames/time', data=np.arange(5) * 1.0, maxshape=(None,), chunks=True)
        f.create_dataset('frames/positions', data=pos, maxshape=(None, 40, 3), chunks=True)
    shutil.copy(p1, p2)
    args = ['--closures', '50', '--matrix-frames', '0,last', '--matrix-closures', '5', '--min-length', '10']
    r1 = subprocess.run([exe, p1, *args], capture_output=True, text=True, timeout=300)
    r2 = subprocess.run([mpiexec, *flags, '-n', '2', exe, p2, *args], capture_output=True, text=True, timeout=300)
    assert r1.returncode == 0 and r2.returncode == 0, (r1.stderr, r2.stderr)
    with h5py.File(p1) as f, h5py.File(p2) as g:
        for name in ['analysis/knots/kf', 'analysis/knots/spectrum', 'analysis/knot_matrix/frame_0',
                     'analysis/knot_matrix/frame_4', 'analysis/shape/mode']:
            assert np.array_equal(f[name][:], g[name][:], equal_nan=True), name
    print('knotflow-analyze: 2 ranks reproduce 1 rank')


if __name__ == '__main__':
    main()
