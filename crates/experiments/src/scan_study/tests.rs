//! Tests of the study's methods and of its `facematch` distances.

use super::description::describe_mesh;
use super::distances::{methods, searched_distance, variant_distance, SEARCHED, VIEW_MATCHED};
use super::variants::{PairCombine, LEAST, VARIANTS};
use super::{matching, Args};
use meshcore::DVec3;

#[test]
fn the_view_matched_variant_is_the_least_of_the_three_pairs() {
    let v = &VARIANTS[LEAST];
    assert!(matches!(v.side_pairs, Some(PairCombine::Least)));
    assert_eq!(v.max_incidence_deg, Some(60.0));
    assert!(VIEW_MATCHED.starts_with(v.name));
    assert!(SEARCHED.starts_with(v.name));
    let mut args = study_args(0.0);
    let m = methods(&args);
    assert_eq!(m.len(), VARIANTS.len() + 3);
    assert_eq!(m[VARIANTS.len()], VIEW_MATCHED);
    args.ref_search_mm = 2.0;
    let m = methods(&args);
    assert_eq!(m.len(), VARIANTS.len() + 4);
    assert_eq!(m[VARIANTS.len() + 1], SEARCHED);
    // The facematch options are the variant's: band, incidence, levels, the least pair.
    let o = matching(&args);
    assert_eq!(o.boundary_margin_mm, v.margin_mm);
    assert_eq!(o.max_incidence_deg, v.max_incidence_deg);
    assert_eq!(o.levels, args.set.res.levels);
    assert!(o.least_pair && o.second_weight == 0.0 && o.gate_mm.is_none());
    assert_eq!(
        o.search.map(|s| (s.radius_mm, s.all_pairs)),
        Some((2.0, true))
    );
    assert!(matching(&study_args(0.0)).search.is_none());
    assert!(o.validate().is_ok());
}

fn study_args(ref_search_mm: f64) -> Args {
    let mut args: Args = crate::parse_args(&["scan-study"]);
    args.ref_search_mm = ref_search_mm;
    args
}

#[test]
fn the_search_finds_a_pole_moved_by_its_radius() {
    // A curved, asymmetric height field in mm on a 1 mm grid (on a plane every placement
    // gives the same scale-free descriptor); the right outer corner of `b` placed on the
    // grid vertex 2 mm toward the left one and the left corner 2 mm toward the right one
    // (so that every pair differs), where the search's first directions put candidates of
    // `a`'s.
    let z = |x: f64, y: f64| 0.006 * x * x + 0.002 * x * y + 0.004 * y * y + 5e-5 * x * x * x;
    let mesh = meshcore::shapes::grid(120, 100, meshcore::shapes::Diagonals::Uniform, |i, j| {
        let (x, y) = (i as f64 - 60.0, j as f64 - 50.0);
        DVec3::new(x, y, z(x, y))
    })
    .unwrap();
    let at = |x: f64, y: f64| DVec3::new(x, y, z(x, y));
    let lms = [at(-40.0, 10.0), at(40.0, 10.0), at(0.0, -25.0)];
    let mut moved = lms;
    moved[0] = at(-38.0, 10.0);
    moved[1] = at(38.0, 10.0);
    let args = study_args(2.0);
    let o = matching(&args);
    let a = describe_mesh(mesh.clone(), &lms, &[], &args).unwrap();
    let b = describe_mesh(mesh, &moved, &[], &args).unwrap();
    let probe = a.matched.as_ref().unwrap().searched.as_ref().unwrap();
    assert!(
        probe.moved.iter().all(|s| s.len() > 20),
        "{:?}",
        probe.moved.each_ref().map(Vec::len)
    );
    let least = variant_distance(&a, &b, LEAST, &o);
    let (searched, fallbacks) = searched_distance(&a, &b, &o);
    assert!(least > 0.005, "{least}");
    // The candidates land on the moved corners: the same descriptor, found exactly.
    assert!(searched < 1e-6 * least, "{searched} against {least}");
    assert_eq!(searched_distance(&b, &a, &o).0, searched);
    // Moved pole pairs whose descriptor fails are left out and counted; nothing else is
    // substituted.
    assert!(
        fallbacks.iter().all(|k| k.ends_with("moved left out")),
        "{fallbacks:?}"
    );
    // Without the search the scans have no moved descriptors and the two distances agree.
    let args = study_args(0.0);
    let o = matching(&args);
    let mesh = a.mesh.clone();
    let (a0, b0) = (
        describe_mesh(mesh.clone(), &lms, &[], &args).unwrap(),
        describe_mesh(mesh, &moved, &[], &args).unwrap(),
    );
    let m0 = a0.matched.as_ref().unwrap();
    assert!(m0.searched.is_none());
    assert!(m0.template.description.moved.iter().all(Vec::is_empty));
    // (The searched one is the lesser of the two ways, which differ by rounding only.)
    let (s0, l0) = (
        searched_distance(&a0, &b0, &o).0,
        variant_distance(&a0, &b0, LEAST, &o),
    );
    assert!(
        (s0 - l0).abs() <= 1e-12 * l0 && s0 <= l0,
        "{s0} against {l0}"
    );
}
