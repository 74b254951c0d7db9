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
    from its newest slot, with schema_version = `schema` (None: no attribute, schema 1)."""
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
