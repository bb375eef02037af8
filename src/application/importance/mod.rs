//! Importance caching over virtual point lights (Georgiev et al. 2012; the paper's §4.2; ALGORITHMS.md
//! §6.3), registered as `importancecache`.
//!
//! The scene's light is represented by `vpls` virtual point lights ([`vpl`]). A cache stores, per VPL,
//! the luminance of its contribution at the cache with visibility (F) and without (U) — VPLs close together
//! as the cache sees them share their shadow rays there ([`visibility`], parameter `visangle`; 0: one ray
//! per VPL that could contribute, as in the paper) — and, once placement is over and the region the cache
//! serves is known, an upper bound over that region (B); each is kept as a quantised distribution over the
//! VPLs ([`distribution`], about one byte per VPL). A sub-pixel sample draws VPLs from each technique F, U, B
//! and C (uniform over all VPLs): `lightsamples` per letter of `distributions` (default
//! [`DEFAULT_LIGHT_SAMPLES`]; ALGORITHMS.md §6.3 and the paper: one each), a count after a letter repeating
//! it, with halvings of U's and B's draws in favour of F that each cache learns from how well its neighbours
//! sample its own light (`learnshares`, default 2; [`ImportanceCache::shares`]), each the mixture of its
//! selected caches' distributions — weighted by their interpolation weights (`mixweight`; beyond
//! ALGORITHMS.md §6.3, whose mixture is uniform) — and combines them by multiple importance sampling
//! ([`mixture`]): the balance heuristic by default, α-max as an option. Every draw costs one shadow ray.
//! The positions the draws take in the distributions are stratified across the pixel's sub-pixel samples
//! ([`Stratum`], parameter `stratify`) — a choice beyond ALGORITHMS.md §6.3, which draws each sample
//! independently: every draw alone is distributed as before, so the estimator is unchanged in expectation,
//! and the pixel's samples stop clumping on the same VPLs (measured in `experiments/notes/importance.md`).
//! Directly seen emitters add their radiance. The few VPLs a near-specular lobe singles out at a shading
//! point, and those closer to it than d_c, are drawn apart there, in every sampling mode ([`split`],
//! parameters `splitcone` and `splitnear`). A glossy lobe wider than that (up to `lobecone`) adds a fifth
//! technique, G, drawing among the VPLs in its cone by flux, the lobe's falloff and clamped squared distance
//! ([`lobe`]) — beyond ALGORITHMS.md §6.3's four, for the glossy receivers whose caches give their lobe's
//! VPLs no density.
//!
//! `placement none` is the reference: the exact sum over every VPL with visibility at every sub-pixel
//! sample — the noise-free many-light image the cached estimator is unbiased for (same VPLs, same clamp).
//! `"string sampling"` `uniform` or `power` renders the standard many-light estimators instead (the same
//! number of VPL draws per sample, chosen uniformly or in proportion to each VPL's flux), with no caches.
//!
//! DGS compares two caches by `Σ_j |F_a[j] − F_b[j]|` and, as the paper found best for importance caching,
//! without the geometry term ([`CachePlan::dgs_geometry`]; `vgc+dgs:geom` still has it).
//!
//! Its parameters are declared and read in [`params`].

mod compensation;
pub mod distribution;
mod leave_one_out;
pub mod lobe;
pub mod mixture;
pub mod params;
pub mod spheres;
pub mod split;
pub mod visibility;
pub mod vpl;

use crate::error::{Error, Result, Warnings};
use crate::gbuffer::ShadingPoint;
use crate::gbuffer::scale::SceneScale;
use crate::parse::integrator::{IntegratorParams, Parameter};
use crate::sampling::rng::hash3;
use crate::sampling::{Cdf, Rng, Stratum};
use crate::scene::Scene;
use crate::scene::accel::OccluderHint;
use crate::scene::ray::RayCounters;
use crate::shading::light::LightSelect;
use crate::shading::lighting::Shading;
use crate::shading::{Spectrum, luminance};

use super::{Application, CachePlan, LeaveOneOut, Neighbour, PerSample, Study};
use distribution::Quantised;
use lobe::LobeTree;
use mixture::{Blend, CONSERVATIVE, LETTERS, LOBE, Mis, Mixture, TECHNIQUES};
use split::Split;
use vpl::{Receiver, Vpls};

/// Stream tag of VPL generation.
const STAGE_VPLS: u64 = 0x7670_6c73;

/// Most levels of `learnshares`: U and B halved three times.
pub const MAX_SHARE_LEVEL: u32 = 3;

/// Stratum stream of the baselines' draws (the techniques use their index, 0–4).
const STREAM_BASELINE: u64 = 16;

/// Most draws G may make per sample (its letters in `distributions` times `lightsamples`), and most
/// `lightsamples`; F, U, B and C may make more ([`params`]).
const MAX_TECHNIQUE_DRAWS: u32 = lobe::MAX_DRAWS as u32;

/// A vertex no cache serves (seen in a mirror or through glass) draws this many times as many VPLs by flux
/// as a baseline sample would ([`ImportanceCache::fallback_draws`]). Such a vertex has no caches' light to
/// draw by, and power sampling's variance per draw is many times importance caching's, so with the same
/// draws those few vertices held much of a scene's error. Spending draws where they lower the error most,
/// n draws of variance V_p each against m of V_i at costs c_p and c_i per draw, asks n / m =
/// √(V_p c_i / (V_i c_p)), about 4–6 with the equal-draw RMSE ratios of 3.3–5.3 measured against power
/// sampling; experiments/notes/importance-tried.md ("Vertices no cache serves") has the bathroom's sweep.
const FALLBACK_FACTOR: u32 = 4;

/// Default of `lightsamples`: the draws each letter of `distributions` makes per sub-pixel sample.
/// ALGORITHMS.md §6.3 (after the paper) draws one per technique, four light samples per shading point; we
/// draw eight per technique. A shading point's fixed work (its camera ray, the search for its caches, the
/// mixture, the split and G's walk) cost half to three quarters of the render stage at one draw per technique
/// on the three 640×360 scenes of `experiments/notes/importance.md`, so further draws come cheap, and, stratified
/// across the pixel's samples, they lower the error faster than one over their count: error² × time fell
/// 4.7–5.7× from one to eight draws per technique on each of the three, and 1.3–1.4× more from eight to
/// sixteen, which doubles the time of an image (the table there). How the 32 draws of F, U, B and C are
/// shared may be learnt per cache (`learnshares`, [`ImportanceCache::shares`]).
pub const DEFAULT_LIGHT_SAMPLES: u32 = 8;

/// How a sample chooses its VPLs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// From its caches (importance caching; `placement none`: the exact sum).
    Cache,
    /// Uniformly among the VPLs, no caches.
    Uniform,
    /// In proportion to each VPL's flux, no caches (the standard many-light estimator).
    Power,
}

impl Sampling {
    fn name(self) -> &'static str {
        match self {
            Sampling::Cache => "cache",
            Sampling::Uniform => "uniform",
            Sampling::Power => "power",
        }
    }
}

/// How a shading point combines the learnt levels of its caches ([`ImportanceCache::shares`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShareLevel {
    /// The mean of their levels, rounded down (the default).
    Mean,
    /// The smallest of their levels: the shares of the most defensive cache.
    Min,
}

impl ShareLevel {
    fn name(self) -> &'static str {
        match self {
            ShareLevel::Mean => "mean",
            ShareLevel::Min => "min",
        }
    }
}

/// The importance-caching application's settings.
#[derive(Clone, Debug)]
pub struct ImportanceCache {
    /// VPLs to generate.
    pub vpls: usize,
    /// Surface vertices of a light path.
    pub max_depth: u32,
    /// Seed of VPL generation.
    pub vpl_seed: u64,
    /// d_c as a fraction of the scene's length scale L.
    pub clamp: f32,
    /// d_c = `clamp` · L, in scene units (resolved from the scene's length scale).
    pub clamp_distance: f32,
    /// VPLs drawn where the clamp's loss is put back, per sample (0: not put back; [`compensation`]).
    pub compensate: u32,
    /// Samples each technique (F, U, B, C, G) draws per sub-pixel sample (0: not used; G only where the
    /// shading point has a lobe in its range): its letters in `distributions` times `light_samples`.
    pub techniques: [u32; TECHNIQUES],
    /// Draws per letter of `distributions` (`lightsamples`).
    pub light_samples: u32,
    /// How their samples are combined.
    pub mis: Mis,
    /// Caches, or a baseline without them.
    pub sampling: Sampling,
    /// VPLs a baseline draws per sample (0: one per enabled technique).
    pub draws: u32,
    /// VPLs drawn by flux at a vertex no cache serves (`fallbackdraws`; 0: [`FALLBACK_FACTOR`] times
    /// [`ImportanceCache::baseline_draws`]; [`Application::estimate`]).
    pub fallback_draws: u32,
    /// Widest sharp-lobe cone summed apart at the shading point, degrees (0: no cones; [`split`]).
    pub split_cone: f32,
    /// Radius of the ball around the shading point whose VPLs are summed apart, in units of d_c (0: no
    /// ball; [`split`]).
    pub split_near: f32,
    /// Widest angle, degrees, of a run of VPLs whose shadow rays a cache's record shares (0: one ray per
    /// VPL; [`visibility`]).
    pub vis_angle: f32,
    /// Widest glossy lobe, degrees, for which the lobe technique G draws (lobes wider than `split_cone`;
    /// [`lobe`]).
    pub lobe_cone: f32,
    /// Whether the draws of a pixel's sub-pixel samples are stratified across them ([`Stratum`]; else each
    /// sample draws independently).
    pub stratify: bool,
    /// Most times a cache may halve the draws of U and B in favour of F (`learnshares`; 0: the shares of
    /// `distributions` everywhere; [`ImportanceCache::shares`]).
    pub learn_shares: u32,
    /// How a shading point takes its caches' levels (`sharelevel`).
    pub share_level: ShareLevel,
    /// The power of the interpolation weight by which the selected caches are mixed (`mixweight`; 0: each
    /// alike; [`mixture`]).
    pub mix_weight: f32,
}

/// One importance cache: where it is (B is built from it once its region is known) and its F, U and B
/// distributions over the VPLs (`None`: all zero, or the technique is not used).
#[derive(Clone, Debug)]
pub struct ImportanceRecord {
    at: ShadingPoint,
    dists: [Option<Quantised>; 3],
    /// How many times shading near the cache halves the draws of U and B in favour of F
    /// ([`ImportanceCache::shares`]; 0 until the lesson).
    level: u8,
}

/// The scene as importance caching reads it: its shading data, the VPLs and the power-sampling table.
pub struct Lit<'s> {
    scene: &'s Scene,
    shading: Shading<'s>,
    vpls: Vpls,
    /// The VPLs' flux as a distribution, for `sampling power`.
    flux: Cdf,
    /// The split: near VPLs and near-specular lobes.
    split: Split,
    /// The VPL tree of the lobe technique G.
    lobes: LobeTree,
}

impl Lit<'_> {
    /// The receiver at a sample: its surface, BSDF and view direction (`None` without a BSDF).
    fn receiver(&self, s: &ShadingPoint) -> Option<Receiver> {
        let si = s.interaction()?;
        let bsdf = self.shading.bsdf(&si)?;
        Some(Receiver::new(si, bsdf, s.wo))
    }

    /// Emission seen directly at a sample.
    fn emitted(&self, s: &ShadingPoint) -> Spectrum {
        match s.interaction() {
            Some(si) if si.area_light.is_some() => self.shading.lights.emitted(&si, s.wo),
            _ => Spectrum::ZERO,
        }
    }

    /// I_j at `x` with visibility.
    fn contribution(&self, j: usize, x: &Receiver, rays: &mut RayCounters) -> Spectrum {
        self.vpls.contribution(self.scene, &self.shading, j, x, rays)
    }

    /// A VPL drawn in proportion to its flux with 64 uniform bits `u`, with its probability.
    fn sample_power(&self, u: u64) -> Option<(usize, f64)> {
        self.flux.sample(crate::sampling::unit_f64(u))
    }
}

impl ImportanceCache {
    /// VPLs a baseline draws per sample: `draws`, or as many as the techniques F, U, B and C draw together
    /// (G draws only at some shading points). Also the split's shadow rays under importance caching.
    fn baseline_draws(&self) -> u32 {
        if self.draws > 0 { self.draws } else { self.techniques[..LOBE].iter().sum() }
    }

    /// VPLs drawn by flux at a vertex no cache serves: `fallbackdraws`, or [`FALLBACK_FACTOR`] times
    /// [`ImportanceCache::baseline_draws`].
    fn fallback_draws(&self) -> u32 {
        if self.fallback_draws > 0 { self.fallback_draws } else { FALLBACK_FACTOR * self.baseline_draws() }
    }

    /// How a shading point mixes its caches: by weight unless `mixweight` is 0.
    fn blend(&self) -> Blend {
        if self.mix_weight > 0.0 { Blend::Weighted } else { Blend::Uniform }
    }

    /// The selected caches' distributions, each with its weight in the mixture: the interpolation weight
    /// 1/Dist to the power `mixweight` (ignored by a uniform blend). A mixture weighted by 1/Dist, which
    /// joins the difference in position and in normal, is one reading of the original's "bilateral" MIS,
    /// which ALGORITHMS.md §6.3 left open and read as a uniform mixture. Measured against that at equal
    /// draws (experiments/notes/importance-tried.md, "The caches mixed by their weights"): power 1 gave
    /// sibenik at 640×360 a 1.045× lower RMSE over three seeds, where power 2 gave 1.027× (and 4 was worse
    /// than uniform); the Cornell box 1.043× (power 2: 1.069×); the bathroom 1.016× (power 2: 1.015×);
    /// HDR-FLIP 2.5–7 % lower. Sibenik is the scene furthest from issue 44's goal, so the default is 1.
    fn mixed<'n>(
        &self,
        near: &'n [Neighbour<'_, ImportanceRecord>],
    ) -> impl Iterator<Item = (&'n [Option<Quantised>; 3], f32)> + Clone + use<'n, '_> {
        let power = self.mix_weight;
        // The largest weight is needed only to take other powers as ratios (not at the default, 1).
        let largest =
            if power == 0.0 || power == 1.0 { 1.0 } else { near.iter().map(|c| c.weight).fold(0.0, f32::max) };
        near.iter().map(move |c| (&c.record.dists, mix_weight(c.weight, largest, power)))
    }

    /// The draws of each technique at level `level`: U and B each halved `level` times (rounded down, and at
    /// least one where they draw), F taking what they give up, so F, U, B and C together draw as many as
    /// `distributions` asks; C and G unchanged. Level 0 is `distributions` itself; by default (8 each) level 1
    /// is F 16, U 4, B 4, C 8, level 2 F 20, U 2, B 2, C 8.
    ///
    /// Beyond ALGORITHMS.md §6.3, which gives every technique one draw. Under the balance heuristic the draws
    /// are one mixture of the techniques' densities, so every draw of U or B is taken from F, the technique
    /// the caches exist for, which is nearly proportional to the light wherever a cache's neighbours see what
    /// it sees; U, B and C are the defence where they do not. The best fixed shares differ by scene (measured in
    /// `experiments/notes/importance-shares.md`: F 24, U 4, B 2, C 2 gave sibenik 20–29 % less RMSE than eight each at
    /// the same time at 640×360, but the bathroom 11 % more at 320×180, whose fireflies — VPLs lighting the blinds
    /// through gaps its caches do not see — U and B catch), so each cache learns its level
    /// ([`Application::lesson`]) and a shading point takes the mean of its caches' levels, rounded down.
    ///
    /// C keeps its draws: it is the one technique whose weight is bounded everywhere (by the VPL count over its
    /// draws), and the lesson cannot see the light it guards — VPLs a shading point sees that no cache near it
    /// does, such as those behind its caches' tangent planes. Halving C too (the first version) gave the small
    /// room of `tests/target_error.rs` fireflies (24 % more RMSE); with C kept it is within 3 % there, the
    /// bathroom ties in RMSE (0.2 %) with 5.7 % less HDR-FLIP, and the Cornell box and sibenik keep most of the
    /// gain (10–11 % and 19–21 % less RMSE at about the same time). Where the caches are sparsest (the Cornell box
    /// at 160×90 with 174 caches) SD and SD+AS have 4–8 % more RMSE with the learnt levels.
    fn shares(&self, level: u8) -> [u32; TECHNIQUES] {
        let mut d = self.techniques;
        if level == 0 || d[0] == 0 {
            return d;
        }
        let total: u32 = d[..LOBE].iter().sum();
        for n in d[1..CONSERVATIVE].iter_mut().filter(|n| **n > 0) {
            *n = (*n >> level).max(1);
        }
        d[0] = total - d[1..LOBE].iter().sum::<u32>();
        d
    }

    /// The level of a shading point: the mean of its selected caches' levels, rounded down (the more defensive
    /// of two), or with `sharelevel min` the smallest.
    ///
    /// Why `min` is offered: a cache's lesson is made at its own site, so where every cache near a shading point
    /// misses a VPL the point sees (occluded or behind the caches' tangent planes), no lesson can tell, and U's
    /// and B's draws are what catches it. Under the mean one cache whose neighbours agree with it can lower
    /// the level of a shading point that its other caches would keep defended. Measured in
    /// `experiments/notes/importance-shares.md` ("The mean of the levels or the least"): the Cornell box's
    /// losses with the learnt shares at 160×90 and 174 caches are fireflies of that kind, and the least level
    /// removes most of them.
    fn level(&self, near: &[Neighbour<'_, ImportanceRecord>]) -> u8 {
        let levels = near.iter().map(|c| c.record.level);
        match self.share_level {
            ShareLevel::Mean => {
                let n = near.len().max(1) as u32;
                (levels.map(u32::from).sum::<u32>() / n) as u8
            }
            ShareLevel::Min => levels.min().unwrap_or(0),
        }
    }

    /// The techniques as the `distributions` parameter spells them: each letter with its count of
    /// `lightsamples` draws when that is more than one (`f12u2bcg4`).
    fn letters(&self) -> String {
        let per = self.light_samples.max(1);
        (0..TECHNIQUES)
            .filter(|&t| self.techniques[t] > 0)
            .map(|t| match self.techniques[t] / per {
                1 => LETTERS[t].to_string(),
                n => format!("{}{n}", LETTERS[t]),
            })
            .collect()
    }

    /// The per-sample baselines: `k` VPLs drawn uniformly or by flux (`sampling`), averaged.
    #[allow(clippy::too_many_arguments)]
    fn baseline(
        &self,
        cx: &Lit<'_>,
        x: &Receiver,
        sampling: Sampling,
        k: u32,
        rng: &mut Rng,
        stratum: Stratum,
        rays: &mut RayCounters,
    ) -> Spectrum {
        let n = cx.vpls.len();
        let k = k.max(1);
        let split = cx.split.at(x);
        let mut l = split.estimate(cx.scene, &cx.shading, &cx.vpls, x, k, rng, rays);
        for d in 0..k {
            let u = self.stratify.then(|| stratum.draw(STREAM_BASELINE, d, k));
            let (j, p) = match sampling {
                Sampling::Uniform if n > 0 => {
                    let j = match u {
                        Some(u) => ((u as u128 * n as u128) >> 64) as usize,
                        None => rng.below(n as u32) as usize,
                    };
                    (j, 1.0 / n as f64)
                }
                Sampling::Power => match cx.sample_power(u.unwrap_or_else(|| rng.next_u64())) {
                    Some(d) => d,
                    None => continue,
                },
                _ => continue,
            };
            if !split.holds(&cx.vpls, j) {
                l += cx.contribution(j, x, rays) * (1.0 / (p * k as f64)) as f32;
            }
        }
        l
    }

    /// A sample's light without caches: its emission plus, with `sampling` `Cache`, the exact sum over every
    /// VPL (the reference), else the baseline that draws `k` VPLs that way.
    #[allow(clippy::too_many_arguments)]
    fn without_caches(
        &self,
        cx: &Lit<'_>,
        s: &ShadingPoint,
        sampling: Sampling,
        k: u32,
        rng: &mut Rng,
        stratum: Stratum,
        rays: &mut RayCounters,
    ) -> [f32; 3] {
        let start = rng.clone();
        let mut l = cx.emitted(s);
        if let Some(x) = cx.receiver(s) {
            l += match sampling {
                Sampling::Cache => (0..cx.vpls.len()).map(|j| cx.contribution(j, &x, rays)).sum(),
                _ => self.baseline(cx, &x, sampling, k, rng, stratum, rays),
            };
            l += compensation::clamp_loss(cx, &x, self.compensate, self.max_depth, &start, rays);
        }
        l.to_array()
    }

    /// The B distribution of a cache at `at` serving a region of radius `region`.
    fn bounded(&self, cx: &Lit<'_>, at: &ShadingPoint, region: f32) -> Option<Quantised> {
        let x = cx.receiver(at)?;
        let mut w: Vec<f32> = (0..cx.vpls.len()).map(|j| cx.vpls.bound(&cx.shading, j, &x, region)).collect();
        let local = cx.split.at(&x);
        local.for_each(&cx.vpls, |j| {
            if local.holds_throughout(&cx.vpls, j, region) {
                w[j] = 0.0
            }
        });
        Quantised::new(&w)
    }
}

impl Application for ImportanceCache {
    const NAME: &'static str = "importancecache";
    const ABOUT: &'static str =
        "importance caching: light from virtual point lights drawn by MIS from cached distributions";
    const PARAMETERS: &'static [Parameter] = params::PARAMETERS;
    const PAPER_CACHES: usize = 25_000;
    /// A light path's surface vertices: pbrt-v3 `path`'s maxdepth counts the camera's vertex too.
    const PATH_DEPTH: Option<&'static str> = Some("vpldepth");
    /// `draws` VPLs drawn by flux at every sub-pixel sample (the VPL sum the reference evaluates whole); the
    /// power and uniform baselines.
    const STUDY: Study<Self> = Study {
        quick: &[("vpls", "1024")],
        per_sample: Some(PerSample { count: "draws", set: &[("sampling", "power")] }),
        baselines: ImportanceCache::baselines,
    };

    type Record = ImportanceRecord;
    type Prepared<'s> = Lit<'s>;

    fn from_params(p: &IntegratorParams<'_>, scale: &SceneScale) -> Result<Self> {
        Self::read(p, scale.length)
    }

    fn scale_derived(&self) -> Vec<(&'static str, f32)> {
        vec![("clamp_distance", self.clamp_distance)]
    }

    fn prepare<'s>(&self, scene: &'s Scene, warnings: &mut Warnings) -> Result<Lit<'s>> {
        let shading = Shading::build(scene, true, warnings)?;
        let vpls = if shading.lights.is_empty() {
            Vpls::none(self.clamp_distance)
        } else {
            let select = LightSelect::new(&shading.lights, "power").map_err(Error::usage)?;
            let mut rng = Rng::keyed(self.vpl_seed, STAGE_VPLS, 0);
            Vpls::generate(scene, &shading, &select, self.vpls, self.max_depth, self.clamp_distance, &mut rng)
        };
        if !shading.lights.is_empty() && vpls.len() < self.vpls {
            warnings.general(format!(
                "{}: only {} of {} VPLs from {} light paths (the lights' paths carry nothing or leave the scene)",
                Self::NAME,
                vpls.len(),
                self.vpls,
                vpls.paths
            ));
        }
        let flux = Cdf::new(vpls.flux.iter().copied());
        let split = Split::new(&vpls, self.split_cone.to_radians(), self.split_near * vpls.clamp2.sqrt());
        let lobes = LobeTree::new(&vpls, self.split_cone.to_radians(), self.lobe_cone.to_radians());
        Ok(Lit { scene, shading, vpls, flux, split, lobes })
    }

    fn shading<'a, 's>(&self, cx: &'a Self::Prepared<'s>) -> Option<&'a Shading<'s>> {
        Some(&cx.shading)
    }

    fn settings(&self) -> Vec<(&'static str, serde_json::Value)> {
        self.settings_report()
    }

    /// The VPLs generated (fewer than `vpls` when the lights' paths carry nothing), the light paths traced
    /// for them, and the VPLs whose sharp lobe sends a beam that the split draws apart.
    fn prepared_report(&self, cx: &Lit<'_>) -> Vec<(&'static str, serde_json::Value)> {
        vec![
            ("vpls_generated", cx.vpls.len().into()),
            ("light_paths", cx.vpls.paths.into()),
            ("vpl_beams", cx.split.beam_count().into()),
        ]
    }

    /// Without the geometry term in DGS (the paper's finding); `sampling uniform` and `power` read no caches.
    fn plan(&self) -> CachePlan {
        let shade_by_reference = match self.sampling {
            Sampling::Cache => None,
            s => Some(format!("\"sampling\" \"{}\" draws VPLs without caches", s.name())),
        };
        CachePlan {
            dgs_geometry: false,
            refine_misses: false,
            shade_by_reference,
            follow_specular: true,
            shows_environment: true,
            learns: self.learn_shares > 0 && self.sampling == Sampling::Cache,
            ..CachePlan::default()
        }
    }

    fn compute_record(&self, cx: &Lit<'_>, at: &ShadingPoint, _: &mut Rng, rays: &mut RayCounters) -> ImportanceRecord {
        let Some(x) = cx.receiver(at) else { return ImportanceRecord { at: *at, dists: [None, None, None], level: 0 } };
        let n = cx.vpls.len();
        let mut unoccluded: Vec<f32> =
            (0..n).map(|j| cx.vpls.unoccluded_value(&cx.shading, j, &x).map_or(0.0, luminance)).collect();
        // The VPLs of the cache's own split are drawn apart wherever they matter: left in, the spikes of
        // its sharp lobes and the clamped maxima of its near VPLs would take most of the distribution.
        // (Measured for the near ones: keeping them here raised the 320×180 bathroom's MSE without its worst
        // 0.1 % of pixels from 0.0294 to 0.0316 over 12 seeds, with one seed's firefly back.)
        cx.split.at(&x).for_each(&cx.vpls, |j| unoccluded[j] = 0.0);
        // A VPL whose unoccluded contribution quantises to 0 gets no shadow ray: F is 0 for it too (C still
        // draws it), and the shadow rays go to the VPLs that matter. (With every value 0 there is nothing
        // to trace: F and U are both empty.)
        let max = distribution::finite_max(&unoccluded);
        let full = if max > 0.0 {
            let mut hint = OccluderHint::default();
            let position = |j: usize| {
                let v = &cx.vpls.list[j];
                (!matches!(v.emitter, vpl::Emitter::Directional)).then_some(v.p)
            };
            visibility::full_values(
                x.si.p,
                position,
                &unoccluded,
                Quantised::smallest_kept(max),
                self.vis_angle.to_radians(),
                |j| {
                    rays.shadow += 1;
                    !cx.scene.geometry.occluded_hinted(&cx.vpls.shadow_ray(j, &x), None, &mut hint)
                },
            )
        } else {
            vec![0.0f32; n]
        };
        ImportanceRecord { at: *at, dists: [Quantised::new(&full), Quantised::new(&unoccluded), None], level: 0 }
    }

    fn diff(&self, a: &ImportanceRecord, b: &ImportanceRecord) -> f32 {
        match (&a.dists[0], &b.dists[0]) {
            (Some(fa), Some(fb)) => fa.abs_diff_sum(fb),
            (Some(f), None) | (None, Some(f)) => f.value_sum(),
            (None, None) => 0.0,
        }
    }

    /// B needs the region the cache serves; techniques that are not used are dropped.
    fn finish_record(&self, cx: &Lit<'_>, record: &mut ImportanceRecord, region: f32) {
        record.dists[2] = if self.techniques[2] > 0 { self.bounded(cx, &record.at, region) } else { None };
        for t in 0..2 {
            if self.techniques[t] == 0 {
                record.dists[t] = None;
            }
        }
    }

    /// The level ([`ImportanceCache::shares`]) under which the caches that shading at this cache's site blends
    /// besides it sample its light with the least variance: its F values as the light, one sample's variance
    /// under the balance heuristic ([`leave_one_out::sampled`]) at each level up to `learnshares`. Where the
    /// neighbours' F sees what the cache sees, F alone is nearly proportional to the light and the defensive
    /// techniques only dilute it; where it does not (a shadow's edge, a VPL behind blinds), U and B keep
    /// their draws (and C always keeps its own: [`ImportanceCache::shares`]).
    fn lesson(&self, cx: &Lit<'_>, own: &ImportanceRecord, near: &[Neighbour<'_, ImportanceRecord>]) -> u8 {
        let Some(f) = &own.dists[0] else { return 0 };
        if near.is_empty() {
            return 0;
        }
        let n = cx.vpls.len();
        let mut best = (f32::INFINITY, 0u8);
        for level in 0..=self.learn_shares.min(MAX_SHARE_LEVEL) as u8 {
            let v = leave_one_out::sampled(f, self.blend(), self.mixed(near), self.shares(level), n).variance;
            if v < best.0 {
                best = (v, level);
            }
        }
        best.1
    }

    /// Shading with caches is unbiased, so its error is the noise of its draws: every letter of
    /// `distributions` draws `keep` × `lightsamples` times, rounded up (at least once).
    fn thinned(&self, keep: f32) -> Option<Self> {
        let now = self.light_samples;
        if self.sampling != Sampling::Cache || !(keep > 0.0 && keep < 1.0) {
            return None;
        }
        let fewer = ((now as f32 * keep).ceil() as u32).clamp(1, now);
        if fewer == now {
            return None;
        }
        let mut thin = self.clone();
        thin.light_samples = fewer;
        // Each technique draws its letters' count times `lightsamples`.
        thin.techniques = self.techniques.map(|d| d / now * fewer);
        Some(thin)
    }

    fn keep_lesson(&self, record: &mut ImportanceRecord, lesson: u8) {
        record.level = lesson;
    }

    fn shade(
        &self,
        cx: &Lit<'_>,
        s: &ShadingPoint,
        near: &[Neighbour<'_, ImportanceRecord>],
        rng: &mut Rng,
        stratum: Stratum,
        rays: &mut RayCounters,
    ) -> [f32; 3] {
        let start = rng.clone();
        let mut l = cx.emitted(s);
        if let Some(x) = cx.receiver(s) {
            let draws = self.shares(self.level(near));
            let lobe = match draws[LOBE] {
                0 => None,
                m => {
                    let mut us = [0u64; lobe::MAX_DRAWS];
                    for (d, u) in us.iter_mut().enumerate().take(m as usize) {
                        *u = if self.stratify { stratum.draw(LOBE as u64, d as u32, m) } else { rng.next_u64() };
                    }
                    cx.lobes.at(&cx.vpls, &x, &us[..m as usize])
                }
            };
            let mix = Mixture::new(self.mixed(near), self.blend(), draws, cx.vpls.len(), lobe);
            let split = cx.split.at(&x);
            l += split.estimate(cx.scene, &cx.shading, &cx.vpls, &x, self.baseline_draws(), rng, rays);
            for t in 0..TECHNIQUES {
                let m = mix.draws(t);
                for d in 0..m {
                    let u = self.stratify.then(|| stratum.draw(t as u64, d, m));
                    let Some(j) = mix.sample(t, d, u, rng) else { continue };
                    let factor = mix.factor(t, j, self.mis);
                    if factor > 0.0 && !split.holds(&cx.vpls, j) {
                        l += cx.contribution(j, &x, rays) * factor;
                    }
                }
            }
            l += compensation::clamp_loss(cx, &x, self.compensate, self.max_depth, &start, rays);
        }
        l.to_array()
    }

    /// Shading is unbiased, so the neighbours do not miss the cache's light but sample it with noise: the
    /// variance of a pixel's value at the site drawing from their distributions, and from the cache's own,
    /// with the cache's F as the light there ([`leave_one_out`]; luminance in every channel).
    fn predict(
        &self,
        cx: &Lit<'_>,
        at: &ShadingPoint,
        own: &ImportanceRecord,
        near: &[Neighbour<'_, ImportanceRecord>],
        samples: u32,
    ) -> Option<LeaveOneOut> {
        if near.is_empty() {
            return None;
        }
        let Some(f) = &own.dists[0] else { return Some(LeaveOneOut::values([0.0; 3], [0.0; 3])) };
        let (n, samples) = (cx.vpls.len(), samples.max(1));
        let others: Vec<_> = self.mixed(near).collect();
        let s = leave_one_out::sampled(f, self.blend(), others.iter().copied(), self.techniques, n);
        let key = hash3(at.p.x.to_bits() as u64, at.p.y.to_bits() as u64, at.p.z.to_bits() as u64);
        let variance = |dists: &[(&[Option<Quantised>; 3], f32)]| {
            let blend = self.blend();
            if self.stratify {
                leave_one_out::pixel_variance(key, f, blend, dists, self.techniques, n, self.mis, samples)
            } else {
                leave_one_out::sampled(f, blend, dists.iter().copied(), self.techniques, n).variance / samples as f32
            }
        };
        Some(LeaveOneOut {
            from_others: [s.expected; 3],
            alone: [s.total; 3],
            variance: variance(&others),
            own_variance: variance(&[(&own.dists, 1.0)]),
            // The records hold F exactly and the reference is the exact VPL sum.
            records_noise: 0.0,
            kept_noise: 0.0,
        })
    }

    fn reference(
        &self,
        cx: &Lit<'_>,
        s: &ShadingPoint,
        rng: &mut Rng,
        stratum: Stratum,
        rays: &mut RayCounters,
    ) -> [f32; 3] {
        self.without_caches(cx, s, self.sampling, self.baseline_draws(), rng, stratum, rays)
    }

    /// Where no cache serves a sample (a point seen in a mirror or through glass, away from every cache):
    /// power sampling with [`ImportanceCache::fallback_draws`] draws, which is unbiased for the same VPL
    /// sum, rather than the reference's exact sum over every VPL.
    fn estimate(
        &self,
        cx: &Lit<'_>,
        s: &ShadingPoint,
        rng: &mut Rng,
        stratum: Stratum,
        rays: &mut RayCounters,
    ) -> [f32; 3] {
        self.without_caches(cx, s, Sampling::Power, self.fallback_draws(), rng, stratum, rays)
    }

    fn record_bytes(&self, record: &ImportanceRecord) -> usize {
        std::mem::size_of::<ImportanceRecord>() + record.dists.iter().flatten().map(Quantised::bytes).sum::<usize>()
    }

    fn record_bytes_bound(&self) -> usize {
        std::mem::size_of::<ImportanceRecord>() + 3 * Quantised::bytes_for(self.vpls)
    }
}

/// A cache's weight in the mixture from its interpolation weight `w`, the largest of its selection's
/// `largest`, and `mixweight` `power`: `w` itself at power 1 (0: the blend is uniform and ignores it), else
/// (w / largest)^power, which is in [0, 1] (0 where it underflows: the mixture leaves such a cache out) and
/// cannot overflow however close a cache is (1/Dist reaches 10⁷/L) or large the power; only the ratios of the
/// weights matter to the mixture.
fn mix_weight(w: f32, largest: f32, power: f32) -> f32 {
    if power == 0.0 || power == 1.0 || largest <= 0.0 { w } else { (w / largest).powf(power) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Importance caching over 8192 VPLs whose techniques draw `techniques` times per sample.
    fn app(techniques: [u32; TECHNIQUES]) -> ImportanceCache {
        ImportanceCache {
            vpls: 8192,
            max_depth: 5,
            vpl_seed: 0,
            clamp: 0.025,
            clamp_distance: 0.25,
            compensate: 4,
            techniques,
            light_samples: 1,
            lobe_cone: 45.0,
            mis: Mis::Balance,
            sampling: Sampling::Cache,
            draws: 0,
            fallback_draws: 0,
            split_cone: 10.0,
            split_near: 1.0,
            vis_angle: 10.0,
            stratify: true,
            learn_shares: 2,
            share_level: ShareLevel::Mean,
            mix_weight: 1.0,
        }
    }

    #[test]
    fn the_record_bound_meets_the_issue_budget() {
        // 25K caches × 8192 VPLs must fit in 1 GB.
        let app = app([1, 1, 1, 1, 0]);
        let total = 25_000 * app.record_bytes_bound();
        assert!(total <= 1_000_000_000, "{total}");
    }

    #[test]
    fn a_vertex_no_cache_serves_draws_four_times_a_baseline_sample_unless_told() {
        let mut eight = app([8, 8, 8, 8, 8]);
        // F, U, B and C draw 32 together (G only at some points): the fallback draws 128.
        assert_eq!((eight.baseline_draws(), eight.fallback_draws()), (32, 128));
        eight.draws = 10;
        assert_eq!(eight.fallback_draws(), 40);
        eight.fallback_draws = 7;
        assert_eq!((eight.baseline_draws(), eight.fallback_draws()), (10, 7));
    }

    #[test]
    fn the_levels_move_the_draws_of_u_and_b_to_f_and_leave_c_and_g_alone() {
        let eight = app([8, 8, 8, 8, 8]);
        assert_eq!(eight.shares(0), [8, 8, 8, 8, 8]);
        assert_eq!(eight.shares(1), [16, 4, 4, 8, 8]);
        assert_eq!(eight.shares(2), [20, 2, 2, 8, 8]);
        assert_eq!(eight.shares(3), [22, 1, 1, 8, 8]);
        // A technique that does not draw stays out; one that draws keeps at least one draw.
        assert_eq!(app([8, 0, 2, 8, 0]).shares(3), [9, 0, 1, 8, 0]);
        // Without F there is no one to give the draws to.
        assert_eq!(app([0, 8, 8, 8, 0]).shares(2), [0, 8, 8, 8, 0]);
    }

    #[test]
    fn the_parameter_table_gives_the_default_light_samples() {
        let row = ImportanceCache::PARAMETERS.iter().find(|p| p.name == "lightsamples").unwrap();
        assert_eq!(row.default.to_string(), DEFAULT_LIGHT_SAMPLES.to_string());
    }

    #[test]
    fn mixture_weights_keep_their_ratios_and_do_not_overflow() {
        assert_eq!(mix_weight(3.5, 7.0, 1.0), 3.5, "power 1 is the interpolation weight itself");
        assert_eq!(mix_weight(7.0, 7.0, 2.0), 1.0);
        assert!((mix_weight(3.5, 7.0, 2.0) - 0.25).abs() < 1e-7);
        // A cache at 1e-7 of the scene's length from the point weighs 1e7 / L; to the eighth power that is
        // far beyond f32, but as a ratio to the largest it stays in [0, 1].
        for w in [1e7f32, 1e3, 1.0, 1e-3] {
            let m = mix_weight(w, 1e7, 8.0);
            assert!(m.is_finite() && (0.0..=1.0).contains(&m), "{w}: {m}");
        }
    }
}
