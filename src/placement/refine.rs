//! STAGE 4, second stage of **refine** (beyond the paper; experiments/notes/refine.md): after an image-space
//! uniform first stage (IM with `1 − refine_share` of the budget), the rest is added in rounds, each drawn
//! from a fresh map of the caches placed so far: where the caches a pixel would blend predict each other
//! badly (the leave-one-out term: each cache left out in turn and predicted by the application's own
//! shading from its neighbours, the miss it leaves), where they disagree (Diff_avg), where the normals
//! change (G), and where the nearest cache the pixel's §5 selection keeps is far away on the surface, for
//! the pixel's distance from the camera (the coverage term), over a small uniform floor. Every round sees the caches of
//! the rounds before it, so refinement follows the error that remains rather than the error one map
//! predicted, and no pixel is left far from a cache it can use (the gaps that made the clustered
//! placements lose to IM, experiments/notes/stability.md). Given a target error instead of a count, the
//! rounds go on until refine's own estimate ([`super::estimate`]) says it is met. A round's caches are
//! drawn from its map *stratified* by the map's mass ([`super::stratified`]), not independently as DGS
//! draws: one cache per equal share of the mass, so a flat stretch of the map gets evenly spread caches
//! rather than clumps and holes.
//!
//! Depends on `gbuffer`, `cache` (the §5 selection), the DGS terms of [`super::discontinuity`],
//! the estimate and `sampling`; sees cache records only through [`CacheOracle::diff_many`] and
//! [`CacheOracle::predict_many`]. Never depends on `render`, `scene` or an application.

use rayon::prelude::*;

use glam::Vec3A;

use super::discontinuity::{PerPixel, SelectionTerms, cache_index, cache_points, geometry_term, selection_terms};
use super::estimate::Misses;
use super::points::usable_normal;
use super::{
    AdaptiveInfo, AdaptivePlacement, CacheId, CacheOracle, PlacementParams, RoundEstimate, Stage1, TargetError,
};
use crate::cache::CacheIndex;
use crate::error::Result;
use crate::gbuffer::GBuffer;

/// Stream tag of refine's draws; the round number is added to it.
const STAGE_DRAW: u64 = 0x5246_0100;

/// Refine's second stage: rounds of map-guided insertion.
///
/// | option | type | default | meaning |
/// |---|---|---|---|
/// | `PlacementParams::refine_share` | f32 | 0.8 | the share of the budget the rounds add (the driver gives IM the rest) |
/// | `PlacementParams::refine_rounds` | u32 | 3 | rounds; the share is split evenly over them |
/// | `PlacementParams::refine_floor` | f32 | 0.1 | uniform floor, as a fraction of the map's mean over free usable pixels |
/// | `PlacementParams::dgs` | DgsTerms | both | whether the map has the difference and the geometry terms (importance caching omits G, as for DGS) |
/// | `PlacementParams::refine_misses` | bool | true | whether the map has the leave-one-out term E (importance caching omits it) |
///
/// A round's map, on every usable pixel without a cache, is `4 · E / mean(E) + D³ / mean(D³) + G / mean(G) + 2 ·
/// min((gap / h)², 16)` plus the floor, with E the weighted mean, over the caches the pixel's §5 selection blends (its
/// weights), of each cache's squared leave-one-out miss (`estimate::Misses`: the application's shading at the cache's
/// site from its neighbours against the cache itself, the error refine's estimate is made of; where shading draws, the
/// variance of a pixel's samples from the neighbours less what they keep from the cache alone; absent when the
/// application cannot predict, or when its plan leaves the term out, as importance caching's does), D = Diff_avg /
/// mean(Diff_avg), where Diff_avg is DGS's mean difference of the caches the pixel's §5 selection blends (ALGORITHMS.md
/// §4.5.3), G is Eq. 3, gap is the world distance to the nearest cache that selection keeps over the pixel's distance
/// from the camera (a pixel that keeps none counts 16) and h is the root mean square of the gaps. The selections behind
/// E, Diff_avg and gap are made on every second pixel in x and y, the others taking their grid pixel's unless an edge
/// lies between them (`discontinuity::selection_terms`). E is what finds a face whose pixels blend the caches of
/// another surface that pass the §5 normal filter (the staircase's steps blending the next step's caches), where the
/// caches agree with each other and Diff_avg sees nothing: with it refine went from 2 clear losses to the best of the
/// paper's five to none on the stability map's cache-AO cells at 320×180, and its mean RMSE from 0.91 to 0.84 of
/// VGC+DGS's; weights 2–8 were within 2 % of each other on the staircase (experiments/notes/refine.md). Unlike DGS's
/// min–max normalisation, dividing by the mean keeps each term's contrast: a scene whose caches disagree everywhere
/// (sibenik's carvings) gets near-uniform rounds, one whose disagreement sits on a few edges (the staircase's steps)
/// gets concentrated ones (the cube sharpens that further). Diff_max is left out: it peaks on single noisy
/// pairs. The weights were chosen on the cache-AO cells of the stability map at 160×90 and 320×180,
/// experiments/notes/refine.md and experiments/results/refine-tuning/. A round's caches are one per equal
/// share of its map's mass ([`super::stratified::draw`]; independent draws were 1.04× the RMSE over the
/// stability map's cache-AO cells at 320×180, experiments/notes/refine.md). The gap is measured on the
/// surface rather than in the image (pixels apart) because irradiance caching lost to the clustered
/// placements on the Cornell box, whose walls are seen at grazing angles: measured so, refine no longer
/// loses in any irradiance cell of the map at 160×90 (experiments/notes/refine.md); dividing by the
/// camera distance keeps far surfaces from drawing more caches than near ones (the world distance alone
/// lost on sibenik, whose nave is deep). Three rounds: with stratified draws two, three and four were within
/// the seeds' spread of each other in RMSE, and four cost up to 1.3× VGC+DGS's placement time where the
/// records are cheap (importance caching), three at most 1.1× (experiments/notes/refine.md).
///
/// With `PlacementParams::target` (`targeterror`) the budget is a ceiling: the first stage is 1/256 of it
/// (the registry's `first_stage_budget`), and rounds of the same maps add caches until
/// the estimate ([`super::estimate::relative_rmse`], from the same misses as E) is at or below the target,
/// each round sized from the last two estimates; every estimate is in `AdaptiveInfo::estimates`, and a
/// target not met within the ceiling is a note.
#[derive(Clone, Copy, Debug, Default)]
pub struct Refine;

impl AdaptivePlacement for Refine {
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
        let mut taken = vec![false; g.width * g.height];
        let fixed = Fixed::new(g, params);
        // The first stage's caches; each round's draws mark their own.
        for c in 0..oracle.len() as CacheId {
            if let Some(t) = taken.get_mut(oracle.site(c) as usize) {
                *t = true;
            }
        }
        let mut state = Rounds { g, params, seed, fixed, taken, info: AdaptiveInfo::default(), current: None };
        match params.target {
            Some(target) => state.until_target(oracle, budget, target),
            None => state.equal_rounds(oracle, budget),
        }
        state.info.notes.dedup();
        Ok(state.info)
    }
}

/// What refine's rounds share.
struct Rounds<'a> {
    g: &'a GBuffer,
    params: &'a PlacementParams,
    seed: u64,
    fixed: Fixed,
    taken: Vec<bool>,
    info: AdaptiveInfo,
    /// The caches placed so far as the last map or estimate saw them (both need the same), if still current.
    current: Option<Current>,
}

/// The caches placed so far, indexed for the §5 selection, with their leave-one-out misses (`None`: the
/// application cannot predict a cache from its neighbours, or fewer than two caches).
struct Current {
    caches: usize,
    points: Vec<(Vec3A, Vec3A)>,
    index: CacheIndex,
    misses: Option<Misses>,
}

impl Current {
    /// The caches placed so far; their misses only where the map or the estimate reads them.
    fn new(g: &GBuffer, oracle: &mut dyn CacheOracle, params: &PlacementParams) -> Self {
        let points = cache_points(g, oracle);
        let index = cache_index(g, &points, params);
        let wanted = params.refine_misses || params.target.is_some();
        let misses = if wanted { Misses::new(g, &points, &index, oracle) } else { None };
        Current { caches: oracle.len(), points, index, misses }
    }
}

impl Rounds<'_> {
    /// The caches placed so far ([`Current`]), made again only when caches were added since.
    fn current(&mut self, oracle: &mut dyn CacheOracle) -> &Current {
        let (g, params) = (self.g, self.params);
        let stale = self.current.as_ref().is_none_or(|c| c.caches != oracle.len());
        if stale {
            self.current = None;
        }
        self.current.get_or_insert_with(|| Current::new(g, oracle, params))
    }

    /// Round `r`: draws `n` caches from a fresh map and evaluates them; returns how many it added.
    fn round(&mut self, oracle: &mut dyn CacheOracle, r: usize, n: usize) -> usize {
        self.current(oracle);
        let current = self.current.as_ref().expect("made by `current`");
        let map = round_map(self.g, &*oracle, self.params, current, &self.taken, &self.fixed);
        let sites = super::stratified::draw(self.g.width, self.g.height, &map, n, self.seed, STAGE_DRAW + r as u64);
        sites.iter().for_each(|&id| self.taken[id as usize] = true);
        if sites.len() < n {
            self.info.notes.push(format!("only {} free usable pixels remain for a round of {n} caches", sites.len()));
        }
        if !sites.is_empty() {
            self.info.added += sites.len();
            self.info.rounds += 1;
            oracle.evaluate(&sites);
            self.info.discontinuity = Some(map);
        }
        sites.len()
    }

    /// `refine_rounds` rounds sharing `budget` equally.
    fn equal_rounds(&mut self, oracle: &mut dyn CacheOracle, budget: usize) {
        let rounds = self.params.refine_rounds.max(1) as usize;
        for r in 0..rounds {
            // Round r's share of the budget: the rounding leaves the sum exactly `budget`.
            let n = budget * (r + 1) / rounds - budget * r / rounds;
            if n > 0 && self.round(oracle, r, n) == 0 {
                break;
            }
        }
    }

    /// The error estimate of the caches placed so far, recorded.
    fn estimate(&mut self, oracle: &mut dyn CacheOracle, target: TargetError) -> Option<f32> {
        let e = self.measure(oracle, target)?;
        self.info.estimates.push(RoundEstimate { caches: oracle.len(), relative_rmse: e });
        Some(e)
    }

    /// The error estimate of the caches placed so far, not recorded.
    fn measure(&mut self, oracle: &mut dyn CacheOracle, target: TargetError) -> Option<f32> {
        let g = self.g;
        let current = self.current(oracle);
        current.misses.as_ref()?.relative_rmse(g, &current.points, &current.index, target.added_mean)
    }

    /// Where the caches meet the target with room to spare (`e` against `goal`): the fewest draws whose
    /// estimate still meets it ([`CacheOracle::thin`]; for an application whose error is its shading's
    /// noise, such as importance caching, whose error hardly grows with fewer caches), so a loose target
    /// renders faster and nearer the error asked for. Fractions whose variance would grow past the room
    /// even at 1/keep are not tried; each one tried is estimated again with the caches as they are.
    fn fewer_draws(&mut self, oracle: &mut dyn CacheOracle, target: TargetError, e: f32, goal: f32) {
        let room = (e / goal).powi(2);
        for keep in THIN_KEEP {
            if keep < room || !oracle.thin(keep) {
                continue;
            }
            self.current = None;
            match self.measure(oracle, target) {
                Some(thin) if thin <= goal => {
                    self.info.estimates.push(RoundEstimate { caches: oracle.len(), relative_rmse: thin });
                    self.info.notes.push(format!(
                        "targeterror {goal}: the caches meet it with {e:.4}; shading draws {keep} of its samples \
                         (estimated {thin:.4})"
                    ));
                    return;
                }
                _ => {}
            }
        }
        if oracle.thin(1.0) {
            self.current = None;
        }
    }

    /// Rounds until the estimate meets `target` or `budget` caches are added. Each round aims at the
    /// count the last two estimates predict (error ∝ caches^−α, α from their slope, 0.5 at first),
    /// adding between a quarter of and as many caches as are placed so far (a larger step overshoots when
    /// α is misjudged: the achieved error then falls well below the target).
    fn until_target(&mut self, oracle: &mut dyn CacheOracle, budget: usize, target: TargetError) {
        let Some(mut e) = self.estimate(oracle, target) else {
            self.info.notes.push(
                "targeterror: this application cannot estimate its error from its caches; the whole budget is placed"
                    .into(),
            );
            return self.equal_rounds(oracle, budget);
        };
        let goal = target.relative.max(f32::MIN_POSITIVE);
        let mut last: Option<(usize, f32)> = None;
        let mut r = 0;
        while e > goal && self.info.added < budget {
            let now = oracle.len();
            let alpha = match last {
                Some((n0, e0)) if e0 > e && now > n0 => ((e0 / e).ln() / (now as f32 / n0 as f32).ln()).clamp(0.3, 1.5),
                _ => 0.5,
            };
            let want = now as f32 * (e / goal).powf(1.0 / alpha);
            let add = ((want - now as f32).round() as usize).clamp(now.div_ceil(4), now);
            let add = add.min(budget - self.info.added);
            if self.round(oracle, r, add) == 0 {
                break;
            }
            r += 1;
            last = Some((now, e));
            match self.estimate(oracle, target) {
                Some(next) => e = next,
                None => break,
            }
        }
        if e <= goal {
            self.fewer_draws(oracle, target, e, goal);
        } else {
            self.info.notes.push(format!(
                "targeterror {goal}: not met within the budget of {} caches (estimated relative RMSE {e:.4}); raise `caches`",
                oracle.len()
            ));
        }
    }
}

/// The fractions of its draws a target error the caches already beat may leave shading, fewest first
/// ([`Rounds::fewer_draws`]): with 8 draws per technique, 2, 4 and 6. Not 1/8: with one draw per technique
/// the estimate read sibenik's error at 160×90 low by 1.4–2.8× (a few VPLs' heavy draws, which its eight
/// simulated runs of a pixel rarely see).
const THIN_KEEP: [f32; 3] = [0.25, 0.5, 0.75];

/// Gap terms above this (in squared spacings) count as this: a pixel that selects no cache at all.
const GAP_CAP: f32 = 16.0;

/// Weight of the coverage term against the mean-1 difference and geometry terms.
const GAP_WEIGHT: f32 = 2.0;
/// The difference term is (Diff_avg / mean)^3, divided by its mean again: the contrast of a cube sends the
/// rounds to where the caches disagree most (the squared error of an interpolated value grows faster than
/// the disagreement that predicts it); 1 and 2 were behind on the Cornell box and the staircase.
const DIFF_POWER: i32 = 3;
/// Weight of the leave-one-out term (the mean squared miss of the caches a pixel blends, over its mean)
/// against the mean-1 difference and geometry terms.
const MISS_WEIGHT: f32 = 4.0;
/// The map's selections are made on every second pixel in x and y (the others take their grid pixel's), which
/// halves what a round costs for 1–2 % of RMSE (experiments/results/refine-tuning/MANIFEST.md).
const STRIDE: usize = 2;

/// One round's map (see [`Refine`]); 0 on caches and unusable pixels.
fn round_map(
    g: &GBuffer,
    oracle: &dyn CacheOracle,
    params: &PlacementParams,
    current: &Current,
    taken: &[bool],
    fixed: &Fixed,
) -> Vec<f32> {
    let mask = &fixed.mask;
    let mut d = vec![0f32; g.width * g.height];
    if !oracle.is_empty() {
        let misses = current.misses.as_ref().filter(|_| params.refine_misses);
        let blended = misses.map(|m| m.blended(&current.points, &current.index));
        let extra = blended.as_ref().map(|f| f as PerPixel<'_>);
        let SelectionTerms { mut avg, gap, extra: mut miss, .. } =
            selection_terms(g, &current.index, oracle, true, extra, STRIDE);
        if params.dgs.diff && oracle.len() >= 2 {
            relative(&mut avg, mask);
            avg.par_iter_mut().for_each(|a| *a = a.powi(DIFF_POWER));
            relative(&mut avg, mask);
            d.par_iter_mut().zip(&avg).for_each(|(d, a)| *d += a);
        }
        // The gaps over their root mean square (the finite ones: a pixel that keeps no cache counts the cap).
        let (sum, count) = gap
            .iter()
            .zip(mask)
            .filter(|(x, m)| **m && x.is_finite())
            .fold((0f64, 0usize), |(s, n), (&x, _)| (s + (x as f64).powi(2), n + 1));
        let spacing = if count > 0 { ((sum / count as f64).sqrt() as f32).max(f32::MIN_POSITIVE) } else { 1.0 };
        d.par_iter_mut().zip(&gap).for_each(|(d, &gp)| *d += GAP_WEIGHT * ((gp / spacing).powi(2)).min(GAP_CAP));
        if !miss.is_empty() {
            relative(&mut miss, mask);
            d.par_iter_mut().zip(&miss).for_each(|(d, m)| *d += MISS_WEIGHT * m);
        }
    }
    if let Some(geo) = &fixed.geometry {
        d.par_iter_mut().zip(geo).for_each(|(d, x)| *d += x);
    }
    add_floor(g, &mut d, taken, params.refine_floor);
    d
}

/// What every round's map shares: the usable pixels and the geometry term G / mean(G) (None when the map
/// leaves G out), which depend on the G-buffer alone and are computed once.
struct Fixed {
    mask: Vec<bool>,
    geometry: Option<Vec<f32>>,
}

impl Fixed {
    fn new(g: &GBuffer, params: &PlacementParams) -> Self {
        let mask: Vec<bool> = g.points.par_iter().map(|sp| sp.as_ref().and_then(usable_normal).is_some()).collect();
        let geometry = params.dgs.geometry.then(|| {
            let mut geo = geometry_term(g, params.dgs_window);
            relative(&mut geo, &mask);
            geo
        });
        Fixed { mask, geometry }
    }
}

/// Divides by the mean over the masked pixels (0 where unmasked or when the mean is 0): the term keeps its
/// contrast and has mean 1.
fn relative(v: &mut [f32], mask: &[bool]) {
    let (sum, n) = v
        .iter()
        .zip(mask)
        .filter(|(x, m)| **m && x.is_finite())
        .fold((0f64, 0usize), |(s, n), (&x, _)| (s + x as f64, n + 1));
    let mean = if n > 0 { (sum / n as f64) as f32 } else { 0.0 };
    v.par_iter_mut().zip(mask).for_each(|(x, &m)| *x = if m && mean > 0.0 && x.is_finite() { *x / mean } else { 0.0 });
}

/// Adds `floor × mean(map)` to every free usable pixel (the map is already 0 on caches and unusable pixels);
/// a map that is 0 everywhere becomes uniform over the free usable pixels.
fn add_floor(g: &GBuffer, map: &mut [f32], taken: &[bool], floor: f32) {
    let free: Vec<bool> =
        (0..map.len()).into_par_iter().map(|i| !taken[i] && super::points::is_usable(g, i as u32)).collect();
    let (sum, count) =
        map.iter().zip(&free).filter(|(_, f)| **f).fold((0f64, 0usize), |(s, n), (&v, _)| (s + v as f64, n + 1));
    let mean = if count > 0 { (sum / count as f64) as f32 } else { 0.0 };
    let add = if mean > 0.0 { floor.max(0.0) * mean } else { 1.0 };
    map.par_iter_mut().zip(&free).for_each(|(v, &f)| *v = if f { *v + add } else { 0.0 });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gbuffer::PixelId;
    use crate::placement::test_scenes as ts;
    use crate::placement::{ImageUniform, InitialPlacement, Prediction};

    #[test]
    fn refine_meets_the_contract() {
        ts::check_adaptive(&Refine, &ImageUniform, true);
    }

    #[test]
    fn the_floor_makes_a_zero_map_uniform_and_keeps_caches_out() {
        let g = ts::flat(16, 8);
        let mut taken = vec![false; 16 * 8];
        taken[5] = true;
        let mut map = vec![0f32; 16 * 8];
        add_floor(&g, &mut map, &taken, 0.5);
        assert_eq!(map[5], 0.0);
        assert!((0..map.len()).filter(|&i| i != 5 && g.points[i].is_some()).all(|i| map[i] == 1.0));
        let mut map: Vec<f32> = (0..16 * 8).map(|i| (i % 3) as f32).collect();
        map[5] = 0.0;
        add_floor(&g, &mut map, &taken, 0.5);
        assert_eq!(map[5], 0.0);
        // Mean of the free pixels' i mod 3 is about 1: every free pixel gains about 0.5.
        assert!(map.iter().enumerate().all(|(i, &v)| i == 5 || g.points[i].is_none() || v >= 0.45));
    }

    #[test]
    fn the_rounds_fill_a_region_the_first_stage_left_empty() {
        // Caches on the left half of a flat plane only: the coverage term sends most new caches right,
        // though the plane's AO is the same everywhere (no difference or geometry term to follow).
        let g = ts::plane(96, 64);
        let left: Vec<u32> = (0..g.points.len() as u32)
            .filter(|&i| {
                (i as usize % 96) < 48 && (i as usize / 96).is_multiple_of(4) && (i as usize).is_multiple_of(4)
            })
            .filter(|&i| crate::placement::points::is_usable(&g, i))
            .collect();
        let mut oracle = ts::MaskOracle::new(&g, &left);
        let p = PlacementParams::default();
        let s1 = Stage1 { sites: left.clone(), ..Default::default() };
        let info = Refine.place(&g, &s1, &mut oracle, 200, &p, 3).unwrap();
        assert_eq!(info.added, 200);
        let right = oracle.sites[left.len()..].iter().filter(|&&id| id as usize % 96 >= 48).count();
        assert!(right >= 140, "only {right} of 200 new caches went to the empty half (uniform: about 100)");
    }

    /// The mask oracle with shading noise, as importance caching's estimate has: every pixel keeps `floor`
    /// over keep^`power`, keep being the share of draws shading was last thinned to ([`CacheOracle::thin`]).
    struct Drawing<'a> {
        inner: ts::MaskOracle<'a>,
        floor: f32,
        power: i32,
        keep: f32,
    }

    impl CacheOracle for Drawing<'_> {
        fn len(&self) -> usize {
            self.inner.len()
        }
        fn site(&self, c: CacheId) -> PixelId {
            self.inner.site(c)
        }
        fn diff(&self, a: CacheId, b: CacheId) -> f32 {
            self.inner.diff(a, b)
        }
        fn evaluate(&mut self, sites: &[PixelId]) {
            self.inner.evaluate(sites)
        }
        fn predict_many(&mut self, asks: &[(CacheId, Vec<(CacheId, f32)>)]) -> Vec<Option<Prediction>> {
            let floor = self.floor / self.keep.powi(self.power);
            self.inner.predict_many(asks).into_iter().map(|p| p.map(|p| Prediction { floor, ..p })).collect()
        }
        fn thin(&mut self, keep: f32) -> bool {
            self.keep = keep.min(1.0);
            true
        }
    }

    #[test]
    fn a_target_the_caches_beat_is_met_with_the_fewest_draws_whose_estimate_meets_it() {
        let g = ts::plane(160, 96);
        let run = |target: f32, power: i32| {
            let p = PlacementParams {
                target: Some(TargetError { relative: target, added_mean: 0.0 }),
                ..PlacementParams::default()
            };
            let first = crate::placement::registry::strategy("refine").unwrap().first_stage_budget(8000, &p);
            let s1 = ImageUniform.place(&g, first, &p, ts::SEED).unwrap();
            let inner = ts::MaskOracle::new(&g, &s1.sites);
            let mut oracle = Drawing { inner, floor: 0.1, power, keep: 1.0 };
            let info = Refine.place(&g, &s1, &mut oracle, 8000 - first, &p, ts::SEED).unwrap();
            (oracle.keep, info)
        };
        // A target far above the first stage's error: the fewest draws tried, estimated again and recorded.
        let (keep, info) = run(10.0, 1);
        let (first, last) = (info.estimates[0], *info.estimates.last().unwrap());
        assert_eq!(keep, THIN_KEEP[0]);
        assert_eq!((info.estimates.len(), last.caches), (2, first.caches));
        assert!(last.relative_rmse > first.relative_rmse && last.relative_rmse <= 10.0, "{info:?}");
        assert!(info.notes.iter().any(|n| n.contains("shading draws 0.25 of its samples")), "{:?}", info.notes);
        // Just above it: no fraction fits the room (the variance grows at least as 1 / keep), so none is tried.
        let (keep, info) = run(first.relative_rmse * 1.05, 1);
        assert_eq!((keep, info.estimates.len()), (1.0, 1));
        assert!(info.notes.is_empty(), "{:?}", info.notes);
        // Room for some, but the estimates with fewer draws exceed the target: shading keeps all its draws.
        let (keep, info) = run(first.relative_rmse * 1.9, 12);
        assert_eq!((keep, info.estimates.len()), (1.0, 1));
        assert!(info.notes.is_empty(), "{:?}", info.notes);
    }

    #[test]
    fn a_target_error_stops_the_rounds_when_the_estimate_meets_it() {
        let g = ts::plane(160, 96);
        let run = |target: f32, budget: usize| {
            let p = PlacementParams {
                target: Some(TargetError { relative: target, added_mean: 0.0 }),
                ..PlacementParams::default()
            };
            let first = crate::placement::registry::strategy("refine").unwrap().first_stage_budget(budget, &p);
            let s1 = ImageUniform.place(&g, first, &p, ts::SEED).unwrap();
            let mut oracle = ts::MaskOracle::new(&g, &s1.sites);
            let info = Refine.place(&g, &s1, &mut oracle, budget - first, &p, ts::SEED).unwrap();
            (first, oracle.sites.len(), info)
        };
        // A loose target: the first stage (1/256 of the ceiling, at least 16) may already meet it.
        let (first, loose, info) = run(0.5, 8000);
        assert_eq!(first, 31);
        assert_eq!(info.estimates[0].caches, first);
        assert!(loose < 400, "{loose} caches for a 50 % target");
        // A tighter one: rounds until the last estimate meets it, each recorded; the count falls short of the
        // ceiling, and the estimates fall.
        let (_, tight, info) = run(0.05, 8000);
        let last = info.estimates.last().unwrap();
        assert!(tight > loose && tight < 8000, "{tight}: {info:?}");
        assert_eq!(last.caches, tight);
        assert!(last.relative_rmse <= 0.05, "{info:?}");
        assert!(info.estimates.windows(2).all(|w| w[1].caches > w[0].caches), "{:?}", info.estimates);
        assert!(info.notes.is_empty(), "{:?}", info.notes);
        // An unreachable one: the whole ceiling, and a note that says so.
        let (_, all, info) = run(1e-6, 600);
        assert_eq!(all, 600);
        assert!(info.notes.iter().any(|n| n.contains("not met")), "{:?}", info.notes);
        // The thread count changes nothing.
        let two = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap().install(|| run(0.05, 8000));
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| run(0.05, 8000));
        assert_eq!((one.1, one.2), (two.1, two.2));
    }
}
