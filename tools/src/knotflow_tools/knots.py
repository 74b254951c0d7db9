"""Knot detection on open chains (PHYSICS.md section 7 and the shared conventions).

Pipeline for one closure: the open chain plus a closure point ``p`` forms a closed polygon
(end -> p -> start); the polygon is simplified by triangle reduction (a vertex is deleted when no
other segment of the closed polygon pierces the triangle it forms with its neighbours), projected
onto a generic random plane, and the Alexander matrix of the diagram is evaluated at t = -1 and
t = -2.  Its determinants are computed exactly with Python integers (Bareiss fraction-free
elimination).  The pair (|Delta(-1)|, odd part of |Delta(-2)|) identifies the knot type.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

KNOT_TYPES = ("0_1", "3_1", "4_1", "5_1", "5_2", "6_1", "6_2", "6_3", "7_1", "other")

#: (|Delta(-1)|, odd part of |Delta(-2)|) -> knot type.
INVARIANT_TABLE = {
    (1, 1): "0_1",
    (3, 7): "3_1",
    (5, 11): "4_1",
    (5, 31): "5_1",
    (7, 1): "5_2",
    (9, 5): "6_1",
    (11, 59): "6_2",
    (13, 67): "6_3",
    (7, 127): "7_1",
}

_TOL_PARAM = 1e-9      # relative tolerance on segment parameters
_TOL_COPLANAR = 1e-12  # relative tolerance on determinants (near-coplanar / near-parallel)
_MAX_PROJECTION_TRIES = 50


# --------------------------------------------------------------------------------------------
# Closure points
# --------------------------------------------------------------------------------------------

def marsaglia_sphere(n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` uniform random unit vectors by Marsaglia's (1972) rejection method."""
    out = np.empty((n, 3))
    filled = 0
    while filled < n:
        m = max(2 * (n - filled), 16)
        x1 = rng.uniform(-1.0, 1.0, m)
        x2 = rng.uniform(-1.0, 1.0, m)
        s = x1 * x1 + x2 * x2
        keep = s < 1.0
        x1, x2, s = x1[keep], x2[keep], s[keep]
        k = min(len(s), n - filled)
        x1, x2, s = x1[:k], x2[:k], s[:k]
        root = np.sqrt(1.0 - s)
        out[filled:filled + k, 0] = 2.0 * x1 * root
        out[filled:filled + k, 1] = 2.0 * x2 * root
        out[filled:filled + k, 2] = 1.0 - 2.0 * s
        filled += k
    return out


def radius_of_gyration(r: np.ndarray) -> float:
    """R_g of the points r (N, 3)."""
    d = r - r.mean(axis=0)
    return float(np.sqrt((d * d).sum(axis=1).mean()))


def closure_points(r: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` closure points uniform on the sphere of radius 10 R_g about the centre of mass."""
    rg = radius_of_gyration(r)
    radius = 10.0 * rg if rg > 0.0 else 1.0
    return r.mean(axis=0) + radius * marsaglia_sphere(n, rng)


# --------------------------------------------------------------------------------------------
# Triangle reduction
# --------------------------------------------------------------------------------------------

def _cross(u, v):
    """Cross product over the last axis (broadcasting), cheaper than numpy.cross."""
    u0, u1, u2 = u[..., 0], u[..., 1], u[..., 2]
    v0, v1, v2 = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0], axis=-1)


def _dot(u, v):
    """Dot product over the last axis (broadcasting)."""
    return u[..., 0] * v[..., 0] + u[..., 1] * v[..., 1] + u[..., 2] * v[..., 2]


def _pierce_matrix(a, b, c, s0, s1, lo, hi):
    """Boolean (nt, ns): does segment s0-s1 meet triangle abc (conservatively)?

    ``lo``/``hi`` (nt, ns) bound the accepted segment parameter; near-coplanar pairs with
    overlapping bounding boxes count as piercing (refusing a deletion is always safe).
    """
    e1 = (b - a)[:, None, :]
    e2 = (c - a)[:, None, :]
    d = (s1 - s0)[None, :, :]
    h = _cross(d, e2)
    det = _dot(e1, h)
    scale = np.sqrt(_dot(e1, e1) * _dot(e2, e2) * _dot(d, d))
    flat = np.abs(det) <= _TOL_COPLANAR * np.maximum(scale, 1e-300)
    safe = np.where(flat, 1.0, det)
    s = s0[None, :, :] - a[:, None, :]
    u = _dot(s, h) / safe
    q = _cross(s, e1)
    v = _dot(d, q) / safe
    t = _dot(e2, q) / safe
    tol = _TOL_PARAM
    hit = (u >= -tol) & (v >= -tol) & (u + v <= 1.0 + tol) & (t >= lo) & (t <= hi) & ~flat
    if flat.any():
        tmin = np.minimum(np.minimum(a, b), c)[:, None, :]
        tmax = np.maximum(np.maximum(a, b), c)[:, None, :]
        smin = np.minimum(s0, s1)[None, :, :]
        smax = np.maximum(s0, s1)[None, :, :]
        ext = (tmax - tmin).max(axis=2, keepdims=True)
        pad = 1e-9 * ext
        box = np.all((smax >= tmin - pad) & (smin <= tmax + pad), axis=2)
        # the two neighbouring segments always touch the triangle at a corner: a flat
        # neighbour is treated as blocking too (conservative)
        hit |= flat & box & (hi >= lo)
    return hit


def reduce_polygon(p: np.ndarray) -> np.ndarray:
    """Triangle reduction of the closed polygon p (M, 3) (vertex M-1 joined to vertex 0).

    Vertices are tested in batches of pairwise non-adjacent candidates; accepted deletions are
    then applied in order, each checked against the shortcut segments created before it, so
    that the result is a sequence of valid elementary moves (topology unchanged).
    """
    p = np.asarray(p, dtype=float)
    while True:
        changed = False
        for parity in (0, 1):
            m = len(p)
            if m <= 3:
                return p
            idx = np.arange(parity, m, 2)
            if m % 2 == 1 and parity == 0:
                idx = idx[:-1]           # vertex m-1 is adjacent to vertex 0
            if len(idx) == 0:
                continue
            a = p[(idx - 1) % m]
            b = p[idx]
            c = p[(idx + 1) % m]
            s0 = p
            s1 = np.roll(p, -1, axis=0)
            nt = len(idx)
            lo = np.full((nt, m), -_TOL_PARAM)
            hi = np.full((nt, m), 1.0 + _TOL_PARAM)
            rows = np.arange(nt)
            # own edges (i-1, i) and (i, i+1): excluded
            lo[rows, (idx - 1) % m] = 2.0
            lo[rows, idx % m] = 2.0
            # neighbours sharing a corner: (i-2, i-1) ends at a corner, (i+1, i+2) starts at one
            hi[rows, (idx - 2) % m] = 1.0 - _TOL_PARAM
            lo[rows, (idx + 1) % m] = _TOL_PARAM
            blocked = _pierce_matrix(a, b, c, s0, s1, lo, hi).any(axis=1)
            cand = idx[~blocked]
            if len(cand) == 0:
                continue
            # shortcut segments of the candidates against the candidates' triangles
            ca = p[(cand - 1) % m]
            cb = p[cand]
            cc = p[(cand + 1) % m]
            nc = len(cand)
            lo2 = np.full((nc, nc), -_TOL_PARAM)
            hi2 = np.full((nc, nc), 1.0 + _TOL_PARAM)
            # shortcut j = (cand_j - 1, cand_j + 1) may share a corner with triangle k
            hi2[((cand[None, :] + 1) % m) == ((cand[:, None] - 1) % m)] = 1.0 - _TOL_PARAM
            lo2[((cand[None, :] - 1) % m) == ((cand[:, None] + 1) % m)] = _TOL_PARAM
            np.fill_diagonal(lo2, 2.0)
            conflict = _pierce_matrix(ca, cb, cc, ca, cc, lo2, hi2)  # [triangle k, shortcut j]
            limit = m - 3
            if not conflict.any() and nc <= limit:
                accepted = list(range(nc))
            else:
                accepted = []
                acc = np.zeros(nc, dtype=bool)
                for k in range(nc):
                    if len(accepted) >= limit:
                        break
                    if not (conflict[k] & acc).any():
                        accepted.append(k)
                        acc[k] = True
            if accepted:
                keep = np.ones(m, dtype=bool)
                keep[cand[accepted]] = False
                p = p[keep]
                changed = True
        if not changed:
            return p


# --------------------------------------------------------------------------------------------
# Alexander invariants
# --------------------------------------------------------------------------------------------

def bareiss_det(mat: list[list[int]]) -> int:
    """Exact determinant of a square integer matrix (Bareiss fraction-free elimination)."""
    a = [list(map(int, row)) for row in mat]
    n = len(a)
    if n == 0:
        return 1
    sign = 1
    prev = 1
    for k in range(n - 1):
        if a[k][k] == 0:
            for r in range(k + 1, n):
                if a[r][k] != 0:
                    a[k], a[r] = a[r], a[k]
                    sign = -sign
                    break
            else:
                return 0
        akk = a[k][k]
        rowk = a[k]
        for i in range(k + 1, n):
            rowi = a[i]
            aik = rowi[k]
            for j in range(k + 1, n):
                rowi[j] = (rowi[j] * akk - aik * rowk[j]) // prev
            rowi[k] = 0
        prev = akk
    return sign * a[n - 1][n - 1]


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    """Rotation whose third row is a uniformly random direction (the projection axis)."""
    z = marsaglia_sphere(1, rng)[0]
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.vstack([x, y, z])


def diagram_crossings(q: np.ndarray):
    """Crossings of the closed polygon q (M, 3) projected along z.

    Returns (under_pos, over_pos, sign) arrays, positions as edge index + parameter, or None
    when the projection is degenerate (parallel overlapping edges, a vertex on an edge, a
    crossing at a vertex, or a genuine intersection in 3D).
    """
    m = len(q)
    x0 = q[:, :2]
    x1 = np.roll(q, -1, axis=0)[:, :2]
    z0 = q[:, 2]
    z1 = np.roll(q, -1, axis=0)[:, 2]
    d = x1 - x0
    ii, jj = np.triu_indices(m, k=2)
    keep = ~((ii == 0) & (jj == m - 1))
    ii, jj = ii[keep], jj[keep]
    if len(ii) == 0:
        return np.empty(0), np.empty(0), np.empty(0, dtype=int)
    di, dj = d[ii], d[jj]
    w = x0[jj] - x0[ii]
    den = di[:, 0] * dj[:, 1] - di[:, 1] * dj[:, 0]
    num_s = w[:, 0] * dj[:, 1] - w[:, 1] * dj[:, 0]
    num_t = w[:, 0] * di[:, 1] - w[:, 1] * di[:, 0]
    scale = np.linalg.norm(di, axis=1) * np.linalg.norm(dj, axis=1)
    par = np.abs(den) <= _TOL_COPLANAR * np.maximum(scale, 1e-300)
    # parallel edges: degenerate if collinear and overlapping in projection
    if par.any():
        ext = np.maximum(scale, 1e-300)
        colin = par & (np.abs(num_s) <= 1e-9 * ext)
        if colin.any():
            a0, a1, b0, b1 = x0[ii[colin]], x1[ii[colin]], x0[jj[colin]], x1[jj[colin]]
            lo = np.maximum(np.minimum(a0, a1), np.minimum(b0, b1))
            hi = np.minimum(np.maximum(a0, a1), np.maximum(b0, b1))
            if np.any(np.all(hi >= lo, axis=1)):
                return None
    safe = np.where(par, 1.0, den)
    s = num_s / safe
    t = num_t / safe
    eps = 1e-9
    near = ~par & (s > -eps) & (s < 1 + eps) & (t > -eps) & (t < 1 + eps)
    inner = ~par & (s > eps) & (s < 1 - eps) & (t > eps) & (t < 1 - eps)
    if np.any(near & ~inner):
        return None
    # adjacent edges folding back onto each other in projection are degenerate too
    dn = np.roll(d, -1, axis=0)
    cr = d[:, 0] * dn[:, 1] - d[:, 1] * dn[:, 0]
    dot = (d * dn).sum(axis=1)
    sc = np.linalg.norm(d, axis=1) * np.linalg.norm(dn, axis=1)
    if np.any((np.abs(cr) <= _TOL_COPLANAR * np.maximum(sc, 1e-300)) & (dot < 0)):
        return None
    ii, jj, s, t = ii[inner], jj[inner], s[inner], t[inner]
    zi = z0[ii] + s * (z1[ii] - z0[ii])
    zj = z0[jj] + t * (z1[jj] - z0[jj])
    zscale = np.abs(z1 - z0).max() + np.abs(q).max() + 1.0
    if np.any(np.abs(zi - zj) <= 1e-12 * zscale):
        return None
    i_over = zi > zj
    over_edge = np.where(i_over, ii, jj)
    under_edge = np.where(i_over, jj, ii)
    over_par = np.where(i_over, s, t)
    under_par = np.where(i_over, t, s)
    do, du = d[over_edge], d[under_edge]
    sign = np.where(do[:, 0] * du[:, 1] - do[:, 1] * du[:, 0] > 0, 1, -1)
    return under_edge + under_par, over_edge + over_par, sign


def alexander_matrix(under_pos, over_pos, sign, t: int) -> list[list[int]]:
    """Alexander matrix (crossings x arcs) of a diagram evaluated at integer t."""
    n = len(under_pos)
    order = np.argsort(under_pos)
    upos = np.asarray(under_pos)[order]
    opos = np.asarray(over_pos)[order]
    sg = np.asarray(sign)[order]
    over_arc = np.searchsorted(upos, opos) % n
    mat = [[0] * n for _ in range(n)]
    for k in range(n):
        i, j, nxt = int(over_arc[k]), k, (k + 1) % n
        mat[k][i] += 1 - t
        if sg[k] > 0:
            mat[k][j] += t
            mat[k][nxt] -= 1
        else:
            mat[k][j] -= 1
            mat[k][nxt] += t
    return mat


def odd_part(v: int) -> int:
    """v with all factors 2 removed (0 stays 0)."""
    v = abs(int(v))
    if v == 0:
        return 0
    while v % 2 == 0:
        v //= 2
    return v


def _dedupe(p: np.ndarray) -> np.ndarray:
    """Remove vertices equal to their (cyclic) predecessor."""
    if len(p) < 2:
        return p
    same = np.all(p == np.roll(p, 1, axis=0), axis=1)
    if same.all():
        return p[:1]
    return p[~same]


def alexander_invariants(polygon: np.ndarray, rng: np.random.Generator,
                         reduce: bool = True) -> tuple[int, int]:
    """(|Delta(-1)|, odd part of |Delta(-2)|) of the closed polygon (M, 3)."""
    p = _dedupe(np.asarray(polygon, dtype=float))
    if reduce:
        p = reduce_polygon(p)
    if len(p) <= 3:
        return 1, 1
    centre = p.mean(axis=0)
    size = max(float(np.abs(p - centre).max()), 1e-300)
    res = None
    for attempt in range(_MAX_PROJECTION_TRIES):
        if attempt >= _MAX_PROJECTION_TRIES // 2:
            # the polygon itself is singular (e.g. a closure point on the chain): perturb it
            # by a tiny seeded random displacement
            p = p + 1e-7 * size * rng.normal(size=p.shape)
        q = (p - centre) @ _random_rotation(rng).T
        res = diagram_crossings(q)
        if res is not None:
            break
    if res is None:
        raise ValueError("no generic projection found (self-intersecting polygon?)")
    under_pos, over_pos, sign = res
    n = len(under_pos)
    if n < 3:
        return 1, 1
    out = []
    for tval in (-1, -2):
        mat = alexander_matrix(under_pos, over_pos, sign, tval)
        minor = [row[:-1] for row in mat[:-1]]
        out.append(abs(bareiss_det(minor)))
    return out[0], odd_part(out[1])


def classify_invariants(d1: int, d2: int) -> str:
    """Knot type name for the invariant pair (|Delta(-1)|, odd part of |Delta(-2)|)."""
    return INVARIANT_TABLE.get((int(d1), odd_part(d2)), "other")


def classify_polygon(polygon: np.ndarray, rng: np.random.Generator | None = None) -> str:
    """Knot type of a closed polygon (M, 3) (vertex M-1 joined to vertex 0)."""
    if rng is None:
        rng = np.random.default_rng(12345)
    return classify_invariants(*alexander_invariants(polygon, rng))


def close_chain(r: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Closed polygon: the open chain r followed by the closure point."""
    return np.vstack([np.asarray(r, dtype=float), np.asarray(point, dtype=float)[None, :]])


# --------------------------------------------------------------------------------------------
# k_f, spectrum, knot matrix
# --------------------------------------------------------------------------------------------

@dataclass
class KnotResult:
    """Result of the stochastic-closure analysis of one open chain."""

    kf: float
    spectrum: dict
    dominant: str
    per_closure: list = field(default_factory=list)
    closures: int = 0


def analyze_chain(r: np.ndarray, closures: int = 1000, seed: int = 1,
                  points: np.ndarray | None = None) -> KnotResult:
    """k_f, spectrum and dominant type of the open chain r (N, 3).

    ``points`` (C, 3) replaces the random closure points (then closures = C).  The same seed
    gives the same closure points and projections, hence the same result.
    """
    r = np.asarray(r, dtype=float)
    if r.ndim != 2 or r.shape[1] != 3 or len(r) < 2:
        raise ValueError(f"the chain has shape {r.shape}: at least 2 beads of 3 coordinates "
                         "are needed")
    if not np.all(np.isfinite(r)):
        bead = int(np.flatnonzero(~np.isfinite(r).all(axis=1))[0])
        raise ValueError(f"the chain holds non-finite coordinates (first at bead {bead}): "
                         "its knot type is undefined")
    rng = np.random.default_rng(seed)
    if points is None:
        points = closure_points(r, closures, rng)
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    types = []
    for pt in points:
        if len(r) < 3:
            types.append("0_1")
            continue
        types.append(classify_polygon(close_chain(r, pt), rng))
    return summarize(types)


def summarize(types: list) -> KnotResult:
    """KnotResult of a list of per-closure types."""
    c = len(types)
    spectrum = {k: 0.0 for k in KNOT_TYPES}
    for ty in types:
        spectrum[ty] += 1.0
    if c > 0:
        spectrum = {k: v / c for k, v in spectrum.items()}
    kf = 1.0 - spectrum["0_1"] if c > 0 else 0.0
    dominant = max(KNOT_TYPES, key=lambda k: (spectrum[k], -KNOT_TYPES.index(k)))
    return KnotResult(kf=kf, spectrum=spectrum, dominant=dominant, per_closure=list(types),
                      closures=c)


def knot_fraction(r: np.ndarray, closures: int = 1000, seed: int = 1) -> float:
    """k_f of the open chain r."""
    return analyze_chain(r, closures, seed).kf


def knot_matrix(r: np.ndarray, closures: int = 100, seed: int = 1, min_length: int = 10,
                stride: int = 1) -> np.ndarray:
    """K[i, j] = k_f of the subchain i..j (0-based, i < j), NaN where not computed.

    Subchains shorter than ``min_length`` beads are skipped; with ``stride`` > 1 only i and j
    on the grid 0, stride, 2 stride, ... (and j = N-1) are computed.
    """
    r = np.asarray(r, dtype=float)
    n = len(r)
    mat = np.full((n, n), np.nan)
    rng = np.random.default_rng(seed)
    grid = list(range(0, n, max(1, stride)))
    if grid[-1] != n - 1:
        grid.append(n - 1)
    for i in grid:
        for j in grid:
            if j <= i or j - i + 1 < max(min_length, 3):
                continue
            sub = r[i:j + 1]
            pts = closure_points(sub, closures, rng)
            nk = 0
            for pt in pts:
                if classify_polygon(close_chain(sub, pt), rng) != "0_1":
                    nk += 1
            mat[i, j] = nk / closures
    return mat


def knot_core(mat: np.ndarray, threshold: float = 0.5):
    """Shortest knotted subchain (i, j) with K >= threshold (ties: smallest i), or None."""
    with np.errstate(invalid="ignore"):
        ii, jj = np.nonzero(np.nan_to_num(mat, nan=-1.0) >= threshold)
    if len(ii) == 0:
        return None
    lengths = jj - ii
    best = np.lexsort((ii, lengths))[0]
    return int(ii[best]), int(jj[best])


def is_slipknot(mat: np.ndarray, kf_whole: float, threshold: float = 0.5,
                whole_max: float = 0.1) -> bool:
    """A knotted subchain (K >= threshold) while the whole chain has k_f < whole_max."""
    return bool(kf_whole < whole_max and knot_core(mat, threshold) is not None)
