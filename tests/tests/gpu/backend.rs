//! What the GPU backend accepts: a missing adapter reported, not panicked; every primitive
//! kind and mode has a kernel; textures and shading normals are ported (checked without an
//! adapter too); the empty scene renders its background.

use raybench_core::{RenderError, Renderer};

#[test]
fn a_missing_adapter_is_reported_not_panicked() {
    let request = raybench_wgpu::AdapterRequest::named("no such adapter 1f8e3c");
    let mut r = raybench_wgpu::WgpuRenderer::with_request("wgpu", "test", request);
    let reason = r.availability().unwrap_err();
    assert!(reason.contains("no such adapter 1f8e3c"), "{reason}");
    let scene =
        std::sync::Arc::new(raybench_scene::load("spheres", std::path::Path::new(".")).unwrap());
    match r.prepare(&scene) {
        Err(RenderError::Unavailable(why)) => assert_eq!(why, reason),
        other => panic!("expected Unavailable, got {other:?}"),
    }
    assert!(matches!(
        r.render(&Default::default()),
        Err(RenderError::NotPrepared)
    ));
}

#[test]
fn the_empty_scene_renders_background() {
    if !raybench_tests::gpu::available() {
        return;
    }
    let scene = raybench_tests::empty_scene();
    for name in raybench_tests::DEVICES {
        let r = raybench_tests::prepared(name, &scene);
        let settings = raybench_core::RenderSettings {
            width: 8,
            height: 5,
            ..Default::default()
        };
        let f = r.render(&settings).unwrap();
        assert!(
            f.ids.iter().all(|&id| id == raybench_core::NO_HIT),
            "{name}"
        );
        assert!(f.color.iter().all(|&c| c == scene.background), "{name}");
        let rays = [raybench_core::Ray::new(
            raybench_core::Vec3::ZERO,
            raybench_core::Vec3::X,
        )];
        assert_eq!(r.occlude_rays(&rays, false).unwrap().0, [false], "{name}");
    }
}

/// Every kind and every mode has a kernel (height fields with bilinear cells in
/// `kernels/bilinear.wgsl`, the volume modes in `kernels/volume.wgsl`).
#[test]
fn every_kind_and_mode_has_a_kernel() {
    let r = raybench_wgpu::WgpuRenderer::new("wgpu", "test");
    for mode in [raybench_core::Mode::Mip, raybench_core::Mode::Composite] {
        assert_eq!(r.supports_mode(mode), Ok(()), "{}", mode.name());
    }
    let mut b = raybench_core::SceneBuilder::new("bilinear");
    let field = raybench_core::HeightField::new(2, 2, vec![0.0; 9], None)
        .unwrap()
        .with_surface(raybench_core::CellSurface::Bilinear);
    b.add_shapes(
        "field",
        vec![raybench_core::Shape::HeightField(std::sync::Arc::new(
            field,
        ))],
        0,
    )
    .unwrap();
    let scene = b.build();
    assert!(raybench_wgpu::check_kinds(&scene).is_ok());
    let mut b = raybench_core::SceneBuilder::new("bezier");
    let points =
        std::array::from_fn(|k| raybench_core::Vec3::new((k % 4) as f32, (k / 4) as f32, 0.0));
    let patch = raybench_core::BezierPatch::new(points).unwrap();
    b.add_shapes(
        "patch",
        vec![raybench_core::Shape::Bezier(std::sync::Arc::new(patch))],
        0,
    )
    .unwrap();
    // Bezier patches have their port (`kernels/bezier.wgsl`).
    assert!(raybench_wgpu::check_kinds(&b.build()).is_ok());
    // Environment maps and emissive spheres are ported (see the shading tests below).
    let mut b = raybench_core::SceneBuilder::new("lights");
    let lamp = b
        .add_material(raybench_core::Material {
            emission: raybench_core::Vec3::ONE,
            ..raybench_core::Material::default()
        })
        .unwrap();
    b.add_sphere(
        raybench_core::Sphere::new(raybench_core::Vec3::ZERO, 1.0),
        lamp,
    )
    .unwrap();
    let lamp_scene = b.clone().build();
    assert!(raybench_wgpu::check_kinds(&lamp_scene).is_ok());
    let env = raybench_core::Environment::new(1, 1, vec![raybench_core::Vec3::ONE], 1.0, 0.0);
    b.environment(std::sync::Arc::new(env.unwrap()));
    assert!(raybench_wgpu::check_kinds(&b.build()).is_ok());
    if !raybench_tests::gpu::available() {
        return;
    }
    let mut r = r;
    assert_eq!(r.supports(&scene), Ok(()));
    assert!(r.prepare(&std::sync::Arc::new(scene)).is_ok());
}

/// Textures and shading normals are ported (`shading.rs`): scenes with them are accepted
/// (without an adapter too), as are faceted ones without textures.
#[test]
fn textures_and_shading_normals_are_accepted() {
    use raybench_core::{
        Material, Renderer as _, SceneBuilder, Texture, TriangleMesh, Vec2, Vec3, VertexAttributes,
        Wrap,
    };
    let r = raybench_wgpu::WgpuRenderer::new("wgpu", "test");
    let mesh = TriangleMesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        indices: vec![[0, 1, 2]],
    };
    let scene = |normals: Vec<Vec3>, textured: bool| {
        let mut b = SceneBuilder::new("t");
        let mut m = Material::default();
        if textured {
            let t = Texture::new("t", 1, 1, vec![Vec3::ONE], [Wrap::Repeat; 2]).unwrap();
            m.base_color_texture = Some(b.add_texture("t", t));
        }
        let m = b.add_material(m).unwrap();
        let uvs = vec![Vec2::ZERO; 3];
        b.add_mesh_with_attributes("m", &mesh, VertexAttributes { normals, uvs }, &[m])
            .unwrap();
        b.build()
    };
    assert_eq!(r.supports(&scene(vec![], true)), Ok(()));
    assert_eq!(r.supports(&scene(vec![Vec3::Z; 3], false)), Ok(()));
    // Texture coordinates alone change nothing the GPU renders.
    let plain = scene(vec![], false);
    assert!(!plain.attributes.is_empty());
    assert_eq!(r.supports(&plain), Ok(()));
}
