//! Golden-image regression (not a pipeline stage; it sits beside `experiment`): a folder of reference EXRs
//! with a manifest saying how each was rendered, re-rendered and compared on demand.
//!
//! | file | what |
//! |---|---|
//! | [`manifest`] | `MANIFEST.json`: one [`Entry`] per golden — the render's inputs ([`Spec`]) and what was recorded |
//! | [`matrix`] | the project's own matrix, enumerated from the placement and application registries |
//! | [`check`](mod@check) | rendering an entry, comparing it with its golden ([`Verdict`]), `check` and `update` |
//! | [`provenance`] | the commit goldens are recorded at, and the refusal to record from uncommitted code |
//!
//! A golden reproduces bit for bit with the same settings and seed on the same [`platform`] — architecture
//! and system, not the CPU model: rendering is deterministic whatever the thread count, uses no CPU-specific
//! code path, and goldens made on Intel reproduce bit for bit on AMD. Only a golden made on another platform,
//! or a check asked for [`Rule::Tolerance`] on purpose (`golden check --tolerance`), passes within a relative
//! RMSE of [`REL_RMSE_TOLERANCE`] and an HDR-FLIP of [`FLIP_TOLERANCE`]; the report names the rule of each
//! entry ([`rule`]).
//!
//! Depends on `scene` (loading), `render` (rendering), `image`, `metrics` and the registries; nothing but
//! the command line depends on it.

pub mod check;
pub mod manifest;
pub mod matrix;
pub use crate::provenance;

pub use check::{Errors, Outcome, Verdict, check, render_spec, update};
pub use manifest::{Entry, MANIFEST, Manifest, Recorded, Spec};

/// Across machine kinds: largest RMSE against the golden, relative to the golden's mean.
pub const REL_RMSE_TOLERANCE: f64 = 1e-4;

/// Across machine kinds: largest mean HDR-FLIP against the golden.
pub const FLIP_TOLERANCE: f64 = 0.005;

/// The platform a golden's bits belong to: architecture and operating system (`x86_64-linux`). The system
/// counts because its maths library computes `sin`, `exp` and the like; the CPU model does not.
pub fn platform() -> String {
    format!("{}-{}", std::env::consts::ARCH, std::env::consts::OS)
}

/// The machine, for the record: [`platform`] and CPU model (`x86_64-linux, AMD EPYC`).
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
    format!("{}, {cpu}", platform())
}

/// The rule a re-render is judged by against its golden.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Rule {
    /// The same bits: the golden was made on this platform.
    Bits,
    /// Within [`REL_RMSE_TOLERANCE`] and [`FLIP_TOLERANCE`], for the reason given.
    Tolerance(Lenience),
}

/// Why a golden is judged by the tolerance rather than by its bits.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Lenience {
    /// It was made on another platform (the one named).
    OtherPlatform(String),
    /// The check was asked for the tolerance (`golden check --tolerance`).
    Asked,
}

impl Rule {
    /// A few words for the report.
    pub fn describe(&self) -> String {
        match self {
            Rule::Bits => "bit for bit".to_string(),
            Rule::Tolerance(Lenience::Asked) => "within the tolerance (asked with --tolerance)".to_string(),
            Rule::Tolerance(Lenience::OtherPlatform(p)) => format!("within the tolerance (made on {p})"),
        }
    }
}

/// The rule for a golden recorded on `recorded` (a [`platform`]) checked on `here`, `asked` whether the check
/// was asked for the tolerance. Bits unless asked or the platforms differ; an unknown (empty) recorded
/// platform is judged by bits too, so that a golden never slips into the tolerance by missing data.
pub fn rule(recorded: &str, here: &str, asked: bool) -> Rule {
    if asked {
        Rule::Tolerance(Lenience::Asked)
    } else if recorded.is_empty() || recorded == here {
        Rule::Bits
    } else {
        Rule::Tolerance(Lenience::OtherPlatform(recorded.to_string()))
    }
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
    fn the_machine_kind_names_the_platform_first() {
        let k = machine_kind();
        assert!(k.starts_with(&format!("{}, ", platform())), "{k}");
        assert_eq!(platform(), format!("{}-{}", std::env::consts::ARCH, std::env::consts::OS));
    }

    #[test]
    fn the_rule_is_bits_on_one_platform_whatever_the_cpu() {
        assert_eq!(rule("x86_64-linux", "x86_64-linux", false), Rule::Bits);
        assert_eq!(rule("", "x86_64-linux", false), Rule::Bits);
        assert_eq!(rule("x86_64-linux", "x86_64-linux", true), Rule::Tolerance(Lenience::Asked));
        assert_eq!(
            rule("aarch64-linux", "x86_64-linux", false),
            Rule::Tolerance(Lenience::OtherPlatform("aarch64-linux".into()))
        );
        assert!(rule("aarch64-macos", "x86_64-linux", false).describe().contains("aarch64-macos"));
    }
}
