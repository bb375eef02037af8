//! Experiments: sweeps over scenes × applications × cache budgets × placements × parameter values × seeds,
//! each render compared with the per-sample reference by RMSE and HDR-FLIP. A sweep is a spec ([`spec`]:
//! a TOML file, or built from the flags of `cachert experiment`) expanded into render jobs ([`jobs`]); its
//! one `results.csv` schema ([`results`]) feeds the tables ([`tables`]), charts ([`figures`]) and the HTML
//! report ([`report`]), never logs, and `--replot` rebuilds tables and charts from that file alone.
//!
//! The per-pixel comparison uses the application's own estimator (`per_pixel`) or its per-pixel baselines
//! (`baselines`: `Application::baselines`; the first gives the converged image).
//!
//! Benchmarks (`cachert bench`, [`bench`](mod@bench)) and the comparisons with pbrt-v2 and pbrt-v3 live here too: every
//! study has this one home.
//!
//! Depends on `job` and `integrator` (rendering), `scene`, `application` (the registry), `image` and
//! `metrics`; nothing but the command line depends on it.

use std::path::Path;

pub mod bench;
pub mod beyond;
pub mod chart;
pub mod figures;
pub mod jobs;
pub mod palette;
mod per_pixel;
pub mod pool;
pub mod ratios;
pub mod report;
pub mod results;
pub mod spec;
pub mod summary;
pub mod tables;
pub mod target;
pub mod ticks;
pub mod wins;

/// The part of stored reference file names that depends on the sweep's `--set` parameters (empty without
/// any), so a reference made with other parameters (say another `maxdistance`) is never reused. The cache
/// driver's placement parameters (σ_a, `sdminsize`, `ratio`, …) do not change the reference and are left out,
/// so sweeps over them share one; `subpixels` and `seed` do and stay in.
fn variant(set: &[(String, String)]) -> String {
    let set: Vec<&(String, String)> = set.iter().filter(|(k, _)| !placement_only(k)).collect();
    if set.is_empty() {
        return String::new();
    }
    tag(&set)
}

/// `-` and a short stable hash (FNV-1a) of `k=v` pairs, for file names.
fn tag(pairs: &[&(String, String)]) -> String {
    let text: String = pairs.iter().map(|(k, v)| format!("{k}={v};")).collect();
    let h = text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3));
    format!("-{:08x}", h as u32)
}

/// Whether a parameter only changes where caches go (σ_a, `sdminsize`, `ratio`, …), not the reference:
/// the cache driver's generic parameters except `subpixels` and `seed`.
fn placement_only(k: &str) -> bool {
    k != "subpixels" && k != "seed" && crate::integrator::cache::PARAMETERS.iter().any(|p| p.name == k)
}

pub(crate) fn name_of(p: &Path) -> String {
    let dir = p.parent().and_then(|d| d.file_name()).map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let stem = p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    if dir.is_empty() { stem } else { format!("{dir}-{stem}") }
}
