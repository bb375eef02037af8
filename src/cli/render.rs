//! `cachert render`: the flags become a render job (`job::RenderJob`: load a scene, render it with its
//! integrator or `--integrator`, write the image atomically), then the time of each stage and the ray
//! throughput are printed.

use std::io::IsTerminal;
use std::path::PathBuf;

use crate::error::Result;
use crate::integrator::RenderSettings;
use crate::integrator::cache::{CacheOverrides, Placement};
use crate::job::{Outputs, RenderJob};
use crate::scene::{CropWindow, LoadOptions};

/// Flags of `cachert render`.
#[derive(clap::Args, Debug, Clone)]
#[command(after_long_help = crate::integrator::cache::help())]
pub struct RenderArgs {
    /// The pbrt-v3 scene file.
    pub scene: PathBuf,
    /// Output image (.exr float RGB, .pfm float32, .png 8-bit sRGB preview); repeat it to write the same
    /// image in several files (--outfile a.exr --outfile a.png); default: the Film's "filename", else the
    /// scene's name with .exr, in the current directory.
    #[arg(long)]
    pub outfile: Vec<PathBuf>,
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
    /// Render only this part of the film, as pbrt-v3's --cropwindow: fractions x0,x1,y0,y1 (replacing the
    /// Film's "cropwindow"); an EXR output keeps the full film as its display window and the crop as its
    /// data window.
    #[arg(long, visible_alias = "cropwindow", value_name = "X0,X1,Y0,Y1", value_parser = CropWindow::parse)]
    pub crop: Option<CropWindow>,
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
    /// vgc, vgc+dgs, refine, vgc+as, vgc+dgs:diff, vgc+dgs:geom.
    #[arg(long, value_parser = parse_placement)]
    pub placement: Option<Placement>,
    /// Cache-based integrators: the total cache budget (the parameter "caches").
    #[arg(long, allow_negative_numbers = true, value_parser = super::parse_caches)]
    pub caches: Option<usize>,
    /// refine: place caches until its own estimate of the relative RMSE against the per-sample reference
    /// is this (e.g. 0.05; the parameter "targeterror"); the budget becomes a ceiling.
    #[arg(long, value_name = "E", allow_negative_numbers = true, value_parser = super::parse_target_error)]
    pub target_error: Option<f64>,
    /// Cache-based renders: write the image with stage-1 caches (red) and stage-2 caches (cyan) marked.
    #[arg(long)]
    pub overlay: Option<PathBuf>,
    /// Cache-based renders: write the DGS discontinuity map (EXR/PFM, plus a PNG preview).
    #[arg(long)]
    pub dmap: Option<PathBuf>,
    /// Cache-based renders: write per-stage times, cache counts, search results, rays and memory as JSON
    /// (`-`: to standard output).
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Set an integrator parameter, overriding the scene file (repeatable), e.g. --set nsamples=16.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = super::parse_key_value)]
    pub set: Vec<(String, String)>,
}

fn parse_placement(s: &str) -> std::result::Result<Placement, String> {
    Placement::parse(s.trim()).map_err(|e| e.to_string())
}

/// Runs `cachert render`, printing each warning and note to stderr as it is found (the scene's before the
/// first pixel); returns the summary to print (empty with --quiet).
pub fn run(args: &RenderArgs) -> Result<String> {
    let mut warnings = crate::error::Warnings::printing(|w| eprintln!("{w}"));
    let finished = job(args).run(&mut warnings)?;
    Ok(if args.quiet { String::new() } else { finished.summary() })
}

/// The render job the flags describe.
pub fn job(args: &RenderArgs) -> RenderJob {
    RenderJob {
        scene: args.scene.clone(),
        load: LoadOptions { quick: args.quick, resolution: args.resolution, crop: args.crop },
        settings: RenderSettings {
            seed: args.seed,
            spp: args.spp,
            threads: args.nthreads,
            progress: !args.quiet && std::io::stderr().is_terminal() && std::io::stdout().is_terminal(),
            quick: args.quick,
            integrator: args.integrator.clone(),
            set: args.set.clone(),
            cache: CacheOverrides {
                placement: args.placement,
                caches: args.caches,
                subpixels: None,
                target_error: args.target_error,
            },
        },
        outputs: Outputs {
            images: args.outfile.clone(),
            overlay: args.overlay.clone(),
            dmap: args.dmap.clone(),
            stats: args.stats.clone(),
        },
    }
}
