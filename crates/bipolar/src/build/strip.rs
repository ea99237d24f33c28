//! Strip tangents (M1, the paper's method 1).

use super::Ctx;
use glam::DVec3;

/// Strip tangents (M1): principal axis of nearby vertices close to the level.
pub(super) struct Strip<'c, 'a> {
    ctx: &'c Ctx<'a>,
    offsets: Vec<u32>,
    adj: Vec<u32>,
    stamp: Vec<u32>,
    gen: u32,
    queue: Vec<u32>,
}

impl<'c, 'a> Strip<'c, 'a> {
    pub(super) fn new(ctx: &'c Ctx<'a>) -> Self {
        let n = ctx.mesh.n_vertices();
        let mut deg = vec![0u32; n + 1];
        for e in &ctx.topo.edges {
            deg[e.v[0] as usize + 1] += 1;
            deg[e.v[1] as usize + 1] += 1;
        }
        for i in 0..n {
            deg[i + 1] += deg[i];
        }
        let mut fill = deg.clone();
        let mut adj = vec![0u32; deg[n] as usize];
        for e in &ctx.topo.edges {
            for (x, y) in [(e.v[0], e.v[1]), (e.v[1], e.v[0])] {
                adj[fill[x as usize] as usize] = y;
                fill[x as usize] += 1;
            }
        }
        Self {
            ctx,
            offsets: deg,
            adj,
            stamp: vec![0; n],
            gen: 0,
            queue: Vec::new(),
        }
    }

    /// Tangent of the level curve `field = level` at `p` (in `face`), projected on the plane of
    /// normal `nrm` and oriented along `nrm x grad`; `None` when the strip is too small or has
    /// no dominant direction.
    pub(super) fn tangent(
        &mut self,
        field: &[f64],
        level: f64,
        p: DVec3,
        face: u32,
        nrm: DVec3,
        grad: DVec3,
    ) -> Option<DVec3> {
        let so = &self.ctx.opts.strip;
        let eps = so.epsilon * self.ctx.mel;
        let rho = so.radius * self.ctx.mel;
        let pos = self.ctx.mesh.positions();
        self.gen = self.gen.wrapping_add(1);
        if self.gen == 0 {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.gen = 1;
        }
        self.queue.clear();
        for &v in &self.ctx.mesh.triangles()[face as usize] {
            if self.stamp[v as usize] != self.gen {
                self.stamp[v as usize] = self.gen;
                self.queue.push(v);
            }
        }
        let mut pts: Vec<DVec3> = Vec::new();
        let mut head = 0;
        while head < self.queue.len() {
            let v = self.queue[head];
            head += 1;
            let x = pos[v as usize];
            if (x - p).length() > rho {
                continue;
            }
            let u = field[v as usize];
            if u.is_finite() && (u - level).abs() <= eps {
                pts.push(x);
            }
            let (a, b) = (
                self.offsets[v as usize] as usize,
                self.offsets[v as usize + 1] as usize,
            );
            for &w in &self.adj[a..b] {
                if self.stamp[w as usize] != self.gen {
                    self.stamp[w as usize] = self.gen;
                    self.queue.push(w);
                }
            }
        }
        if pts.len() < so.min_vertices.max(2) {
            return None;
        }
        let c = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
        let mut m = [[0.0; 3]; 3];
        for q in &pts {
            let d = *q - c;
            for r in 0..3 {
                for s in 0..3 {
                    m[r][s] += d[r] * d[s];
                }
            }
        }
        let (vals, vecs) = meshcore::linalg::sym_eigen3(glam::DMat3::from_cols_array_2d(&m));
        if vals[0].is_nan() || vals[0] <= 0.0 || vals[0] < so.min_ratio * vals[1].max(0.0) {
            return None;
        }
        let t = vecs[0];
        let t = (t - t.dot(nrm) * nrm).normalize_or_zero();
        if t == DVec3::ZERO {
            return None;
        }
        let reference = nrm.cross(grad);
        Some(if t.dot(reference) < 0.0 { -t } else { t })
    }
}
