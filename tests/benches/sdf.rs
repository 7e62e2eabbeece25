//! Criterion benchmarks of sphere tracing against an analytic intersection: the centre rays
//! of a 256 x 256 image in which a unit sphere covers about 40 % of the frame, traced against the
//! sphere as an SDF model (`sdf/sdf-sphere`, marched) and as raybench's analytic sphere
//! (`sdf/analytic-sphere`), one ray after the other on the calling thread.
//!
//! ```text
//! cargo bench -p raybench-tests --bench sdf
//! ```

// `criterion_group!` and `criterion_main!` generate public items without documentation.
#![allow(missing_docs)]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use raybench_core::{Ray, Shape, Sphere, Vec3};
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

/// The scene: a camera 4 units from a unit SDF sphere at the origin.
const SCENE: &str = "[camera]\nposition = [0, 0, 4]\nlook_at = [0, 0, 0]\nfov = 40\n\
                     [[object]]\nkind = \"sdf\"\n\
                     tree = { type = \"sphere\", center = [0, 0, 0], radius = 1 }\n";

/// Image side of the rays.
const SIZE: u32 = 256;

fn bench_sdf(c: &mut Criterion) {
    let scene =
        raybench_scene::load_scene_str(SCENE, "sdf-sphere", None, Path::new("/none")).unwrap();
    let Shape::Sdf(model) = scene.geometry.shape(0) else {
        unreachable!("the scene holds one SDF model")
    };
    let sphere = Sphere::new(Vec3::ZERO, 1.0);
    let camera = scene.camera.rays(SIZE, SIZE);
    let rays: Vec<Ray> = (0..SIZE)
        .flat_map(|y| (0..SIZE).map(move |x| (x, y)))
        .map(|(x, y)| camera.center_ray(x, y))
        .collect();
    let mut group = c.benchmark_group("sdf");
    group.throughput(Throughput::Elements(rays.len() as u64));
    group.bench_function("sdf-sphere", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| model.intersect(black_box(r)).is_some())
                .count()
        });
    });
    group.bench_function("analytic-sphere", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| sphere.intersect(black_box(r)).is_some())
                .count()
        });
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    targets = bench_sdf
}
criterion_main!(benches);
