//! STAGE 6 (render): pbrt-v3's `directlighting` integrator — emitted radiance of the surface seen, direct
//! lighting from every light (`strategy "all"`, each light's `nsamples`) or from one light chosen uniformly
//! (`"one"`), and perfect specular reflection and transmission followed up to `maxdepth`.
//!
//! A per-pixel reference for the cache applications; depends on `scene`, `shading` and the estimators in
//! `shading::lighting`.

use crate::error::{Error, Result, Warnings};
use crate::scene::Scene;
use crate::scene::ray::Ray;
use crate::scene::sampler::SamplerSpec;
use crate::shading::Spectrum;
use crate::shading::bsdf::Bsdf;
use crate::shading::bxdf::BxdfFlags;
use crate::shading::light::LightSelect;

use super::{PixelIntegrator, RayCounters};
use crate::parse::integrator::{IntegratorParams, ParamDef, Parameter};
use crate::sampling::pixel_samples::PixelSamples;
use crate::shading::lighting::Scratch;
use crate::shading::lighting::{ShadePoint, Shading, sample_all_lights, sample_one_light};

/// Most surfaces without a material a ray passes through before it gives up.
const MAX_PASS_THROUGH: usize = 1024;

/// How lights are sampled at each shading point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// Every light, with its `nsamples` samples.
    All,
    /// One light chosen uniformly.
    One,
}

/// `strategy`: every light, or one chosen uniformly (an unknown name is a warning and means `all`, as in
/// pbrt-v3).
pub const STRATEGY: ParamDef<String> =
    ParamDef::text("strategy", "all", "`all`: every light with its nsamples; `one`: one light chosen uniformly");
/// `maxdepth`: the specular bounces followed (`path` reads it as its bounces). pbrt-v3 reads any `int`, so
/// any non-negative one is accepted (the Cornell box of the shared scenes sets 65); `directlighting`
/// follows at most [`MAX_SPECULAR_DEPTH`] of them, with a warning beyond.
pub const MAXDEPTH: ParamDef<i64> =
    ParamDef::int("maxdepth", 5, "specular bounces followed").between(0, i32::MAX as i64);

/// Most specular bounces `directlighting` follows (each level of its recursion keeps a BSDF).
pub const MAX_SPECULAR_DEPTH: u32 = 1024;

/// The parameters of `directlighting` (the table of docs/integrators/per-pixel.md).
pub const PARAMETERS: &[Parameter] = &[STRATEGY.row, MAXDEPTH.row];

/// pbrt-v3's `directlighting` integrator: the parameters of [`PARAMETERS`].
pub struct DirectLighting<'a> {
    shading: Shading<'a>,
    strategy: Strategy,
    max_depth: u32,
    /// Samples per light (rounded as the sampler rounds arrays).
    counts: Vec<u32>,
    uniform: LightSelect,
}

impl<'a> DirectLighting<'a> {
    /// Reads the parameters and prepares the scene's shading data.
    pub fn from_params(
        p: &IntegratorParams<'_>,
        scene: &'a Scene,
        sampler: &SamplerSpec,
        quick: bool,
        warnings: &mut Warnings,
    ) -> Result<Self> {
        let mut max_depth = p.get(&MAXDEPTH)? as u32;
        if max_depth > MAX_SPECULAR_DEPTH {
            warnings.general(format!(
                "{}directlighting: \"maxdepth\" {max_depth}: following at most {MAX_SPECULAR_DEPTH} specular bounces",
                p.at("maxdepth")
            ));
            max_depth = MAX_SPECULAR_DEPTH;
        }
        let strategy = match p.get(&STRATEGY)?.as_str() {
            "all" => Strategy::All,
            "one" => Strategy::One,
            other => {
                // pbrt-v3 warns and uses "all".
                warnings.general(format!(
                    "{}directlighting: unknown strategy \"{other}\"; using \"all\"",
                    p.at("strategy")
                ));
                Strategy::All
            }
        };
        let shading = Shading::build(scene, false, warnings)?;
        let counts = (0..shading.lights.len())
            .map(|j| if quick { 1 } else { sampler.round_count(shading.lights.samples(j)) })
            .collect();
        let uniform = LightSelect::new(&shading.lights, "uniform").map_err(Error::usage)?;
        Ok(DirectLighting { shading, strategy, max_depth, counts, uniform })
    }

    /// The radiance along `ray` at recursion depth `depth`; `bsdfs` holds a BSDF for this depth and each
    /// deeper one.
    #[allow(clippy::too_many_arguments)]
    fn radiance(
        &self,
        scene: &Scene,
        mut ray: Ray,
        depth: u32,
        bsdfs: &mut [Bsdf],
        s: &mut PixelSamples,
        scratch: &mut Scratch,
        c: &mut RayCounters,
    ) -> Spectrum {
        let sh = &self.shading;
        let Some((bsdf, deeper)) = bsdfs.split_first_mut() else { return Spectrum::ZERO };
        for _ in 0..MAX_PASS_THROUGH {
            c.camera += 1;
            let Some(si) = scene.geometry.intersect(&ray) else { return sh.lights.le_escaped(&ray) };
            if !sh.bsdf_into(&si, bsdf) {
                ray = si.spawn_ray(ray.d);
                continue;
            }
            let wo = -ray.d;
            let x = ShadePoint { si: &si, bsdf, wo };
            let mut l = sh.lights.emitted(&si, wo);
            if !sh.lights.is_empty() {
                l += match self.strategy {
                    Strategy::All => sample_all_lights(scene, sh, &x, &self.counts, s, scratch, c),
                    Strategy::One => sample_one_light(scene, sh, |u| self.uniform.sample(u), &x, s, c),
                };
            }
            if depth + 1 < self.max_depth {
                for lobe in [BxdfFlags::REFLECTION, BxdfFlags::TRANSMISSION] {
                    l += self.specular(scene, &x, lobe, depth, deeper, s, scratch, c);
                }
            }
            return l;
        }
        Spectrum::ZERO
    }

    /// pbrt-v3 `SpecularReflect` / `SpecularTransmit`: follows the perfectly specular lobe of kind `lobe`.
    #[allow(clippy::too_many_arguments)]
    fn specular(
        &self,
        scene: &Scene,
        x: &ShadePoint<'_>,
        lobe: BxdfFlags,
        depth: u32,
        bsdfs: &mut [Bsdf],
        s: &mut PixelSamples,
        scratch: &mut Scratch,
        c: &mut RayCounters,
    ) -> Spectrum {
        let flags = lobe | BxdfFlags::SPECULAR;
        if x.bsdf.num_components(flags) == 0 {
            // pbrt-v3 draws the sample and finds no lobe; the dimensions advance the same way.
            s.skip2d();
            return Spectrum::ZERO;
        }
        let u = s.get2d();
        let Some(bs) = x.bsdf.sample_f(x.wo, u, flags) else { return Spectrum::ZERO };
        let cos = bs.wi.dot(x.bsdf.shading_normal()).abs();
        if bs.pdf <= 0.0 || bs.f == Spectrum::ZERO || cos == 0.0 {
            return Spectrum::ZERO;
        }
        let li = self.radiance(scene, x.si.spawn_ray(bs.wi), depth + 1, bsdfs, s, scratch, c);
        bs.f * li * cos / bs.pdf
    }
}

impl PixelIntegrator for DirectLighting<'_> {
    fn li(
        &self,
        scene: &Scene,
        ray: Ray,
        s: &mut PixelSamples,
        scratch: &mut Scratch,
        c: &mut RayCounters,
    ) -> [f32; 3] {
        let mut bsdfs = scratch.take_bsdfs(self.max_depth.max(1) as usize);
        let l = self.radiance(scene, ray, 0, &mut bsdfs, s, scratch, c);
        scratch.bsdfs = bsdfs;
        l.to_array()
    }
}
