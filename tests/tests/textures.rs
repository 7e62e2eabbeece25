//! Shading normals and textures through the loaders and the integrators, on tiny files the
//! tests write themselves: a textured quad as glTF (external PNG, data URI, GLB buffer view)
//! and as OBJ+MTL renders each texel's linear value; a missing texture is a warning and a
//! flat colour; a low-poly sphere with vertex normals shades smoothly, `smooth = false`
//! facets it, and shading normals change no id and no `t`.

use base64::Engine as _;
use raybench_core::{Frame, Mode, NO_HIT, RenderSettings, Scene, Vec3, Wrap, srgb_to_linear};
use raybench_tests::{EXACT_BACKENDS, ORACLE, render_with};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A fresh folder for one test's files.
fn folder(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("raybench-textures-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The 4 x 4 sRGB texture of the tests: four 2 x 2 quadrants of one colour each, so that
/// bilinear lookups well inside a quadrant return its colour exactly.
const QUADRANTS: [[u8; 3]; 4] = [[255, 0, 0], [0, 128, 0], [20, 60, 240], [200, 100, 50]];

fn texture_png() -> Vec<u8> {
    let mut img = image::RgbImage::new(4, 4);
    for (x, y, p) in img.enumerate_pixels_mut() {
        *p = image::Rgb(QUADRANTS[(y / 2 * 2 + x / 2) as usize]);
    }
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// Quadrant `q`'s colour in linear light.
fn linear(q: usize) -> Vec3 {
    let c = QUADRANTS[q].map(|c| srgb_to_linear(f32::from(c) / 255.0));
    Vec3::from(c)
}

/// A scene file showing `mesh` (a unit quad in the z = 0 plane, corners at +-1) from far
/// away along +z, so that every view ray is almost normal to it, lit head-on: ray casting's
/// colour is then the base colour (times `0.35 cos + 0.65`, within 1e-5 of 1).
fn quad_scene(dir: &Path, mesh: &str, extra: &str) -> Arc<Scene> {
    let toml = format!(
        r#"
camera = {{ position = [0.0, 0.0, 300.0], look_at = [0.0, 0.0, 0.0], fov = {fov} }}
light = [{{ kind = "directional", direction = [0.0, 0.0, -1.0], radiance = [1.0, 1.0, 1.0] }}]

[[object]]
kind = "mesh"
path = "{mesh}"
{extra}
"#,
        fov = 2.0 * (1.0f64 / 300.0).atan().to_degrees()
    );
    let path = dir.join("scene.toml");
    std::fs::write(&path, toml).unwrap();
    Arc::new(raybench_scene::load(path.to_str().unwrap(), dir).unwrap())
}

fn cast(scene: &Arc<Scene>, size: u32, mode: Mode) -> Frame {
    let settings = RenderSettings {
        width: size,
        height: size,
        mode,
        ..RenderSettings::default()
    };
    render_with(ORACLE, scene, &settings, 2)
}

/// The centre pixels of the quadrants of a 64 x 64 frame of the quad (top left, top right,
/// bottom left, bottom right, as the image is seen) hold the quadrants' linear colours.
fn assert_quadrants(frame: &Frame, scale: Vec3, what: &str) {
    for (q, (x, y)) in [(16, 16), (47, 16), (16, 47), (47, 47)]
        .into_iter()
        .enumerate()
    {
        let c = frame.color[(y * frame.width + x) as usize];
        let expect = linear(q) * scale;
        assert!(
            (c - expect).abs().max_element() < 1e-4,
            "{what}: quadrant {q} at ({x}, {y}): {c}, expected {expect}"
        );
    }
}

/// The quad as glTF JSON: positions, normals, texture coordinates (top left (0, 0)) and
/// indices in one buffer (`buffer`: its URI, or none for a GLB's binary chunk), one
/// material (`material`: its JSON), textures and images (`images`: their JSON) after it.
fn quad_gltf(buffer: Option<&str>, bin_len: usize, material: &str, images: &str) -> String {
    let uri = buffer.map_or(String::new(), |u| format!(r#""uri": "{u}", "#));
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0,
        "scenes": [{{"nodes": [0]}}],
        "nodes": [{{"mesh": 0}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}},
            "indices": 3, "material": 0}}]}}],
        "materials": [{material}],
        {images}
        "buffers": [{{{uri}"byteLength": {bin_len}}}],
        "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}},
                        {{"buffer": 0, "byteOffset": 48, "byteLength": 48}},
                        {{"buffer": 0, "byteOffset": 96, "byteLength": 32}},
                        {{"buffer": 0, "byteOffset": 128, "byteLength": 12}}],
        "accessors": [
          {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
            "min": [-1, -1, 0], "max": [1, 1, 0]}},
          {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"}},
          {{"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"}},
          {{"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}}]}}"#
    )
}

/// The quad's buffer: positions (top left, top right, bottom left, bottom right), normals
/// (+z), texture coordinates and two counter-clockwise triangles.
fn quad_bin() -> Vec<u8> {
    let mut bin = Vec::new();
    let f = |bin: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|x| bin.extend(x.to_le_bytes()));
    f(
        &mut bin,
        &[-1., 1., 0., 1., 1., 0., -1., -1., 0., 1., -1., 0.],
    );
    f(&mut bin, &[0., 0., 1., 0., 0., 1., 0., 0., 1., 0., 0., 1.]);
    f(&mut bin, &[0., 0., 1., 0., 0., 1., 1., 1.]);
    for i in [2u16, 1, 0, 2, 3, 1] {
        bin.extend(i.to_le_bytes());
    }
    bin
}

fn base64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

#[test]
fn gltf_base_colour_textures_render_their_texels() {
    let dir = folder("gltf-base");
    std::fs::write(dir.join("tex.png"), texture_png()).unwrap();
    std::fs::write(dir.join("quad.bin"), quad_bin()).unwrap();
    // The base colour factor scales the texture.
    let material = r#"{"pbrMetallicRoughness": {"baseColorFactor": [1, 0.5, 1, 1],
        "baseColorTexture": {"index": 0}}}"#;
    let images = r#""textures": [{"source": 0}], "images": [{"uri": "tex.png"}],"#;
    let json = quad_gltf(Some("quad.bin"), quad_bin().len(), material, images);
    std::fs::write(dir.join("quad.gltf"), json).unwrap();
    let scene = quad_scene(&dir, "quad.gltf", "");
    assert_eq!(scene.textures.len(), 1);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let scale = Vec3::new(1.0, 0.5, 1.0);
    assert_quadrants(&cast(&scene, 64, Mode::Cast), scale, "cast");
    // Whitted: the light's irradiance (1) on the colour plus the ambient term.
    let whitted = cast(&scene, 64, Mode::Whitted);
    assert_quadrants(
        &whitted,
        scale * (1.0 + raybench_core::integrator::AMBIENT),
        "whitted",
    );
}

#[test]
fn gltf_emissive_textures_from_data_uris_and_glb_buffer_views() {
    let dir = folder("gltf-emissive");
    let png = texture_png();
    // Black base colour: the colour is the emission, the factor times the texel.
    let material = r#"{"pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]},
        "emissiveFactor": [2, 1, 1], "emissiveTexture": {"index": 0}}"#;
    let scale = Vec3::new(2.0, 1.0, 1.0);
    // The image as a data URI, the buffer too.
    let images = format!(
        r#""textures": [{{"source": 0}}], "images": [{{"uri": "data:image/png;base64,{}"}}],"#,
        base64(&png)
    );
    let bin = quad_bin();
    let uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
    let json = quad_gltf(Some(&uri), bin.len(), material, &images);
    std::fs::write(dir.join("quad.gltf"), json).unwrap();
    let scene = quad_scene(&dir, "quad.gltf", "");
    assert_quadrants(&cast(&scene, 64, Mode::Cast), scale, "data URI");
    // Emission as the path tracer's lights see it: `Scene::emission_at` at the quad's
    // top-left quadrant's centre (the first triangle's vertices are the bottom left, top
    // right and top left corners).
    let e = scene.emission_at(0, 0.25, 0.5);
    assert!((e - linear(0) * scale).abs().max_element() < 1e-5, "{e}");

    // GLB: the image in a buffer view after the mesh data.
    let mut bin = quad_bin();
    let image_offset = bin.len();
    bin.extend(&png);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let images = r#""textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"wrapS": 33071, "wrapT": 33648}],
        "images": [{"bufferView": 4, "mimeType": "image/png"}],"#;
    let json = quad_gltf(None, bin.len(), material, images).replace(
        r#"{"buffer": 0, "byteOffset": 128, "byteLength": 12}"#,
        &format!(
            r#"{{"buffer": 0, "byteOffset": 128, "byteLength": 12}},
            {{"buffer": 0, "byteOffset": {image_offset}, "byteLength": {}}}"#,
            png.len()
        ),
    );
    let mut j = json.into_bytes();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut glb = Vec::new();
    glb.extend(b"glTF");
    glb.extend(2u32.to_le_bytes());
    glb.extend(((12 + 8 + j.len() + 8 + bin.len()) as u32).to_le_bytes());
    glb.extend((j.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&j);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(&bin);
    std::fs::write(dir.join("quad.glb"), &glb).unwrap();
    let data = raybench_scene::load_gltf_file(&dir.join("quad.glb")).unwrap();
    assert_eq!(data.textures.len(), 1);
    assert_eq!(
        data.textures[0].wrap,
        [Wrap::ClampToEdge, Wrap::MirroredRepeat]
    );
    assert_eq!(data.normals.len(), 4);
    assert_eq!(data.uvs[3], raybench_core::Vec2::ONE);
    let scene = quad_scene(&dir, "quad.glb", "");
    assert_quadrants(&cast(&scene, 64, Mode::Cast), scale, "GLB");
}

/// The quad as OBJ (texture coordinates counting up from the image's bottom row, as OBJ
/// does) with an MTL file naming `map_Kd`.
fn quad_obj(dir: &Path, map_kd: &str) {
    let obj = "mtllib quad.mtl\nv -1 1 0\nv 1 1 0\nv -1 -1 0\nv 1 -1 0\n\
               vt 0 1\nvt 1 1\nvt 0 0\nvt 1 0\nusemtl tex\nf 3/3 2/2 1/1\nf 3/3 4/4 2/2\n";
    std::fs::write(dir.join("quad.obj"), obj).unwrap();
    let mtl = format!("newmtl tex\nKd 1 1 1\nmap_Kd {map_kd}\n");
    std::fs::write(dir.join("quad.mtl"), mtl).unwrap();
}

#[test]
fn obj_map_kd_renders_its_texels() {
    let dir = folder("obj");
    std::fs::create_dir_all(dir.join("maps")).unwrap();
    std::fs::write(dir.join("maps/tex.png"), texture_png()).unwrap();
    quad_obj(&dir, "maps/tex.png");
    let scene = quad_scene(&dir, "quad.obj", "");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_quadrants(&cast(&scene, 64, Mode::Cast), Vec3::ONE, "OBJ");
    // Twice the same mesh: the texture is decoded once.
    let scene = quad_scene(
        &dir,
        "quad.obj",
        "[[object]]\nkind = \"mesh\"\npath = \"quad.obj\"\ntransform = { translate = [0, 0, -1] }",
    );
    assert_eq!(scene.textures.len(), 1);
    assert_eq!(scene.materials.len(), 3);
}

#[test]
fn a_missing_or_broken_texture_is_a_warning_and_a_flat_colour() {
    let dir = folder("missing");
    quad_obj(&dir, "absent.png");
    let scene = quad_scene(&dir, "quad.obj", "");
    assert!(scene.textures.is_empty());
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    assert!(
        scene.warnings[0].contains("absent.png") && scene.warnings[0].contains("flat colour"),
        "{:?}",
        scene.warnings
    );
    let f = cast(&scene, 64, Mode::Cast);
    assert!(
        (f.color[(16 * 64 + 16) as usize] - Vec3::ONE)
            .abs()
            .max_element()
            < 1e-4
    );
    // Not an image at all.
    std::fs::write(dir.join("absent.png"), b"not a PNG").unwrap();
    let scene = quad_scene(&dir, "quad.obj", "");
    assert!(scene.textures.is_empty());
    assert!(
        scene.warnings[0].contains("not a PNG or JPEG"),
        "{:?}",
        scene.warnings
    );
}

/// A UV sphere of radius 1 with `rings` x `segments` quads split into triangles, as OBJ
/// with its exact normals as vertex normals.
fn sphere_obj(dir: &Path, rings: u32, segments: u32) {
    let mut obj = String::new();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let p = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            obj += &format!("v {} {} {}\nvn {} {} {}\n", p.x, p.y, p.z, p.x, p.y, p.z);
        }
    }
    let at = |i: u32, j: u32| i * segments + j % segments + 1;
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
            obj += &format!("f {a}//{a} {b}//{b} {d}//{d}\nf {a}//{a} {d}//{d} {c}//{c}\n");
        }
    }
    std::fs::write(dir.join("sphere.obj"), obj).unwrap();
}

/// The largest brightness step between horizontally neighbouring pixels inside a disc of
/// `radius` pixels around the image's centre (inside the sphere's silhouette, where the
/// interpolated normals of its outermost facets turn away from the viewer and the geometric
/// normals take over).
fn largest_step(f: &Frame, radius: f32) -> f32 {
    let mut step = 0.0f32;
    let c = f.width as f32 / 2.0;
    for y in 0..f.height {
        for x in 1..f.width {
            let (a, b) = ((y * f.width + x - 1) as usize, (y * f.width + x) as usize);
            if (x as f32 - c).hypot(y as f32 + 0.5 - c) < radius {
                assert!(f.ids[a] != NO_HIT && f.ids[b] != NO_HIT);
                step = step.max((f.color[a].x - f.color[b].x).abs());
            }
        }
    }
    step
}

#[test]
fn vertex_normals_shade_smoothly_and_change_no_hit() {
    let dir = folder("sphere");
    sphere_obj(&dir, 8, 12);
    let scene = |extra: &str| {
        let toml = format!(
            "[camera]\nposition = [0.0, 0.0, 4.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 35\n\
             [[light]]\nkind = \"directional\"\ndirection = [-0.5, -0.4, -1.0]\n\
             radiance = [1.0, 1.0, 1.0]\n\
             [[object]]\nkind = \"mesh\"\npath = \"sphere.obj\"\n{extra}"
        );
        let path = dir.join("scene.toml");
        std::fs::write(&path, toml).unwrap();
        Arc::new(raybench_scene::load(path.to_str().unwrap(), &dir).unwrap())
    };
    let smooth = scene("");
    let faceted = scene("smooth = false");
    assert!(smooth.attributes.has_normals() && !faceted.attributes.has_normals());
    for mode in [Mode::Cast, Mode::Whitted] {
        let s = cast(&smooth, 96, mode);
        let f = cast(&faceted, 96, mode);
        // Ray casting has no shadows (Whitted's shadow rays cut the smooth terminator
        // along the facets, as in every renderer with shading normals). Measured: steps
        // of at most 0.013 smooth, 0.28 faceted.
        if mode == Mode::Cast {
            let (ss, fs) = (largest_step(&s, 24.0), largest_step(&f, 24.0));
            assert!(ss < 0.1 * fs, "{mode:?}: smooth steps {ss}, faceted {fs}");
        }
        // Shading normals change the colours, never the ids or t.
        assert_eq!(s.ids, f.ids, "{mode:?}");
        assert!(
            s.t.iter()
                .zip(&f.t)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
        assert_ne!(s.color, f.color);
        // Every exact backend shades the same hits the same way.
        for backend in raybench_tests::available(EXACT_BACKENDS) {
            let settings = RenderSettings {
                width: 96,
                height: 96,
                mode,
                ..RenderSettings::default()
            };
            let other = render_with(backend, &smooth, &settings, 2);
            assert_eq!(other.ids, s.ids, "{backend} {mode:?}");
            assert_eq!(other.color, s.color, "{backend} {mode:?}");
        }
    }
    // Path tracing samples around the shading normal and stays finite.
    let settings = RenderSettings {
        width: 32,
        height: 32,
        spp: 4,
        mode: Mode::Path,
        ..RenderSettings::default()
    };
    let p = render_with(ORACLE, &smooth, &settings, 2);
    assert!(p.color.iter().all(|c| c.is_finite()));
}

#[test]
fn bad_attributes_are_errors_or_warnings() {
    let dir = folder("bad");
    // A zero vertex normal: the geometric normal, with a warning.
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n";
    std::fs::write(dir.join("zero.obj"), obj).unwrap();
    let scene = raybench_scene::load(dir.join("zero.obj").to_str().unwrap(), &dir).unwrap();
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("1 vertex normals are zero")),
        "{:?}",
        scene.warnings
    );
    // A normal index out of range.
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//9\n";
    std::fs::write(dir.join("range.obj"), obj).unwrap();
    let e = raybench_scene::load(dir.join("range.obj").to_str().unwrap(), &dir)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(e.contains("range.obj"), "{e}");
    // glTF: NORMAL with fewer elements than POSITION.
    let bin = quad_bin();
    let uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
    let json = quad_gltf(Some(&uri), bin.len(), "{}", "").replacen(
        r#""componentType": 5126, "count": 4, "type": "VEC3"}"#,
        r#""componentType": 5126, "count": 3, "type": "VEC3"}"#,
        1,
    );
    std::fs::write(dir.join("short.gltf"), json).unwrap();
    let e = raybench_scene::load_gltf_file(&dir.join("short.gltf"))
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(e.contains("NORMAL has 3 elements for 4 vertices"), "{e}");
}
