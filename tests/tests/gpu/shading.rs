//! Shading: textures, shading normals, every bounded emitter as a light of `path`, the
//! environment map (`crates/wgpu/src/shading.rs`, `kernels/lights.wgsl`). The scenes are the
//! files of `tests/scenes/`; each runs `raybench_tests::gpu::check` (ray casting at 1 and 4
//! samples, Whitted, path tracing at 4 samples with MIS, explicit rays) at 32 x 32 with the
//! shared tolerances, none widened. And the volume modes (`mip`, `composite`): the phantom,
//! and a scene whose volumes are cut by surfaces and overlap
//! (`raybench_tests::gpu::VOLUMES_SCENE`).

use super::scene_file;
use raybench_tests::gpu::check;

scene_file_tests! {
    /// Emissive spheres (sampled by their cone) and an emissive triangle light a floor, a
    /// diffuse and a mirror sphere; no point light, black background.
    emissive_spheres_are_sampled_lights => "emissive-spheres.toml",
    /// A rotated 16 x 8 equirectangular map with a sun texel, and a small emissive sphere:
    /// misses read the map in every mode; path tracing samples the map's distribution and
    /// the sphere, with MIS.
    environment_map_lights_the_scene => "environment.toml",
    /// A UV sphere with vertex normals and texture coordinates on a floor whose coordinates
    /// repeat the texture, under a directional, a point and an emissive-sphere light.
    textured_smooth_mesh => "textured-smooth.toml",
    /// A smooth textured mesh placed five times (as it is, rotated, mirrored, scaled
    /// unevenly, with a material override): each instance's vertex normals carried by its
    /// normal matrix, its texture coordinates read from the mesh's own table
    /// (`shading::mesh_attribute_tables`).
    instanced_smooth_textured_mesh => "instanced-smooth.toml",
    /// Suzanne with her vertex normals (the built-in scene facets her).
    smooth_suzanne => "smooth-suzanne.toml",
}

#[test]
fn phantom_volume_modes() {
    raybench_tests::gpu::check_volumes("phantom", 32);
}

#[test]
fn volumes_cut_by_surfaces() {
    raybench_tests::gpu::check_volumes("volumes-cut", 32);
}
