//! STAGE 2 (scene loading): pbrt-v3's `heightfield` shape — a grid of `nu × nv` heights over the unit
//! square — turned into [`MeshData`] in object space with pbrt-v3's vertices, uvs and triangulation.
//!
//! Input: the Shape's parameters (`nu`, `nv`, `Pz`). Output: [`MeshData`] with positions, uvs and indices
//! (no normals, as pbrt-v3); the scene builder places it like any other mesh.
//!
//! Depends only on `error`, the parameter list of `parse` and [`MeshData`]; nothing here knows about
//! transforms, materials or the BVH. Sizes are checked against the heights actually given before anything is
//! allocated.
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

use super::mesh_data::MeshData;
use crate::error::{Error, Result, SourceLoc};
use crate::parse::ParamList;

/// The heightfield mesh of an `nu × nv` grid (`nu, nv ≥ 2`) with heights `z` (`nu·nv` of them, row by row,
/// u fastest), as pbrt-v3's `CreateHeightfield`: vertex `(x, y)` is at `(x/(nu-1), y/(nv-1), z)` with that
/// (u, v), and each cell is split along its (x, y)–(x+1, y+1) diagonal into
/// `(x,y) (x+1,y) (x+1,y+1)` and `(x,y) (x+1,y+1) (x,y+1)`.
///
/// Fails when a size is below 2, `z` has another length, or the grid has more vertices than `u32` indexes.
pub fn heightfield(nu: usize, nv: usize, z: &[f64]) -> std::result::Result<MeshData, String> {
    if nu < 2 || nv < 2 {
        return Err(format!("the grid must be at least 2×2, got {nu}×{nv}"));
    }
    let n = nu.checked_mul(nv).filter(|&n| n <= u32::MAX as usize);
    if n != Some(z.len()) {
        return Err(format!("{nu}×{nv} grid needs {} heights \"Pz\", got {}", nu as u128 * nv as u128, z.len()));
    }
    if let Some(i) = z.iter().position(|h| !h.is_finite()) {
        return Err(format!("height {i} is not finite ({})", z[i]));
    }
    let mut positions = Vec::with_capacity(z.len());
    let mut uvs = Vec::with_capacity(z.len());
    for y in 0..nv {
        for x in 0..nu {
            let u = x as f32 / (nu - 1) as f32;
            let v = y as f32 / (nv - 1) as f32;
            positions.push([u, v, z[y * nu + x] as f32]);
            uvs.push([u, v]);
        }
    }
    let mut indices = Vec::with_capacity(6 * (nu - 1) * (nv - 1));
    let vert = |x: usize, y: usize| (x + y * nu) as u32;
    for y in 0..nv - 1 {
        for x in 0..nu - 1 {
            indices.extend([vert(x, y), vert(x + 1, y), vert(x + 1, y + 1)]);
            indices.extend([vert(x, y), vert(x + 1, y + 1), vert(x, y + 1)]);
        }
    }
    Ok(MeshData { positions, normals: Vec::new(), uvs, indices })
}

/// Reads the parameters of `Shape "heightfield"` (`"integer nu"`, `"integer nv"`, `"float Pz"`) and builds
/// its mesh. Missing parameters, sizes below 2 and a wrong number of heights are errors (pbrt-v3 aborts).
pub fn heightfield_params(params: &ParamList, loc: &SourceLoc) -> Result<MeshData> {
    let at = |name: &str| params.loc_of(name).unwrap_or(loc).clone();
    let size = |name: &str| -> Result<usize> {
        match params.int(name)? {
            None => Err(Error::at(loc, format!("heightfield: missing required parameter \"integer {name}\""))),
            Some(n) if n < 2 => {
                Err(Error::at(&at(name), format!("heightfield: \"{name}\" must be at least 2, got {n}")))
            }
            Some(n) => usize::try_from(n)
                .map_err(|_| Error::at(&at(name), format!("heightfield: \"{name}\" is too large ({n})"))),
        }
    };
    let nu = size("nu")?;
    let nv = size("nv")?;
    let Some(z) = params.floats("Pz")? else {
        return Err(Error::at(loc, "heightfield: missing required parameter \"float Pz\""));
    };
    heightfield(nu, nv, z).map_err(|e| Error::at(&at("Pz"), format!("heightfield: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_by_two_is_the_unit_square_in_two_triangles() {
        let m = heightfield(2, 2, &[0.0, 1.0, 2.0, 3.0]).unwrap();
        assert_eq!(m.positions, [[0.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 1.0, 2.0], [1.0, 1.0, 3.0]]);
        assert_eq!(m.uvs, [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]);
        assert_eq!(m.indices, [0, 1, 3, 0, 3, 2]);
        assert!(m.normals.is_empty());
        assert_eq!(m.validate(), Ok(()));
    }

    #[test]
    fn three_by_two_rows_run_along_u() {
        let z = [0.5, 0.25, -1.0, 2.0, 0.0, 4.0];
        let m = heightfield(3, 2, &z).unwrap();
        let want: Vec<[f32; 3]> = vec![
            [0.0, 0.0, 0.5],
            [0.5, 0.0, 0.25],
            [1.0, 0.0, -1.0],
            [0.0, 1.0, 2.0],
            [0.5, 1.0, 0.0],
            [1.0, 1.0, 4.0],
        ];
        assert_eq!(m.positions, want);
        assert_eq!(m.indices, [0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4]);
        assert_eq!(m.uvs[4], [0.5, 1.0]);
    }

    #[test]
    fn bad_sizes_are_errors() {
        assert!(heightfield(1, 2, &[0.0, 0.0]).unwrap_err().contains("at least 2×2"));
        assert!(heightfield(2, 2, &[0.0; 3]).unwrap_err().contains("needs 4 heights"));
        assert!(heightfield(usize::MAX, 3, &[0.0; 3]).unwrap_err().contains("heights"));
        assert!(heightfield(1 << 20, 1 << 20, &[0.0; 4]).unwrap_err().contains("1099511627776 heights"));
        assert!(heightfield(2, 2, &[0.0, f64::NAN, 0.0, 0.0]).unwrap_err().contains("height 1 is not finite"));
    }
}
