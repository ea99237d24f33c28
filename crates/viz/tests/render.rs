//! Mesh rendering tests: determinism, silhouette area, visibility of curves and points.

use glam::DVec3;
use meshcore::TriMesh;
use std::f64::consts::{PI, TAU};
use viz::{
    colormap, render_png, render_rgb, render_svg, render_to_file, Marker, Polyline, Scene, View,
    VizError,
};

/// UV sphere of radius `r` centred at the origin (outward-oriented triangles), poles on y.
fn sphere(r: f64, n_lat: usize, n_lon: usize) -> TriMesh {
    let m = testsupport::uv_sphere_y_up(r, n_lat, n_lon);
    // Orientation check: the normal of the first face points outwards.
    let f0 = m.face_corners(0);
    assert!(m.face_normal(0).dot(f0[0] + f0[1] + f0[2]) > 0.0);
    m
}

const BG: [u8; 3] = [255, 255, 255];

fn pixel(rgb: &[u8], w: u32, x: u32, y: u32) -> [u8; 3] {
    let i = ((y * w + x) * 3) as usize;
    [rgb[i], rgb[i + 1], rgb[i + 2]]
}

#[test]
fn png_is_deterministic_and_valid() {
    let mesh = sphere(1.0, 24, 48);
    let mut scene = Scene::new(&mesh);
    scene.polylines.push(Polyline {
        points: (0..=64)
            .map(|k| {
                let a = TAU * k as f64 / 64.0;
                DVec3::new(a.cos(), 0.0, a.sin())
            })
            .collect(),
        closed: false,
        color: [200, 0, 0],
        width: 2.0,
    });
    let a = render_png(&scene, &View::front(), 160, 120).unwrap();
    let b = render_png(&scene, &View::front(), 160, 120).unwrap();
    assert_eq!(a, b);
    assert_eq!(&a[..8], b"\x89PNG\r\n\x1a\n");
    let s1 = render_svg(&scene, &View::front(), 160, 120);
    let s2 = render_svg(&scene, &View::front(), 160, 120);
    assert_eq!(s1, s2);
    assert!(s1.starts_with("<svg") && s1.trim_end().ends_with("</svg>"));
}

#[test]
fn sphere_silhouette_area_matches_disc() {
    // The scene is fitted with 5 % margins: the sphere's diameter spans 90 % of the smaller
    // side, so its silhouette is a disc of radius 0.45 * 200 = 90 px.
    let mesh = sphere(1.0, 48, 96);
    let scene = Scene::new(&mesh);
    for view in [
        View::front(),
        View::top(),
        View::new(DVec3::new(1.0, -2.0, 0.5), DVec3::Z),
    ] {
        let (w, h) = (240u32, 200u32);
        let rgb = render_rgb(&scene, &view, w, h).unwrap();
        let covered = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| pixel(&rgb, w, x, y) != BG)
            .count() as f64;
        let expected = PI * 90.0 * 90.0;
        let rel = (covered - expected).abs() / expected;
        assert!(
            rel < 0.03,
            "view {view:?}: {covered} px vs {expected:.0} ({rel:.3})"
        );
    }
    // Same in SVG: count polygons is not an area, but front-facing culling keeps about half.
    let svg = render_svg(&scene, &View::front(), 240, 200);
    let n = svg.matches("<polygon").count();
    assert!(
        n > mesh.n_faces() * 2 / 5 && n < mesh.n_faces() * 3 / 5,
        "{n}"
    );
}

fn ring_at_z(z: f64, r: f64) -> Vec<DVec3> {
    (0..48)
        .map(|k| {
            let a = TAU * k as f64 / 48.0;
            DVec3::new(r * a.cos(), r * a.sin(), z)
        })
        .collect()
}

#[test]
fn polyline_behind_mesh_is_hidden_and_point_in_front_is_drawn() {
    let mesh = sphere(1.0, 32, 64);
    let (w, h) = (200u32, 200u32);
    let plain = render_rgb(&Scene::new(&mesh), &View::front(), w, h).unwrap();
    // A ring on the back hemisphere (z = -0.6, radius 0.8): hidden in the front view.
    let mut scene = Scene::new(&mesh);
    scene.polylines.push(Polyline {
        points: ring_at_z(-0.6, 0.8),
        closed: true,
        color: [255, 0, 0],
        width: 3.0,
    });
    let behind = render_rgb(&scene, &View::front(), w, h).unwrap();
    assert_eq!(plain, behind, "a curve behind the sphere must not be drawn");
    let svg = render_svg(&scene, &View::front(), w, h);
    assert!(!svg.contains("<polyline"));
    // The same ring in the back view is visible.
    let back = render_rgb(&scene, &View::back(), w, h).unwrap();
    let red = |rgb: &[u8]| {
        rgb.chunks_exact(3)
            .filter(|p| p[0] > 180 && p[1] < 80 && p[2] < 80)
            .count()
    };
    assert!(red(&back) > 100, "{}", red(&back));
    assert!(render_svg(&scene, &View::back(), w, h).contains("<polyline"));
    // On the front hemisphere: visible.
    let mut scene = Scene::new(&mesh);
    scene.polylines.push(Polyline {
        points: ring_at_z(0.6, 0.8),
        closed: true,
        color: [255, 0, 0],
        width: 3.0,
    });
    assert!(red(&render_rgb(&scene, &View::front(), w, h).unwrap()) > 100);
    // A point in front of the sphere is drawn; one behind is not.
    let mut scene = Scene::new(&mesh);
    scene.points.push(Marker {
        position: DVec3::new(0.0, 0.0, 1.0),
        color: [0, 0, 255],
        radius: 5.0,
    });
    scene.points.push(Marker {
        position: DVec3::new(0.5, 0.5, -0.70),
        color: [0, 255, 0],
        radius: 5.0,
    });
    let rgb = render_rgb(&scene, &View::front(), w, h).unwrap();
    let c = pixel(&rgb, w, 100, 100);
    assert!(c[2] > 200 && c[0] < 60, "centre pixel {c:?}");
    assert!(!rgb
        .chunks_exact(3)
        .any(|p| p[1] > 200 && p[0] < 60 && p[2] < 60));
    let svg = render_svg(&scene, &View::front(), w, h);
    assert_eq!(svg.matches("<circle").count(), 1);
    assert!(svg.contains("#0000ff"));
}

#[test]
fn vertex_colors_show_and_are_validated() {
    let mesh = sphere(1.0, 16, 32);
    let field: Vec<f64> = mesh.positions().iter().map(|p| p.y).collect();
    let scene = Scene::new(&mesh).with_field(&field);
    let (w, h) = (100u32, 100u32);
    let rgb = render_rgb(&scene, &View::front(), w, h).unwrap();
    // Top is yellowish (high), bottom purple (low).
    let top = pixel(&rgb, w, 50, 15);
    let bottom = pixel(&rgb, w, 50, 85);
    assert!(
        top[1] > bottom[1] && top[0] > bottom[0],
        "{top:?} {bottom:?}"
    );
    let mut bad = Scene::new(&mesh);
    bad.vertex_colors = Some(vec![[0, 0, 0]; 3]);
    assert!(matches!(
        render_png(&bad, &View::front(), w, h),
        Err(VizError::VertexColorCount { got: 3, .. })
    ));
    assert!(matches!(
        render_png(&scene, &View::front(), 0, h),
        Err(VizError::InvalidSize { .. })
    ));
    // SVG ignores the bad colours rather than failing, render_to_file validates.
    assert!(render_svg(&bad, &View::front(), w, h).contains("<polygon"));
    let dir = std::env::temp_dir().join(format!("viz-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    assert!(render_to_file(dir.join("x.svg"), &bad, &View::front(), w, h).is_err());
    assert!(matches!(
        render_to_file(dir.join("x.jpg"), &scene, &View::front(), w, h),
        Err(VizError::UnsupportedFormat(_))
    ));
    render_to_file(dir.join("x.PNG"), &scene, &View::front(), w, h).unwrap();
    let bytes = std::fs::read(dir.join("x.PNG")).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    render_to_file(dir.join("x.svg"), &scene, &View::front(), w, h).unwrap();
    let text = std::fs::read_to_string(dir.join("x.svg")).unwrap();
    assert!(text.contains("<svg"));
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(colormap::field_colors(&field).len(), mesh.n_vertices());
}

#[test]
fn non_finite_overlays_are_skipped_and_views_parse() {
    let mesh = sphere(1.0, 8, 16);
    let mut scene = Scene::new(&mesh);
    scene.polylines.push(Polyline {
        points: vec![
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::NAN,
            DVec3::new(0.5, 0.0, 0.9),
        ],
        closed: false,
        color: [255, 0, 0],
        width: 1.0,
    });
    scene.points.push(Marker {
        position: DVec3::new(f64::INFINITY, 0.0, 0.0),
        color: [0, 0, 0],
        radius: 3.0,
    });
    assert!(render_png(&scene, &View::front(), 64, 64).is_ok());
    assert!(!render_svg(&scene, &View::front(), 64, 64).contains("<circle"));
    assert_eq!(View::parse("front").unwrap(), View::front());
    assert_eq!(View::parse(" Top ").unwrap(), View::top());
    let v = View::parse("0, 0, -2").unwrap();
    assert!((v.dir - DVec3::NEG_Z).length() < 1e-15);
    assert!(View::parse("0,0,0").is_err());
    assert!(View::parse("sideways").is_err());
    assert!(View::parse("1,2").is_err());
    // Degenerate views are repaired, not fatal.
    let (r, u, f) = View::new(DVec3::Y, DVec3::Y).basis();
    assert!((r.cross(u) - (-f)).length() < 1e-12 || (r.cross(u) + f).length() < 1e-12);
    let (r, u, f) = View::front().basis();
    assert!((r - DVec3::X).length() < 1e-15);
    assert!((u - DVec3::Y).length() < 1e-15);
    assert!((f - DVec3::NEG_Z).length() < 1e-15);
}

#[test]
fn picture_format_names_round_trip() {
    testsupport::check_choice_error::<viz::Format>("jpg", |e| {
        matches!(e, viz::VizError::UnknownChoice(_))
    });
}
