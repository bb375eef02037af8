//! All-or-nothing file writes: the content goes to a hidden temporary file in the target's directory,
//! which is renamed over the target only after everything was written and flushed. A failure at any point
//! removes the temporary file, so readers never see a partial image. [`check_output`] checks an output
//! path before the work that fills it starts.
//!
//! Depends only on [`crate::error`]; it knows nothing of scenes or rendering.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};

/// Distinguishes temporary files of concurrent writes from the same process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Writes `path` through `fill`, atomically. `fill` gets a buffered, seekable writer and returns a
/// message on failure; every error (opening, `fill`, flushing, renaming) becomes an [`Error::file`] for
/// `path` and leaves neither `path` (if it did not exist) nor the temporary file behind.
pub(crate) fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> std::result::Result<(), String>,
) -> Result<()> {
    let tmp = temporary_name(path);
    let file = File::create(&tmp).map_err(|e| Error::file(path, format!("cannot create: {e}")))?;
    let mut out = BufWriter::new(file);
    let written = fill(&mut out)
        .and_then(|()| out.flush().map_err(|e| format!("cannot write: {e}")))
        .and_then(|()| out.get_ref().sync_all().map_err(|e| format!("cannot write: {e}")));
    drop(out);
    let renamed = written.and_then(|()| {
        std::fs::rename(&tmp, path).map_err(|e| format!("cannot move the finished file into place: {e}"))
    });
    renamed.map_err(|msg| {
        // Best effort: the temporary may already be gone, and the error to report is `msg`.
        let _ = std::fs::remove_file(&tmp);
        Error::file(path, msg)
    })
}

/// Whether `path` can be written as the output `what` names (a flag such as `--outfile`, or `OUT`) before
/// any work is done: an extension [`super::write`] knows (`.exr`, `.pfm`, `.png`) when it is an `image`, a
/// folder that exists, and one that takes a new file (checked by creating and removing an empty one). Every
/// failure is a usage error naming `what` and `path`.
pub fn check_output(what: &str, path: &Path, image: bool) -> Result<()> {
    if image {
        super::Format::from_path(path).map_err(|e| Error::usage(format!("{what}: {e}")))?;
    }
    let folder = match path.parent() {
        Some(f) if !f.as_os_str().is_empty() => f,
        _ => Path::new("."),
    };
    if !folder.is_dir() {
        return Err(Error::usage(format!(
            "{what} {}: the folder \"{}\" does not exist",
            path.display(),
            folder.display()
        )));
    }
    let probe = folder.join(format!(".cachert-write-check-{}", std::process::id()));
    match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
        Ok(_) => {
            // Best effort: the probe is empty and hidden.
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => {
            Err(Error::usage(format!("{what} {}: cannot write in \"{}\": {e}", path.display(), folder.display())))
        }
    }
}

/// `dir/.name.tmp-PID-N` next to `path`.
fn temporary_name(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.tmp-{}-{n}", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch_dir(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("cachert-atomic-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn success_leaves_exactly_the_target() {
        let dir = scratch_dir("ok");
        let target = dir.join("a.bin");
        write_atomically(&target, |w| w.write_all(b"hello").map_err(|e| e.to_string())).unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"hello");
        assert_eq!(entries(&dir), vec!["a.bin".to_string()]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failure_midway_leaves_nothing() {
        let dir = scratch_dir("midway");
        let target = dir.join("a.bin");
        let err = write_atomically(&target, |w| {
            w.write_all(&[7u8; 100_000]).map_err(|e| e.to_string())?;
            Err("encoder gave up".to_string())
        })
        .unwrap_err();
        assert!(err.to_string().contains("a.bin") && err.to_string().contains("encoder gave up"), "{err}");
        assert!(entries(&dir).is_empty(), "{:?}", entries(&dir));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failure_keeps_an_existing_target_intact() {
        let dir = scratch_dir("keep");
        let target = dir.join("a.bin");
        std::fs::write(&target, b"old").unwrap();
        assert!(write_atomically(&target, |_| Err("no".into())).is_err());
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        assert_eq!(entries(&dir), vec!["a.bin".to_string()]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn check_output_names_the_problem() {
        let dir = scratch_dir("check");
        assert!(check_output("OUT", &dir.join("a.exr"), true).is_ok());
        assert!(check_output("--stats", &dir.join("a.json"), false).is_ok());
        let e = check_output("OUT", &dir.join("a.jpg"), true).unwrap_err().to_string();
        assert!(e.contains(".exr, .pfm or .png") && e.starts_with("OUT"), "{e}");
        let e = check_output("OUT", &dir.join("no/a.png"), true).unwrap_err().to_string();
        assert!(e.contains("does not exist") && e.contains("no/a.png"), "{e}");
        assert!(entries(&dir).is_empty(), "{:?}", entries(&dir));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_directory_is_an_error_naming_the_file() {
        let dir = scratch_dir("missing");
        let target = dir.join("no/such/dir/a.bin");
        let err = write_atomically(&target, |_| Ok(())).unwrap_err();
        assert!(err.to_string().contains("no/such/dir/a.bin"), "{err}");
        assert!(entries(&dir).is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
