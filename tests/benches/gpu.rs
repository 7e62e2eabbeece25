//! Criterion benchmarks of the GPU backend (`wgpu`, [`raybench_wgpu::WgpuRenderer`]) on the
//! adapter wgpu selects (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`; without a GPU, Mesa's
//! lavapipe, which runs at about one CPU thread's speed).
//!
//! Benchmarks, per scene (bunny, sponza and `terrain:708`, the scenes the README's GPU
//! figures are quoted for, then the report's other quick scenes):
//!
//! - `trace/wgpu/<scene>/primary`: a ray-casting frame at `RAYBENCH_GPU_SIZE` squared
//!   pixels (default 1024): one centre ray per pixel, shading included;
//! - `trace/wgpu/<scene>/incoherent`: 65,536 seeded random rays inside the scene's box
//!   ([`raybench_core::ray_sets::incoherent`], seed 1, as the CPU suite's), uploaded and read
//!   back around the timed dispatch;
//! - `trace/wgpu/<scene>/path`: a path-traced frame at the same size, 1 sample per pixel,
//!   5 bounces (every ray counted: camera, bounce and shadow rays).
//!
//! The time criterion records is the GPU's execution time (timestamp queries where the
//! adapter has them, else wall time around submit and wait), as `mrays_per_s` in the report;
//! upload and readback are left out, and the scene is uploaded once, before any timing.
//! Throughput is in rays (criterion's `elem/s`), counted by the kernels.
//!
//! ```text
//! RAYBENCH_ASSETS=../shared/scenes cargo bench -p raybench-tests --bench gpu
//! RAYBENCH_GPU_SIZE=256 RAYBENCH_ASSETS=../shared/scenes cargo bench -p raybench-tests --bench gpu -- bunny
//! ```

// `criterion_group!` and `criterion_main!` generate public items without documentation.
#![allow(missing_docs)]

use criterion::{
    BenchmarkId, Criterion, SamplingMode, Throughput, criterion_group, criterion_main,
};
use raybench_core::{Mode, RenderSettings, Renderer};
use std::sync::Arc;
use std::time::Duration;

/// Scenes of the README's GPU figures first.
const SCENES: &[&str] = &["bunny", "sponza", "terrain:708", "cornell-box", "spheres"];

fn size() -> u32 {
    std::env::var("RAYBENCH_GPU_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .filter(|&s| (1..=raybench_core::limits::MAX_DIMENSION).contains(&s))
        .unwrap_or(1024)
}

fn gpu_seconds(t: &raybench_core::Timings) -> Duration {
    Duration::from_secs_f64(t.get("gpu").expect("the GPU backend reports its GPU time"))
}

fn benches_all(c: &mut Criterion) {
    let probe = raybench_wgpu::WgpuRenderer::new("wgpu", "");
    if let Err(e) = probe.availability() {
        eprintln!("skipping the GPU benchmarks: {e}");
        return;
    }
    eprintln!("adapter: {}", probe.device().unwrap_or_default());
    let size = size();
    let mut group = c.benchmark_group("trace");
    group.sampling_mode(SamplingMode::Flat);
    for &name in SCENES {
        let scene = match raybench_scene::load(name, &raybench_scene::assets_dir(None)) {
            Ok(s) => Arc::new(s),
            Err(e) if e.is_missing_asset() => {
                eprintln!("skipping scene {name}: {e}");
                continue;
            }
            Err(e) => panic!("cannot load scene {name}: {e}"),
        };
        let mut r = raybench_wgpu::WgpuRenderer::new("wgpu", "");
        if let Err(e) = r.prepare(&scene) {
            eprintln!("skipping scene {name}: {e}");
            continue;
        }
        for (set, mode) in [("primary", Mode::Cast), ("path", Mode::Path)] {
            let settings = RenderSettings {
                width: size,
                height: size,
                mode,
                ..RenderSettings::default()
            };
            // Untimed warm-up: compiles the kernel and counts the rays.
            let warm = r.render(&settings).expect("GPU frame");
            group.throughput(Throughput::Elements(warm.stats.rays));
            group.bench_function(BenchmarkId::new("wgpu", format!("{name}/{set}")), |b| {
                b.iter_custom(|iters| {
                    (0..iters)
                        .map(|_| gpu_seconds(&r.render(&settings).expect("GPU frame").timings))
                        .sum()
                });
            });
        }
        let rays = raybench_core::ray_sets::incoherent(scene.geometry.bounds(), 65_536, 1);
        let _ = r.trace_rays(&rays, false).expect("GPU rays");
        group.throughput(Throughput::Elements(rays.len() as u64));
        group.bench_function(
            BenchmarkId::new("wgpu", format!("{name}/incoherent")),
            |b| {
                b.iter_custom(|iters| {
                    (0..iters)
                        .map(|_| {
                            gpu_seconds(&r.trace_rays_timed(&rays, false).expect("GPU rays").2)
                        })
                        .sum()
                });
            },
        );
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    targets = benches_all
}
criterion_main!(benches);
