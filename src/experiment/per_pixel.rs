//! Experiments: the per-pixel side of "caching exists to be faster than per-pixel rendering at equal
//! quality". Renders the application's per-pixel baseline (`Application::baseline`: for AO pbrt-v3's
//! `ambientocclusion` with the cache runs' ray length, divided by π) with a box filter (what the cache
//! driver's sub-pixel shading does): once converged (64 pixel samples × 64 rays, so the pixel footprint is
//! integrated too — four sub-pixel samples at other positions than the reference's differ at every edge
//! however many rays they trace), and at several ray counts with four pixel samples, each measured against
//! the converged image and against the per-sample reference.
//!
//! Depends on `scene`, `render`, `application` (the registry), `image` and `metrics`; only `experiment`
//! uses it.

use crate::application::registry::{self, WithApplication};
use crate::application::{Application, Baseline};
use crate::error::{Error, Result, Warnings};
use crate::image::Image;
use crate::integrator::cache::stats::{CacheStats, StageTimes};
use crate::integrator::{RenderSettings, render};
use crate::metrics::{Metric, compare};
use crate::parse::integrator::IntegratorParams;
use crate::parse::{Named, ParamList};
use crate::scene::filter::{Filter, FilterKind};
use crate::scene::{LoadedScene, Scene};

use super::{Row, Sweep};

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
        let app = A::from_params(&IntegratorParams::new(A::NAME, params, self.set), self.scene)?;
        Ok((A::STUDY.baselines)(&app))
    }
}

/// The per-pixel baselines of the sweep's integrator (never empty: an error when it has none).
pub(super) fn baselines(l: &LoadedScene, sweep: &Sweep) -> Result<Vec<Baseline>> {
    let of = BaselineOf { scene: &l.scene, integrator: l.integrator.as_ref(), set: &sweep.set };
    let all = registry::dispatch(&sweep.integrator, of).transpose()?.unwrap_or_default();
    if all.is_empty() {
        return Err(Error::usage(format!(
            "experiment: \"{}\" has no per-pixel baseline to compare with",
            sweep.integrator
        )));
    }
    Ok(all)
}

/// RMSE and mean HDR-FLIP of `img` against `reference`.
pub(super) fn measure(img: &Image, reference: &Image) -> Result<(f64, f64)> {
    let m = compare(img, reference, &[Metric::Rmse, Metric::Flip])?;
    Ok((m[0].1, m[1].1))
}

/// The converged per-pixel image of the scene, kept in the output folder as `STORED-converged.exr` and reused
/// (`stored`: the scene's name with the tag of the sweep's integrator and parameters).
pub(super) fn converged(
    l: &mut LoadedScene,
    sweep: &Sweep,
    base: &Baseline,
    stored: &str,
    log: &mut dyn FnMut(&str),
) -> Result<Image> {
    let path = sweep.out.join(format!("{stored}-converged.exr"));
    if let Ok(img) = crate::image::read(&path)
        && [img.width, img.height] == l.scene.film.cropped_bounds().size()
    {
        return Ok(img);
    }
    let (img, secs) = per_pixel(l, sweep, base, CONVERGED.0, CONVERGED.1)?;
    log(&format!("{stored}: converged per-pixel image ({} spp x {} rays) in {secs:.1} s", CONVERGED.0, CONVERGED.1));
    crate::image::write(&img, &path)?;
    Ok(img)
}

/// One row per baseline and entry of `sweep.baseline_samples` (rays per pixel sample, four pixel samples):
/// placement `LABEL:N` (`ao:N`, `power:N`), budget 0, seed 0; `rmse`/`flip` against `reference`,
/// `converged` against `conv`.
pub(super) fn rows(
    l: &mut LoadedScene,
    sweep: &Sweep,
    bases: &[Baseline],
    name: &str,
    (reference, conv): (&Image, &Image),
    log: &mut dyn FnMut(&str),
) -> Result<Vec<Row>> {
    let mut out = Vec::new();
    for base in bases {
        for &n in &sweep.baseline_samples {
            let (img, secs) = per_pixel(l, sweep, base, PIXEL_SAMPLES, n)?;
            let (rmse, flip) = measure(&img, reference)?;
            let against = measure(&img, conv)?;
            log(&format!(
                "{name} {}:{n} ({} {}={n} x {PIXEL_SAMPLES} spp): rmse {rmse:.5} flip {flip:.5}, against the \
                 converged image rmse {:.5} flip {:.5} ({secs:.1} s)",
                base.label, base.integrator, base.samples, against.0, against.1
            ));
            let times = StageTimes { render: secs, total: secs, ..Default::default() };
            let (scene, placement) = (name.to_string(), format!("{}:{n}", base.label));
            let stats = CacheStats { times, ..Default::default() };
            out.push(Row { scene, placement, caches: 0, seed: 0, rmse, flip, converged: Some(against), stats });
        }
    }
    Ok(out)
}

/// The baseline with `spp` pixel samples of `n` rays, box-filtered, scaled to the application's units; and
/// its wall seconds.
fn per_pixel(l: &mut LoadedScene, sweep: &Sweep, base: &Baseline, spp: u32, n: u32) -> Result<(Image, f64)> {
    let mut set = vec![(base.samples.to_string(), n.to_string())];
    set.extend(base.set.iter().cloned());
    let settings = RenderSettings {
        seed: 0,
        spp: Some(spp),
        threads: sweep.threads,
        integrator: Some(base.integrator.into()),
        set,
        ..Default::default()
    };
    // A box over the pixel, as the cache driver reconstructs its sub-pixel samples.
    let saved = std::mem::replace(&mut l.scene.filter, Filter { radius: [0.5, 0.5], kind: FilterKind::Box });
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
