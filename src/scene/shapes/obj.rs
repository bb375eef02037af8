//! STAGE 2 (scene loading): reads Wavefront OBJ files (our `Shape "objmesh"` extension) into [`MeshData`].
//!
//! Input: a path. Output: all the file's objects and groups merged into one triangle mesh in object space.
//! Parsing is done by the `tobj` crate, with polygons triangulated as fans and one index per vertex;
//! points and lines are ignored. Materials are not read at all: `mtllib`/`usemtl` lines do not change the
//! geometry, so a missing or broken `.mtl` file is not an error.
//!
//! Depends only on `error` (and its sibling [`super::mesh_data`]).
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use super::mesh_data::MeshData;
use crate::error::{Error, Result, Warnings};

/// Reads the OBJ file at `path` into one [`MeshData`], merging all of its objects (models) in file order.
///
/// Positions are always kept. Normals and uvs are kept only if *every* object has one per vertex;
/// otherwise they are dropped for the whole mesh without a warning (a file that gives normals to some objects
/// only is common and harmless: shading falls back to geometric normals). Texture coordinates are kept as
/// written (no v flip). As in [`super::ply::read_ply`], NaN, infinite or zero normals drop all normals with a
/// warning, and a file without triangles gives a warning.
///
/// Errors: an unreadable file, tobj's parse errors (tobj's own message, which has no line number), too many
/// vertices for 32-bit indices, a non-finite position, and a crash inside tobj (caught, not propagated).
pub fn read_obj(path: &Path, warnings: &mut Warnings) -> Result<MeshData> {
    let bytes = std::fs::read(path).map_err(|e| Error::file(path, format!("cannot read OBJ file: {e}")))?;
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ignore_points: true, ignore_lines: true };
    // Materials are never loaded: this also keeps tobj's MTL parser (which can panic on a short `Kd` line)
    // away from user input.
    let no_materials = |_: &Path| Ok((Vec::new(), Default::default()));
    // tobj has index arithmetic that overflows (a panic in debug builds) on absurd relative indices; a
    // malformed file must give an error, not a crash.
    let loaded = catch_unwind(AssertUnwindSafe(|| tobj::load_obj_buf(&mut bytes.as_slice(), &options, no_materials)))
        .map_err(|_| Error::file(path, "invalid OBJ file (the OBJ parser crashed on it)"))?;
    let (models, _materials) = loaded.map_err(|e| Error::file(path, format!("invalid OBJ file: {e}")))?;

    let mut mesh = merge(&models).map_err(|msg| Error::file(path, msg))?;
    let bad = mesh.drop_unusable_normals();
    if bad > 0 {
        warnings.general(format!(
            "{}: objmesh: {bad} of {} vertex normals are NaN, infinite or zero; ignoring all normals of this mesh",
            path.display(),
            mesh.positions.len()
        ));
    }
    if mesh.triangle_count() == 0 {
        warnings.general(format!("{}: objmesh: the file has no triangles, so the shape is empty", path.display()));
    }
    mesh.validate().map_err(|msg| Error::file(path, msg))?;
    Ok(mesh)
}

/// Concatenates tobj's models, offsetting each model's indices by the vertices before it.
fn merge(models: &[tobj::Model]) -> Result<MeshData, String> {
    let vertices = |m: &tobj::Mesh| m.positions.len() / 3;
    let normals = models.iter().all(|m| m.mesh.normals.len() == 3 * vertices(&m.mesh));
    let uvs = models.iter().all(|m| m.mesh.texcoords.len() == 2 * vertices(&m.mesh));
    let total: usize = models.iter().map(|m| vertices(&m.mesh)).sum();
    if total > u32::MAX as usize {
        return Err(format!("{total} vertices; at most {} are supported", u32::MAX));
    }
    let mut mesh = MeshData {
        positions: Vec::with_capacity(total),
        normals: Vec::with_capacity(if normals { total } else { 0 }),
        uvs: Vec::with_capacity(if uvs { total } else { 0 }),
        indices: Vec::with_capacity(models.iter().map(|m| m.mesh.indices.len()).sum()),
    };
    for model in models {
        let m = &model.mesh;
        // Cannot truncate: total vertices were checked against u32::MAX above.
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(m.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
        if normals {
            mesh.normals.extend(m.normals.chunks_exact(3).map(|n| [n[0], n[1], n[2]]));
        }
        if uvs {
            mesh.uvs.extend(m.texcoords.chunks_exact(2).map(|t| [t[0], t[1]]));
        }
        mesh.indices.extend(m.indices.iter().map(|&i| base.saturating_add(i)));
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    use crate::scene::shapes::test_files::{self as tf, scene_dir};

    fn read(text: &str) -> (Result<MeshData>, Warnings) {
        tf::read(read_obj, "obj", text.as_bytes())
    }

    fn ok(text: &str) -> MeshData {
        tf::ok(read_obj, "obj", text.as_bytes())
    }

    fn err(text: &str) -> String {
        tf::err(read_obj, "obj", text.as_bytes())
    }

    const TWO_OBJECTS: &str = "mtllib does-not-exist.mtl\n\
        v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 2 0\n\
        vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 1\n\
        vn 0 0 1\n\
        o quad\nusemtl missing\nf 1/1/1 2/2/1 3/3/1 4/4/1\n\
        o pentagon\nf 1/1 2/2 3/3 5/5 4/4\n";

    #[test]
    fn objects_are_merged_and_polygons_triangulated() {
        let mesh = ok(TWO_OBJECTS);
        // The quad has 4 vertices of its own, the pentagon 5; the second object's indices are offset by 4.
        assert_eq!(mesh.positions.len(), 9);
        assert_eq!(mesh.triangle_count(), 2 + 3);
        assert_eq!(&mesh.indices[..6], &[0, 1, 2, 0, 2, 3]);
        assert_eq!(&mesh.indices[6..], &[4, 5, 6, 4, 6, 7, 4, 7, 8]);
        assert_eq!(mesh.positions[7], [0.5, 2.0, 0.0]);
        assert_eq!(mesh.uvs.len(), 9);
        assert_eq!(mesh.uvs[7], [0.5, 1.0]);
        // Only the quad has normals, so none are kept, silently.
        assert!(mesh.normals.is_empty());
        assert_eq!(mesh.validate(), Ok(()));
    }

    #[test]
    fn normals_and_uvs_are_kept_when_every_vertex_has_them() {
        let mesh = ok("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\nf 1/1/1 2/1/1 3/1/1\n");
        assert_eq!(mesh.normals, vec![[0.0, 0.0, 1.0]; 3]);
        assert_eq!(mesh.uvs, vec![[0.0, 0.0]; 3]);
        // One vertex without a uv drops the uvs.
        let mesh = ok("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3\n");
        assert!(mesh.uvs.is_empty());
        assert_eq!(mesh.positions.len(), 3);
    }

    #[test]
    fn bad_normals_are_dropped_with_a_warning() {
        let (mesh, warnings) = read("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nf 1//1 2//1 3//1\n");
        assert!(mesh.unwrap().normals.is_empty());
        assert_eq!(warnings.len(), 1);
    }

    #[test]
    fn broken_files_are_errors() {
        assert_eq!(err("v 0 0 0\nv 1 x 0\n"), "invalid OBJ file: position parse error");
        assert_eq!(err("v 0 0 0\nv 1 0 0\nf 1 2 3\n"), "invalid OBJ file: face vertex index out of bounds");
        assert_eq!(err("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n"), "vertex 2 has a non-finite position (NaN, 1, 0)");
        // tobj's index arithmetic overflows here (a panic in debug builds, an error in release ones).
        assert!(err("v 0 0 0\nvt 0 0\nvn 0 0 1\nf 1/-100/-100 1/1/1 1/1/1\n").starts_with("invalid OBJ file"));
        let missing = std::env::temp_dir().join("cachert-obj-test-does-not-exist.obj");
        let e = read_obj(&missing, &mut Warnings::default()).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}: cannot read OBJ file: ", missing.display())), "{e}");
    }

    #[test]
    fn points_lines_and_nothing_give_an_empty_mesh_with_a_warning() {
        let (mesh, warnings) = read("v 0 0 0\nv 1 0 0\np 1\nl 1 2\n");
        assert_eq!(mesh.unwrap().triangle_count(), 0);
        assert_eq!(warnings.len(), 1);
    }

    #[test]
    fn sibenik_obj_has_the_triangles_of_sibenik_ply() {
        let Some(dir) = scene_dir("mcguire-sibenik-geometry") else {
            return;
        };
        let mut warnings = Warnings::default();
        let obj = read_obj(&dir.join("sibenik-converted.obj"), &mut warnings).unwrap();
        let ply = super::super::ply::read_ply(&dir.join("sibenik-ply.ply"), &mut warnings).unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(obj.triangle_count(), 75_284);
        assert_eq!(obj.triangle_count(), ply.triangle_count());
        assert!(obj.normals.is_empty() && obj.uvs.is_empty());
    }

    #[test]
    fn reads_the_cornell_boxes() {
        let Some(dir) = scene_dir("mcguire-cornellbox-obj") else {
            return;
        };
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "obj"))
            .collect();
        files.sort();
        assert_eq!(files.len(), 10);
        for f in &files {
            let mut warnings = Warnings::default();
            let mesh = read_obj(f, &mut warnings).unwrap();
            assert!(warnings.is_empty(), "{warnings:?}");
            assert!(mesh.triangle_count() >= 10, "{}: {} triangles", f.display(), mesh.triangle_count());
            eprintln!(
                "{}: {} triangles, {} vertices, normals {}, uvs {}",
                f.display(),
                mesh.triangle_count(),
                mesh.positions.len(),
                mesh.normals.len(),
                mesh.uvs.len()
            );
        }
    }
}
