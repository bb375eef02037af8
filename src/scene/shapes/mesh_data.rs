//! STAGE 2 (scene loading): the triangle data that the mesh readers ([`super::ply`], [`super::obj`])
//! produce and that the shape code turns into triangles.
//!
//! Input: nothing (the readers fill it in). Output: [`MeshData`], still in the file's own object space;
//! the object-to-world transform is applied later by the scene builder.
//!
//! Depends only on `error` (for the located message of [`triangle_indices`], shared by the shapes that read
//! an `"integer indices"` array); nothing here knows about transforms, materials or the BVH.
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

use crate::error::{Error, Result, SourceLoc};

/// Checks an `"integer indices"` array (`ix`, written at `at`) of a triangle mesh over `nv` vertices: whole
/// triangles, every index in range. Messages start with `prefix` (e.g. `"loopsubdiv: "`).
pub fn triangle_indices(ix: &[f64], nv: usize, at: &SourceLoc, prefix: &str) -> Result<Vec<u32>> {
    if !ix.len().is_multiple_of(3) {
        return Err(Error::at(
            at,
            format!("{prefix}parameter \"indices\": {} values is not a multiple of 3", ix.len()),
        ));
    }
    ix.iter()
        .enumerate()
        .map(|(k, &v)| {
            if v >= 0.0 && v < nv as f64 {
                Ok(v as u32)
            } else {
                Err(Error::at(
                    at,
                    format!(
                        "{prefix}parameter \"indices\": value {v} at position {k} is out of range: there are {nv} vertices"
                    ),
                ))
            }
        })
        .collect()
}

/// Triangles as read from a file, in the file's own (object) space.
///
/// Vertex attributes are stored per vertex and shared by the triangles that index them. `normals` and `uvs`
/// are either empty (the file has none, or they were dropped) or have exactly one entry per position.
/// Readers return data that passes [`MeshData::validate`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex shading normals as stored in the file (not normalised): empty, or one per position.
    pub normals: Vec<[f32; 3]>,
    /// Per-vertex texture coordinates: empty, or one per position.
    pub uvs: Vec<[f32; 2]>,
    /// Vertex indices, 3 per triangle, each `< positions.len()`.
    pub indices: Vec<u32>,
}

impl MeshData {
    /// The number of triangles (`indices.len() / 3`).
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Checks the invariants: `normals` and `uvs` are empty or as long as `positions`, `indices` holds whole
    /// triangles, every index is in range, and every position is finite.
    ///
    /// Normals and uvs are not checked for finiteness; see [`MeshData::drop_unusable_normals`]. The error is
    /// a message naming the first offending vertex or index; callers wrap it with the file or scene location.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.positions.len();
        if !self.normals.is_empty() && self.normals.len() != n {
            return Err(format!("{} normals for {n} vertices (expected none or one per vertex)", self.normals.len()));
        }
        if !self.uvs.is_empty() && self.uvs.len() != n {
            return Err(format!("{} uvs for {n} vertices (expected none or one per vertex)", self.uvs.len()));
        }
        if !self.indices.len().is_multiple_of(3) {
            return Err(format!("{} vertex indices is not a multiple of 3", self.indices.len()));
        }
        if let Some((i, &v)) = self.indices.iter().enumerate().find(|&(_, &v)| v as usize >= n) {
            return Err(format!("triangle {} references vertex {v}, but there are {n} vertices", i / 3));
        }
        if let Some((i, p)) = self.positions.iter().enumerate().find(|(_, p)| !p.iter().all(|c| c.is_finite())) {
            return Err(format!("vertex {i} has a non-finite position ({}, {}, {})", p[0], p[1], p[2]));
        }
        Ok(())
    }

    /// Drops *all* normals when any of them is NaN, infinite or of zero length, and returns how many were
    /// unusable (0 means the normals were kept).
    ///
    /// One bad normal would give NaN shading at every point it is interpolated into; rather than patching
    /// single vertices, the whole mesh falls back to geometric normals, as if the file had none. Readers
    /// call this and record a warning when it returns more than 0.
    pub fn drop_unusable_normals(&mut self) -> usize {
        let bad = self.normals.iter().filter(|n| !normal_is_usable(n)).count();
        if bad > 0 {
            self.normals = Vec::new();
        }
        bad
    }
}

/// Whether `n` is finite and not of zero length.
fn normal_is_usable(n: &[f32; 3]) -> bool {
    n.iter().all(|c| c.is_finite()) && n.iter().any(|&c| c != 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle() -> MeshData {
        MeshData {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            normals: vec![[0.0, 0.0, 1.0]; 3],
            uvs: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            indices: vec![0, 1, 2],
        }
    }

    #[test]
    fn a_good_triangle_validates() {
        let m = triangle();
        assert_eq!(m.validate(), Ok(()));
        assert_eq!(m.triangle_count(), 1);
        assert_eq!(MeshData::default().validate(), Ok(()));
    }

    #[test]
    fn each_broken_invariant_is_named() {
        let mut m = triangle();
        m.normals.pop();
        assert!(m.validate().unwrap_err().contains("2 normals for 3 vertices"));
        let mut m = triangle();
        m.uvs.push([0.0, 0.0]);
        assert!(m.validate().unwrap_err().contains("4 uvs for 3 vertices"));
        let mut m = triangle();
        m.indices.push(0);
        assert!(m.validate().unwrap_err().contains("not a multiple of 3"));
        let mut m = triangle();
        m.indices.extend([0, 1, 7]);
        assert_eq!(m.validate().unwrap_err(), "triangle 1 references vertex 7, but there are 3 vertices");
        let mut m = triangle();
        m.positions[2][1] = f32::INFINITY;
        assert_eq!(m.validate().unwrap_err(), "vertex 2 has a non-finite position (0, inf, 0)");
    }

    #[test]
    fn unusable_normals_drop_the_whole_array() {
        let mut m = triangle();
        assert_eq!(m.drop_unusable_normals(), 0);
        assert_eq!(m.normals.len(), 3);
        m.normals[0] = [f32::NAN, 0.0, 1.0];
        m.normals[1] = [0.0, 0.0, 0.0];
        assert_eq!(m.drop_unusable_normals(), 2);
        assert!(m.normals.is_empty());
        assert_eq!(m.validate(), Ok(()));
    }
}
