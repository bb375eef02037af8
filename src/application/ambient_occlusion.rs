//! Cache-based ambient occlusion with visibility caches (Clarberg & Akenine-Möller 2008; ALGORITHMS.md §6.1).
//!
//! A cache gathers visibility along the n×n directions of the equal-area hemisphere grid in its fixed
//! generic-axis frame (§3.2–3.3) and stores a bit per direction plus AO = Σ V_k cos θ_k / Σ cos θ_k — the
//! cosine-weighted unoccluded fraction in [0, 1] (CHOICE A14: normalised, unlike pbrt-v3's π-scaled
//! `ambientocclusion`). Directions below the geometric surface are not traced (V = 0). Rays end at
//! `max_distance` (default 0.1·L, CHOICE A14). Two caches differ by the Hamming distance of their masks.
//! A sample is shaded by the inverse-distance blend of its caches' AO; the reference evaluates the same
//! n² rays at the sample itself.
//!
//! Registered as the integrator `cacheao`; its own parameters are [`CacheAo::PARAMETERS`]. The image holds
//! AO in [0, 1], not pbrt-v3's π-scaled value.
//!
//! Its per-pixel counterpart, pbrt-v3's `ambientocclusion`, is `render::ambient_occlusion` (the same file
//! name one layer down).

use glam::Vec3A;

use crate::error::{Result, Warnings};
use crate::gbuffer::ShadingPoint;
use crate::gbuffer::scale::SceneScale;
use crate::parse::integrator::{IntegratorParams, ParamDef, Parameter, Valid, json_f32};
use crate::sampling::warp::equal_area_hemisphere;
use crate::sampling::{Frame, Rng, Stratum};
use crate::scene::Scene;
use crate::scene::accel::OccluderHint;
use crate::scene::ray::{Ray, RayCounters, offset_ray_origin};

use super::{Application, Baseline, LeaveOneOut, Neighbour, PerSample, Study};

/// A visibility cache: one bit per gathering direction and the AO value.
#[derive(Clone, Debug, PartialEq)]
pub struct VisibilityRecord {
    /// Bit k set when direction k is unoccluded within the maximum distance.
    pub mask: Box<[u64]>,
    /// Σ V_k cos θ_k / Σ cos θ_k.
    pub ao: f32,
}

/// The AO application's settings and its fixed direction set.
#[derive(Clone, Debug)]
pub struct CacheAo {
    dirs: Vec<Vec3A>,
    cos_sum: f32,
    /// Occlusion ray length.
    pub max_distance: f32,
    /// Whether `max_distance` is the default, [`MAX_DISTANCE_OF_L`] · L.
    max_distance_derived: bool,
}

/// `gather`: the side n of the gathering grid.
pub const GATHER: ParamDef<i64> =
    ParamDef::int("gather", 32, "gathering grid side: gather² rays per cache").between(1, 256);
/// The default `maxdistance` as a fraction of the scene's length scale L.
pub const MAX_DISTANCE_OF_L: f32 = 0.1;
/// `maxdistance`: the occlusion ray length (default 0.1 · L, unbounded in a scene of no size).
pub const MAX_DISTANCE: ParamDef<f64> =
    ParamDef::computed("maxdistance", "0.1 · L", "occlusion ray length").valid(Valid::Positive { finite: true });

impl CacheAo {
    /// Gathers along an `n`×`n` grid (n = 32 in the paper: 1024 rays), rays of length `max_distance`.
    pub fn new(n: usize, max_distance: f32) -> Self {
        // Index k = j·n + i is cell (i, j) (ALGORITHMS.md §3.3); rays are traced in serpentine order so
        // consecutive ones are neighbours and often share a blocker (see OccluderHint).
        let dirs: Vec<Vec3A> = (0..n * n)
            .map(|k| equal_area_hemisphere([((k % n) as f32 + 0.5) / n as f32, ((k / n) as f32 + 0.5) / n as f32]))
            .collect();
        let cos_sum = dirs.iter().map(|d| d.z).sum();
        CacheAo { dirs, cos_sum, max_distance, max_distance_derived: false }
    }

    /// pbrt-v3's `ambientocclusion` with the same ray length and cosine sampling, divided by π.
    fn baselines(&self) -> Vec<Baseline> {
        // The per-pixel integrator needs a finite length: 1e30 is "unbounded" for any scene.
        let d = if self.max_distance.is_finite() { self.max_distance.to_string() } else { "1e30".into() };
        vec![Baseline {
            label: "ao",
            integrator: "ambientocclusion",
            set: vec![("maxdistance".into(), d), ("cossample".into(), "true".into())],
            samples: "nsamples",
            scale: std::f32::consts::FRAC_1_PI,
        }]
    }

    /// Number of gathering directions.
    pub fn directions(&self) -> usize {
        self.dirs.len()
    }

    fn gather(&self, scene: &Scene, at: &ShadingPoint, rays: &mut RayCounters) -> VisibilityRecord {
        let frame = Frame::generic(at.n);
        let mut mask = vec![0u64; self.dirs.len().div_ceil(64)].into_boxed_slice();
        let mut unoccluded = 0.0f32;
        let mut hint = OccluderHint::default();
        let n = (self.dirs.len() as f64).sqrt() as usize;
        for step in 0..self.dirs.len() {
            let (i, j) = (step % n, step / n);
            let k = j * n + if j % 2 == 0 { i } else { n - 1 - i };
            let local = &self.dirs[k];
            let w = frame.to_world(*local);
            if w.dot(at.ng) <= 0.0 {
                continue;
            }
            let ray = Ray { o: offset_ray_origin(at.p, at.p_error, at.ng, w), d: w, t_max: self.max_distance };
            rays.shadow += 1;
            let blocked = scene.geometry.occluded_hinted(&ray, at.origin, &mut hint);
            if !blocked {
                mask[k / 64] |= 1 << (k % 64);
                unoccluded += local.z;
            }
        }
        VisibilityRecord { mask, ao: if self.cos_sum > 0.0 { unoccluded / self.cos_sum } else { 0.0 } }
    }
}

impl Application for CacheAo {
    const NAME: &'static str = "cacheao";
    const ABOUT: &'static str = "cache-based ambient occlusion (visibility caches), AO in [0, 1]";
    const PARAMETERS: &'static [Parameter] = &[GATHER.row, MAX_DISTANCE.row];

    /// gather² directions about the shading normal at every sub-pixel sample; pbrt-v3's `ambientocclusion`.
    const STUDY: Study<Self> =
        Study { quick: &[], per_sample: Some(PerSample { count: "gather", set: &[] }), baselines: CacheAo::baselines };

    type Record = VisibilityRecord;
    type Prepared<'s> = &'s Scene;

    fn from_params(p: &IntegratorParams<'_>, scale: &SceneScale) -> Result<Self> {
        let gather = p.get(&GATHER)?;
        let l = scale.length;
        let (max_distance, derived) = match p.get_opt(&MAX_DISTANCE)? {
            Some(v) => (v as f32, false),
            None if l > 0.0 => (MAX_DISTANCE_OF_L * l, true),
            None => (f32::INFINITY, false),
        };
        Ok(CacheAo { max_distance_derived: derived, ..CacheAo::new(gather as usize, max_distance) })
    }

    fn scale_derived(&self) -> Vec<(&'static str, f32)> {
        if self.max_distance_derived { vec![("maxdistance", self.max_distance)] } else { Vec::new() }
    }

    fn prepare<'s>(&self, scene: &'s Scene, _: &mut Warnings) -> Result<&'s Scene> {
        Ok(scene)
    }

    fn settings(&self) -> Vec<(&'static str, serde_json::Value)> {
        let n = (self.dirs.len() as f64).sqrt().round() as u64;
        vec![("gather", n.into()), ("maxdistance", json_f32(self.max_distance))]
    }

    fn compute_record(
        &self,
        scene: &&Scene,
        at: &ShadingPoint,
        _rng: &mut Rng,
        rays: &mut RayCounters,
    ) -> VisibilityRecord {
        self.gather(scene, at, rays)
    }

    fn diff(&self, a: &VisibilityRecord, b: &VisibilityRecord) -> f32 {
        a.mask.iter().zip(b.mask.iter()).map(|(x, y)| (x ^ y).count_ones()).sum::<u32>() as f32
    }

    /// Shading reads only the AO value: the mask goes.
    fn finish_record(&self, _: &&Scene, record: &mut VisibilityRecord, _: f32) {
        record.mask = Box::new([]);
    }

    fn shade(
        &self,
        _: &&Scene,
        _: &ShadingPoint,
        near: &[Neighbour<'_, VisibilityRecord>],
        _: &mut Rng,
        _: Stratum,
        _: &mut RayCounters,
    ) -> [f32; 3] {
        let (mut sum, mut wsum) = (0.0f32, 0.0f32);
        for c in near {
            sum += c.weight * c.record.ao;
            wsum += c.weight;
        }
        [if wsum > 0.0 { sum / wsum } else { 0.0 }; 3]
    }

    /// The blend of the others' AO against the cache's own (shading draws nothing).
    fn predict(
        &self,
        _: &&Scene,
        _: &ShadingPoint,
        own: &VisibilityRecord,
        near: &[Neighbour<'_, VisibilityRecord>],
        _: u32,
    ) -> Option<LeaveOneOut> {
        let wsum: f32 = near.iter().map(|c| c.weight).sum();
        (wsum > 0.0).then(|| {
            LeaveOneOut::values([near.iter().map(|c| c.weight * c.record.ao).sum::<f32>() / wsum; 3], [own.ao; 3])
        })
    }

    fn reference(&self, scene: &&Scene, s: &ShadingPoint, _: &mut Rng, _: Stratum, rays: &mut RayCounters) -> [f32; 3] {
        [self.gather(scene, s, rays).ao; 3]
    }

    fn record_bytes(&self, record: &VisibilityRecord) -> usize {
        std::mem::size_of::<VisibilityRecord>() + std::mem::size_of_val(&*record.mask)
    }

    fn record_bytes_bound(&self) -> usize {
        std::mem::size_of::<VisibilityRecord>() + self.dirs.len().div_ceil(64) * 8
    }
}
