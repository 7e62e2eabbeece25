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

/// A mesh of convex polygons (three or more vertices each).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PolygonMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Vertex indices of each polygon, in winding order.
    pub faces: Vec<Vec<u32>>,
}

impl PolygonMesh {
    /// Splits every polygon into triangles, in face order: a polygon `v0 v1 ... vn` becomes
    /// the fan `(v0, v1, v2), (v0, v2, v3), ...`, so a quad is split along its `v0-v2`
    /// diagonal. Correct for convex polygons, which is what the format promises.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] for a face with fewer than three vertices.
    pub fn triangulate(&self) -> Result<TriangleMesh, SceneError> {
        let mut indices = Vec::with_capacity(self.faces.len() * 2);
        for (i, f) in self.faces.iter().enumerate() {
            if f.len() < 3 {
                return Err(SceneError::Invalid(format!(
                    "polygon {} has {} vertices (at least 3 needed)",
                    i + 1,
                    f.len()
                )));
            }
            for k in 1..f.len() - 1 {
                indices.push([f[0], f[k], f[k + 1]]);
            }
        }
        let mesh = TriangleMesh {
            positions: self.positions.clone(),
            indices,
        };
        mesh.validate()?;
        Ok(mesh)
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
        let m = poly.triangulate().unwrap();
        assert_eq!(
            m.indices,
            vec![[0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 2, 3], [0, 3, 4]]
        );
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
