//! Running a spec's jobs and collecting what they wrote. Each job is one render job (what `cachert render`
//! runs) that writes `runs/<id>.exr` and `runs/<id>.json` (its `--stats` report), and its warnings or error to `runs/<id>.log`.
//! The jobs run in this process ([`run`]: resumable, since a job whose `.json` exists is skipped; locked,
//! so two sweeps never write one folder), or are written out as command lines for a scheduler such as GNU
//! parallel or a Slurm array ([`emit`]); either way [`collect`] then measures every run against its
//! reference and writes `results.csv`, `results.json`, `table.md` and, per scene and application, charts of
//! the error against time and against the number of caches. A failed run is a row with its message, not the end of the sweep.
//!
//! Depends on `job` (each run is a typed render job; its command line is only for `--emit-jobs`), `image`,
//! `metrics` and the chart writer.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::{Error, Result};
use crate::image::Image;
use crate::integrator::RenderSettings;
use crate::integrator::cache::{CacheOverrides, Placement};
use crate::job::{Outputs, RenderJob};
use crate::metrics::{Metric, compare};
use crate::scene::LoadOptions;

use super::spec::{BaselineRun, Job, Spec};

/// The folder of per-run files inside an experiment's output folder.
pub const RUNS: &str = "runs";

/// The Markdown tables of an experiment folder.
pub const TABLES: &str = "tables.md";

/// The suffix of a run's cache overlay (seed-0 cache runs write one): `runs/<id>-overlay.png`.
pub const OVERLAY: &str = "-overlay.png";

/// The lock file that keeps two sweeps from writing one folder.
pub const LOCK: &str = ".cachert-experiment.lock";

/// The render job of `job` writing into `out/runs/`: the image, its `--stats` report, and for a seed-0
/// cache run the overlay; `threads` workers. A placement name the registry does not know is an error.
pub fn render_job(job: &Job, out: &Path, threads: Option<usize>) -> Result<RenderJob> {
    let runs = out.join(RUNS);
    let placement = Placement::parse(&job.placement)?;
    // The report shows where the caches went in one run per method.
    let overlay =
        (job.seed == 0 && placement != Placement::Reference).then(|| runs.join(format!("{}{OVERLAY}", job.id)));
    Ok(RenderJob {
        scene: job.file.clone(),
        load: LoadOptions { resolution: job.resolution, ..LoadOptions::default() },
        settings: RenderSettings {
            seed: job.seed,
            threads,
            integrator: Some(job.application.clone()),
            set: job.set.clone(),
            cache: CacheOverrides {
                placement: Some(placement),
                caches: Some(job.caches),
                subpixels: None,
                target_error: None,
            },
            ..Default::default()
        },
        outputs: Outputs {
            images: vec![runs.join(format!("{}.exr", job.id))],
            overlay,
            dmap: None,
            stats: Some(runs.join(format!("{}.json", job.id))),
        },
    })
}

/// The arguments of `cachert` that render `job` into `out/runs/` (without the program name).
pub fn argv(job: &Job, out: &Path) -> Result<Vec<String>> {
    Ok(render_job(job, out, None)?.argv())
}

/// `s` quoted for a POSIX shell when it needs it.
fn quote(s: &str) -> String {
    if !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "-_./=+:,@%".contains(c)) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// One shell command line running `job` with the program `exe`, its stderr going to `runs/<id>.log`.
pub fn command_line(job: &Job, out: &Path, exe: &str) -> Result<String> {
    let mut line = quote(exe);
    for a in argv(job, out)? {
        line.push(' ');
        line.push_str(&quote(&a));
    }
    let log = out.join(RUNS).join(format!("{}.log", job.id));
    Ok(format!("{line} 2> {}", quote(&log.display().to_string())))
}

/// Whether `job` has finished: its statistics file exists (it is written last, atomically).
pub fn done(job: &Job, out: &Path) -> bool {
    out.join(RUNS).join(format!("{}.json", job.id)).is_file()
}

/// Holds an experiment folder's lock file; removes it when dropped.
#[derive(Debug)]
pub struct Lock(PathBuf);

impl Drop for Lock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// Whether the lock file names a process that no longer runs (known only where `/proc` lists processes):
/// a sweep that was killed leaves its lock behind, and resuming it must not be refused.
fn stale(holder: &str) -> bool {
    let proc = Path::new("/proc");
    match holder.trim().parse::<u32>() {
        Ok(pid) => proc.join("self").exists() && !proc.join(pid.to_string()).exists(),
        Err(_) => false,
    }
}

/// Takes `out`'s lock, or says who holds it. A lock left by a process that no longer runs (an interrupted
/// sweep) is taken over.
pub fn lock(out: &Path) -> Result<Lock> {
    std::fs::create_dir_all(out.join(RUNS)).map_err(|e| Error::file(out, format!("cannot create: {e}")))?;
    let path = out.join(LOCK);
    let mut retried = false;
    loop {
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(mut f) => {
                let _ = std::io::Write::write_all(&mut f, format!("{}\n", std::process::id()).as_bytes());
                return Ok(Lock(path));
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                let holder = std::fs::read_to_string(&path).unwrap_or_default();
                if !retried && stale(&holder) {
                    retried = true;
                    let _ = std::fs::remove_file(&path);
                    continue;
                }
                return Err(Error::file(
                    &path,
                    format!(
                        "another experiment is writing this folder (process {}); if none is, remove this file",
                        holder.trim()
                    ),
                ));
            }
            Err(e) => return Err(Error::file(&path, format!("cannot create the lock file: {e}"))),
        }
    }
}

/// Writes every job of `spec` not yet done in `out` as a command line of `exe` to `path`, one per line;
/// returns how many, and how many baseline jobs not yet done were left out (they render only in the
/// sweep's own process, [`run`]). The jobs are independent: a scheduler may run them in any order, on any
/// machine that sees the same paths.
pub fn emit(spec: &Spec, out: &Path, path: &Path, exe: &str) -> Result<(usize, usize)> {
    std::fs::create_dir_all(out.join(RUNS)).map_err(|e| Error::file(out, format!("cannot create: {e}")))?;
    let todo: Vec<&Job> = spec.jobs.iter().filter(|j| !done(j, out)).collect();
    let lines: Vec<String> =
        todo.iter().filter(|j| j.baseline.is_none()).map(|j| command_line(j, out, exe)).collect::<Result<_>>()?;
    let text: String = lines.iter().map(|l| format!("{l}\n")).collect();
    crate::image::write_bytes(path, text.as_bytes())?;
    Ok((lines.len(), todo.len() - lines.len()))
}

/// Runs `job` in this process (the same render its command line makes; a baseline job as
/// [`super::per_pixel`] renders it), writing its warnings (or its error) to `runs/<id>.log`; returns the
/// error message of a failed run.
fn run_one(job: &Job, out: &Path, threads: Option<usize>) -> std::result::Result<(), String> {
    let mut log = String::new();
    let result = if job.baseline.is_some() {
        super::per_pixel::run(job, out, threads)
    } else {
        let mut warnings = crate::error::Warnings::default();
        let result = render_job(job, out, threads).and_then(|j| j.run(&mut warnings)).map(|_| ());
        for w in warnings.iter() {
            let _ = writeln!(log, "{w}");
        }
        result
    };
    let result = result.map_err(|e| e.to_string());
    if let Err(e) = &result {
        let _ = writeln!(log, "error: {e}");
    }
    let _ = std::fs::write(out.join(RUNS).join(format!("{}.log", job.id)), log);
    result
}

/// The order [`run`] renders `jobs` in: first those whose time no table compares (the references and the
/// converged per-pixel image), then the timed ones with the per-pixel runs spread evenly among the cache runs
/// (each list keeps its own order). The equal-time tables compare seconds measured minutes apart, and the
/// speed of a shared host drifts over minutes (one baseline took 10.7, 12.7 and 14.3 s in three sweeps of
/// `experiments/results/imc-equal-time-sibenik-M-2026-11-30/`); interleaved, both sides of a comparison meet
/// the same drift instead of the per-pixel runs all meeting the start of the sweep and the caches its end.
fn in_run_order(jobs: Vec<&Job>) -> Vec<&Job> {
    let untimed = |j: &Job| j.is_reference() || j.baseline == Some(BaselineRun::Converged);
    let per_pixel = |j: &Job| j.baseline.is_some() || j.samples.is_some();
    let (first, timed): (Vec<&Job>, Vec<&Job>) = jobs.into_iter().partition(|j| untimed(j));
    let (pixels, caches): (Vec<&Job>, Vec<&Job>) = timed.into_iter().partition(|j| per_pixel(j));
    // Item i of a list of n sits at (i + ½) / n of the run: with integers, (2i + 1) · other_len over 2 · n · other_len.
    let (np, nc) = (pixels.len().max(1), caches.len().max(1));
    let mut woven: Vec<(usize, u8, &Job)> =
        pixels.into_iter().enumerate().map(|(i, j)| ((2 * i + 1) * nc, 0, j)).collect();
    woven.extend(caches.into_iter().enumerate().map(|(i, j)| ((2 * i + 1) * np, 1, j)));
    woven.sort_by_key(|&(at, side, _)| (at, side));
    first.into_iter().chain(woven.into_iter().map(|(_, _, j)| j)).collect()
}

/// Runs every job of `spec` not yet done in `out` (holding the folder's lock, with a progress bar over the
/// whole sweep on a terminal), then [`collect`]s. `log` gets one line per job, in the order of
/// [`in_run_order`].
pub fn run(
    spec: &Spec,
    out: &Path,
    threads: Option<usize>,
    log: &mut dyn FnMut(&str),
) -> Result<(Vec<Record>, String)> {
    let _lock = lock(out)?;
    let todo = in_run_order(spec.jobs.iter().filter(|j| !done(j, out)).collect());
    log(&format!("{} jobs, {} done, {} to run", spec.jobs.len(), spec.jobs.len() - todo.len(), todo.len()));
    let bar = if std::io::stderr().is_terminal() {
        indicatif::ProgressBar::new(todo.len() as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("sweep [{bar:40}] {pos}/{len} {elapsed_precise} (eta {eta}) {msg}")
    {
        bar.set_style(style);
    }
    for job in todo {
        bar.set_message(job.id.clone());
        let start = std::time::Instant::now();
        match run_one(job, out, threads) {
            Ok(()) => log(&format!("{}: {:.1} s", job.id, start.elapsed().as_secs_f64())),
            Err(e) => log(&format!("{}: failed: {e}", job.id)),
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    collect(spec, out, log)
}

/// One row of `results.csv`: a run, its settings, what it measured and cost.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Record {
    /// The job id (its files are `runs/<id>.*`).
    pub id: String,
    /// `ok`, `failed` (with `error`) or `missing` (never run, or killed).
    pub status: String,
    /// Why it failed.
    pub error: String,
    /// Scene name.
    pub scene: String,
    /// Application.
    pub application: String,
    /// Placement (`none` for a per-pixel run).
    pub placement: String,
    /// The method's label in tables and charts (`Job::method`).
    pub method: String,
    /// The sample count of a per-pixel run.
    pub samples: Option<u32>,
    /// Budget (0 for a per-pixel run or a baseline).
    pub caches: usize,
    /// Seed.
    pub seed: u64,
    /// Film resolution (the reference's when the spec leaves it to the scene; `None` when unknown).
    pub resolution: Option<[u32; 2]>,
    /// The varied parameters, `k=v;…`.
    pub varied: String,
    /// Every `--set` pair, `k=v;…`.
    pub set: String,
    /// RMSE against the reference.
    pub rmse: f64,
    /// Mean HDR-FLIP against the reference.
    pub flip: f64,
    /// RMSE against the converged per-pixel image (a spec with `baselines`: seed-0 runs and the baselines).
    pub rmse_converged: Option<f64>,
    /// Mean HDR-FLIP against the converged per-pixel image.
    pub flip_converged: Option<f64>,
    /// Stage times in seconds, by the names of the `--stats` report (`total` included).
    pub times: BTreeMap<String, f64>,
    /// Stage-1 and stage-2 caches placed.
    pub caches_placed: [u64; 2],
    /// Rays traced while evaluating caches and while rendering.
    pub rays: [u64; 2],
    /// Peak resident memory of the process, when known.
    pub peak_memory_bytes: Option<u64>,
    /// Bytes of cache records.
    pub record_bytes: u64,
    /// VGC's σ_a in degrees, when VGC placed.
    pub sigma_a_deg: Option<f64>,
    /// Seconds of the reference render.
    pub reference_s: f64,
    /// The reference's mean over every pixel and channel (RMSE over it is the relative RMSE a target error
    /// asks for).
    pub reference_mean: f64,
    /// refine with a target error: its last estimate of the relative RMSE (`--stats`' `error_estimates`).
    pub estimate: Option<f64>,
}

fn read_json(path: &Path) -> Option<serde_json::Value> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

/// The error line of a failed job's log (its last `error:` line), if it has one.
fn failure(out: &Path, job: &Job) -> Option<String> {
    let text = std::fs::read_to_string(out.join(RUNS).join(format!("{}.log", job.id))).ok()?;
    text.lines().rev().find_map(|l| l.strip_prefix("error: ").map(str::to_string))
}

/// A record of `job` with its settings and nothing measured yet.
fn record(job: &Job, status: &str, error: String) -> Record {
    Record {
        id: job.id.clone(),
        status: status.into(),
        error,
        scene: job.scene.clone(),
        application: job.application.clone(),
        placement: job.placement.clone(),
        method: job.method(),
        samples: job.samples,
        caches: if job.samples.is_some() || job.baseline.is_some() { 0 } else { job.caches },
        seed: job.seed,
        resolution: job.resolution,
        varied: job.varied.clone(),
        set: job.set.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(";"),
        rmse: f64::NAN,
        flip: f64::NAN,
        rmse_converged: None,
        flip_converged: None,
        times: BTreeMap::new(),
        caches_placed: [0, 0],
        rays: [0, 0],
        peak_memory_bytes: None,
        record_bytes: 0,
        sigma_a_deg: None,
        reference_s: f64::NAN,
        reference_mean: f64::NAN,
        estimate: None,
    }
}

/// Fills `r` from a run's `--stats` report.
fn fill(r: &mut Record, stats: &serde_json::Value) {
    let s = &stats["stats"];
    if let Some(t) = s["times"].as_object() {
        r.times = t.iter().filter_map(|(k, v)| Some((k.clone(), v.as_f64()?))).collect();
    }
    r.caches_placed = [s["stage1_caches"].as_u64().unwrap_or(0), s["stage2_caches"].as_u64().unwrap_or(0)];
    r.rays = [s["cache_rays"]["total"].as_u64().unwrap_or(0), s["render_rays"]["total"].as_u64().unwrap_or(0)];
    r.peak_memory_bytes = s["peak_memory_bytes"].as_u64();
    r.record_bytes = s["record_bytes"].as_u64().unwrap_or(0);
    r.sigma_a_deg = s["placement"]["sigma_a_deg"].as_f64();
    r.estimate = s["error_estimates"].as_array().and_then(|e| e.last()).and_then(|e| e["relative_rmse"].as_f64());
}

/// A reference image and its seconds, or why there is none.
type Reference = std::result::Result<(Image, f64), String>;

/// The images every run is measured against: per reference id, the reference and, with `baselines`, the
/// converged per-pixel image.
struct References<'a> {
    per_sample: BTreeMap<&'a str, Reference>,
    converged: BTreeMap<&'a str, Image>,
}

impl References<'_> {
    /// Measures `img` against `job`'s reference (and, at seed 0, its converged image) into `r`.
    fn measure(&self, r: &mut Record, job: &Job, img: Result<Image>) {
        let img = match (img, self.per_sample.get(job.reference.as_str())) {
            (_, None) => return (r.status, r.error) = ("failed".into(), "no reference job".into()),
            (_, Some(Err(e))) => return (r.status, r.error) = ("failed".into(), format!("its reference: {e}")),
            (Err(e), _) => return (r.status, r.error) = ("failed".into(), e.to_string()),
            (Ok(img), Some(Ok((reference, secs)))) => {
                r.reference_s = *secs;
                r.reference_mean = reference.mean().iter().sum::<f64>() / 3.0;
                r.resolution = Some([reference.width as u32, reference.height as u32]);
                match compare(&img, reference, &[Metric::Rmse, Metric::Flip]) {
                    Ok(m) => (r.rmse, r.flip) = (m[0].1, m[1].1),
                    Err(e) => return (r.status, r.error) = ("failed".into(), e.to_string()),
                }
                img
            }
        };
        if let Some(conv) = self.converged.get(job.reference.as_str())
            && job.seed == 0
            && job.baseline != Some(BaselineRun::Converged)
            && let Ok(m) = compare(&img, conv, &[Metric::Rmse, Metric::Flip])
        {
            (r.rmse_converged, r.flip_converged) = (Some(m[0].1), Some(m[1].1));
        }
    }
}

/// The records of a baseline job: one per baseline its `.json` lists (`LABEL:N`, or `converged`).
fn baseline_records(job: &Job, stats: &serde_json::Value, runs: &Path, refs: &References) -> Vec<Record> {
    let mut out = Vec::new();
    for b in stats["baselines"].as_array().into_iter().flatten() {
        let label = b["label"].as_str().unwrap_or("baseline");
        let mut r = record(job, "ok", String::new());
        if let Some(BaselineRun::Rays(n)) = job.baseline {
            r.id = format!("{}-{label}", job.id);
            r.method = format!("{label}:{n}");
        }
        let secs = b["seconds"].as_f64().unwrap_or(f64::NAN);
        r.times = [("render".to_string(), secs), ("total".to_string(), secs)].into_iter().collect();
        let img = crate::image::read(&runs.join(super::per_pixel::image_name(job, label)));
        refs.measure(&mut r, job, img);
        out.push(r);
    }
    out
}

/// Measures every run of `spec` found in `out` against its reference and writes `results.csv`,
/// `results.json`, `tables.md`, the charts and `report.html`; returns the records and the first table (which
/// method wins where). Runs that failed or are
/// missing (or whose reference is) are rows with their status and message.
pub fn collect(spec: &Spec, out: &Path, log: &mut dyn FnMut(&str)) -> Result<(Vec<Record>, String)> {
    let runs = out.join(RUNS);
    let mut refs = References { per_sample: BTreeMap::new(), converged: BTreeMap::new() };
    for job in spec.jobs.iter().filter(|j| j.is_reference()) {
        let got = match read_json(&runs.join(format!("{}.json", job.id))) {
            Some(stats) => crate::image::read(&runs.join(format!("{}.exr", job.id)))
                .map(|img| (img, stats["stats"]["times"]["total"].as_f64().unwrap_or(f64::NAN)))
                .map_err(|e| e.to_string()),
            None => Err(failure(out, job).unwrap_or_else(|| "not run".into())),
        };
        refs.per_sample.insert(job.id.as_str(), got);
    }
    for job in spec.jobs.iter().filter(|j| j.baseline == Some(BaselineRun::Converged) && done(j, out)) {
        if let Ok(img) = crate::image::read(&runs.join(format!("{}.exr", job.id))) {
            refs.converged.insert(job.reference.as_str(), img);
        }
    }
    let mut records = Vec::new();
    for job in spec.jobs.iter().filter(|j| !j.is_reference()) {
        let stats = read_json(&runs.join(format!("{}.json", job.id)));
        let mut r = match (&stats, failure(out, job)) {
            (Some(_), _) => record(job, "ok", String::new()),
            (None, Some(e)) => record(job, "failed", e),
            (None, None) => record(job, "missing", "not run (or interrupted)".into()),
        };
        match &stats {
            Some(s) if job.baseline.is_some() => {
                records.extend(baseline_records(job, s, &runs, &refs));
                continue;
            }
            Some(s) => {
                fill(&mut r, s);
                refs.measure(&mut r, job, crate::image::read(&runs.join(format!("{}.exr", job.id))));
            }
            None => {}
        }
        records.push(r);
    }
    let failed = records.iter().filter(|r| r.status != "ok").count();
    log(&format!("collected {} runs ({} ok, {failed} failed or missing)", records.len(), records.len() - failed));
    super::results::write_csv(&records, &out.join(super::results::CSV))?;
    let json =
        serde_json::to_string_pretty(&records).map_err(|e| Error::file(out, format!("cannot encode results: {e}")))?;
    crate::image::write_bytes(&out.join("results.json"), json.as_bytes())?;
    let figures = super::figures::write(&records, out, log)?;
    let tables = super::tables::all(&records);
    super::results::write_tables(&tables, &out.join(TABLES))?;
    let report = super::report::write(spec, &records, &tables, &figures, out)?;
    log(&format!(
        "wrote {}, {TABLES}, {} charts and {}",
        out.join(super::results::CSV).display(),
        figures.len(),
        report.display()
    ));
    // What the command prints: the claims table, the one to read first.
    let summary = tables.first().map_or_else(String::new, |t| t.markdown());
    Ok((records, summary))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shell_quoting_keeps_plain_words_and_quotes_the_rest() {
        assert_eq!(quote("vgc+dgs"), "vgc+dgs");
        assert_eq!(quote("a b"), "'a b'");
        assert_eq!(quote("it's"), "'it'\\''s'");
        assert_eq!(quote(""), "''");
    }

    fn job(id: &str, reference: &str, samples: Option<u32>, baseline: Option<BaselineRun>) -> Job {
        Job {
            id: id.into(),
            scene: "s".into(),
            file: PathBuf::from("s.pbrt"),
            application: "an-application".into(),
            placement: if reference == id || samples.is_some() || baseline.is_some() { "none" } else { "vgc+dgs" }
                .into(),
            caches: 1,
            seed: 0,
            resolution: None,
            set: Vec::new(),
            varied: String::new(),
            reference: reference.into(),
            samples,
            baseline,
        }
    }

    #[test]
    fn the_references_run_first_and_the_per_pixel_runs_spread_among_the_cache_runs() {
        let mut jobs = vec![job("ref", "ref", None, None), job("conv", "ref", None, Some(BaselineRun::Converged))];
        jobs.extend([4, 16, 64, 256].map(|n| job(&format!("bl{n}"), "ref", None, Some(BaselineRun::Rays(n)))));
        jobs.extend((0..9).map(|k| job(&format!("c{k}"), "ref", None, None)));
        jobs.push(job("pp8", "ref", Some(8), None));
        // The reference swapped with a baseline, an order a sweep's spec would not give: the order comes from
        // the kinds, each kind keeping its order in the list.
        jobs.swap(0, 5);
        let order: Vec<&str> = in_run_order(jobs.iter().collect()).iter().map(|j| j.id.as_str()).collect();
        assert_eq!(order[..2], ["conv", "ref"]);
        assert_eq!(order.len(), jobs.len());
        // Five per-pixel runs among nine cache runs: never two in a row, the first after at most one cache run,
        // the last before at most one.
        let timed = &order[2..];
        let pixel = |id: &&str| id.starts_with("bl") || id.starts_with("pp");
        assert!(timed.windows(2).all(|w| !(pixel(&w[0]) && pixel(&w[1]))), "{timed:?}");
        assert!(pixel(&timed[0]) || pixel(&timed[1]), "{timed:?}");
        assert!(pixel(&timed[timed.len() - 1]) || pixel(&timed[timed.len() - 2]), "{timed:?}");
        let pixels: Vec<&str> = timed.iter().copied().filter(pixel).collect();
        assert_eq!(pixels, ["bl256", "bl4", "bl16", "bl64", "pp8"]);
        let caches: Vec<&str> = timed.iter().copied().filter(|id| !pixel(id)).collect();
        assert_eq!(caches, (0..9).map(|k| format!("c{k}")).collect::<Vec<_>>());
    }

    #[test]
    fn a_second_lock_is_refused_until_the_first_is_dropped() {
        let dir = std::env::temp_dir().join(format!("cachert-lock-{}", std::process::id()));
        let first = lock(&dir).unwrap();
        let e = lock(&dir).unwrap_err().to_string();
        assert!(e.contains(LOCK) && e.contains(&std::process::id().to_string()), "{e}");
        drop(first);
        drop(lock(&dir).unwrap());
        // A lock left by a process that no longer runs (beyond any pid_max) is taken over.
        std::fs::write(dir.join(LOCK), "4000000000\n").unwrap();
        let taken = lock(&dir).unwrap();
        assert_eq!(std::fs::read_to_string(dir.join(LOCK)).unwrap().trim(), std::process::id().to_string());
        drop(taken);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
