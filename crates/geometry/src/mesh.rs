//! Indexed triangle meshes and polygon meshes.

use crate::error::SceneError;
use crate::triangle::Triangle;
use glam::Vec3;

/// An indexed triangle mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Three vertex indices per triangle.
    pub indices: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// Checks that every index is in range and every position finite.
    ///
    /// # Errors
    /// [`SceneError::IndexOutOfRange`] or [`SceneError::NonFinite`].
    pub fn validate(&self) -> Result<(), SceneError> {
        if let Some(p) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(SceneError::NonFinite(format!("vertex {}", p + 1)));
        }
        if let Some(p) = self
            .positions
            .iter()
            .position(|p| p.abs().max_element() > crate::limits::MAX_COORDINATE)
        {
            return Err(SceneError::TooLarge(format!(
                "vertex {} exceeds the coordinate limit of {:e}",
                p + 1,
                crate::limits::MAX_COORDINATE
            )));
        }
        let len = self.positions.len();
        for tri in &self.indices {
            for &i in tri {
                if i as usize >= len {
                    return Err(SceneError::IndexOutOfRange {
                        index: i as usize,
                        len,
                    });
                }
            }
        }
        Ok(())
    }

    /// The triangles in index order. Call [`TriangleMesh::validate`] first.
    pub fn triangles(&self) -> impl Iterator<Item = Triangle> + '_ {
        self.indices.iter().map(|&[a, b, c]| {
            Triangle::new(
                self.positions[a as usize],
                self.positions[b as usize],
                self.positions[c as usize],
            )
        })
    }

    /// Applies `f` to every position.
    pub fn transform(&mut self, f: impl Fn(Vec3) -> Vec3) {
        for p in &mut self.positions {
            *p = f(*p);
        }
    }
}

/// A mesh of polygons (three or more vertices each, in winding order).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PolygonMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Vertex indices of each polygon, in winding order.
    pub faces: Vec<Vec<u32>>,
}

/// A triangulated [`PolygonMesh`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Triangulated {
    /// The triangles, face by face.
    pub mesh: TriangleMesh,
    /// Indices (0-based) of the faces that were self-intersecting (fanned as given).
    pub self_intersecting: Vec<usize>,
}

/// How [`triangulate_polygon`] split a polygon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PolygonKind {
    /// Convex (or degenerate, or a triangle): fanned from its first vertex.
    Convex,
    /// Simple but not convex: ear-clipped.
    Concave,
    /// Self-intersecting (or winding around more than once), or concave with more than
    /// [`MAX_EAR_CLIP_VERTICES`] vertices: fanned from its first vertex, which matches
    /// no fill rule; the loaders warn.
    SelfIntersecting,
}

/// Largest non-convex polygon that is ear-clipped (clipping costs up to the cube of the
/// vertex count); larger ones are fanned and reported as [`PolygonKind::SelfIntersecting`].
pub const MAX_EAR_CLIP_VERTICES: usize = 256;

/// The polygon's points projected onto the plane of its Newell normal (counter-clockwise:
/// positive area), or of its first turning corner when the Newell normal is zero; `None`
/// for collinear points, a non-finite normal or an out-of-range index.
fn project(positions: &[Vec3], face: &[u32]) -> Option<Vec<[f64; 2]>> {
    let p: Vec<glam::DVec3> = face
        .iter()
        .map(|&i| positions.get(i as usize).map(|v| v.as_dvec3()))
        .collect::<Option<_>>()?;
    let mut n = glam::DVec3::ZERO;
    for (k, a) in p.iter().enumerate() {
        let b = p[(k + 1) % p.len()];
        n += glam::DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    if n == glam::DVec3::ZERO {
        // No net area: collinear points, or lobes that cancel (a symmetric bow tie). The
        // plane of the first corner that turns, if any.
        let k = p.len();
        n = (0..k)
            .map(|i| (p[(i + 1) % k] - p[i]).cross(p[(i + 2) % k] - p[(i + 1) % k]))
            .find(|c| *c != glam::DVec3::ZERO)?;
    }
    if !n.is_finite() {
        return None;
    }
    let a = n.abs();
    // Drop the dominant axis; swap the other two when its component is negative, so that
    // the polygon is counter-clockwise seen from the normal.
    let (i, j, flip) = if a.z >= a.x && a.z >= a.y {
        (0, 1, n.z < 0.0)
    } else if a.x >= a.y {
        (1, 2, n.x < 0.0)
    } else {
        (2, 0, n.y < 0.0)
    };
    Some(
        p.iter()
            .map(|v| if flip { [v[j], v[i]] } else { [v[i], v[j]] })
            .collect(),
    )
}

fn cross(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

/// Convex: no right turn (beyond rounding: a sine of `-1e-6`, so that nearly straight
/// edges of real meshes keep their fan), and the turns add up to one full turn (a
/// pentagram turns left everywhere but twice around).
fn is_convex(q: &[[f64; 2]]) -> bool {
    let n = q.len();
    let mut turning = 0.0f64;
    for k in 0..n {
        let (a, b, c) = (q[k], q[(k + 1) % n], q[(k + 2) % n]);
        let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
        let sin = u[0] * v[1] - u[1] * v[0];
        if sin < -1e-6 * u[0].hypot(u[1]) * v[0].hypot(v[1]) {
            return false;
        }
        turning += sin.atan2(u[0] * v[0] + u[1] * v[1]);
    }
    turning < 3.0 * std::f64::consts::PI
}

/// Whether segments `ab` and `cd` cross or touch.
fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (d1, d2) = (cross(a, b, c), cross(a, b, d));
    let (d3, d4) = (cross(c, d, a), cross(c, d, b));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let on = |p: [f64; 2], q: [f64; 2], r: [f64; 2], d: f64| {
        d == 0.0
            && r[0] >= p[0].min(q[0])
            && r[0] <= p[0].max(q[0])
            && r[1] >= p[1].min(q[1])
            && r[1] <= p[1].max(q[1])
    };
    on(a, b, c, d1) || on(a, b, d, d2) || on(c, d, a, d3) || on(c, d, b, d4)
}

/// Simple: no two non-adjacent edges meet.
fn is_simple(q: &[[f64; 2]]) -> bool {
    let n = q.len();
    (0..n).all(|i| {
        (i + 2..n)
            .filter(|&j| (j + 1) % n != i)
            .all(|j| !segments_meet(q[i], q[(i + 1) % n], q[j], q[(j + 1) % n]))
    })
}

/// Ear clipping of a simple counter-clockwise polygon: appends `n - 2` triangles of
/// `face`'s indices. A polygon so thin that rounding leaves no ear has its remainder fanned.
fn ear_clip(q: &[[f64; 2]], face: &[u32], out: &mut Vec<[u32; 3]>) {
    let mut left: Vec<usize> = (0..q.len()).collect();
    while left.len() > 3 {
        let n = left.len();
        let ear = (0..n).find(|&k| {
            let (a, b, c) = (left[(k + n - 1) % n], left[k], left[(k + 1) % n]);
            if cross(q[a], q[b], q[c]) <= 0.0 {
                return false;
            }
            // No other vertex inside or on the triangle.
            left.iter().all(|&p| {
                p == a
                    || p == b
                    || p == c
                    || cross(q[a], q[b], q[p]) < 0.0
                    || cross(q[b], q[c], q[p]) < 0.0
                    || cross(q[c], q[a], q[p]) < 0.0
            })
        });
        let Some(k) = ear else { break };
        let (a, b, c) = (left[(k + n - 1) % n], left[k], left[(k + 1) % n]);
        out.push([face[a], face[b], face[c]]);
        left.remove(k);
    }
    for k in 1..left.len() - 1 {
        out.push([face[left[0]], face[left[k]], face[left[k + 1]]]);
    }
}

/// Appends the triangles of one polygon (`face`: at least three indices into `positions`)
/// to `out`: `face.len() - 2` of them. Convex polygons are fanned from their first vertex,
/// `(v0, v1, v2), (v0, v2, v3), ...` (so a quad splits along its `v0-v2` diagonal, as
/// before ear clipping existed, and ids stay those of the fan); simple non-convex
/// polygons, projected onto the plane of their Newell normal, are ear-clipped; the rest
/// ([`PolygonKind::SelfIntersecting`]) are fanned as given.
pub fn triangulate_polygon(
    positions: &[Vec3],
    face: &[u32],
    out: &mut Vec<[u32; 3]>,
) -> PolygonKind {
    let fan = |out: &mut Vec<[u32; 3]>| {
        for k in 1..face.len().saturating_sub(1) {
            out.push([face[0], face[k], face[k + 1]]);
        }
    };
    let kind = match project(positions, face) {
        _ if face.len() <= 3 => PolygonKind::Convex,
        None => PolygonKind::Convex,
        Some(q) if is_convex(&q) => PolygonKind::Convex,
        Some(q) if q.len() <= MAX_EAR_CLIP_VERTICES && is_simple(&q) => {
            ear_clip(&q, face, out);
            return PolygonKind::Concave;
        }
        Some(_) => PolygonKind::SelfIntersecting,
    };
    fan(out);
    kind
}

impl PolygonMesh {
    /// Splits every polygon into triangles, in face order, by [`triangulate_polygon`]:
    /// convex polygons as fans, simple non-convex ones by ear clipping, self-intersecting
    /// ones as fans (listed in [`Triangulated::self_intersecting`]).
    ///
    /// # Errors
    /// [`SceneError::Invalid`] for a face with fewer than three vertices,
    /// [`SceneError::IndexOutOfRange`] or [`SceneError::NonFinite`] from
    /// [`TriangleMesh::validate`].
    pub fn triangulate(&self) -> Result<Triangulated, SceneError> {
        let mut indices = Vec::with_capacity(self.faces.len() * 2);
        let mut self_intersecting = Vec::new();
        for (i, f) in self.faces.iter().enumerate() {
            if f.len() < 3 {
                return Err(SceneError::Invalid(format!(
                    "polygon {} has {} vertices (at least 3 needed)",
                    i + 1,
                    f.len()
                )));
            }
            if triangulate_polygon(&self.positions, f, &mut indices)
                == PolygonKind::SelfIntersecting
            {
                self_intersecting.push(i);
            }
        }
        let mesh = TriangleMesh {
            positions: self.positions.clone(),
            indices,
        };
        mesh.validate()?;
        Ok(Triangulated {
            mesh,
            self_intersecting,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quad_and_pentagon_are_fanned() {
        let poly = PolygonMesh {
            positions: vec![Vec3::ZERO; 5],
            faces: vec![vec![0, 1, 2, 3], vec![0, 1, 2, 3, 4]],
        };
        let m = poly.triangulate().unwrap().mesh;
        assert_eq!(
            m.indices,
            vec![[0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 2, 3], [0, 3, 4]]
        );
    }

    /// Twice the area of the triangles, each counted with its orientation about `+z`.
    fn signed_area(p: &[Vec3], tris: &[[u32; 3]]) -> f32 {
        tris.iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| p[i as usize]);
                (b - a).cross(c - a).z
            })
            .sum()
    }

    /// An L-shaped hexagon is fanned into the wrong shape (a triangle outside the
    /// L, one flipped); ear clipping covers the L exactly.
    #[test]
    fn non_convex_polygons_are_ear_clipped() {
        // The L: (0,0) (2,0) (2,1) (1,1) (1,2) (0,2), area 3, listed from (1,2), which does
        // not see the corner (2,1).
        let l = [(1, 2), (0, 2), (0, 0), (2, 0), (2, 1), (1, 1)];
        let positions: Vec<Vec3> = l
            .iter()
            .map(|&(x, y)| Vec3::new(x as f32, y as f32, 0.0))
            .collect();
        let face: Vec<u32> = (0..6).collect();
        let mut fan = Vec::new();
        for k in 1..5 {
            fan.push([0, k, k + 1]);
        }
        // The fan's triangles overlap and leave part of the L uncovered: its unsigned area
        // is not 3.
        let unsigned: f32 = fan
            .iter()
            .map(|t| signed_area(&positions, &[*t]).abs())
            .sum();
        assert_ne!(unsigned, 6.0);
        let mut tris = Vec::new();
        assert_eq!(
            triangulate_polygon(&positions, &face, &mut tris),
            PolygonKind::Concave
        );
        assert_eq!(tris.len(), 4);
        // Every triangle turns the polygon's way, and together they cover area 3 exactly.
        for t in &tris {
            assert!(signed_area(&positions, &[*t]) > 0.0, "{t:?} is flipped");
        }
        assert_eq!(signed_area(&positions, &tris), 6.0);
        // The same L in a tilted plane, clockwise seen from +z: still 4 triangles, the
        // same winding as the polygon.
        let tilted: Vec<Vec3> = positions
            .iter()
            .map(|p| Vec3::new(p.y, p.x, p.x + 0.5 * p.y))
            .collect();
        let mut tris = Vec::new();
        assert_eq!(
            triangulate_polygon(&tilted, &face, &mut tris),
            PolygonKind::Concave
        );
        assert_eq!(tris.len(), 4);
        let newell = (tilted[1] - tilted[0]).cross(tilted[2] - tilted[0]);
        for t in &tris {
            let [a, b, c] = t.map(|i| tilted[i as usize]);
            assert!((b - a).cross(c - a).dot(newell) > 0.0, "{t:?} is flipped");
        }
    }

    #[test]
    fn convex_and_self_intersecting_polygons_are_fanned() {
        // A convex pentagon with a collinear vertex: the fan, unchanged.
        let p = [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)];
        let positions: Vec<Vec3> = p.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect();
        let mut tris = Vec::new();
        let kind = triangulate_polygon(&positions, &[0, 1, 2, 3, 4], &mut tris);
        assert_eq!(kind, PolygonKind::Convex);
        assert_eq!(tris, [[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
        // A bow tie and a pentagram (left turns only, but twice around).
        let bow = [(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)];
        let star: Vec<(f32, f32)> = (0..5)
            .map(|k| {
                let a = (k * 2) as f32 * std::f32::consts::TAU / 5.0;
                (a.cos(), a.sin())
            })
            .collect();
        for shape in [&bow[..], &star[..]] {
            let positions: Vec<Vec3> = shape.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect();
            let face: Vec<u32> = (0..shape.len() as u32).collect();
            let mut tris = Vec::new();
            let kind = triangulate_polygon(&positions, &face, &mut tris);
            assert_eq!(kind, PolygonKind::SelfIntersecting, "{shape:?}");
            assert_eq!(tris.len(), shape.len() - 2);
            assert_eq!(tris[0], [0, 1, 2]);
        }
        let poly = PolygonMesh {
            positions: bow.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect(),
            faces: vec![vec![0, 1, 2], vec![0, 1, 2, 3]],
        };
        assert_eq!(poly.triangulate().unwrap().self_intersecting, [1]);
    }

    #[test]
    fn bad_faces_are_errors() {
        let poly = PolygonMesh {
            positions: vec![Vec3::ZERO; 3],
            faces: vec![vec![0, 1]],
        };
        assert!(poly.triangulate().is_err());
        let poly = PolygonMesh {
            positions: vec![Vec3::ZERO; 3],
            faces: vec![vec![0, 1, 3]],
        };
        assert!(matches!(
            poly.triangulate(),
            Err(SceneError::IndexOutOfRange { index: 3, len: 3 })
        ));
        let m = TriangleMesh {
            positions: vec![Vec3::NAN],
            indices: vec![],
        };
        assert!(matches!(m.validate(), Err(SceneError::NonFinite(_))));
    }
}
