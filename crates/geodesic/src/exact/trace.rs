//! Geodesic path tracing: a second, recording propagation (cut off just past the target's
//! distance) keeps every emitted window with its parent, and the path is unfolded backwards
//! from the target through that chain of windows, pseudo-source vertices and edges.

use super::{classify_point, ExactGeodesic, Origin, Pred, Record, Seed, Solve, NONE};
use crate::{GeodesicError, SolveOptions, Source, SurfacePoint};
use glam::DVec3;

impl ExactGeodesic {
    /// Traces a shortest surface path from the nearest of `sources` to `target`.
    ///
    /// Returns the polyline from the source to the target (vertices of the path where it crosses
    /// edges or bends at pseudo-source vertices); its length equals the exact distance up to
    /// rounding. Returns an empty vector when the target cannot be reached (another component).
    /// Costs two propagations, the second one recording windows up to the target's distance, so
    /// its memory grows with the number of windows inside that radius.
    pub fn trace_path(
        &self,
        sources: &[Source],
        target: SurfacePoint,
    ) -> Result<Vec<DVec3>, GeodesicError> {
        let tseed = classify_point(self, &target)?;
        let (face, bary, p) = match tseed {
            Seed::Face { face, bary, .. } => (face, bary, self.bary_pos(face, bary)),
            Seed::Vertex(v) => {
                let f = target.face;
                let t = self.tris[f as usize];
                let mut b = [0.0; 3];
                if let Some(k) = t.iter().position(|&u| u == v) {
                    b[k] = 1.0;
                }
                (f, b, self.positions[v as usize])
            }
            Seed::Degenerate { face, pos } => (face, [f64::NAN; 3], pos),
        };
        // Pass 1: vertex distances give an upper bound for the target.
        let mut first = Solve::new(self, SolveOptions::default().cutoff()?, false);
        first.seed(sources)?;
        first.run();
        let tri = self.tris[face as usize];
        let mut bound = tri
            .iter()
            .map(|&v| first.d[v as usize] + (self.positions[v as usize] - p).length())
            .fold(f64::INFINITY, f64::min);
        for &(sf, sb, sp) in &first.points {
            if self.point_in_face_closure(sf, sb, face) {
                bound = bound.min((sp - p).length());
            }
        }
        if !bound.is_finite() {
            return Ok(Vec::new());
        }
        // Pass 2: record windows up to just past the bound.
        let scale = self.positions[tri[0] as usize].length().max(1.0);
        let cut = bound * (1.0 + 1e-9) + 1e-12 * scale;
        let mut s = Solve::new(self, cut, true);
        s.seed(sources)?;
        s.run();
        let recs = s.records.take().unwrap_or_default();
        // Best way into the target.
        enum Start {
            Direct(usize),
            Vertex(u32),
            Window(usize, f64),
        }
        let mut best = f64::INFINITY;
        let mut start = None;
        for (i, &(sf, sb, sp)) in s.points.iter().enumerate() {
            if self.point_in_face_closure(sf, sb, face) {
                let d = (sp - p).length();
                if d < best {
                    best = d;
                    start = Some(Start::Direct(i));
                }
            }
        }
        for &v in &tri {
            let d = s.d[v as usize] + (self.positions[v as usize] - p).length();
            if d < best {
                best = d;
                start = Some(Start::Vertex(v));
            }
        }
        if self.live[face as usize] {
            for (ri, r) in recs.iter().enumerate() {
                if r.h / 3 != face {
                    continue;
                }
                let (px, py) = self.frame_coords(r.h, bary);
                let w = &r.w;
                let x = w.sx + (px - w.sx) * (-w.sy) / (py - w.sy);
                let tol = 1e-12 * self.geom[r.h as usize].l;
                if x < w.b0 - tol || x > w.b1 + tol {
                    continue;
                }
                let d = w.sigma + (px - w.sx).hypot(py - w.sy);
                if d < best {
                    best = d;
                    start = Some(Start::Window(ri, x.clamp(w.b0, w.b1)));
                }
            }
        }
        let Some(start) = start else {
            return Ok(Vec::new());
        };
        let mut path = vec![p];
        let limit = recs.len() + 4 * self.positions.len() + 16;
        let mut steps = 0;
        let mut cur = match start {
            Start::Direct(i) => {
                path.push(s.points[i].2);
                None
            }
            Start::Vertex(v) => Some(Back::Vertex(v)),
            Start::Window(ri, x) => Some(Back::Edge(ri as u32, x)),
        };
        while let Some(state) = cur {
            steps += 1;
            if steps > limit {
                break;
            }
            cur = match state {
                Back::Vertex(v) => {
                    path.push(self.positions[v as usize]);
                    match s.pred[v as usize] {
                        Pred::None | Pred::Source => None,
                        Pred::Point(i) => {
                            path.push(s.points[i as usize].2);
                            None
                        }
                        Pred::Vertex(u) => Some(Back::Vertex(u)),
                        Pred::Window(ri, t) => Some(Back::Edge(ri, t)),
                    }
                }
                Back::Edge(ri, x) => {
                    let r: &Record = &recs[ri as usize];
                    let xp = self.edge_point(r.h, x);
                    path.push(xp);
                    match r.origin {
                        Origin::Vertex(v) => Some(Back::Vertex(v)),
                        Origin::Point(i) => {
                            path.push(s.points[i as usize].2);
                            None
                        }
                        Origin::Window(pi) if pi != NONE => {
                            let parent = &recs[pi as usize];
                            let b = self.edge_point_bary(r.h, x, parent.h / 3);
                            let (qx, qy) = self.frame_coords(parent.h, b);
                            let w = &parent.w;
                            let den = qy - w.sy;
                            let xn = if den > 0.0 {
                                qx + (w.sx - qx) * qy / den
                            } else {
                                qx
                            };
                            Some(Back::Edge(
                                pi,
                                xn.clamp(0.0, self.geom[parent.h as usize].l),
                            ))
                        }
                        Origin::Window(_) => None,
                    }
                }
            };
        }
        path.dedup_by(|a, b| (*a - *b).length() == 0.0);
        path.reverse();
        Ok(path)
    }

    fn bary_pos(&self, f: u32, b: [f64; 3]) -> DVec3 {
        let t = self.tris[f as usize];
        b[0] * self.positions[t[0] as usize]
            + b[1] * self.positions[t[1] as usize]
            + b[2] * self.positions[t[2] as usize]
    }

    /// Coordinates in the frame of half-edge `h` of a point of face(h) given by barycentrics.
    fn frame_coords(&self, h: u32, b: [f64; 3]) -> (f64, f64) {
        let k = (h % 3) as usize;
        let g = &self.geom[h as usize];
        let (b1, b2) = (b[(k + 1) % 3], b[(k + 2) % 3]);
        (b1 * g.l + b2 * g.cx, b2 * g.cy)
    }

    /// 3D point at parameter `x` along half-edge `h`.
    fn edge_point(&self, h: u32, x: f64) -> DVec3 {
        let s = (x / self.geom[h as usize].l).clamp(0.0, 1.0);
        let a = self.positions[self.tail(h) as usize];
        let b = self.positions[self.head(h) as usize];
        a + s * (b - a)
    }

    /// Barycentrics in face `f` of the point at parameter `x` along half-edge `h` (whose edge is
    /// an edge of `f`).
    fn edge_point_bary(&self, h: u32, x: f64, f: u32) -> [f64; 3] {
        let s = (x / self.geom[h as usize].l).clamp(0.0, 1.0);
        let (a, b) = (self.tail(h), self.head(h));
        let t = self.tris[f as usize];
        let mut out = [0.0; 3];
        for k in 0..3 {
            if t[k] == a {
                out[k] += 1.0 - s;
            } else if t[k] == b {
                out[k] += s;
            }
        }
        out
    }

    /// True if the point (face `sf`, barycentrics `sb`) lies in the closed face `f`.
    fn point_in_face_closure(&self, sf: u32, sb: [f64; 3], f: u32) -> bool {
        let st = self.tris[sf as usize];
        let t = self.tris[f as usize];
        (0..3).all(|k| sb[k] == 0.0 || t.contains(&st[k]))
    }
}

#[derive(Debug, Clone, Copy)]
enum Back {
    Vertex(u32),
    Edge(u32, f64),
}
