//! Criterion benchmarks of the GPU backends (`raybench_tests::DEVICES`: `wgpu` over the
//! BVH2 and `wgpu-cwbvh` over the compressed wide BVH, [`raybench_wgpu::WgpuRenderer`]) on
//! the adapter wgpu selects (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`; without a GPU, Mesa's
//! lavapipe, which runs at about one CPU thread's speed).
//!
//! Benchmarks, per scene (bunny, dabrovic-sponza and `terrain:708`, the scenes docs/gpu.md's GPU
//! figures are quoted for, then the report's other quick scenes; `RAYBENCH_GPU_SCENES`, a
//! comma-separated list, replaces them) and backend:
//!
//! - `trace/<backend>/<scene>/primary`: a ray-casting frame at `RAYBENCH_GPU_SIZE` squared
//!   pixels (default 1024): one centre ray per pixel, shading included;
//! - `trace/<backend>/<scene>/incoherent`: `RAYBENCH_GPU_RAYS` (default 65,536; a large GPU
//!   needs about a million to fill) seeded random rays inside the scene's box
//!   ([`raybench_core::ray_sets::incoherent`], seed 1, as the CPU suite's), uploaded and read
//!   back around the timed dispatch;
//! - `trace/<backend>/<scene>/occlusion`: the same rays as any-hit queries (the any-hit
//!   kernel, which stops at the first hit);
//! - `trace/<backend>/<scene>/path`: a path-traced frame at the same size, 1 sample per
//!   pixel, 5 bounces (every ray counted: camera, bounce and shadow rays).
//!
//! With `RAYBENCH_GPU_JSON=FILE` the suite also writes its figures there (schema
//! `raybench-gpu-bench/1`: the adapter, and per benchmark the GPU seconds per iteration and
//! Mrays/s), for `scripts/device/gpu-measure.sh`.
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
use raybench_core::{Mode, RenderSettings};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Scenes of docs/gpu.md's figures first.
const SCENES: &[&str] = &[
    "bunny",
    "dabrovic-sponza",
    "terrain:708",
    "cornell-box",
    "spheres",
];

fn size() -> u32 {
    std::env::var("RAYBENCH_GPU_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .filter(|&s| (1..=raybench_core::limits::MAX_DIMENSION).contains(&s))
        .unwrap_or(1024)
}

/// The number of incoherent rays per batch: `RAYBENCH_GPU_RAYS`, default 65,536.
fn ray_count() -> usize {
    std::env::var("RAYBENCH_GPU_RAYS")
        .ok()
        .and_then(|s| s.parse().ok())
        .filter(|&n| (1..=1 << 24).contains(&n))
        .unwrap_or(65_536)
}

fn scenes() -> Vec<String> {
    match std::env::var("RAYBENCH_GPU_SCENES") {
        Ok(list) if !list.trim().is_empty() => {
            list.split(',').map(|s| s.trim().to_owned()).collect()
        }
        _ => SCENES.iter().map(|s| (*s).to_owned()).collect(),
    }
}

fn gpu_seconds(t: &raybench_core::Timings) -> Duration {
    Duration::from_secs_f64(t.get("gpu").expect("the GPU backend reports its GPU time"))
}

/// One benchmark's totals: rays per iteration, iterations and GPU seconds in all.
struct Figure {
    id: String,
    rays: u64,
    iters: u64,
    seconds: f64,
}

/// The totals of every timed batch, for `RAYBENCH_GPU_JSON`.
static FIGURES: Mutex<Vec<Figure>> = Mutex::new(Vec::new());

/// Times `iters` runs of `run` (GPU seconds each) and adds them to benchmark `id`'s totals.
fn timed(id: &str, rays: u64, iters: u64, mut run: impl FnMut() -> Duration) -> Duration {
    let total: Duration = (0..iters).map(|_| run()).sum();
    let mut figures = FIGURES.lock().unwrap_or_else(|e| e.into_inner());
    match figures.iter_mut().find(|f| f.id == id) {
        Some(f) => {
            f.iters += iters;
            f.seconds += total.as_secs_f64();
        }
        None => figures.push(Figure {
            id: id.to_owned(),
            rays,
            iters,
            seconds: total.as_secs_f64(),
        }),
    }
    total
}

/// Writes the figures to `RAYBENCH_GPU_JSON`, if set.
fn write_json(adapter: &str, size: u32) {
    let Ok(path) = std::env::var("RAYBENCH_GPU_JSON") else {
        return;
    };
    let figures = FIGURES.lock().unwrap_or_else(|e| e.into_inner());
    let rows: Vec<serde_json::Value> = figures
        .iter()
        .map(|f| {
            let per = f.seconds / f.iters.max(1) as f64;
            serde_json::json!({
                "id": f.id,
                "rays": f.rays,
                "iterations": f.iters,
                "gpu_seconds_per_iteration": per,
                "mrays_per_s": f.rays as f64 / per.max(f64::MIN_POSITIVE) / 1e6,
            })
        })
        .collect();
    let doc = serde_json::json!({
        "schema": "raybench-gpu-bench/1",
        "adapter": adapter,
        "size": size,
        "benchmarks": rows,
    });
    let text = serde_json::to_string_pretty(&doc).expect("plain JSON values");
    if let Err(e) = std::fs::write(&path, text + "\n") {
        eprintln!("error: {path}: cannot write the GPU figures: {e}");
        std::process::exit(1);
    }
}

fn benches_all(c: &mut Criterion) {
    let probe = (raybench_registry::backend(raybench_tests::DEVICE)
        .expect("registered")
        .make)();
    if let Err(e) = probe.availability() {
        eprintln!("skipping the GPU benchmarks: {e}");
        return;
    }
    let adapter = probe.device().unwrap_or_default();
    eprintln!("adapter: {adapter}");
    let size = size();
    let mut group = c.benchmark_group("trace");
    group.sampling_mode(SamplingMode::Flat);
    for name in scenes() {
        let scene = match raybench_scene::load(&name, &raybench_scene::assets_dir(None)) {
            Ok(s) => Arc::new(s),
            Err(e) if e.is_missing_asset() => {
                eprintln!("skipping scene {name}: {e}");
                continue;
            }
            Err(e) => panic!("cannot load scene {name}: {e}"),
        };
        let rays = raybench_core::ray_sets::incoherent(scene.geometry.bounds(), ray_count(), 1);
        for backend in raybench_tests::DEVICES {
            let mut r = (raybench_registry::backend(backend)
                .expect("registered")
                .make)();
            if let Err(e) = r.prepare(&scene) {
                eprintln!("skipping {backend} on scene {name}: {e}");
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
                let rays_per = warm.stats.rays;
                group.throughput(Throughput::Elements(rays_per));
                let id = format!("{backend}/{name}/{set}");
                group.bench_function(BenchmarkId::new(backend, format!("{name}/{set}")), |b| {
                    b.iter_custom(|iters| {
                        timed(&id, rays_per, iters, || {
                            gpu_seconds(&r.render(&settings).expect("GPU frame").timings)
                        })
                    });
                });
            }
            let _ = r.trace_rays(&rays, false).expect("GPU rays");
            let _ = r.occlude_rays(&rays, false).expect("GPU rays");
            group.throughput(Throughput::Elements(rays.len() as u64));
            let n = rays.len() as u64;
            let id = format!("{backend}/{name}/incoherent");
            group.bench_function(
                BenchmarkId::new(backend, format!("{name}/incoherent")),
                |b| {
                    b.iter_custom(|iters| {
                        timed(&id, n, iters, || {
                            gpu_seconds(&r.trace_rays_timed(&rays, false).expect("GPU rays").2)
                        })
                    });
                },
            );
            let id = format!("{backend}/{name}/occlusion");
            group.bench_function(
                BenchmarkId::new(backend, format!("{name}/occlusion")),
                |b| {
                    b.iter_custom(|iters| {
                        timed(&id, n, iters, || {
                            gpu_seconds(&r.occlude_rays_timed(&rays, false).expect("GPU rays").2)
                        })
                    });
                },
            );
        }
        // After every scene, so a run cut short still leaves its figures so far.
        write_json(&adapter, size);
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
