//! STAGE 5 (shading): the shading data of a scene made ready for rendering (materials compiled, texture
//! images loaded, lights built) and pbrt-v3's direct-lighting estimators over it — `EstimateDirect` with
//! multiple importance sampling (power heuristic, β = 2), `UniformSampleAllLights` and
//! `UniformSampleOneLight` — shared by the `directlighting` and `path` integrators and by the cache
//! applications that shade real surfaces, with the per-thread [`Scratch`] they reuse.
//!
//! Depends on `scene`, `sampling` and the rest of `shading`; knows nothing of integrators, placement or
//! caches.

use glam::Vec3A;

use crate::error::{Result, Warnings};
use crate::sampling::pixel_samples::PixelSamples;
use crate::scene::Scene;
use crate::scene::accel::OccluderHint;
use crate::scene::geometry::SurfaceInteraction;
use crate::scene::ray::{Ray, RayCounters};
use crate::shading::Spectrum;
use crate::shading::bsdf::Bsdf;
use crate::shading::bxdf::BxdfFlags;
use crate::shading::light::Lights;
use crate::shading::material::Materials;
use crate::shading::texture::Textures;

/// Storage a thread's integrator reuses from one camera sample to the next (one per tile).
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    /// 2-D sample arrays (ambient-occlusion directions, light and BSDF samples).
    pub points: Vec<[f32; 2]>,
    /// Per light, the blocker of its last shadow ray (see `scene::accel::OccluderHint`): `directlighting`
    /// with every light sampled at every vertex tests it first, as neighbouring points' shadow rays toward
    /// the same light are often blocked by the same triangle. It never changes an answer.
    pub light_hints: Vec<OccluderHint>,
    /// BSDFs kept from one camera sample to the next, one per depth of recursion (`path` uses the first,
    /// `directlighting` one per specular bounce): refilled at each hit ([`Bsdf::reset`]) rather than built
    /// afresh, which writes all 848 bytes of its lobe storage.
    pub bsdfs: Vec<Bsdf>,
}

impl Scratch {
    /// Takes [`Scratch::bsdfs`] out, at least `n` of them (made when missing), so that an integrator can
    /// hold them while it lends the scratch to the estimators; it puts them back with `scratch.bsdfs = …`.
    pub fn take_bsdfs(&mut self, n: usize) -> Vec<Bsdf> {
        let mut bsdfs = std::mem::take(&mut self.bsdfs);
        if bsdfs.len() < n {
            bsdfs.resize(n, Bsdf::new(Vec3A::Z, Vec3A::Z, Vec3A::X, 1.0));
        }
        bsdfs
    }
}

/// Materials, textures and lights of one scene, ready to shade with.
pub struct Shading<'a> {
    /// Compiled materials.
    pub materials: Materials,
    /// Textures with their images.
    pub textures: Textures,
    /// Light sources (one per emitting triangle, as in pbrt-v3).
    pub lights: Lights<'a>,
    /// pbrt-v3's `allowMultipleLobes` (true for `path`: smooth glass is one `FresnelSpecular` lobe; false
    /// for `directlighting`, whose specular-bounce code samples reflection and transmission separately).
    pub multiple_lobes: bool,
}

impl<'a> Shading<'a> {
    /// Prepares the shading data of `scene`; a scene without lights gets a warning (its image is black, as
    /// pbrt-v3's is).
    pub fn build(scene: &'a Scene, multiple_lobes: bool, warnings: &mut Warnings) -> Result<Shading<'a>> {
        let textures = Textures::build(scene, warnings)?;
        let materials = Materials::build(scene, warnings)?;
        let lights = Lights::build(scene, warnings)?;
        if lights.is_empty() {
            warnings.general("the scene has no light sources; the image will be black".to_string());
        }
        Ok(Shading { materials, textures, lights, multiple_lobes })
    }

    /// The BSDF at a hit (`None` for a surface without material, which rays pass through).
    #[inline]
    pub fn bsdf(&self, si: &SurfaceInteraction) -> Option<Bsdf> {
        self.materials.bsdf_with(si.material, si, &self.textures, self.multiple_lobes)
    }

    /// [`Shading::bsdf`] written into `out`, which a path keeps across its vertices; false (and `out`
    /// untouched) for a surface without material.
    #[inline]
    pub fn bsdf_into(&self, si: &SurfaceInteraction, out: &mut Bsdf) -> bool {
        self.materials.bsdf_into(si.material, si, &self.textures, self.multiple_lobes, out)
    }
}

/// Most surfaces without a material one path passes through before it gives up.
pub const MAX_PASS_THROUGH: usize = 1024;

/// Counts the surfaces without a material a path has passed through (pbrt-v3's integrators skip them and
/// go on along the same ray).
#[derive(Clone, Copy, Debug, Default)]
pub struct PassThrough {
    passes: usize,
}

impl PassThrough {
    /// The ray that continues past `si`, a surface without material that `ray` hit (`None` once the path
    /// has passed [`MAX_PASS_THROUGH`] of them: it gives up). Callers ask [`Shading::bsdf`] first and come
    /// here when it has none; the BSDF is not passed through this function, so it is not copied.
    #[inline]
    pub fn past(&mut self, si: &SurfaceInteraction, ray: &Ray) -> Option<Ray> {
        self.passes += 1;
        (self.passes <= MAX_PASS_THROUGH).then(|| si.spawn_ray(ray.d))
    }
}

/// pbrt-v3's power heuristic with β = 2, one sample per technique.
#[inline]
pub fn power_heuristic(f_pdf: f32, g_pdf: f32) -> f32 {
    let (f, g) = (f_pdf * f_pdf, g_pdf * g_pdf);
    if f.is_infinite() {
        return 1.0;
    }
    if f + g == 0.0 { 0.0 } else { f / (f + g) }
}

/// Everything the estimators need about the point being shaded.
pub struct ShadePoint<'a> {
    /// The surface interaction.
    pub si: &'a SurfaceInteraction,
    /// Its BSDF.
    pub bsdf: &'a Bsdf,
    /// Direction toward the viewer (−ray.d).
    pub wo: Vec3A,
}

/// Radiance reflected at `x` from light `light` by one light sample and one BSDF sample combined with the
/// power heuristic (pbrt-v3 `EstimateDirect`, specular lobes excluded, no participating media).
pub fn estimate_direct(
    scene: &Scene,
    sh: &Shading<'_>,
    x: &ShadePoint<'_>,
    light: usize,
    u_light: [f32; 2],
    u_scatter: [f32; 2],
    c: &mut RayCounters,
) -> Spectrum {
    estimate_direct_hinted(scene, sh, x, light, [u_light, u_scatter], c, &mut OccluderHint::default())
}

/// [`estimate_direct`] (samples `u` = [light, scatter]) whose shadow rays first test the blocker remembered
/// in `hint` and remember theirs: the same result, fewer traversals when consecutive calls for one light
/// come from nearby points.
pub fn estimate_direct_hinted(
    scene: &Scene,
    sh: &Shading<'_>,
    x: &ShadePoint<'_>,
    light: usize,
    [u_light, u_scatter]: [[f32; 2]; 2],
    c: &mut RayCounters,
    hint: &mut OccluderHint,
) -> Spectrum {
    let flags = BxdfFlags::NON_SPECULAR;
    // A light wholly behind the surface, on the side away from the viewer, adds exactly nothing to a BSDF that
    // only reflects: its samples all have f = 0 (the geometric normal makes them transmission) and no BSDF
    // direction with f ≠ 0 meets it. Skipping them saves a light sample and a BSDF sample per light;
    // the result, the sample values consumed and the rays traced are the same.
    let ng = x.si.ng;
    let side = if x.wo.dot(ng) > 0.0 { ng } else { -ng };
    if sh.lights.behind(light, x.si.p, side) && !x.bsdf.has_transmission() {
        return Spectrum::ZERO;
    }
    let ns = x.bsdf.shading_normal();
    let delta = sh.lights.is_delta(light);
    let mut ld = Spectrum::ZERO;
    if let Some(ls) = sh.lights.sample_li(light, x.si, u_light)
        && ls.pdf > 0.0
        && ls.li != Spectrum::ZERO
    {
        let f = x.bsdf.f(x.wo, ls.wi, flags) * ls.wi.dot(ns).abs();
        if f != Spectrum::ZERO {
            c.shadow += 1;
            if !scene.geometry.occluded_hinted(&ls.shadow, Some(x.si.origin), hint) {
                if delta {
                    ld += f * ls.li / ls.pdf;
                } else {
                    let scatter_pdf = x.bsdf.pdf(x.wo, ls.wi, flags);
                    ld += f * ls.li * power_heuristic(ls.pdf, scatter_pdf) / ls.pdf;
                }
            }
        }
    }
    if delta {
        return ld;
    }
    // The specular lobes are excluded above, so the sample is weighted against the light's density. The
    // light is asked first, as soon as the direction is drawn: most directions miss a small light and need
    // neither the BSDF's value and density nor any traversal (see `Lights::hit_by`); a direction that meets
    // it is kept when nothing else is in between.
    let toward_light = |wi| sh.lights.hit_by(light, x.si, wi);
    let Some((bs, h)) = x.bsdf.sample_f_toward(x.wo, u_scatter, flags, toward_light) else { return ld };
    let f = bs.f * bs.wi.dot(ns).abs();
    if f == Spectrum::ZERO || bs.pdf <= 0.0 {
        return ld;
    }
    c.shadow += 1;
    if scene.geometry.occluded_hinted(&h.shadow, Some(x.si.origin), hint) {
        return ld;
    }
    ld + f * h.li * power_heuristic(bs.pdf, h.pdf) / bs.pdf
}

/// pbrt-v3 `UniformSampleAllLights`: every light, with `counts[j]` samples each (arrays of the sampler);
/// each light's shadow rays keep their hint in `scratch.light_hints`.
pub fn sample_all_lights(
    scene: &Scene,
    sh: &Shading<'_>,
    x: &ShadePoint<'_>,
    counts: &[u32],
    s: &mut PixelSamples,
    scratch: &mut Scratch,
    c: &mut RayCounters,
) -> Spectrum {
    let mut l = Spectrum::ZERO;
    scratch.light_hints.resize(counts.len(), OccluderHint::default());
    for (j, &n) in counts.iter().enumerate() {
        let n = n as usize;
        scratch.points.resize(2 * n, [0.0; 2]);
        let (u_light, u_scatter) = scratch.points.split_at_mut(n);
        s.array2d(u_light);
        s.array2d(u_scatter);
        let mut ld = Spectrum::ZERO;
        let hint = &mut scratch.light_hints[j];
        for k in 0..n {
            ld += estimate_direct_hinted(scene, sh, x, j, [u_light[k], u_scatter[k]], c, hint);
        }
        l += ld / n as f32;
    }
    l
}

/// pbrt-v3 `UniformSampleOneLight`: one light chosen by `choose` (a sample in [0, 1) → the light and its
/// probability), its estimate divided by that probability.
pub fn sample_one_light(
    scene: &Scene,
    sh: &Shading<'_>,
    choose: impl Fn(f32) -> Option<(usize, f32)>,
    x: &ShadePoint<'_>,
    s: &mut PixelSamples,
    c: &mut RayCounters,
) -> Spectrum {
    let u = s.get2d();
    let Some((light, pmf)) = choose(u[0]) else { return Spectrum::ZERO };
    if pmf == 0.0 {
        return Spectrum::ZERO;
    }
    let u_light = s.get2d();
    let u_scatter = s.get2d();
    estimate_direct(scene, sh, x, light, u_light, u_scatter, c) / pmf
}
