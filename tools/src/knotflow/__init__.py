"""knotflow: the knotflow Fortran library from Python (docs/python-api.md).

Hydrodynamic mobilities (none, RPY, multipole with lubrication), bead velocities, chain forces,
knots (k_f, spectrum and knot matrix by stochastic closure) and shape of bead configurations
given as numpy (N, 3) arrays, and runs of scene files with their case files read back; the
same library code as the knotflow programs, loaded from the shared library ``libknotflow_capi``
(where from: :mod:`knotflow._library`). Errors and refused arguments raise :class:`KnotflowError`
with the library's message.
"""

from knotflow._library import KnotflowError
from knotflow.analysis import (
    KnotMatrix,
    Knots,
    Shape,
    default_closures,
    default_seed,
    knot_core,
    knot_matrix,
    knot_spectrum,
    knot_types,
    knots,
    knotted_fraction,
    matrix_defaults,
    shape,
)
from knotflow.forces import chain_forces, forces_defaults
from knotflow.hydro import (
    Model,
    default_eps_lub,
    mobility,
    model_names,
    overlap_rules,
    shear_disturbance,
    velocities,
)
from knotflow.runs import Case, Run, read_case, run_scene, scene_cases

__version__ = "0.1.0"

__all__ = [
    "KnotflowError",
    "Model",
    "mobility",
    "velocities",
    "shear_disturbance",
    "model_names",
    "overlap_rules",
    "default_eps_lub",
    "chain_forces",
    "forces_defaults",
    "knots",
    "knotted_fraction",
    "knot_spectrum",
    "knot_types",
    "default_closures",
    "default_seed",
    "Knots",
    "knot_matrix",
    "knot_core",
    "matrix_defaults",
    "KnotMatrix",
    "shape",
    "Shape",
    "run_scene",
    "scene_cases",
    "Run",
    "read_case",
    "Case",
]
