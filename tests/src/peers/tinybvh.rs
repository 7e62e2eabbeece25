//! tinybvh (Jacco Bikker's single-header C++ library) through its Rust wrapper `tinybvh-rs`
//! (cargo feature `tinybvh`; builds the C++ with g++ and C++20): the peer benchmark's
//! one-thread contestants.
//!
//! tinybvh-rs's structures own C++ objects through `cxx::UniquePtr` and are neither `Send`
//! nor `Sync`, and its BVH2 borrows the vertex array; so they cannot be an `Accel` behind a
//! `Renderer` (which rayon shares between threads) without an `unsafe impl`. Here each
//! contestant is one function: the vertices live in its scope, the structure borrows them,
//! and every ray of the workload is traced one at a time on the calling thread. The figures
//! are therefore on 1 thread only.
//!
//! What the wrapper offers, and how the workload maps onto it:
//! - single-ray layouts: `bvh::BVH` (tinybvh's `BVH`, Wald's 32-byte BVH2, built by
//!   `Build`, binned SAH, or `BuildHQ`, SAH with spatial splits) with `Intersect`; and
//!   `bvh8_cpu::BVH` (`BVH8_CPU`), whose `Intersect` the wrapper compiles only under
//!   `#[cfg(target_feature = "avx2")]`, so its contestant exists only when raybench is
//!   compiled with AVX2 enabled (`RUSTFLAGS="-C target-cpu=native"`);
//! - closest hits only: there is no occlusion query, so the any-hit figure is a closest-hit
//!   query on the shortened ray (its answer, occluded or not, is exact; its speed is not
//!   that of an any-hit traversal);
//! - rays have no `t_min` (hits at `t >= 0`) and their `t_max` is the initial `hit.t`;
//!   `Ray::new` normalises directions, so `t_max` is scaled by the direction's length (the
//!   workload's directions are unit vectors already);
//! - the builders are tinybvh's own, on one thread.

use super::report::{ContestantReport, QueryReport, Run, SetReport};
use super::{Options, RaySetWork, Workload};
use crate::peers::contestants::Kind;
use raybench_core::{Ray, Shape};
use std::time::Instant;
use tinybvh_rs::{Intersector, bvh};

/// tinybvh's "no hit" distance.
const FAR: f32 = tinybvh_rs::INFINITE;

/// The mesh's triangles as tinybvh wants them (three `[x, y, z, 0]` per triangle) and the
/// raybench id of each, or why the scene is not for tinybvh (a primitive that is no
/// triangle).
fn triangles(w: &Workload) -> Result<(Vec<[f32; 4]>, Vec<u32>), String> {
    let g = &w.scene.geometry;
    if !g.unbounded().is_empty() {
        return Err("tinybvh holds triangles only (the scene has planes)".into());
    }
    let mut vertices = Vec::with_capacity(3 * g.len());
    let mut ids = Vec::with_capacity(g.len());
    for &id in g.bounded() {
        let Shape::Triangle(t) = g.shape(id) else {
            return Err(format!(
                "tinybvh holds triangles only (primitive {id} is not one)"
            ));
        };
        vertices.extend(t.v.iter().map(|v| [v.x, v.y, v.z, 0.0]));
        ids.push(id);
    }
    if ids.is_empty() {
        return Err("no triangles".into());
    }
    Ok((vertices, ids))
}

/// `ray` as tinybvh's, ending at `t_max` (scaled to tinybvh's normalised direction; its
/// `FAR` when unbounded).
fn tiny_ray(ray: &Ray) -> tinybvh_rs::Ray {
    let mut r = tinybvh_rs::Ray::new(ray.origin.to_array(), ray.dir.to_array());
    let t = ray.t_max * ray.dir.length();
    r.hit.t = if t.is_finite() { t.min(FAR) } else { FAR };
    r
}

/// Traces every ray of `rays` (tinybvh's, ready) one at a time with `bvh`, writing the hit
/// (primitive index, or `u32::MAX`) per ray.
fn trace(bvh: &impl Intersector, rays: &[tinybvh_rs::Ray], out: &mut [u32]) {
    for (r, o) in rays.iter().zip(out.iter_mut()) {
        let mut ray = *r;
        bvh.intersect(&mut ray);
        *o = if ray.hit.t < r.hit.t {
            ray.hit.prim
        } else {
            u32::MAX
        };
    }
}

/// One query timed on one thread, with the rays whose answer differs from `bvh`'s.
fn query(
    bvh: &impl Intersector,
    rays: &[Ray],
    repeat: usize,
    differ: impl Fn(&[u32]) -> usize,
) -> QueryReport {
    let tiny: Vec<tinybvh_rs::Ray> = rays.iter().map(tiny_ray).collect();
    let mut hits = vec![u32::MAX; rays.len()];
    let seconds = super::best_time(repeat, || trace(bvh, &tiny, &mut hits));
    std::hint::black_box(&hits);
    QueryReport {
        runs: vec![Run {
            threads: 1,
            seconds,
            mrays: rays.len() as f64 / seconds / 1e6,
        }],
        differ: differ(&hits),
        node_visits_per_ray: None,
        prim_tests_per_ray: None,
        ratios: Vec::new(),
    }
}

/// Both queries of one ray set: closest hits (primitive mapped back to raybench's id and
/// compared with `bvh`'s) and the occlusion of the shadow rays (compared with `bvh`'s).
fn ray_set(bvh: &impl Intersector, s: &RaySetWork, ids: &[u32], repeat: usize) -> SetReport {
    let id = |h: u32| (h != u32::MAX).then(|| ids.get(h as usize).copied().unwrap_or(u32::MAX));
    SetReport {
        name: s.set.name(),
        closest: query(bvh, &s.rays, repeat, |hits| {
            hits.iter()
                .zip(&s.closest)
                .filter(|(h, r)| id(**h) != **r)
                .count()
        }),
        any: query(bvh, &s.shadow, repeat, |hits| {
            hits.iter()
                .zip(&s.occluded)
                .filter(|(h, o)| (**h != u32::MAX) != **o)
                .count()
        }),
    }
}

/// Builds with `build` (over the vertices of [`triangles`], whose ids are `ids`) `repeat`
/// times on one thread, then traces every ray set of `w` with the last structure:
/// contestant `name`'s report (the best build time).
fn contestant<B: Intersector>(
    name: &str,
    w: &Workload,
    o: &Options,
    ids: &[u32],
    build: impl Fn() -> Result<B, tinybvh_rs::Error>,
) -> Result<ContestantReport, String> {
    let mut build_s = f64::INFINITY;
    let mut built = None;
    for _ in 0..o.repeat {
        let start = Instant::now();
        let b = build().map_err(|e| e.to_string())?;
        build_s = build_s.min(start.elapsed().as_secs_f64());
        built = Some(b);
    }
    let bvh = built.ok_or("no build (repeat is 0)")?;
    Ok(ContestantReport {
        name: name.to_string(),
        kind: Kind::Peer,
        build_s,
        build_vs_embree: None,
        ray_sets: w
            .sets
            .iter()
            .map(|s| ray_set(&bvh, s, ids, o.repeat))
            .collect(),
    })
}

/// Contestant `tinybvh-bvh2`: `BVH::Build` (binned SAH), `BVH::Intersect`.
///
/// # Errors
/// A scene with primitives other than triangles.
pub fn bvh2_fast(w: &Workload, o: &Options) -> Result<ContestantReport, String> {
    let (vertices, ids) = triangles(w)?;
    contestant(BVH2, w, o, &ids, || {
        bvh::BVH::new(vertices.as_slice().into())
    })
}

/// Contestant `tinybvh-bvh2-hq`: `BVH::BuildHQ` (SAH with spatial splits),
/// `BVH::Intersect`.
///
/// # Errors
/// A scene with primitives other than triangles.
pub fn bvh2_hq(w: &Workload, o: &Options) -> Result<ContestantReport, String> {
    let (vertices, ids) = triangles(w)?;
    contestant(BVH2_HQ, w, o, &ids, || {
        bvh::BVH::new_hq(vertices.as_slice().into())
    })
}

/// Contestant `tinybvh-bvh8-cpu`: `BVH::Build`, split to leaves of 4, converted to
/// `MBVH8`, then `BVH8_CPU`, traced with its AVX2 `Intersect` (compiled only with AVX2
/// enabled, as in the wrapper). The build time covers all three steps.
///
/// # Errors
/// A scene with primitives other than triangles.
#[cfg(target_feature = "avx2")]
pub fn bvh8_cpu(w: &Workload, o: &Options) -> Result<ContestantReport, String> {
    use tinybvh_rs::{bvh8_cpu, mbvh};
    let (vertices, ids) = triangles(w)?;
    contestant(BVH8_CPU, w, o, &ids, || {
        let mut b = bvh::BVH::new(vertices.as_slice().into())?;
        b.split_leaves(4);
        bvh8_cpu::BVH::new(&mbvh::BVH::new(&b))
    })
}

/// Name of [`bvh2_fast`].
pub const BVH2: &str = "tinybvh-bvh2";
/// Name of [`bvh2_hq`].
pub const BVH2_HQ: &str = "tinybvh-bvh2-hq";
/// Name of `bvh8_cpu` (AVX2 builds only).
pub const BVH8_CPU: &str = "tinybvh-bvh8-cpu";
