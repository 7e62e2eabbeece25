//! The built-in scenes, embedded from `bench-scenes/` so they work from any directory.

/// A built-in scene.
#[derive(Clone, Copy, Debug)]
pub struct BuiltinScene {
    /// Its name.
    pub name: &'static str,
    /// One line of description.
    pub description: &'static str,
    /// The mesh files it needs from the assets directory (empty: self-contained).
    pub assets: &'static [&'static str],
    /// Its TOML source.
    pub source: &'static str,
}

macro_rules! builtin {
    ($name:literal, $desc:literal, [$($asset:literal),*]) => {
        BuiltinScene {
            name: $name,
            description: $desc,
            assets: &[$($asset),*],
            source: include_str!(concat!("../../../bench-scenes/", $name, ".toml")),
        }
    };
}

/// Every built-in scene, in the order `raybench scenes` lists them.
pub const BUILTIN_SCENES: &[BuiltinScene] = &[
    builtin!(
        "spheres",
        "the lecture's example: five coloured spheres over a plane",
        []
    ),
    builtin!(
        "whitted",
        "a glass and a mirror sphere over a checkered floor, point lights",
        []
    ),
    builtin!(
        "cornell-box",
        "the Cornell box (36 triangles, area light)",
        ["cornell-box/CornellBox-Original.obj"]
    ),
    builtin!(
        "bunny-lowres",
        "Stanford bunny, 3,674 triangles",
        ["bunny-lowres/bunny-lowres.obj"]
    ),
    builtin!(
        "bunny",
        "Stanford bunny, 69,451 triangles",
        ["bunny/stanford-bunny.obj"]
    ),
    builtin!(
        "sponza",
        "Dabrovic's Sponza atrium, 66,454 triangles, seen from inside",
        ["sponza-dabrovic/sponza.obj"]
    ),
    builtin!(
        "suzanne",
        "Blender's Suzanne, 968 triangles",
        ["suzanne/suzanne.obj"]
    ),
    builtin!(
        "teapot",
        "the Utah teapot, 6,320 triangles",
        ["teapot/teapot.obj"]
    ),
    builtin!(
        "teapot-stadium",
        "the teapot inside a huge, nearly empty box (where uniform grids lose)",
        ["teapot/teapot.obj"]
    ),
    builtin!(
        "heightfield",
        "a 1024^2-cell height field intersected directly, a mirror sphere, water",
        []
    ),
    builtin!(
        "phantom",
        "the 3D Shepp-Logan head phantom, 128^3 voxels (modes mip and composite)",
        []
    ),
    builtin!(
        "csg",
        "CSG trees of spheres, boxes, cylinders, cones and half-spaces: all three operations",
        []
    ),
    // Issue 10, tori and quadrics.
    builtin!(
        "quadrics",
        "tori, an ellipsoid, a paraboloid, a tilted cylinder and cone, a ring cut by a box",
        []
    ),
    builtin!(
        "teapot-bezier",
        "the Utah teapot as 32 bicubic Bezier patches, intersected directly",
        ["teapot-bezier/teapot.bpt"]
    ),
    builtin!(
        "sdf",
        "signed-distance models by sphere tracing: smooth union, blend, subtraction, torus",
        []
    ),
];
