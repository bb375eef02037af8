//! `cachert render`: load a scene, render it with its integrator (or `--integrator`), write the image
//! atomically, and print the time of each stage and the ray throughput.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use crate::application::registry;
use crate::error::Result;
use crate::integrator::cache::{CacheOverrides, Placement};
use crate::integrator::{RenderSettings, render};
use crate::scene::{LoadOptions, load};

/// Flags of `cachert render`.
#[derive(clap::Args, Debug, Clone)]
#[command(after_long_help = crate::integrator::cache::help())]
pub struct RenderArgs {
    /// The pbrt-v3 scene file.
    pub scene: PathBuf,
    /// Output image (.exr float RGB, .pfm float32, .png 8-bit sRGB preview); default: the Film's
    /// "filename", else the scene's name with .exr, in the current directory.
    #[arg(long)]
    pub outfile: Option<PathBuf>,
    /// Worker threads (default, or 0 as in pbrt-v3: all cores). The image does not depend on it.
    #[arg(long)]
    pub nthreads: Option<usize>,
    /// Samples per pixel, overriding the scene's Sampler.
    #[arg(long)]
    pub spp: Option<u32>,
    /// Seed of every random stream: the same seed gives the same image, bit for bit.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Film resolution WxH instead of the scene's (the screen window follows the new aspect ratio).
    #[arg(long, value_parser = super::parse_resolution)]
    pub resolution: Option<[u32; 2]>,
    /// pbrt-v3's --quick: resolution ÷ 4, one pixel sample, one integrator sample.
    #[arg(long)]
    pub quick: bool,
    /// No progress bar and no summary (warnings still go to stderr).
    #[arg(long)]
    pub quiet: bool,
    /// Integrator to use instead of the scene's (e.g. ambientocclusion, or a cache-based one; see below).
    #[arg(long)]
    pub integrator: Option<String>,
    /// Cache-based integrators: the placement strategy (the parameter "placement"): none, im, sd, sd+as,
    /// vgc, vgc+dgs, vgc+as, vgc+dgs:diff, vgc+dgs:geom.
    #[arg(long, value_parser = parse_placement)]
    pub placement: Option<Placement>,
    /// Cache-based integrators: the total cache budget (the parameter "caches").
    #[arg(long)]
    pub caches: Option<usize>,
    /// Cache-based renders: write the image with stage-1 caches (red) and stage-2 caches (cyan) marked.
    #[arg(long)]
    pub overlay: Option<PathBuf>,
    /// Cache-based renders: write the DGS discontinuity map (EXR/PFM, plus a PNG preview).
    #[arg(long)]
    pub dmap: Option<PathBuf>,
    /// Cache-based renders: write per-stage times, cache counts, search results, rays and memory as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Set an integrator parameter, overriding the scene file (repeatable), e.g. --set nsamples=16.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = super::parse_key_value)]
    pub set: Vec<(String, String)>,
}

fn parse_placement(s: &str) -> std::result::Result<Placement, String> {
    Placement::parse(s.trim()).map_err(|e| e.to_string())
}

/// Runs `cachert render`; returns the summary to print (empty with --quiet) and the warnings, already printed.
pub fn run(args: &RenderArgs) -> Result<String> {
    execute(args, &mut print_warnings)
}

/// [`run`] with the warnings handed to `warn` instead of printed (an experiment keeps them in each run's
/// log). The render is exactly the one the same command line makes.
pub fn execute(args: &RenderArgs, warn: &mut dyn FnMut(&crate::error::Warnings)) -> Result<String> {
    let loaded = load(&args.scene, LoadOptions { quick: args.quick, resolution: args.resolution })?;
    let mut warnings = loaded.warnings.clone();
    let settings = RenderSettings {
        seed: args.seed,
        spp: args.spp,
        threads: args.nthreads,
        progress: !args.quiet && std::io::stderr().is_terminal() && std::io::stdout().is_terminal(),
        quick: args.quick,
        integrator: args.integrator.clone(),
        set: args.set.clone(),
        cache: CacheOverrides { placement: args.placement, caches: args.caches, subpixels: None },
    };
    // Settle the output name before rendering, so a bad extension fails fast.
    let out = output_path(args, &loaded.scene.film.filename);
    crate::image::Format::from_path(&out)?;
    let result = render(&loaded.scene, loaded.integrator.as_ref(), &settings, &mut warnings);
    warn(&warnings);
    let result = result?;
    // Check every requested output before writing any, so a failed run leaves nothing behind.
    let cache = result.cache.as_deref();
    if (args.overlay.is_some() || args.dmap.is_some() || args.stats.is_some()) && cache.is_none() {
        return Err(crate::Error::usage(format!(
            "--overlay, --dmap and --stats need a cache-based integrator (--integrator with one of: {})",
            registry::names()
        )));
    }
    if args.dmap.is_some() && cache.is_some_and(|c| c.discontinuity.is_none()) {
        return Err(crate::Error::usage(
            "--dmap: this placement has no discontinuity map (use vgc+dgs or one of its ablations)",
        ));
    }
    for p in [&args.overlay, &args.dmap].into_iter().flatten() {
        crate::image::Format::from_path(p)?;
    }
    crate::image::write(&result.image, &out)?;
    if let Some(c) = cache {
        if let Some(p) = &args.overlay {
            crate::cli::cache_outputs::write_overlay(c, p)?;
        }
        if let Some(p) = &args.dmap {
            crate::cli::cache_outputs::write_dmap(c, p)?;
        }
        if let Some(p) = &args.stats {
            let settings = serde_json::json!({
                "scene": args.scene.display().to_string(),
                "integrator": result.integrator,
                "seed": args.seed,
                "set": args.set.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>(),
                "parameters": c.settings,
            });
            crate::cli::cache_outputs::write_stats(c, &settings, p)?;
        }
    }
    if args.quiet {
        return Ok(String::new());
    }
    if let Some(c) = cache {
        let rays = result.rays.total() as f64;
        return Ok(format!(
            "wrote {} ({}x{}, {} sub-pixel samples, {})\nparse {:.3} s | scene build {:.3} s | BVH build {:.3} s\n{}\nrays {:.1} M: {:.2} Mrays/s",
            out.display(),
            result.image.width,
            result.image.height,
            result.spp,
            result.integrator,
            loaded.stats.parse_secs,
            loaded.stats.build_secs,
            loaded.stats.bvh_secs,
            c.stats.summary(),
            rays / 1e6,
            rays / 1e6 / c.stats.times.total.max(1e-9)
        ));
    }
    let s = &loaded.stats;
    let rays = result.rays.total() as f64;
    Ok(format!(
        "wrote {} ({}x{}, {} spp, {})\n\
         parse {:.3} s | scene build {:.3} s | BVH build {:.3} s | render {:.3} s\n\
         rays {:.1} M (camera {:.2} M, occlusion {:.2} M): {:.2} Mrays/s",
        out.display(),
        result.image.width,
        result.image.height,
        result.spp,
        result.integrator,
        s.parse_secs,
        s.build_secs,
        s.bvh_secs,
        result.render_secs,
        rays / 1e6,
        result.rays.camera as f64 / 1e6,
        result.rays.shadow as f64 / 1e6,
        rays / 1e6 / result.render_secs.max(1e-9),
    ))
}

/// Prints warnings to stderr, one per line.
pub fn print_warnings(w: &crate::error::Warnings) {
    for w in w.iter() {
        eprintln!("{w}");
    }
}

fn output_path(args: &RenderArgs, film_name: &Option<PathBuf>) -> PathBuf {
    if let Some(o) = &args.outfile {
        return o.clone();
    }
    if let Some(f) = film_name {
        return f.clone();
    }
    let stem = args.scene.file_stem().unwrap_or(Path::new("cachert").as_os_str());
    PathBuf::from(stem).with_extension("exr")
}
