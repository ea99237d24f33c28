//! A mesh with its topology, built together.

use crate::{Topology, TriMesh};

/// A [`TriMesh`] with its [`Topology`], built together and read-only afterwards, so an API that
/// takes a `&Surface` cannot receive a topology of another mesh.
#[derive(Debug, Clone)]
pub struct Surface {
    mesh: TriMesh,
    topology: Topology,
}

impl Surface {
    /// Builds the topology of `mesh` (O(n + m)) and keeps both.
    pub fn new(mesh: TriMesh) -> Self {
        let topology = Topology::new(&mesh);
        Self { mesh, topology }
    }

    /// The mesh.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// Its topology.
    pub fn topology(&self) -> &Topology {
        &self.topology
    }

    /// The mesh, giving up the topology.
    pub fn into_mesh(self) -> TriMesh {
        self.mesh
    }
}

impl From<TriMesh> for Surface {
    fn from(mesh: TriMesh) -> Self {
        Self::new(mesh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::icosphere;

    #[test]
    fn surface_keeps_the_mesh_and_its_topology() {
        let m = icosphere(1);
        let s = Surface::from(m.clone());
        assert_eq!(s.mesh(), &m);
        assert_eq!(s.topology().face_edges().len(), m.n_faces());
        assert_eq!(s.topology().vertex_component().len(), m.n_vertices());
        assert_eq!(s.into_mesh(), m);
    }
}
