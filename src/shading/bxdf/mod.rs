//! STAGE 5 (shading): pbrt-v3's BxDFs (src/core/reflection.{h,cpp}, microfacet.{h,cpp}) — one lobe each,
//! in the local shading frame where z is the shading normal — and the flags that classify them.
//!
//! A lobe is a small `Copy` value (no allocation); [`Bxdf`] dispatches over the closed set with a `match`.
//! Only radiance transport (camera paths) is modelled: the transmission lobes scale by (η_i/η_t)².
//! Depends on `sampling::warp` and the `Spectrum` type; knows nothing of scenes, textures or materials.

pub mod distribution;
pub mod fresnel;
pub mod fresnel_blend;
pub mod lambert;
pub mod local;
pub mod microfacet;
pub mod oren_nayar;
pub mod specular;

use glam::Vec3A;

pub use distribution::{TrowbridgeReitz, roughness_to_alpha};
pub use fresnel::Fresnel;
pub use fresnel_blend::FresnelBlend;
pub use lambert::{LambertianReflection, LambertianTransmission};
pub use microfacet::{MicrofacetReflection, MicrofacetTransmission};
pub use oren_nayar::OrenNayar;
pub use specular::{FresnelSpecular, SpecularReflection, SpecularTransmission};

use super::Spectrum;

/// pbrt-v3's `BxDFType`: a bit set of what a lobe does (side and kind of scattering).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct BxdfFlags(pub u8);

impl BxdfFlags {
    /// No lobe.
    pub const NONE: BxdfFlags = BxdfFlags(0);
    /// Scatters to the side of the outgoing direction.
    pub const REFLECTION: BxdfFlags = BxdfFlags(1);
    /// Scatters to the other side.
    pub const TRANSMISSION: BxdfFlags = BxdfFlags(2);
    /// Diffuse.
    pub const DIFFUSE: BxdfFlags = BxdfFlags(4);
    /// Glossy.
    pub const GLOSSY: BxdfFlags = BxdfFlags(8);
    /// A delta distribution.
    pub const SPECULAR: BxdfFlags = BxdfFlags(16);
    /// Every lobe.
    pub const ALL: BxdfFlags = BxdfFlags(31);
    /// Diffuse reflection.
    pub const DIFFUSE_REFLECTION: BxdfFlags = BxdfFlags(1 | 4);
    /// Diffuse transmission.
    pub const DIFFUSE_TRANSMISSION: BxdfFlags = BxdfFlags(2 | 4);
    /// Glossy reflection.
    pub const GLOSSY_REFLECTION: BxdfFlags = BxdfFlags(1 | 8);
    /// Glossy transmission.
    pub const GLOSSY_TRANSMISSION: BxdfFlags = BxdfFlags(2 | 8);
    /// Specular reflection.
    pub const SPECULAR_REFLECTION: BxdfFlags = BxdfFlags(1 | 16);
    /// Specular transmission.
    pub const SPECULAR_TRANSMISSION: BxdfFlags = BxdfFlags(2 | 16);
    /// Both specular lobes of a smooth dielectric.
    pub const SPECULAR_BOTH: BxdfFlags = BxdfFlags(1 | 2 | 16);
    /// Every flag except specular (what MIS light sampling evaluates).
    pub const NON_SPECULAR: BxdfFlags = BxdfFlags(31 & !16);

    /// Whether any bit of `other` is set here.
    #[inline]
    pub fn intersects(self, other: BxdfFlags) -> bool {
        self.0 & other.0 != 0
    }

    /// Whether every bit of `other` is set here.
    #[inline]
    pub fn contains(self, other: BxdfFlags) -> bool {
        self.0 & other.0 == other.0
    }

    /// pbrt-v3's `MatchesFlags`: a lobe of type `self` takes part in a query for `flags` when all of its
    /// bits are requested.
    #[inline]
    pub fn matches(self, flags: BxdfFlags) -> bool {
        flags.contains(self)
    }
}

impl std::ops::BitOr for BxdfFlags {
    type Output = BxdfFlags;
    #[inline]
    fn bitor(self, rhs: BxdfFlags) -> BxdfFlags {
        BxdfFlags(self.0 | rhs.0)
    }
}

impl std::ops::BitAnd for BxdfFlags {
    type Output = BxdfFlags;
    #[inline]
    fn bitand(self, rhs: BxdfFlags) -> BxdfFlags {
        BxdfFlags(self.0 & rhs.0)
    }
}

/// A direction drawn from a lobe (local frame): the lobe's value, the direction, its density and what kind
/// of scattering it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BxdfSample {
    /// f(wo, wi).
    pub f: Spectrum,
    /// The sampled incident direction.
    pub wi: Vec3A,
    /// Its density (solid angle; for delta lobes the discrete probability).
    pub pdf: f32,
    /// The lobe type that produced it.
    pub sampled: BxdfFlags,
}

/// A direction drawn by a lobe that is not a delta distribution (local frame), before its value and density
/// are computed: [`Bxdf::complete`] turns it into the [`BxdfSample`] that [`Bxdf::sample_f`] returns. A
/// caller that only wants directions meeting something (a light, in `EstimateDirect`) looks at `wi` first
/// and skips the value and density of the directions it has no use for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drawn {
    /// The incident direction.
    pub wi: Vec3A,
    /// The microfacet normal it was reflected about (microfacet reflection, whose density is that of
    /// the sampled normal; zero for the other lobes).
    wh: Vec3A,
}

impl Drawn {
    /// A direction drawn without a microfacet normal.
    #[inline]
    pub(crate) fn new(wi: Vec3A) -> Drawn {
        Drawn { wi, wh: Vec3A::ZERO }
    }
}

/// One lobe of a BSDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bxdf {
    /// Ideal diffuse reflection.
    Lambertian(LambertianReflection),
    /// Ideal diffuse transmission.
    LambertianTransmission(LambertianTransmission),
    /// Rough diffuse reflection.
    OrenNayar(OrenNayar),
    /// Glossy reflection.
    MicrofacetReflection(MicrofacetReflection),
    /// Glossy transmission.
    MicrofacetTransmission(MicrofacetTransmission),
    /// Diffuse under a glossy coat.
    FresnelBlend(FresnelBlend),
    /// Mirror reflection.
    SpecularReflection(SpecularReflection),
    /// Perfect refraction.
    SpecularTransmission(SpecularTransmission),
    /// Smooth dielectric (both delta lobes).
    FresnelSpecular(FresnelSpecular),
}

impl Bxdf {
    /// What the lobe does.
    #[inline]
    pub fn flags(&self) -> BxdfFlags {
        match self {
            Bxdf::Lambertian(_) | Bxdf::OrenNayar(_) => BxdfFlags::DIFFUSE_REFLECTION,
            Bxdf::LambertianTransmission(_) => BxdfFlags::DIFFUSE_TRANSMISSION,
            Bxdf::MicrofacetReflection(_) | Bxdf::FresnelBlend(_) => BxdfFlags::GLOSSY_REFLECTION,
            Bxdf::MicrofacetTransmission(_) => BxdfFlags::GLOSSY_TRANSMISSION,
            Bxdf::SpecularReflection(_) => BxdfFlags::SPECULAR_REFLECTION,
            Bxdf::SpecularTransmission(_) => BxdfFlags::SPECULAR_TRANSMISSION,
            Bxdf::FresnelSpecular(_) => BxdfFlags::SPECULAR_BOTH,
        }
    }

    /// f(wo, wi) in the local frame (0 for delta lobes).
    ///
    /// The Lambertian lobe, by far the most common, is answered inline; the others are in a function of
    /// their own, so that a BSDF's loop over its lobes does not compute the half vector and the angles the
    /// glossy lobes need ahead of the match (the compiler hoisted them, and a Lambertian surface paid for
    /// them: 10 % of a path tracer's time on the Cornell box).
    #[inline]
    pub fn f(&self, wo: Vec3A, wi: Vec3A) -> Spectrum {
        match self {
            Bxdf::Lambertian(b) => b.f(wo, wi),
            _ => self.f_other(wo, wi),
        }
    }

    #[inline(never)]
    fn f_other(&self, wo: Vec3A, wi: Vec3A) -> Spectrum {
        match self {
            Bxdf::Lambertian(b) => b.f(wo, wi),
            Bxdf::LambertianTransmission(b) => b.f(wo, wi),
            Bxdf::OrenNayar(b) => b.f(wo, wi),
            Bxdf::MicrofacetReflection(b) => b.f(wo, wi),
            Bxdf::MicrofacetTransmission(b) => b.f(wo, wi),
            Bxdf::FresnelBlend(b) => b.f(wo, wi),
            Bxdf::SpecularReflection(_) | Bxdf::SpecularTransmission(_) | Bxdf::FresnelSpecular(_) => Spectrum::ZERO,
        }
    }

    /// Draws wi for `wo` from `u` ∈ [0,1)²; `None` when the lobe produces nothing (pdf 0).
    #[inline]
    pub fn sample_f(&self, wo: Vec3A, u: [f32; 2]) -> Option<BxdfSample> {
        match self {
            Bxdf::SpecularReflection(b) => b.sample_f(wo, u),
            Bxdf::SpecularTransmission(b) => b.sample_f(wo, u),
            Bxdf::FresnelSpecular(b) => b.sample_f(wo, u),
            _ => self.complete(wo, self.draw(wo, u)?),
        }
    }

    /// The direction [`Bxdf::sample_f`] draws for `wo` from `u`, without its value and density (`None` when
    /// the lobe draws nothing, and always for the delta lobes, which only [`Bxdf::sample_f`] samples).
    #[inline]
    pub fn draw(&self, wo: Vec3A, u: [f32; 2]) -> Option<Drawn> {
        match self {
            Bxdf::Lambertian(_) | Bxdf::OrenNayar(_) => Some(Drawn::new(lambert::cosine_sample(wo, u, true).0)),
            Bxdf::LambertianTransmission(_) => Some(Drawn::new(lambert::cosine_sample(wo, u, false).0)),
            Bxdf::MicrofacetReflection(b) => b.draw(wo, u),
            Bxdf::MicrofacetTransmission(b) => b.draw(wo, u),
            Bxdf::FresnelBlend(b) => b.draw(wo, u),
            Bxdf::SpecularReflection(_) | Bxdf::SpecularTransmission(_) | Bxdf::FresnelSpecular(_) => None,
        }
    }

    /// The sample [`Bxdf::sample_f`] returns for the direction `d` that [`Bxdf::draw`] drew for `wo`: its
    /// value and density (`None` when the density is 0).
    #[inline]
    pub fn complete(&self, wo: Vec3A, d: Drawn) -> Option<BxdfSample> {
        let (pdf, sampled) = match self {
            Bxdf::Lambertian(_) | Bxdf::OrenNayar(_) => (lambert::cosine_pdf(wo, d.wi), BxdfFlags::DIFFUSE_REFLECTION),
            Bxdf::LambertianTransmission(b) => (b.pdf(wo, d.wi), BxdfFlags::DIFFUSE_TRANSMISSION),
            Bxdf::MicrofacetReflection(b) => (b.distribution.reflected_pdf(wo, d.wh), BxdfFlags::GLOSSY_REFLECTION),
            Bxdf::MicrofacetTransmission(b) => (b.pdf(wo, d.wi), BxdfFlags::GLOSSY_TRANSMISSION),
            Bxdf::FresnelBlend(b) => (b.pdf(wo, d.wi), BxdfFlags::GLOSSY_REFLECTION),
            Bxdf::SpecularReflection(_) | Bxdf::SpecularTransmission(_) | Bxdf::FresnelSpecular(_) => return None,
        };
        (pdf > 0.0).then(|| BxdfSample { f: self.f(wo, d.wi), wi: d.wi, pdf, sampled })
    }

    /// Density of [`Bxdf::sample_f`] producing `wi` (0 for delta lobes).
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        match self {
            Bxdf::Lambertian(_) | Bxdf::OrenNayar(_) => lambert::cosine_pdf(wo, wi),
            _ => self.pdf_other(wo, wi),
        }
    }

    /// [`Bxdf::pdf`] of the lobes that are not cosine-sampled (kept out of line for the reason given at
    /// [`Bxdf::f`]).
    #[inline(never)]
    fn pdf_other(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        match self {
            Bxdf::Lambertian(_) | Bxdf::OrenNayar(_) => lambert::cosine_pdf(wo, wi),
            Bxdf::LambertianTransmission(b) => b.pdf(wo, wi),
            Bxdf::MicrofacetReflection(b) => b.pdf(wo, wi),
            Bxdf::MicrofacetTransmission(b) => b.pdf(wo, wi),
            Bxdf::FresnelBlend(b) => b.pdf(wo, wi),
            Bxdf::SpecularReflection(_) | Bxdf::SpecularTransmission(_) | Bxdf::FresnelSpecular(_) => 0.0,
        }
    }

    /// pbrt-v3's `BxDF::rho(w, …)`: hemispherical-directional reflectance from the given sample points
    /// (exact for the Lambertian lobes, which return their albedo; 0 for `wo` in the surface plane, where
    /// pbrt-v3 would produce NaN).
    pub fn rho_hd(&self, wo: Vec3A, u: &[[f32; 2]]) -> Spectrum {
        match self {
            Bxdf::Lambertian(b) => return b.r,
            Bxdf::LambertianTransmission(b) => return b.t,
            _ => {}
        }
        if u.is_empty() || wo.z == 0.0 {
            return Spectrum::ZERO;
        }
        let mut r = Spectrum::ZERO;
        for &ui in u {
            if let Some(s) = self.sample_f(wo, ui) {
                let v = s.f * local::abs_cos_theta(s.wi) / s.pdf;
                // A direction exactly in the surface plane has f = ∞ and cos = 0 for delta lobes; skip it.
                if v.is_finite() {
                    r += v;
                }
            }
        }
        r / u.len() as f32
    }
}
