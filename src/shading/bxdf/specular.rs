//! STAGE 5 (shading): pbrt-v3's delta lobes — `SpecularReflection`, `SpecularTransmission` and
//! `FresnelSpecular` (both dielectric lobes in one, choosing by the Fresnel term) — for radiance transport.
//! Their f and pdf are 0 for every given pair of directions; only sampling finds the one direction.
//!
//! Local shading frame; depends on [`super::fresnel`] and [`super::local`].

use glam::Vec3A;

use super::fresnel::{Fresnel, fr_dielectric};
use super::local::{abs_cos_theta, cos_theta, face_forward, refract};
use super::{BxdfFlags, BxdfSample};
use crate::shading::Spectrum;

/// A perfect mirror direction with tint `r` and a Fresnel term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularReflection {
    /// Tint.
    pub r: Spectrum,
    /// Fresnel term.
    pub fresnel: Fresnel,
}

impl SpecularReflection {
    /// The mirror direction, f = F·R/|cos θi|, pdf 1.
    #[inline]
    pub fn sample_f(&self, wo: Vec3A, _u: [f32; 2]) -> Option<BxdfSample> {
        let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
        let f = self.fresnel.evaluate(cos_theta(wi)) * self.r / abs_cos_theta(wi);
        Some(BxdfSample { f, wi, pdf: 1.0, sampled: BxdfFlags::SPECULAR_REFLECTION })
    }
}

/// Which side's index is incident and which transmitted, and the normal on `wo`'s side.
#[inline]
fn refraction_setup(wo: Vec3A, eta_a: f32, eta_b: f32) -> (f32, f32) {
    if cos_theta(wo) > 0.0 { (eta_a, eta_b) } else { (eta_b, eta_a) }
}

/// Perfect refraction between `eta_a` (normal side) and `eta_b` with tint `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularTransmission {
    /// Tint.
    pub t: Spectrum,
    /// Index on the side of the shading normal.
    pub eta_a: f32,
    /// Index on the other side.
    pub eta_b: f32,
}

impl SpecularTransmission {
    /// The refracted direction, f = T·(1 − F)·(η_i/η_t)²/|cos θi|, pdf 1 (`None` at total internal reflection).
    #[inline]
    pub fn sample_f(&self, wo: Vec3A, _u: [f32; 2]) -> Option<BxdfSample> {
        let (ei, et) = refraction_setup(wo, self.eta_a, self.eta_b);
        let wi = refract(wo, face_forward(Vec3A::Z, wo), ei / et)?;
        let fr = fr_dielectric(cos_theta(wi), self.eta_a, self.eta_b);
        let f = self.t * (1.0 - fr) * (ei * ei) / (et * et) / abs_cos_theta(wi);
        Some(BxdfSample { f, wi, pdf: 1.0, sampled: BxdfFlags::SPECULAR_TRANSMISSION })
    }
}

/// A smooth dielectric with both delta lobes, reflection chosen with probability F (pbrt-v3's glass under
/// integrators that allow multiple lobes, such as `path`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FresnelSpecular {
    /// Reflection tint.
    pub r: Spectrum,
    /// Transmission tint.
    pub t: Spectrum,
    /// Index on the side of the shading normal.
    pub eta_a: f32,
    /// Index on the other side.
    pub eta_b: f32,
}

impl FresnelSpecular {
    /// Reflection with probability F, else refraction.
    #[inline]
    pub fn sample_f(&self, wo: Vec3A, u: [f32; 2]) -> Option<BxdfSample> {
        let fr = fr_dielectric(cos_theta(wo), self.eta_a, self.eta_b);
        if u[0] < fr {
            let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
            let f = fr * self.r / abs_cos_theta(wi);
            return Some(BxdfSample { f, wi, pdf: fr, sampled: BxdfFlags::SPECULAR_REFLECTION });
        }
        let (ei, et) = refraction_setup(wo, self.eta_a, self.eta_b);
        let wi = refract(wo, face_forward(Vec3A::Z, wo), ei / et)?;
        let f = self.t * (1.0 - fr) * (ei * ei) / (et * et) / abs_cos_theta(wi);
        let pdf = 1.0 - fr;
        (pdf > 0.0).then_some(BxdfSample { f, wi, pdf, sampled: BxdfFlags::SPECULAR_TRANSMISSION })
    }
}
