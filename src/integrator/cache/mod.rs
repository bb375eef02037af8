//! STAGE 7 (integrator): the cache driver — every cache-based integrator, whatever its application, renders
//! through here. [`render_with`] reads the generic parameters ([`settings::PARAMETERS`]) and the
//! application's own (`Application::from_params`), names the scene settings a cache render cannot use, runs
//! the generic driver ([`run::render_cached`]) and reports; `integrator::render` reaches it through the
//! application registry by name ([`CacheRender`]), and a test can call it with an application of its own.
//!
//! Depends on `application` (the trait and registry), `placement`, `cache`, `gbuffer` and `scene`; no module
//! here names a particular application.

pub mod run;
pub mod settings;
pub mod stats;

pub use run::{CachedOutput, render_cached};
pub use settings::{CacheOverrides, CacheSettings, PARAMETERS, Placement};
pub use stats::ScaleReport;

use crate::application::Application;
use crate::application::registry::{APPLICATIONS, WithApplication};
use crate::error::{Result, Warnings};
use crate::gbuffer::scale::{SceneScale, VIEW_FACTOR};
use crate::parse::integrator::json_f32;
use crate::parse::{Named, ParamList};
use crate::scene::{Scene, filter};

use super::{RenderOutput, RenderSettings, render_per_pixel_term};
use crate::parse::integrator::report_unused;
use crate::parse::integrator::{IntegratorParams, help_text};
use crate::render::with_threads;

/// Renders `scene` with cache application `A`: the scene's `Integrator` parameters (when it names `A`)
/// and `settings.set` give both the generic and `A`'s parameters; `settings.cache` wins over them.
pub fn render_with<A: Application>(
    scene: &Scene,
    integrator: Option<&Named>,
    settings: &RenderSettings,
    warnings: &mut Warnings,
) -> Result<RenderOutput> {
    let empty = ParamList::default();
    let params = match integrator {
        Some(n) if n.name == A::NAME => &n.params,
        _ => &empty,
    };
    let p = IntegratorParams::new(A::NAME, params, &settings.set);
    // The one length scale L of this render: the application's defaults, λ and placement all read it.
    let scale = SceneScale::of(scene);
    let app = A::from_params(&p, &scale)?;
    let plan = app.plan();
    let term = plan.added_per_pixel;
    let overrides = cache_sample_settings(scene, params, settings, term.is_some(), warnings);
    let mut cs =
        CacheSettings::from_params(&p, &overrides, scene, scale, A::PAPER_CACHES, settings.seed, settings.progress)?;
    if !plan.dgs_geometry {
        cs.params.dgs.geometry = false;
    }
    let without_caches = plan.shade_by_reference;
    if without_caches.is_some() {
        cs.placement = Placement::Reference;
    }
    p.check_overrides()?;
    report_unused(integrator, A::NAME, &settings.set, warnings);
    let mut run_warnings = Warnings::default();
    let run = || -> Result<CachedOutput> {
        let start = std::time::Instant::now();
        let cx = app.prepare(scene, &mut run_warnings)?;
        let prepare_secs = start.elapsed().as_secs_f64();
        let mut out = render_cached(scene, &app, &cx, &cs)?;
        out.stats.times.prepare = prepare_secs;
        out.stats.times.total += prepare_secs;
        out.stats.prepared = app.prepared_report(&cx).into_iter().map(|(k, v)| (k.to_string(), v)).collect();
        out.stats.scale = Some(scale_report(&cs, &app));
        if let Some(why) = &without_caches {
            out.stats.notes.push(format!("{why}: every sample is shaded without caches (placement none)"));
        }
        if let Some(term) = &term {
            let w = &mut run_warnings;
            let (image, rays, secs) = render_per_pixel_term(scene, term.integrator, &term.set, settings, w)?;
            out.image.add(&image);
            out.stats.render_rays.add(&rays);
            out.stats.times.per_pixel_term = secs;
            out.stats.times.total += secs;
            out.stats.notes.push(format!(
                "the image adds {} ({}) rendered with the scene's Sampler and PixelFilter",
                term.integrator,
                term.set.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", ")
            ));
        }
        Ok(out)
    };
    let out = with_threads(settings.threads, run);
    // Kept whether or not the render succeeded (a failing scene's warnings still say what was read).
    warnings.extend(run_warnings);
    let out = out??;
    let mut rays = out.stats.cache_rays;
    rays.add(&out.stats.render_rays);
    Ok(RenderOutput {
        image: out.image.clone(),
        rays,
        render_secs: out.stats.times.total,
        spp: cs.subpixels,
        integrator: format!("{}, placement {}", A::NAME, cs.placement),
        cache: Some(Box::new(out)),
    })
}

/// The length scale L of a render and the defaults derived from it: λ unless set, and the application's.
fn scale_report<A: Application>(cs: &CacheSettings, app: &A) -> ScaleReport {
    let lambda = cs.params.lambda.is_none().then(|| ("lambda", cs.params.lambda_for(cs.scale.length)));
    let derived = lambda.into_iter().chain(app.scale_derived()).map(|(k, v)| (k.to_string(), json_f32(v))).collect();
    ScaleReport { scale: cs.scale, derived }
}

/// [`render_with`] as a registry visitor: `integrator::render` dispatches an integrator name through it.
pub struct CacheRender<'a, 'w> {
    /// The scene.
    pub scene: &'a Scene,
    /// The scene's `Integrator` directive.
    pub integrator: Option<&'a Named>,
    /// Render settings.
    pub settings: &'a RenderSettings,
    /// Where warnings go.
    pub warnings: &'w mut Warnings,
}

impl WithApplication for CacheRender<'_, '_> {
    type Output = Result<RenderOutput>;
    fn apply<A: Application>(self) -> Result<RenderOutput> {
        render_with::<A>(self.scene, self.integrator, self.settings, self.warnings)
    }
}

/// The parameter tables of every cache-based integrator as plain text (`cachert render --help`).
pub fn help() -> String {
    let mut out = help_text(
        "Parameters of every cache-based integrator (in the scene's Integrator line, or --set NAME=VALUE):",
        PARAMETERS,
    );
    for e in APPLICATIONS {
        out.push('\n');
        out.push_str(&help_text(&format!("{} ({}), its own parameters:", e.name, e.about), e.parameters));
    }
    out.push_str(&format!(
        "(L is the scene's length scale: the diagonal of its bounding box, or {VIEW_FACTOR} times the extent of what \
         the camera sees where that is smaller; README.md, \"Scene scale\".)\n"
    ));
    out
}

/// The sample settings a cache-based render honours and the ones it cannot, said aloud: `--spp` (and
/// `--quick`'s one sample per pixel) become the sub-pixel sample count unless `subpixels` is set; the scene's
/// Sampler and PixelFilter, and the Film's `scale` and `maxsampleluminance`, are not used (the driver shades
/// `subpixels` jittered positions per pixel and averages them), each with a warning where it was written.
/// Returns `settings.cache` with the honoured sub-pixel count added.
fn cache_sample_settings(
    scene: &Scene,
    params: &ParamList,
    settings: &RenderSettings,
    per_pixel_term: bool,
    warnings: &mut Warnings,
) -> CacheOverrides {
    let mut o = settings.cache;
    let subpixels_set = params.get("subpixels").is_some() || settings.set.iter().any(|(k, _)| k == "subpixels");
    let wanted = settings.spp.map(|n| (n, "--spp")).or(settings.quick.then_some((1, "--quick")));
    match wanted {
        Some((n, flag)) if subpixels_set => warnings.general(format!(
            "{flag} ({n} samples per pixel) is not used: \"subpixels\" is set and gives the sub-pixel sample count"
        )),
        Some((n, _)) => o.subpixels = Some(n),
        None => {}
    }
    let per_pixel = "it shades \"subpixels\" jittered positions per pixel (set it, or --spp)";
    // A per-pixel term renders with the scene's Sampler, PixelFilter and Film settings: only the cached
    // part leaves them out.
    if !per_pixel_term {
        if let Some(loc) = &scene.declared.sampler {
            let name = &scene.sampler.name;
            warnings.at(loc, format!("Sampler \"{name}\" is not used by cache-based integrators: {per_pixel}"));
        }
        let box_filter = scene.filter.kind == filter::FilterKind::Box && scene.filter.radius == [0.5, 0.5];
        if let Some(loc) = scene.declared.filter.as_ref().filter(|_| !box_filter) {
            warnings.at(
                loc,
                "PixelFilter is not used by cache-based integrators: the sub-pixel samples of a pixel are averaged (a box filter of radius 0.5)",
            );
        }
    }
    let which = if per_pixel_term { "to the cached light" } else { "by cache-based integrators" };
    if scene.film.scale != 1.0 {
        warnings.general(format!("Film \"scale\" {} is not applied {which}", scene.film.scale));
    }
    if scene.film.max_sample_luminance.is_finite() {
        warnings
            .general(format!("Film \"maxsampleluminance\" {} is not applied {which}", scene.film.max_sample_luminance));
    }
    o
}
