//! STAGE 5 (shading): pbrt-v3's `LambertianReflection` and `LambertianTransmission` — constant BSDFs R/π
//! on the outgoing side and T/π on the opposite side, cosine-sampled.
//!
//! Local shading frame; depends on [`super`]'s sample type and the cosine warp.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3A;

use super::local::{abs_cos_theta, same_hemisphere};
use crate::sampling::warp::cosine_hemisphere;
use crate::shading::Spectrum;

/// Cosine-weighted direction on `wo`'s side (`same_side`) or the other side, with its density (pbrt-v3's
/// default `BxDF::Sample_f` / `LambertianTransmission::Sample_f`).
#[inline]
pub fn cosine_sample(wo: Vec3A, u: [f32; 2], same_side: bool) -> (Vec3A, f32) {
    let mut wi = cosine_hemisphere(u);
    if (wo.z < 0.0) == same_side {
        wi.z = -wi.z;
    }
    (wi, abs_cos_theta(wi) * FRAC_1_PI)
}

/// Density of [`cosine_sample`] on `wo`'s side.
#[inline]
pub fn cosine_pdf(wo: Vec3A, wi: Vec3A) -> f32 {
    if same_hemisphere(wo, wi) { abs_cos_theta(wi) * FRAC_1_PI } else { 0.0 }
}

/// Ideal diffuse reflection with albedo `r`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LambertianReflection {
    /// Albedo.
    pub r: Spectrum,
}

impl LambertianReflection {
    /// R/π (the hemisphere test is the BSDF's, by the geometric normal).
    #[inline]
    pub fn f(&self, _wo: Vec3A, _wi: Vec3A) -> Spectrum {
        self.r * FRAC_1_PI
    }
}

/// Ideal diffuse transmission with transmittance `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LambertianTransmission {
    /// Transmittance.
    pub t: Spectrum,
}

impl LambertianTransmission {
    /// T/π.
    #[inline]
    pub fn f(&self, _wo: Vec3A, _wi: Vec3A) -> Spectrum {
        self.t * FRAC_1_PI
    }

    /// Cosine density on the side opposite `wo`.
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if same_hemisphere(wo, wi) { 0.0 } else { abs_cos_theta(wi) * FRAC_1_PI }
    }
}
