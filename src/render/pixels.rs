//! STAGE 6 (render): the pixel loop. The sample bounds are cut into 16×16 tiles rendered in parallel; each
//! tile reconstructs into its own film tile and the tiles are merged in tile order.

use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

use crate::image::Image;
use crate::scene::Scene;
use crate::scene::film::PixelBounds;
use crate::scene::ray::Ray;
use crate::scene::sampler::SamplerSpec;

use super::film::{Film, FilmTile, clamp_sample_luminance};
use super::{PixelIntegrator, RayCounters};
use crate::sampling::pixel_samples::PixelSamples;
use crate::shading::lighting::Scratch;

const TILE: i32 = 16;

/// Renders `scene` with `integrator`, `sampler.spp` samples per pixel, each clamped to the Film's
/// `maxsampleluminance`; returns the image (before the Film's `scale`, which the caller applies once with
/// `film::apply_scale`), the rays traced and the wall time. Identical output for any thread count.
pub fn render_image(
    scene: &Scene,
    sampler: &SamplerSpec,
    integrator: &dyn PixelIntegrator,
    seed: u64,
    progress: bool,
) -> (Image, RayCounters, f64) {
    let start = Instant::now();
    let image_px = scene.film.cropped_bounds();
    let sample_px = scene.film.sample_bounds(scene.filter.radius);
    let tiles = tiles(&sample_px);
    let bar = progress_bar(progress, tiles.len() as u64);
    let results: Vec<(FilmTile, RayCounters)> = tiles
        .par_iter()
        .map(|t| {
            let r = render_tile(scene, sampler, integrator, seed, t, &image_px);
            bar.inc(1);
            r
        })
        .collect();
    bar.finish_and_clear();
    let mut film = Film::new(image_px);
    let mut rays = RayCounters::default();
    for (tile, c) in &results {
        film.merge(tile);
        rays.add(c);
    }
    (film.to_image(), rays, start.elapsed().as_secs_f64())
}

fn tiles(b: &PixelBounds) -> Vec<PixelBounds> {
    let mut out = Vec::new();
    let mut y = b.min[1];
    while y < b.max[1] {
        let mut x = b.min[0];
        while x < b.max[0] {
            out.push(PixelBounds { min: [x, y], max: [(x + TILE).min(b.max[0]), (y + TILE).min(b.max[1])] });
            x += TILE;
        }
        y += TILE;
    }
    out
}

fn render_tile(
    scene: &Scene,
    sampler: &SamplerSpec,
    integrator: &dyn PixelIntegrator,
    seed: u64,
    t: &PixelBounds,
    image: &PixelBounds,
) -> (FilmTile, RayCounters) {
    let mut tile = FilmTile::new(*t, &scene.filter, image);
    let mut samples = PixelSamples::new(sampler.kind, sampler.spp, seed);
    let mut scratch = Scratch::default();
    let mut counters = RayCounters::default();
    let max_lum = scene.film.max_sample_luminance;
    for y in t.min[1]..t.max[1] {
        for x in t.min[0]..t.max[0] {
            // Each sample's camera ray is made one sample ahead: its chain of divisions and square roots then
            // overlaps the previous sample's shading instead of stalling the traversal that needs it. The
            // stream is a function of (pixel, sample, dimension), so the values are the same in this order.
            let mut next = camera_sample(scene, &mut samples, [x, y], 0);
            for i in 0..sampler.spp {
                let (p_film, ray) = next;
                if i + 1 < sampler.spp {
                    next = camera_sample(scene, &mut samples, [x, y], i + 1);
                }
                // Back to this sample, past the camera's dimensions.
                samples.start([x, y], i);
                samples.skip2d();
                samples.skip2d();
                let mut l = integrator.li(scene, ray, &mut samples, &mut scratch, &mut counters);
                if !l.iter().all(|v| v.is_finite()) {
                    l = [0.0; 3];
                }
                tile.add(p_film, clamp_sample_luminance(l, max_lum), &scene.filter);
            }
        }
    }
    (tile, counters)
}

/// The film position and camera ray of sample `i` of `pixel`, leaving `samples` past the camera's two
/// dimension pairs (film, then lens: the lens sample is drawn, or its dimensions skipped, whether or not the
/// camera has a lens).
#[inline]
fn camera_sample(scene: &Scene, samples: &mut PixelSamples, pixel: [i32; 2], i: u32) -> ([f32; 2], Ray) {
    samples.start(pixel, i);
    let u = samples.get2d();
    let p_film = [pixel[0] as f32 + u[0], pixel[1] as f32 + u[1]];
    let u_lens = if scene.camera.uses_lens() {
        samples.get2d()
    } else {
        samples.skip2d();
        [0.5; 2]
    };
    (p_film, scene.camera.generate_ray(p_film, u_lens))
}

fn progress_bar(show: bool, n: u64) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(n);
    if let Ok(style) =
        ProgressStyle::with_template("{spinner} rendering [{bar:40}] {percent}% {elapsed_precise} (eta {eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}
