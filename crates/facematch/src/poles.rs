//! The reference landmarks of a face (outer eye corners, nose tip) and the three pole pairs.

use landmarks::{LandmarkName, VisibleLandmarks};
use meshcore::{DVec3, TriMesh};

/// An outer eye corner that is not on the surface, and where it is (a ground truth, or where
/// the detector's fitted face predicts it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lost {
    /// The right corner (r); else the left (q).
    pub right: bool,
    /// Where it is (mesh frame).
    pub position: DVec3,
}

/// The three reference vertices of a face. With a [`Lost`] corner only the other corner's side
/// pair describes the face; the lost corner's vertex field holds the nose tip's (never used as
/// a pole: [`Poles::pole_vertices`] refuses it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Poles {
    /// The right outer eye corner.
    pub r: u32,
    /// The left outer eye corner.
    pub q: u32,
    /// The nose tip.
    pub nose: u32,
    /// An outer eye corner that is not on the surface.
    pub lost: Option<Lost>,
}

impl Poles {
    /// The three landmarks without a lost corner.
    pub fn new(r: u32, q: u32, nose: u32) -> Self {
        Self {
            r,
            q,
            nose,
            lost: None,
        }
    }

    /// From the vertices of the outer eye corners and the nose tip (or why each is missing) and
    /// the corners' places `at` (true or predicted): all three, or, with `allow_lost`, one
    /// corner missing (a [`Lost`] corner at its place). Otherwise the first missing one's
    /// reason.
    pub fn from_parts(
        [r, q, nose]: [Result<u32, String>; 3],
        at: [DVec3; 2],
        allow_lost: bool,
    ) -> Result<Self, String> {
        let lost = |right: bool| {
            Some(Lost {
                right,
                position: at[usize::from(!right)],
            })
        };
        match (r, q, nose?) {
            (Ok(r), Ok(q), nose) => Ok(Self::new(r, q, nose)),
            (Err(_), Ok(q), nose) if allow_lost => Ok(Self {
                r: nose,
                q,
                nose,
                lost: lost(true),
            }),
            (Ok(r), Err(_), nose) if allow_lost => Ok(Self {
                r,
                q: nose,
                nose,
                lost: lost(false),
            }),
            (Err(e), _, _) | (_, Err(e), _) => Err(e),
        }
    }

    /// From detected landmarks on `mesh` ([`Poles::from_parts`]): a corner the detector reported
    /// unseen may be lost, at the place the fitted face predicts, or with `predicted` placed at
    /// the vertex nearest that place when it is within `snap` of the mesh.
    pub fn from_detected(
        mesh: &TriMesh,
        d: &VisibleLandmarks,
        allow_lost: bool,
        predicted: bool,
        snap: f64,
    ) -> Result<Self, String> {
        use LandmarkName as L;
        let v = |n: L| {
            d.get(n).map(|l| l.vertex).or_else(|u| {
                let placed = (predicted && n != L::NoseTip)
                    .then(|| crate::nearest_vertex(mesh, d.predicted[n as usize]))
                    .flatten();
                match placed {
                    Some((w, dist)) if dist <= snap => Ok(w),
                    _ => Err(format!("detection: {n} {u}")),
                }
            })
        };
        Self::from_parts(
            [v(L::OuterEyeRight), v(L::OuterEyeLeft), v(L::NoseTip)],
            [
                d.predicted[L::OuterEyeRight as usize],
                d.predicted[L::OuterEyeLeft as usize],
            ],
            allow_lost,
        )
    }

    /// Positions of r, q and the nose tip (for a lost corner, its [`Lost::position`]).
    pub fn positions(self, mesh: &TriMesh) -> [DVec3; 3] {
        let mut p = [self.r, self.q, self.nose].map(|v| mesh.position(v));
        if let Some(l) = self.lost {
            p[usize::from(!l.right)] = l.position;
        }
        p
    }

    /// The two pole vertices of `pair`, in the places of r and q.
    pub fn pole_vertices(self, pair: Pair) -> (u32, u32) {
        match pair {
            Pair::Corners => (self.r, self.q),
            Pair::RightNose => (self.r, self.nose),
            Pair::LeftNose => (self.q, self.nose),
        }
    }

    /// The same poles on a renumbered mesh (`map[old] = new`, `u32::MAX`: dropped), a dropped
    /// landmark placed at the vertex of `to` nearest its old place within `snap`; `None` when
    /// one cannot be placed. A lost corner stays lost.
    pub fn carried(self, from: &TriMesh, to: &TriMesh, map: &[u32], snap: f64) -> Option<Self> {
        let place = |v: u32| match map.get(v as usize).copied() {
            Some(w) if w != u32::MAX => Some(w),
            _ => match crate::nearest_vertex(to, from.position(v)) {
                Some((w, d)) if d <= snap => Some(w),
                _ => None,
            },
        };
        let nose = place(self.nose)?;
        let corner = |v: u32, right: bool| match self.lost {
            Some(l) if l.right == right => Some(nose),
            _ => place(v),
        };
        Some(Self {
            r: corner(self.r, true)?,
            q: corner(self.q, false)?,
            nose,
            lost: self.lost,
        })
    }
}

/// The two poles of a bipolar descriptor: the outer eye corners (the paper's), or one outer eye
/// corner with the nose tip. The discriminant indexes per-pair arrays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Pair {
    /// The outer eye corners.
    Corners = 0,
    /// The right outer eye corner (r) and the nose tip.
    RightNose = 1,
    /// The left outer eye corner (q) and the nose tip.
    LeftNose = 2,
}

impl Pair {
    /// The three pairs, in index order.
    pub const ALL: [Pair; 3] = [Pair::Corners, Pair::RightNose, Pair::LeftNose];

    /// The pair's name in files and reports.
    pub fn name(self) -> &'static str {
        match self {
            Pair::Corners => "corners",
            Pair::RightNose => "right-nose",
            Pair::LeftNose => "left-nose",
        }
    }

    /// The pair by its index.
    pub fn from_index(i: usize) -> Option<Pair> {
        Self::ALL.get(i).copied()
    }

    /// The pair a probe is compared by: the corners, or, when `limit_deg` is given and the face
    /// is turned from its scanner (direction `scanner`) by more than it, the corner nearer the
    /// scanner with the nose tip. The turn is estimated from the eye line alone,
    /// `asin(|x . scanner|)` (x: the unit eye line r to q), so a pitch of the head barely
    /// changes it. A face with a lost corner has only the other corner's pair.
    pub fn for_probe(
        r: DVec3,
        q: DVec3,
        scanner: DVec3,
        limit_deg: Option<f64>,
        lost: Option<Lost>,
    ) -> Pair {
        match lost {
            Some(l) if l.right => return Pair::LeftNose,
            Some(_) => return Pair::RightNose,
            None => {}
        }
        let Some(limit) = limit_deg else {
            return Pair::Corners;
        };
        let s = (q - r).normalize_or_zero().dot(scanner.normalize_or_zero());
        match s.abs().clamp(0.0, 1.0).asin().to_degrees() {
            t if t <= limit => Pair::Corners,
            _ if s > 0.0 => Pair::LeftNose,
            _ => Pair::RightNose,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_corner_is_lost_only_when_allowed() {
        let at = [DVec3::X, DVec3::Y];
        let p = Poles::from_parts([Err("gone".into()), Ok(4), Ok(9)], at, true).unwrap();
        assert_eq!(
            p.lost.map(|l| (l.right, l.position)),
            Some((true, DVec3::X))
        );
        assert_eq!(p.q, 4);
        let e = Poles::from_parts([Err("gone".into()), Ok(4), Ok(9)], at, false).unwrap_err();
        assert_eq!(e, "gone");
        let e = Poles::from_parts([Ok(1), Ok(4), Err("no nose".into())], at, true).unwrap_err();
        assert_eq!(e, "no nose");
    }

    #[test]
    fn a_turned_face_takes_the_nearer_side_pair() {
        let z = DVec3::Z;
        let r = DVec3::new(-5.0, 0.0, 0.0);
        let turn = |deg: f64| {
            let a = deg.to_radians();
            r + 10.0 * DVec3::new(a.cos(), 0.0, a.sin())
        };
        assert_eq!(
            Pair::for_probe(r, turn(20.0), z, Some(30.0), None),
            Pair::Corners
        );
        assert_eq!(
            Pair::for_probe(r, turn(40.0), z, Some(30.0), None),
            Pair::LeftNose
        );
        assert_eq!(
            Pair::for_probe(r, turn(-40.0), z, Some(30.0), None),
            Pair::RightNose
        );
        assert_eq!(Pair::for_probe(r, turn(40.0), z, None, None), Pair::Corners);
        let lost = Some(Lost {
            right: false,
            position: DVec3::ZERO,
        });
        assert_eq!(
            Pair::for_probe(r, turn(0.0), z, None, lost),
            Pair::RightNose
        );
    }

    #[test]
    fn a_turned_probe_takes_the_corner_nearer_its_scanner() {
        // Eye line along x, 100 mm, turned about the vertical y axis; the scanner looks down z.
        let eyes = |yaw_deg: f64| {
            let t = meshcore::DQuat::from_rotation_y(yaw_deg.to_radians());
            (
                t * DVec3::new(-50.0, 0.0, 0.0),
                t * DVec3::new(50.0, 0.0, 0.0),
            )
        };
        let pick = |yaw: f64, limit: Option<f64>| {
            let (r, q) = eyes(yaw);
            Pair::for_probe(r, q, DVec3::Z, limit, None)
        };
        assert_eq!(pick(0.0, Some(30.0)), Pair::Corners);
        assert_eq!(pick(25.0, Some(30.0)), Pair::Corners);
        assert_eq!(pick(-25.0, Some(30.0)), Pair::Corners);
        assert_eq!(pick(40.0, None), Pair::Corners);
        // Turned by 40 degrees: the corner with the larger z faces the scanner.
        for yaw in [35.0, 40.0, -35.0, -40.0] {
            let (r, q) = eyes(yaw);
            let near = if q.z > r.z {
                Pair::LeftNose
            } else {
                Pair::RightNose
            };
            assert_eq!(pick(yaw, Some(30.0)), near, "yaw {yaw}");
        }
        // A pitch of the head (about x) barely moves the estimate.
        let nod = meshcore::DQuat::from_rotation_x(0.4);
        let (r, q) = eyes(20.0);
        assert_eq!(
            Pair::for_probe(nod * r, nod * q, DVec3::Z, Some(30.0), None),
            Pair::Corners
        );
        // A lost corner leaves the other's pair, whatever the turn.
        let lost = |right| {
            Some(Lost {
                right,
                position: DVec3::ZERO,
            })
        };
        let (r, q) = eyes(0.0);
        assert_eq!(
            Pair::for_probe(r, q, DVec3::Z, None, lost(true)),
            Pair::LeftNose
        );
        assert_eq!(
            Pair::for_probe(r, q, DVec3::Z, Some(30.0), lost(false)),
            Pair::RightNose
        );
    }

    /// A 40 x 40 mm sheet (2 mm grid) and detected landmarks at grid vertices, the right outer
    /// corner unseen and predicted at `predicted`.
    fn sheet(predicted: DVec3) -> (TriMesh, VisibleLandmarks) {
        use landmarks::{Landmark, Unseen};
        let mesh =
            meshcore::shapes::grid(20, 20, meshcore::shapes::Diagonals::Alternating, |i, j| {
                DVec3::new(2.0 * i as f64, 2.0 * j as f64, 0.0)
            })
            .unwrap();
        let at = |i: u32, j: u32| j * 21 + i;
        // In `LandmarkName::ALL` order: outer right, inner right, inner left, outer left, nose.
        let vertices = [at(2, 15), at(6, 15), at(14, 15), at(18, 15), at(10, 5)];
        let landmark = |v: u32| Landmark {
            vertex: v,
            position: mesh.position(v),
            confidence: 1.0,
        };
        let mut landmarks = vertices.map(|v| Ok(landmark(v)));
        landmarks[LandmarkName::OuterEyeRight as usize] =
            Err(Unseen::Unobserved { agreement: 0.8 });
        let mut at_pred = vertices.map(|v| mesh.position(v));
        at_pred[LandmarkName::OuterEyeRight as usize] = predicted;
        let found = VisibleLandmarks {
            landmarks,
            predicted: at_pred,
            confidence: 1.0,
            fit_rms: 0.0,
            inlier_fraction: 1.0,
            symmetry: 1.0,
            model_to_mesh: meshcore::DAffine3::IDENTITY,
        };
        (mesh, found)
    }

    #[test]
    fn an_unseen_corner_is_lost_or_placed_at_its_prediction() {
        // Predicted 1.02 mm from the sheet's vertex (3, 15), its nearest.
        let (mesh, d) = sheet(DVec3::new(6.2, 30.0, 1.0));
        let poles = |lost, predicted| Poles::from_detected(&mesh, &d, lost, predicted, 3.0);
        let lost = poles(true, false).unwrap();
        assert_eq!(lost.lost.map(|l| l.right), Some(true));
        let placed = poles(true, true).unwrap();
        assert_eq!(placed.lost, None);
        assert_eq!(placed.r, 15 * 21 + 3);
        assert_eq!(placed.q, 15 * 21 + 18);
        // Without lost corners allowed, the unseen corner is an error unless placed.
        assert!(poles(false, false).unwrap_err().contains("outer_eye_right"));
        assert_eq!(poles(false, true).unwrap(), placed);
        // A prediction farther than the snap distance from the sheet stays lost.
        let (mesh, d) = sheet(DVec3::new(6.0, 30.0, 3.5));
        let far = Poles::from_detected(&mesh, &d, true, true, 3.0).unwrap();
        assert!(far.lost.is_some());
    }
}
