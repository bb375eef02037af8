//! STAGE 5 (shading): pbrt-v3's `ComputeScatteringFunctions` for each material — the lobes a compiled
//! material puts in the BSDF at one hit, with textured values read there and clamped as pbrt-v3 clamps them.
//!
//! Depends on [`super::compile`], [`super::param`], the BxDFs and the BSDF; allocation-free.

use crate::scene::geometry::SurfaceInteraction;
use crate::shading::Spectrum;
use crate::shading::bsdf::Bsdf;
use crate::shading::bxdf::{
    Bxdf, Fresnel, FresnelBlend, FresnelSpecular, LambertianReflection, LambertianTransmission, MicrofacetReflection,
    MicrofacetTransmission, OrenNayar, SpecularReflection, SpecularTransmission, TrowbridgeReitz, roughness_to_alpha,
};
use crate::shading::texture::Textures;

use super::compile::Compiled;
use super::param::{FloatParam, clamp_spectrum, safe_ior, safe_roughness};

/// Deepest nesting of `mix` materials followed (deeper parts add no lobes).
const MAX_MIX_DEPTH: u32 = 16;

/// What a hit needs to build a BSDF.
pub struct MaterialHit<'a> {
    /// The surface point.
    pub si: &'a SurfaceInteraction,
    /// The scene's textures.
    pub textures: &'a Textures,
    /// pbrt-v3's `allowMultipleLobes`: smooth glass as one `FresnelSpecular` lobe (true: `path`) or as
    /// separate specular reflection and transmission lobes (false: `directlighting`, `whitted`).
    pub multiple_lobes: bool,
}

impl MaterialHit<'_> {
    fn color(&self, p: &super::param::SpecParam) -> Spectrum {
        p.eval_clamped(self.si, self.textures)
    }

    fn float(&self, p: &FloatParam) -> f32 {
        p.eval(self.si, self.textures)
    }

    fn alpha(&self, p: &FloatParam, remap: bool) -> f32 {
        let r = safe_roughness(self.float(p));
        if remap { roughness_to_alpha(r) } else { r }
    }

    /// Empties `b` and gives it this hit's frame.
    fn reset(&self, b: &mut Bsdf, eta: f32) {
        b.reset(self.si.ng, self.si.ns, self.si.dpdu, eta);
    }
}

fn is_black(s: Spectrum) -> bool {
    s == Spectrum::ZERO
}

/// Fills `b` with the BSDF of material `id` at the hit; false (and `b` untouched) for a material without
/// one. `b` is overwritten, not allocated: callers keep one per path (see [`Bsdf::reset`]).
pub fn scatter(materials: &[Compiled], id: u32, hit: &MaterialHit, depth: u32, b: &mut Bsdf) -> bool {
    let m = materials.get(id as usize).copied().unwrap_or(Compiled::None);
    match m {
        Compiled::None => return false,
        Compiled::Matte { kd, sigma } => {
            hit.reset(b, 1.0);
            let r = hit.color(&kd);
            let s = hit.float(&sigma);
            let s = if s.is_nan() { 0.0 } else { s.clamp(0.0, 90.0) };
            if !is_black(r) {
                b.add(if s == 0.0 {
                    Bxdf::Lambertian(LambertianReflection { r })
                } else {
                    Bxdf::OrenNayar(OrenNayar::new(r, s))
                });
            }
        }
        Compiled::Plastic { kd, ks, roughness, remap } => {
            hit.reset(b, 1.0);
            let kd = hit.color(&kd);
            if !is_black(kd) {
                b.add(Bxdf::Lambertian(LambertianReflection { r: kd }));
            }
            let ks = hit.color(&ks);
            if !is_black(ks) {
                let a = hit.alpha(&roughness, remap);
                b.add(Bxdf::MicrofacetReflection(MicrofacetReflection {
                    r: ks,
                    distribution: TrowbridgeReitz::new(a, a),
                    fresnel: Fresnel::Dielectric { eta_i: 1.5, eta_t: 1.0 },
                }));
            }
        }
        Compiled::Substrate { kd, ks, urough, vrough, remap } => {
            hit.reset(b, 1.0);
            let (d, s) = (hit.color(&kd), hit.color(&ks));
            if !is_black(d) || !is_black(s) {
                let distribution = TrowbridgeReitz::new(hit.alpha(&urough, remap), hit.alpha(&vrough, remap));
                b.add(Bxdf::FresnelBlend(FresnelBlend { rd: d, rs: s, distribution }));
            }
        }
        Compiled::Metal { eta, k, urough, vrough, remap } => {
            hit.reset(b, 1.0);
            let distribution = TrowbridgeReitz::new(hit.alpha(&urough, remap), hit.alpha(&vrough, remap));
            // η = k = 0 would make the conductor term 0/0 at normal incidence; keep η a hair above 0.
            let eta = eta.eval(hit.si, hit.textures).max(Spectrum::splat(1e-4));
            let k = clamp_spectrum(k.eval(hit.si, hit.textures));
            b.add(Bxdf::MicrofacetReflection(MicrofacetReflection {
                r: Spectrum::ONE,
                distribution,
                fresnel: Fresnel::Conductor { eta, k },
            }));
        }
        Compiled::Mirror { kr } => {
            hit.reset(b, 1.0);
            let r = hit.color(&kr);
            if !is_black(r) {
                b.add(Bxdf::SpecularReflection(SpecularReflection { r, fresnel: Fresnel::NoOp }));
            }
        }
        Compiled::Glass { kr, kt, eta, urough, vrough, remap } => glass(hit, kr, kt, eta, urough, vrough, remap, b),
        Compiled::Uber { .. } => uber(hit, m, b),
        Compiled::Mix { .. } => mix(materials, m, hit, depth, b),
        Compiled::Translucent { .. } => translucent(hit, m, b),
    }
    true
}

/// Uber: pbrt-v3's `UberMaterial` — an opacity's specular pass-through, diffuse, glossy, specular reflection
/// and transmission lobes.
fn uber(hit: &MaterialHit, m: Compiled, b: &mut Bsdf) {
    let Compiled::Uber { kd, ks, kr, kt, urough, vrough, eta, opacity, remap } = m else { return };
    let e = safe_ior(hit.float(&eta));
    let op = hit.color(&opacity);
    let t = clamp_spectrum(Spectrum::ONE - op);
    if !is_black(t) {
        hit.reset(b, 1.0);
        b.add(Bxdf::SpecularTransmission(SpecularTransmission { t, eta_a: 1.0, eta_b: 1.0 }));
    } else {
        hit.reset(b, e);
    }
    let kd = op * hit.color(&kd);
    if !is_black(kd) {
        b.add(Bxdf::Lambertian(LambertianReflection { r: kd }));
    }
    let ks = op * hit.color(&ks);
    if !is_black(ks) {
        let ru = safe_roughness(hit.float(&urough));
        let rv = vrough.map_or(ru, |v| safe_roughness(hit.float(&v)));
        let (au, av) = if remap { (roughness_to_alpha(ru), roughness_to_alpha(rv)) } else { (ru, rv) };
        b.add(Bxdf::MicrofacetReflection(MicrofacetReflection {
            r: ks,
            distribution: TrowbridgeReitz::new(au, av),
            fresnel: Fresnel::Dielectric { eta_i: 1.0, eta_t: e },
        }));
    }
    let kr = op * hit.color(&kr);
    if !is_black(kr) {
        b.add(Bxdf::SpecularReflection(SpecularReflection {
            r: kr,
            fresnel: Fresnel::Dielectric { eta_i: 1.0, eta_t: e },
        }));
    }
    let kt = op * hit.color(&kt);
    if !is_black(kt) {
        b.add(Bxdf::SpecularTransmission(SpecularTransmission { t: kt, eta_a: 1.0, eta_b: e }));
    }
}

/// Mix: the lobes of both parts, weighted by `amount` and 1 − `amount` (pbrt-v3's `MixMaterial`).
fn mix(materials: &[Compiled], m: Compiled, hit: &MaterialHit, depth: u32, b: &mut Bsdf) {
    let Compiled::Mix { amount, materials: [m1, m2] } = m else { return };
    // A part without a BSDF (`none`) adds no lobes (pbrt-v3 would dereference a null BSDF); lobes past
    // the eighth are dropped (pbrt-v3 would abort; `Materials::build` warns).
    let s1 = hit.color(&amount);
    let s2 = clamp_spectrum(Spectrum::ONE - s1);
    let deeper = depth < MAX_MIX_DEPTH;
    if !(deeper && scatter(materials, m1, hit, depth + 1, b)) {
        hit.reset(b, 1.0);
    }
    b.scale_all(s1);
    // The second part needs storage of its own; mixes are rare enough for a local one.
    let mut b2 = Bsdf::new(hit.si.ng, hit.si.ns, hit.si.dpdu, 1.0);
    if deeper && scatter(materials, m2, hit, depth + 1, &mut b2) {
        for (lobe, s) in b2.lobes() {
            b.add_scaled(*lobe, s * s2);
        }
    }
}

/// Translucent: diffuse and glossy lobes reflected and transmitted (pbrt-v3's `TranslucentMaterial`).
fn translucent(hit: &MaterialHit, m: Compiled, b: &mut Bsdf) {
    let Compiled::Translucent { kd, ks, reflect, transmit, roughness, remap } = m else { return };
    let eta = 1.5;
    hit.reset(b, eta);
    let (r, t) = (hit.color(&reflect), hit.color(&transmit));
    if is_black(r) && is_black(t) {
        return;
    }
    let kd = hit.color(&kd);
    if !is_black(kd) {
        if !is_black(r) {
            b.add(Bxdf::Lambertian(LambertianReflection { r: r * kd }));
        }
        if !is_black(t) {
            b.add(Bxdf::LambertianTransmission(LambertianTransmission { t: t * kd }));
        }
    }
    let ks = hit.color(&ks);
    if !is_black(ks) {
        let a = hit.alpha(&roughness, remap);
        let distribution = TrowbridgeReitz::new(a, a);
        if !is_black(r) {
            b.add(Bxdf::MicrofacetReflection(MicrofacetReflection {
                r: r * ks,
                distribution,
                fresnel: Fresnel::Dielectric { eta_i: 1.0, eta_t: eta },
            }));
        }
        if !is_black(t) {
            b.add(Bxdf::MicrofacetTransmission(MicrofacetTransmission {
                t: t * ks,
                distribution,
                eta_a: 1.0,
                eta_b: eta,
            }));
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn glass(
    hit: &MaterialHit,
    kr: super::param::SpecParam,
    kt: super::param::SpecParam,
    eta: FloatParam,
    urough: FloatParam,
    vrough: FloatParam,
    remap: bool,
    b: &mut Bsdf,
) {
    let eta = safe_ior(hit.float(&eta));
    let (ru, rv) = (safe_roughness(hit.float(&urough)), safe_roughness(hit.float(&vrough)));
    let (r, t) = (hit.color(&kr), hit.color(&kt));
    hit.reset(b, eta);
    if is_black(r) && is_black(t) {
        return;
    }
    let specular = ru == 0.0 && rv == 0.0;
    if specular && hit.multiple_lobes {
        b.add(Bxdf::FresnelSpecular(FresnelSpecular { r, t, eta_a: 1.0, eta_b: eta }));
        return;
    }
    let (au, av) = if remap { (roughness_to_alpha(ru), roughness_to_alpha(rv)) } else { (ru, rv) };
    let distribution = TrowbridgeReitz::new(au, av);
    if !is_black(r) {
        let fresnel = Fresnel::Dielectric { eta_i: 1.0, eta_t: eta };
        b.add(if specular {
            Bxdf::SpecularReflection(SpecularReflection { r, fresnel })
        } else {
            Bxdf::MicrofacetReflection(MicrofacetReflection { r, distribution, fresnel })
        });
    }
    if !is_black(t) {
        b.add(if specular {
            Bxdf::SpecularTransmission(SpecularTransmission { t, eta_a: 1.0, eta_b: eta })
        } else {
            Bxdf::MicrofacetTransmission(MicrofacetTransmission { t, distribution, eta_a: 1.0, eta_b: eta })
        });
    }
}
