//! Shading attributes of meshes: vertex normals and texture coordinates, interpolated across
//! each triangle at a hit.
//!
//! Storage costs nothing for meshes without attributes: the scene keeps one
//! [`AttributeRange`] per object that has some (its first primitive id, its triangles'
//! vertex indices, its per-vertex normals and texture coordinates), sorted by primitive id,
//! and a hit finds its range by binary search on its primitive id. A scene of plain meshes
//! has no range and every lookup is one emptiness test. The attributes change shading only:
//! ids and `t` of every backend stay those of the geometry.

use glam::{Vec2, Vec3};

/// Per-vertex shading attributes of one mesh, indexed like its positions: what a loader
/// hands [`crate::SceneBuilder::add_mesh_with_attributes`]. Either list may be empty
/// (the mesh has none of that attribute).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VertexAttributes {
    /// Vertex normals (any length; normalised when added). A zero or non-finite normal
    /// makes its triangles fall back to the geometric normal.
    pub normals: Vec<Vec3>,
    /// Texture coordinates (glTF's convention: `v` counts down from the image's top row).
    pub uvs: Vec<Vec2>,
}

/// The attributes of one object's triangles, primitive ids `first..first + indices.len()`.
#[derive(Clone, Debug, PartialEq)]
pub struct AttributeRange {
    first: u32,
    indices: Vec<[u32; 3]>,
    /// Unit normals, or zero where the file's normal was unusable; empty when none.
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
}

/// What the attributes say at one point of a triangle.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AttributesAt {
    /// The interpolated unit shading normal, as the file orients it (not yet flipped to the
    /// geometric normal's side); `None` without usable vertex normals.
    pub normal: Option<Vec3>,
    /// The interpolated texture coordinates; `None` without them.
    pub uv: Option<Vec2>,
}

/// The shading attributes of a scene's meshes, by primitive id.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShadingAttributes {
    ranges: Vec<AttributeRange>,
}

impl ShadingAttributes {
    /// Whether no object has attributes.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// Whether some object has vertex normals.
    #[must_use]
    pub fn has_normals(&self) -> bool {
        self.ranges.iter().any(|r| !r.normals.is_empty())
    }

    /// Bytes the attributes take.
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.ranges
            .iter()
            .map(|r| r.indices.len() * 12 + r.normals.len() * 12 + r.uvs.len() * 8)
            .sum()
    }

    /// Adds the attributes of the object whose triangles are `indices`, from primitive id
    /// `first` on (after every range added so far). `normals` are unit or zero; either
    /// list may be empty; both empty, or no triangle, adds nothing.
    pub(crate) fn push(
        &mut self,
        first: u32,
        indices: Vec<[u32; 3]>,
        normals: Vec<Vec3>,
        uvs: Vec<Vec2>,
    ) {
        if indices.is_empty() || (normals.is_empty() && uvs.is_empty()) {
            return;
        }
        debug_assert!(self.ranges.last().is_none_or(|r| r.first < first));
        self.ranges.push(AttributeRange {
            first,
            indices,
            normals,
            uvs,
        });
    }

    /// Adds the attributes of an instanced mesh's primitives, placed at ids `base + i`
    /// (after every range added so far), each vertex normal carried by `carry` (an
    /// instance's [`crate::Instance::world_normal`]; a zero normal stays unusable): how
    /// [`crate::flatten`] keeps an instance's smooth shading.
    pub(crate) fn push_placed(
        &mut self,
        mesh: &ShadingAttributes,
        base: u32,
        carry: impl Fn(Vec3) -> Vec3,
    ) {
        for r in &mesh.ranges {
            let normals = r
                .normals
                .iter()
                .map(|&n| if n == Vec3::ZERO { n } else { carry(n) })
                .collect();
            self.push(base + r.first, r.indices.clone(), normals, r.uvs.clone());
        }
    }

    /// The attributes of primitive `prim` at barycentric weights `u` (vertex 1) and `v`
    /// (vertex 2), as a triangle [`crate::Hit`] gives them.
    #[inline]
    #[must_use]
    pub fn at(&self, prim: u32, u: f32, v: f32) -> AttributesAt {
        // Scenes without attributes (most benchmark scenes) pay one test per hit: the
        // lookup itself stays out of line.
        if self.ranges.is_empty() {
            return AttributesAt::default();
        }
        self.lookup(prim, u, v)
    }

    /// [`Self::at`] for scenes that have attributes.
    #[inline(never)]
    fn lookup(&self, prim: u32, u: f32, v: f32) -> AttributesAt {
        let i = self.ranges.partition_point(|r| r.first <= prim);
        let Some(r) = i.checked_sub(1).map(|i| &self.ranges[i]) else {
            return AttributesAt::default();
        };
        let Some(&[a, b, c]) = r.indices.get((prim - r.first) as usize) else {
            return AttributesAt::default();
        };
        let (a, b, c) = (a as usize, b as usize, c as usize);
        let w = 1.0 - u - v;
        let normal = if r.normals.is_empty() {
            None
        } else {
            let (na, nb, nc) = (r.normals[a], r.normals[b], r.normals[c]);
            if na == Vec3::ZERO || nb == Vec3::ZERO || nc == Vec3::ZERO {
                None
            } else {
                // Opposite normals may cancel: then the geometric normal.
                (na * w + nb * u + nc * v).try_normalize()
            }
        };
        let uv = (!r.uvs.is_empty()).then(|| r.uvs[a] * w + r.uvs[b] * u + r.uvs[c] * v);
        AttributesAt { normal, uv }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookups_find_their_range_and_interpolate() {
        let mut s = ShadingAttributes::default();
        assert_eq!(s.at(0, 0.2, 0.3), AttributesAt::default());
        // Primitives 3 and 4 have normals; 7 has texture coordinates only.
        let n = vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ZERO];
        s.push(3, vec![[0, 1, 2], [0, 1, 3]], n, vec![]);
        let uv = vec![Vec2::ZERO, Vec2::X, Vec2::Y];
        s.push(7, vec![[0, 1, 2]], vec![], uv);
        s.push(9, vec![[0, 1, 2]], vec![], vec![]);
        assert!(s.has_normals());
        for prim in [0, 2, 5, 6, 8, 9, 100] {
            assert_eq!(s.at(prim, 0.2, 0.3), AttributesAt::default(), "{prim}");
        }
        let a = s.at(3, 0.25, 0.5);
        let expect = Vec3::new(0.25, 0.25, 0.5).normalize();
        assert!((a.normal.unwrap() - expect).length() < 1e-6);
        assert_eq!(a.uv, None);
        // A zero vertex normal: the geometric normal is used.
        assert_eq!(s.at(4, 0.25, 0.5).normal, None);
        let a = s.at(7, 0.25, 0.5);
        assert_eq!((a.normal, a.uv), (None, Some(Vec2::new(0.25, 0.5))));
    }
}
