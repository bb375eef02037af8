//! STAGE 6 (render): pbrt-v3's `ambientocclusion` integrator, exactly: a frame around the geometric normal
//! faced toward the viewer, `nsamples` cosine-weighted (or uniform) directions per camera sample, unbounded
//! shadow rays spawned like pbrt-v3's `SpawnRay` (or bounded by pbrt-v4's `maxdistance`), and the estimator
//! Σ cos θ / (pdf · n), which is π where nothing occludes. Surfaces without a material are passed through.
//!
//! This per-pixel integrator is the brute-force reference the cache-based applications are measured against;
//! its cached counterpart is `src/application/ambient_occlusion.rs` (the same file name one layer up).

use glam::Vec3A;

use crate::error::Result;
use crate::sampling::Frame;
use crate::sampling::warp::{
    UNIFORM_HEMISPHERE_PDF, cosine_hemisphere_batch, cosine_hemisphere_pdf, uniform_hemisphere,
};
use crate::scene::Scene;
use crate::scene::accel::{OccluderCache, OccluderHint};
use crate::scene::ray::{Ray, offset_ray_origin};
use crate::scene::sampler::SamplerSpec;

use super::{PixelIntegrator, RayCounters};
use crate::parse::integrator::{IntegratorParams, ParamDef, Parameter, Valid};
use crate::sampling::pixel_samples::PixelSamples;
use crate::shading::lighting::Scratch;

/// Settings of the `ambientocclusion` integrator: the parameters of [`PARAMETERS`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmbientOcclusion {
    /// Occlusion rays per camera sample.
    pub n_samples: u32,
    /// Cosine-weighted sampling.
    pub cos_sample: bool,
    /// Shadow-ray length.
    pub max_distance: f32,
}

/// Largest `nsamples` accepted.
pub const MAX_AO_SAMPLES: i64 = 1 << 20;

/// `nsamples`.
pub const NSAMPLES: ParamDef<i64> =
    ParamDef::int("nsamples", 64, "occlusion rays per camera sample (rounded as the sampler rounds arrays)")
        .between(1, MAX_AO_SAMPLES);
/// `cossample`.
pub const COSSAMPLE: ParamDef<bool> =
    ParamDef::bool("cossample", true, "cosine-weighted directions (else uniform over the hemisphere)");
/// `maxdistance` (unbounded by default).
pub const MAXDISTANCE: ParamDef<f64> =
    ParamDef::float("maxdistance", f64::INFINITY, "shadow-ray length (pbrt-v4's parameter)")
        .valid(Valid::Positive { finite: false });

/// The parameters of `ambientocclusion`.
pub const PARAMETERS: &[Parameter] = &[NSAMPLES.row, COSSAMPLE.row, MAXDISTANCE.row];

/// Most surfaces without a material a camera ray passes through before it gives up.
const MAX_PASS_THROUGH: usize = 1024;

impl AmbientOcclusion {
    /// Reads the integrator's parameters; `quick` sets nsamples to 1 as pbrt-v3's `--quick` does.
    pub fn from_params(p: &IntegratorParams<'_>, sampler: &SamplerSpec, quick: bool) -> Result<Self> {
        let n = p.get(&NSAMPLES)?;
        let max_distance = p.get(&MAXDISTANCE)? as f32;
        let n = if quick { 1 } else { sampler.round_count(n as u32) };
        Ok(AmbientOcclusion { n_samples: n, cos_sample: p.get(&COSSAMPLE)?, max_distance })
    }

    /// AO at a surface point seen along `wo_dir` (the incoming ray direction), with `u` one 2-D sample per
    /// direction. Returns Σ cos θ / (pdf · n).
    ///
    /// Directions are made a batch of `BATCH` at a time in straight-line code the compiler vectorises, and
    /// the two possible spawn origins (pbrt-v3's `OffsetRayOrigin` depends on the direction only through the
    /// side of the surface it leaves from) are computed once per point instead of once per ray.
    pub fn occlusion(
        &self,
        scene: &Scene,
        si: &crate::scene::geometry::SurfaceInteraction,
        ray_dir: Vec3A,
        u: &[[f32; 2]],
        counters: &mut RayCounters,
    ) -> f32 {
        OCCLUDERS.with_borrow_mut(|cache| self.occlusion_cached(scene, si, ray_dir, u, cache, counters))
    }

    /// [`AmbientOcclusion::occlusion`] with the caller's cache of blockers remembered by direction (see
    /// [`OccluderCache`]; the result never depends on what it holds).
    pub fn occlusion_cached(
        &self,
        scene: &Scene,
        si: &crate::scene::geometry::SurfaceInteraction,
        ray_dir: Vec3A,
        u: &[[f32; 2]],
        cache: &mut OccluderCache,
        counters: &mut RayCounters,
    ) -> f32 {
        let n = if si.ng.dot(-ray_dir) < 0.0 { -si.ng } else { si.ng };
        let frame = Frame::from_normal(n);
        let origins =
            [offset_ray_origin(si.p, si.p_error, si.ng, si.ng), offset_ray_origin(si.p, si.p_error, si.ng, -si.ng)];
        let inv_n = 1.0 / u.len() as f32;
        let mut l = 0.0;
        let mut hint = OccluderHint::default();
        let mut local = [[0.0f32; 3]; BATCH];
        for chunk in u.chunks(BATCH) {
            if self.cos_sample {
                cosine_hemisphere_batch(chunk, &mut local);
            } else {
                for (w, &ui) in local.iter_mut().zip(chunk) {
                    *w = uniform_hemisphere(ui).to_array();
                }
            }
            for w in &local[..chunk.len()] {
                let wl = Vec3A::from(*w);
                let pdf = if self.cos_sample { cosine_hemisphere_pdf(wl.z) } else { UNIFORM_HEMISPHERE_PDF };
                if pdf <= 0.0 {
                    continue;
                }
                let d = frame.to_world(wl);
                let o = origins[usize::from(d.dot(si.ng) < 0.0)];
                let r = Ray { o, d, t_max: self.max_distance };
                counters.shadow += 1;
                if !scene.geometry.occluded_cached(&r, Some(si.origin), &mut hint, cache) {
                    l += wl.z / pdf * inv_n;
                }
            }
        }
        l
    }
}

thread_local! {
    /// Each worker thread's blockers remembered by direction, kept from point to point and pixel to pixel
    /// (consecutive camera samples of a thread are neighbours). They only order the work: no answer depends
    /// on them, so images are the same for any thread count.
    static OCCLUDERS: std::cell::RefCell<OccluderCache> = const { std::cell::RefCell::new(OccluderCache::new()) };
}

/// Directions made per batch by [`AmbientOcclusion::occlusion`].
const BATCH: usize = 8;

impl PixelIntegrator for AmbientOcclusion {
    fn li(
        &self,
        scene: &Scene,
        mut ray: Ray,
        s: &mut PixelSamples,
        scratch: &mut Scratch,
        c: &mut RayCounters,
    ) -> [f32; 3] {
        for _ in 0..MAX_PASS_THROUGH {
            c.camera += 1;
            let Some(si) = scene.geometry.intersect(&ray) else { return [0.0; 3] };
            if scene.is_null_material(si.material) {
                ray = si.spawn_ray(ray.d);
                continue;
            }
            let points = &mut scratch.points;
            points.resize(self.n_samples as usize, [0.0; 2]);
            s.array2d(points);
            s.coherent(points);
            let l = self.occlusion(scene, &si, ray.d, points, c);
            return [l; 3];
        }
        [0.0; 3]
    }
}
