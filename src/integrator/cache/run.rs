//! STAGE 7 (integrator): the one generic cache-based render driver (DESIGN.md §1, ALGORITHMS.md §0):
//! G-buffer → first-stage placement → evaluate caches → second-stage placement (evaluating what it adds)
//! → kd-tree → shade every sub-pixel sample from its selected caches. Or, for [`Placement::Reference`], the
//! per-sample reference: the application's brute-force answer at every sub-pixel sample. Each step is timed
//! as in the paper's Table 4.
//!
//! Generic over the [`Application`]; placement strategies come from the registry by name. Records are
//! evaluated in parallel with random streams keyed by the cache's pixel, so results never depend on threads.

use std::time::Instant;

use glam::Vec3A;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

use crate::application::{Application, Neighbour};
use crate::cache::{CacheIndex, GroupScratch};
use crate::error::{Error, Result};
use crate::gbuffer::{GBuffer, PixelId};
use crate::image::Image;
use crate::placement::{CacheId, CacheOracle, Prediction, registry};
use crate::render::film::clamp_sample_luminance;
use crate::sampling::rng::{hash3, mix64};
use crate::sampling::sequence::sobol02;
use crate::sampling::{Rng, Stratum};
use crate::scene::Scene;
use crate::scene::ray::RayCounters;

use super::camera_path::{CameraPaths, PathCounts, Vertex};
use super::settings::{CacheSettings, Placement};
use super::stats::{CacheStats, StageTimes};
use crate::os::{available_memory_bytes, peak_memory_bytes};
use crate::shading::Spectrum;

/// What a cache-based render produced besides the image.
#[derive(Clone, Debug)]
pub struct CachedOutput {
    /// The image (cropped film size).
    pub image: Image,
    /// Timings, counts, search results.
    pub stats: CacheStats,
    /// Pixels of the first-stage caches.
    pub stage1: Vec<PixelId>,
    /// Pixels of the second-stage caches.
    pub stage2: Vec<PixelId>,
    /// The DGS discontinuity map, when the strategy made one (row-major, G-buffer size).
    pub discontinuity: Option<Vec<f32>>,
    /// The resolved settings, generic and the application's, as the `--stats` report writes them.
    pub settings: serde_json::Map<String, serde_json::Value>,
}

/// Bytes in a GiB (for messages).
const GIB: f64 = (1u64 << 30) as f64;

/// Stage tags of random streams.
const STAGE_RECORD: u64 = 0x7265_636f;
const STAGE_SHADE: u64 = 0x7368_6164;
/// Pixels of a row whose sub-pixel samples share one group lookup in the cache index.
const GROUP_PIXELS: usize = 8;
/// Sub-pixel positions use a fixed key, so every method and the reference shade the same samples.
const SUBPIXEL_KEY: u64 = 0x5355_4250_4958;

/// The evaluated caches: sites, records and what evaluating them cost. Implements [`CacheOracle`].
struct Store<'a, 's, A: Application> {
    cx: &'a A::Prepared<'s>,
    app: &'a A,
    /// `app` with fewer draws, once a target error the caches beat asked for it ([`CacheOracle::thin`]).
    thin: Option<A>,
    g: &'a GBuffer,
    seed: u64,
    /// Sub-pixel samples per pixel (what a pixel's variance in [`Application::predict`] is over).
    subpixels: u32,
    sites: Vec<PixelId>,
    records: Vec<A::Record>,
    eval_secs: f64,
    rays: RayCounters,
    bar: ProgressBar,
}

impl<A: Application> Store<'_, '_, A> {
    /// The settings shading uses: the application's own, or fewer draws ([`CacheOracle::thin`]).
    fn shading_app(&self) -> &A {
        self.thin.as_ref().unwrap_or(self.app)
    }
}

impl<A: Application> CacheOracle for Store<'_, '_, A> {
    fn len(&self) -> usize {
        self.records.len()
    }

    fn site(&self, c: CacheId) -> PixelId {
        self.sites[c as usize]
    }

    fn diff(&self, a: CacheId, b: CacheId) -> f32 {
        self.app.diff(&self.records[a as usize], &self.records[b as usize])
    }

    fn diff_many(&self, pairs: &[(CacheId, CacheId)]) -> Vec<f32> {
        pairs.par_iter().map(|&(a, b)| self.diff(a, b)).collect()
    }

    fn predict_many(&mut self, asks: &[(CacheId, Vec<(CacheId, f32)>)]) -> Vec<Option<Prediction>> {
        let (cx, app, g, records, sites) = (self.cx, self.shading_app(), self.g, &self.records, &self.sites);
        let subpixels = self.subpixels;
        let neighbour = |c: CacheId, weight: f32| {
            let sp = g.get(sites[c as usize])?;
            Some(Neighbour { record: &records[c as usize], p: sp.p, n: sp.n, weight })
        };
        asks.par_iter()
            .map(|(c, others)| {
                let at = g.get(sites[*c as usize])?;
                let near: Vec<_> = others.iter().filter_map(|&(o, w)| neighbour(o, w)).collect();
                let p = app.predict(cx, at, &records[*c as usize], &near, subpixels)?;
                // A pixel's squared error: the squared difference and its variance, less the variance it
                // keeps with the cache itself; that and the noise it keeps beyond shading's are the floor.
                let bias2 = (0..3).map(|k| (p.from_others[k] - p.alone[k]).powi(2)).sum::<f32>() / 3.0;
                let floor = p.own_variance.min(p.variance);
                let sq_err = bias2 + p.variance - floor;
                Some(Prediction {
                    sq_err,
                    noise: p.records_noise,
                    floor: floor + p.kept_noise,
                    value: p.alone.iter().sum::<f32>() / 3.0,
                })
            })
            .collect()
    }

    fn thin(&mut self, keep: f32) -> bool {
        if keep >= 1.0 {
            return self.thin.take().is_some();
        }
        self.thin = self.app.thinned(keep);
        self.thin.is_some()
    }

    fn evaluate(&mut self, sites: &[PixelId]) {
        let t = Instant::now();
        let (cx, app, g, seed, bar) = (self.cx, self.app, self.g, self.seed, &self.bar);
        let out: Vec<Option<(A::Record, RayCounters)>> = sites
            .par_iter()
            .map(|&id| {
                let sp = g.get(id)?;
                let mut rng = Rng::keyed(seed, STAGE_RECORD, id as u64);
                let mut rays = RayCounters::default();
                let r = app.compute_record(cx, sp, &mut rng, &mut rays);
                bar.inc(1);
                Some((r, rays))
            })
            .collect();
        for (&id, r) in sites.iter().zip(out) {
            if let Some((rec, rays)) = r {
                self.sites.push(id);
                self.records.push(rec);
                self.rays.add(&rays);
            }
        }
        self.eval_secs += t.elapsed().as_secs_f64();
    }
}

fn bar(show: bool, len: u64, what: &str) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let b = ProgressBar::new(len);
    if let Ok(style) =
        ProgressStyle::with_template(&format!("{{spinner}} {what} [{{bar:40}}] {{pos}}/{{len}} {{elapsed_precise}}"))
    {
        b.set_style(style.progress_chars("=> "));
    }
    b
}

/// The key of sub-pixel sample `i` of pixel (x, y), which its random stream is drawn from: the pixel's
/// index times 64 plus `i` for the first 64 (the images made before more were allowed keep their bits), a
/// hash of the three beyond (so that sample 64 of a pixel does not share the stream of sample 0 of the next).
fn sample_key(x: i32, y: i32, i: u32) -> u64 {
    let pixel = (y as u32 as u64) << 32 | x as u32 as u64;
    if i < 64 { pixel.wrapping_mul(64).wrapping_add(i as u64) } else { hash3(SUBPIXEL_KEY, pixel, i as u64) | 1 << 63 }
}

/// The `i`-th of `n` sub-pixel offsets of pixel (x, y): one per cell of a (0,2)-net (a 2×2 stratification
/// for n = 4), keyed only by the pixel.
fn subpixel(x: i32, y: i32, i: u32) -> [f32; 2] {
    let k = mix64(hash3(SUBPIXEL_KEY, x as u32 as u64, y as u32 as u64));
    sobol02(i, [(k >> 32) as u32, k as u32])
}

/// Renders `scene` with application `app` (and what it prepared from the scene, `cx`) and the caches `s`
/// describes.
pub fn render_cached<A: Application>(
    scene: &Scene,
    app: &A,
    cx: &A::Prepared<'_>,
    s: &CacheSettings,
) -> Result<CachedOutput> {
    let start = Instant::now();
    let mut times = StageTimes::default();
    let mut stats = CacheStats::default();
    let g = GBuffer::from_scene(scene, s.scale.length);
    times.shading_points = start.elapsed().as_secs_f64();
    stats.valid_pixels = g.valid_count;
    if g.valid_count == 0 {
        stats.notes.push("no pixel centre sees the scene: there is nothing to cache, the image is black".into());
    }
    let none = s.placement == Placement::Reference;
    let mut stage1 = Vec::new();
    let mut stage2 = Vec::new();
    let mut discontinuity = None;
    let mut index_and_store = None;
    let lambda = s.params.lambda_for(g.scale);
    let mut store = Store {
        cx,
        app,
        thin: None,
        g: &g,
        seed: s.seed,
        subpixels: s.subpixels.max(1),
        sites: Vec::new(),
        records: Vec::new(),
        eval_secs: 0.0,
        rays: RayCounters::default(),
        bar: bar(s.progress, s.caches.min(g.valid_count) as u64, "caches"),
    };
    let mut cache_points = Vec::new();
    let mut radii = Vec::new();
    // The settings shading uses: `app`, or fewer draws where placement met a target error with them.
    let thin;
    let mut app = app;
    if let (Placement::Strategy(name), true) = (s.placement, g.valid_count > 0) {
        let strategy = registry::strategy(name)?;
        let total = budget(app, s, g.valid_count, &mut stats)?;
        discontinuity = place(&strategy, &mut store, total, s, &mut times, &mut stats)?;
        if let Some(t) = store.thin.take() {
            thin = t;
            app = &thin;
        }
        stage1 = store.sites[..stats.stage1_caches].to_vec();
        stage2 = store.sites[stats.stage1_caches..].to_vec();
        let t = Instant::now();
        cache_points =
            store.sites.iter().map(|&id| g.get(id).map_or((Vec3A::NAN, Vec3A::NAN), |p| (p.p, p.n))).collect();
        let index = CacheIndex::new(&cache_points, s.params.lookup, lambda).with_scale(g.scale);
        times.kd_tree = t.elapsed().as_secs_f64();
        stats.record_bytes = store.records.iter().map(|r| app.record_bytes(r)).sum();
        let t = Instant::now();
        let keep = s.params.lookup.keep;
        radii = (0..store.records.len() as u32).into_par_iter().map(|id| index.region_radius(id, keep)).collect();
        store.records.par_iter_mut().zip(&radii).for_each(|(r, &radius)| app.finish_record(cx, r, radius));
        if app.plan().learns {
            let lessons = lessons(app, cx, &index, &cache_points, &store.records);
            store.records.par_iter_mut().zip(lessons).for_each(|(r, l)| app.keep_lesson(r, l));
        }
        times.finish_records = t.elapsed().as_secs_f64();
        stats.record_bytes_kept = store.records.iter().map(|r| app.record_bytes(r)).sum();
        index_and_store = Some(index);
    }
    stats.cache_rays = store.rays;
    let t = Instant::now();
    let caches =
        Caches { index: index_and_store.as_ref(), records: &store.records, points: &cache_points, radii: &radii };
    let paths = CameraPaths::new(scene, &app.plan(), app.shading(cx))?;
    let (image, render_rays, path_counts) = shade_image(scene, app, cx, s, &caches, &paths, none);
    stats.camera_paths = path_counts;
    times.render = t.elapsed().as_secs_f64();
    stats.render_rays = render_rays;
    stats.total_caches = store.records.len();
    times.total = start.elapsed().as_secs_f64();
    stats.times = times;
    stats.peak_memory_bytes = peak_memory_bytes();
    let mut settings = s.to_json();
    settings.extend(app.settings().into_iter().map(|(k, v)| (k.to_string(), v)));
    Ok(CachedOutput { image, stats, stage1, stage2, discontinuity, settings })
}

/// Every record's [`Application::lesson`]: the caches the §5 selection at its own site blends, itself left out.
fn lessons<A: Application>(
    app: &A,
    cx: &A::Prepared<'_>,
    index: &CacheIndex,
    points: &[(Vec3A, Vec3A)],
    records: &[A::Record],
) -> Vec<u8> {
    (0..records.len())
        .into_par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |(near, weights), c| {
                let (p, n) = points[c];
                index.select(p, n, near);
                near.retain(|x: &crate::cache::Neighbour| x.id as usize != c);
                index.interpolate_weights(near, weights);
                let blend: Vec<_> = weights
                    .iter()
                    .map(|&(id, weight)| {
                        let (p, n) = points[id as usize];
                        Neighbour { record: &records[id as usize], p, n, weight }
                    })
                    .collect();
                app.lesson(cx, &records[c], &blend)
            },
        )
        .collect()
}

/// The caches to place: the budget, at most one per valid pixel (with a note when it asks for more). A
/// budget of 0, or one whose records would not fit in the memory available, is an error.
fn budget<A: Application>(app: &A, s: &CacheSettings, valid: usize, stats: &mut CacheStats) -> Result<usize> {
    if s.caches == 0 {
        return Err(Error::usage("the cache budget \"caches\" must be at least 1"));
    }
    let total = s.caches.min(valid);
    let need = total as u64 * app.record_bytes_bound() as u64;
    if let Some(avail) = available_memory_bytes()
        && need > avail
    {
        return Err(Error::usage(format!(
            "{}: {total} caches would need up to {:.2} GiB of records ({} bytes each); {:.2} GiB is available",
            A::NAME,
            need as f64 / GIB,
            app.record_bytes_bound(),
            avail as f64 / GIB
        )));
    }
    if s.caches > valid {
        stats.notes.push(format!(
            "{} caches requested but only {valid} pixels see the scene: every valid pixel becomes a cache",
            s.caches
        ));
    }
    Ok(total)
}

/// Places `total` caches with `strategy` — its initial stage, then its adaptive one if it has one —
/// evaluating each site's record into `store`, timed as the paper's Table 4; returns the adaptive stage's
/// discontinuity map, if it made one.
fn place<A: Application>(
    strategy: &registry::Strategy,
    store: &mut Store<'_, '_, A>,
    total: usize,
    s: &CacheSettings,
    times: &mut StageTimes,
    stats: &mut CacheStats,
) -> Result<Option<Vec<f32>>> {
    let g = store.g;
    let n1 = strategy.first_stage_budget(total, &s.params);
    let t = Instant::now();
    let first = strategy.initial.place(g, n1, &s.params, s.seed)?;
    times.initial_generation = t.elapsed().as_secs_f64();
    store.evaluate(&first.sites);
    times.initial_computation = store.eval_secs;
    stats.stage1_caches = store.len();
    let mut discontinuity = None;
    if let Some(second) = &strategy.adaptive {
        let (t, eval_before) = (Instant::now(), store.eval_secs);
        let budget = total - store.len();
        let info = second.place(g, &first, store, budget, &s.params, s.seed)?;
        let adaptive_eval = store.eval_secs - eval_before;
        times.adaptive_computation = adaptive_eval;
        times.adaptive_generation = t.elapsed().as_secs_f64() - adaptive_eval;
        stats.adaptive_rounds = info.rounds;
        stats.error_estimates = info.estimates;
        stats.notes.extend(info.notes);
        discontinuity = info.discontinuity;
    }
    store.bar.finish_and_clear();
    stats.stage2_caches = store.len() - stats.stage1_caches;
    stats.placement = first.info.clone();
    Ok(discontinuity)
}

/// The evaluated caches as shading reads them: the lookup index, the records, each cache's (p, n) and the
/// radius of the region it serves (its distance to its `keep`-th nearest cache).
struct Caches<'a, R> {
    index: Option<&'a CacheIndex>,
    records: &'a [R],
    points: &'a [(Vec3A, Vec3A)],
    radii: &'a [f32],
}

impl<R> Caches<'_, R> {
    /// Whether cache `id` is near enough to shade a point at (`p`, `n`) that a specular bounce led to (not
    /// placed for it): within the region it serves, on the same side.
    fn serves(&self, id: u32, p: Vec3A, n: Vec3A) -> bool {
        let (cp, cn) = self.points[id as usize];
        (cp - p).length() <= self.radii.get(id as usize).copied().unwrap_or(0.0) && cn.dot(n) > 0.0
    }
}

/// Stage tag of the random streams of a sample's camera-path vertices after its first.
const STAGE_VERTEX: u64 = 0x7665_7274;

/// `v` times the specular throughput `w`, channel by channel.
fn weighted(v: [f32; 3], w: Spectrum) -> [f32; 3] {
    let w = w.to_array();
    [v[0] * w[0], v[1] * w[1], v[2] * w[2]]
}

/// Shades every sub-pixel sample (box filter over the pixel): each vertex its camera path hands over
/// ([`CameraPaths`]) from the caches, or by the reference; a vertex after a specular bounce that no cache
/// serves ([`Caches::serves`]) by the application's per-sample estimator. Each value is clamped to the
/// Film's `maxsampleluminance` as it is added, as pbrt-v3's `Film::AddSample` clamps a sample — per vertex
/// and for the light the path gathered itself, which differs from clamping their sum only where a sample
/// has several and their sum is over the limit. Returns the image, the rays and what the paths did.
fn shade_image<A: Application>(
    scene: &Scene,
    app: &A,
    cx: &A::Prepared<'_>,
    s: &CacheSettings,
    caches: &Caches<'_, A::Record>,
    paths: &CameraPaths<'_, '_>,
    reference: bool,
) -> (Image, RayCounters, PathCounts) {
    let b = scene.film.cropped_bounds();
    let [w, h] = b.size();
    let n = s.subpixels.max(1);
    let eye = scene.camera.position();
    let pb = bar(s.progress, h as u64, if reference { "reference" } else { "render" });
    let rows: Vec<(Vec<[f32; 3]>, RayCounters, PathCounts)> = (0..h)
        .into_par_iter()
        .map(|row| {
            let mut out = vec![[0.0f32; 3]; w];
            let mut rays = RayCounters::default();
            let mut counts = PathCounts::default();
            let (mut weights, mut blend) = (Vec::new(), Vec::new());
            let (mut points, mut queries, mut vertices) = (Vec::new(), Vec::new(), Vec::new());
            let mut lookup = GroupScratch::default();
            let y = b.min[1] + row as i32;
            let key = |x: i32, i: u32| sample_key(x, y, i);
            for first in (0..w).step_by(GROUP_PIXELS) {
                // The vertices of a run of pixels' sub-pixel samples, looked up in the index as one group
                // (the same selections as one lookup each, several times faster).
                points.clear();
                let end = (first + GROUP_PIXELS).min(w);
                for (col, px) in out.iter_mut().enumerate().take(end).skip(first) {
                    let x = b.min[0] + col as i32;
                    for i in 0..n {
                        let u = subpixel(x, y, i);
                        let ray = scene.camera.generate_ray([x as f32 + u[0], y as f32 + u[1]], [0.5, 0.5]);
                        let gathered = paths.trace(ray, eye, &mut vertices, &mut counts, &mut rays);
                        if gathered != Spectrum::ZERO {
                            let g = clamp_sample_luminance(gathered.to_array(), scene.film.max_sample_luminance);
                            (0..3).for_each(|c| px[c] += g[c]);
                        }
                        let stratum = Stratum::new(s.seed, key(x, 0), i, n);
                        for v in &vertices {
                            let k =
                                if v.index == 0 { key(x, i) } else { hash3(STAGE_VERTEX, key(x, i), v.index as u64) };
                            points.push(Shade { col, key: k, stratum, vertex: *v });
                        }
                    }
                }
                let mut add = |col: usize, v: [f32; 3]| {
                    let v = clamp_sample_luminance(v, scene.film.max_sample_luminance);
                    (0..3).for_each(|k| out[col][k] += v[k])
                };
                if reference {
                    for p in &points {
                        let mut rng = Rng::keyed(s.seed, STAGE_SHADE, p.key);
                        let v = app.reference(cx, &p.vertex.point, &mut rng, p.stratum, &mut rays);
                        add(p.col, weighted(v, p.vertex.weight));
                    }
                } else if let Some(index) = caches.index {
                    queries.clear();
                    queries.extend(points.iter().map(|p| (p.vertex.point.p, p.vertex.point.n)));
                    index.select_group_in(&queries, &mut lookup, |j, near| {
                        let p = &points[j];
                        let sp = &p.vertex.point;
                        index.interpolate_weights(near, &mut weights);
                        if p.vertex.bounces > 0 && !weights.iter().any(|&(id, _)| caches.serves(id, sp.p, sp.n)) {
                            weights.clear();
                        }
                        blend.clear();
                        blend.extend(weights.iter().map(|&(id, weight)| {
                            let (p, n) = caches.points[id as usize];
                            Neighbour { record: &caches.records[id as usize], p, n, weight }
                        }));
                        let mut rng = Rng::keyed(s.seed, STAGE_SHADE, p.key);
                        if !blend.is_empty() {
                            let v = app.shade(cx, sp, &blend, &mut rng, p.stratum, &mut rays);
                            add(p.col, weighted(v, p.vertex.weight));
                        } else if p.vertex.bounces > 0 {
                            counts.by_estimator += 1;
                            let v = app.estimate(cx, sp, &mut rng, p.stratum, &mut rays);
                            add(p.col, weighted(v, p.vertex.weight));
                        }
                    });
                }
            }
            out.iter_mut().for_each(|px| *px = px.map(|v| v / n as f32));
            pb.inc(1);
            (out, rays, counts)
        })
        .collect();
    pb.finish_and_clear();
    let mut img = Image::new(w, h);
    let mut rays = RayCounters::default();
    let mut counts = PathCounts::default();
    for (y, (row, r, c)) in rows.into_iter().enumerate() {
        for (x, c) in row.into_iter().enumerate() {
            img.set(x, y, c);
        }
        rays.add(&r);
        counts.add(&c);
    }
    (img, rays, counts)
}

/// One vertex to shade: its pixel's column in the row, its random stream's key, its sample's stratum.
struct Shade {
    col: usize,
    key: u64,
    stratum: Stratum,
    vertex: Vertex,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_keys_are_distinct_across_neighbouring_pixels_and_many_samples() {
        let mut keys = std::collections::HashSet::new();
        for y in -2..3 {
            for x in -2..3 {
                for i in 0..1024 {
                    assert!(keys.insert(sample_key(x, y, i)), "({x}, {y}) sample {i} repeats a key");
                }
            }
        }
        // The first 64 keep the old formula, so images with up to 64 sub-pixel samples keep their bits.
        assert_eq!(sample_key(5, 7, 3), ((7u64 << 32) | 5) * 64 + 3);
    }
}
