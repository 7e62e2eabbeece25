//! Seeded procedural scenes: `soup:M`, `spheres:M`, `icosphere:L`, `terrain:N`,
//! `heightfield:N`.
//!
//! Every generator is a pure function of its parameters and seed (random numbers come from
//! the core's counter-based [`pcg3d`] hash), so the same spec gives the same scene
//! everywhere.

use crate::budget::{Holds, Reservation};
use crate::error::LoadError;
use raybench_core::HeightField;
use raybench_core::sampling::{pcg3d, to_unit_f32};
use raybench_core::{
    Camera, Light, Material, Scene, SceneBuilder, SceneError, Sphere, TriangleMesh, Vec3,
};
use std::collections::HashMap;
use std::sync::Arc;

/// A generator's description for `raybench scenes`.
#[derive(Clone, Copy, Debug)]
pub struct GeneratorInfo {
    /// Name before the colon.
    pub name: &'static str,
    /// What the argument means.
    pub argument: &'static str,
    /// Largest accepted argument.
    pub max: u64,
    /// One line of description.
    pub description: &'static str,
}

/// The generators.
pub const GENERATORS: [GeneratorInfo; 5] = [
    GeneratorInfo {
        name: "soup",
        argument: "M triangles",
        max: 20_000_000,
        description: "random small triangles in a cube",
    },
    GeneratorInfo {
        name: "spheres",
        argument: "M spheres",
        max: 20_000_000,
        description: "random spheres in a cube",
    },
    GeneratorInfo {
        name: "icosphere",
        argument: "subdivision level L (20 * 4^L triangles)",
        max: 10,
        description: "closed, watertight subdivided icosahedron",
    },
    GeneratorInfo {
        name: "terrain",
        argument: "N x N cells (2 N^2 triangles)",
        max: 4096,
        description: "height-field terrain (sin/cos bumps) tessellated into triangles",
    },
    GeneratorInfo {
        name: "heightfield",
        argument: "N x N cells (one height-field primitive)",
        max: 4096,
        description: "the terrain:N heights as one directly intersected height field",
    },
];

/// The seed used when a spec gives none.
pub const DEFAULT_SEED: u32 = 1;

/// What a generator makes.
#[derive(Clone, Debug)]
pub enum Generated {
    /// A triangle mesh.
    Mesh(TriangleMesh),
    /// Spheres.
    Spheres(Vec<Sphere>),
    /// The vertex heights of an `n x n`-cell height field (see [`terrain_heights`]).
    HeightField {
        /// Cells per side.
        n: u32,
        /// `(n + 1)^2` heights, row by row.
        heights: Vec<f32>,
    },
}

/// True when `spec` has the form `name:arg` with a known generator name.
#[must_use]
pub fn is_generator_spec(spec: &str) -> bool {
    spec.split_once(':')
        .is_some_and(|(name, _)| GENERATORS.iter().any(|g| g.name == name))
}

fn uniform(index: u32, seed: u32, dim: u32) -> f32 {
    to_unit_f32(pcg3d([index, seed, dim])[0])
}

/// Parses `name:arg` into the generator and its argument.
///
/// # Errors
/// [`LoadError::Generator`] for unknown names, non-numbers, zero or too large arguments.
pub fn parse_spec(spec: &str) -> Result<(GeneratorInfo, u64), LoadError> {
    let err = |message: String| LoadError::Generator {
        spec: spec.to_owned(),
        message,
    };
    let (name, arg) = spec
        .split_once(':')
        .ok_or_else(|| err("expected name:number".into()))?;
    let info = GENERATORS
        .iter()
        .find(|g| g.name == name)
        .copied()
        .ok_or_else(|| err(format!("unknown generator '{name}'")))?;
    let n: u64 = arg.parse().map_err(|_| {
        err(format!(
            "'{arg}' is not a non-negative whole number ({})",
            info.argument
        ))
    })?;
    let min = u64::from(info.name != "icosphere");
    if n < min || n > info.max {
        return Err(err(format!(
            "{} must be in {min}..={} ({})",
            n, info.max, info.argument
        )));
    }
    Ok((info, n))
}

/// The number of primitives generator `info` makes with argument `n` (one for a height
/// field), known before generating.
#[must_use]
pub fn primitive_count(info: &GeneratorInfo, n: u64) -> u64 {
    match info.name {
        "icosphere" => 20u64 << (2 * n),
        "terrain" => 2 * n * n,
        "heightfield" => 1,
        _ => n,
    }
}

/// What generator `info` with argument `n` holds, for the memory budget.
pub(crate) fn holds(info: &GeneratorInfo, n: u64) -> Holds {
    match info.name {
        "heightfield" => Holds::Vertices((n + 1) * (n + 1)),
        _ => Holds::Primitives(primitive_count(info, n)),
    }
}

/// Runs the generator of `spec` with `seed`.
///
/// # Errors
/// As [`parse_spec`].
pub fn generate(spec: &str, seed: u32) -> Result<Generated, LoadError> {
    let (info, n) = parse_spec(spec)?;
    Ok(match info.name {
        "soup" => Generated::Mesh(soup(n as u32, seed)),
        "spheres" => Generated::Spheres(random_spheres(n as u32, seed)),
        "icosphere" => Generated::Mesh(icosphere(n as u32)),
        "heightfield" => Generated::HeightField {
            n: n as u32,
            heights: terrain_heights(n as u32),
        },
        _ => Generated::Mesh(terrain(n as u32)),
    })
}

/// `m` random triangles in the cube `[-1, 1]^3`: centres uniform, vertices offset from the
/// centre by up to `1 / cbrt(m)` per axis (about 0.02 for 100,000, the soup of PEERS.md).
#[must_use]
pub fn soup(m: u32, seed: u32) -> TriangleMesh {
    let size = 1.0 / (m.max(1) as f32).cbrt();
    let mut positions = Vec::with_capacity(m as usize * 3);
    for i in 0..m {
        let c = Vec3::new(
            uniform(i, seed, 0),
            uniform(i, seed, 1),
            uniform(i, seed, 2),
        ) * 2.0
            - 1.0;
        for k in 0..3 {
            let d = Vec3::new(
                uniform(i, seed, 3 + 3 * k),
                uniform(i, seed, 4 + 3 * k),
                uniform(i, seed, 5 + 3 * k),
            ) * 2.0
                - 1.0;
            positions.push(c + d * size);
        }
    }
    let indices = (0..m).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    TriangleMesh { positions, indices }
}

/// `m` random spheres in the cube `[-1, 1]^3` with radii between 0.2 and 1 times
/// `0.6 / cbrt(m)`.
#[must_use]
pub fn random_spheres(m: u32, seed: u32) -> Vec<Sphere> {
    let scale = 0.6 / (m.max(1) as f32).cbrt();
    (0..m)
        .map(|i| {
            let c = Vec3::new(
                uniform(i, seed, 10),
                uniform(i, seed, 11),
                uniform(i, seed, 12),
            ) * 2.0
                - 1.0;
            Sphere::new(c, scale * (0.2 + 0.8 * uniform(i, seed, 13)))
        })
        .collect()
}

/// The unit icosphere: an icosahedron whose faces are split into four `level` times, every
/// vertex projected onto the sphere. Edges share vertices, so the mesh is closed and a
/// watertight test lets no ray through.
#[must_use]
pub fn icosphere(level: u32) -> TriangleMesh {
    let phi = (1.0 + 5.0f32.sqrt()) * 0.5;
    let mut positions: Vec<Vec3> = [
        (-1.0, phi, 0.0),
        (1.0, phi, 0.0),
        (-1.0, -phi, 0.0),
        (1.0, -phi, 0.0),
        (0.0, -1.0, phi),
        (0.0, 1.0, phi),
        (0.0, -1.0, -phi),
        (0.0, 1.0, -phi),
        (phi, 0.0, -1.0),
        (phi, 0.0, 1.0),
        (-phi, 0.0, -1.0),
        (-phi, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut indices: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                let p = ((positions[a as usize] + positions[b as usize]) * 0.5).normalize();
                positions.push(p);
                (positions.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(indices.len() * 4);
        for &[a, b, c] in &indices {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        indices = next;
    }
    TriangleMesh { positions, indices }
}

/// Height of the terrain at `(x, z)` in `[-1, 1]^2`: a sum of sin/cos bumps.
#[must_use]
pub fn terrain_height(x: f32, z: f32) -> f32 {
    0.12 * (3.0 * x).sin() * (2.5 * z).cos()
        + 0.05 * (9.0 * x + 1.0).sin() * (7.0 * z + 0.5).sin()
        + 0.015 * (31.0 * x).cos() * (27.0 * z).sin()
}

/// The `(n + 1)^2` vertex heights of [`terrain`]`(n)`, row by row, computed with the same
/// expressions (so that a [`raybench_core::HeightField`] over them has the mesh's
/// vertices bit for bit).
#[must_use]
pub fn terrain_heights(n: u32) -> Vec<f32> {
    let n = n.max(1);
    let mut heights = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
    for j in 0..=n {
        for i in 0..=n {
            let x = -1.0 + 2.0 * i as f32 / n as f32;
            let z = -1.0 + 2.0 * j as f32 / n as f32;
            heights.push(terrain_height(x, z));
        }
    }
    heights
}

/// An `n x n`-cell height field over `[-1, 1]^2` in x and z, heights along y, tessellated
/// into `2 n^2` triangles: cell `(i, j)` (column `i`, row `j`, row-major) becomes triangles
/// `2 (j n + i)` = `(p00, p01, p11)` and `2 (j n + i) + 1` = `(p00, p11, p10)`, where `pXY` is
/// the vertex at column `i + X`, row `j + Y`.
#[must_use]
pub fn terrain(n: u32) -> TriangleMesh {
    let n = n.max(1);
    let verts = n + 1;
    let mut positions = Vec::with_capacity((verts * verts) as usize);
    for j in 0..verts {
        for i in 0..verts {
            let x = -1.0 + 2.0 * i as f32 / n as f32;
            let z = -1.0 + 2.0 * j as f32 / n as f32;
            positions.push(Vec3::new(x, terrain_height(x, z), z));
        }
    }
    let mut indices = Vec::with_capacity(2 * (n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let p00 = j * verts + i;
            let p10 = p00 + 1;
            let p01 = p00 + verts;
            let p11 = p01 + 1;
            indices.push([p00, p01, p11]);
            indices.push([p00, p11, p10]);
        }
    }
    TriangleMesh { positions, indices }
}

/// Geometry that exercises an acceleration structure, for tests of backends against the
/// naive oracle: a triangle soup (4,000), an icosphere (level 4), a terrain (48 x 48 cells),
/// a mix of triangles, `spheres` random spheres and a plane in interleaved id order, and
/// the empty geometry.
#[must_use]
pub fn test_geometries(
    spheres: u32,
) -> Vec<(&'static str, std::sync::Arc<raybench_core::Geometry>)> {
    use raybench_core::{Geometry, Plane, Shape};
    let tris = |m: TriangleMesh| m.triangles().map(Shape::Triangle).collect::<Vec<_>>();
    let mut mixed = tris(icosphere(2));
    mixed.extend(random_spheres(spheres, 9).into_iter().map(Shape::Sphere));
    mixed.push(Shape::Plane(Plane::new(Vec3::new(0.0, -1.5, 0.0), Vec3::Y)));
    mixed.extend(tris(soup(300, 4)));
    vec![
        ("soup", Arc::new(Geometry::new(tris(soup(4000, 1))))),
        ("icosphere", Arc::new(Geometry::new(tris(icosphere(4))))),
        ("terrain", Arc::new(Geometry::new(tris(terrain(48))))),
        ("mixed", Arc::new(Geometry::new(mixed))),
        ("empty", Arc::new(Geometry::default())),
    ]
}

fn palette() -> [Material; 5] {
    let c = |name: &str, r, g, b| Material {
        name: name.into(),
        base_color: Vec3::new(r, g, b),
        ..Material::default()
    };
    [
        c("red", 0.8, 0.25, 0.2),
        c("green", 0.3, 0.7, 0.3),
        c("blue", 0.25, 0.4, 0.85),
        c("yellow", 0.85, 0.75, 0.3),
        c("white", 0.8, 0.8, 0.8),
    ]
}

/// The camera of `terrain:N` and `heightfield:N`: from above at an angle.
fn terrain_camera() -> Camera {
    Camera {
        position: Vec3::new(0.0, 1.3, 2.1),
        look_at: Vec3::new(0.0, -0.1, 0.0),
        up: Vec3::Y,
        vfov_degrees: 45.0,
    }
}

/// A builder for a scene of one mesh file (a bare mesh scene) or generator spec: a
/// grey-blue background and one directional light from above (the camera frames the
/// geometry by default).
pub(crate) fn lit_builder(name: &str) -> Result<SceneBuilder, SceneError> {
    let mut b = SceneBuilder::new(name);
    b.background(Vec3::new(0.55, 0.65, 0.8))?;
    b.add_light(Light::Directional {
        direction: Vec3::new(-0.4, -1.0, -0.6),
        radiance: Vec3::ONE,
    })?;
    Ok(b)
}

/// The whole scene of a generator spec: the geometry, a light, and a camera framing it
/// (from above at an angle for terrain and height fields).
///
/// # Errors
/// As [`parse_spec`].
pub fn generate_scene(spec: &str) -> Result<Scene, LoadError> {
    let scene_err = |cause| LoadError::Scene {
        context: spec.to_owned(),
        cause,
    };
    let (info, n) = parse_spec(spec)?;
    Reservation::new()?.reserve(holds(&info, n), &format!("generator '{spec}'"))?;
    let generated = generate(spec, DEFAULT_SEED)?;
    let mut b = lit_builder(spec).map_err(scene_err)?;
    let mut mats = Vec::new();
    for m in palette() {
        mats.push(b.add_material(m).map_err(scene_err)?);
    }
    match generated {
        Generated::Mesh(mesh) => {
            let name = spec.split(':').next().unwrap_or(spec);
            let material = if name == "terrain" { mats[1] } else { mats[4] };
            b.add_mesh(spec, &mesh, material).map_err(scene_err)?;
            if name == "terrain" {
                b.camera(terrain_camera()).map_err(scene_err)?;
            }
        }
        Generated::HeightField { n, heights } => {
            let field = HeightField::new(n, n, heights, None).map_err(scene_err)?;
            b.add_shapes(
                spec,
                vec![raybench_core::Shape::HeightField(Arc::new(field))],
                mats[1],
            )
            .map_err(scene_err)?;
            b.camera(terrain_camera()).map_err(scene_err)?;
        }
        Generated::Spheres(spheres) => {
            for (i, s) in spheres.into_iter().enumerate() {
                b.add_sphere(s, mats[i % mats.len()]).map_err(scene_err)?;
            }
        }
    }
    Ok(b.build())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts() {
        assert_eq!(soup(100, 1).indices.len(), 100);
        assert_eq!(random_spheres(7, 1).len(), 7);
        assert_eq!(icosphere(0).indices.len(), 20);
        assert_eq!(icosphere(3).indices.len(), 20 * 64);
        // Closed: V - E + F = 2 with E = 3F/2.
        let m = icosphere(3);
        assert_eq!(
            m.positions.len() as i64 - 3 * m.indices.len() as i64 / 2 + m.indices.len() as i64,
            2
        );
        assert_eq!(terrain(708).indices.len(), 1_002_528);
    }

    #[test]
    fn seeded_and_deterministic() {
        assert_eq!(soup(50, 3), soup(50, 3));
        assert_ne!(soup(50, 3), soup(50, 4));
    }

    #[test]
    fn bad_specs() {
        for spec in [
            "soup:",
            "soup:-1",
            "soup:0",
            "soup:abc",
            "terrain:5000",
            "icosphere:11",
            "cube:3",
            "soup:1e3",
        ] {
            assert!(parse_spec(spec).is_err(), "{spec}");
        }
        assert!(parse_spec("icosphere:0").is_ok());
        assert!(is_generator_spec("soup:10") && !is_generator_spec("bunny"));
    }
}
