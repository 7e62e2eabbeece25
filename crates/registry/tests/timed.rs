use raybench_core::{Ray, Renderer};
use raybench_core::{SceneBuilder, Sphere, Vec3};
use raybench_naive::NaiveAccel;
use raybench_registry::*;
use raybench_render::CpuRenderer;
use std::sync::Arc;

#[test]
fn the_default_times_a_cpu_batch_as_render() {
    let mut b = SceneBuilder::new("test");
    b.add_sphere(Sphere::new(Vec3::ZERO, 1.0), 0).unwrap();
    let mut r = CpuRenderer::<NaiveAccel>::with_default_build("naive", "test");
    r.prepare(&Arc::new(b.build())).unwrap();
    let rays = [
        Ray::new(Vec3::new(0.0, 0.0, 3.0), -Vec3::Z),
        Ray::new(Vec3::new(3.0, 0.0, 3.0), -Vec3::Z),
    ];
    let (hits, counters, timings) = r.trace_rays_timed(&rays, false).unwrap();
    assert_eq!(
        (
            hits.iter().map(Option::is_some).collect::<Vec<_>>(),
            counters
        ),
        (vec![true, false], None)
    );
    assert_eq!(timings.0.len(), 1);
    assert!(timings.get("render").is_some_and(|s| s >= 0.0));
    let (occluded, _, timings) = r.occlude_rays_timed(&rays, false).unwrap();
    assert_eq!(occluded, [true, false]);
    assert!(timings.get("render").is_some());
    assert_eq!(r.device(), None);
}
