//! Plain-data triangle mesh shared by every crate of the bipolar workspace.
//!
//! * [`TriMesh`]: f64 positions ([`glam::DVec3`]) and `u32` triangles, validated on construction
//!   (non-empty, finite coordinates, indices in range).
//! * [`Topology`]: adjacency built once (vertex-face incidence, unique edges with their faces,
//!   boundary loops, connected components, manifold and orientation checks); read-only.
//! * [`VertexAdjacency`]: the sorted one-ring of every vertex (CSR), from the triangles.
//! * [`Surface`]: a mesh with its topology, built together (what APIs needing both take).
//! * [`SurfacePoint`]: a point on the surface as (face, barycentric coordinates), with conversion
//!   to a position and [`FaceLocator`] for the nearest surface point to an arbitrary 3D point.
//! * [`linalg`]: the small dense linear algebra of the workspace (3x3 symmetric eigen, SVD,
//!   Kabsch and Horn rotations, the one rigid fit [`linalg::fit_rigid`]).
//! * [`repair`]: explicit, opt-in repairs (drop degenerate faces, weld duplicate vertices),
//!   the one implementation every reader and binary uses.
//! * [`subdivide_midpoint`]: one step of midpoint subdivision (every triangle into four, the
//!   surface unchanged).
//! * [`Choice`] and [`choice!`]: option enums that parse by name, with [`UnknownChoice`]
//!   listing the valid names.
//!
//! Nothing here panics on user data: constructors return [`MeshError`].

mod adjacency;
pub mod choice;
mod error;
mod file;
pub mod linalg;
mod locate;
mod mesh;
pub mod repair;
pub mod shapes;
mod subdivide;
mod surface;
mod topology;
pub mod units;

pub use adjacency::VertexAdjacency;
pub use choice::{Choice, UnknownChoice};
pub use error::MeshError;
pub use file::{read_text, write_bytes, FileError};
pub use glam::{DAffine3, DMat3, DQuat, DVec3};
pub use locate::{closest_point_on_triangle, FaceLocator};
pub use mesh::{Aabb, SurfacePoint, TriMesh};
pub use subdivide::subdivide_midpoint;
pub use surface::Surface;
pub use topology::{vertex_components, Edge, Topology, NO_FACE};
