//! Experiments: sweeps over scenes × cache budgets × placements × seeds, each render compared with the
//! per-sample reference by RMSE and HDR-FLIP; results go to CSV and JSON (charts and the HTML report are
//! built from these files, never from logs) and a table of averages over seeds.
//!
//! Any cache-based integrator of the application registry can be swept (`Sweep::integrator`); the per-pixel
//! comparison uses the application's own per-pixel baselines (`Application::baselines`; the first
//! gives the converged image).
//!
//! Benchmarks (`cachert bench`, [`bench`](mod@bench)) and the comparisons with pbrt-v2 and pbrt-v3 live here too: every
//! study has this one home.
//!
//! Depends on `job` and `integrator` (rendering), `scene`, `application` (the registry), `image` and
//! `metrics`; nothing but the command line depends on it.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::application::registry;
use crate::error::{Error, Result, Warnings};
use crate::image::Image;
use crate::integrator::cache::stats::{CacheStats, StageTimes};
use crate::integrator::cache::{CacheOverrides, CachedOutput, Placement};
use crate::integrator::{RenderSettings, render};
use crate::metrics::{Metric, compare};
use crate::scene::{LoadOptions, LoadedScene, load};

pub mod bench;
pub mod chart;
pub mod figures;
pub mod jobs;
mod per_pixel;
pub mod replot;
pub mod report;
pub mod spec;
pub mod summary;
pub mod tables;

/// One sweep.
#[derive(Clone, Debug)]
pub struct Sweep {
    /// Scene files.
    pub scenes: Vec<PathBuf>,
    /// Film resolution for every scene.
    pub resolution: Option<[u32; 2]>,
    /// The cache-based integrator (a name of `application::registry`).
    pub integrator: String,
    /// Cache budgets.
    pub caches: Vec<usize>,
    /// Placements.
    pub placements: Vec<Placement>,
    /// Seeds 0..seeds.
    pub seeds: u64,
    /// Extra parameters of the integrator for every run (e.g. maxdistance).
    pub set: Vec<(String, String)>,
    /// Output folder.
    pub out: PathBuf,
    /// Worker threads.
    pub threads: Option<usize>,
    /// Also render the application's per-pixel baselines (pbrt-v3's `ambientocclusion` for AO; power and
    /// uniform VPL sampling for importance caching) with these ray counts (per pixel sample) and measure them
    /// against the same reference (rows `ao:N`, `power:N`, `uniform:N`), with the
    /// reference's own time (row `none`).
    pub baseline_samples: Vec<u32>,
}

/// One measured run.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Scene file stem.
    pub scene: String,
    /// Placement.
    pub placement: String,
    /// Budget.
    pub caches: usize,
    /// Seed.
    pub seed: u64,
    /// RMSE against the reference.
    pub rmse: f64,
    /// Mean HDR-FLIP against the reference.
    pub flip: f64,
    /// RMSE and mean HDR-FLIP against the converged per-pixel image (with `--ao-samples`; seed 0 only).
    pub converged: Option<(f64, f64)>,
    /// Stage times and counts of the run.
    pub stats: CacheStats,
}

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

fn name_of(p: &Path) -> String {
    let dir = p.parent().and_then(|d| d.file_name()).map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let stem = p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    if dir.is_empty() { stem } else { format!("{dir}-{stem}") }
}

fn run_one(
    l: &LoadedScene,
    sweep: &Sweep,
    placement: Placement,
    caches: usize,
    seed: u64,
) -> Result<(Image, CachedOutput)> {
    let settings = RenderSettings {
        seed,
        threads: sweep.threads,
        integrator: Some(sweep.integrator.clone()),
        set: sweep.set.clone(),
        cache: CacheOverrides { placement: Some(placement), caches: Some(caches), subpixels: None },
        ..Default::default()
    };
    let out = render(&l.scene, l.integrator.as_ref(), &settings, &mut Warnings::default())?;
    let cache = out
        .cache
        .ok_or_else(|| Error::usage(format!("experiment: \"{}\" produced no cache report", sweep.integrator)))?;
    Ok((out.image, *cache))
}

/// Runs the sweep; returns all rows (also written to `out/results.{csv,json}`) and the summary table.
pub fn run(sweep: &Sweep, log: &mut dyn FnMut(&str)) -> Result<(Vec<Row>, String)> {
    if registry::entry(&sweep.integrator).is_none() {
        return Err(Error::usage(format!(
            "experiment: \"{}\" is not a cache-based integrator (one of: {})",
            sweep.integrator,
            registry::names()
        )));
    }
    std::fs::create_dir_all(&sweep.out).map_err(|e| Error::file(&sweep.out, format!("cannot create: {e}")))?;
    let mut rows = Vec::new();
    for path in &sweep.scenes {
        let name = name_of(path);
        let mut l = load(path, LoadOptions { resolution: sweep.resolution, ..Default::default() })?;
        // Stored images depend on the integrator and its parameters: another run never reuses them.
        let stored = format!("{name}-{}{}", sweep.integrator, variant(&sweep.set));
        let ref_path = sweep.out.join(format!("{stored}-reference.exr"));
        let time_path = sweep.out.join(format!("{stored}-reference-seconds.txt"));
        let cached = crate::image::read(&ref_path)
            .ok()
            .filter(|img| [img.width, img.height] == l.scene.film.cropped_bounds().size())
            .zip(std::fs::read_to_string(&time_path).ok().and_then(|t| t.trim().parse::<f64>().ok()));
        let (reference, ref_secs) = match cached {
            Some(found) => found,
            None => {
                let (img, c) = run_one(&l, sweep, Placement::Reference, 1, 0)?;
                let secs = c.stats.times.total;
                log(&format!("{name}: reference in {secs:.1} s"));
                crate::image::write(&img, &ref_path)?;
                std::fs::write(&time_path, format!("{secs}\n"))
                    .map_err(|e| Error::file(&time_path, format!("cannot write: {e}")))?;
                (img, secs)
            }
        };
        // With --ao-samples: the converged image every seed-0 render is also measured against.
        let converged = if sweep.baseline_samples.is_empty() {
            None
        } else {
            let bases = per_pixel::baselines(&l, sweep)?;
            let conv = per_pixel::converged(&mut l, sweep, &bases[0], &stored, log)?;
            let times = StageTimes { total: ref_secs, ..Default::default() };
            let stats = CacheStats { times, ..Default::default() };
            let against = Some(per_pixel::measure(&reference, &conv)?);
            let (scene, placement) = (name.clone(), "none".to_string());
            rows.push(Row { scene, placement, caches: 0, seed: 0, rmse: 0.0, flip: 0.0, converged: against, stats });
            rows.extend(per_pixel::rows(&mut l, sweep, &bases, &name, (&reference, &conv), log)?);
            Some(conv)
        };
        for &caches in &sweep.caches {
            for &placement in &sweep.placements {
                for seed in 0..sweep.seeds {
                    let (img, c) = run_one(&l, sweep, placement, caches, seed)?;
                    let m = compare(&img, &reference, &[Metric::Rmse, Metric::Flip])?;
                    let (rmse, flip) = (m[0].1, m[1].1);
                    let against = match &converged {
                        Some(conv) if seed == 0 => Some(per_pixel::measure(&img, conv)?),
                        _ => None,
                    };
                    log(&format!(
                        "{name} {placement} {caches} seed {seed}: rmse {rmse:.5} flip {flip:.5} ({:.1} s)",
                        c.stats.times.total
                    ));
                    if seed == 0 {
                        crate::image::write(
                            &img,
                            &sweep
                                .out
                                .join(format!("{name}-{}-{caches}.exr", placement.name().replace([':', '+'], "_"))),
                        )?;
                    }
                    rows.push(Row {
                        scene: name.clone(),
                        placement: placement.to_string(),
                        caches,
                        seed,
                        rmse,
                        flip,
                        converged: against,
                        stats: c.stats,
                    });
                }
            }
        }
    }
    write_results(&rows, &sweep.out)?;
    match chart::font() {
        Ok(()) => {
            write_charts(&rows, &sweep.out)?;
        }
        Err(e) => log(&format!("no charts: {e}")),
    }
    Ok((rows.clone(), table(&rows, sweep)))
}

/// Writes the error-against-time chart of each scene of `rows` into `out` (`SCENE-error-vs-time.svg`, and
/// the PNG beside it); returns the SVGs. The charts' font must have been found ([`chart::font`]).
pub(crate) fn write_charts(rows: &[Row], out: &Path) -> Result<Vec<PathBuf>> {
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    let mut written = Vec::new();
    for scene in scenes {
        let svg = out.join(format!("{scene}-error-vs-time.svg"));
        chart::write(rows, scene, &svg)?;
        written.push(svg);
    }
    Ok(written)
}

fn write_results(rows: &[Row], out: &Path) -> Result<()> {
    let t0 = StageTimes::default();
    let steps: String = t0.steps().iter().map(|(name, _)| format!("{}_s,", name.replace([' ', '-'], "_"))).collect();
    let mut csv =
        format!("scene,placement,caches,seed,rmse,flip,rmse_converged,flip_converged,total_s,{steps}stage1,stage2\n");
    for r in rows {
        let converged =
            |i: usize| r.converged.map_or(String::new(), |c| format!("{:.6}", if i == 0 { c.0 } else { c.1 }));
        let steps: String = r.stats.times.steps().iter().map(|(_, secs)| format!("{secs:.4},")).collect();
        let _ = writeln!(
            csv,
            "{},{},{},{},{:.6},{:.6},{},{},{:.4},{steps}{},{}",
            r.scene,
            r.placement,
            r.caches,
            r.seed,
            r.rmse,
            r.flip,
            converged(0),
            converged(1),
            r.stats.times.total,
            r.stats.stage1_caches,
            r.stats.stage2_caches
        );
    }
    let json =
        serde_json::to_string_pretty(rows).map_err(|e| Error::file(out, format!("cannot encode results: {e}")))?;
    for (file, text) in [("results.csv", csv), ("results.json", json)] {
        let p = out.join(file);
        std::fs::write(&p, text).map_err(|e| Error::file(&p, format!("cannot write: {e}")))?;
    }
    Ok(())
}

/// Markdown table: per scene and budget, each placement's RMSE and FLIP averaged over seeds.
fn table(rows: &[Row], sweep: &Sweep) -> String {
    let mut t = String::new();
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    for scene in scenes {
        let measured: Vec<&Row> = rows.iter().filter(|r| r.scene == scene && r.converged.is_some()).collect();
        if !measured.is_empty() {
            let _ = writeln!(
                t,
                "\n{scene}, against the converged image of the per-pixel baseline (`none`: the per-sample \
                 reference; `LABEL:N`: the per-pixel baseline, N rays (or draws) per sample × 4 pixel samples; \
                 placements: seed 0). Two references: the tables below measure against the per-sample reference, \
                 this one against the baseline's converged image, which need not estimate the same quantity (for \
                 ambient occlusion pbrt-v3's hemisphere about the geometric normal, while the caches and the \
                 per-sample reference gather about the shading normal): the `none` row is the gap between the \
                 two. A spec's `per_pixel` runs the application's own estimator instead, so they agree by \
                 construction.\n\n\
                 | render | caches | RMSE | HDR-FLIP | total s |\n|---|---|---|---|---|"
            );
            for r in measured {
                let (rmse, flip) = r.converged.unwrap_or_default();
                let _ = writeln!(
                    t,
                    "| {} | {} | {rmse:.5} | {flip:.5} | {:.2} |",
                    r.placement, r.caches, r.stats.times.total
                );
            }
        }
        for &caches in &sweep.caches {
            let _ = writeln!(
                t,
                "\n{scene}, {caches} caches (mean over {} seeds)\n\n| placement | RMSE | HDR-FLIP | total s |\n|---|---|---|---|",
                sweep.seeds
            );
            for p in &sweep.placements {
                let sel: Vec<&Row> =
                    rows.iter().filter(|r| r.scene == scene && r.caches == caches && r.placement == p.name()).collect();
                if sel.is_empty() {
                    continue;
                }
                let n = sel.len() as f64;
                let mean = |f: &dyn Fn(&Row) -> f64| sel.iter().map(|r| f(r)).sum::<f64>() / n;
                let _ = writeln!(
                    t,
                    "| {p} | {:.5} | {:.5} | {:.2} |",
                    mean(&|r| r.rmse),
                    mean(&|r| r.flip),
                    mean(&|r| r.stats.times.total)
                );
            }
        }
    }
    t
}
