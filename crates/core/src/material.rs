//! Materials and lights.

use glam::Vec3;

/// How a surface scatters light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MaterialKind {
    /// Lambertian, with an optional Blinn-Phong highlight (`specular`, `shininess`).
    Diffuse,
    /// A perfect mirror tinted by `specular`.
    Mirror,
    /// A smooth dielectric with index of refraction `ior`.
    Glass,
}

/// A material. Scene files and MTL files map onto these fields (`docs/scene-format.md`).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name (from the scene or MTL file).
    pub name: String,
    /// Scattering model.
    pub kind: MaterialKind,
    /// Diffuse colour (linear RGB), MTL `Kd`.
    pub base_color: Vec3,
    /// Specular or mirror colour, MTL `Ks`.
    pub specular: Vec3,
    /// Blinn-Phong exponent, MTL `Ns`.
    pub shininess: f32,
    /// Emitted radiance, MTL `Ke`.
    pub emission: Vec3,
    /// Index of refraction, MTL `Ni`.
    pub ior: f32,
    /// An optional checkerboard replacing `base_color` on alternate squares.
    pub checker: Option<Checker>,
    /// An optional base-colour texture (an index into [`crate::Scene::textures`]): the
    /// diffuse colour is `base_color` times its texel at the hit's texture coordinates
    /// (glTF `baseColorTexture` times `baseColorFactor`, MTL `map_Kd` times `Kd`).
    /// Primitives without texture coordinates get `base_color` alone.
    pub base_color_texture: Option<u32>,
    /// An optional emission texture (an index into [`crate::Scene::textures`]): the
    /// emitted radiance is `emission` times its texel (glTF `emissiveTexture` times
    /// `emissiveFactor`).
    pub emission_texture: Option<u32>,
}

/// A checkerboard in x and z (for floors): squares of edge `size` alternate between the
/// material's base colour and `color`, by the parity of `floor(x / size) + floor(z / size)`.
/// (y is left out: on a floor at y = 0 the computed hit height jitters around 0.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Checker {
    /// The second colour.
    pub color: Vec3,
    /// Cell edge length (positive).
    pub size: f32,
}

impl Material {
    /// The diffuse colour at point `p` (the checkerboard, if any, applied).
    #[inline]
    #[must_use]
    pub fn albedo_at(&self, p: Vec3) -> Vec3 {
        match self.checker {
            None => self.base_color,
            Some(c) => {
                let parity = ((p.x / c.size).floor() + (p.z / c.size).floor()).rem_euclid(2.0);
                if parity < 0.5 {
                    self.base_color
                } else {
                    c.color
                }
            }
        }
    }
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            kind: MaterialKind::Diffuse,
            base_color: Vec3::splat(0.75),
            specular: Vec3::ZERO,
            shininess: 32.0,
            emission: Vec3::ZERO,
            ior: 1.5,
            checker: None,
            base_color_texture: None,
            emission_texture: None,
        }
    }
}

/// A light source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// A point light with radiant intensity `intensity` (falls off with distance squared).
    Point {
        /// Position.
        position: Vec3,
        /// Intensity (linear RGB).
        intensity: Vec3,
    },
    /// A directional light: parallel light travelling along `direction`.
    Directional {
        /// Direction the light travels (towards the scene); unit length.
        direction: Vec3,
        /// Irradiance (linear RGB).
        radiance: Vec3,
    },
}
