//! `cachert bench`: whole-pipeline figures for the pbrt-v3 reference scenes of `../shared/scenes` — CPU
//! seconds (loading and rendering, each also on its own), Mrays/s, the ratio to pbrt-v3's own CPU time for the
//! same image on this machine kind, thread scaling, and the image's distance to pbrt-v3's reference in units
//! of the Monte Carlo noise floor.
//!
//! pbrt-v3's CPU time covers its whole process (parsing, BVH building and rendering), so cachert's is
//! counted the same way: from before the scene is parsed to after the image is rendered. With `--pbrt` the
//! pbrt-v3 binary runs in the same bench run, on the same scene text, and its child-process CPU time is
//! measured; without it, the recorded 256-ray figures of `../shared/scenes/README.md` are used where they
//! apply. A benchmark prints figures from one run and asserts nothing (the machine is shared and noisy);
//! `--json` keeps them in a file so that quoted figures come from one.
//!
//! A study (beside the sweeps of `experiment`): [`micro`] times single stages, [`irc_peer`] compares
//! irradiance caching with pbrt-v2's. Its flags are derived on [`BenchArgs`] here, so that the one list of a
//! benchmark's settings is also its command line; `cli` only dispatches to [`run`]. Depends on
//! `integrator`, `scene`, `os` and `metrics`; nothing but the command line depends on it.

pub mod irc_peer;
pub mod micro;
pub mod peer_chart;

use std::fmt::Write;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use serde::Serialize;

use crate::error::{Error, Result, Warnings};
use crate::integrator::{RenderSettings, render};
use crate::os::{children_cpu_secs, process_cpu_secs};
use crate::scene::{LoadOptions, load_str};

/// pbrt-v3's user CPU seconds for each `ao-ref.pbrt` at its 256 AO rays (from `../shared/scenes/README.md`).
pub const PBRT_V3_CPU_SECS: [(&str, f64); 4] = [
    ("bitterli-cornell-box-v3", 70.7),
    ("pbrtv3scenes-veach-mis", 49.5),
    ("pbrtv3scenes-buddha-fractal", 166.6),
    ("bitterli-staircase2", 115.8),
];

/// The AO ray count of the `ao-ref.pbrt` files and their references.
const REF_NSAMPLES: u32 = 256;

/// Flags of `cachert bench`.
#[derive(clap::Args, Debug, Clone)]
#[command(args_conflicts_with_subcommands = true)]
pub struct BenchArgs {
    /// `micro`: benchmarks of single stages instead of the reference scenes.
    #[command(subcommand)]
    pub command: Option<BenchCommand>,
    /// Folder holding the reference scenes.
    #[arg(long, default_value = "../shared/scenes")]
    pub scenes: PathBuf,
    /// Only scenes whose folder name contains this.
    #[arg(long)]
    pub only: Option<String>,
    /// Worker threads for the main run (and for pbrt-v3).
    #[arg(long, default_value_t = 2)]
    pub nthreads: usize,
    /// Also render with one thread and report the speed-up of `--nthreads` over it.
    #[arg(long)]
    pub scaling: bool,
    /// AO rays per camera sample, one bench row each (comma-separated), e.g. 16,64,256.
    #[arg(long, value_delimiter = ',', default_value = "256")]
    pub nsamples: Vec<u32>,
    /// pbrt-v3's binary: run it on the same scene text in this run and measure its CPU time (else the
    /// recorded 256-ray times are used, and other ray counts have no ratio).
    #[arg(long)]
    pub pbrt: Option<PathBuf>,
    /// Write the table as JSON to this file as well.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// The integrator timed: `ambientocclusion` (rows per `--nsamples`), or `directlighting` / `path`
    /// (pbrt-v3's defaults, maxdepth 5; rows per `--spp`) on the scenes that have a light
    /// (Cornell box, veach-mis, staircase2).
    #[arg(long, default_value = "ambientocclusion")]
    pub integrator: String,
    /// Pixel samples of the `directlighting` / `path` rows (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "16")]
    pub spp: Vec<u32>,
    /// pbrt-v2's binary, for `--integrator` naming cachert's irradiance caching: pbrt-v2's irradiance cache
    /// against cachert's on the Cornell box, error against CPU time.
    #[arg(long)]
    pub pbrt_v2: Option<PathBuf>,
    /// With `--integrator` naming irradiance caching: write the error-versus-CPU-time chart here (SVG).
    #[arg(long)]
    pub chart: Option<PathBuf>,
    /// Time each row this many times, cachert and pbrt-v3 alternately, and keep each one's least CPU time
    /// (the run least disturbed by other work on a shared machine; every run's figure is in the JSON).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100))]
    pub repeat: u32,
    /// With `--integrator` naming irradiance caching: render each cachert row at seeds 0..N−1 and report
    /// the mean and standard deviation of its errors; pbrt-v2's defaults are rendered min(N, 6) times with
    /// different random numbers for their pixels (pbrt-v2 takes no seed; see `irc_peer`), its other rows once.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100))]
    pub seeds: u32,
}

/// What `cachert bench` can run instead of the reference scenes.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum BenchCommand {
    /// Benchmarks of single stages, one run each: flip, ply, placement, selection, parse (default: all).
    Micro(micro::MicroArgs),
}

/// The scenes `directlighting` and `path` are timed on (the bench scenes with light sources).
const SHADED_SCENES: [&str; 3] = ["bitterli-cornell-box-v3", "pbrtv3scenes-veach-mis", "bitterli-staircase2"];

/// The `Integrator` line of a shading bench row.
fn shading_integrator_line(name: &str) -> Result<&'static str> {
    match name {
        "directlighting" => Ok("Integrator \"directlighting\" \"integer maxdepth\" [5]"),
        "path" => Ok("Integrator \"path\" \"integer maxdepth\" [5]"),
        other => {
            Err(Error::usage(format!("--integrator {other}: the bench times ambientocclusion, directlighting or path")))
        }
    }
}

/// `text` (an `ao-ref.pbrt`: 16 random-sampler pixel samples, box filter) with its Integrator line replaced
/// by `integrator` and its pixel samples set to `spp`.
fn with_integrator(text: &str, integrator: &str, spp: u32, file: &Path) -> Result<String> {
    let from = "\"integer pixelsamples\" [16]";
    let Some(line) = text.lines().find(|l| l.starts_with("Integrator ")) else {
        return Err(Error::usage(format!("{}: no Integrator line to replace", file.display())));
    };
    if !text.contains(from) {
        return Err(Error::usage(format!("{}: no `{from}` to replace", file.display())));
    }
    Ok(text.replacen(line, integrator, 1).replacen(from, &format!("\"integer pixelsamples\" [{spp}]"), 1))
}

/// One row of the bench table.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct BenchRow {
    /// Scene folder name.
    pub scene: String,
    /// The integrator timed.
    pub integrator: String,
    /// AO rays per camera sample (`ambientocclusion`), or pixel samples (`directlighting`, `path`).
    pub nsamples: u32,
    /// Worker threads.
    pub threads: usize,
    /// cachert CPU seconds for parsing and building the scene (BVH included).
    pub load_cpu_s: f64,
    /// cachert CPU seconds for rendering.
    pub render_cpu_s: f64,
    /// cachert CPU seconds, load + render: what pbrt-v3's figure covers.
    pub cpu_s: f64,
    /// Wall seconds, load + render.
    pub wall_s: f64,
    /// Rays traced, millions.
    pub mrays: f64,
    /// Millions of rays per wall second of the render.
    pub mrays_per_s: f64,
    /// pbrt-v3's CPU seconds for the same image, if known.
    pub pbrt_cpu_s: Option<f64>,
    /// Where `pbrt_cpu_s` comes from: "measured" (this run) or "recorded" (the scenes README).
    pub pbrt_source: Option<String>,
    /// pbrt-v3 CPU seconds / cachert CPU seconds (higher is faster).
    pub speedup: Option<f64>,
    /// cachert CPU seconds / pbrt-v3 CPU seconds (the "≤ 0.45×" figure).
    pub cpu_fraction: Option<f64>,
    /// 1-thread render wall / `threads`-thread render wall, with `--scaling`.
    pub scaling: Option<f64>,
    /// RMSE to pbrt-v3's `ao-ref.pfm` divided by the noise model's expected RMSE at this ray count.
    pub rmse_over_floor: Option<f64>,
    /// cachert's CPU seconds in each of the `--repeat` runs (`cpu_s` is the least).
    pub cpu_s_runs: Vec<f64>,
    /// pbrt-v3's CPU seconds in each run, when measured (`pbrt_cpu_s` is the least).
    pub pbrt_cpu_s_runs: Vec<f64>,
}

/// `text` with its `ambientocclusion` ray count set to `n` (the `ao-ref.pbrt` files write `[256]`).
fn with_nsamples(text: &str, n: u32, file: &Path) -> Result<String> {
    let from = format!("\"integer nsamples\" [{REF_NSAMPLES}]");
    if !text.contains(&from) {
        return Err(Error::usage(format!("{}: no `{from}` to replace", file.display())));
    }
    Ok(text.replacen(&from, &format!("\"integer nsamples\" [{n}]"), 1))
}

/// Runs pbrt-v3 on `text` (read from standard input, relative paths resolved in `dir`); returns its CPU
/// seconds.
fn run_pbrt(pbrt: &Path, text: &str, dir: &Path, threads: usize) -> Result<f64> {
    let scratch = std::env::temp_dir().join(format!("cachert-bench-{}", std::process::id()));
    std::fs::create_dir_all(&scratch).map_err(|e| Error::file(&scratch, e.to_string()))?;
    let out = scratch.join("pbrt.pfm");
    let before = children_cpu_secs();
    let mut child = Command::new(pbrt)
        .current_dir(dir)
        .args(["--quiet", "--nthreads", &threads.to_string(), "--logdir"])
        .arg(&scratch)
        .arg("--outfile")
        .arg(&out)
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| Error::usage(format!("cannot run pbrt-v3 at {}: {e}", pbrt.display())))?;
    if let Some(mut stdin) = child.stdin.take() {
        stdin.write_all(text.as_bytes()).map_err(|e| Error::usage(format!("pbrt-v3: cannot write the scene: {e}")))?;
    }
    let status = child.wait_with_output().map_err(|e| Error::usage(format!("pbrt-v3: {e}")))?;
    let cpu = children_cpu_secs() - before;
    let _ = std::fs::remove_dir_all(&scratch);
    if !status.status.success() {
        return Err(Error::usage(format!(
            "pbrt-v3 failed ({}): {}",
            status.status,
            String::from_utf8_lossy(&status.stderr).trim()
        )));
    }
    Ok(cpu)
}

/// Runs the benchmark and returns its table (and writes it to `--json`).
pub fn run(args: &BenchArgs) -> Result<String> {
    if let Some(BenchCommand::Micro(micro)) = &args.command {
        return micro::run(micro);
    }
    if !args.scenes.is_dir() {
        return Err(Error::usage(format!("{}: no such folder (pass --scenes)", args.scenes.display())));
    }
    if args.nsamples.contains(&0) {
        return Err(Error::usage("--nsamples: ray counts must be at least 1"));
    }
    if args.integrator == irc_peer::INTEGRATOR {
        return irc_peer::run(args);
    }
    if args.seeds > 1 {
        return Err(Error::usage(format!(
            "--seeds applies to the irradiance-caching comparison (--integrator {}); the other rows are timings \
             of one image",
            irc_peer::INTEGRATOR
        )));
    }
    // pbrt-v3 runs in each scene's folder, so a relative path must be made absolute first.
    let pbrt = match &args.pbrt {
        Some(p) => Some(std::fs::canonicalize(p).map_err(|e| Error::file(p, format!("pbrt-v3 binary: {e}")))?),
        None => None,
    };
    let mut rows = Vec::new();
    if args.integrator != "ambientocclusion" {
        let line = shading_integrator_line(&args.integrator)?;
        if args.spp.contains(&0) {
            return Err(Error::usage("--spp: sample counts must be at least 1"));
        }
        for name in SHADED_SCENES {
            if args.only.as_deref().is_some_and(|o| !name.contains(o)) {
                continue;
            }
            let dir = args.scenes.join(name);
            let file = dir.join("ao-ref.pbrt");
            let text = std::fs::read_to_string(&file).map_err(|e| Error::file(&file, e.to_string()))?;
            for &spp in &args.spp {
                let text = with_integrator(&text, line, spp, &file)?;
                let (row, _) = bench_both(name, &text, &file, spp, args, pbrt.as_deref(), &dir)?;
                eprintln!("{}", format_row(&row));
                rows.push(row);
            }
        }
        return finish(rows, args);
    }
    for (name, recorded) in PBRT_V3_CPU_SECS {
        if args.only.as_deref().is_some_and(|o| !name.contains(o)) {
            continue;
        }
        let dir = args.scenes.join(name);
        let file = dir.join("ao-ref.pbrt");
        let text = std::fs::read_to_string(&file).map_err(|e| Error::file(&file, e.to_string()))?;
        let refs = (crate::image::read(&dir.join("ao-ref.pfm")), crate::image::read(&dir.join("ao-ref-b.pfm")));
        for &n in &args.nsamples {
            let text = with_nsamples(&text, n, &file)?;
            let (mut row, image) = bench_both(name, &text, &file, n, args, pbrt.as_deref(), &dir)?;
            if let (Ok(a), Ok(b)) = &refs {
                let floor = crate::metrics::rmse(a, b)?;
                let k = f64::from(REF_NSAMPLES) / f64::from(n);
                let expected = floor * ((k + 1.0) / 2.0).sqrt();
                row.rmse_over_floor = Some(crate::metrics::rmse(&image, a)? / expected);
            }
            if pbrt.is_none() && n == REF_NSAMPLES {
                set_pbrt(&mut row, recorded, "recorded");
            }
            eprintln!("{}", format_row(&row));
            rows.push(row);
        }
    }
    finish(rows, args)
}

/// Writes `--json` and returns the table.
fn finish(rows: Vec<BenchRow>, args: &BenchArgs) -> Result<String> {
    if let Some(path) = &args.json {
        let json = serde_json::to_string_pretty(&rows).map_err(|e| Error::usage(format!("JSON: {e}")))?;
        crate::image::write_bytes(path, json.as_bytes())?;
    }
    Ok(table(&rows, args.nthreads, args.repeat))
}

/// Fills in pbrt-v3's CPU time and the ratios.
fn set_pbrt(row: &mut BenchRow, secs: f64, source: &str) {
    row.pbrt_cpu_s = Some(secs);
    row.pbrt_source = Some(source.into());
    row.speedup = Some(secs / row.cpu_s);
    row.cpu_fraction = Some(row.cpu_s / secs);
}

/// [`bench_cachert`] and, with a pbrt-v3 binary, pbrt-v3 on the same text, `--repeat` times alternately:
/// the row of cachert's least-CPU run with pbrt-v3's least CPU time, every run's figures listed.
fn bench_both(
    name: &str,
    text: &str,
    file: &Path,
    n: u32,
    args: &BenchArgs,
    pbrt: Option<&Path>,
    dir: &Path,
) -> Result<(BenchRow, crate::image::Image)> {
    let (mut best, image) = bench_cachert(name, text, file, n, args)?;
    let (mut cpu_runs, mut pbrt_runs) = (vec![best.cpu_s], Vec::new());
    for k in 0..args.repeat {
        if k > 0 {
            let (row, _) = bench_cachert(name, text, file, n, args)?;
            cpu_runs.push(row.cpu_s);
            if row.cpu_s < best.cpu_s {
                best = row;
            }
        }
        if let Some(p) = pbrt {
            pbrt_runs.push(run_pbrt(p, text, dir, args.nthreads)?);
        }
    }
    if let Some(least) = pbrt_runs.iter().copied().reduce(f64::min) {
        set_pbrt(&mut best, least, "measured");
    }
    best.cpu_s_runs = cpu_runs;
    best.pbrt_cpu_s_runs = pbrt_runs;
    Ok((best, image))
}

/// Loads and renders one scene text, timing load and render separately; returns the row and the image.
fn bench_cachert(
    name: &str,
    text: &str,
    file: &Path,
    n: u32,
    args: &BenchArgs,
) -> Result<(BenchRow, crate::image::Image)> {
    let settings = |threads| RenderSettings { threads: Some(threads), ..Default::default() };
    let (cpu0, t0) = (process_cpu_secs(), Instant::now());
    let loaded = load_str(text, file, LoadOptions::default())?;
    let cpu1 = process_cpu_secs();
    let mut warnings = Warnings::default();
    let t1 = Instant::now();
    let r = render(&loaded.scene, loaded.integrator.as_ref(), &settings(args.nthreads), &mut warnings)?;
    let render_wall = t1.elapsed().as_secs_f64();
    let wall = t0.elapsed().as_secs_f64();
    let cpu2 = process_cpu_secs();
    let (load_cpu, render_cpu) = match (cpu0, cpu1, cpu2) {
        (Some(a), Some(b), Some(c)) => (b - a, c - b),
        _ => ((wall - render_wall) * args.nthreads as f64, render_wall * args.nthreads as f64),
    };
    let scaling = if args.scaling {
        let t = Instant::now();
        render(&loaded.scene, loaded.integrator.as_ref(), &settings(1), &mut warnings)?;
        Some(t.elapsed().as_secs_f64() / render_wall)
    } else {
        None
    };
    let mrays = r.rays.total() as f64 / 1e6;
    let row = BenchRow {
        scene: name.into(),
        integrator: args.integrator.clone(),
        nsamples: n,
        threads: args.nthreads,
        load_cpu_s: load_cpu,
        render_cpu_s: render_cpu,
        cpu_s: load_cpu + render_cpu,
        wall_s: wall,
        mrays,
        mrays_per_s: mrays / render_wall.max(1e-9),
        pbrt_cpu_s: None,
        pbrt_source: None,
        speedup: None,
        cpu_fraction: None,
        scaling,
        rmse_over_floor: None,
        cpu_s_runs: Vec::new(),
        pbrt_cpu_s_runs: Vec::new(),
    };
    Ok((row, r.image))
}

fn opt(v: Option<f64>, digits: usize, suffix: &str) -> String {
    v.map_or("-".into(), |v| format!("{v:.digits$}{suffix}"))
}

fn format_row(r: &BenchRow) -> String {
    format!(
        "{:<28} {:>5} {:>8.1} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>10} {:>8} {:>7} {:>8} {:>10}",
        r.scene,
        r.nsamples,
        r.mrays,
        r.wall_s,
        r.load_cpu_s,
        r.render_cpu_s,
        r.cpu_s,
        r.mrays_per_s,
        opt(r.pbrt_cpu_s, 1, ""),
        opt(r.speedup, 2, "x"),
        opt(r.cpu_fraction, 3, ""),
        opt(r.scaling, 2, "x"),
        opt(r.rmse_over_floor, 3, ""),
    )
}

fn table(rows: &[BenchRow], threads: usize, repeat: u32) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<28} {:>5} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>10} {:>8} {:>7} {:>8} {:>10}",
        "scene",
        "rays|spp",
        "Mrays",
        "wall s",
        "load cpu",
        "rend cpu",
        "cpu s",
        "Mrays/s",
        "pbrt cpu s",
        "speedup",
        "fract",
        "scaling",
        "rmse/floor"
    );
    for r in rows {
        let _ = writeln!(out, "{}", format_row(r));
    }
    let _ = write!(
        out,
        "cpu s = load + render CPU seconds, as pbrt-v3's whole-process figure; speedup = pbrt-v3 CPU / cachert CPU \
         (target ≥ 2); fract = cachert CPU / pbrt-v3 CPU; scaling = 1-thread wall / {threads}-thread wall; \
         rmse/floor = RMSE to ao-ref.pfm over the noise model's expected RMSE at that ray count (AO only); \
         rays|spp = AO rays per camera sample, or pixel samples for directlighting and path"
    );
    if repeat > 1 {
        let _ = write!(out, "; each CPU figure is the least of {repeat} runs, cachert and pbrt-v3 alternating");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ray_count_is_replaced_once_and_a_missing_one_is_an_error() {
        let t = "Integrator \"ambientocclusion\" \"integer nsamples\" [256]\nWorldBegin\n";
        let out = with_nsamples(t, 16, Path::new("x.pbrt")).unwrap();
        assert!(out.contains("\"integer nsamples\" [16]") && !out.contains("[256]"));
        assert!(with_nsamples("WorldBegin\n", 16, Path::new("x.pbrt")).is_err());
    }

    #[test]
    fn the_integrator_and_sample_count_are_replaced() {
        let t = "Integrator \"ambientocclusion\" \"integer nsamples\" [256]\nSampler \"random\" \"integer pixelsamples\" [16]\n";
        let line = shading_integrator_line("path").unwrap();
        let out = with_integrator(t, line, 4, Path::new("x.pbrt")).unwrap();
        assert_eq!(
            out,
            "Integrator \"path\" \"integer maxdepth\" [5]\nSampler \"random\" \"integer pixelsamples\" [4]\n"
        );
        assert!(shading_integrator_line("bdpt").is_err());
        assert!(with_integrator("WorldBegin\n", line, 4, Path::new("x.pbrt")).is_err());
    }
}
