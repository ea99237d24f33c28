//! The four descriptors of one face configuration and the four distances between two, with
//! the refusals listed instead of stopping the run.

use super::Args;
use crate::pipeline::{dist, Area, PoleRefs};
use crate::polar::{self, polar_descriptor, PolarOptions, Pole};
use crate::report::Failures;
use crate::walk::Walker;
use bipolar::PolarDescriptor;
use facecurves::nose::{facial_curves, facial_distance, iso_curves, iso_distance};
use facecurves::{ElasticOptions, FacialCurvesDescriptor, IsoCurvatureDescriptor, IsoLevels};
use meshcore::{Surface, TriMesh};
use std::time::{Duration, Instant};

/// The four descriptors of one face configuration (`None`: not asked for, or refused and
/// listed in the failures; a single pole whose rays reach no level is the empty set).
#[derive(Debug, Clone)]
pub(super) struct Descs {
    pub bipolar: Option<bipolar::Descriptor>,
    pub polar: Option<PolarDescriptor>,
    pub facial: Option<FacialCurvesDescriptor>,
    pub iso: Option<IsoCurvatureDescriptor>,
}

/// What describing a configuration needs besides the fields.
pub(super) struct Ctx<'a> {
    /// The task's arguments (resolution).
    pub args: &'a Args,
    /// The iso-curvature levels, the same for every face.
    pub iso_levels: IsoLevels,
    /// Where refusals are listed.
    pub failures: &'a Failures,
}

impl Ctx<'_> {
    /// The static-area bipolar descriptor of `refs` (`None`: refused, listed).
    pub(super) fn bipolar(
        &self,
        mesh: &TriMesh,
        refs: &PoleRefs,
        name: &str,
    ) -> Option<bipolar::Descriptor> {
        let surface = bipolar::Surface::new(mesh.clone());
        let n = self.args.set.res.levels;
        let d = refs.descriptor(&surface, n, Area::Static, None, facematch::grid_rule());
        self.failures
            .ok(d, || format!("bipolar descriptor of {name}"))
    }

    /// Single pole, facial curves and iso-curvature (region of radius D) from the nose field
    /// `un` with the pole `nose`; no bipolar descriptor.
    pub(super) fn nose_descs(
        &self,
        (mesh, walker): (&TriMesh, &Walker<'_>),
        refs: &PoleRefs,
        un: &[f64],
        nose: Pole,
        name: &str,
    ) -> Descs {
        let n = self.args.set.res.levels;
        let popts = PolarOptions {
            step: refs.d / f64::from(n),
            levels: n,
            sectors: self.args.set.res.sectors,
        };
        let polar = polar_descriptor(walker, un, nose, 0.5 * (refs.r + refs.q), &popts);
        let polar = self.failures.ok(polar, || format!("single pole of {name}"));
        let surface = Surface::new(mesh.clone());
        let facial = facial_curves(&surface, un, refs.d, n);
        let iso = iso_curves(&surface, un, refs.d, &self.iso_levels);
        Descs {
            bipolar: None,
            polar: Some(polar.unwrap_or_else(|| polar::empty(&popts))),
            facial: self
                .failures
                .ok(facial, || format!("facial curves of {name}")),
            iso: self
                .failures
                .ok(iso, || format!("iso-curvature curves of {name}")),
        }
    }

    /// All four descriptors: [`Ctx::bipolar`] and [`Ctx::nose_descs`].
    pub(super) fn describe(
        &self,
        mesh_walker: (&TriMesh, &Walker<'_>),
        refs: &PoleRefs,
        un: &[f64],
        nose: Pole,
        name: &str,
    ) -> Descs {
        Descs {
            bipolar: self.bipolar(mesh_walker.0, refs, name),
            ..self.nose_descs(mesh_walker, refs, un, nose, name)
        }
    }

    /// The four distances (NaN where a descriptor is missing or the distance failed) and the
    /// time each took.
    pub(super) fn distances(&self, a: &Descs, b: &Descs, what: &str) -> ([f64; 4], [Duration; 4]) {
        let mut d = [f64::NAN; 4];
        let mut t = [Duration::ZERO; 4];
        let t0 = Instant::now();
        d[0] = dist(&a.bipolar, &b.bipolar).unwrap_or(f64::NAN);
        t[0] = t0.elapsed();
        let t0 = Instant::now();
        d[1] = dist(&a.polar, &b.polar).unwrap_or(f64::NAN);
        t[1] = t0.elapsed();
        if let (Some(x), Some(y)) = (&a.facial, &b.facial) {
            let t0 = Instant::now();
            let r = facial_distance(x, y, &ElasticOptions::default());
            t[2] = t0.elapsed();
            d[2] = self
                .failures
                .ok(r, || format!("facial distance {what}"))
                .unwrap_or(f64::NAN);
        }
        if let (Some(x), Some(y)) = (&a.iso, &b.iso) {
            let t0 = Instant::now();
            let r = iso_distance(x, y);
            t[3] = t0.elapsed();
            d[3] = self
                .failures
                .ok(r, || format!("iso-curvature distance {what}"))
                .unwrap_or(f64::NAN);
        }
        (d, t)
    }
}
