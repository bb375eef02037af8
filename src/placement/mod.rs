//! STAGE 4: where caches go. First-stage strategies see only the G-buffer (geometry); second-stage
//! strategies also see the first-stage caches through a [`CacheOracle`] — positions, the difference of
//! two caches' gathering samples and (for refine's error estimate) what a cache's neighbours predict at its
//! site — never the record type, so every strategy works with every application
//! (ambient occlusion, irradiance, importance caching).
//!
//! Strategy names (what users type and reports print) are resolved by [`registry::strategy`].
//! Depends on `gbuffer`, `cache` (the §5 neighbour selection) and `sampling`; never on `render` or `scene`.
//!
//! | file | what |
//! |---|---|
//! | [`image_uniform`] | IM, jittered-stratified image-space sampling (ALGORITHMS.md §4.1) |
//! | [`spatial_directional`] | SD, LightSlice's 6-D BVH with a threshold search (§4.2) |
//! | [`view_guided`] | VGC, the paper's first stage, Eq. 1–2 with a σ_s search (§4.4) |
//! | [`adaptive`] | AS, neighbour-error insertion after SD or VGC (§4.3, a reconstruction) |
//! | [`discontinuity`] | DGS, the paper's second stage, Eq. 3–4 (§4.5) |
//! | [`estimate`] | refine's reference-free estimate of the image's relative RMSE (leave-one-out) |
//! | [`refine`] | refine's rounds of map-guided insertion after IM (beyond the paper; experiments/notes/refine.md) |
//! | [`registry`] | the strategy names |
//! | [`synthetic`] | analytic G-buffers and a mock oracle, for tests and `cachert bench micro` |
//! | `points`, `split`, `hierarchy`, `search`, `cluster`, `budget`, `discrete2d` | shared machinery: usable points and Eq. 1 scaling, node splits, the build-once hierarchy and its cut, the log-scale budget search, representatives and exact budgets, common budget cases, the 2-D sampler |
//!
//! Every random decision uses `Rng::keyed(seed, stage tag, index)` with the index of a cell, cluster, cache
//! or draw — never a thread — and every parallel step combines its results in index order, so the same seed
//! gives the same caches for any thread count.

pub mod adaptive;
pub mod discontinuity;
pub mod estimate;
pub mod image_uniform;
pub mod refine;
pub mod registry;
pub mod spatial_directional;
pub mod synthetic;
pub mod view_guided;

mod budget;
mod cluster;
mod discrete2d;
mod hierarchy;
mod points;
mod search;
mod split;
mod stratified;
#[cfg(test)]
mod test_scenes;

pub use adaptive::AdaptiveSampling;
pub use discontinuity::Discontinuity;
pub use image_uniform::ImageUniform;
pub use refine::Refine;
pub use spatial_directional::SpatialDirectional;
pub use view_guided::ViewGuided;

use std::fmt::Debug;
use std::ops::Range;

use crate::cache::LookupParams;
use crate::error::Result;
use crate::gbuffer::{GBuffer, PixelId};

/// Index of an evaluated cache (0.. in evaluation order: stage-1 caches first).
pub type CacheId = u32;

/// How a cluster of shading points is split in two (needed by adaptive sampling, which splits the leaf of
/// a cache once more).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SplitRule {
    /// SD: longest axis of the 6-D (position, s·normal) box, at its centre; `normal_scale` is s.
    SpatialDirectional {
        /// The normal scale s of the 6-D coordinates.
        normal_scale: f32,
    },
    /// VGC: longest world-space axis at its midpoint (median fallback).
    ViewGuided,
}

/// The clusters a first-stage strategy formed, one per site (IM has none).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Clusters {
    /// Members of all clusters, concatenated.
    pub members: Vec<PixelId>,
    /// For each site (same order as [`Stage1::sites`]), its range in `members`.
    pub ranges: Vec<Range<u32>>,
    /// How to split a cluster once more.
    pub rule: Option<SplitRule>,
}

/// What a first-stage strategy found besides its sites (for `--stats` and reports).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlacementInfo {
    /// VGC: the spatial threshold σ_s the binary search settled on (scene units).
    pub sigma_s: Option<f32>,
    /// VGC: the angular threshold σ_a used (degrees).
    pub sigma_a_deg: Option<f32>,
    /// SD: the split threshold T the binary search settled on.
    pub sd_threshold: Option<f32>,
    /// Iterations of the binary search (VGC or SD).
    pub search_iterations: u32,
    /// Cluster count the search reached before sites were adjusted to the budget.
    pub clusters_found: usize,
    /// Non-fatal remarks (budget above the valid pixel count, saturation, …).
    pub notes: Vec<String>,
}

/// The result of a first stage: distinct valid pixels that become caches.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stage1 {
    /// Cache sites, distinct valid pixels.
    pub sites: Vec<PixelId>,
    /// The clusters behind the sites, when the strategy forms clusters.
    pub clusters: Option<Clusters>,
    /// Search results and remarks.
    pub info: PlacementInfo,
}

/// A first-stage strategy: geometry only.
pub trait InitialPlacement: Debug + Sync {
    /// Chooses exactly `min(budget, valid pixels)` distinct valid pixels (or explains why it cannot).
    fn place(&self, g: &GBuffer, budget: usize, params: &PlacementParams, seed: u64) -> Result<Stage1>;
}

/// The driver's view of evaluated caches, for second-stage strategies. Implemented by the render driver
/// for any application; placement never sees the record type.
pub trait CacheOracle {
    /// Number of caches evaluated so far (ids `0..len()`).
    fn len(&self) -> usize;
    /// Whether no cache is evaluated yet.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The pixel a cache sits on.
    fn site(&self, c: CacheId) -> PixelId;
    /// Σ_k |g_a\[k\] − g_b\[k\]| over corresponding gathering samples (AO: Hamming distance of masks).
    fn diff(&self, a: CacheId, b: CacheId) -> f32;
    /// Many differences at once (implementations may run them in parallel); same order as `pairs`.
    fn diff_many(&self, pairs: &[(CacheId, CacheId)]) -> Vec<f32> {
        pairs.iter().map(|&(a, b)| self.diff(a, b)).collect()
    }
    /// Evaluates caches at `sites` (distinct valid pixels without a cache) and appends them.
    fn evaluate(&mut self, sites: &[PixelId]);
    /// For each `(c, others)`: what the application's shading at cache `c`'s own site makes of the caches
    /// `others` (ids with normalised weights, `c` not among them) against what it makes of `c` alone — the
    /// leave-one-out question behind refine's error estimate. `None` where the application cannot answer
    /// it (the default: no application can).
    fn predict_many(&mut self, asks: &[(CacheId, Vec<(CacheId, f32)>)]) -> Vec<Option<Prediction>> {
        vec![None; asks.len()]
    }
    /// Shading (and [`CacheOracle::predict_many`]'s answers) from now on with about `keep` (0 < `keep` ≤ 1)
    /// of the application's draws per sample, 1 restoring them: what a target error the caches already
    /// beat is met with, where the application's error is its shading's noise. Returns whether shading
    /// changed (the default: no application can).
    fn thin(&mut self, keep: f32) -> bool {
        let _ = keep;
        false
    }
}

/// What a cache's neighbours predict at its site ([`CacheOracle::predict_many`]), in the image's units (the
/// colour channels' mean): the squared error of a pixel there that more caches can remove, what remains of
/// it with the cache itself, and the cache's own value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prediction {
    /// (Value from the others − value from the cache alone)², plus, where shading draws, what the pixel's
    /// variance from the others exceeds its variance from the cache alone by.
    pub sq_err: f32,
    /// The part of `sq_err` the records' own noise makes (their gathering; 0 where records are exact): the
    /// estimate takes it out of the miss, refine's map does not (estimate.rs says why).
    pub noise: f32,
    /// The pixel's variance from the cache alone (0 where shading draws nothing) and the noise it keeps
    /// beyond shading's (its blend's records' and the per-sample reference's; 0 where they are exact): the
    /// error's floor.
    pub floor: f32,
    /// Mean over the colour channels of the value from the cache alone.
    pub value: f32,
}

/// A target error for refine ([`PlacementParams::target`]): rounds stop when the estimate meets it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TargetError {
    /// The relative RMSE asked for: RMSE against the per-sample reference over its mean, all channels.
    pub relative: f32,
    /// The mean of what the image adds to the cached values outside the caches (a per-pixel term, over
    /// all pixels and channels), which the relative error's denominator includes (0 when nothing is added).
    pub added_mean: f32,
}

/// One of refine's error estimates (`--stats`): the caches placed when it was made and what it said.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoundEstimate {
    /// Caches placed so far.
    pub caches: usize,
    /// Estimated relative RMSE of the image these caches would give.
    pub relative_rmse: f32,
}

/// What a second stage did (for `--stats`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AdaptiveInfo {
    /// Caches added.
    pub added: usize,
    /// Rounds of insertion (AS may need several).
    pub rounds: u32,
    /// DGS: the per-pixel discontinuity map D (row-major, 0 for invalid pixels and stage-1 caches).
    pub discontinuity: Option<Vec<f32>>,
    /// Non-fatal remarks.
    pub notes: Vec<String>,
    /// refine with a target error: its estimate after the first stage and after each round.
    pub estimates: Vec<RoundEstimate>,
}

/// A second-stage strategy: adds `budget` caches where the first-stage caches disagree. Every cache it
/// adds is evaluated through `oracle.evaluate` before it returns.
pub trait AdaptivePlacement: Debug + Sync {
    /// Adds up to `budget` caches (exactly `budget` when enough free valid pixels exist).
    fn place(
        &self,
        g: &GBuffer,
        stage1: &Stage1,
        oracle: &mut dyn CacheOracle,
        budget: usize,
        params: &PlacementParams,
        seed: u64,
    ) -> Result<AdaptiveInfo>;
}

/// How the VGC angular split measures and splits normals (ALGORITHMS.md §4.4, ambiguity A4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AngularMode {
    /// Spread = 2 × max angle to the mean normal; split the largest normal-component extent (default).
    Cone,
    /// The paper's literal (φ, θ) box in degrees.
    SphericalAngles,
}

/// Which terms make up the DGS discontinuity map (Eq. 4 and the Table 2 ablations).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DgsTerms {
    /// Diff_avg′ + Diff_max′.
    pub diff: bool,
    /// G′ (Eq. 3).
    pub geometry: bool,
}

/// Every placement parameter of ALGORITHMS.md §7, with the paper's defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct PlacementParams {
    /// Stage-2 share R of the budget (two-stage strategies).
    pub ratio: f32,
    /// VGC angular threshold σ_a in degrees; `None`: from the budget (15° at 120K … 25° at 25K, log-interpolated).
    pub sigma_a_deg: Option<f32>,
    /// Γ: growth of the thresholds with depth, per metre.
    pub gamma: f32,
    /// Scene units per metre conversion: metres = units × meters_per_unit.
    pub meters_per_unit: f32,
    /// λ of Eq. 2 and Eq. 5; `None`: 0.5 / L.
    pub lambda: Option<f32>,
    /// Representative jitter as a fraction of the cluster extent (total width).
    pub jitter: f32,
    /// VGC angular mode.
    pub angular: AngularMode,
    /// SD minimum cluster size S_min.
    pub sd_min_size: usize,
    /// The §5 selection used by DGS, AS and the final lookup.
    pub lookup: LookupParams,
    /// DGS map terms.
    pub dgs: DgsTerms,
    /// DGS geometry window (odd side length; 5 in the paper).
    pub dgs_window: usize,
    /// refine: the share of the budget its rounds add after the uniform first stage.
    pub refine_share: f32,
    /// refine: rounds of insertion.
    pub refine_rounds: u32,
    /// refine: the uniform floor added to each round's map, as a fraction of the map's mean.
    pub refine_floor: f32,
    /// refine: whether each round's map has the leave-one-out term (the application's plan says; its error
    /// estimate asks the same question whatever this says).
    pub refine_misses: bool,
    /// refine: place caches until this error is estimated met (the budget is then a ceiling); `None`:
    /// place the whole budget.
    pub target: Option<TargetError>,
}

impl Default for PlacementParams {
    fn default() -> Self {
        PlacementParams {
            ratio: 0.15,
            sigma_a_deg: None,
            gamma: 0.2,
            meters_per_unit: 1.0,
            lambda: None,
            jitter: 0.2,
            angular: AngularMode::Cone,
            sd_min_size: 10,
            lookup: LookupParams::default(),
            dgs: DgsTerms { diff: true, geometry: true },
            dgs_window: 5,
            refine_share: 0.8,
            refine_rounds: 3,
            refine_floor: 0.1,
            refine_misses: true,
            target: None,
        }
    }
}

/// Pixels of the paper's images (1920×1080), to which its cache budgets refer.
pub const PAPER_PIXELS: f64 = 1920.0 * 1080.0;

impl PlacementParams {
    /// λ for a scene of diagonal `l`.
    pub fn lambda_for(&self, l: f32) -> f32 {
        self.lambda.unwrap_or(if l > 0.0 { 0.5 / l } else { 0.0 })
    }

    /// σ_a in degrees for a total budget of `caches` over an image of `pixels` pixels: the given value, or the
    /// paper's 15° at 120K and 25° at 25K/40K caches per 1920×1080 pixels, interpolated linearly in the log of
    /// the 1080p-equivalent budget `caches × 1920·1080 / pixels` and clamped to [15°, 25°] (ALGORITHMS.md
    /// A22): a 640×360 image at the paper's density gets the paper's σ_a.
    pub fn sigma_a_for(&self, caches: usize, pixels: usize) -> f32 {
        if let Some(s) = self.sigma_a_deg {
            return s;
        }
        let equivalent = caches.max(1) as f64 * PAPER_PIXELS / pixels.max(1) as f64;
        let (n0, n1) = (40_000f64.ln(), 120_000f64.ln());
        let t = ((equivalent.ln() - n0) / (n1 - n0)) as f32;
        (25.0 + t * (15.0 - 25.0)).clamp(15.0, 25.0)
    }
}
