//! `cachert bench`: whole-pipeline figures for the pbrt-v3 reference scenes of `../shared/scenes` — CPU
//! seconds, Mrays/s, the ratio to pbrt-v3's own CPU time for the same image on this machine kind, thread
//! scaling, and the image's distance to pbrt-v3's reference in units of the Monte Carlo noise floor.
//! A benchmark prints figures from one run; it asserts nothing (the machine is shared and noisy).

use std::fmt::Write;
use std::path::PathBuf;
use std::time::Instant;

use crate::error::{Error, Result, Warnings};
use crate::render::{RenderSettings, render};
use crate::scene::{LoadOptions, load};

/// pbrt-v3's user CPU seconds for each `ao-ref.pbrt` (from `../shared/scenes/README.md`).
pub const PBRT_V3_CPU_SECS: [(&str, f64); 4] = [
    ("bitterli-cornell-box-v3", 70.7),
    ("pbrtv3scenes-veach-mis", 49.5),
    ("pbrtv3scenes-buddha-fractal", 166.6),
    ("bitterli-staircase2", 115.8),
];

/// Flags of `cachert bench`.
#[derive(clap::Args, Debug, Clone)]
pub struct BenchArgs {
    /// Folder holding the reference scenes.
    #[arg(long, default_value = "../shared/scenes")]
    pub scenes: PathBuf,
    /// Only scenes whose folder name contains this.
    #[arg(long)]
    pub only: Option<String>,
    /// Worker threads for the main run.
    #[arg(long, default_value_t = 2)]
    pub nthreads: usize,
    /// Also render with one thread and report the speed-up of `--nthreads` over it.
    #[arg(long)]
    pub scaling: bool,
}

/// CPU seconds (user + system) this process has used so far, from /proc (Linux); `None` elsewhere.
fn process_cpu_secs() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let after = stat.rsplit_once(')')?.1;
    let f: Vec<&str> = after.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// Runs the benchmark and returns its table.
pub fn run(args: &BenchArgs) -> Result<String> {
    if !args.scenes.is_dir() {
        return Err(Error::usage(format!("{}: no such folder (pass --scenes)", args.scenes.display())));
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<28} {:>8} {:>9} {:>9} {:>8} {:>10} {:>7} {:>8} {:>10}",
        "scene", "Mrays", "wall s", "cpu s", "Mrays/s", "pbrt cpu s", "ratio", "scaling", "rmse/floor"
    );
    for (name, pbrt) in PBRT_V3_CPU_SECS {
        if args.only.as_deref().is_some_and(|o| !name.contains(o)) {
            continue;
        }
        let dir = args.scenes.join(name);
        let loaded = load(&dir.join("ao-ref.pbrt"), LoadOptions::default())?;
        let mut warnings = Warnings::default();
        let settings = |threads| RenderSettings { threads: Some(threads), ..Default::default() };
        let (cpu0, t0) = (process_cpu_secs(), Instant::now());
        let r = render(&loaded.scene, loaded.integrator.as_ref(), &settings(args.nthreads), &mut warnings)?;
        let wall = t0.elapsed().as_secs_f64();
        let cpu = match (cpu0, process_cpu_secs()) {
            (Some(a), Some(b)) => b - a,
            _ => wall * args.nthreads as f64,
        };
        let scaling = if args.scaling {
            let t1 = Instant::now();
            render(&loaded.scene, loaded.integrator.as_ref(), &settings(1), &mut warnings)?;
            format!("{:.2}x", t1.elapsed().as_secs_f64() / wall)
        } else {
            "-".into()
        };
        let floor_ratio =
            match (crate::image::read(&dir.join("ao-ref.pfm")), crate::image::read(&dir.join("ao-ref-b.pfm"))) {
                (Ok(a), Ok(b)) => {
                    let floor = crate::metrics::rmse(&a, &b)?;
                    format!("{:.3}", crate::metrics::rmse(&r.image, &a)? / floor)
                }
                _ => "-".into(),
            };
        let rays = r.rays.total() as f64 / 1e6;
        let _ = writeln!(
            out,
            "{name:<28} {rays:>8.1} {wall:>9.2} {cpu:>9.2} {:>8.2} {pbrt:>10.1} {:>6.2}x {scaling:>8} {floor_ratio:>10}",
            rays / wall,
            pbrt / cpu
        );
    }
    let _ = write!(
        out,
        "ratio = pbrt-v3 CPU seconds / cachert CPU seconds for the same image (target ≥ 2); scaling = 1-thread wall / {}-thread wall",
        args.nthreads
    );
    Ok(out)
}
