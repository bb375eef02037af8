//! STAGE 5 (shading): pbrt-v3's `MicrofacetReflection` and `MicrofacetTransmission` (Torrance–Sparrow with
//! a Trowbridge–Reitz distribution, sampled through its visible normals), for radiance transport.
//!
//! Local shading frame; depends on [`super::distribution`], [`super::fresnel`] and [`super::local`].

use glam::Vec3A;

use super::Drawn;
use super::distribution::TrowbridgeReitz;
use super::fresnel::{Fresnel, fr_dielectric};
use super::local::{abs_cos_theta, cos_theta, face_forward, reflect, refract, same_hemisphere};
use crate::shading::Spectrum;

/// Glossy reflection: R·D·G·F / (4 cos θo cos θi).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MicrofacetReflection {
    /// Tint.
    pub r: Spectrum,
    /// Microfacet normals.
    pub distribution: TrowbridgeReitz,
    /// Fresnel term.
    pub fresnel: Fresnel,
}

impl MicrofacetReflection {
    /// The BSDF value.
    #[inline]
    pub fn f(&self, wo: Vec3A, wi: Vec3A) -> Spectrum {
        let (cos_o, cos_i) = (abs_cos_theta(wo), abs_cos_theta(wi));
        let wh = wi + wo;
        if cos_i == 0.0 || cos_o == 0.0 || wh == Vec3A::ZERO {
            return Spectrum::ZERO;
        }
        let wh = wh.normalize();
        let f = self.fresnel.evaluate(wi.dot(face_forward(wh, Vec3A::Z)));
        self.r * self.distribution.d(wh) * self.distribution.g(wo, wi) * f / (4.0 * cos_i * cos_o)
    }

    /// A direction reflected about a visible microfacet normal (its density is that normal's, see
    /// [`Bxdf::complete`](super::Bxdf::complete)).
    #[inline]
    pub fn draw(&self, wo: Vec3A, u: [f32; 2]) -> Option<Drawn> {
        let wh = self.distribution.sample_facing_wh(wo, u)?;
        let wi = reflect(wo, wh);
        same_hemisphere(wo, wi).then_some(Drawn { wi, wh })
    }

    /// Density of `MicrofacetReflection`'s `sample_f`.
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if !same_hemisphere(wo, wi) {
            return 0.0;
        }
        let pdf = self.distribution.reflected_pdf(wo, (wo + wi).normalize());
        if pdf.is_finite() { pdf } else { 0.0 }
    }
}

/// Glossy transmission through a rough dielectric between `eta_a` (normal side) and `eta_b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MicrofacetTransmission {
    /// Tint.
    pub t: Spectrum,
    /// Microfacet normals.
    pub distribution: TrowbridgeReitz,
    /// Index on the side of the shading normal.
    pub eta_a: f32,
    /// Index on the other side.
    pub eta_b: f32,
}

impl MicrofacetTransmission {
    /// The BSDF value (Walter et al. 2007, radiance scaled by 1/η²).
    #[inline]
    pub fn f(&self, wo: Vec3A, wi: Vec3A) -> Spectrum {
        if same_hemisphere(wo, wi) {
            return Spectrum::ZERO;
        }
        let (cos_o, cos_i) = (cos_theta(wo), cos_theta(wi));
        if cos_i == 0.0 || cos_o == 0.0 {
            return Spectrum::ZERO;
        }
        let eta = if cos_o > 0.0 { self.eta_b / self.eta_a } else { self.eta_a / self.eta_b };
        let mut wh = (wo + wi * eta).normalize();
        if wh.z < 0.0 {
            wh = -wh;
        }
        if wo.dot(wh) * wi.dot(wh) > 0.0 {
            return Spectrum::ZERO;
        }
        let fr = fr_dielectric(wo.dot(wh), self.eta_a, self.eta_b);
        let denom = wo.dot(wh) + eta * wi.dot(wh);
        let factor = 1.0 / eta;
        let v = (self.distribution.d(wh)
            * self.distribution.g(wo, wi)
            * eta
            * eta
            * wi.dot(wh).abs()
            * wo.dot(wh).abs()
            * factor
            * factor
            / (cos_i * cos_o * denom * denom))
            .abs();
        if !v.is_finite() {
            return Spectrum::ZERO;
        }
        (1.0 - fr) * self.t * v
    }

    /// A direction refracted through a visible microfacet normal (`None` at total internal reflection).
    #[inline]
    pub fn draw(&self, wo: Vec3A, u: [f32; 2]) -> Option<Drawn> {
        let wh = self.distribution.sample_facing_wh(wo, u)?;
        let eta = if cos_theta(wo) > 0.0 { self.eta_a / self.eta_b } else { self.eta_b / self.eta_a };
        Some(Drawn::new(refract(wo, wh, eta)?))
    }

    /// Density of `MicrofacetTransmission`'s `sample_f`.
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if same_hemisphere(wo, wi) {
            return 0.0;
        }
        let eta = if cos_theta(wo) > 0.0 { self.eta_b / self.eta_a } else { self.eta_a / self.eta_b };
        let wh = (wo + wi * eta).normalize();
        if wo.dot(wh) * wi.dot(wh) > 0.0 {
            return 0.0;
        }
        let denom = wo.dot(wh) + eta * wi.dot(wh);
        let dwh_dwi = ((eta * eta * wi.dot(wh)) / (denom * denom)).abs();
        let pdf = self.distribution.pdf(wo, wh) * dwh_dwi;
        if pdf.is_finite() { pdf } else { 0.0 }
    }
}
