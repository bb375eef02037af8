//! STAGE 2 (scene): triangle meshes placed in the scene — vertices transformed to world space (or to the
//! space of the object definition they belong to), pbrt-v3's `trianglemesh` parameters read and checked.

use crate::error::{Error, Result, SourceLoc, Warnings};
use crate::parse::ParamList;
use crate::scene::accel::MAX_COORD;
use crate::scene::shapes::mesh_data::{MeshData, triangle_indices};
use crate::scene::transform::Transform;
use crate::scene::transform::transform_normal;

/// A triangle mesh in world space (or object-definition space).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex shading normals (empty when the mesh has none).
    pub normals: Vec<[f32; 3]>,
    /// Per-vertex (u, v) (empty when the mesh has none).
    pub uvs: Vec<[f32; 2]>,
    /// Three vertex indices per triangle.
    pub indices: Vec<u32>,
    /// ReverseOrientation xor a handedness-swapping transform: flip the geometric normal.
    pub flip_normals: bool,
    /// Material id.
    pub material: u32,
    /// Area light id, when the mesh emits.
    pub area_light: Option<u32>,
}

impl TriangleMesh {
    /// Places `data` with `xf` (object → world). Fails when a transformed vertex leaves f32 range or lies
    /// beyond ±[`MAX_COORD`] (the BVH cannot handle it).
    pub fn place(data: MeshData, xf: &Transform, reverse_orientation: bool, material: u32) -> Result<Self, String> {
        let affine = xf.to_affine()?;
        let positions: Vec<[f32; 3]> = if xf.is_identity() {
            data.positions
        } else {
            data.positions.iter().map(|p| xf.point(p.map(|x| x as f64)).as_vec3().to_array()).collect()
        };
        if let Some(i) = positions.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
            return Err(format!("vertex {i} is not finite after the transform"));
        }
        if let Some(i) = positions.iter().position(|p| !p.iter().all(|x| x.abs() <= MAX_COORD)) {
            let max = MAX_COORD;
            return Err(format!("vertex {i} lies beyond ±{max:e} after the transform (too far out for the BVH)"));
        }
        let normals = if xf.is_identity() {
            data.normals
        } else {
            data.normals.iter().map(|n| transform_normal(&affine, glam::Vec3A::from(*n)).to_array()).collect()
        };
        Ok(TriangleMesh {
            positions,
            normals,
            uvs: data.uvs,
            indices: data.indices,
            flip_normals: reverse_orientation ^ xf.swaps_handedness(),
            material,
            area_light: None,
        })
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The vertices of triangle `t`.
    #[inline]
    pub fn triangle(&self, t: usize) -> [[f32; 3]; 3] {
        let i = &self.indices[3 * t..3 * t + 3];
        [self.positions[i[0] as usize], self.positions[i[1] as usize], self.positions[i[2] as usize]]
    }
}

/// Reads the parameters of `Shape "trianglemesh"` (pbrt-v3 `CreateTriangleMeshShape`) into mesh data,
/// checking counts and index ranges; inconsistent optional arrays are dropped with a warning, as pbrt-v3 does.
pub fn trianglemesh_params(params: &ParamList, loc: &SourceLoc, warnings: &mut Warnings) -> Result<MeshData> {
    let at = |name: &str| params.loc_of(name).unwrap_or(loc).clone();
    let Some(p) = params.point3s("P")? else {
        return Err(Error::at(loc, "trianglemesh: missing required parameter \"point3 P\""));
    };
    let nv = p.len();
    let indices: Vec<u32> = match params.ints("indices")? {
        Some(ix) => triangle_indices(ix, nv, &at("indices"), "")?,
        None if nv == 3 => vec![0, 1, 2],
        None => return Err(Error::at(loc, "trianglemesh: missing required parameter \"integer indices\"")),
    };
    if indices.is_empty() {
        // pbrt-v3 accepts this silently; say that nothing will be drawn.
        let at = at(if params.loc_of("indices").is_some() { "indices" } else { "P" });
        warnings.at(&at, format!("trianglemesh with {nv} vertices and no triangles: nothing is drawn"));
    }
    let mut uvs: Vec<[f32; 2]> = match params.point2s("uv")? {
        Some(v) => v,
        None => params.point2s("st")?.unwrap_or_default(),
    }
    .into_iter()
    .map(|c| [c[0] as f32, c[1] as f32])
    .collect();
    if !uvs.is_empty() && uvs.len() != nv {
        warnings.at(
            &at(if params.loc_of("uv").is_some() { "uv" } else { "st" }),
            format!("{} texture coordinates for {nv} vertices; ignoring them", uvs.len()),
        );
        uvs.clear();
    }
    let mut normals: Vec<[f32; 3]> =
        params.normals("N")?.unwrap_or_default().into_iter().map(|n| n.map(|x| x as f32)).collect();
    if !normals.is_empty() && normals.len() != nv {
        warnings.at(&at("N"), format!("{} normals for {nv} vertices; ignoring them", normals.len()));
        normals.clear();
    }
    if params.vector3s("S")?.is_some() {
        warnings.at(&at("S"), "per-vertex tangents \"S\" are ignored (pbrt-v3 uses them only for shading frames)");
    }
    let _ = params.ints("faceIndices")?;
    let mut data = MeshData { positions: p.into_iter().map(|v| v.map(|x| x as f32)).collect(), normals, uvs, indices };
    if let Err(e) = data.validate() {
        return Err(Error::at(&at("P"), format!("trianglemesh: {e}")));
    }
    if data.drop_unusable_normals() > 0 {
        warnings.at(&at("N"), "some normals are zero or not finite; ignoring all normals of this mesh");
    }
    Ok(data)
}
