//! Experiments: the per-pixel side of "caching exists to be faster than per-pixel rendering at equal
//! quality" — the jobs of a spec's `baselines`. Renders the application's per-pixel baselines
//! (`Study::baselines` of `Application::STUDY`: for AO pbrt-v3's `ambientocclusion` with the cache runs' ray length, divided
//! by π) with a box filter (what the cache driver's sub-pixel shading does): the first once converged (64
//! pixel samples × 64 rays, so the pixel footprint is integrated too — four sub-pixel samples at other
//! positions than the reference's differ at every edge however many rays they trace), and each at several
//! ray counts with four pixel samples. `jobs::collect` measures them against the converged image and
//! against the per-sample reference.
//!
//! Depends on `scene`, `integrator`, `application` (the registry) and `image`; only `experiment` uses it.

use std::path::Path;

use crate::application::registry::{self, WithApplication};
use crate::application::{Application, Baseline};
use crate::error::{Error, Result, Warnings};
use crate::gbuffer::scale::SceneScale;
use crate::image::Image;
use crate::integrator::{RenderSettings, render};
use crate::parse::integrator::IntegratorParams;
use crate::parse::{Named, ParamList};
use crate::scene::filter::{FilterKind, FilterSpec};
use crate::scene::{LoadOptions, LoadedScene, Scene};

use super::jobs::RUNS;
use super::spec::{BaselineRun, Job};

/// Pixel samples of the per-pixel renders: the cache driver's default sub-pixel count.
const PIXEL_SAMPLES: u32 = 4;

/// Converged image: pixel samples and rays per pixel sample (4096 rays per pixel).
const CONVERGED: (u32, u32) = (64, 64);

/// The application's baselines, resolved with the parameters the cache runs use (the scene's Integrator
/// line when it names the application, then the sweep's `--set`).
struct BaselineOf<'a> {
    scene: &'a Scene,
    integrator: Option<&'a Named>,
    set: &'a [(String, String)],
}

impl WithApplication for BaselineOf<'_> {
    type Output = Result<Vec<Baseline>>;
    fn apply<A: Application>(self) -> Self::Output {
        let empty = ParamList::default();
        let params = self.integrator.filter(|n| n.name == A::NAME).map_or(&empty, |n| &n.params);
        let scale = SceneScale::of(self.scene);
        let app = A::from_params(&IntegratorParams::new(A::NAME, params, self.set), &scale)?;
        Ok((A::STUDY.baselines)(&app))
    }
}

/// The per-pixel baselines of `app` with the parameters `set` (never empty: an error when it has none).
fn baselines(l: &LoadedScene, app: &str, set: &[(String, String)]) -> Result<Vec<Baseline>> {
    let of = BaselineOf { scene: &l.scene, integrator: l.integrator.as_ref(), set };
    let all = registry::dispatch(app, of).transpose()?.unwrap_or_default();
    if all.is_empty() {
        return Err(Error::usage(format!("experiment: \"{app}\" has no per-pixel baseline to compare with")));
    }
    Ok(all)
}

/// The image file of baseline `label` in a baseline job's run (`runs/<id>-<label>.exr`); the converged
/// image is the job's own `runs/<id>.exr`.
pub(super) fn image_name(job: &Job, label: &str) -> String {
    match job.baseline {
        Some(BaselineRun::Rays(_)) => format!("{}-{label}.exr", job.id),
        _ => format!("{}.exr", job.id),
    }
}

/// Renders a baseline job (`job.baseline` is set) into `out/runs/`: its images, then `runs/<id>.json`
/// listing each baseline's label, integrator and render seconds (written last: the job's "done" mark).
pub(super) fn run(job: &Job, out: &Path, threads: Option<usize>) -> Result<()> {
    let Some(kind) = job.baseline else {
        return Err(Error::usage(format!("experiment: job \"{}\" is not a baseline job", job.id)));
    };
    let mut l = crate::scene::load(&job.file, LoadOptions { resolution: job.resolution, ..Default::default() })?;
    let bases = baselines(&l, &job.application, &job.set)?;
    let (chosen, spp, rays): (&[Baseline], u32, Option<u32>) = match kind {
        BaselineRun::Converged => (&bases[..1], CONVERGED.0, None),
        BaselineRun::Rays(n) => (&bases[..], PIXEL_SAMPLES, Some(n)),
    };
    let runs = out.join(RUNS);
    let mut done = Vec::new();
    for base in chosen {
        let n = rays.unwrap_or(CONVERGED.1);
        let (img, secs) = per_pixel(&mut l, threads, base, spp, n)?;
        let name = image_name(job, base.label);
        crate::image::write(&img, &runs.join(&name))?;
        done.push(serde_json::json!({
            "label": base.label,
            "integrator": base.integrator,
            "pixel_samples": spp,
            "samples": n,
            "seconds": secs,
            "image": name,
        }));
    }
    let json = serde_json::json!({ "baselines": done });
    crate::image::write_bytes(&runs.join(format!("{}.json", job.id)), json.to_string().as_bytes())
}

/// The baseline with `spp` pixel samples of `n` rays, box-filtered, scaled to the application's units; and
/// its wall seconds.
fn per_pixel(l: &mut LoadedScene, threads: Option<usize>, base: &Baseline, spp: u32, n: u32) -> Result<(Image, f64)> {
    let mut set = vec![(base.samples.to_string(), n.to_string())];
    set.extend(base.set.iter().cloned());
    let settings = RenderSettings {
        seed: 0,
        spp: Some(spp),
        threads,
        integrator: Some(base.integrator.into()),
        set,
        ..Default::default()
    };
    // A box over the pixel, as the cache driver reconstructs its sub-pixel samples.
    let saved = std::mem::replace(&mut l.scene.filter, FilterSpec { radius: [0.5, 0.5], kind: FilterKind::Box });
    let result = render(&l.scene, None, &settings, &mut Warnings::default());
    l.scene.filter = saved;
    let out = result?;
    // The integrator's own render time, as cache runs report theirs: scene loading left out of both, the
    // light set-up (importance caching's VPLs) counted in both (the driver's total includes `prepare`).
    let secs = out.render_secs;
    let mut img = out.image;
    img.pixels.iter_mut().for_each(|p| p.iter_mut().for_each(|c| *c *= base.scale));
    Ok((img, secs))
}
