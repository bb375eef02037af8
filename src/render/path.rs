//! STAGE 6 (render): pbrt-v3's `path` integrator — unidirectional path tracing with next-event estimation
//! (one light per vertex, MIS between light and BSDF sampling inside `EstimateDirect`), emission counted at
//! the camera vertex and after specular bounces only, Russian roulette after the third bounce below
//! `rrthreshold` with refraction's radiance scaling factored out (pbrt-v3's `etaScale`).
//!
//! `lightsamplestrategy`: `uniform`, `power` and `spatial` (pbrt-v3's default: per-voxel probabilities, see
//! `shading::light::spatial`) as pbrt-v3 has them.
//!
//! A per-pixel reference for the cache applications; depends on `scene`, `shading` and `shading::lighting`.

use crate::error::{Result, Warnings};
use crate::scene::Scene;
use crate::scene::ray::Ray;
use crate::shading::Spectrum;
use crate::shading::bxdf::BxdfFlags;
use crate::shading::light::{LightSelect, SpatialSelect};

use super::{PixelIntegrator, RayCounters};
use crate::parse::integrator::{IntegratorParams, ParamDef, Parameter, Valid};
use crate::sampling::pixel_samples::PixelSamples;
use crate::shading::lighting::Scratch;
use crate::shading::lighting::{PassThrough, ShadePoint, Shading, sample_one_light};

/// `maxdepth`: bounces (declared by `directlighting`, the same default and range).
pub const MAXDEPTH: ParamDef<i64> = super::directlighting::MAXDEPTH.meaning("bounces");
/// `rrthreshold`.
pub const RRTHRESHOLD: ParamDef<f64> =
    ParamDef::float("rrthreshold", 1.0, "Russian roulette when the path throughput's largest channel is below this")
        .valid(Valid::AtLeast { lo: 0.0, finite: false });
/// `lightsamplestrategy` (an unknown name is a warning and means `spatial`, as in pbrt-v3).
pub const LIGHTSAMPLESTRATEGY: ParamDef<String> =
    ParamDef::text("lightsamplestrategy", "spatial", "`uniform`, `power` or `spatial` (per-voxel light probabilities)");

/// The parameters of `path` (the table of docs/integrators/per-pixel.md).
pub const PARAMETERS: &[Parameter] = &[MAXDEPTH.row, RRTHRESHOLD.row, LIGHTSAMPLESTRATEGY.row];

/// pbrt-v3's `path` integrator: the parameters of [`PARAMETERS`].
pub struct Path<'a> {
    shading: Shading<'a>,
    max_depth: u32,
    rr_threshold: f32,
    select: Select,
}

/// How `path` picks the light it samples at a vertex.
enum Select {
    /// The same probabilities everywhere (`uniform`, `power`).
    Fixed(LightSelect),
    /// Probabilities per voxel of the scene (`spatial`, pbrt-v3's default).
    Spatial(SpatialSelect),
}

impl<'a> Path<'a> {
    /// Reads the parameters and prepares the scene's shading data.
    pub fn from_params(p: &IntegratorParams<'_>, scene: &'a Scene, warnings: &mut Warnings) -> Result<Self> {
        let max_depth = p.get(&MAXDEPTH)? as u32;
        let rr_threshold = p.get(&RRTHRESHOLD)? as f32;
        let strategy = p.get(&LIGHTSAMPLESTRATEGY)?;
        let shading = Shading::build(scene, true, warnings)?;
        let select = match strategy.as_str() {
            "spatial" => Select::Spatial(SpatialSelect::new(scene.bounds())),
            other => match LightSelect::new(&shading.lights, other) {
                Ok(select) => Select::Fixed(select),
                Err(why) => {
                    // pbrt-v3 reports an unknown strategy and uses "spatial".
                    warnings.general(format!("{}path: {why}; using \"spatial\"", p.at("lightsamplestrategy")));
                    Select::Spatial(SpatialSelect::new(scene.bounds()))
                }
            },
        };
        Ok(Path { shading, max_depth, rr_threshold, select })
    }
}

impl PixelIntegrator for Path<'_> {
    fn li(
        &self,
        scene: &Scene,
        mut ray: Ray,
        s: &mut PixelSamples,
        scratch: &mut Scratch,
        c: &mut RayCounters,
    ) -> [f32; 3] {
        let sh = &self.shading;
        let mut l = Spectrum::ZERO;
        let mut beta = Spectrum::ONE;
        let mut specular_bounce = false;
        let mut eta_scale = 1.0f32;
        let mut bounces = 0u32;
        let mut pass = PassThrough::default();
        let mut bsdfs = scratch.take_bsdfs(1);
        let bsdf = &mut bsdfs[0];
        loop {
            c.camera += 1;
            let hit = scene.geometry.intersect(&ray);
            if bounces == 0 || specular_bounce {
                l += beta
                    * match &hit {
                        Some(si) => sh.lights.emitted(si, -ray.d),
                        None => sh.lights.le_escaped(&ray),
                    };
            }
            let Some(si) = hit else { break };
            if bounces >= self.max_depth {
                break;
            }
            let voxel = match &self.select {
                Select::Spatial(v) => Some(v.locate(si.p)),
                Select::Fixed(_) => None,
            };
            if !sh.bsdf_into(&si, bsdf) {
                let Some(next) = pass.past(&si, &ray) else { break };
                ray = next;
                continue;
            };
            let wo = -ray.d;
            let x = ShadePoint { si: &si, bsdf, wo };
            if bsdf.num_components(BxdfFlags::NON_SPECULAR) > 0 {
                let d = match &self.select {
                    Select::Fixed(f) => sample_one_light(scene, sh, |u| f.sample(u), &x, s, c),
                    Select::Spatial(v) => {
                        let voxel = voxel.unwrap_or_else(|| v.locate(si.p));
                        sample_one_light(scene, sh, |u| v.sample_in(&sh.lights, voxel, u), &x, s, c)
                    }
                };
                l += beta * d;
            }
            let Some(bs) = bsdf.sample_f(wo, s.get2d(), BxdfFlags::ALL) else { break };
            if bs.f == Spectrum::ZERO || bs.pdf <= 0.0 {
                break;
            }
            beta *= bs.f * bs.wi.dot(bsdf.shading_normal()).abs() / bs.pdf;
            specular_bounce = bs.sampled.contains(BxdfFlags::SPECULAR);
            if specular_bounce && bs.sampled.contains(BxdfFlags::TRANSMISSION) {
                let eta = bsdf.eta;
                eta_scale *= if wo.dot(si.ng) > 0.0 { eta * eta } else { 1.0 / (eta * eta) };
            }
            ray = si.spawn_ray(bs.wi);
            let rr = (beta * eta_scale).max_element();
            if rr < self.rr_threshold && bounces > 3 {
                let q = (1.0 - rr).max(0.05);
                if s.get2d()[0] < q {
                    break;
                }
                beta /= 1.0 - q;
            }
            bounces += 1;
        }
        scratch.bsdfs = bsdfs;
        l.to_array()
    }
}
