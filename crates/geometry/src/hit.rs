//! The record of a ray/primitive hit.

use glam::Vec3;

/// The closest hit along a ray, as returned by an [`crate::Accel`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit point.
    pub t: f32,
    /// Global primitive id: objects in scene-file order, each mesh's triangles in file order
    /// after triangulation.
    pub prim: u32,
    /// Sub-primitive id for objects with inner parts (a height-field cell, a CSG leaf);
    /// 0 for simple primitives.
    pub sub: u32,
    /// First surface parameter (triangle: barycentric weight of vertex 1; sphere: longitude
    /// in [0, 1); plane: 0).
    pub u: f32,
    /// Second surface parameter (triangle: barycentric weight of vertex 2; sphere: latitude
    /// in [0, 1]; plane: 0).
    pub v: f32,
    /// Unit geometric normal, as the primitive defines it (not flipped towards the ray).
    pub normal: Vec3,
}

impl Hit {
    /// The workspace's tie rule: smaller `t` wins, equal `t` goes to the smaller primitive
    /// id. Every backend picks the closest hit with this comparison, through
    /// [`keep_closer`] (SIMD and GPU kernels port it lane by lane and test the port
    /// against it).
    #[inline]
    #[must_use]
    pub fn closer(t: f32, prim: u32, than_t: f32, than_prim: u32) -> bool {
        t < than_t || (t == than_t && prim < than_prim)
    }
}

/// A primitive's own answer to a ray: where, and the surface parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimHit {
    /// Ray parameter.
    pub t: f32,
    /// Sub-primitive id (0 for simple primitives).
    pub sub: u32,
    /// First surface parameter (see [`Hit::u`]).
    pub u: f32,
    /// Second surface parameter (see [`Hit::v`]).
    pub v: f32,
}

/// Offers the candidate `(id, hit)` to `best` under the tie rule ([`Hit::closer`]): it
/// replaces `best` when there is none yet or when it is closer. Returns whether it
/// replaced. The one place where candidate hits are compared: [`crate::Geometry::test_closest`]
/// for whole primitives, a height field for its cells' triangles (keyed by sub-primitive
/// id), and the SIMD and FFI backends for the hits their own kernels found.
#[inline]
pub fn keep_closer(best: &mut Option<(u32, PrimHit)>, id: u32, hit: PrimHit) -> bool {
    let better = match best {
        None => true,
        Some((bid, bh)) => Hit::closer(hit.t, id, bh.t, *bid),
    };
    if better {
        *best = Some((id, hit));
    }
    better
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(t: f32) -> PrimHit {
        PrimHit {
            t,
            sub: 0,
            u: 0.0,
            v: 0.0,
        }
    }

    #[test]
    fn keep_closer_applies_the_tie_rule() {
        let mut best = None;
        assert!(
            keep_closer(&mut best, 7, at(2.0)),
            "the first candidate wins"
        );
        assert!(!keep_closer(&mut best, 3, at(2.5)), "farther loses");
        assert!(
            !keep_closer(&mut best, 9, at(2.0)),
            "a tie with a larger id loses"
        );
        assert!(
            keep_closer(&mut best, 5, at(2.0)),
            "a tie with a smaller id wins"
        );
        assert_eq!(best.map(|(id, h)| (id, h.t)), Some((5, 2.0)));
        assert!(
            keep_closer(&mut best, 8, at(1.0)),
            "closer wins whatever its id"
        );
        assert!(!keep_closer(&mut best, 0, at(f32::NAN)), "NaN never wins");
        assert_eq!(best.map(|(id, _)| id), Some(8));
    }
}
