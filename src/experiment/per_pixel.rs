//! Experiments: the per-pixel side of "cache AO exists to be faster than per-pixel AO at equal quality".
//! Renders pbrt-v3's `ambientocclusion` at several ray counts with the cache runs' ray length, four pixel
//! samples and a box filter (what the cache driver's sub-pixel shading does), and measures each image,
//! divided by π, against the same per-sample reference the placements are measured against.
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
    sweep
        .set
        .iter()
        .rev()
        .find(|(k, _)| k == "maxdistance")
        .map_or_else(|| (0.1 * l.scene.diagonal()).to_string(), |(_, v)| v.clone())
}

/// One row per entry of `nsamples` (AO rays per pixel sample): placement `ao:N`, budget 0, seed 0.
pub(super) fn rows(
    l: &mut LoadedScene,
    sweep: &Sweep,
    name: &str,
    reference: &Image,
    nsamples: &[u32],
    log: &mut dyn FnMut(&str),
) -> Result<Vec<Row>> {
    // A box over the pixel, as the cache driver reconstructs its sub-pixel samples.
    let saved = std::mem::replace(&mut l.scene.filter, Filter { radius: [0.5, 0.5], kind: FilterKind::Box });
    let result = nsamples.iter().map(|&n| one(l, sweep, name, reference, n, log)).collect();
    l.scene.filter = saved;
    result
}

fn one(
    l: &LoadedScene,
    sweep: &Sweep,
    name: &str,
    reference: &Image,
    n: u32,
    log: &mut dyn FnMut(&str),
) -> Result<Row> {
    let settings = RenderSettings {
        seed: 0,
        spp: Some(PIXEL_SAMPLES),
        threads: sweep.threads,
        integrator: Some("ambientocclusion".into()),
        set: vec![
            ("nsamples".into(), n.to_string()),
            ("maxdistance".into(), max_distance(l, sweep)),
            ("cossample".into(), "true".into()),
        ],
        ..Default::default()
    };
    let t = Instant::now();
    let mut img = render(&l.scene, None, &settings, &mut Warnings::default())?.image;
    let secs = t.elapsed().as_secs_f64();
    // pbrt-v3's estimator is π for an open hemisphere; the cache image holds the fraction in [0, 1].
    let inv_pi = std::f32::consts::FRAC_1_PI;
    img.pixels.iter_mut().for_each(|p| p.iter_mut().for_each(|c| *c *= inv_pi));
    let m = compare(&img, reference, &[Metric::Rmse, Metric::Flip])?;
    let (rmse, flip) = (m[0].1, m[1].1);
    log(&format!(
        "{name} ambientocclusion {n} rays x {PIXEL_SAMPLES} spp: rmse {rmse:.5} flip {flip:.5} ({secs:.1} s)"
    ));
    let times = StageTimes { render: secs, total: secs, ..Default::default() };
    Ok(Row {
        scene: name.into(),
        placement: format!("ao:{n}"),
        caches: 0,
        seed: 0,
        rmse,
        flip,
        stats: CacheStats { times, ..Default::default() },
    })
}
