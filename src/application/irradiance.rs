//! Irradiance caching (Ward 1988; the paper's §4.1; ALGORITHMS.md §6.2), registered as `irradiancecache`.
//!
//! A cache gathers along the n×n directions of the equal-area hemisphere grid in its generic-axis frame
//! (§3.2–3.3; n = 64: 4096 directions). Each direction is one path: the first hit's emission is left out
//! (it is direct light at the cache), every later vertex adds next-event estimation from one light chosen
//! by power (pbrt-v3's `EstimateDirect`, MIS between light and BSDF sampling), the path continues by BSDF
//! sampling (also past the last light-sampling vertex when the bounce is specular, for the emission it
//! finds, as pbrt-v3 `path` does), emitted radiance found after a specular bounce is added, and Russian
//! roulette starts after the third bounce (pbrt-v3 `path`'s rule). `maxdepth` counts the vertices that
//! sample a light, as pbrt-v2's `maxindirectdepth` does: with the per-pixel direct term of `output full`
//! the light paths are those of pbrt-v3 `path` with `maxdepth + 1`. A ray that leaves the scene at the first
//! hit brings no light (an infinite light's radiance at the cache is direct light, as in pbrt-v2's
//! irradiance cache).
//!
//! E = π · Σ_k L_k cos θ_k / Σ_k cos θ_k (RGB): ALGORITHMS.md's (2π/n²) Σ_k L_k cos θ_k with the grid's own
//! Σ cos θ_k in place of its limit n²/2, so that uniform radiance L gives exactly πL at any grid size (the
//! cell-centre rule overestimates Σ cos θ_k by 3 % at n = 8, 0.05 % at n = 64), as cache AO normalises by
//! its Σ cos θ_k. The record keeps E and, until placement is over, the luminance of
//! every L_k, which is what two caches are compared by (Σ_k |ΔY|, §4.5.2). A sample is shaded as
//! ρ_hd(ω_o)·E/π with E blended from its caches (ALGORITHMS.md §5, less the caches lying in front of the
//! sample: Ward's test, see `in_front`; a choice of ours, `rejectinfront false` leaves it out), ρ_hd over
//! the BSDF's non-specular reflection lobes (exact for Lambertian lobes, 64 fixed stratified samples
//! otherwise); purely specular and transmitting lobes
//! get nothing from the caches. `output full` adds pbrt-v3's `directlighting` image (emission and direct
//! light, with the scene's Sampler and PixelFilter) so the image compares with a path-traced one.
//!
//! The reference gathers the same n² paths at every sub-pixel sample.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::Vec3A;

use crate::error::{Error, Result, Warnings};
use crate::gbuffer::ShadingPoint;
use crate::gbuffer::scale::SceneScale;
use crate::parse::integrator::{Choice, IntegratorParams, MAX_DEPTH, ParamDef, Parameter};
use crate::sampling::warp::equal_area_hemisphere;
use crate::sampling::{Frame, Rng, Stratum};
use crate::scene::Scene;
use crate::scene::accel::PrimOrigin;
use crate::scene::ray::{Ray, RayCounters, offset_ray_origin};
use crate::shading::bsdf::Bsdf;
use crate::shading::bxdf::BxdfFlags;
use crate::shading::light::LightSelect;
use crate::shading::lighting::{PassThrough, ShadePoint, Shading, estimate_direct};
use crate::shading::{Spectrum, luminance};

use super::{Application, CachePlan, LeaveOneOut, Neighbour, PerPixelTerm, PerSample, Study};

/// Samples of the fixed set that estimates ρ_hd of non-Lambertian lobes (an 8×8 stratified grid).
const RHO_SIDE: usize = 8;

/// What the image holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Output {
    /// Indirect light only (the paper's figures).
    Indirect,
    /// Emitted and direct light (pbrt-v3 `directlighting`, per pixel) plus the cached indirect light.
    Full,
}

impl Output {
    fn name(self) -> &'static str {
        match self {
            Output::Indirect => "indirect",
            Output::Full => "full",
        }
    }
}

/// `gather`: the side n of the gathering grid. The default is 32 (1024 paths per cache), not the paper's 64
/// (4096, ALGORITHMS.md §6.2), and it goes with three times the paper's budget ([`IrradianceCache`]'s
/// `DEFAULT_CACHES`): measured on the Cornell box at 256×256 against pbrt-v3's path image
/// (`experiments/results/irc-peer/peer-2026-11-27.md`, 5 seeds), the paper's setting gave 0.00252 off-light RMSE in
/// 10.3 CPU s and 32² paths × 4000 caches 0.00190 in 10.9 s; on sibenik at 240×135 (3 seeds, against
/// cachert's `path` at 512 samples; `experiments/results/irc-default/table.md`) the paper's setting gave RMSE
/// 0.01685 and HDR-FLIP 0.0777 in 18.2 CPU s, this default 0.01647 and 0.0659 in 14.1 s. Fewer paths per
/// cache and more caches: interpolation error falls faster with density than the records' noise rises, and
/// the records' noise is blended over several caches at every sample.
/// Experiments that reproduce the paper write `gather = 64` (their specs do).
pub const GATHER: ParamDef<i64> =
    ParamDef::int("gather", 32, "gathering grid side: gather² paths per cache").between(1, 256);
/// `maxdepth`: the vertices of a gathering path that sample a light.
pub const MAXDEPTH: ParamDef<i64> = ParamDef::int(
    "maxdepth",
    3,
    "path vertices that sample a light (pbrt-v2's maxindirectdepth; = pbrt-v3 path maxdepth − 1)",
)
.between(0, MAX_DEPTH);
/// `output`: what the image holds.
pub const OUTPUT: Choice<Output> = Choice::new(
    "output",
    "full",
    &[("indirect", Output::Indirect), ("full", Output::Full)],
    "indirect: cached indirect light only; full: plus emission and directlighting per pixel",
);
/// `rejectinfront`: Ward's test.
pub const REJECT_IN_FRONT: ParamDef<bool> = ParamDef::bool(
    "rejectinfront",
    true,
    "leave out caches in front of the sample's tangent plane (Ward's test); false: Eq. 5 alone",
);

/// An irradiance cache: E and, while placement needs it, the luminance of each gathering direction.
#[derive(Clone, Debug, PartialEq)]
pub struct IrradianceRecord {
    /// Indirect irradiance (RGB).
    pub e: [f32; 3],
    /// The variance of E's luminance over the gathering (the noise of its n² single paths;
    /// [`IrradianceCache::gather_noise`]), for refine's error estimate.
    pub noise: f32,
    /// Luminance of the radiance arriving along each gathering direction (index k of §3.3); empty once
    /// placement is over.
    pub radiance: Box<[f32]>,
}

/// The irradiance-caching application: settings and the fixed direction set.
#[derive(Clone, Debug)]
pub struct IrradianceCache {
    dirs: Vec<Vec3A>,
    /// The grid's side n (`dirs` holds n² directions, row by row).
    side: usize,
    /// π / Σ_k cos θ_k: turns Σ_k L_k cos θ_k into E.
    norm: f32,
    /// Σ_k cos² θ_k, for the variance of E from the variance of each L_k.
    cos2_sum: f32,
    /// Vertices of a gathering path that sample a light.
    pub max_depth: u32,
    /// What the image holds.
    pub output: Output,
    /// Whether a sample leaves out the caches that lie in front of it (see `in_front`).
    pub reject_in_front: bool,
    rho_u: Vec<[f32; 2]>,
}

/// The scene with its lights, materials and textures, as irradiance caching reads it.
pub struct Lit<'s> {
    scene: &'s Scene,
    shading: Shading<'s>,
    select: LightSelect,
    /// Samples that reflected cached (or gathered) irradiance, and those of them whose BSDF has a glossy
    /// reflection lobe (reflecting it as if diffuse), for `--stats`.
    shaded: [AtomicU64; 2],
}

impl IrradianceCache {
    /// Gathers along an `n`×`n` grid with paths sampling a light at `max_depth` vertices.
    pub fn new(n: usize, max_depth: u32, output: Output) -> Self {
        let dirs = (0..n * n)
            .map(|k| equal_area_hemisphere([((k % n) as f32 + 0.5) / n as f32, ((k / n) as f32 + 0.5) / n as f32]))
            .collect::<Vec<Vec3A>>();
        let cos_sum: f32 = dirs.iter().map(|d| d.z).sum();
        let cos2_sum: f32 = dirs.iter().map(|d| d.z * d.z).sum();
        let norm = if cos_sum > 0.0 { std::f32::consts::PI / cos_sum } else { 0.0 };
        let mut rng = Rng::new(0x7268_6f5f_6864);
        let rho_u = (0..RHO_SIDE * RHO_SIDE)
            .map(|i| {
                let [a, b] = rng.uniform2();
                [((i % RHO_SIDE) as f32 + a) / RHO_SIDE as f32, ((i / RHO_SIDE) as f32 + b) / RHO_SIDE as f32]
            })
            .map(|u| u.map(|v| v.min(1.0 - f32::EPSILON / 2.0)))
            .collect();
        IrradianceCache {
            dirs,
            side: n,
            norm,
            cos2_sum,
            max_depth,
            output,
            reject_in_front: REJECT_IN_FRONT.default(),
            rho_u,
        }
    }

    /// E at `at` by the n² gathering paths; the luminance of each direction's radiance goes to
    /// `radiance[k]` when given (directions below the surface get 0).
    fn gather(
        &self,
        cx: &Lit<'_>,
        at: &ShadingPoint,
        rng: &mut Rng,
        rays: &mut RayCounters,
        mut radiance: Option<&mut [f32]>,
    ) -> Spectrum {
        if self.max_depth == 0 || cx.shading.lights.is_empty() {
            return Spectrum::ZERO;
        }
        let frame = Frame::generic(at.n);
        let mut sum = Spectrum::ZERO;
        let mut bsdf = Bsdf::new(at.ng, at.n, Vec3A::X, 1.0);
        for (k, local) in self.dirs.iter().enumerate() {
            let w = frame.to_world(*local);
            if w.dot(at.ng) <= 0.0 {
                continue;
            }
            let ray = Ray::new(offset_ray_origin(at.p, at.p_error, at.ng, w), w);
            let l = self.incident(cx, ray, at.origin, &mut bsdf, rng, rays);
            if let Some(r) = radiance.as_deref_mut() {
                r[k] = luminance(l);
            }
            sum += l * local.z;
        }
        sum * self.norm
    }

    /// Indirect radiance arriving along `ray`, which leaves the surface `from` (see the module documentation
    /// for what counts). `bsdf` is scratch storage the path refills at each vertex.
    fn incident(
        &self,
        cx: &Lit<'_>,
        mut ray: Ray,
        mut from: Option<PrimOrigin>,
        bsdf: &mut Bsdf,
        rng: &mut Rng,
        rays: &mut RayCounters,
    ) -> Spectrum {
        let (scene, sh) = (cx.scene, &cx.shading);
        let mut l = Spectrum::ZERO;
        let mut beta = Spectrum::ONE;
        let mut specular = false;
        let mut vertices = 0u32;
        let mut pass = PassThrough::default();
        loop {
            rays.camera += 1;
            let Some(si) = scene.geometry.intersect_from(&ray, from) else {
                if specular {
                    l += beta * sh.lights.le_escaped(&ray);
                }
                break;
            };
            if specular {
                l += beta * sh.lights.emitted(&si, -ray.d);
            }
            // Past the last light-sampling vertex a path goes on only after a specular bounce, for the
            // emission it finds (as pbrt-v3 path does after its last vertex).
            if vertices >= self.max_depth {
                break;
            }
            if !sh.bsdf_into(&si, bsdf) {
                let Some(next) = pass.past(&si, &ray) else { break };
                ray = next;
                from = Some(si.origin);
                continue;
            }
            let wo = -ray.d;
            let x = ShadePoint { si: &si, bsdf, wo };
            if bsdf.num_components(BxdfFlags::NON_SPECULAR) > 0
                && let Some((light, pmf)) = cx.select.sample(rng.uniform())
            {
                let (u_light, u_scatter) = (rng.uniform2(), rng.uniform2());
                l += beta * estimate_direct(scene, sh, &x, light, u_light, u_scatter, rays) / pmf;
            }
            vertices += 1;
            let Some(bs) = bsdf.sample_f(wo, rng.uniform2(), BxdfFlags::ALL) else { break };
            if bs.f == Spectrum::ZERO || bs.pdf <= 0.0 {
                break;
            }
            specular = bs.sampled.contains(BxdfFlags::SPECULAR);
            if vertices >= self.max_depth && !specular {
                break;
            }
            beta *= bs.f * bs.wi.dot(bsdf.shading_normal()).abs() / bs.pdf;
            ray = si.spawn_ray(bs.wi);
            from = Some(si.origin);
            // pbrt-v3 path's Russian roulette (after the third bounce, throughput below 1).
            let rr = beta.max_element();
            if rr < 1.0 && vertices > 3 {
                let q = (1.0 - rr).max(0.05);
                if rng.uniform() < q {
                    break;
                }
                beta /= 1.0 - q;
            }
        }
        l
    }

    /// The variance of the luminance of E over its gathering (the noise of its n² single paths), read from
    /// the luminance `r` of each direction's radiance: half the mean squared difference along grid neighbours
    /// (adjacent cells of the equal-area square, adjacent directions) is each direction's variance, on the
    /// assumption that the incident radiance itself changes little from one cell to the next (where it does,
    /// the variance reads high). 0 for a grid of one direction, which has no neighbours.
    fn gather_noise(&self, r: &[f32]) -> f32 {
        let n = self.side;
        if n < 2 || r.len() != n * n {
            return 0.0;
        }
        let (mut d2, mut pairs) = (0f64, 0usize);
        for y in 0..n {
            for x in 0..n {
                let k = y * n + x;
                if x + 1 < n {
                    d2 += ((r[k] - r[k + 1]) as f64).powi(2);
                    pairs += 1;
                }
                if y + 1 < n {
                    d2 += ((r[k] - r[k + n]) as f64).powi(2);
                    pairs += 1;
                }
            }
        }
        let per_direction = d2 / (2 * pairs) as f64;
        ((self.norm as f64).powi(2) * per_direction * self.cos2_sum as f64) as f32
    }

    /// Whether shading at `s` blends cache `c` when not every cache is in front of it (see `in_front`).
    fn blends(&self, s: &ShadingPoint, c: &Neighbour<'_, IrradianceRecord>) -> bool {
        !self.reject_in_front || !in_front(s, c.p, c.n)
    }

    /// ρ_hd(ω_o)/π at a sample: the factor that turns irradiance into reflected radiance.
    fn reflectance(&self, cx: &Lit<'_>, s: &ShadingPoint) -> Spectrum {
        let Some(bsdf) = s.interaction().and_then(|si| cx.shading.bsdf(&si)) else { return Spectrum::ZERO };
        let glossy = bsdf
            .lobes()
            .any(|(b, scale)| b.flags().contains(BxdfFlags::GLOSSY_REFLECTION) && scale.max_element() > 0.0);
        cx.shaded[0].fetch_add(1, Ordering::Relaxed);
        cx.shaded[1].fetch_add(u64::from(glossy), Ordering::Relaxed);
        diffuse_reflectance(&bsdf, s.wo, &self.rho_u) * std::f32::consts::FRAC_1_PI
    }
}

/// How far above a sample's tangent plane a cache may lie, as a fraction of its distance (tan ≈ 2.9°).
const IN_FRONT_SLOPE: f32 = 0.05;

/// Ward's "in front" test (Ward, Rubinstein & Clear 1988): whether the cache at `p` (normal `n`) lies in
/// front of the sample `s`, above the plane through `s` with the mean of the two normals by more than
/// [`IN_FRONT_SLOPE`] of their distance. Such a cache sits between the sample and the surfaces the sample
/// sees, so its irradiance is not the sample's: the light fixture hung 0.02 below the Cornell box's
/// ceiling carries caches that ALGORITHMS.md §5's Dist cannot tell from the ceiling's in the gap above it
/// (same normal, 0.02 away), and they lit that unlit gap. Caches on the sample's plane, or on a sphere
/// through it (seen from outside or inside: the mean normal makes the offset vanish), are never in front.
fn in_front(s: &ShadingPoint, p: Vec3A, n: Vec3A) -> bool {
    let to = p - s.p;
    to.dot((s.n + n) * 0.5) > IN_FRONT_SLOPE * to.length()
}

/// Most materials [`glossy_warning`] names before it counts the rest.
const GLOSSY_NAMED: usize = 6;

/// The one warning that the cached light leaves glossy lobes as pbrt-v2's irradiance cache does, naming the
/// materials that can have one (none: no warning).
fn glossy_warning(scene: &Scene, shading: &Shading<'_>, warnings: &mut Warnings) {
    let glossy: Vec<String> = (0..scene.materials.len())
        .filter(|&i| shading.materials.may_be_glossy(i as u32))
        .map(|i| {
            let m = &scene.materials[i];
            m.loc.as_ref().map_or_else(|| m.type_name.clone(), |loc| format!("{} ({loc})", m.type_name))
        })
        .collect();
    if glossy.is_empty() {
        return;
    }
    let more = glossy.len().saturating_sub(GLOSSY_NAMED);
    let mut named = glossy[..glossy.len().min(GLOSSY_NAMED)].join(", ");
    if more > 0 {
        named += &format!(" and {more} more");
    }
    warnings.general(format!(
        "{}: glossy lobes reflect the cached indirect light as if diffuse (ρ_hd·E/π, as pbrt-v2's irradiancecache does), not as their lobe would: {named}; --stats gives the share of samples this touched",
        IrradianceCache::NAME
    ));
}

/// ρ_hd(ω_o) over the non-specular reflection lobes of `bsdf`: the lobes that reflect cached irradiance.
fn diffuse_reflectance(bsdf: &Bsdf, wo: Vec3A, u: &[[f32; 2]]) -> Spectrum {
    let wo_l = bsdf.to_local(wo);
    bsdf.lobes()
        .filter(|(b, _)| {
            let f = b.flags();
            f.contains(BxdfFlags::REFLECTION) && !f.intersects(BxdfFlags::SPECULAR | BxdfFlags::TRANSMISSION)
        })
        .map(|(b, scale)| scale * b.rho_hd(wo_l, u))
        .sum()
}

impl Application for IrradianceCache {
    const NAME: &'static str = "irradiancecache";
    const ABOUT: &'static str = "irradiance caching: indirect diffuse light ρ_hd·E/π from gathered irradiance";
    const PARAMETERS: &'static [Parameter] = &[GATHER.row, MAXDEPTH.row, OUTPUT.row, REJECT_IN_FRONT.row];

    const PAPER_CACHES: usize = 40_000;
    /// Three times the paper's budget, with 32² paths per cache instead of its 64² (see [`GATHER`]): as
    /// accurate or more in less time on both scenes measured.
    const DEFAULT_CACHES: usize = 3 * Self::PAPER_CACHES;
    /// The vertices of a gathering path that sample a light, pbrt-v2's `maxindirectdepth`.
    const PATH_DEPTH: Option<&'static str> = Some("maxdepth");
    /// gather² paths at every sub-pixel sample. The quick settings keep the cached part of the image
    /// (`output indirect`): the goldens and the stability bounds measure the caches' own error, which the
    /// default image's exact per-pixel direct light would only dilute.
    const STUDY: Study<Self> = Study {
        quick: &[("gather", "16"), ("output", "indirect")],
        per_sample: Some(PerSample { count: "gather", set: &[] }),
        ..Study::NONE
    };

    type Record = IrradianceRecord;
    type Prepared<'s> = Lit<'s>;

    fn from_params(p: &IntegratorParams<'_>, _: &SceneScale) -> Result<Self> {
        let gather = p.get(&GATHER)?;
        let max_depth = p.get(&MAXDEPTH)?;
        let output = p.choice(&OUTPUT)?;
        let reject_in_front = p.get(&REJECT_IN_FRONT)?;
        Ok(IrradianceCache { reject_in_front, ..IrradianceCache::new(gather as usize, max_depth as u32, output) })
    }

    fn prepare<'s>(&self, scene: &'s Scene, warnings: &mut Warnings) -> Result<Lit<'s>> {
        let shading = Shading::build(scene, true, warnings)?;
        let select = LightSelect::new(&shading.lights, "power").map_err(Error::usage)?;
        if self.max_depth == 0 {
            warnings.general(format!(
                "{}: \"maxdepth\" 0 samples no light along gathering paths: the caches hold no indirect light",
                Self::NAME
            ));
        }
        glossy_warning(scene, &shading, warnings);
        Ok(Lit { scene, shading, select, shaded: Default::default() })
    }

    fn shading<'a, 's>(&self, cx: &'a Self::Prepared<'s>) -> Option<&'a Shading<'s>> {
        Some(&cx.shading)
    }

    fn settings(&self) -> Vec<(&'static str, serde_json::Value)> {
        let n = (self.dirs.len() as f64).sqrt().round() as u64;
        vec![
            ("gather", n.into()),
            ("maxdepth", self.max_depth.into()),
            ("output", self.output.name().into()),
            ("rejectinfront", self.reject_in_front.into()),
        ]
    }

    /// The lights the gathering paths sample (each emitting triangle counts as one, as in pbrt-v3).
    /// and, once the image is made, the share of shaded samples whose glossy lobes reflected the cached
    /// light as diffuse.
    fn prepared_report(&self, cx: &Lit<'_>) -> Vec<(&'static str, serde_json::Value)> {
        let [shaded, glossy] = [0, 1].map(|i| cx.shaded[i].load(Ordering::Relaxed));
        let share = if shaded > 0 { glossy as f64 / shaded as f64 } else { 0.0 };
        vec![
            ("lights", cx.shading.lights.len().into()),
            ("samples_reflecting", shaded.into()),
            ("glossy_as_diffuse", glossy.into()),
            ("glossy_share", serde_json::json!((share * 1e4).round() / 1e4)),
        ]
    }

    /// `output full` adds pbrt-v3's `directlighting` with its defaults.
    fn plan(&self) -> CachePlan {
        let added_per_pixel =
            (self.output == Output::Full).then(|| PerPixelTerm { integrator: "directlighting", set: Vec::new() });
        // The caches' indirect light is seen in mirrors and through glass too; the added per-pixel term
        // (`directlighting`) already shows the environment and follows the same specular paths.
        CachePlan { added_per_pixel, follow_specular: true, ..CachePlan::default() }
    }

    fn compute_record(
        &self,
        cx: &Lit<'_>,
        at: &ShadingPoint,
        rng: &mut Rng,
        rays: &mut RayCounters,
    ) -> IrradianceRecord {
        let mut radiance = vec![0.0f32; self.dirs.len()].into_boxed_slice();
        let e = self.gather(cx, at, rng, rays, Some(&mut radiance));
        IrradianceRecord { e: e.to_array(), noise: self.gather_noise(&radiance), radiance }
    }

    fn diff(&self, a: &IrradianceRecord, b: &IrradianceRecord) -> f32 {
        a.radiance.iter().zip(b.radiance.iter()).map(|(x, y)| (x - y).abs()).sum()
    }

    /// Shading reads only E: the per-direction radiance goes.
    fn finish_record(&self, _: &Lit<'_>, record: &mut IrradianceRecord, _: f32) {
        record.radiance = Box::new([]);
    }

    fn shade(
        &self,
        cx: &Lit<'_>,
        s: &ShadingPoint,
        near: &[Neighbour<'_, IrradianceRecord>],
        _: &mut Rng,
        _: Stratum,
        _: &mut RayCounters,
    ) -> [f32; 3] {
        let blend = |all: bool| {
            near.iter().filter(|c| all || self.blends(s, c)).fold((Spectrum::ZERO, 0.0f32), |(e, w), c| {
                (e + c.weight * Spectrum::from_array(c.record.e), w + c.weight)
            })
        };
        let (mut e, mut wsum) = blend(false);
        if wsum <= 0.0 {
            // Every cache is in front: blend them all, as ALGORITHMS.md §5 alone does.
            (e, wsum) = blend(true);
        }
        if wsum <= 0.0 || e == Spectrum::ZERO {
            return [0.0; 3];
        }
        (self.reflectance(cx, s) * e / wsum).to_array()
    }

    /// Shading draws nothing: the blend of the others against the cache alone, reflectance included. The
    /// records are noisy, each E a sum of n² single paths, and so is the reference (the same gathering at
    /// each sub-pixel sample): their variances ([`IrradianceCache::gather_noise`], carried to the reflected
    /// value as the same relative variance) say what part of the miss is the records' noise (the cache's
    /// own and the blend's) and what a pixel keeps: its blend's noise and the reference's.
    fn predict(
        &self,
        cx: &Lit<'_>,
        at: &ShadingPoint,
        own: &IrradianceRecord,
        near: &[Neighbour<'_, IrradianceRecord>],
        samples: u32,
    ) -> Option<LeaveOneOut> {
        if near.is_empty() {
            return None;
        }
        let (mut rng, stratum, mut rays) = (Rng::new(0), Stratum::new(0, 0, 0, 1), RayCounters::default());
        let alone = [Neighbour { record: own, p: at.p, n: at.n, weight: 1.0 }];
        let own_value = self.shade(cx, at, &alone, &mut rng, stratum, &mut rays);
        let from_others = self.shade(cx, at, near, &mut rng, stratum, &mut rays);
        let mut p = LeaveOneOut::values(from_others, own_value);
        let e_of = |r: &IrradianceRecord| luminance(Spectrum::from_array(r.e));
        // The caches shading blends: those not in front of the site, or all of them if every one is.
        let kept = |all: bool| near.iter().filter(move |c| all || self.blends(at, c));
        let all = kept(false).map(|c| c.weight).sum::<f32>() <= 0.0;
        let (mut sw_e, mut sw2_var) = (0f64, 0f64);
        for c in kept(all) {
            sw_e += (c.weight * e_of(c.record)) as f64;
            sw2_var += ((c.weight * c.weight) as f64) * c.record.noise as f64;
        }
        let relative = |var: f64, e: f64| if e > 0.0 { (var / (e * e)) as f32 } else { 0.0 };
        let square_mean = |v: [f32; 3]| v.iter().map(|x| x * x).sum::<f32>() / 3.0;
        let own_noise = relative(own.noise as f64, e_of(own) as f64) * square_mean(own_value);
        let blend_noise = relative(sw2_var, sw_e) * square_mean(from_others);
        p.records_noise = own_noise + blend_noise;
        p.kept_noise = blend_noise + own_noise / samples.max(1) as f32;
        Some(p)
    }

    fn reference(&self, cx: &Lit<'_>, s: &ShadingPoint, rng: &mut Rng, _: Stratum, rays: &mut RayCounters) -> [f32; 3] {
        let e = self.gather(cx, s, rng, rays, None);
        if e == Spectrum::ZERO {
            return [0.0; 3];
        }
        (self.reflectance(cx, s) * e).to_array()
    }

    fn record_bytes(&self, record: &IrradianceRecord) -> usize {
        std::mem::size_of::<IrradianceRecord>() + std::mem::size_of_val(&*record.radiance)
    }

    fn record_bytes_bound(&self) -> usize {
        std::mem::size_of::<IrradianceRecord>() + self.dirs.len() * std::mem::size_of::<f32>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::bxdf::Bxdf;
    use crate::shading::bxdf::fresnel::Fresnel;
    use crate::shading::bxdf::lambert::LambertianReflection;
    use crate::shading::bxdf::specular::SpecularReflection;

    #[test]
    fn uniform_radiance_gives_pi_at_every_grid_size() {
        for n in [1, 2, 8, 64] {
            let app = IrradianceCache::new(n, 3, Output::Indirect);
            let e = app.dirs.iter().map(|d| d.z).sum::<f32>() * app.norm;
            assert!((e - std::f32::consts::PI).abs() < 1e-5, "n = {n}: {e}");
            // The limit the normalisation replaces: (2π/n²) Σ cos θ_k → π.
            let plain = app.dirs.iter().map(|d| d.z).sum::<f32>() * 2.0 * std::f32::consts::PI / (n * n) as f32;
            assert!(n < 64 || (plain / e - 1.0).abs() < 1e-3, "n = {n}: {plain}");
        }
    }

    /// A record gathered from radiance `field(k)` plus independent noise of standard deviation `sd`.
    fn noisy_record(app: &IrradianceCache, field: impl Fn(usize) -> f32, sd: f32, rng: &mut Rng) -> IrradianceRecord {
        let radiance: Box<[f32]> = (0..app.dirs.len())
            .map(|k| {
                // The sum of 12 uniforms less 6: unit variance, near normal.
                let g = (0..12).map(|_| rng.uniform()).sum::<f32>() - 6.0;
                field(k) + sd * g
            })
            .collect();
        let e = app.norm * app.dirs.iter().zip(radiance.iter()).map(|(d, l)| d.z * l).sum::<f32>();
        IrradianceRecord { e: [e; 3], noise: app.gather_noise(&radiance), radiance }
    }

    #[test]
    fn gathering_noise_reads_the_variance_of_e_the_paths_make() {
        let app = IrradianceCache::new(16, 3, Output::Indirect);
        let mut rng = Rng::new(11);
        // Constant radiance 2 with noise 0.5 per direction: E's true variance is norm² · 0.25 · Σ cos².
        let truth = app.norm.powi(2) * 0.25 * app.cos2_sum;
        let runs = 400;
        let (mut es, mut read) = (Vec::new(), 0f64);
        for _ in 0..runs {
            let r = noisy_record(&app, |_| 2.0, 0.5, &mut rng);
            es.push(r.e[0] as f64);
            read += r.noise as f64 / runs as f64;
        }
        let mean = es.iter().sum::<f64>() / runs as f64;
        let spread = es.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (runs - 1) as f64;
        assert!((read / truth as f64 - 1.0).abs() < 0.03, "read {read}, truth {truth}");
        assert!((spread / truth as f64 - 1.0).abs() < 0.2, "spread over runs {spread}, truth {truth}");
        // Radiance that varies smoothly over the grid and carries no noise reads as nearly noiseless.
        let smooth = noisy_record(&app, |k| 1.0 + (k % 16) as f32 / 16.0 + (k / 16) as f32 / 32.0, 0.0, &mut rng);
        assert!(smooth.noise < truth / 20.0, "smooth field read {} against {truth}", smooth.noise);
        // One direction has no neighbours to read a spread from.
        let one = IrradianceCache::new(1, 3, Output::Indirect);
        assert_eq!(noisy_record(&one, |_| 2.0, 0.5, &mut rng).noise, 0.0);
    }

    #[test]
    fn only_non_specular_reflection_lobes_reflect_cached_irradiance() {
        let n = Vec3A::Z;
        let mut b = Bsdf::new(n, n, Vec3A::X, 1.0);
        b.add(Bxdf::Lambertian(LambertianReflection { r: Spectrum::splat(0.4) }));
        b.add(Bxdf::SpecularReflection(SpecularReflection { r: Spectrum::ONE, fresnel: Fresnel::NoOp }));
        let app = IrradianceCache::new(4, 3, Output::Indirect);
        let wo = Vec3A::new(0.3, 0.2, 0.9).normalize();
        assert_eq!(diffuse_reflectance(&b, wo, &app.rho_u), Spectrum::splat(0.4));
    }

    #[test]
    fn caches_in_front_of_a_sample_are_those_above_its_tangent_plane() {
        let s = ShadingPoint {
            p: Vec3A::new(0.0, 2.0, 0.13),
            p_error: Vec3A::ZERO,
            n: -Vec3A::Y,
            ng: -Vec3A::Y,
            wo: -Vec3A::Y,
            depth: 1.0,
            dpdu: Vec3A::X,
            uv: [0.0; 2],
            material: 0,
            area_light: None,
            origin: None,
            flipped: [false; 2],
        };
        let down = -Vec3A::Y;
        // The ceiling around the sample, near or far: never in front.
        for p in [Vec3A::new(0.05, 2.0, 0.1), Vec3A::new(-0.7, 2.0, 0.9), s.p] {
            assert!(!in_front(&s, p, down), "{p}");
        }
        // The light fixture 0.02 below the ceiling, a few centimetres away: in front.
        assert!(in_front(&s, Vec3A::new(-0.058, 1.98, 0.133), down));
        // A cache behind the sample's plane (a convex bend) is not.
        assert!(!in_front(&s, Vec3A::new(0.3, 2.01, 0.13), Vec3A::new(0.05, -1.0, 0.0).normalize()));
        // On a sphere seen from inside (radius 1, the sample at its lowest point), the mean normal makes the
        // offset vanish at any distance: nothing is in front.
        let c = Vec3A::new(0.0, 1.0, 0.13);
        let on = |a: f32| {
            (c + Vec3A::new(a.sin(), -a.cos(), 0.0), (c - (c + Vec3A::new(a.sin(), -a.cos(), 0.0))).normalize())
        };
        let up = ShadingPoint { p: c - Vec3A::Y, n: Vec3A::Y, ng: Vec3A::Y, ..s };
        let (near, n_near) = on(0.05);
        assert!(!in_front(&up, near, n_near));
        let (far, n_far) = on(0.5);
        assert!(!in_front(&up, far, n_far));
    }

    #[test]
    fn the_rho_samples_are_stratified_in_the_unit_square() {
        let app = IrradianceCache::new(4, 3, Output::Indirect);
        assert_eq!(app.rho_u.len(), RHO_SIDE * RHO_SIDE);
        for (i, u) in app.rho_u.iter().enumerate() {
            let cell = [(u[0] * RHO_SIDE as f32) as usize, (u[1] * RHO_SIDE as f32) as usize];
            assert_eq!(cell, [i % RHO_SIDE, i / RHO_SIDE]);
        }
    }
}
