"""Regression checks of the knotflow-analyze command line (coordinate-file mode).

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
                       (['--bogus'], '--bogus'), (['--seed'], '--seed')]:
        p = run(exe, chain, *args)
        lines = p.stderr.strip().splitlines()
        assert p.returncode != 0 and len(lines) == 1 and word in lines[0], (args, p.stderr)
    p = run(exe, os.path.join(work, 'missing.xyz'))
    assert p.returncode != 0 and 'missing.xyz' in p.stderr
    print('knotflow-analyze CLI checks passed')


if __name__ == '__main__':
    main()
