//! What cleaning removes on the scanner's default artifacts: scans the neutral paper-set faces
//! (ICT, cm) with `Artifacts::structured_light()` and, with the same seed, without spikes and
//! outliers, so the planted ones are known; then runs the spike pass, the hole pass and the
//! whole default `clean` and prints the counts. Needs the shared data
//! (`cargo run --release -p scanprep --example artifacts`).

use rangescan::{scan, Artifacts, ScanOptions};
use scanprep::{clean, fill_grid_holes, remove_grid_spikes, CleanOptions, Input, SpikeOptions};

fn main() {
    let Some(dir) = testsupport::shared_path(testsupport::PAPER_SET) else {
        return;
    };
    println!("face          pitch  valid   spikes caught  outliers caught  good removed  holes planted->found filled left  clean: vertices  ms");
    for id in 1..=6 {
        let path = dir.join(format!("id{id}_neutral.obj"));
        let face = testsupport::read_mesh(&path);
        for pitch in [0.5, 0.75] {
            let art = Artifacts::structured_light();
            let o = ScanOptions {
                input_mm_per_unit: 10.0,
                pitch_mm: pitch,
                artifacts: art,
                seed: id,
                ..ScanOptions::default()
            };
            let s = scan(&face, &o).expect("scan");
            let quiet = ScanOptions {
                artifacts: Artifacts {
                    spikes: None,
                    outliers: None,
                    ..art
                },
                ..o.clone()
            };
            let q = scan(&face, &quiet).expect("scan");
            let g = &s.grid;
            let n = g.xyz.len();
            let spike: Vec<bool> = (0..n)
                .map(|i| g.is_valid(i) && q.grid.is_valid(i) && g.xyz[i] != q.grid.xyz[i])
                .collect();
            let outlier: Vec<bool> = (0..n)
                .map(|i| g.is_valid(i) && !q.grid.is_valid(i))
                .collect();
            let mut h = g.clone();
            remove_grid_spikes(&mut h, &SpikeOptions::default()).expect("spikes");
            let removed = |i: usize| g.is_valid(i) && !h.is_valid(i);
            let sc = (0..n).filter(|&i| spike[i] && removed(i)).count();
            let oc = (0..n).filter(|&i| outlier[i] && removed(i)).count();
            let good = (0..n)
                .filter(|&i| !spike[i] && !outlier[i] && removed(i))
                .count();
            let holes = fill_grid_holes(&mut h, 10.0).expect("holes");
            let filled = holes.iter().filter(|x| x.filled).count();
            let t = std::time::Instant::now();
            let c = clean(Input::Grid(g), &CleanOptions::default()).expect("clean");
            let ms = t.elapsed().as_secs_f64() * 1e3;
            println!(
                "id{id}_neutral  {pitch:.2}  {:>6}  {:>4}/{:<4}       {:>3}/{:<3}          {:>4} ({:.3} %)  4 -> {:>2} {:>2} {:>2}        {:>7}  {ms:.0}",
                s.stats.valid,
                sc,
                spike.iter().filter(|&&x| x).count(),
                oc,
                outlier.iter().filter(|&&x| x).count(),
                good,
                100.0 * good as f64 / s.stats.valid as f64,
                holes.len(),
                filled,
                holes.len() - filled,
                c.report.output.0
            );
            if id == 1 && pitch == 0.5 {
                for l in c.report.summary() {
                    println!("    {l}");
                }
            }
        }
    }
}
