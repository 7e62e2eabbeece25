//! Criterion benchmarks of the gridded models: the min-max quadtree of height fields
//! against the plain 2D-DDA walk and against the tessellated terrain in the BVH, and the
//! volume integration with empty-space skipping against the plain 3D-DDA walk.
//!
//! - `heightfield/<traversal>/<N>`: the 256 x 256 centre rays of the `terrain:N` camera
//!   against the `heightfield:N` primitive alone (`tree` or `dda`), and `mesh-bvh`: the same
//!   rays against `terrain:N` in the BVH (N up to 1024 there: the tessellated 4096^2 grid
//!   takes gigabytes; the report measures it);
//! - `volume/phantom/<mode>/<skip|plain>`: 128 x 128 camera rays of the built-in `phantom`
//!   scene integrated through its volume, maximum-intensity projection or compositing.
//!
//! Everything runs on the calling thread; inputs are built before timing.

// `criterion_group!` and `criterion_main!` generate public items without documentation.
#![allow(missing_docs)]

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use raybench_bvh::{Bvh, BvhParams};
use raybench_core::{
    Accel, HeightFieldTraversal, NoCounters, Ray, Shape, VolumeParams, VolumeSample, ray_sets,
};
use std::hint::black_box;
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

const SIZE: u32 = 256;

fn bench_heightfield(c: &mut Criterion) {
    let mut group = c.benchmark_group("heightfield");
    group.throughput(Throughput::Elements(u64::from(SIZE * SIZE)));
    for n in [256u32, 1024, 4096] {
        let scene = raybench_scene::load(&format!("heightfield:{n}"), Path::new("/none")).unwrap();
        let Shape::HeightField(tree) = scene.geometry.shape(0) else {
            unreachable!("heightfield:N is one height field")
        };
        let dda = tree
            .as_ref()
            .clone()
            .with_traversal(HeightFieldTraversal::Dda);
        let rays: Vec<Ray> = ray_sets::primary_tiled(&scene.camera, SIZE, SIZE, 16);
        for (name, field) in [("tree", tree.as_ref()), ("dda", &dda)] {
            group.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter(|| {
                    let mut hits = 0u32;
                    for r in &rays {
                        hits += u32::from(black_box(field).intersect(r).is_some());
                    }
                    hits
                });
            });
        }
        if n <= 1024 {
            let mesh = raybench_scene::load(&format!("terrain:{n}"), Path::new("/none")).unwrap();
            let bvh = Bvh::build_with(Arc::clone(&mesh.geometry), BvhParams::default());
            let mut out = vec![None; rays.len()];
            group.bench_function(BenchmarkId::new("mesh-bvh", n), |b| {
                b.iter(|| {
                    bvh.intersect_batch(black_box(&rays), &mut out, &mut NoCounters);
                    out.iter().filter(|h| h.is_some()).count()
                });
            });
        }
    }
    group.finish();
}

fn bench_volume(c: &mut Criterion) {
    let mut group = c.benchmark_group("volume/phantom");
    let scene = raybench_scene::load("phantom", Path::new("/none")).unwrap();
    let side = 128;
    let rays: Vec<Ray> = ray_sets::primary_tiled(&scene.camera, side, side, 16);
    group.throughput(Throughput::Elements(u64::from(side * side)));
    let volume = scene.volumes[0].as_ref();
    for composite in [false, true] {
        let mode = if composite { "composite" } else { "mip" };
        for skip_empty in [true, false] {
            let v = volume.clone().with_params(VolumeParams {
                skip_empty,
                ..volume.params()
            });
            let name = if skip_empty { "skip" } else { "plain" };
            group.bench_function(BenchmarkId::new(mode, name), |b| {
                b.iter(|| {
                    let mut sum = 0.0f32;
                    for r in &rays {
                        let mut acc = VolumeSample::default();
                        black_box(&v).integrate(r, f32::INFINITY, composite, &mut acc);
                        sum += acc.transmittance + acc.max;
                    }
                    sum
                });
            });
        }
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    targets = bench_heightfield, bench_volume
}
criterion_main!(benches);
