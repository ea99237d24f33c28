//! glTF 2.0 / GLB: reader (all triangle primitives of the default scene, node transforms
//! applied) and a GLB writer for a mesh plus point sets and polylines with colours.

use crate::{IoError, LoadedMesh};
use glam::{DMat4, DVec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::{Mode, Semantic};
use meshcore::TriMesh;
use serde_json::{json, Value};
use std::path::Path;

/// Reads an accessor as rows of `f64` (normalised integers mapped to [0, 1]), checking every
/// offset against the buffer sizes.
fn read_accessor(
    acc: &gltf::Accessor<'_>,
    buffers: &[gltf::buffer::Data],
    file: &str,
) -> Result<(usize, Vec<f64>), IoError> {
    let ai = acc.index();
    let err = |m: String| IoError::whole(file, format!("accessor {ai}: {m}"));
    if acc.sparse().is_some() {
        return Err(IoError::Unsupported {
            file: file.into(),
            at: crate::Location::File,
            problem: format!("sparse accessor {ai}"),
        });
    }
    let view = acc.view().ok_or_else(|| err("has no buffer view".into()))?;
    let data = buffers
        .get(view.buffer().index())
        .ok_or_else(|| err("buffer missing".into()))?;
    let comp = acc.data_type().size();
    let dims = acc.dimensions().multiplicity();
    let elem = comp * dims;
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(err(format!(
            "stride {stride} smaller than the element size {elem}"
        )));
    }
    let vstart = view.offset();
    let vend = vstart
        .checked_add(view.length())
        .filter(|&e| e <= data.len())
        .ok_or_else(|| {
            err(format!(
                "buffer view {} (bytes {vstart}+{}) exceeds its buffer of {} bytes",
                view.index(),
                view.length(),
                data.len()
            ))
        })?;
    let view_bytes = &data[vstart..vend];
    let n = acc.count();
    if n > 0 {
        let need = (acc.offset() as u128) + (n as u128 - 1) * stride as u128 + elem as u128;
        if need > view_bytes.len() as u128 {
            return Err(err(format!(
                "{n} elements need {need} bytes but the buffer view has {}",
                view_bytes.len()
            )));
        }
    }
    let norm = acc.normalized();
    let mut out = Vec::with_capacity(n * dims);
    for i in 0..n {
        let base = acc.offset() + i * stride;
        for k in 0..dims {
            let o = base + k * comp;
            let b = &view_bytes[o..o + comp];
            let v = match acc.data_type() {
                DataType::I8 => {
                    let v = b[0] as i8 as f64;
                    if norm {
                        (v / 127.0).max(-1.0)
                    } else {
                        v
                    }
                }
                DataType::U8 => {
                    let v = b[0] as f64;
                    if norm {
                        v / 255.0
                    } else {
                        v
                    }
                }
                DataType::I16 => {
                    let v = i16::from_le_bytes([b[0], b[1]]) as f64;
                    if norm {
                        (v / 32767.0).max(-1.0)
                    } else {
                        v
                    }
                }
                DataType::U16 => {
                    let v = u16::from_le_bytes([b[0], b[1]]) as f64;
                    if norm {
                        v / 65535.0
                    } else {
                        v
                    }
                }
                DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            };
            out.push(v);
        }
    }
    Ok((dims, out))
}

struct Collect {
    pos: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
    colors: Vec<[u8; 4]>,
    all_colored: bool,
    skipped: usize,
    visits: usize,
}

fn add_primitive(
    prim: &gltf::Primitive<'_>,
    m: &DMat4,
    buffers: &[gltf::buffer::Data],
    file: &str,
    c: &mut Collect,
) -> Result<(), IoError> {
    match prim.mode() {
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => {}
        _ => {
            c.skipped += 1;
            return Ok(());
        }
    }
    let pacc = prim
        .get(&Semantic::Positions)
        .ok_or_else(|| IoError::whole(file, "triangle primitive without POSITION"))?;
    if pacc.dimensions() != Dimensions::Vec3 {
        return Err(IoError::whole(
            file,
            format!("POSITION accessor {} is not VEC3", pacc.index()),
        ));
    }
    let (_, p) = read_accessor(&pacc, buffers, file)?;
    let nv = p.len() / 3;
    let base = c.pos.len();
    if base + nv > u32::MAX as usize {
        return Err(IoError::whole(file, "too many vertices"));
    }
    for q in p.chunks_exact(3) {
        c.pos.push(m.transform_point3(DVec3::new(q[0], q[1], q[2])));
    }
    match prim.get(&Semantic::Colors(0)) {
        Some(cacc) if c.all_colored => {
            let (d, v) = read_accessor(&cacc, buffers, file)?;
            if v.len() / d.max(1) != nv || d < 3 {
                return Err(IoError::whole(
                    file,
                    format!(
                        "COLOR_0 accessor {} has {} entries for {nv} vertices",
                        cacc.index(),
                        v.len() / d.max(1)
                    ),
                ));
            }
            for q in v.chunks_exact(d) {
                let f = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
                c.colors.push([
                    f(q[0]),
                    f(q[1]),
                    f(q[2]),
                    if d == 4 { f(q[3]) } else { 255 },
                ]);
            }
        }
        _ => c.all_colored = false,
    }
    let idx: Vec<u32> = match prim.indices() {
        Some(iacc) => {
            if iacc.dimensions() != Dimensions::Scalar
                || matches!(
                    iacc.data_type(),
                    DataType::F32 | DataType::I8 | DataType::I16
                )
            {
                return Err(IoError::whole(
                    file,
                    format!(
                        "index accessor {} is not an unsigned integer scalar",
                        iacc.index()
                    ),
                ));
            }
            let (_, v) = read_accessor(&iacc, buffers, file)?;
            let mut out = Vec::with_capacity(v.len());
            for x in v {
                if x as usize >= nv {
                    return Err(IoError::whole(
                        file,
                        format!(
                            "index {x} out of range in accessor {} ({nv} vertices)",
                            iacc.index()
                        ),
                    ));
                }
                out.push((x as usize + base) as u32);
            }
            out
        }
        None => (base as u32..(base + nv) as u32).collect(),
    };
    let det_neg = m.determinant() < 0.0;
    let mut push = |t: [u32; 3]| c.tris.push(if det_neg { [t[0], t[2], t[1]] } else { t });
    match prim.mode() {
        Mode::Triangles => {
            if idx.len() % 3 != 0 {
                return Err(IoError::whole(
                    file,
                    format!(
                        "triangle list of {} indices (not a multiple of 3)",
                        idx.len()
                    ),
                ));
            }
            idx.chunks_exact(3).for_each(|t| push([t[0], t[1], t[2]]));
        }
        Mode::TriangleStrip => {
            for i in 2..idx.len() {
                push(if i % 2 == 0 {
                    [idx[i - 2], idx[i - 1], idx[i]]
                } else {
                    [idx[i - 1], idx[i - 2], idx[i]]
                });
            }
        }
        _ => {
            for i in 2..idx.len() {
                push([idx[0], idx[i - 1], idx[i]]);
            }
        }
    }
    Ok(())
}

fn visit(
    node: gltf::Node<'_>,
    parent: &DMat4,
    depth: usize,
    buffers: &[gltf::buffer::Data],
    file: &str,
    c: &mut Collect,
) -> Result<(), IoError> {
    c.visits += 1;
    if depth > 64 || c.visits > 100_000 {
        return Err(IoError::whole(
            file,
            "node hierarchy deeper than 64 levels or with more than 100000 node visits (cycle or shared nodes?)",
        ));
    }
    let local = node.transform().matrix();
    let cols = local.map(|col| col.map(f64::from));
    let m = *parent * DMat4::from_cols_array_2d(&cols);
    if let Some(mesh) = node.mesh() {
        for prim in mesh.primitives() {
            add_primitive(&prim, &m, buffers, file, c)?;
        }
    }
    for child in node.children() {
        visit(child, &m, depth + 1, buffers, file, c)?;
    }
    Ok(())
}

/// Parses a `.gltf` or `.glb` file; `base` resolves external buffer files.
///
/// The `gltf` crate (1.4) can panic while validating some malformed files (it indexes the
/// accessor list with an index it has not checked yet); that panic is caught here and turned
/// into an error, so a corrupt file never takes the caller down.
pub(crate) fn read_gltf(
    bytes: &[u8],
    file: &str,
    base: Option<&Path>,
) -> Result<LoadedMesh, IoError> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        read_gltf_unguarded(bytes, file, base)
    }))
    .unwrap_or_else(|_| {
        Err(IoError::whole(
            file,
            "invalid glTF: the file is malformed (the gltf crate's validation failed on it)",
        ))
    })
}

fn read_gltf_unguarded(
    bytes: &[u8],
    file: &str,
    base: Option<&Path>,
) -> Result<LoadedMesh, IoError> {
    let g = gltf::Gltf::from_slice(bytes)
        .map_err(|e| IoError::whole(file, format!("invalid glTF: {e}")))?;
    let buffers = gltf::import_buffers(&g.document, base, g.blob.clone())
        .map_err(|e| IoError::whole(file, format!("cannot load glTF buffers: {e}")))?;
    let doc = &g.document;
    let mut c = Collect {
        pos: Vec::new(),
        tris: Vec::new(),
        colors: Vec::new(),
        all_colored: true,
        skipped: 0,
        visits: 0,
    };
    match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => {
            for node in scene.nodes() {
                visit(node, &DMat4::IDENTITY, 0, &buffers, file, &mut c)?;
            }
        }
        None => {
            for mesh in doc.meshes() {
                for prim in mesh.primitives() {
                    add_primitive(&prim, &DMat4::IDENTITY, &buffers, file, &mut c)?;
                }
            }
        }
    }
    if c.tris.is_empty() {
        return Err(IoError::whole(
            file,
            format!(
                "no triangle primitive ({} point/line primitive(s))",
                c.skipped
            ),
        ));
    }
    // Drop vertices no triangle uses (e.g. unused accessor rows), keeping order.
    let mut out = crate::finish(file, c.pos, c.tris)?;
    if c.all_colored && c.colors.len() == out.mesh.n_vertices() {
        out.colors = Some(c.colors);
    }
    if c.skipped > 0 {
        out.warnings
            .push(format!("{} point/line primitive(s) ignored", c.skipped));
    }
    Ok(out)
}

meshcore::choice! {
    /// How the points of a [`Polyline`] are joined.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum LineMode: "line mode", crate::IoError {
        /// Consecutive points joined (glTF `LINE_STRIP`).
        Strip = "strip",
        /// Consecutive points joined and the last to the first (glTF `LINE_LOOP`).
        Loop = "loop",
        /// Points taken in pairs, each pair one segment (glTF `LINES`).
        Segments = "segments",
    }
}

/// A triangle mesh in a [`GltfScene`].
#[derive(Debug, Clone, PartialEq)]
pub struct SceneMesh {
    /// Node name.
    pub name: String,
    /// The mesh.
    pub mesh: TriMesh,
    /// Optional per-vertex RGBA colours (otherwise light grey).
    pub colors: Option<Vec<[u8; 4]>>,
}

/// A point set (glTF `POINTS` primitive).
#[derive(Debug, Clone, PartialEq)]
pub struct PointSet {
    /// Node name.
    pub name: String,
    /// The points.
    pub points: Vec<DVec3>,
    /// One colour for all points, or one per point.
    pub colors: Vec<[u8; 4]>,
}

/// A polyline or a set of segments (glTF `LINE_STRIP`, `LINE_LOOP` or `LINES`).
#[derive(Debug, Clone, PartialEq)]
pub struct Polyline {
    /// Node name.
    pub name: String,
    /// The points.
    pub points: Vec<DVec3>,
    /// How they are joined.
    pub mode: LineMode,
    /// One colour for all points, or one per point.
    pub colors: Vec<[u8; 4]>,
}

/// What a GLB file written by [`write_glb`] contains: meshes, point sets and polylines, each its
/// own node. Coordinates are stored as `f32` (glTF requires it).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GltfScene {
    /// Triangle meshes.
    pub meshes: Vec<SceneMesh>,
    /// Point sets.
    pub point_sets: Vec<PointSet>,
    /// Polylines.
    pub polylines: Vec<Polyline>,
}

impl GltfScene {
    /// Adds a mesh with optional per-vertex colours.
    pub fn add_mesh(
        &mut self,
        name: &str,
        mesh: &TriMesh,
        colors: Option<Vec<[u8; 4]>>,
    ) -> &mut Self {
        self.meshes.push(SceneMesh {
            name: name.into(),
            mesh: mesh.clone(),
            colors,
        });
        self
    }
    /// Adds a point set of one colour.
    pub fn add_points(&mut self, name: &str, points: &[DVec3], color: [u8; 4]) -> &mut Self {
        self.point_sets.push(PointSet {
            name: name.into(),
            points: points.to_vec(),
            colors: vec![color],
        });
        self
    }
    /// Adds a polyline of one colour.
    pub fn add_polyline(
        &mut self,
        name: &str,
        points: &[DVec3],
        mode: LineMode,
        color: [u8; 4],
    ) -> &mut Self {
        self.polylines.push(Polyline {
            name: name.into(),
            points: points.to_vec(),
            mode,
            colors: vec![color],
        });
        self
    }
}

struct Bin {
    data: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while self.data.len() % 4 != 0 {
            self.data.push(0);
        }
        self.views.push(json!({"buffer": 0, "byteOffset": self.data.len(), "byteLength": bytes.len(), "target": target}));
        self.data.extend_from_slice(bytes);
        self.views.len() - 1
    }
    fn vec3(&mut self, pts: &[DVec3], with_bounds: bool, file: &str) -> Result<usize, IoError> {
        let mut b = Vec::with_capacity(pts.len() * 12);
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for p in pts {
            let q = [p.x as f32, p.y as f32, p.z as f32];
            if q.iter().any(|v| !v.is_finite()) {
                return Err(IoError::invalid(
                    file,
                    format!("point ({}, {}, {}) is not finite in f32", p.x, p.y, p.z),
                ));
            }
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
                b.extend_from_slice(&q[k].to_le_bytes());
            }
        }
        let v = self.view(&b, 34962);
        let mut acc =
            json!({"bufferView": v, "componentType": 5126, "count": pts.len(), "type": "VEC3"});
        if with_bounds {
            acc["min"] = json!(lo);
            acc["max"] = json!(hi);
        }
        self.accessors.push(acc);
        Ok(self.accessors.len() - 1)
    }
    fn colors(&mut self, c: &[[u8; 4]], n: usize, file: &str) -> Result<usize, IoError> {
        let expanded: Vec<u8> = match c.len() {
            1 => (0..n).flat_map(|_| c[0]).collect(),
            m if m == n => c.iter().flatten().copied().collect(),
            m => {
                return Err(IoError::invalid(
                    file,
                    format!("{m} colours for {n} points (give 1 or {n})"),
                ))
            }
        };
        let v = self.view(&expanded, 34962);
        self.accessors.push(json!({"bufferView": v, "componentType": 5121, "normalized": true, "count": n, "type": "VEC4"}));
        Ok(self.accessors.len() - 1)
    }
    fn indices(&mut self, idx: &[u32]) -> usize {
        let b: Vec<u8> = idx.iter().flat_map(|i| i.to_le_bytes()).collect();
        let v = self.view(&b, 34963);
        self.accessors.push(
            json!({"bufferView": v, "componentType": 5125, "count": idx.len(), "type": "SCALAR"}),
        );
        self.accessors.len() - 1
    }
}

/// Serialises a scene as GLB bytes.
pub(crate) fn glb_bytes(scene: &GltfScene, file: &str) -> Result<Vec<u8>, IoError> {
    let mut bin = Bin {
        data: Vec::new(),
        views: Vec::new(),
        accessors: Vec::new(),
    };
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    // Material 0: lit, double-sided (meshes); material 1: unlit (points and lines).
    for m in &scene.meshes {
        let n = m.mesh.n_vertices();
        let pa = bin.vec3(m.mesh.positions(), true, file)?;
        let normals: Vec<DVec3> = m
            .mesh
            .vertex_normals()
            .into_iter()
            .map(|v| if v == DVec3::ZERO { DVec3::Z } else { v })
            .collect();
        let na = bin.vec3(&normals, false, file)?;
        let mut attrs = json!({"POSITION": pa, "NORMAL": na});
        if let Some(c) = &m.colors {
            if c.len() != n {
                return Err(IoError::invalid(
                    file,
                    format!("mesh {:?}: {} colours for {n} vertices", m.name, c.len()),
                ));
            }
            attrs["COLOR_0"] = json!(bin.colors(c, n, file)?);
        }
        let flat: Vec<u32> = m.mesh.triangles().iter().flatten().copied().collect();
        let ia = bin.indices(&flat);
        meshes.push(json!({"name": m.name, "primitives": [{"attributes": attrs, "indices": ia, "mode": 4, "material": 0}]}));
        nodes.push(json!({"name": m.name, "mesh": meshes.len() - 1}));
    }
    for p in &scene.point_sets {
        if p.points.is_empty() {
            return Err(IoError::invalid(
                file,
                format!("point set {:?} is empty", p.name),
            ));
        }
        let pa = bin.vec3(&p.points, true, file)?;
        let ca = bin.colors(&p.colors, p.points.len(), file)?;
        meshes.push(json!({"name": p.name, "primitives": [{"attributes": {"POSITION": pa, "COLOR_0": ca}, "mode": 0, "material": 1}]}));
        nodes.push(json!({"name": p.name, "mesh": meshes.len() - 1}));
    }
    for l in &scene.polylines {
        let (mode, ok) = match l.mode {
            LineMode::Segments => (1, l.points.len() >= 2 && l.points.len() % 2 == 0),
            LineMode::Loop => (2, l.points.len() >= 2),
            LineMode::Strip => (3, l.points.len() >= 2),
        };
        if !ok {
            return Err(IoError::invalid(
                file,
                format!(
                    "polyline {:?} has {} points (at least 2; even for segments)",
                    l.name,
                    l.points.len()
                ),
            ));
        }
        let pa = bin.vec3(&l.points, true, file)?;
        let ca = bin.colors(&l.colors, l.points.len(), file)?;
        meshes.push(json!({"name": l.name, "primitives": [{"attributes": {"POSITION": pa, "COLOR_0": ca}, "mode": mode, "material": 1}]}));
        nodes.push(json!({"name": l.name, "mesh": meshes.len() - 1}));
    }
    if nodes.is_empty() {
        return Err(IoError::invalid(file, "empty scene"));
    }
    while bin.data.len() % 4 != 0 {
        bin.data.push(0);
    }
    let doc = json!({
        "asset": {"version": "2.0", "generator": "bipolar mesh-io"},
        "extensionsUsed": ["KHR_materials_unlit"],
        "scene": 0,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [
            {"name": "surface", "doubleSided": true, "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8}},
            {"name": "unlit", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0]}, "extensions": {"KHR_materials_unlit": {}}}
        ],
        "buffers": [{"byteLength": bin.data.len()}],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    let mut js = serde_json::to_vec(&doc).map_err(|e| IoError::invalid(file, e.to_string()))?;
    while js.len() % 4 != 0 {
        js.push(b' ');
    }
    let total = 12 + 8 + js.len() + 8 + bin.data.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(js.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&js);
    out.extend_from_slice(&(bin.data.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
    out.extend_from_slice(&bin.data);
    Ok(out)
}

/// Writes a scene as a GLB file.
pub fn write_glb(path: impl AsRef<Path>, scene: &GltfScene) -> Result<(), IoError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let bytes = glb_bytes(scene, &name)?;
    std::fs::write(path, bytes).map_err(|e| IoError::io("write", path, e))
}

/// Serialises a scene as GLB bytes in memory.
pub fn write_glb_to_bytes(scene: &GltfScene) -> Result<Vec<u8>, IoError> {
    glb_bytes(scene, "<memory>")
}
