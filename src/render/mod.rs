//! STAGE 6 (render): the per-pixel integrators — `ambientocclusion`, `directlighting` and `path`, chosen by
//! name — and the pixel loop they run in (tiles in parallel, samples keyed by pixel and index, film
//! reconstruction).
//!
//! Depends on `scene` (what to render), `shading`, `sampling`, `parse` (their parameters) and `image`; never
//! on `application`, `placement` or the cache driver (`integrator` dispatches by name above both).

pub mod ambient_occlusion;
pub mod directlighting;
pub mod film;
pub mod path;
mod pixels;

pub use pixels::render_image;

use crate::error::{Error, Result, Warnings};
use crate::parse::integrator::{IntegratorParams, Parameter};
use crate::sampling::pixel_samples::PixelSamples;
use crate::scene::Scene;
use crate::scene::ray::Ray;
use crate::shading::lighting::Scratch;

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

/// The per-pixel integrators cachert implements, by scene-file name (the cache-based ones are the
/// applications of `application::registry`, rendered by `integrator::cache`).
pub const INTEGRATORS: &[&str] = &["ambientocclusion", "directlighting", "path"];

/// Each per-pixel integrator of [`INTEGRATORS`] with its parameter table.
pub const PARAMETERS: &[(&str, &[Parameter])] = &[
    ("ambientocclusion", ambient_occlusion::PARAMETERS),
    ("directlighting", directlighting::PARAMETERS),
    ("path", path::PARAMETERS),
];

/// The per-pixel integrator named `name` with parameters `p`, or `None` when no per-pixel integrator has
/// that name (the caller knows the cache-based names too, and says so).
pub fn per_pixel_integrator<'a>(
    name: &str,
    p: &IntegratorParams<'_>,
    scene: &'a Scene,
    sampler: &crate::scene::sampler::SamplerSpec,
    quick: bool,
    warnings: &mut Warnings,
) -> Result<Option<Box<dyn PixelIntegrator + 'a>>> {
    Ok(Some(match name {
        "ambientocclusion" => Box::new(ambient_occlusion::AmbientOcclusion::from_params(p, sampler, quick)?),
        "directlighting" => Box::new(directlighting::DirectLighting::from_params(p, scene, sampler, quick, warnings)?),
        "path" => Box::new(path::Path::from_params(p, scene, warnings)?),
        _ => return Ok(None),
    }))
}

/// Runs `f` in a pool of `threads` workers (default, or 0 as in pbrt-v3: rayon's global pool, all cores).
pub fn with_threads<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> Result<T> {
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
