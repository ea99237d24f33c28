//! The iso-angle rule on faces with open eyes: between the outer eye corners the eye openings
//! cut level curves of the first field in two pieces (above and below an eye) whose opening
//! ranges overlap, so one key `(i, k, side, sign)` is found on both. `IsoRepeats::Ambiguous`
//! keeps both (flagged ambiguous, never paired); `IsoRepeats::Nearest` (the default) keeps the
//! one nearest the geodesic between the references. Exact fields from the outer eye corners of
//! paper-set faces, static area at N = 10 as in the experiments. Skipped when the shared data
//! folder is absent.

use bipolar::{
    describe, Descriptor, DescriptorOptions, Fields, IsoAngleOptions, IsoRepeats, LevelSpec,
    Surface,
};
use facemodel::Face;
use geodesic::Method;

mod common;

/// The iso-angle descriptor of `face` with `repeats`, and the second field.
fn iso_descriptor(face: &Face, repeats: IsoRepeats) -> (Descriptor, Vec<f64>) {
    let common::CornerFields { ur, uq, d, mask } = common::corner_fields(face, Method::Exact);
    let desc = describe(
        &Surface::new(face.mesh.clone()),
        Fields::Precomputed {
            fields: &[ur, uq.clone()],
            references: None,
        },
        &DescriptorOptions {
            vertex_mask: Some(mask),
            ..common::iso_angle(
                LevelSpec::Step(d / 10.0),
                10,
                IsoAngleOptions {
                    repeats,
                    ..IsoAngleOptions::default()
                },
            )
        },
    )
    .unwrap();
    (desc, uq)
}

fn ambiguous_share(d: &Descriptor) -> f64 {
    d.points.iter().filter(|p| p.ambiguous).count() as f64 / d.points.len() as f64
}

/// Second field at a descriptor point (linear in its face).
fn ub_at(face: &Face, uq: &[f64], p: &bipolar::DescriptorPoint) -> f64 {
    face.mesh
        .interpolate(uq, &meshcore::SurfacePoint::new(p.face, p.bary))
        .unwrap()
}

#[test]
fn repeated_keys_across_the_eye_openings_keep_the_place_nearest_the_geodesic() {
    let Some(faces) = testsupport::paper_faces(&["id1_neutral", "id2_neutral", "id3_neutral"])
    else {
        return;
    };
    let mut checked = 0;
    for face in &faces {
        let (all, uq) = iso_descriptor(face, IsoRepeats::Ambiguous);
        let (near, _) = iso_descriptor(face, IsoRepeats::Nearest);
        let (a, n) = (ambiguous_share(&all), ambiguous_share(&near));
        // The eye openings make many keys repeat; the rule resolves most of them.
        assert!(a > 0.15, "{}: only {:.1} % ambiguous", face.name, 100.0 * a);
        assert!(
            n < 0.5 * a && n < 0.10,
            "{}: {:.1} % -> {:.1} %",
            face.name,
            100.0 * a,
            100.0 * n
        );
        // Points of unrepeated keys are untouched; of each repeated key, the kept point is the
        // one with the smallest second field, and it is no longer ambiguous.
        for p in &near.points {
            let same: Vec<_> = all.points.iter().filter(|q| q.key == p.key).collect();
            assert!(same.iter().any(|q| q.position == p.position));
            if same.len() > 1 && !p.ambiguous {
                let u = ub_at(face, &uq, p);
                assert!(same.iter().all(|q| ub_at(face, &uq, q) >= u), "{:?}", p.key);
            }
        }
        // Every key of the full set is still there (once, or with all its places when they
        // are too close to tell).
        for q in &all.points {
            assert!(near.points.iter().any(|p| p.key == q.key));
        }
        checked += 1;
    }
    assert_eq!(checked, 3);
}
