//! Experiments: the per-pixel side of "cache AO exists to be faster than per-pixel AO at equal quality".
//! Renders pbrt-v3's `ambientocclusion` with the cache runs' ray length and a box filter (what the cache
//! driver's sub-pixel shading does), divided by π: once converged (64 pixel samples × 64 rays, so the pixel
//! footprint is integrated too — four sub-pixel samples at other positions than the reference's differ
//! at every edge however many rays they trace), and at several ray counts with four pixel samples, each
//! measured against the converged image and against the per-sample reference.
//!
//! Depends on `scene`, `render`, `image` and `metrics`; only `experiment` uses it.

use std::time::Instant;

use crate::error::{Result, Warnings};
use crate::image::Image;
use crate::metrics::{Metric, compare};
use crate::render::cache_stats::{CacheStats, StageTimes};
use crate::render::{RenderSettings, render};
use crate::scene::LoadedScene;
use crate::scene::filter::{Filter, FilterKind};

use super::{Row, Sweep};

/// Pixel samples of the per-pixel renders: the cache driver's default sub-pixel count.
const PIXEL_SAMPLES: u32 = 4;

/// The `maxdistance` the cache runs use: `--set maxdistance=…`, else 0.1 · the scene diagonal.
fn max_distance(l: &LoadedScene, sweep: &Sweep) -> String {
    sweep.set.iter().rev().find(|(k, _)| k == "maxdistance").map_or_else(
        || {
            let d = l.scene.diagonal();
            // cacheao's own default: 0.1 · L, unbounded for a scene without extent.
            if d > 0.0 { (0.1 * d).to_string() } else { "1e30".into() }
        },
        |(_, v)| v.clone(),
    )
}

/// Converged image: pixel samples and AO rays per pixel sample (4096 rays per pixel).
const CONVERGED: (u32, u32) = (64, 64);

/// RMSE and mean HDR-FLIP of `img` against `reference`.
pub(super) fn measure(img: &Image, reference: &Image) -> Result<(f64, f64)> {
    let m = compare(img, reference, &[Metric::Rmse, Metric::Flip])?;
    Ok((m[0].1, m[1].1))
}

/// The converged per-pixel image of the scene, kept in the output folder as `STORED-converged.exr` and reused
/// (`stored`: the scene's name with the tag of the sweep's parameters).
pub(super) fn converged(l: &mut LoadedScene, sweep: &Sweep, stored: &str, log: &mut dyn FnMut(&str)) -> Result<Image> {
    let path = sweep.out.join(format!("{stored}-converged.exr"));
    if let Ok(img) = crate::image::read(&path)
        && [img.width, img.height] == l.scene.film.cropped_bounds().size()
    {
        return Ok(img);
    }
    let (img, secs) = per_pixel_ao(l, sweep, CONVERGED.0, CONVERGED.1)?;
    log(&format!("{stored}: converged per-pixel image ({} spp x {} rays) in {secs:.1} s", CONVERGED.0, CONVERGED.1));
    crate::image::write(&img, &path)?;
    Ok(img)
}

/// One row per entry of `sweep.ao_samples` (AO rays per pixel sample, four pixel samples): placement
/// `ao:N`, budget 0, seed 0; `rmse`/`flip` against `reference`, `converged` against `conv`.
pub(super) fn rows(
    l: &mut LoadedScene,
    sweep: &Sweep,
    name: &str,
    reference: &Image,
    conv: &Image,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<Row>> {
    let mut out = Vec::new();
    for &n in &sweep.ao_samples {
        let (img, secs) = per_pixel_ao(l, sweep, PIXEL_SAMPLES, n)?;
        let (rmse, flip) = measure(&img, reference)?;
        let against = measure(&img, conv)?;
        log(&format!(
            "{name} ambientocclusion {n} rays x {PIXEL_SAMPLES} spp: rmse {rmse:.5} flip {flip:.5}, against the \
             converged image rmse {:.5} flip {:.5} ({secs:.1} s)",
            against.0, against.1
        ));
        let times = StageTimes { render: secs, total: secs, ..Default::default() };
        let (scene, placement) = (name.to_string(), format!("ao:{n}"));
        let stats = CacheStats { times, ..Default::default() };
        out.push(Row { scene, placement, caches: 0, seed: 0, rmse, flip, converged: Some(against), stats });
    }
    Ok(out)
}

/// pbrt-v3's `ambientocclusion` with `spp` pixel samples of `n` rays, box-filtered, ÷ π; and its wall seconds.
fn per_pixel_ao(l: &mut LoadedScene, sweep: &Sweep, spp: u32, n: u32) -> Result<(Image, f64)> {
    let settings = RenderSettings {
        seed: 0,
        spp: Some(spp),
        threads: sweep.threads,
        integrator: Some("ambientocclusion".into()),
        set: vec![
            ("nsamples".into(), n.to_string()),
            ("maxdistance".into(), max_distance(l, sweep)),
            ("cossample".into(), "true".into()),
        ],
        ..Default::default()
    };
    // A box over the pixel, as the cache driver reconstructs its sub-pixel samples.
    let saved = std::mem::replace(&mut l.scene.filter, Filter { radius: [0.5, 0.5], kind: FilterKind::Box });
    let t = Instant::now();
    let result = render(&l.scene, None, &settings, &mut Warnings::default());
    let secs = t.elapsed().as_secs_f64();
    l.scene.filter = saved;
    let mut img = result?.image;
    // pbrt-v3's estimator is π for an open hemisphere; the cache image holds the fraction in [0, 1].
    let inv_pi = std::f32::consts::FRAC_1_PI;
    img.pixels.iter_mut().for_each(|p| p.iter_mut().for_each(|c| *c *= inv_pi));
    Ok((img, secs))
}
