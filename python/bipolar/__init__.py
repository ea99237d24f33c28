"""bipolar: the bipolar invariant representation of 3D surfaces, from Python.

Meshes (every format of the Rust mesh-io crate), geodesic distance fields (exact, fast
marching, heat method, Dijkstra) from a solver prepared once per mesh, the bipolar descriptor
with every option of ``bipolar describe``, normalised shape distances (keys, ICP, Hausdorff)
and distance matrices, automatic face landmarks, face matching (``enroll``, ``Template``,
``Gallery.identify``, ``verify``: ``bipolar enroll / identify / verify``). numpy arrays in
and out; the GIL is released while Rust computes.

Sub-modules: ``bipolar.gdist`` (drop-in for tvb-gdist), ``bipolar.dask`` (describe many files,
block distance matrices and 1:N identification, of descriptors or of face templates, on a
dask.distributed cluster),
``bipolar.errors`` (the exception hierarchy).

Example::

    import bipolar
    face = bipolar.read_mesh("face.obj")
    d = bipolar.describe(face, 1507, 3721, levels=30, max_level=30)
    d.points, d.keys, d.cos                     # (n, 3), (n,) uint64, (n,)
    solver = bipolar.GeodesicSolver(face, "exact")
    field = solver.distances(1507, max_distance=5.0)
"""

from __future__ import annotations

from . import errors
from ._bipolar import (
    LANDMARK_NAMES,
    VERIFY_THRESHOLD,
    Descriptor,
    DistanceOptions,
    FacialCurves,
    Gallery,
    GeodesicSolver,
    IsoCurvatureCurves,
    Mesh,
    PolarDescriptor,
    Template,
    __version__,
    clean,
    cross_distances,
    describe,
    describe_polar,
    detect_landmarks,
    distance,
    distance_details,
    distance_matrix,
    elastic_distance,
    enroll,
    facial_curves,
    facial_curves_distance,
    grid_plane,
    icosphere,
    iso_curvature_curves,
    iso_curvature_distance,
    pack_key,
    polar_distance,
    read_bnt,
    read_descriptor,
    read_ict_landmarks,
    read_landmarks,
    read_lm2,
    read_mesh,
    read_mesh_bytes,
    scan,
    searched_distance,
    unpack_key,
    unpack_polar_key,
    uv_sphere,
    verify,
    visible_faces,
    write_lm3,
    write_mesh,
    write_ply,
)
from .errors import (
    BipolarError,
    ComputationError,
    FileError,
    FileFormatError,
    IndexOutOfRangeError,
    InputError,
    InputTypeError,
    LandmarksNotFoundError,
    NoDescriptorPointsError,
    TemplateSettingsError,
)

__all__ = [
    "LANDMARK_NAMES",
    "VERIFY_THRESHOLD",
    "BipolarError",
    "ComputationError",
    "Descriptor",
    "DistanceOptions",
    "FacialCurves",
    "FileError",
    "FileFormatError",
    "Gallery",
    "GeodesicSolver",
    "IndexOutOfRangeError",
    "InputError",
    "InputTypeError",
    "IsoCurvatureCurves",
    "LandmarksNotFoundError",
    "Mesh",
    "NoDescriptorPointsError",
    "PolarDescriptor",
    "Template",
    "TemplateSettingsError",
    "__version__",
    "clean",
    "cross_distances",
    "describe",
    "describe_polar",
    "detect_landmarks",
    "distance",
    "distance_details",
    "distance_matrix",
    "elastic_distance",
    "enroll",
    "errors",
    "facial_curves",
    "facial_curves_distance",
    "grid_plane",
    "icosphere",
    "iso_curvature_curves",
    "iso_curvature_distance",
    "pack_key",
    "polar_distance",
    "read_bnt",
    "read_descriptor",
    "read_ict_landmarks",
    "read_landmarks",
    "read_lm2",
    "read_mesh",
    "read_mesh_bytes",
    "scan",
    "searched_distance",
    "visible_faces",
    "unpack_key",
    "unpack_polar_key",
    "uv_sphere",
    "verify",
    "write_lm3",
    "write_mesh",
    "write_ply",
]
