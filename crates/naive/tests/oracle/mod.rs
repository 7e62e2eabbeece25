//! Naive's answers on ray sets, computed once and checked against many times: shared,
//! through `#[path]`, by the crates' tests that check one structure after another against
//! the oracle on the same rays (`crates/packet/tests/exact.rs`, every instruction set and
//! tree; `crates/peers/tests/naive.rs`, every peer). Naive is most of such a check's time.

use raybench_core::{Accel, Geometry, Hit, NoCounters, Ray, ray_sets};
use raybench_naive::NaiveAccel;
use std::sync::Arc;

/// One ray set of a geometry with naive's answers: closest hits, then the shadow probes
/// built from them (rays up to 90% of the closest hit, then the rays themselves) and their
/// any hits.
pub struct OracleSet {
    /// The set's name.
    pub name: &'static str,
    /// The rays.
    pub rays: Vec<Ray>,
    /// Naive's closest hit of each ray.
    pub closest: Vec<Option<Hit>>,
    /// [`ray_sets::shadow_probes`] of the rays and their closest hits.
    pub shadow: Vec<Ray>,
    /// Whether naive finds each shadow probe blocked.
    pub occluded: Vec<bool>,
}

/// A geometry and naive's answers on its ray sets.
pub struct Oracle {
    /// The geometry's name.
    pub name: &'static str,
    /// The geometry.
    pub geometry: Arc<Geometry>,
    /// Its ray sets with naive's answers.
    pub sets: Vec<OracleSet>,
}

/// Naive's answers on every ray set that `sets` makes of each of `geometries`.
pub fn oracles(
    geometries: Vec<(&'static str, Arc<Geometry>)>,
    sets: impl Fn(&Geometry) -> Vec<(&'static str, Vec<Ray>)>,
) -> Vec<Oracle> {
    geometries
        .into_iter()
        .map(|(name, geometry)| {
            let naive = NaiveAccel::build(Arc::clone(&geometry));
            let sets = sets(&geometry)
                .into_iter()
                .map(|(name, rays)| {
                    let closest: Vec<Option<Hit>> = rays
                        .iter()
                        .map(|r| naive.intersect(r, &mut NoCounters))
                        .collect();
                    let shadow = ray_sets::shadow_probes(&rays, &closest);
                    let occluded = shadow
                        .iter()
                        .map(|r| naive.occluded(r, &mut NoCounters))
                        .collect();
                    OracleSet {
                        name,
                        rays,
                        closest,
                        shadow,
                        occluded,
                    }
                })
                .collect();
            Oracle {
                name,
                geometry,
                sets,
            }
        })
        .collect()
}
