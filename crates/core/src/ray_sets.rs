//! Standard ray sets for benchmarks: primary camera rays, seeded incoherent rays, and the
//! sets derived from the primary rays' hits (`shadow`, `ao`, `diffuse`: [`derived`]).
//!
//! Every set is a pure function of the scene, the camera, the image size and (for the
//! derived sets) the primary hits and [`DerivedParams`]; the random numbers are the
//! counter-based [`Sampler`]'s, keyed by the primary ray's index, a sample and a fixed
//! dimension. So every backend, peer and thread count traces exactly the same rays, and
//! since every exact backend returns bit-identical primary hits, the derived sets are the
//! same whichever exact backend traced the primary rays.

use crate::camera::Camera;
use crate::material::Light;
use crate::optics::{cosine_hemisphere, offset_ray_origin};
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::{Hit, Ray, limits};
use glam::Vec3;
use std::fmt;

pub use crate::integrator::SHADOW_SHORTEN;
pub use raybench_geometry::random_rays::incoherent;

/// Which rays a measurement traces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum RaySet {
    /// One ray per pixel through the pixel centre, row by row.
    #[default]
    Primary,
    /// `width * height` random rays: origins uniform in the scene's bounding box,
    /// directions uniform on the sphere (the workload of `../shared/PEERS.md`).
    Incoherent,
    /// Any hit: from every primary hit to every point and directional light, and one
    /// light sample by power (emissive primitives, the environment map) per hit
    /// ([`derived`]).
    Shadow,
    /// Any hit: [`DerivedParams::ao_rays`] cosine-distributed rays per primary hit, as long
    /// as [`DerivedParams::ao_distance`] of the scene's diagonal ([`derived`]).
    Ao,
    /// Closest hit: one cosine-distributed bounce per primary hit ([`derived`]).
    Diffuse,
}

impl RaySet {
    /// Every ray set.
    pub const ALL: [Self; 5] = [
        Self::Primary,
        Self::Incoherent,
        Self::Shadow,
        Self::Ao,
        Self::Diffuse,
    ];

    /// The name used on the command line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Primary => "primary",
            Self::Incoherent => "incoherent",
            Self::Shadow => "shadow",
            Self::Ao => "ao",
            Self::Diffuse => "diffuse",
        }
    }

    /// The ray set called `name`, if any.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|r| r.name() == name)
    }

    /// Whether the set asks for any hit (occlusion: is anything in `[t_min, t_max]`?)
    /// rather than the closest hit: `shadow` and `ao`.
    #[must_use]
    pub fn any_hit(self) -> bool {
        matches!(self, Self::Shadow | Self::Ao)
    }

    /// Whether the set is generated from the primary rays' hits ([`derived`]).
    #[must_use]
    pub fn is_derived(self) -> bool {
        matches!(self, Self::Shadow | Self::Ao | Self::Diffuse)
    }
}

/// The default of [`DerivedParams::ao_rays`] (`--ao-rays`).
pub const DEFAULT_AO_RAYS: u32 = 4;

/// The largest [`DerivedParams::ao_rays`].
pub const MAX_AO_RAYS: u32 = 1024;

/// The default of [`DerivedParams::ao_distance`]: ambient-occlusion rays reach a tenth of
/// the scene's bounding-box diagonal (local occlusion, as renderers use it, rather than
/// whole-scene visibility).
pub const AO_DISTANCE: f32 = 0.1;

/// Sampler dimensions of the derived sets, disjoint so that the sets are uncorrelated:
/// shadow rays use the light choice and a point on the light (3), ambient occlusion a
/// direction (2), the diffuse bounce a direction (2).
const SHADOW_DIMENSION: u32 = 0;
const AO_DIMENSION: u32 = 3;
const DIFFUSE_DIMENSION: u32 = 5;

/// Derived rays ignore hits closer than this fraction of the largest coordinate magnitude
/// (of the scene's bounding box and of the hit point): `t_min = 2^-16 x scale`, in scene
/// units. The origin offset ([`offset_ray_origin`]) is a few ulps of the hit point's own
/// coordinates, but the watertight triangle test's `t` has an absolute error of a few ulps
/// of the triangle's coordinates relative to the origin: a ray leaving a large floor near
/// `y = 0` at a grazing angle along `x` found its own triangle at `t = 0` to `5e-5` in a
/// scene whose coordinates reach a few hundred (`teapot-stadium`), a hit outside the
/// triangle's box, which naive reports and the BVHs' box tests cull. Hits that close are
/// rounding, not geometry; leaving them out makes the sets the same query for every
/// exact backend.
pub const SELF_HIT_FRACTION: f32 = 1.0 / 65_536.0;

/// Parameters of the derived ray sets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DerivedParams {
    /// Ambient-occlusion rays per primary hit, in `1..=`[`MAX_AO_RAYS`].
    pub ao_rays: u32,
    /// Length of an ambient-occlusion ray as a fraction of the scene's bounding-box
    /// diagonal (positive, finite).
    pub ao_distance: f32,
    /// Seed of the random numbers.
    pub seed: u32,
}

impl Default for DerivedParams {
    fn default() -> Self {
        Self {
            ao_rays: DEFAULT_AO_RAYS,
            ao_distance: AO_DISTANCE,
            seed: 0,
        }
    }
}

/// Why [`derived`] produced no rays.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DerivedError {
    /// The set is not derived from primary hits (`primary`, `incoherent`).
    NotDerived(RaySet),
    /// The parameters are out of range, with the reason.
    BadParams(String),
    /// The rays and hits differ in length.
    LengthMismatch {
        /// Rays given.
        rays: usize,
        /// Hits given.
        hits: usize,
    },
    /// The set would exceed [`limits::MAX_EXPLICIT_RAYS`].
    TooManyRays {
        /// The set.
        set: RaySet,
        /// Rays it would hold (an upper bound for `shadow`).
        count: u64,
    },
}

impl fmt::Display for DerivedError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotDerived(set) => write!(
                f,
                "ray set '{}' is not derived from primary hits",
                set.name()
            ),
            Self::BadParams(reason) => write!(f, "{reason}"),
            Self::LengthMismatch { rays, hits } => {
                write!(f, "{rays} primary rays but {hits} hits")
            }
            Self::TooManyRays { set, count } => write!(
                f,
                "{count} {} rays exceed the limit of {} (use a smaller image or fewer \
                 --ao-rays)",
                set.name(),
                limits::MAX_EXPLICIT_RAYS
            ),
        }
    }
}

impl std::error::Error for DerivedError {}

/// The rays of a derived set (`shadow`, `ao` or `diffuse`), generated from `primary` rays
/// and their closest hits `hits` (same length; normally
/// [`primary_tiled`]`(camera, w, h, tile)`, the order the integrators trace, traced by any
/// exact backend). Each hit `i` at `p = primary[i].at(t)` starts its rays at `p` moved off
/// the surface by [`offset_ray_origin`] along the geometric normal turned to the side the
/// primary ray came from; misses generate nothing. The rays come out hit by hit, in the
/// order of `primary`, and within a hit in the order below. Random numbers are
/// [`Sampler`]`::new(i, sample, params.seed)` at fixed dimensions, so the set is a pure
/// function of its inputs. Every ray ignores hits closer than [`SELF_HIT_FRACTION`] of the
/// largest coordinate magnitude of the scene and of the hit point (its `t_min`): rounding
/// of the surface it leaves. The `t` ranges below start there.
///
/// - `shadow` (any hit): one ray to every light of `scene.lights`: to a point light
///   parametrised from the origin to the light, `t` up to [`SHADOW_SHORTEN`]; along a
///   directional light, `t` unbounded. Then, when the scene has emitters (emissive
///   primitives or an environment map), one light sample of [`crate::Emitters::sample`]
///   (the light chosen by power, a point or direction on it), as path tracing's
///   next-event estimation makes it: to a point likewise stopping [`SHADOW_SHORTEN`] short
///   of it, towards the environment unbounded; none where that sample finds nothing (the
///   chosen emitter faces away). Sample 0, dimensions 0..3. A ray that would leave the
///   surface on its far side or along it (its direction at 90 degrees or more from the
///   normal above) is not made: the surface itself blocks that light, as renderers count
///   it without tracing, and whether such a ray found its own surface would depend on the
///   origin's offset, not on the scene. [`derived_set`] counts them
///   ([`Derived::facing_away`]).
/// - `ao` (any hit): `params.ao_rays` cosine-distributed directions about the normal
///   (sample `k` for the `k`-th, dimensions 3..5), `t` up to `params.ao_distance x
///   diagonal` where `diagonal` is the length of the scene's bounding box' diagonal
///   (unbounded when the box is empty or infinite: only planes).
/// - `diffuse` (closest hit): one cosine-distributed direction (sample 0, dimensions
///   5..7), `t` unbounded.
///
/// # Errors
/// [`DerivedError::NotDerived`] for `primary` and `incoherent`, [`DerivedError::BadParams`]
/// for `ao_rays` outside `1..=`[`MAX_AO_RAYS`] or a `ao_distance` that is not positive and
/// finite, [`DerivedError::LengthMismatch`], and [`DerivedError::TooManyRays`] when the set
/// could exceed [`limits::MAX_EXPLICIT_RAYS`] (checked before anything is allocated).
pub fn derived(
    set: RaySet,
    scene: &Scene,
    primary: &[Ray],
    hits: &[Option<Hit>],
    params: &DerivedParams,
) -> Result<Vec<Ray>, DerivedError> {
    derived_set(set, scene, primary, hits, params).map(|d| d.rays)
}

/// A derived ray set and the rays it leaves out.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Derived {
    /// The rays ([`derived`]).
    pub rays: Vec<Ray>,
    /// Shadow rays not made because they would leave the surface on its far side (the light
    /// lies behind the surface, which blocks it): blocked without being traced. 0 for the
    /// other sets.
    pub facing_away: u64,
}

/// [`derived`], with the count of the shadow rays it leaves out because the surface itself
/// blocks their light ([`Derived::facing_away`]).
///
/// # Errors
/// As [`derived`].
pub fn derived_set(
    set: RaySet,
    scene: &Scene,
    primary: &[Ray],
    hits: &[Option<Hit>],
    params: &DerivedParams,
) -> Result<Derived, DerivedError> {
    if !set.is_derived() {
        return Err(DerivedError::NotDerived(set));
    }
    if !(1..=MAX_AO_RAYS).contains(&params.ao_rays) {
        return Err(DerivedError::BadParams(format!(
            "--ao-rays {} must be in 1..={MAX_AO_RAYS}",
            params.ao_rays
        )));
    }
    if !(params.ao_distance > 0.0 && params.ao_distance.is_finite()) {
        return Err(DerivedError::BadParams(format!(
            "the ambient-occlusion distance {} must be positive and finite",
            params.ao_distance
        )));
    }
    if primary.len() != hits.len() {
        return Err(DerivedError::LengthMismatch {
            rays: primary.len(),
            hits: hits.len(),
        });
    }
    let hit_count = hits.iter().filter(|h| h.is_some()).count() as u64;
    let per_hit = match set {
        RaySet::Shadow => scene.lights.len() as u64 + u64::from(!scene.emitters.is_empty()),
        RaySet::Ao => u64::from(params.ao_rays),
        _ => 1,
    };
    let count = hit_count * per_hit;
    if count > limits::MAX_EXPLICIT_RAYS {
        return Err(DerivedError::TooManyRays { set, count });
    }
    let bounds = scene.geometry.world_bounds();
    let bounded = !bounds.is_empty() && bounds.extent().length().is_finite();
    let ao_t_max = if bounded {
        params.ao_distance * bounds.extent().length()
    } else {
        f32::INFINITY
    };
    // The largest coordinate magnitude of the scene: the scale of the triangle test's
    // rounding (see SELF_HIT_FRACTION).
    let scale = if bounded {
        bounds.min.abs().max(bounds.max.abs()).max_element()
    } else {
        0.0
    };
    let mut out = Vec::with_capacity(count as usize);
    let mut facing_away = 0;
    for (i, (ray, hit)) in primary.iter().zip(hits).enumerate() {
        let Some(hit) = hit else { continue };
        let p = ray.at(hit.t);
        // The geometric normal on the side the primary ray came from.
        let n = if hit.normal.dot(ray.dir) < 0.0 {
            hit.normal
        } else {
            -hit.normal
        };
        let origin = offset_ray_origin(p, n);
        let start = Start {
            origin,
            normal: n,
            t_min: SELF_HIT_FRACTION * scale.max(p.abs().max_element()),
        };
        let pixel = i as u32;
        match set {
            RaySet::Shadow => {
                facing_away += shadow_rays(scene, start, pixel, params.seed, &mut out);
            }
            RaySet::Ao => {
                for k in 0..params.ao_rays {
                    let mut s = Sampler::new(pixel, k, params.seed);
                    s.set_dimension(AO_DIMENSION);
                    let (u1, u2) = s.next_2d();
                    let dir = cosine_hemisphere(n, u1, u2);
                    out.push(start.ray(dir, ao_t_max));
                }
            }
            _ => {
                let mut s = Sampler::new(pixel, 0, params.seed);
                s.set_dimension(DIFFUSE_DIMENSION);
                let (u1, u2) = s.next_2d();
                out.push(start.ray(cosine_hemisphere(n, u1, u2), f32::INFINITY));
            }
        }
    }
    Ok(Derived {
        rays: out,
        facing_away,
    })
}

/// Where a hit's rays start: the offset origin, the geometric normal on the side they
/// leave from, and the distance (in scene units) under which hits are not counted.
#[derive(Clone, Copy)]
struct Start {
    origin: Vec3,
    normal: Vec3,
    t_min: f32,
}

impl Start {
    /// The ray along `dir` (any length) over `[t_min / |dir|, t_max]`.
    fn ray(self, dir: Vec3, t_max: f32) -> Ray {
        Ray::with_interval(self.origin, dir, self.t_min / dir.length(), t_max)
    }
}

/// The shadow rays of one hit (see [`derived`]); returns how many it left out because they
/// would leave the surface on its far side.
fn shadow_rays(scene: &Scene, start: Start, pixel: u32, seed: u32, out: &mut Vec<Ray>) -> u64 {
    let origin = start.origin;
    let mut facing_away = 0;
    let mut push = |ray: Ray| {
        if ray.dir.dot(start.normal) > 0.0 {
            out.push(ray);
        } else {
            facing_away += 1;
        }
    };
    for light in &scene.lights {
        push(match *light {
            Light::Point { position, .. } => start.ray(position - origin, SHADOW_SHORTEN),
            Light::Directional { direction, .. } => start.ray(-direction, f32::INFINITY),
        });
    }
    if !scene.emitters.is_empty() {
        let mut s = Sampler::new(pixel, 0, seed);
        s.set_dimension(SHADOW_DIMENSION);
        let u_light = s.next_f32();
        let u_point = s.next_2d();
        if let Some(ls) = scene.emitters.sample(scene, origin, u_light, u_point) {
            push(if ls.dist.is_finite() {
                start.ray(ls.wi * ls.dist, SHADOW_SHORTEN)
            } else {
                start.ray(ls.wi, f32::INFINITY)
            });
        }
    }
    facing_away
}

/// The primary rays of a `width x height` image, row by row from the top.
#[must_use]
pub fn primary(camera: &Camera, width: u32, height: u32) -> Vec<Ray> {
    let rays = camera.rays(width, height);
    let mut out = Vec::with_capacity(width as usize * height as usize);
    for y in 0..height {
        for x in 0..width {
            out.push(rays.center_ray(x, y));
        }
    }
    out
}

/// The same primary rays in the order the integrators trace them: `tile x tile` tiles row
/// by row, each in [`crate::integrator::tile_pixels`] order (4 x 4 pixel blocks). What a
/// benchmark of batch tracing should feed a packet backend.
#[must_use]
pub fn primary_tiled(camera: &Camera, width: u32, height: u32, tile: u32) -> Vec<Ray> {
    let rays = camera.rays(width, height);
    crate::integrator::tiles(width, height, tile)
        .into_iter()
        .flat_map(|t| crate::integrator::tile_pixels(t, width))
        .map(|(x, y, _)| rays.center_ray(x, y))
        .collect()
}

/// Any-hit probes for testing shadow queries: each ray clipped to 90% of its closest hit
/// `closest[i]` (10 units when it misses), so that nothing should block it unless the
/// structure is wrong, followed by the unclipped rays, which are blocked exactly where they
/// hit.
///
/// # Panics
/// When the slices differ in length.
#[must_use]
pub fn shadow_probes(rays: &[Ray], closest: &[Option<crate::Hit>]) -> Vec<Ray> {
    assert_eq!(rays.len(), closest.len());
    rays.iter()
        .zip(closest)
        .map(|(r, h)| Ray::with_interval(r.origin, r.dir, r.t_min, h.map_or(10.0, |h| h.t * 0.9)))
        .chain(rays.iter().copied())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primary_rays_match_the_camera() {
        let cam = Camera::default();
        let rays = primary(&cam, 4, 3);
        assert_eq!(rays.len(), 12);
        assert_eq!(rays[5], cam.rays(4, 3).center_ray(1, 1));
    }

    use crate::builder::SceneBuilder;
    use crate::material::Material;
    use crate::{Shape, Sphere, Triangle};

    /// A unit sphere at the origin, a point light, a directional light and an emissive
    /// triangle above (facing down).
    fn scene() -> Scene {
        let mut b = SceneBuilder::new("derived");
        let white = b.add_material(Material::default()).unwrap();
        let lamp = b
            .add_material(Material {
                emission: Vec3::ONE,
                ..Material::default()
            })
            .unwrap();
        b.add_sphere(Sphere::new(Vec3::ZERO, 1.0), white).unwrap();
        let tri = Triangle::new(
            Vec3::new(-1.0, 4.0, -1.0),
            Vec3::new(1.0, 4.0, -1.0),
            Vec3::new(0.0, 4.0, 1.0),
        );
        let tri = if tri.normal().y > 0.0 {
            Triangle::new(tri.v[0], tri.v[2], tri.v[1])
        } else {
            tri
        };
        b.add_triangles("lamp", &[tri], &[lamp]).unwrap();
        b.add_light(Light::Point {
            position: Vec3::new(0.0, 0.0, 5.0),
            intensity: Vec3::ONE,
        })
        .unwrap();
        b.add_light(Light::Directional {
            direction: Vec3::new(0.0, -1.0, 0.0),
            radiance: Vec3::ONE,
        })
        .unwrap();
        b.build()
    }

    /// Rays towards the sphere's front (`+z`), one missing, with their hits.
    fn primary_hits() -> (Vec<Ray>, Vec<Option<Hit>>) {
        let rays = vec![
            Ray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::new(0.0, 0.0, -1.0)),
            Ray::new(Vec3::new(0.0, 5.0, 3.0), Vec3::new(0.0, 0.0, -1.0)),
            Ray::new(Vec3::new(0.3, 0.2, 3.0), Vec3::new(0.0, 0.0, -1.0)),
        ];
        let hits = rays
            .iter()
            .map(|r| {
                let s = Sphere::new(Vec3::ZERO, 1.0);
                s.intersect(r)
                    .map(|h| Shape::Sphere(s).complete_hit(r, 0, h))
            })
            .collect();
        (rays, hits)
    }

    #[test]
    fn derived_sets_have_their_counts_and_bounds() {
        let scene = scene();
        let (rays, hits) = primary_hits();
        assert_eq!(hits.iter().filter(|h| h.is_some()).count(), 2);
        let p = DerivedParams::default();
        // Two lights and one emitter sample per hit, less those behind the surface: the
        // directional light (from +y) grazes the first hit (normal +z) and is left out; the
        // emitter triangle above lies behind the first hit's tangent plane.
        let set = derived_set(RaySet::Shadow, &scene, &rays, &hits, &p).unwrap();
        let shadow = set.rays.clone();
        assert_eq!(
            shadow,
            derived(RaySet::Shadow, &scene, &rays, &hits, &p).unwrap()
        );
        assert!(set.facing_away >= 2, "{}", set.facing_away);
        assert!(shadow.len() + set.facing_away as usize <= 6);
        assert!(shadow.len() >= 3, "{}", shadow.len());
        let to_light = shadow[0];
        assert_eq!(to_light.t_max, SHADOW_SHORTEN);
        assert!((to_light.at(1.0) - Vec3::new(0.0, 0.0, 5.0)).length() < 1e-5);
        assert!(to_light.origin.z > 1.0, "offset towards the viewer");
        // The second hit's rays: the point light, then the directional light.
        assert!((shadow[1].at(1.0) - Vec3::new(0.0, 0.0, 5.0)).length() < 1e-5);
        assert_eq!(shadow[2].dir, Vec3::Y);
        assert_eq!(shadow[2].t_max, f32::INFINITY);
        // Every ray leaves its surface on the lit side (the origins are offset along the
        // normal, which on the unit sphere is the origin's direction).
        for r in &shadow {
            assert!(r.dir.dot(r.origin.normalize()) > 0.0, "{r:?}");
        }

        let ao = derived(RaySet::Ao, &scene, &rays, &hits, &p).unwrap();
        assert_eq!(ao.len(), 2 * DEFAULT_AO_RAYS as usize);
        let diagonal = scene.geometry.world_bounds().extent().length();
        for (k, r) in ao.iter().enumerate() {
            let n = hits[if k < 4 { 0 } else { 2 }].unwrap().normal;
            assert!(r.dir.dot(n) > 0.0, "ao ray {k} below the surface");
            assert_eq!(r.t_max, AO_DISTANCE * diagonal);
            // The scene reaches 4 (the emitter's height): 4 x 2^-16, along unit directions.
            assert!(
                (r.t_min - 4.0 * SELF_HIT_FRACTION).abs() < 1e-9,
                "{}",
                r.t_min
            );
        }
        let diffuse = derived(RaySet::Diffuse, &scene, &rays, &hits, &p).unwrap();
        assert_eq!(diffuse.len(), 2);
        assert!(diffuse.iter().all(|r| r.t_max == f32::INFINITY));
        assert_ne!(diffuse[0].dir, ao[0].dir, "sets use their own dimensions");
    }

    #[test]
    fn derived_sets_are_pure_functions_of_their_inputs() {
        let scene = scene();
        let (rays, hits) = primary_hits();
        for set in [RaySet::Shadow, RaySet::Ao, RaySet::Diffuse] {
            let p = DerivedParams::default();
            let a = derived(set, &scene, &rays, &hits, &p).unwrap();
            assert_eq!(a, derived(set, &scene, &rays, &hits, &p).unwrap());
            let other = DerivedParams { seed: 9, ..p };
            if set != RaySet::Shadow {
                assert_ne!(a, derived(set, &scene, &rays, &hits, &other).unwrap());
            }
            assert!(set.is_derived());
            assert_eq!(set.any_hit(), set != RaySet::Diffuse);
            assert_eq!(RaySet::from_name(set.name()), Some(set));
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        let scene = scene();
        let (rays, hits) = primary_hits();
        let p = DerivedParams::default();
        assert_eq!(
            derived(RaySet::Primary, &scene, &rays, &hits, &p),
            Err(DerivedError::NotDerived(RaySet::Primary))
        );
        assert!(matches!(
            derived(RaySet::Ao, &scene, &rays[..1], &hits, &p),
            Err(DerivedError::LengthMismatch { rays: 1, hits: 3 })
        ));
        for bad in [
            DerivedParams { ao_rays: 0, ..p },
            DerivedParams {
                ao_rays: MAX_AO_RAYS + 1,
                ..p
            },
            DerivedParams {
                ao_distance: f32::NAN,
                ..p
            },
            DerivedParams {
                ao_distance: 0.0,
                ..p
            },
        ] {
            assert!(matches!(
                derived(RaySet::Ao, &scene, &rays, &hits, &bad),
                Err(DerivedError::BadParams(_))
            ));
        }
        // 2^24 / 1024 + 1 hits of 1024 rays each: refused before any ray is made.
        let n = (limits::MAX_EXPLICIT_RAYS / u64::from(MAX_AO_RAYS)) as usize + 1;
        let many_rays = vec![rays[0]; n];
        let many_hits = vec![hits[0]; n];
        let err = derived(
            RaySet::Ao,
            &scene,
            &many_rays,
            &many_hits,
            &DerivedParams {
                ao_rays: MAX_AO_RAYS,
                ..p
            },
        )
        .unwrap_err();
        assert!(matches!(err, DerivedError::TooManyRays { .. }));
        assert!(err.to_string().contains("exceed the limit"));
    }
}
