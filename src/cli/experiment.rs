//! `cachert experiment`: a placement sweep (scenes × budgets × placements × seeds) against the per-sample
//! reference, written to CSV/JSON with tables, charts and a report — from a TOML spec file (`cachert
//! experiment SPEC.toml --out DIR`: resumable, locked, with `--emit-jobs` and `--collect` for running the
//! renders elsewhere), or from flags, which build the same spec and run it the same way.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::application::registry;
use crate::error::{Error, Result};
use crate::experiment::spec::{AppSpec, SceneSpec, SpecFile, Value};

/// Flags of `cachert experiment`.
#[derive(clap::Args, Debug, Clone)]
pub struct ExperimentArgs {
    /// A TOML spec of the sweep (scenes, applications, placements, budgets, parameter values, seeds);
    /// without it the sweep comes from the flags below. With it, only --out, --nthreads, --emit-jobs and
    /// --collect apply (the others are refused: the spec says what they would).
    pub spec: Option<PathBuf>,
    /// With a spec: write the renders still to do as shell command lines to FILE (for GNU parallel, a Slurm
    /// array, …) instead of running them.
    #[arg(long = "emit-jobs", value_name = "FILE", requires = "spec")]
    pub emit_jobs: Option<PathBuf>,
    /// With a spec: render nothing; measure the per-run files found in --out and write the results.
    #[arg(long, requires = "spec", conflicts_with = "emit_jobs")]
    pub collect: bool,
    /// Scene files (repeatable).
    #[arg(long = "scene", required_unless_present_any = ["spec", "replot", "pool"], conflicts_with = "spec")]
    pub scenes: Vec<PathBuf>,
    /// Film resolution WxH for every scene (e.g. 640x360).
    #[arg(long, value_parser = super::parse_resolution, conflicts_with = "spec")]
    pub resolution: Option<[u32; 2]>,
    /// The cache-based integrator (default: the first registered; see `cachert render --help`).
    #[arg(long, conflicts_with = "spec")]
    pub integrator: Option<String>,
    /// Cache budgets, comma-separated.
    #[arg(long, default_value = "13000", conflicts_with = "spec")]
    pub caches: String,
    /// Placements, comma-separated.
    #[arg(long, default_value = "im,sd,sd+as,vgc,vgc+dgs", conflicts_with = "spec")]
    pub placements: String,
    /// Number of seeds (0, 1, …) averaged per setting.
    #[arg(long, default_value_t = 3, conflicts_with = "spec")]
    pub seeds: u64,
    /// Integrator parameter for every run (repeatable), e.g. --set maxdistance=0.6.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = super::parse_key_value, conflicts_with = "spec")]
    pub set: Vec<(String, String)>,
    /// Output folder (reference images are kept there and reused).
    #[arg(long, default_value = "experiment-out")]
    pub out: PathBuf,
    /// Worker threads.
    #[arg(long)]
    pub nthreads: Option<usize>,
    /// Also time the integrator's per-pixel baselines (pbrt-v3's `ambientocclusion` for AO; power and uniform
    /// VPL sampling for importance caching) at these ray counts (per pixel sample, comma-separated) against
    /// the same reference.
    #[arg(long = "baseline-samples", visible_alias = "ao-samples", conflicts_with = "spec")]
    pub baseline_samples: Option<String>,
    /// Render nothing: rebuild tables.md and the charts of a finished sweep in folder DIR from its
    /// results.csv alone (to bring a change to the tables or charts to results already measured).
    #[arg(long, value_name = "DIR", conflicts_with_all = [
        "spec", "scenes", "resolution", "integrator", "caches", "placements", "seeds", "set", "out", "nthreads",
        "baseline_samples",
    ])]
    pub replot: Option<PathBuf>,
    /// With --replot: write only DIR/equal-time-vs-<DIR2>.md, the equal-time tables of DIR with the per-pixel
    /// runs taken from DIR2/results.csv (another sweep against the same reference, say without a parameter
    /// that changes the per-pixel estimators).
    #[arg(long, value_name = "DIR2", requires = "replot")]
    pub baselines: Option<PathBuf>,
    /// Render nothing: judge each placement beyond the paper's five (`refine`) against them over the cells
    /// of several finished sweeps together (repeat the flag, one folder each; a cell measured again by a
    /// later folder replaces the earlier one's) and print the tables as Markdown.
    #[arg(long, value_name = "DIR", conflicts_with_all = [
        "spec", "scenes", "resolution", "integrator", "caches", "placements", "seeds", "set", "out", "nthreads",
        "baseline_samples", "replot",
    ])]
    pub pool: Vec<PathBuf>,
}

/// Runs the sweep and returns the table.
pub fn run(a: &ExperimentArgs) -> Result<String> {
    if !a.pool.is_empty() {
        return crate::experiment::pool::markdown(&a.pool);
    }
    if let (Some(dir), Some(other)) = (&a.replot, &a.baselines) {
        let written = crate::experiment::results::rebuild_against(dir, other)?;
        return Ok(format!("rebuilt: {}\n", written.display()));
    }
    if let Some(dir) = &a.replot {
        let written = crate::experiment::results::rebuild(dir, &mut |line| eprintln!("{line}"))?;
        return Ok(written.iter().map(|p| format!("rebuilt: {}\n", p.display())).collect());
    }
    if let Some(path) = &a.spec {
        return run_spec(a, path);
    }
    let spec = crate::experiment::spec::expand(&from_flags(a)?, Path::new(FLAGS), &|_, msg| {
        Error::usage(format!("experiment: {msg}"))
    })?;
    let (_, table) = crate::experiment::jobs::run(&spec, &a.out, a.nthreads, &mut |line| eprintln!("{line}"))?;
    Ok(format!("{table}\nresults: {}/results.csv, results.json, tables.md, report.html", a.out.display()))
}

/// The name a spec built from flags goes by (in the report's title).
const FLAGS: &str = "(from flags)";

/// The spec the flags describe: one application over the scenes.
fn from_flags(a: &ExperimentArgs) -> Result<SpecFile> {
    let caches = counts("--caches", &a.caches)?;
    let baselines = match &a.baseline_samples {
        Some(list) => {
            counts("--baseline-samples", list)?.into_iter().map(|n| n.min(u32::MAX as usize) as u32).collect()
        }
        None => Vec::new(),
    };
    let default = registry::APPLICATIONS.first().map_or("", |e| e.name);
    let set: BTreeMap<String, Value> = a.set.iter().map(|(k, v)| (k.clone(), Value::Text(v.clone()))).collect();
    let scene = a.scenes.iter().map(|p| SceneSpec { file: p.display().to_string(), name: None }).collect();
    Ok(SpecFile {
        resolution: a.resolution,
        seeds: a.seeds,
        scene,
        application: vec![AppSpec {
            name: a.integrator.clone().unwrap_or_else(|| default.to_string()),
            placements: a.placements.split(',').map(|p| p.trim().to_string()).collect(),
            caches: Some(caches),
            set,
            baselines,
            ..Default::default()
        }],
    })
}

/// A comma-separated list of positive counts.
fn counts(flag: &str, list: &str) -> Result<Vec<usize>> {
    list.split(',')
        .map(|c| {
            c.trim()
                .parse::<usize>()
                .ok()
                .filter(|&n| n > 0)
                .ok_or_else(|| Error::usage(format!("{flag}: \"{c}\" is not a positive count")))
        })
        .collect()
}

/// `cachert experiment SPEC.toml`: run (resuming), emit the jobs, or collect.
fn run_spec(a: &ExperimentArgs, path: &std::path::Path) -> Result<String> {
    let spec = crate::experiment::spec::read(path)?;
    if let Some(file) = &a.emit_jobs {
        let exe = std::env::current_exe().map(|p| p.display().to_string()).unwrap_or_else(|_| "cachert".to_string());
        let (n, left) = crate::experiment::jobs::emit(&spec, &a.out, file, &exe)?;
        let left = if left == 0 {
            String::new()
        } else {
            format!(
                " ({left} baseline jobs render only in this process: cachert experiment {} --out {} runs them and collects)",
                path.display(),
                a.out.display()
            )
        };
        return Ok(format!(
            "wrote {n} jobs of {} to {}; run them (e.g. parallel -j 2 < {}), then: cachert experiment {} --out {} --collect{left}",
            spec.jobs.len(),
            file.display(),
            file.display(),
            path.display(),
            a.out.display()
        ));
    }
    let mut log = |line: &str| eprintln!("{line}");
    let (_, table) = if a.collect {
        let _lock = crate::experiment::jobs::lock(&a.out)?;
        crate::experiment::jobs::collect(&spec, &a.out, &mut log)?
    } else {
        crate::experiment::jobs::run(&spec, &a.out, a.nthreads, &mut log)?
    };
    Ok(format!("{table}\nresults: {}/results.csv, results.json, tables.md, report.html", a.out.display()))
}
