"""Case files as older knotflow versions left them, for the regression tests: up to schema 2
one checkpoint lay directly in /checkpoint (rewritten in place with every frame) instead of the
two slots /checkpoint/slot0 and /checkpoint/slot1 written alternately since schema 3."""
import numpy as np


def newest_slot(h):
    """The checkpoint slot (h5py group) of the open case file `h` with the larger frame count."""
    slots = [h["checkpoint"][s] for s in ("slot0", "slot1") if s in h["checkpoint"]]
    return max(slots, key=lambda g: int(g["nframes"][()]))


def to_single_checkpoint(h, schema=2):
    """Rewrite the case file `h` (h5py, opened for writing) to the single-checkpoint layout,
    from its newest slot, with schema_version = `schema` (None: no attribute, schema 1), and
    without the run records these versions did not write (drop_run_records)."""
    drop_run_records(h)
    src = newest_slot(h)
    for k in list(src.keys()):
        h.move(src.name + "/" + k, "/checkpoint/" + k)
    for s in ("slot0", "slot1"):
        if s in h["checkpoint"]:
            del h["checkpoint"][s]
    if schema is None:
        if "schema_version" in h.attrs:
            del h.attrs["schema_version"]
    else:
        h.attrs["schema_version"] = np.int32(schema)


def slot_digest(g):
    """The digest knotflow stores in the checkpoint slot `g` (kf_case_checkpoint checkpoint_digest:
    Adler-style sums modulo a prime over the bytes of its parts, in this order)."""
    parts = [np.array([g["nframes"][()], g["steps"][()], g["rejected"][()]], dtype="<i8"),
             np.array([g["time"][()], g["dt"][()]], dtype="<f8"), g["positions"][()]]
    if "stepper" in g:
        parts += [g["stepper/reals"][()], g["stepper/ints"][()]]
    if "diagnostics" in g:
        parts += [g["diagnostics/" + k][()] for k in ("counters", "values", "ongoing")]
    if "counters" in g:
        parts.append(g["counters"][()])
    if "run" in g:
        parts += [g["run/counts"][()], g["run/figures"][()]]
    data = b"".join(np.ascontiguousarray(p).tobytes() for p in parts)
    b = np.frombuffer(data, dtype=np.uint8).astype(np.int64)
    prime = 2147483629
    sums = np.cumsum(b)
    d1 = (1 + int(sums[-1])) % prime
    d2 = (len(b) + int(sums.sum())) % prime
    return d2 * 2147483648 + d1


def drop_run_records(h):
    """Rewrite the case file `h` (h5py, opened for writing) as knotflow wrote it before /runs
    (schema 3): no /runs, no run figures in the checkpoint slots (their digests recomputed,
    after checking that this digest reproduces the stored one)."""
    for s in ("slot0", "slot1"):
        if s not in h["checkpoint"]:
            continue
        g = h["checkpoint"][s]
        assert slot_digest(g) == int(g["digest"][()]), "the digest is not reproduced"
        if "run" in g:
            del g["run"]
        g["digest"][()] = np.int64(slot_digest(g))
    if "runs" in h:
        del h["runs"]
    h.attrs["schema_version"] = np.int32(3)
