//! Where the time of enrolling one scan goes: `cargo run --release -p facematch --example
//! enroll_timing -- SCAN.bnt [RUNS] [METHOD]` prints, per run, the preparation's steps (with the
//! cleaning's own steps), the description and the views, as the median over the runs. METHOD
//! (default: the options' exact) is the geodesic method of the fields, to time another one.

use facematch::{describe_view, view_directions, MatchOptions, ScanInput, Template};
use landmarks::GenericModel;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: enroll_timing SCAN.bnt [RUNS] [METHOD]")?;
    let runs: usize = args.next().map_or(Ok(5), |s| s.parse())?;
    let mut options = MatchOptions::default();
    if let Some(m) = args.next() {
        options.method = m.parse()?;
    }
    let grid = mesh_io::read_bnt_grid(&path)?;
    let generic = GenericModel::default_model()?;
    let mut rows: Vec<Vec<(String, f64)>> = Vec::new();
    for _ in 0..runs {
        let mut row = Vec::new();
        let t = Instant::now();
        let scan = facematch::prepare_with(ScanInput::Grid(&grid), &generic, &options)?;
        row.push(("prepare".to_string(), t.elapsed().as_secs_f64()));
        let st = scan.times;
        for (n, d) in [
            ("  clean", st.clean),
            ("  detect", st.detect),
            ("  crop clean", st.crop_clean),
            ("  crop detect", st.crop_detect),
        ] {
            row.push((n.to_string(), d.as_secs_f64()));
        }
        let t = Instant::now();
        let poles = scan.poles(&options)?;
        let d = facematch::describe(&scan.mesh, poles, scan.scanner, &options, false)?;
        row.push(("describe".to_string(), t.elapsed().as_secs_f64()));
        let t = Instant::now();
        if let Some(v) = &options.view {
            let [r, q, _] = d.landmarks;
            for (_, toward) in view_directions(scan.scanner, r, q, &v.yaws_deg) {
                let _ = describe_view(&scan.mesh, poles, scan.scanner, toward, &options, v);
            }
        }
        row.push(("views (one thread)".to_string(), t.elapsed().as_secs_f64()));
        let t = Instant::now();
        let _ = Template::of_scan(&scan, "a", &path, &options, false)?;
        row.push(("template (parallel)".to_string(), t.elapsed().as_secs_f64()));
        row.push(("vertices".to_string(), scan.mesh.n_vertices() as f64));
        rows.push(row);
    }
    // The cleaning's own steps, once.
    let clean = scanprep::clean(scanprep::Input::Grid(&grid), &options.prepare.clean)?;
    for (n, d) in &clean.report.timings {
        println!("clean step {n:12} {:.3}", d.as_secs_f64());
    }
    println!("clean output vertices  {}", clean.mesh.n_vertices());
    for k in 0..rows[0].len() {
        let mut v: Vec<f64> = rows.iter().map(|r| r[k].1).collect();
        v.sort_by(f64::total_cmp);
        println!("{:22} {:.3}", rows[0][k].0, v[v.len() / 2]);
    }
    Ok(())
}
