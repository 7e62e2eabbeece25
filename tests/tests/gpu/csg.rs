//! CSG trees, tori and quadrics (`kernels/csg.wgsl`): each solid alone, placed and not;
//! tori edge-on, where camera rays graze the tube; the solids a thousand units from the
//! origin, seen from close by and from far away (the f32 forms that replace the core's
//! f64); nested differences over shared faces. Each scene is a file of `tests/scenes/`
//! (`csg-*.toml`, sharing their materials and light) and goes through `check` unchanged.

use super::{scene_file, scene_toml, scratch};
use raybench_tests::gpu::check;

scene_file_tests! {
    /// Every solid alone, placed and not (`csg-solids.toml`).
    csg_each_solid_alone => "csg-solids.toml",
    /// The camera in the plane of the first torus: every ray grazes its tube or crosses it
    /// at a shallow angle; a spindle torus (r > R) and a horn torus (r = R) beside it
    /// (`csg-tori.toml`).
    csg_tori_edge_on => "csg-tori.toml",
    /// Every mode. (Path tracing once traced 1.6% fewer rays than naive here, and 2.3% on
    /// `quadrics`: lavapipe cut threads whose loops over four samples in one dispatch passed
    /// its iteration cap; software adapters now trace one sample per dispatch,
    /// `plan::max_samples`.) A difference inside a difference (normals negated twice), faces
    /// shared between the operands, a torus cut by a box and a half-space, and a union of
    /// more leaves than the kernels keep (`csg-nested.toml`).
    csg_nested_differences => "csg-nested.toml",
}

/// Solids 1000 units from the origin, seen from near and far: every image agrees
/// (far-near: ids 100%, relative dt 2.5e-7, no pixel differs in any mode). Among the
/// incoherent rays one that starts about 1e-3 from a surface differs by 3.0e-7 in `t`,
/// 3.0e-4 of its short `t` (coordinates near 1000 have an ulp of 6e-5: f32 cannot place
/// such a ray's origin more closely), which is why explicit rays are compared relative to
/// their reach ([`raybench_tests::gpu::reach_dt`]).
#[test]
fn csg_far_from_the_origin() {
    // The quadrics and a torus 1000 units out on x, seen from 8 units (`csg-far.toml`) and
    // from 300: every mode from near; ray casting and explicit rays from far.
    let near = scene_file("csg-far.toml");
    check(&near, 32, true);
    let far = std::fs::read_to_string(&near)
        .unwrap()
        .replace("name = \"csg-far-near\"", "name = \"csg-far-far\"")
        .replace(
            "position = [1000.0, 2.0, 8.0]",
            "position = [1000.0, 60.0, 300.0]",
        );
    assert!(far.contains("[1000.0, 60.0, 300.0]") && far.contains("csg-far-far"));
    check(&scene_toml(&scratch("csg"), "far-far", &far), 32, false);
}
