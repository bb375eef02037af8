//! Test support for the unit tests of `src/` (compiled only with `cfg(test)`): the shared third-party
//! scenes, with the policy of `tests/common`: under CI (the environment variable `CI` set to anything but
//! empty, `false` or `0`) their absence fails the test; elsewhere the test prints one line and returns, and
//! `shared_scenes_present` fails so that a plain `cargo test` shows it.
//!
//! Depends on nothing of the crate.

use std::io::Write as _;
use std::path::{Path, PathBuf};

/// Whether the tests run under CI.
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| {
        let v = v.trim();
        !(v.is_empty() || v == "0" || v.eq_ignore_ascii_case("false"))
    })
}

/// `$CACHERT_SHARED/scenes` when set, else `CARGO_MANIFEST_DIR/../shared/scenes`, or why it is absent.
fn scenes_dir() -> Result<PathBuf, String> {
    let root = match std::env::var_os("CACHERT_SHARED") {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared"),
    };
    let dir = root.join("scenes");
    if dir.is_dir() {
        Ok(dir)
    } else {
        Err(format!(
            "{} is absent (the third-party scenes live there; CACHERT_SHARED names another copy)",
            dir.display()
        ))
    }
}

/// `<shared>/scenes/<rel>` for a test that needs it, or `None` after saying so (a failure under CI).
pub fn shared_scenes(rel: &str) -> Option<PathBuf> {
    let why = match scenes_dir() {
        Ok(dir) if dir.join(rel).exists() => return Some(dir.join(rel)),
        Ok(dir) => format!("{} is absent from the shared scenes", dir.join(rel).display()),
        Err(why) => why,
    };
    if in_ci() {
        panic!("{why}; under CI (the environment variable CI is set) everything the tests need must be there");
    }
    let test = std::thread::current().name().unwrap_or("a test").to_string();
    let _ = std::io::stderr().write_all(format!("skipped {test}: {why}\n").as_bytes());
    None
}

#[test]
fn shared_scenes_present() {
    if let Err(why) = scenes_dir() {
        panic!("{why}: the unit tests that need them did not run");
    }
}
