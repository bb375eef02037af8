//! Test support for the mesh readers (stage 2): scratch files in the temp dir, read back through a reader,
//! with the warnings it gave, and the shared third-party scenes. Compiled only for unit tests.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use super::mesh_data::MeshData;
use crate::error::{Error, Result, Warnings};

/// A mesh reader: `read_ply` or `read_obj`.
pub(crate) type Reader = fn(&Path, &mut Warnings) -> Result<MeshData>;

/// A file in the temp dir that is deleted when dropped.
struct TempFile(PathBuf);

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// Writes `bytes` to a fresh `.ext` file and reads it with `reader`.
pub(crate) fn read(reader: Reader, ext: &str, bytes: &[u8]) -> (Result<MeshData>, Warnings) {
    static N: AtomicUsize = AtomicUsize::new(0);
    let name = format!("cachert-{ext}-test-{}-{}.{ext}", std::process::id(), N.fetch_add(1, Ordering::Relaxed));
    let file = TempFile(std::env::temp_dir().join(name));
    std::fs::write(&file.0, bytes).unwrap();
    let mut warnings = Warnings::default();
    (reader(&file.0, &mut warnings), warnings)
}

/// The mesh, asserting that reading it gave no warning.
pub(crate) fn ok(reader: Reader, ext: &str, bytes: &[u8]) -> MeshData {
    let (mesh, warnings) = read(reader, ext, bytes);
    assert!(warnings.is_empty(), "{warnings:?}");
    mesh.unwrap()
}

/// The file error's message, without the path.
pub(crate) fn err(reader: Reader, ext: &str, bytes: &[u8]) -> String {
    match read(reader, ext, bytes).0 {
        Err(Error::File { msg, .. }) => msg,
        other => panic!("expected a file error, got {other:?}"),
    }
}

/// `../shared/scenes/<dir>` beside the repository, or `None` when it is absent (a failure under CI; see
/// `test_support`).
pub(crate) fn scene_dir(dir: &str) -> Option<PathBuf> {
    crate::test_support::shared_scenes(dir)
}
