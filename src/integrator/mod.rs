//! STAGE 7 (integrator): every integrator by name — the per-pixel ones of `render` and the cache-based ones,
//! each application of `application::registry` rendered by the one generic cache driver ([`cache`]) — with
//! the settings a render takes beyond the scene file ([`RenderSettings`]) and what it produced
//! ([`RenderOutput`]). [`render`] is the one by-name dispatch that the command line, the goldens and the
//! experiments call; [`dry_run`] goes the same way up to the first pixel, for the warnings `cachert info`
//! lists.
//!
//! Depends on `render`, `application`, `placement`, `cache`, `gbuffer`, `shading`, `scene` and `parse`;
//! only the studies (`golden`, `experiment`) and the command line depend on it.

pub mod cache;

use crate::application::registry;
use crate::error::{Error, Result, Warnings};
use crate::image::Image;
use crate::parse::integrator::{IntegratorParams, report_unused};
use crate::parse::{Named, ParamList};
use crate::render::film::apply_scale;
use crate::render::{INTEGRATORS, RayCounters, per_pixel_integrator, render_image, with_threads};
use crate::scene::Scene;

/// How to render, beyond what the scene file says.
#[derive(Clone, Debug, Default, PartialEq)]
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
    pub cache: cache::CacheOverrides,
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
    pub cache: Option<Box<cache::CachedOutput>>,
}

/// Every integrator name, per-pixel then cache-based, comma-separated (for messages).
pub fn integrator_names() -> String {
    let cached = registry::APPLICATIONS.iter().map(|e| e.name);
    INTEGRATORS.iter().copied().chain(cached).collect::<Vec<_>>().join(", ")
}

/// The error for an integrator name that is neither per-pixel nor cache-based.
fn not_implemented(name: &str) -> Error {
    Error::usage(format!(
        "integrator \"{name}\" is not implemented by cachert (available: {}); choose one with --integrator",
        integrator_names()
    ))
}

/// How far [`render`]'s one code path goes: the whole render, or everything before the first pixel (reading
/// parameters, building the integrator and its shading data, a cache application's preparation) for the
/// warnings and errors that gives ([`dry_run`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// Render the image.
    Render,
    /// Stop before the first pixel (or cache) is shaded.
    DryRun,
}

/// Builds the integrator named by the scene (or by `settings.integrator`) and renders. The image has the
/// Film's `scale` and `maxsampleluminance` applied (`render::film`), whichever integrator made it.
pub fn render(
    scene: &Scene,
    integrator: Option<&Named>,
    settings: &RenderSettings,
    warnings: &mut Warnings,
) -> Result<RenderOutput> {
    let out = render_pass(scene, integrator, settings, warnings, Pass::Render)?;
    Ok(out.expect("a render pass returns an image"))
}

/// Every warning that [`render`] would give for the same scene, `Integrator` directive and settings (the
/// integrator's own: parameters unused or replaced, scene settings it cannot use, its shading set-up's),
/// and every error it would give before its first pixel, without rendering: the same code path as
/// [`render`], stopped before shading ([`Pass::DryRun`]), so the two cannot drift apart. The scene's own
/// warnings (from loading) are not added here: they come with the loaded scene.
pub fn dry_run(
    scene: &Scene,
    integrator: Option<&Named>,
    settings: &RenderSettings,
    warnings: &mut Warnings,
) -> Result<()> {
    render_pass(scene, integrator, settings, warnings, Pass::DryRun).map(|_| ())
}

/// A pbrt-v3 integrator cachert does not have, rendered by one it has whose image is the same in
/// expectation (only the noise differs), with a note that says so.
#[derive(Clone, Copy, Debug)]
pub struct StandIn {
    /// pbrt-v3's name.
    pub pbrt: &'static str,
    /// The integrator that renders it; it reads the line's parameters (those it does not know are
    /// warned about as unused).
    pub cachert: &'static str,
    /// Why the image is the same.
    pub why: &'static str,
}

/// Every pbrt-v3 integrator cachert renders with another of its own (the table of docs/supported.md).
pub const STAND_INS: &[StandIn] = &[
    StandIn {
        pbrt: "volpath",
        cachert: "path",
        why: "without participating media (which cachert ignores, with a warning) pbrt-v3's volpath is path",
    },
    StandIn {
        pbrt: "bdpt",
        cachert: "path",
        why: "bidirectional path tracing with the same maxdepth converges to path's image; only the noise differs",
    },
    StandIn {
        pbrt: "mlt",
        cachert: "path",
        why: "Metropolis light transport with the same maxdepth converges to path's image; only the noise differs",
    },
    StandIn {
        pbrt: "sppm",
        cachert: "path",
        why: "stochastic progressive photon mapping converges to path's image as its radius shrinks; only the noise \
              and the photon blur differ",
    },
    StandIn {
        pbrt: "whitted",
        cachert: "directlighting",
        why: "Whitted ray tracing (every light sampled, specular reflection and transmission to maxdepth) has \
              directlighting's image; only the noise differs",
    },
];

/// pbrt-v3 integrators whose `maxdepth` is the length of a light path (`volpath` without media is `path`).
const PATH_LIKE: &[&str] = &["path", "volpath", "bdpt", "mlt", "sppm"];

/// The light-path depth a cache integrator `name` takes from the scene's path-like integrator that it
/// replaces: its [`Application::PATH_DEPTH`](crate::application::Application::PATH_DEPTH) parameter set to
/// `maxdepth` − 1 (pbrt-v3's default `maxdepth` 5 when the line has none), within the parameter's range
/// 0–64; `None` when the parameter is set with `--set`, the application has no such parameter, or the
/// scene's integrator is not path-like.
fn inherited_depth(integrator: Option<&Named>, name: &str, settings: &RenderSettings) -> Option<(String, String)> {
    let n = integrator.filter(|n| n.name != name && PATH_LIKE.contains(&n.name.as_str()))?;
    let key = registry::entry(name)?.path_depth?;
    if settings.set.iter().any(|(k, _)| k == key) {
        return None;
    }
    let maxdepth = n.params.int("maxdepth").ok().flatten().unwrap_or(5);
    Some((key.to_string(), (maxdepth.saturating_sub(1)).clamp(0, 64).to_string()))
}

/// [`render`] or [`dry_run`]: `None` for a dry run.
fn render_pass(
    scene: &Scene,
    integrator: Option<&Named>,
    settings: &RenderSettings,
    warnings: &mut Warnings,
    pass: Pass,
) -> Result<Option<RenderOutput>> {
    let empty = ParamList::default();
    let scene_name = integrator.map_or("path", |n| n.name.as_str());
    let stand_in = STAND_INS.iter().find(|s| s.pbrt == scene_name && settings.integrator.is_none());
    let name = settings.integrator.as_deref().or(stand_in.map(|s| s.cachert)).unwrap_or(scene_name);
    if let (Some(s), Some(n)) = (stand_in, integrator) {
        warnings.note_at(&n.name_loc, format!("Integrator \"{}\" is rendered by \"{}\": {}", s.pbrt, s.cachert, s.why));
    }
    // Parameters written for another integrator do not apply to an override.
    let params = match integrator {
        Some(n) if n.name == name || stand_in.is_some() => &n.params,
        _ => &empty,
    };
    let mut sampler = scene.sampler.clone();
    if let Some(spp) = settings.spp {
        if spp == 0 {
            return Err(Error::usage("--spp must be at least 1"));
        }
        sampler.spp = spp;
    }
    let depth = inherited_depth(integrator, name, settings);
    if let Some(n) = integrator.filter(|n| n.name != name && stand_in.is_none() && !n.params.is_empty()) {
        let unused: Vec<&str> =
            n.params.iter().map(|p| p.name.as_str()).filter(|&p| depth.is_none() || p != "maxdepth").collect();
        let carried = depth.as_ref().map(|(k, v)| format!("its \"maxdepth\" gives {name}'s \"{k}\" {v}"));
        let unused = (!unused.is_empty()).then(|| format!("its parameters ({}) are not used", unused.join(", ")));
        let what = carried.into_iter().chain(unused).collect::<Vec<_>>().join("; ");
        warnings.note_at(&n.name_loc, format!("Integrator \"{}\" is replaced by --integrator {name}; {what}", n.name));
    }
    let with_depth;
    let settings = match depth {
        Some(kv) => {
            with_depth = RenderSettings {
                set: std::iter::once(kv).chain(settings.set.iter().cloned()).collect(),
                ..settings.clone()
            };
            &with_depth
        }
        None => settings,
    };
    let cache = cache::CacheRender { scene, integrator, settings, warnings: &mut *warnings, pass };
    if let Some(out) = registry::dispatch(name, cache) {
        return out;
    }
    if settings.cache != cache::CacheOverrides::default() {
        return Err(Error::usage(format!(
            "--placement and --caches apply to cache-based integrators ({}), not to \"{name}\"",
            registry::names()
        )));
    }
    let iparams = IntegratorParams::new(name, params, &settings.set);
    let pixel = per_pixel_integrator(name, &iparams, scene, &sampler, settings.quick, warnings)?
        .ok_or_else(|| not_implemented(name))?;
    iparams.check_overrides()?;
    report_unused(
        integrator,
        integrator.filter(|_| stand_in.is_some()).map_or(name, |n| &n.name),
        &settings.set,
        warnings,
    );
    if pass == Pass::DryRun {
        return Ok(None);
    }
    let run = || render_image(scene, &sampler, pixel.as_ref(), settings.seed, settings.progress);
    let (mut image, rays, render_secs) = with_threads(settings.threads, run)?;
    apply_scale(&mut image, &scene.film);
    let integrator = name.to_string();
    Ok(Some(RenderOutput { image, rays, render_secs, spp: sampler.spp, integrator, cache: None }))
}

/// Renders the per-pixel integrator `name` with parameters `set` only (the scene's `Integrator` line is
/// not read) with the scene's Sampler and PixelFilter — `--spp` and `--quick` apply — for a cache
/// application's per-pixel term. Runs in the current thread pool; returns the image, rays and wall time
/// (`None` for a dry run, which only builds the integrator, for its warnings and errors).
/// Its samples are clamped to the Film's `maxsampleluminance`; the image is not scaled by the Film's
/// `scale`, which the cache driver applies once to the sum.
pub(crate) fn render_per_pixel_term(
    scene: &Scene,
    name: &str,
    set: &[(String, String)],
    settings: &RenderSettings,
    warnings: &mut Warnings,
    pass: Pass,
) -> Result<Option<(Image, RayCounters, f64)>> {
    let mut sampler = scene.sampler.clone();
    if let Some(spp) = settings.spp.filter(|&n| n > 0) {
        sampler.spp = spp;
    }
    let empty = ParamList::default();
    let iparams = IntegratorParams::new(name, &empty, set);
    let pixel = per_pixel_integrator(name, &iparams, scene, &sampler, settings.quick, warnings)?
        .ok_or_else(|| not_implemented(name))?;
    if pass == Pass::DryRun {
        return Ok(None);
    }
    Ok(Some(render_image(scene, &sampler, pixel.as_ref(), settings.seed, settings.progress)))
}
