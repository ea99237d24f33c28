//! Golden test: the crate's `SelectionRule::All` descriptor against the independent grid
//! implementation of `testsupport::oracle` on faces of the paper set (Dijkstra fields from the
//! outer eye corners, step D / 10, the whole face up to level 20 and the static area up to
//! level 10): the same keys with the same ambiguity, and the same points to 1e-12 of the
//! face's bounding-box diagonal. Skipped when the shared data folder is absent.

use bipolar::{describe, DescriptorOptions, Fields, LevelSpec, SelectionRule, Surface};
use geodesic::Method;
use testsupport::oracle::{bipolar_grid, grid_key_parts, GridOptions};

mod common;

#[test]
fn rule_all_equals_the_oracle_on_paper_faces() {
    let Some(faces) = testsupport::paper_faces(&["id1_neutral", "id1_anger", "id2_neutral"]) else {
        return;
    };
    let mut compared = 0;
    for f in &faces {
        let m = &f.mesh;
        let common::CornerFields { ur, uq, d, mask } = common::corner_fields(f, Method::Dijkstra);
        let surface = Surface::new(m.clone());
        let tol = 1e-12 * m.bbox().diagonal();
        let step = d / 10.0;
        for (max_level, mask) in [(20, None), (10, Some(mask))] {
            let ours = describe(
                &surface,
                Fields::Precomputed {
                    fields: &[ur.clone(), uq.clone()],
                    references: None,
                },
                &DescriptorOptions {
                    levels: LevelSpec::Step(step),
                    max_level: Some(max_level),
                    vertex_mask: mask.clone(),
                    rule: SelectionRule::All,
                    ..Default::default()
                },
            )
            .unwrap();
            let oracle = bipolar_grid(
                m,
                &ur,
                &uq,
                &GridOptions { step, max_level },
                mask.as_deref(),
            );
            assert!(oracle.len() > 30, "{}: {} points", f.name, oracle.len());
            // One entry per key (the crate keeps every copy of an ambiguous key, all flagged;
            // the oracle keeps the first).
            let mut ours_by_key = ours.points.clone();
            ours_by_key.dedup_by(|b, a| a.key == b.key);
            let crate_keys: Vec<(u32, u32, bool, bool)> = ours_by_key
                .iter()
                .map(|p| (p.key.i, p.key.j, p.key.side > 0, p.ambiguous))
                .collect();
            let oracle_keys: Vec<(u32, u32, bool, bool)> = oracle
                .keys
                .iter()
                .zip(&oracle.ambiguous)
                .map(|(&k, &amb)| {
                    let (i, j, side) = grid_key_parts(k);
                    (i, j, side, amb)
                })
                .collect();
            assert_eq!(
                crate_keys, oracle_keys,
                "{} up to level {max_level}",
                f.name
            );
            for (p, o) in ours_by_key.iter().zip(&oracle.points) {
                let e = (p.position - *o).length();
                assert!(
                    p.ambiguous || e <= tol,
                    "{}: {:?} differs by {e:e}",
                    f.name,
                    p.key
                );
            }
        }
        compared += 1;
    }
    assert_eq!(compared, 3);
}
