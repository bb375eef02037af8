//! Golden-image regression (not a pipeline stage; it sits beside `experiment`): a folder of reference EXRs
//! with a manifest saying how each was rendered, re-rendered and compared on demand.
//!
//! | file | what |
//! |---|---|
//! | [`manifest`] | `MANIFEST.json`: one [`Entry`] per golden — the render's inputs ([`Spec`]) and what was recorded |
//! | [`matrix`] | the project's own matrix, enumerated from the placement and application registries |
//! | [`check`](mod@check) | rendering an entry, comparing it with its golden ([`Verdict`]), `check` and `update` |
//!
//! A golden reproduces bit for bit with the same settings and seed on the same machine kind (rendering is
//! deterministic whatever the thread count); on another machine kind it passes within a relative RMSE of
//! [`REL_RMSE_TOLERANCE`] and an HDR-FLIP of [`FLIP_TOLERANCE`].
//!
//! Depends on `scene` (loading), `render` (rendering), `image`, `metrics` and the registries; nothing but
//! the command line depends on it.

pub mod check;
pub mod manifest;
pub mod matrix;

pub use check::{Errors, Outcome, Verdict, check, render_spec, update};
pub use manifest::{Entry, MANIFEST, Manifest, Recorded, Spec};

/// Across machine kinds: largest RMSE against the golden, relative to the golden's mean.
pub const REL_RMSE_TOLERANCE: f64 = 1e-4;

/// Across machine kinds: largest mean HDR-FLIP against the golden.
pub const FLIP_TOLERANCE: f64 = 0.005;

/// What "the same machine kind" means here: architecture, operating system and CPU model. Rendering uses
/// no CPU-specific code paths, so this is cautious: two kinds differing only in CPU model usually agree bit
/// for bit too, and are then reported as identical.
pub fn machine_kind() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".to_string());
    format!("{}-{}, {cpu}", std::env::consts::ARCH, std::env::consts::OS)
}

/// Whether `name` matches a `--filter` pattern: a substring, or with `*` a wildcard pattern over the whole
/// name (`spheres.*.vgc*`). An empty pattern matches everything.
pub fn matches(name: &str, pattern: &str) -> bool {
    if !pattern.contains('*') {
        return name.contains(pattern);
    }
    let parts: Vec<&str> = pattern.split('*').collect();
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if !name.starts_with(first) || name.len() < first.len() + last.len() || !name.ends_with(last) {
        return false;
    }
    let mut rest = &name[first.len()..name.len() - last.len()];
    for p in &parts[1..parts.len() - 1] {
        match rest.find(p) {
            Some(i) => rest = &rest[i + p.len()..],
            None => return false,
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn filters_match_substrings_and_wildcards() {
        assert!(matches("spheres.someapp.vgc+dgs", ""));
        assert!(matches("spheres.someapp.vgc+dgs", "someapp"));
        assert!(!matches("spheres.someapp.vgc+dgs", "room"));
        assert!(matches("spheres.someapp.vgc+dgs", "spheres.*.vgc*"));
        assert!(matches("spheres.someapp.vgc+dgs", "*dgs"));
        assert!(!matches("spheres.someapp.vgc+dgs", "*vgc"));
        assert!(matches("ab", "a*b"));
        assert!(!matches("ab", "ab*b"));
        assert!(matches("a.x.b.y.c", "a*b*c"));
        assert!(!matches("a.x.c.y.b", "a*b*c"));
    }

    #[test]
    fn the_machine_kind_names_architecture_and_system() {
        let k = machine_kind();
        assert!(k.starts_with(std::env::consts::ARCH) && k.contains(std::env::consts::OS), "{k}");
    }
}
