//! A small hand-made template: the committed format fixture (`fixtures/facematch/small.bpt`)
//! is its bytes.

use crate::{Description, KeyedSet, Lost, Pair, Template, TemplateView};
use meshcore::DVec3;

/// A small template with every kind of field: a failed pair, moved sets, a lost corner, a view
/// and a failed view. `cargo run -p facematch --example write_fixture` writes its bytes.
pub fn small_template() -> Template {
    let set = |n: u64, s: f64| KeyedSet {
        keys: (0..n).map(|k| k * 7 + 3).collect(),
        points: (0..n)
            .map(|k| DVec3::new(s * k as f64, -0.1 * k as f64, 1.0 / (k as f64 + 3.0)))
            .collect(),
    };
    Template {
        identity: "id07".into(),
        source: "id07-e0.bnt".into(),
        settings: "method=exact levels=10".into(),
        description: Description {
            sets: [
                Ok(set(4, 0.5)),
                Err("bipolar descriptor: no points".into()),
                Ok(set(3, 1.25)),
            ],
            moved: [
                vec![set(2, 0.75)],
                Vec::new(),
                vec![set(3, 2.0), set(1, 3.0)],
            ],
            moved_failed: [1, 0, 2],
            pair: Pair::LeftNose,
            landmarks: [
                DVec3::new(-45.5, 10.0, 3.0),
                DVec3::new(46.0, 9.5, 2.5),
                DVec3::new(0.0, -25.0, 30.0),
            ],
            lost: Some(Lost {
                right: true,
                position: DVec3::new(-45.5, 10.0, 3.0),
            }),
            scanner: DVec3::Z,
        },
        views: vec![
            TemplateView {
                yaw_deg: 15.0,
                toward: DVec3::new(0.25881904510252074, 0.0, 0.9659258262890683),
                sets: Ok([
                    Ok(set(2, 0.1)),
                    Err("a pole has no field".into()),
                    Ok(set(5, 0.2)),
                ]),
            },
            TemplateView {
                yaw_deg: -15.0,
                toward: DVec3::new(-0.25881904510252074, 0.0, 0.9659258262890683),
                sets: Err("a landmark is not on the view".into()),
            },
        ],
        notes: vec!["no scanner direction given: +z taken".into()],
    }
}
