//! STAGE 4, second stage **DGS**: discontinuity-guided sampling, the second stage of the paper's method
//! (paper §3.2, Eq. 3–4; ALGORITHMS.md §4.5). A per-pixel map D = Diff_avg′ + Diff_max′ + G′ is built from
//! the differences between the first-stage caches each pixel would blend and from the normals in a window
//! around it; N2 new caches are drawn from D without replacement (marginal row, conditional column).
//!
//! Depends on `gbuffer`, `cache` (the §5 selection), the shared placement helpers and `sampling`; sees cache
//! records only through [`CacheOracle::diff_many`]. Never depends on `render`, `scene` or an application.

use glam::Vec3A;
use rayon::prelude::*;

use super::budget::{free_usable, pick_uniform};
use super::discrete2d::Discrete2D;
use super::points::usable_normal;
use super::{AdaptiveInfo, AdaptivePlacement, CacheId, CacheOracle, DgsTerms, PlacementParams, Stage1};
use crate::cache::{CacheIndex, GroupScratch, Neighbour};
use crate::error::Result;
use crate::gbuffer::{GBuffer, PixelId};
use crate::sampling::Rng;

/// Stream tags of DGS's random decisions.
const STAGE_DRAW: u64 = 0x4447_0001;
const STAGE_FALLBACK: u64 = 0x4447_0002;
/// Rows per parallel band when gathering neighbour sets.
const BAND: usize = 8;
/// Side of the pixel tiles whose selections share one candidate list ([`CacheIndex::select_group`]).
const TILE: usize = 8;

/// DGS — discontinuity-guided sampling.
///
/// | option | type | default | meaning |
/// |---|---|---|---|
/// | `terms` | `Option<DgsTerms>` | None | which terms form D; `None` takes `PlacementParams::dgs` (ablations `vgc+dgs:diff`, `vgc+dgs:geom` fix it) |
/// | `PlacementParams::lookup` | LookupParams | N = 20, 30°, M = 6 | the §5 selection; its M is K, the caches compared per pixel (A9) |
/// | `PlacementParams::dgs_window` | usize | 5 | side of the G window (Eq. 3) |
///
/// D is 0 on invalid pixels and on every existing cache; each term is min–max normalised over usable pixels
/// (A11). When D sums to 0 (or runs out) the rest is drawn uniformly from free usable pixels. The map is
/// returned in [`AdaptiveInfo::discontinuity`]. Applications whose D should omit G (importance caching,
/// ALGORITHMS.md §4.5.4) are configured by the driver through `PlacementParams::dgs`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Discontinuity {
    /// Fixed terms (ablations), or `None` for `PlacementParams::dgs`.
    pub terms: Option<DgsTerms>,
}

/// Position and normal of every evaluated cache (NaN for a site that is not usable, which the index skips).
pub(super) fn cache_points(g: &GBuffer, oracle: &dyn CacheOracle) -> Vec<(Vec3A, Vec3A)> {
    (0..oracle.len() as CacheId)
        .map(|c| {
            g.get(oracle.site(c))
                .and_then(|sp| usable_normal(sp).map(|n| (sp.p, n)))
                .unwrap_or((Vec3A::NAN, Vec3A::NAN))
        })
        .collect()
}

/// The §5 index over `points` (from [`cache_points`]) as the driver builds it at render time: the
/// selection of `params`, λ from the scene's length scale L (1 when L is unknown), the exact-hit radius from L.
pub(super) fn cache_index(g: &GBuffer, points: &[(Vec3A, Vec3A)], params: &PlacementParams) -> CacheIndex {
    let l = g.scale;
    let lambda = params.lambda_for(if l.is_finite() && l > 0.0 { l } else { 1.0 });
    CacheIndex::new(points, params.lookup, lambda).with_scale(l)
}

/// The neighbour sets of one band of rows: per pixel an index into the band's sets (u32::MAX = none), the
/// sets (sorted cache ids, concatenated) and the band's distinct pairs (a < b, packed a << 32 | b, sorted).
#[derive(Default)]
struct Band {
    pixel_set: Vec<u32>,
    ids: Vec<u32>,
    off: Vec<u32>,
    pairs: Vec<u64>,
    /// With `sites` given: per pixel of the band, the world distance to the nearest cache it selects over the
    /// pixel's own distance from the camera (infinite when it selects none or is unusable).
    gap: Vec<f32>,
    /// With a [`PerPixel`] given: its value per pixel of the band (0 where unusable).
    extra: Vec<f32>,
}

/// A per-pixel quantity made from a pixel's §5 selection: `f(normal, selection, scratch)` (refine's
/// leave-one-out term); the scratch is for the interpolation weights.
pub(super) type PerPixel<'a> = &'a (dyn Fn(Vec3A, &[Neighbour], &mut Vec<(u32, f32)>) -> f32 + Sync);

/// A non-grid pixel that lies off its grid pixel's tangent plane by more than this fraction of its depth is
/// looked up itself: a selection made across such an offset (a step, a lamp below a ceiling) is another
/// surface's.
const EDGE_OFFSET: f32 = 0.002;

/// Gathers a band's neighbour sets; with `sites` (each cache's pixel, by id) also each pixel's gap, and with
/// `extra` its value per pixel. With `stride` s > 1 only the pixels whose x and y are multiples of s are
/// looked up, and every other pixel takes the set (gap, extra) of the grid pixel at or above-left of it —
/// unless that one is unusable, or (with `extra`) its normal is beyond the §5 normal filter of the pixel's
/// or the pixel lies off its tangent plane by more than [`EDGE_OFFSET`]: then the pixel is looked up
/// itself, so that thin faces and creases keep their own (refine's leave-one-out term, which finds them,
/// lost 2.5 % of RMSE over the stability map's cache-AO cells at 320×180 without this). Without `extra`
/// (an application that cannot predict) the edges are not looked up: they cost placement time (up to 15 %
/// for importance caching on sibenik's carvings, experiments/results/refine-tuning/2026-11-28b/) and only the
/// leave-one-out term needed them. `BAND` must be a multiple of s; s = 1 looks every pixel up.
fn gather_band(
    g: &GBuffer,
    index: &CacheIndex,
    rows: std::ops::Range<usize>,
    sites: Option<&[PixelId]>,
    extra: Option<PerPixel<'_>>,
    stride: usize,
) -> Band {
    let k = index.lookup().keep;
    let cos_max = index.lookup().theta_max_deg.to_radians().cos();
    let (y0, nrows) = (rows.start, rows.len());
    let stride = stride.max(1);
    // The grid pixel (band-relative) whose set pixel (x, y) takes.
    let source = |x: usize, y: usize| (x - x % stride, y - (y0 + y) % stride);
    let usable = |x: usize, y: usize| g.get(g.id(x, y)).and_then(|sp| usable_normal(sp).map(|n| (sp, n)));
    let looked_up = |x: usize, y: usize| {
        let (sx, sy) = source(x, y);
        (sx, sy) == (x, y)
            || match (usable(sx, y0 + sy), usable(x, y0 + y)) {
                (Some(_), Some(_)) if extra.is_none() => false,
                (Some((s, ns)), Some((sp, n))) => {
                    ns.dot(n) < cos_max || ns.dot(sp.p - s.p).abs() > EDGE_OFFSET * sp.depth
                }
                _ => true,
            }
    };
    // Per pixel of the band: its selection (sorted ids, padded with u32::MAX), found tile by tile.
    let mut sel = vec![u32::MAX; g.width * nrows * k];
    let mut lens = vec![0usize; g.width * nrows];
    let mut gap = if sites.is_some() { vec![f32::INFINITY; g.width * nrows] } else { Vec::new() };
    let mut extra_v = if extra.is_some() { vec![0f32; g.width * nrows] } else { Vec::new() };
    let mut weights = Vec::new();
    let mut queries = Vec::with_capacity(TILE * TILE);
    let mut where_ = Vec::with_capacity(TILE * TILE);
    let mut depths = Vec::with_capacity(TILE * TILE);
    let mut scratch = GroupScratch::default();
    for tx in (0..g.width).step_by(TILE) {
        for ty in (0..nrows).step_by(TILE) {
            queries.clear();
            depths.clear();
            where_.clear();
            for y in ty..(ty + TILE).min(nrows) {
                for x in tx..(tx + TILE).min(g.width) {
                    if stride > 1 && !looked_up(x, y) {
                        continue;
                    }
                    if let Some((sp, n)) = g.get(g.id(x, y0 + y)).and_then(|sp| usable_normal(sp).map(|n| (sp, n))) {
                        queries.push((sp.p, n));
                        depths.push(sp.depth);
                        where_.push(y * g.width + x);
                    }
                }
            }
            index.select_group_in(&queries, &mut scratch, |i, near| {
                let at = where_[i];
                if let Some(f) = extra {
                    extra_v[at] = f(queries[i].1, near, &mut weights);
                }
                if let Some(sites) = sites {
                    let (p, depth) = (queries[i].0, depths[i]);
                    gap[at] = near
                        .iter()
                        .filter_map(|nb| sites.get(nb.id as usize).and_then(|&s| g.get(s)))
                        .map(|c| (c.p - p).length())
                        .fold(f32::INFINITY, f32::min)
                        / depth.max(f32::MIN_POSITIVE);
                }
                let slot = &mut sel[at * k..(at + 1) * k];
                for (s, nb) in slot.iter_mut().zip(near) {
                    *s = nb.id;
                }
                slot[..near.len()].sort_unstable();
                lens[at] = near.len();
            });
        }
    }
    let mut b = Band { off: vec![0], gap, extra: extra_v, ..Default::default() };
    for y in 0..nrows {
        let mut prev: Option<u32> = None;
        for x in 0..g.width {
            let at = y * g.width + x;
            if !where_valid(g, x, y0 + y) {
                b.pixel_set.push(u32::MAX);
                prev = None;
                continue;
            }
            let from = if stride > 1 && !looked_up(x, y) {
                let (sx, sy) = source(x, y);
                let from = sy * g.width + sx;
                if let Some(v) = b.gap.get(from).copied() {
                    b.gap[at] = v;
                }
                if let Some(v) = b.extra.get(from).copied() {
                    b.extra[at] = v;
                }
                from
            } else {
                at
            };
            let set = &sel[from * k..from * k + lens[from]];
            // Neighbouring pixels usually blend the same caches: reuse the previous pixel's set.
            if let Some(s) = prev.filter(|&s| &b.ids[b.off[s as usize] as usize..b.off[s as usize + 1] as usize] == set)
            {
                b.pixel_set.push(s);
                continue;
            }
            let s = (b.off.len() - 1) as u32;
            for (i, &a) in set.iter().enumerate() {
                b.pairs.extend(set[i + 1..].iter().map(|&c| ((a as u64) << 32) | c as u64));
            }
            b.ids.extend_from_slice(set);
            b.off.push(b.ids.len() as u32);
            b.pixel_set.push(s);
            prev = Some(s);
        }
    }
    b.pairs.sort_unstable();
    b.pairs.dedup();
    b
}

/// Whether pixel (x, y) takes part in the map.
fn where_valid(g: &GBuffer, x: usize, y: usize) -> bool {
    g.get(g.id(x, y)).and_then(usable_normal).is_some()
}

/// Distinct pairs with their differences, indexed by first cache (CSR) for lookups.
struct PairTable {
    pairs: Vec<u64>,
    diffs: Vec<f32>,
    first: Vec<u32>,
}

impl PairTable {
    fn get(&self, a: u32, b: u32) -> f32 {
        let (a, b) = if a < b { (a, b) } else { (b, a) };
        let lo = self.first.get(a as usize).copied().unwrap_or(0) as usize;
        let hi = self.first.get(a as usize + 1).copied().unwrap_or(0) as usize;
        let key = ((a as u64) << 32) | b as u64;
        match self.pairs.get(lo..hi).map(|s| s.binary_search(&key)) {
            Some(Ok(i)) => self.diffs.get(lo + i).copied().unwrap_or(0.0),
            _ => 0.0,
        }
    }
}

/// Diff_avg and Diff_max per pixel (ALGORITHMS.md §4.5.3, all unordered pairs of the K caches, A10). Every
/// distinct pair over the whole image is evaluated in one `diff_many` call.
fn diff_terms(g: &GBuffer, index: &CacheIndex, oracle: &dyn CacheOracle) -> (Vec<f32>, Vec<f32>) {
    let t = selection_terms(g, index, oracle, false, None, 1);
    (t.avg, t.max)
}

/// What one pass of §5 selections over the image gives (see [`selection_terms`]); row-major per pixel.
pub(super) struct SelectionTerms {
    /// Diff_avg.
    pub avg: Vec<f32>,
    /// Diff_max.
    pub max: Vec<f32>,
    /// The gap (empty when not asked for).
    pub gap: Vec<f32>,
    /// The [`PerPixel`] quantity (empty when none was given).
    pub extra: Vec<f32>,
}

/// [`diff_terms`] and, when `want_gap`, each pixel's gap: the world distance to the nearest cache its §5
/// selection keeps over the pixel's distance from the camera (infinite where it keeps none) — and, with
/// `extra`, that quantity per pixel — all from the same selections, made on a grid of every `stride`-th
/// pixel in x and y (1 or 2; see `gather_band`). Measured so, a gap on a surface seen at a grazing angle
/// counts for more than the same gap in pixels on one that faces the camera: its pixels are farther apart
/// on the surface, and the values the caches interpolate vary over the surface, not the image.
pub(super) fn selection_terms(
    g: &GBuffer,
    index: &CacheIndex,
    oracle: &dyn CacheOracle,
    want_gap: bool,
    extra: Option<PerPixel<'_>>,
    stride: usize,
) -> SelectionTerms {
    let sites: Option<Vec<PixelId>> = want_gap.then(|| (0..oracle.len() as CacheId).map(|c| oracle.site(c)).collect());
    let bands: Vec<Band> = (0..g.height.div_ceil(BAND))
        .into_par_iter()
        .map(|i| gather_band(g, index, i * BAND..((i + 1) * BAND).min(g.height), sites.as_deref(), extra, stride))
        .collect();
    let mut pairs: Vec<u64> = bands.iter().flat_map(|b| b.pairs.iter().copied()).collect();
    pairs.par_sort_unstable();
    pairs.dedup();
    let unpacked: Vec<(CacheId, CacheId)> = pairs.iter().map(|&k| ((k >> 32) as u32, k as u32)).collect();
    let mut diffs = oracle.diff_many(&unpacked);
    diffs.resize(pairs.len(), 0.0);
    diffs.iter_mut().filter(|d| !d.is_finite()).for_each(|d| *d = 0.0);
    let mut first = vec![0u32; oracle.len() + 1];
    for &(a, _) in &unpacked {
        if let Some(f) = first.get_mut(a as usize + 1) {
            *f += 1;
        }
    }
    for i in 1..first.len() {
        first[i] += first[i - 1];
    }
    let table = PairTable { pairs, diffs, first };
    let per_band: Vec<(Vec<f32>, Vec<f32>)> = bands.par_iter().map(|b| band_terms(b, &table)).collect();
    let mut avg = Vec::with_capacity(g.width * g.height);
    let mut max = Vec::with_capacity(g.width * g.height);
    for (a, m) in per_band {
        avg.extend(a);
        max.extend(m);
    }
    let gap: Vec<f32> = bands.iter().flat_map(|b| b.gap.iter().copied()).collect();
    let extra: Vec<f32> = bands.into_iter().flat_map(|b| b.extra).collect();
    SelectionTerms { avg, max, gap, extra }
}

/// Per-pixel (Diff_avg, Diff_max) of one band from its sets (K < 2 ⇒ 0).
fn band_terms(b: &Band, table: &PairTable) -> (Vec<f32>, Vec<f32>) {
    let set_terms: Vec<(f32, f32)> = (0..b.off.len() - 1)
        .map(|s| {
            let set = &b.ids[b.off[s] as usize..b.off[s + 1] as usize];
            let (mut sum, mut max, mut n) = (0f64, 0f32, 0u32);
            for (i, &a) in set.iter().enumerate() {
                for &c in &set[i + 1..] {
                    let d = table.get(a, c);
                    sum += d as f64;
                    max = max.max(d);
                    n += 1;
                }
            }
            (if n > 0 { (sum / n as f64) as f32 } else { 0.0 }, max)
        })
        .collect();
    b.pixel_set.iter().map(|&s| set_terms.get(s as usize).copied().unwrap_or((0.0, 0.0))).unzip()
}

/// G(s) = Σ_{q in the window, q usable, q ≠ s} (1 − n_s·n_q) (Eq. 3); 0 for unusable pixels. Rows in
/// parallel; unusable pixels carry a zero normal and weight 0.
pub(super) fn geometry_term(g: &GBuffer, window: usize) -> Vec<f32> {
    let r = window.max(1) / 2;
    let (w, h) = (g.width, g.height);
    let normals: Vec<(Vec3A, f32)> = g
        .points
        .par_iter()
        .map(|sp| sp.as_ref().and_then(usable_normal).map_or((Vec3A::ZERO, 0.0), |n| (n, 1.0)))
        .collect();
    let mut out = vec![0f32; w * h];
    out.par_chunks_mut(w.max(1)).enumerate().for_each(|(y, row)| {
        let (y0, y1) = (y.saturating_sub(r), (y + r).min(h - 1));
        for (x, o) in row.iter_mut().enumerate() {
            let (ns, ws) = normals[y * w + x];
            if ws == 0.0 {
                continue;
            }
            let (x0, x1) = (x.saturating_sub(r), (x + r).min(w - 1));
            let mut sum = 0.0;
            for qy in y0..=y1 {
                for &(nq, wq) in &normals[qy * w + x0..=qy * w + x1] {
                    sum += wq * (1.0 - ns.dot(nq));
                }
            }
            // The pixel itself is in the window: take its own term back out.
            *o = (sum - (1.0 - ns.dot(ns))).max(0.0);
        }
    });
    out
}

/// Min–max normalisation to [0, 1] over the pixels where `mask` is set (A11); 0 when max = min.
pub(super) fn normalise(v: &mut [f32], mask: &[bool]) {
    let (lo, hi) = v
        .iter()
        .zip(mask)
        .filter(|(_, m)| **m)
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), (&x, _)| (lo.min(x), hi.max(x)));
    let range = hi - lo;
    v.par_iter_mut().zip(mask).for_each(|(x, &m)| {
        *x = if m && range > 0.0 && range.is_finite() { ((*x - lo) / range).clamp(0.0, 1.0) } else { 0.0 };
    });
}

/// The discontinuity map D of Eq. 4 with the chosen terms, 0 on unusable pixels and existing caches.
pub(crate) fn discontinuity_map(
    g: &GBuffer,
    oracle: &dyn CacheOracle,
    terms: DgsTerms,
    params: &PlacementParams,
) -> Vec<f32> {
    let mask: Vec<bool> = g.points.par_iter().map(|sp| sp.as_ref().and_then(usable_normal).is_some()).collect();
    let mut d = vec![0f32; g.width * g.height];
    if terms.diff && oracle.len() >= 2 {
        let index = cache_index(g, &cache_points(g, oracle), params);
        let (mut avg, mut max) = diff_terms(g, &index, oracle);
        normalise(&mut avg, &mask);
        normalise(&mut max, &mask);
        d.par_iter_mut().zip(avg.par_iter().zip(&max)).for_each(|(d, (a, m))| *d += a + m);
    }
    if terms.geometry {
        let mut geo = geometry_term(g, params.dgs_window);
        normalise(&mut geo, &mask);
        d.par_iter_mut().zip(&geo).for_each(|(d, x)| *d += x);
    }
    for c in 0..oracle.len() as CacheId {
        if let Some(v) = d.get_mut(oracle.site(c) as usize) {
            *v = 0.0;
        }
    }
    d.par_iter_mut().zip(&mask).for_each(|(d, &m)| {
        if !m || !d.is_finite() {
            *d = 0.0
        }
    });
    d
}

/// Draws `budget` distinct pixels from `map` without replacement (draw i uses the stream (seed, draw, i));
/// when the map runs out, the rest are uniform among free usable pixels. Returns the pixels and a note when
/// fewer could be placed.
fn draw(g: &GBuffer, map: &[f32], taken: &mut [bool], budget: usize, seed: u64) -> (Vec<PixelId>, Vec<String>) {
    let mut table = Discrete2D::new(g.width, g.height, map);
    let mut out = Vec::with_capacity(budget);
    let mut notes = Vec::new();
    for i in 0..budget {
        let mut rng = Rng::keyed(seed, STAGE_DRAW, i as u64);
        let Some((x, y)) = table.sample(rng.uniform(), rng.uniform()) else { break };
        table.remove(x, y);
        let id = g.id(x, y);
        taken[id as usize] = true;
        out.push(id);
    }
    if out.len() < budget {
        let mut free = free_usable(g, taken);
        let rest = pick_uniform(&mut free, budget - out.len(), seed, STAGE_FALLBACK);
        if out.is_empty() {
            notes.push("the discontinuity map is zero everywhere: new caches are uniformly random".to_string());
        }
        rest.iter().for_each(|&id| taken[id as usize] = true);
        out.extend(rest);
        if out.len() < budget {
            notes.push(format!("only {} free usable pixels remain for a stage-2 budget of {budget}", out.len()));
        }
    }
    (out, notes)
}

impl AdaptivePlacement for Discontinuity {
    fn place(
        &self,
        g: &GBuffer,
        _stage1: &Stage1,
        oracle: &mut dyn CacheOracle,
        budget: usize,
        params: &PlacementParams,
        seed: u64,
    ) -> Result<AdaptiveInfo> {
        super::budget::check_gbuffer(g)?;
        if budget == 0 {
            return Ok(AdaptiveInfo::default());
        }
        let terms = self.terms.unwrap_or(params.dgs);
        let map = discontinuity_map(g, oracle, terms, params);
        let mut taken = vec![false; g.width * g.height];
        for c in 0..oracle.len() as CacheId {
            if let Some(t) = taken.get_mut(oracle.site(c) as usize) {
                *t = true;
            }
        }
        let (sites, notes) = draw(g, &map, &mut taken, budget, seed);
        if !sites.is_empty() {
            oracle.evaluate(&sites);
        }
        Ok(AdaptiveInfo { added: sites.len(), rounds: 1, discontinuity: Some(map), notes, ..Default::default() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::placement::test_scenes::{self as ts, MaskOracle};
    use crate::placement::{InitialPlacement, ViewGuided};

    #[test]
    fn dgs_meets_the_contract() {
        ts::check_adaptive(&Discontinuity::default(), &ViewGuided { two_stage: true }, true);
        for terms in [DgsTerms { diff: true, geometry: false }, DgsTerms { diff: false, geometry: true }] {
            ts::check_adaptive(&Discontinuity { terms: Some(terms) }, &ViewGuided { two_stage: true }, terms.diff);
        }
    }

    #[test]
    fn the_map_is_zero_on_caches_and_background_and_pairs_are_evaluated_once() {
        let g = ts::sphere_on_plane(96, 64);
        let p = PlacementParams::default();
        let s1 = ViewGuided::default().place(&g, 300, &p, 1).unwrap();
        let mut oracle = MaskOracle::new(&g, &s1.sites);
        let info = Discontinuity::default().place(&g, &s1, &mut oracle, 60, &p, 1).unwrap();
        assert_eq!(oracle.diff_many_calls.get(), 1);
        assert_eq!(oracle.evaluate_calls, 1);
        let map = info.discontinuity.unwrap();
        assert_eq!(map.len(), 96 * 64);
        assert!(map.iter().all(|v| v.is_finite() && *v >= 0.0 && *v <= 3.0));
        assert!(s1.sites.iter().all(|&id| map[id as usize] == 0.0));
        assert!((0..map.len()).filter(|&i| g.points[i].is_none()).all(|i| map[i] == 0.0));
        assert!(map.iter().any(|&v| v > 0.0));
    }

    #[test]
    fn the_diff_terms_peak_at_the_hidden_step() {
        let g = ts::flat(128, 96);
        let p = PlacementParams { dgs: DgsTerms { diff: true, geometry: false }, ..Default::default() };
        let s1 = ViewGuided::default().place(&g, 400, &p, 1).unwrap();
        let oracle = MaskOracle::new(&g, &s1.sites);
        let map = discontinuity_map(&g, &oracle, p.dgs, &p);
        let near = |id: usize| g.points[id].is_some_and(|sp| (sp.p.x - ts::STEP_X).abs() < 0.3);
        let mean = |f: &dyn Fn(usize) -> bool| {
            let v: Vec<f32> = (0..map.len()).filter(|&i| f(i)).map(|i| map[i]).collect();
            v.iter().sum::<f32>() / v.len().max(1) as f32
        };
        let (at, away) = (mean(&near), mean(&|i| g.points[i].is_some() && !near(i)));
        assert!(at > 5.0 * away, "{at} vs {away}");
    }

    #[test]
    fn the_geometry_term_is_eq3_over_the_window() {
        let g = ts::nan_normals(23, 17);
        let geo = geometry_term(&g, 5);
        for y in 0..17usize {
            for x in 0..23usize {
                let n = |x: usize, y: usize| g.get(g.id(x, y)).and_then(usable_normal);
                let want = n(x, y).map_or(0.0, |ns| {
                    let mut sum = 0.0;
                    for qy in y.saturating_sub(2)..=(y + 2).min(16) {
                        for qx in x.saturating_sub(2)..=(x + 2).min(22) {
                            if (qx, qy) != (x, y) {
                                sum += n(qx, qy).map_or(0.0, |nq| 1.0 - ns.dot(nq));
                            }
                        }
                    }
                    sum
                });
                assert!((geo[y * 23 + x] - want).abs() < 1e-4, "({x}, {y}): {} vs {want}", geo[y * 23 + x]);
            }
        }
    }

    #[test]
    fn a_zero_map_falls_back_to_uniform() {
        // One plane and the geometry term alone: G = 0 everywhere, so the draws are uniform (still exact and
        // distinct).
        let g = ts::flat(64, 48);
        let p = PlacementParams { dgs: DgsTerms { diff: false, geometry: true }, ..Default::default() };
        let s1 = ViewGuided::default().place(&g, 100, &p, 1).unwrap();
        let mut oracle = MaskOracle::new(&g, &s1.sites);
        let info = Discontinuity::default().place(&g, &s1, &mut oracle, 50, &p, 1).unwrap();
        assert!(info.discontinuity.is_some_and(|m| m.iter().all(|&v| v == 0.0)));
        assert_eq!(info.added, 50);
        assert!(info.notes.iter().any(|n| n.contains("uniformly")), "{:?}", info.notes);
        ts::check_sites(&g, &oracle.sites);
    }
}
