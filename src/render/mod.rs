//! STAGE 6: rendering — the pixel loop (tiles in parallel, samples keyed by pixel and index, film
//! reconstruction) and the per-pixel integrators, chosen by name; cache-based integrators come from the
//! application registry and render through [`cache_driver`].
//!
//! Depends on `scene` (what to render), `sampling`, `image` and, for cache-based integrators, `application`;
//! the scene never depends on this module.

pub mod ao;
pub mod cache_driver;
pub mod directlighting;
mod driver;
pub mod film;
pub mod path;

pub use driver::render_image;

use crate::application::registry;
use crate::error::{Error, Result, Warnings};
use crate::image::Image;
use crate::parse::integrator::IntegratorParams;
use crate::parse::{Named, ParamList};
use crate::scene::Scene;
use crate::scene::ray::Ray;
use crate::shading::lighting::Scratch;

use crate::sampling::pixel_samples::PixelSamples;

pub use crate::scene::ray::RayCounters;

/// An integrator that estimates the radiance along one camera ray.
pub trait PixelIntegrator: Sync {
    /// Radiance along `ray`, drawing sample values from `s`; `scratch` is reusable per-thread storage.
    fn li(
        &self,
        scene: &Scene,
        ray: Ray,
        s: &mut PixelSamples,
        scratch: &mut Scratch,
        counters: &mut RayCounters,
    ) -> [f32; 3];
}

/// How to render, beyond what the scene file says.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RenderSettings {
    /// Seed of every random stream.
    pub seed: u64,
    /// Samples per pixel instead of the sampler's.
    pub spp: Option<u32>,
    /// Worker threads (default: all cores).
    pub threads: Option<usize>,
    /// Show a progress bar.
    pub progress: bool,
    /// pbrt-v3's `--quick` (integrator sample counts to 1).
    pub quick: bool,
    /// Integrator name instead of the scene's.
    pub integrator: Option<String>,
    /// Integrator parameters set on the command line (`--set key=value`), overriding the scene's.
    pub set: Vec<(String, String)>,
    /// Typed settings of cache-based integrators (`--placement`, `--caches`), winning over `set`.
    pub cache: cache_driver::CacheOverrides,
}

/// What a render produced.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The cropped image.
    pub image: Image,
    /// Rays traced.
    pub rays: RayCounters,
    /// Wall seconds of the pixel loop.
    pub render_secs: f64,
    /// Samples per pixel used.
    pub spp: u32,
    /// The integrator that ran.
    pub integrator: String,
    /// Cache placement, statistics and maps of a cache-based render.
    pub cache: Option<Box<cache_driver::CachedOutput>>,
}

/// The per-pixel integrators cachert implements, by scene-file name (the cache-based ones are
/// `application::registry::APPLICATIONS`).
pub const INTEGRATORS: &[&str] = &["ambientocclusion", "directlighting", "path"];

/// Every integrator name, per-pixel then cache-based, comma-separated (for messages).
pub fn integrator_names() -> String {
    let cached = registry::APPLICATIONS.iter().map(|e| e.name);
    INTEGRATORS.iter().copied().chain(cached).collect::<Vec<_>>().join(", ")
}

/// Builds the integrator named by the scene (or by `settings.integrator`) and renders.
pub fn render(
    scene: &Scene,
    integrator: Option<&Named>,
    settings: &RenderSettings,
    warnings: &mut Warnings,
) -> Result<RenderOutput> {
    let empty = ParamList::default();
    let scene_name = integrator.map_or("path", |n| n.name.as_str());
    let name = settings.integrator.as_deref().unwrap_or(scene_name);
    // Parameters written for another integrator do not apply to an override.
    let params = match integrator {
        Some(n) if n.name == name => &n.params,
        _ => &empty,
    };
    let mut sampler = scene.sampler.clone();
    if let Some(spp) = settings.spp {
        if spp == 0 {
            return Err(Error::usage("--spp must be at least 1"));
        }
        sampler.spp = spp;
    }
    if let Some(n) = integrator.filter(|n| n.name != name && !n.params.is_empty()) {
        warnings.at(
            &n.name_loc,
            format!(
                "Integrator \"{}\" is replaced by --integrator {name}; its parameters ({}) are not used",
                n.name,
                n.params.iter().map(|p| p.name.as_str()).collect::<Vec<_>>().join(", ")
            ),
        );
    }
    let cache = cache_driver::CacheRender { scene, integrator, settings, warnings: &mut *warnings };
    if let Some(out) = registry::dispatch(name, cache) {
        return out;
    }
    if settings.cache != cache_driver::CacheOverrides::default() {
        return Err(Error::usage(format!(
            "--placement and --caches apply to cache-based integrators ({}), not to \"{name}\"",
            registry::names()
        )));
    }
    let iparams = IntegratorParams::new(params, &settings.set);
    let pixel = per_pixel_integrator(name, &iparams, scene, &sampler, settings.quick, warnings)?;
    iparams.check_overrides(name)?;
    report_unused(integrator, name, &settings.set, warnings);
    let run = || render_image(scene, &sampler, pixel.as_ref(), settings.seed, settings.progress);
    let (image, rays, render_secs) = with_threads(settings.threads, run)?;
    Ok(RenderOutput { image, rays, render_secs, spp: sampler.spp, integrator: name.to_string(), cache: None })
}

/// The per-pixel integrator named `name` with parameters `p`.
fn per_pixel_integrator<'a>(
    name: &str,
    p: &IntegratorParams<'_>,
    scene: &'a Scene,
    sampler: &crate::scene::sampler::SamplerSpec,
    quick: bool,
    warnings: &mut Warnings,
) -> Result<Box<dyn PixelIntegrator + 'a>> {
    Ok(match name {
        "ambientocclusion" => Box::new(ao::AmbientOcclusion::from_params(p, sampler, quick)?),
        "directlighting" => Box::new(directlighting::DirectLighting::from_params(p, scene, sampler, quick, warnings)?),
        "path" => Box::new(path::Path::from_params(p, scene, warnings)?),
        other => {
            return Err(Error::usage(format!(
                "integrator \"{other}\" is not implemented by cachert (available: {}); choose one with --integrator",
                integrator_names()
            )));
        }
    })
}

/// Renders the per-pixel integrator `name` with parameters `set` only (the scene's `Integrator` line is
/// not read) with the scene's Sampler and PixelFilter — `--spp` and `--quick` apply — for a cache
/// application's per-pixel term. Runs in the current thread pool; returns the image, rays and wall time.
pub(crate) fn render_per_pixel_term(
    scene: &Scene,
    name: &str,
    set: &[(String, String)],
    settings: &RenderSettings,
    warnings: &mut Warnings,
) -> Result<(Image, RayCounters, f64)> {
    let mut sampler = scene.sampler.clone();
    if let Some(spp) = settings.spp.filter(|&n| n > 0) {
        sampler.spp = spp;
    }
    let empty = ParamList::default();
    let iparams = IntegratorParams::new(&empty, set);
    let pixel = per_pixel_integrator(name, &iparams, scene, &sampler, settings.quick, warnings)?;
    Ok(render_image(scene, &sampler, pixel.as_ref(), settings.seed, settings.progress))
}

/// Runs `f` in a pool of `threads` workers (default, or 0 as in pbrt-v3: rayon's global pool, all cores).
pub(crate) fn with_threads<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> Result<T> {
    match threads.filter(|&n| n > 0) {
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| Error::usage(format!("cannot start {n} threads: {e}")))?;
            Ok(pool.install(f))
        }
        None => Ok(f()),
    }
}

/// Warns about Integrator parameters that the integrator did not read.
pub(crate) fn report_unused(integrator: Option<&Named>, name: &str, set: &[(String, String)], warnings: &mut Warnings) {
    if let Some(n) = integrator.filter(|n| n.name == name) {
        for p in n.params.unused() {
            // A parameter replaced by --set was not read because the command line won, not because it is unknown.
            if p.name == "pixelbounds" {
                warnings.at(
                    &p.loc,
                    "Integrator: \"pixelbounds\" is not supported; the whole film is rendered (Film \"cropwindow\" restricts it)",
                );
            } else if !set.iter().any(|(k, _)| *k == p.name) {
                warnings.at(&p.loc, format!("Integrator: unused parameter \"{} {}\"", p.ty.word(), p.name));
            }
        }
    }
}
