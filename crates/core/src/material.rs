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
