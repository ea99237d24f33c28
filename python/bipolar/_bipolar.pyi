"""Typed stubs of the extension module ``bipolar._bipolar`` (re-exported by ``bipolar``)."""

import os
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str
LANDMARK_NAMES: List[str]
#: ``verify``'s threshold: scores at or below it are the same person (docs/matching.md).
VERIFY_THRESHOLD: float

PathLike = Union[str, "os.PathLike[str]"]
ArrayLike = npt.ArrayLike
F64 = npt.NDArray[np.float64]
MethodName = Literal["exact", "fmm", "heat", "dijkstra"]
Reference = Union[int, str, Sequence[float], npt.NDArray[np.float64]]

class Mesh:
    """A triangle mesh (f64 positions, u32 triangles) with per-vertex extras; immutable."""

    def __init__(self, vertices: ArrayLike, triangles: ArrayLike) -> None: ...
    @property
    def vertices(self) -> F64: ...
    @property
    def triangles(self) -> npt.NDArray[np.uint32]: ...
    @property
    def n_vertices(self) -> int: ...
    @property
    def n_faces(self) -> int: ...
    @property
    def colors(self) -> Optional[npt.NDArray[np.uint8]]: ...
    @property
    def scalars(self) -> Dict[str, F64]: ...
    @property
    def grid_index(self) -> Optional[npt.NDArray[np.uint32]]: ...
    @property
    def warnings(self) -> List[str]: ...
    def bbox_diagonal(self) -> float: ...
    def mean_edge_length(self) -> float: ...
    def area(self) -> float: ...
    def vertex_normals(self) -> F64: ...
    def nearest(
        self, points: ArrayLike
    ) -> Tuple[npt.NDArray[np.uint32], F64, F64]: ...
    def surface_positions(self, faces: ArrayLike, bary: ArrayLike) -> F64: ...
    def with_extras(
        self,
        *,
        colors: Optional[ArrayLike] = None,
        scalars: Optional[Dict[str, ArrayLike]] = None,
        scalar_type: Literal["float32", "float64"] = "float64",
    ) -> "Mesh": ...
    def weld(self, tol: float = 0.0) -> Tuple["Mesh", Dict[str, int]]: ...
    def drop_degenerate(self, rel_tol: float = 0.0) -> Tuple["Mesh", Dict[str, int]]: ...
    def to_bytes(self, format: str) -> bytes: ...
    def __len__(self) -> int: ...

def read_mesh(path: PathLike) -> Mesh: ...
def read_mesh_bytes(data: bytes, format: str) -> Mesh: ...
def write_mesh(path: PathLike, mesh: Mesh) -> None: ...
def write_ply(
    path: PathLike,
    mesh: Mesh,
    encoding: Literal["ascii", "binary_little_endian", "binary_big_endian"] = "binary_little_endian",
) -> None: ...
def read_bnt(
    path: PathLike, *, max_edge_factor: float = 4.0, largest_component_only: bool = True
) -> Mesh: ...
def read_landmarks(path: PathLike) -> Dict[str, F64]: ...
def read_ict_landmarks(path: PathLike) -> Dict[str, Dict[str, F64]]: ...
def read_lm2(path: PathLike) -> Dict[str, F64]: ...
def write_lm3(path: PathLike, landmarks: Dict[str, ArrayLike]) -> None: ...
def icosphere(subdivisions: int) -> Mesh: ...
def uv_sphere(n_lat: int, n_lon: int) -> Mesh: ...
def grid_plane(
    n: int, h: float = 1.0, x0: float = 0.0, jitter: float = 0.0, seed: int = 0
) -> Mesh: ...

class GeodesicSolver:
    """A geodesic distance solver prepared once per mesh; calls release the GIL."""

    def __init__(self, mesh: Union[Mesh, PathLike], method: MethodName = "exact") -> None: ...
    @property
    def method(self) -> str: ...
    @property
    def n_vertices(self) -> int: ...
    def distances(
        self,
        sources: Optional[Union[int, ArrayLike]] = None,
        *,
        faces: Optional[ArrayLike] = None,
        bary: Optional[ArrayLike] = None,
        max_distance: Optional[float] = None,
    ) -> F64: ...
    def distances_many(
        self,
        sources: Sequence[Union[int, Sequence[int]]],
        *,
        max_distance: Optional[float] = None,
        threads: Optional[int] = None,
    ) -> F64: ...
    def sparse_distances(
        self,
        sources: ArrayLike,
        *,
        max_distance: Optional[float] = None,
        threads: Optional[int] = None,
    ) -> Tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], F64]: ...

class _KeyedSurfacePoints:
    """Stub-only: what both descriptors expose (keyed points on the mesh, arrays are copies)."""

    @property
    def points(self) -> F64: ...
    @property
    def keys(self) -> npt.NDArray[np.uint64]: ...
    @property
    def faces(self) -> npt.NDArray[np.uint32]: ...
    @property
    def bary(self) -> F64: ...
    @property
    def step(self) -> float: ...
    def __len__(self) -> int: ...

class Descriptor(_KeyedSurfacePoints):
    """A bipolar descriptor: keyed points sorted by key then position; picklable."""

    @staticmethod
    def from_arrays(
        points: ArrayLike,
        keys: ArrayLike,
        cos: Optional[ArrayLike] = None,
        ambiguous: Optional[ArrayLike] = None,
    ) -> "Descriptor": ...
    @staticmethod
    def from_json(text: str) -> "Descriptor": ...
    @property
    def cos(self) -> F64: ...
    @property
    def ambiguous(self) -> npt.NDArray[np.bool_]: ...
    @property
    def max_level(self) -> int: ...
    @property
    def reference_distance(self) -> float: ...
    @property
    def references(self) -> F64: ...
    @property
    def options(self) -> Dict[str, Any]: ...
    @property
    def stats(self) -> Dict[str, int]: ...
    def key_fields(self) -> Dict[str, npt.NDArray[Any]]: ...
    def save(self, path: PathLike) -> None: ...
    def to_json(self) -> str: ...

@overload
def describe(
    mesh: Union[Mesh, PathLike],
    ref_a: Reference,
    ref_b: Reference,
    *,
    refs: Optional[Sequence[Reference]] = None,
    levels: Optional[int] = None,
    step: Optional[float] = None,
    max_level: Optional[int] = None,
    angles: int = 8,
    alpha: float = 0.95,
    rule: Literal["isoangle", "iso-angle", "filter", "all"] = "isoangle",
    tolerance: Optional[float] = None,
    tangent: Literal["gradient", "strip", "spline"] = "gradient",
    method: MethodName = "exact",
    landmarks: Optional[Union[PathLike, Dict[str, ArrayLike]]] = None,
    solver: Optional[GeodesicSolver] = None,
    boundary_margin: Optional[float] = None,
    max_incidence: Optional[float] = None,
    search_radius: None = None,
    search_directions: int = 6,
) -> Descriptor: ...
@overload
def describe(
    mesh: Union[Mesh, PathLike],
    ref_a: Reference,
    ref_b: Reference,
    *,
    refs: Optional[Sequence[Reference]] = None,
    levels: Optional[int] = None,
    step: Optional[float] = None,
    max_level: Optional[int] = None,
    angles: int = 8,
    alpha: float = 0.95,
    rule: Literal["isoangle", "iso-angle", "filter", "all"] = "isoangle",
    tolerance: Optional[float] = None,
    tangent: Literal["gradient", "strip", "spline"] = "gradient",
    method: MethodName = "exact",
    landmarks: Optional[Union[PathLike, Dict[str, ArrayLike]]] = None,
    solver: Optional[GeodesicSolver] = None,
    boundary_margin: Optional[float] = None,
    max_incidence: Optional[float] = None,
    search_radius: float,
    search_directions: int = 6,
) -> List[Descriptor]: ...
def read_descriptor(path: PathLike) -> Descriptor: ...

class PolarDescriptor(_KeyedSurfacePoints):
    """A single-pole descriptor: points at geodesic radius ``level * step`` from the pole on
    ``sectors`` straightest-geodesic rays (arrays are copies)."""

    @property
    def levels(self) -> npt.NDArray[np.uint32]: ...
    @property
    def sectors(self) -> npt.NDArray[np.uint32]: ...
    @property
    def n_levels(self) -> int: ...
    @property
    def n_sectors(self) -> int: ...

def describe_polar(
    mesh: Union[Mesh, PathLike],
    pole: Reference,
    towards: Reference,
    *,
    step: float,
    levels: int = 10,
    sectors: int = 16,
    method: MethodName = "exact",
    landmarks: Optional[Union[PathLike, Dict[str, ArrayLike]]] = None,
    solver: Optional[GeodesicSolver] = None,
) -> PolarDescriptor: ...
def polar_distance(a: PolarDescriptor, b: PolarDescriptor) -> float: ...
def unpack_polar_key(key: int) -> Tuple[int, int]: ...

class FacialCurves:
    """Facial curves: one level curve of the geodesic distance from the nose tip per level
    (``curves``: dicts with ``pieces``, ``level``, ``closed``, ``points`` (k, 3))."""

    @property
    def curves(self) -> List[Dict[str, Any]]: ...
    @property
    def step(self) -> float: ...
    @property
    def n_levels(self) -> int: ...
    def __len__(self) -> int: ...

class IsoCurvatureCurves:
    """Iso-curvature network: level curves of the principal curvatures (``curves``: dicts with
    ``field`` ("k1" or "k2"), ``level``, ``closed``, ``points`` (k, 3))."""

    @property
    def curves(self) -> List[Dict[str, Any]]: ...
    @property
    def levels_k1(self) -> List[float]: ...
    @property
    def levels_k2(self) -> List[float]: ...
    @property
    def k1(self) -> F64: ...
    @property
    def k2(self) -> F64: ...
    def __len__(self) -> int: ...

def facial_curves(
    mesh: Union[Mesh, PathLike],
    nose: Reference,
    *,
    radius: float,
    levels: int = 8,
    method: MethodName = "exact",
    landmarks: Optional[Union[PathLike, Dict[str, ArrayLike]]] = None,
    solver: Optional[GeodesicSolver] = None,
) -> FacialCurves: ...
def iso_curvature_curves(
    mesh: Union[Mesh, PathLike],
    *,
    levels: int = 6,
    k1_levels: Optional[ArrayLike] = None,
    k2_levels: Optional[ArrayLike] = None,
    centre: Optional[Reference] = None,
    radius: Optional[float] = None,
    curvature_radius: float = 3.0,
    method: MethodName = "exact",
    landmarks: Optional[Union[PathLike, Dict[str, ArrayLike]]] = None,
    solver: Optional[GeodesicSolver] = None,
) -> IsoCurvatureCurves: ...
def facial_curves_distance(
    a: FacialCurves,
    b: FacialCurves,
    *,
    aggregate: Literal["rss", "root-sum-square", "sum"] = "rss",
    samples: int = 100,
    scale: bool = False,
) -> float: ...
def iso_curvature_distance(a: IsoCurvatureCurves, b: IsoCurvatureCurves) -> float: ...
def elastic_distance(
    a: ArrayLike,
    b: ArrayLike,
    *,
    a_closed: bool = False,
    b_closed: bool = False,
    samples: int = 100,
    scale: bool = False,
    resampling: Literal["arc-length", "arclength", "parameter"] = "arc-length",
) -> float: ...
def pack_key(a: int, b: int, i: int, j: int, side: int, sign: int) -> int: ...
def unpack_key(key: int) -> Tuple[int, int, int, int, int, int]: ...

class DistanceOptions:
    """How two descriptors are compared (the flags of ``bipolar distance``)."""

    def __init__(
        self,
        *,
        mode: Literal["keys", "icp", "hausdorff"] = "keys",
        solver: Literal["kabsch", "horn"] = "kabsch",
        robust: Optional[Literal["huber", "tukey"]] = None,
        gate: Optional[float] = None,
        keep_ambiguous: bool = False,
        variant: Literal["point", "plane"] = "point",
        trim: float = 0.0,
        iterations: int = 100,
        global_search: bool = True,
    ) -> None: ...
    @property
    def mode(self) -> str: ...
    def as_dict(self) -> Dict[str, Any]: ...

def distance(
    a: Descriptor, b: Descriptor, options: Optional[DistanceOptions] = None, **kwargs: Any
) -> float: ...
def distance_details(
    a: Descriptor, b: Descriptor, options: Optional[DistanceOptions] = None, **kwargs: Any
) -> Dict[str, Any]: ...
def distance_matrix(
    descriptors: Sequence[Descriptor],
    options: Optional[DistanceOptions] = None,
    *,
    threads: Optional[int] = None,
    **kwargs: Any,
) -> F64: ...
def searched_distance(
    a: Union[Descriptor, Sequence[Descriptor]],
    b: Union[Descriptor, Sequence[Descriptor]],
    options: Optional[DistanceOptions] = None,
    **kwargs: Any,
) -> float: ...
def cross_distances(
    rows: Sequence[Descriptor],
    cols: Sequence[Descriptor],
    options: Optional[DistanceOptions] = None,
    *,
    threads: Optional[int] = None,
    **kwargs: Any,
) -> F64: ...
def detect_landmarks(
    mesh: Union[Mesh, PathLike],
    *,
    model: Optional[PathLike] = None,
    scale: Optional[float] = None,
    min_confidence: Optional[float] = None,
    toward_viewer: Optional[ArrayLike] = None,
) -> Dict[str, Any]: ...

def scan(
    mesh: Union[Mesh, PathLike],
    *,
    units: Optional[Literal["mm", "cm", "m"]] = None,
    pitch: float = 0.5,
    yaw: float = 0.0,
    pitch_angle: float = 0.0,
    pinhole: Optional[float] = None,
    artifacts: Literal["none", "structured-light"] = "none",
    seed: int = 0,
) -> Tuple[Mesh, Dict[str, Any]]: ...
def visible_faces(
    mesh: Union[Mesh, PathLike],
    toward_viewer: ArrayLike,
    *,
    pitch: Optional[float] = None,
    max_incidence: float = 75.0,
) -> npt.NDArray[np.bool_]: ...
def clean(
    mesh: Union[Mesh, PathLike],
    *,
    units: Optional[Literal["mm", "cm", "m"]] = None,
    crop_center: Optional[ArrayLike] = None,
    crop_radius: float = 100.0,
    max_hole: float = 10.0,
    smooth: int = 0,
    target_edge: Optional[float] = None,
) -> Tuple[Mesh, Dict[str, Any]]: ...

# Face matching (facematch): as `bipolar enroll`, `identify`, `verify`.

Scan = Union[Mesh, PathLike]

class Template:
    """A face template (``.bpt``): identity, source, settings, the descriptors of the three pole
    pairs and of the turned views; read back bit-identically."""

    @staticmethod
    def from_scan(
        scan: Scan,
        identity: Optional[str] = None,
        *,
        probe: bool = False,
        source: Optional[str] = None,
        scanner: Optional[ArrayLike] = None,
        units: Optional[Literal["mm", "cm", "m"]] = None,
    ) -> "Template": ...
    @staticmethod
    def from_bytes(data: bytes, name: str = "<bytes>") -> "Template": ...
    @staticmethod
    def read(path: PathLike) -> "Template": ...
    def to_bytes(self) -> bytes: ...
    def write(self, path: PathLike) -> None: ...
    @property
    def identity(self) -> str: ...
    @property
    def source(self) -> str: ...
    @property
    def settings(self) -> str: ...
    @property
    def notes(self) -> List[str]: ...
    @property
    def pair(self) -> Literal["corners", "right-nose", "left-nose"]: ...
    @property
    def searched(self) -> bool: ...
    @property
    def landmarks(self) -> F64: ...
    @property
    def view_yaws(self) -> List[float]: ...
    def __eq__(self, other: object) -> bool: ...

Probe = Union[Template, Mesh, PathLike]

class Gallery:
    """Templates to identify probes against (a folder of ``.bpt`` files or a ``.bpg`` file)."""

    def __init__(self, templates: Sequence[Template]) -> None: ...
    @staticmethod
    def open(path: PathLike) -> "Gallery": ...
    def write(self, path: PathLike) -> None: ...
    def to_bytes(self) -> bytes: ...
    @property
    def templates(self) -> List[Template]: ...
    @property
    def identities(self) -> List[str]: ...
    def identify(
        self,
        probe: Probe,
        *,
        top: Optional[int] = None,
        gate: Optional[float] = None,
        scanner: Optional[ArrayLike] = None,
        units: Optional[Literal["mm", "cm", "m"]] = None,
    ) -> List[Dict[str, Any]]: ...
    def __len__(self) -> int: ...

def enroll(
    scans: Sequence[Scan],
    identities: Optional[Sequence[str]] = None,
    *,
    identity_from: Optional[str] = None,
    scanner: Optional[ArrayLike] = None,
    units: Optional[Literal["mm", "cm", "m"]] = None,
    skip_failed: bool = False,
) -> Gallery: ...
def verify(
    a: Probe,
    b: Probe,
    *,
    gate: Optional[float] = None,
    scanner: Optional[ArrayLike] = None,
    units: Optional[Literal["mm", "cm", "m"]] = None,
) -> Dict[str, Any]: ...
def _merge_rankings(shards: Sequence[Sequence[Dict[str, Any]]]) -> List[Dict[str, Any]]: ...
