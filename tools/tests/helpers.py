"""Constructions of test chains (PHYSICS.md section 5 and classical knot parametrisations)."""

import numpy as np

TREFOIL_SCALE = 3.538436590931158


def resample_closed(curve, s_fine, npts):
    """npts points evenly spaced in arc length around the closed curve sampled at s_fine."""
    pts = curve(s_fine)
    seg = np.linalg.norm(np.diff(np.vstack([pts, pts[:1]]), axis=0), axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    total = cum[-1]
    target = np.arange(npts) * total / npts
    closed = np.vstack([pts, pts[:1]])
    out = np.empty((npts, 3))
    for k in range(3):
        out[:, k] = np.interp(target, cum, closed[:, k])
    return out, total


def open_trefoil(n_remove=99):
    """The open trefoil of PHYSICS.md 5 (orientation a): 100 points, remove one (default last)."""
    def curve(s):
        return np.stack([np.sin(s) + 2 * np.sin(2 * s), np.cos(s) - 2 * np.cos(2 * s),
                         -np.sin(3 * s)], axis=1)
    s = np.linspace(0.0, 2 * np.pi, 200001)[:-1]
    pts, _ = resample_closed(curve, s, 100)
    pts *= TREFOIL_SCALE
    return np.delete(pts, n_remove, axis=0)


def torus_knot(p, q, n=200, R=3.0, r=1.0):
    """Closed (p, q) torus knot polygon with n vertices (2, 3 -> trefoil, 2, 5 -> 5_1)."""
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    rad = R + r * np.cos(q * t)
    return np.stack([rad * np.cos(p * t), rad * np.sin(p * t), r * np.sin(q * t)], axis=1)


def figure_eight(n=200):
    """Closed figure-eight knot 4_1 (a standard parametrisation)."""
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.stack([(2 + np.cos(2 * t)) * np.cos(3 * t), (2 + np.cos(2 * t)) * np.sin(3 * t),
                     np.sin(4 * t)], axis=1)


def knot_5_2(n=300):
    """Closed 5_2 knot: the Lissajous knot with frequencies (3, 2, 7) and phases (0.7, 0.2, 0)."""
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.stack([np.cos(3 * t + 0.7), np.cos(2 * t + 0.2), np.cos(7 * t)], axis=1)


def open_from_closed(poly, gap=1):
    """Open chain obtained by removing ``gap`` consecutive vertices of a closed polygon."""
    return poly[:len(poly) - gap]


def random_walk(n, seed, step=1.0):
    """Freely jointed random walk with n beads."""
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n - 1, 3))
    v *= step / np.linalg.norm(v, axis=1)[:, None]
    return np.vstack([np.zeros(3), np.cumsum(v, axis=0)])


def tailed_trefoil(ntail=10):
    """Trefoil opened at the tip of a lobe (the point of largest distance from the z axis,
    s = pi/3) with straight tails of ntail beads running radially outwards from both ends:
    the knot is deep inside the chain, so nearly every closure is a trefoil."""
    full = open_trefoil(99)      # used as a closed polygon (one bond slightly longer)
    rad = np.hypot(full[:, 0], full[:, 1])
    tip = int(np.argmax(rad))
    chain = np.roll(full, -(tip + 1), axis=0)[:-1]       # tip removed, starts after it
    out = np.array([full[tip, 0], full[tip, 1], 0.0])
    out /= np.linalg.norm(out)
    steps = 1.02 * np.arange(1, ntail + 1)[:, None] * out[None, :]
    tail0 = (chain[0] + steps)[::-1]
    tail1 = chain[-1] + steps
    return np.vstack([tail0, chain, tail1])
