//! Time per step of scan preparation on a ~40k-sample scan of an ICT face (0.75 mm pitch,
//! the structured-light artifact model). Skipped when the shared data are absent.

// criterion_group! generates an undocumented function.
#![allow(missing_docs)]
use criterion::{criterion_group, criterion_main, Criterion};
use mesh_io::BntOptions;
use meshcore::DVec3;
use rangescan::{scan, Artifacts, ScanOptions};
use scanprep::{
    check_grid, clean, crop_sphere, decimate, fill_grid_holes, remove_grid_spikes,
    remove_small_components, taubin_smooth, CleanOptions, Crop, Input, SpikeOptions,
};

fn bench(c: &mut Criterion) {
    let Some(path) = testsupport::paper_face("id1_neutral.obj") else {
        return;
    };
    let face = testsupport::read_mesh(path);
    let o = ScanOptions {
        input_mm_per_unit: 10.0,
        pitch_mm: 0.75,
        artifacts: Artifacts::structured_light(),
        seed: 1,
        ..ScanOptions::default()
    };
    let s = scan(&face, &o).expect("scan");
    let g = s.grid;
    println!(
        "scan: {} x {}, {} valid samples",
        g.nrows, g.ncols, s.stats.valid
    );
    // The nose tip: the scan's front-most valid sample.
    let nose = (0..g.xyz.len())
        .filter(|&i| g.is_valid(i))
        .map(|i| g.xyz[i])
        .max_by(|a, b| a.z.total_cmp(&b.z))
        .unwrap_or(DVec3::ZERO);
    let mut grp = c.benchmark_group("scanprep");
    grp.sample_size(20);
    grp.bench_function("check", |b| b.iter(|| check_grid(&g, 0.5).unwrap()));
    grp.bench_function("spikes", |b| {
        b.iter(|| remove_grid_spikes(&mut g.clone(), &SpikeOptions::default()).unwrap())
    });
    let mut despiked = g.clone();
    remove_grid_spikes(&mut despiked, &SpikeOptions::default()).unwrap();
    grp.bench_function("holes", |b| {
        b.iter(|| fill_grid_holes(&mut despiked.clone(), 10.0).unwrap())
    });
    let mut filled = despiked.clone();
    fill_grid_holes(&mut filled, 10.0).unwrap();
    let bo = BntOptions {
        largest_component_only: false,
        ..BntOptions::default()
    };
    grp.bench_function("triangulate", |b| {
        b.iter(|| mesh_io::bnt_grid_to_mesh(&filled, &bo).unwrap())
    });
    let mesh = mesh_io::bnt_grid_to_mesh(&filled, &bo).unwrap().mesh;
    grp.bench_function("components", |b| {
        b.iter(|| remove_small_components(&mesh, 0.2).unwrap())
    });
    grp.bench_function("crop", |b| {
        b.iter(|| crop_sphere(&mesh, nose, 100.0).unwrap())
    });
    grp.bench_function("smooth_5", |b| b.iter(|| taubin_smooth(&mesh, 5).unwrap()));
    grp.bench_function("decimate_1.5mm", |b| {
        b.iter(|| decimate(&mesh, 1.5).unwrap())
    });
    let opts = CleanOptions {
        crop: Some(Crop::around(nose)),
        ..CleanOptions::default()
    };
    grp.bench_function("clean_default_with_crop", |b| {
        b.iter(|| clean(Input::Grid(&g), &opts).unwrap())
    });
    grp.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
