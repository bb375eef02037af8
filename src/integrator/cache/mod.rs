//! STAGE 7 (integrator): the cache driver — every cache-based integrator, whatever its application, renders
//! through here. [`render_with`] reads the generic parameters ([`settings::PARAMETERS`]) and the
//! application's own (`Application::from_params`), names the scene settings a cache render cannot use, runs
//! the generic driver ([`run::render_cached`]) and reports; `integrator::render` reaches it through the
//! application registry by name ([`CacheRender`]), and a test can call it with an application of its own.
//!
//! Depends on `application` (the trait and registry), `placement`, `cache`, `gbuffer` and `scene`; no module
//! here names a particular application.

pub mod camera_path;
pub mod run;
pub mod settings;
pub mod stats;

pub use run::{CachedOutput, render_cached};
pub use settings::{CacheOverrides, CacheSettings, PARAMETERS, Placement};
pub use stats::ScaleReport;

use crate::application::registry::{APPLICATIONS, WithApplication};
use crate::application::{Application, PerPixelTerm};
use crate::error::{Result, Warnings};
use crate::gbuffer::scale::{SceneScale, VIEW_FACTOR};
use crate::image::Image;
use crate::parse::integrator::json_f32;
use crate::parse::{Named, ParamList};
use crate::scene::ray::RayCounters;
use crate::scene::{Scene, filter};

use super::{Pass, RenderOutput, RenderSettings, render_per_pixel_term};
use crate::parse::integrator::report_unused;
use crate::parse::integrator::{IntegratorParams, help_text};
use crate::render::film::apply_scale;
use crate::render::with_threads;

/// Renders `scene` with cache application `A`: the scene's `Integrator` parameters (when it names `A`)
/// and `settings.set` give both the generic and `A`'s parameters; `settings.cache` wins over them. Every
/// sample is clamped to the Film's `maxsampleluminance` and the finished image (with `A`'s per-pixel term,
/// if it adds one) is multiplied by the Film's `scale` once, as for the per-pixel integrators.
pub fn render_with<A: Application>(
    scene: &Scene,
    integrator: Option<&Named>,
    settings: &RenderSettings,
    warnings: &mut Warnings,
) -> Result<RenderOutput> {
    let out = render_pass::<A>(scene, integrator, settings, warnings, Pass::Render)?;
    Ok(out.expect("a render pass returns an image"))
}

/// [`render_with`], or for [`Pass::DryRun`] the same steps up to shading — parameters, the settings a
/// cache render cannot use, `A`'s preparation and its per-pixel term's integrator — for their warnings
/// and errors, returning `None`.
fn render_pass<A: Application>(
    scene: &Scene,
    integrator: Option<&Named>,
    settings: &RenderSettings,
    warnings: &mut Warnings,
    pass: Pass,
) -> Result<Option<RenderOutput>> {
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
        CacheSettings::from_params(&p, &overrides, scene, scale, A::DEFAULT_CACHES, settings.seed, settings.progress)?;
    if !plan.dgs_geometry {
        cs.params.dgs.geometry = false;
    }
    cs.params.refine_misses = plan.refine_misses;
    let without_caches = plan.shade_by_reference;
    if without_caches.is_some() {
        cs.placement = Placement::Reference;
    }
    p.check_overrides()?;
    report_unused(integrator, A::NAME, &settings.set, warnings);
    let mut run_warnings = Warnings::default();
    let run = || -> Result<Option<CachedOutput>> {
        let start = std::time::Instant::now();
        let cx = app.prepare(scene, &mut run_warnings)?;
        let prepare_secs = start.elapsed().as_secs_f64();
        // With a target error the per-pixel term renders first: the relative error refine aims at is the
        // whole image's, whose mean includes the term (the term itself is the same in the reference).
        let mut early = None;
        let mut cs = cs.clone();
        if let (Some(term), Some(target), Pass::Render) = (&term, &mut cs.params.target, pass) {
            let w = &mut run_warnings;
            early = render_per_pixel_term(scene, term.integrator, &term.set, settings, w, pass)?;
            if let Some((image, _, _)) = &early {
                target.added_mean = (image.mean().iter().sum::<f64>() / 3.0) as f32;
            }
        }
        let mut out = match pass {
            Pass::Render => Some(render_cached(scene, &app, &cx, &cs)?),
            Pass::DryRun => None,
        };
        if let Some(out) = &mut out {
            out.stats.times.prepare = prepare_secs;
            out.stats.times.total += prepare_secs;
            out.stats.prepared = app.prepared_report(&cx).into_iter().map(|(k, v)| (k.to_string(), v)).collect();
            out.stats.scale = Some(scale_report(&cs, &app));
            if let Some(why) = &without_caches {
                out.stats.notes.push(format!("{why}: every sample is shaded without caches (placement none)"));
            }
        }
        // Both parts clamp their own samples to the Film's maxsampleluminance (the per-pixel term in its
        // pixel loop, the cached part in `shade_image`). pbrt-v3 would clamp each sample's sum of the two;
        // this differs from it only for samples where the sum is over the limit while both parts add light
        // (in practice where both are bright at once): a part under the limit passes whole. The two parts
        // do not share samples (the term has the Sampler's, the cached part its sub-pixel positions), so the
        // sum's clamp cannot be reproduced.
        if let Some(term) = &term {
            let w = &mut run_warnings;
            let rendered = match early {
                Some(done) => Some(done),
                None => render_per_pixel_term(scene, term.integrator, &term.set, settings, w, pass)?,
            };
            if let (Some(out), Some(rendered)) = (&mut out, rendered) {
                add_term(out, term, rendered);
            }
        }
        if let Some(out) = &mut out {
            // The Film's scale, once, on the whole image (the per-pixel term is unscaled until here).
            apply_scale(&mut out.image, &scene.film);
        }
        Ok(out)
    };
    let out = with_threads(settings.threads, run);
    // Kept whether or not the render succeeded (a failing scene's warnings still say what was read).
    warnings.extend(run_warnings);
    let Some(out) = out?? else { return Ok(None) };
    let mut rays = out.stats.cache_rays;
    rays.add(&out.stats.render_rays);
    Ok(Some(RenderOutput {
        image: out.image.clone(),
        rays,
        render_secs: out.stats.times.total,
        spp: cs.subpixels,
        integrator: format!("{}, placement {}", A::NAME, cs.placement),
        cache: Some(Box::new(out)),
    }))
}

/// Adds the per-pixel term's image, rays and time to the cached render, with a note naming it.
fn add_term(out: &mut CachedOutput, term: &PerPixelTerm, (image, rays, secs): (Image, RayCounters, f64)) {
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

/// The length scale L of a render and the defaults derived from it: λ unless set, and the application's.
fn scale_report<A: Application>(cs: &CacheSettings, app: &A) -> ScaleReport {
    let lambda = cs.params.lambda.is_none().then(|| ("lambda", cs.params.lambda_for(cs.scale.length)));
    let derived = lambda.into_iter().chain(app.scale_derived()).map(|(k, v)| (k.to_string(), json_f32(v))).collect();
    ScaleReport { scale: cs.scale, derived }
}

/// [`render_with`] (or its dry run) as a registry visitor: `integrator::render` and `integrator::dry_run`
/// dispatch an integrator name through it.
pub struct CacheRender<'a, 'w> {
    /// The scene.
    pub scene: &'a Scene,
    /// The scene's `Integrator` directive.
    pub integrator: Option<&'a Named>,
    /// Render settings.
    pub settings: &'a RenderSettings,
    /// Where warnings go.
    pub warnings: &'w mut Warnings,
    /// Render, or stop before shading.
    pub pass: Pass,
}

impl WithApplication for CacheRender<'_, '_> {
    type Output = Result<Option<RenderOutput>>;
    fn apply<A: Application>(self) -> Result<Option<RenderOutput>> {
        render_pass::<A>(self.scene, self.integrator, self.settings, self.warnings, self.pass)
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
         the camera sees where that is smaller; docs/scene-scale.md.)\n"
    ));
    out
}

/// The sample settings a cache-based render honours and the ones it cannot, said aloud: `--spp` (and
/// `--quick`'s one sample per pixel) become the sub-pixel sample count unless `subpixels` is set; the scene's
/// Sampler and PixelFilter are not used (the driver shades `subpixels` jittered positions per pixel and
/// averages them), said in one note at the first of the two lines that declares them. (The Film's `scale` and `maxsampleluminance`
/// are honoured: [`render_with`].) Returns `settings.cache` with the honoured sub-pixel count added.
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
    // A per-pixel term (irradiance caching's `output full`) renders with the scene's Sampler and
    // PixelFilter: only the cached part leaves them out. Both facts are one note, at the first of the two
    // lines.
    let box_filter = scene.filter.kind == filter::FilterKind::Box && scene.filter.radius == [0.5, 0.5];
    let sampler = scene.declared.sampler.as_ref().map(|l| (l, format!("Sampler \"{}\"", scene.sampler.name)));
    let filter = scene.declared.filter.as_ref().filter(|_| !box_filter);
    let unused = match (sampler, filter) {
        (Some((l, s)), Some(f)) => Some((l, format!("{s} and PixelFilter (line {}) are", f.line))),
        (Some((l, s)), None) => Some((l, format!("{s} is"))),
        (None, Some(f)) => Some((f, "PixelFilter is".to_string())),
        (None, None) => None,
    };
    if let Some((loc, what)) = unused {
        let whom = if per_pixel_term {
            "the cached part of the image (its per-pixel part uses them)"
        } else {
            "cache-based integrators"
        };
        warnings.note_at(
            loc,
            format!(
                "{what} not used by {whom}: the caches are shaded at \"subpixels\" jittered positions per pixel \
                 (set it, or --spp), averaged (a box filter of radius 0.5)"
            ),
        );
    }
    o
}
