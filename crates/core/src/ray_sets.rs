//! Standard ray sets for benchmarks: primary camera rays and seeded incoherent rays.

use crate::Ray;
use crate::camera::Camera;
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
}

impl RaySet {
    /// Every ray set.
    pub const ALL: [Self; 2] = [Self::Primary, Self::Incoherent];

    /// The name used on the command line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Primary => "primary",
            Self::Incoherent => "incoherent",
        }
    }

    /// The ray set called `name`, if any.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|r| r.name() == name)
    }
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
}
