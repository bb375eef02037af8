//! STAGE 5 (shading): pbrt-v3's `OrenNayar` rough diffuse reflection (the qualitative model with A and B from
//! σ in degrees), cosine-sampled like every diffuse lobe.
//!
//! Local shading frame; depends on [`super::local`] and [`super::lambert`]'s cosine sampling.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3A;

use super::local::{abs_cos_theta, cos_phi, sin_phi, sin_theta};

use crate::shading::Spectrum;

/// Oren–Nayar reflection with albedo `r` and the model's A, B.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrenNayar {
    /// Albedo.
    pub r: Spectrum,
    /// The constant term.
    pub a: f32,
    /// The weight of the view-dependent term.
    pub b: f32,
}

impl OrenNayar {
    /// The lobe for albedo `r` and facet slope deviation `sigma_deg` (degrees).
    pub fn new(r: Spectrum, sigma_deg: f32) -> Self {
        let s = sigma_deg.to_radians();
        let s2 = s * s;
        OrenNayar { r, a: 1.0 - s2 / (2.0 * (s2 + 0.33)), b: 0.45 * s2 / (s2 + 0.09) }
    }

    /// The BSDF value.
    #[inline]
    pub fn f(&self, wo: Vec3A, wi: Vec3A) -> Spectrum {
        let (sin_i, sin_o) = (sin_theta(wi), sin_theta(wo));
        let mut max_cos = 0.0f32;
        if sin_i > 1e-4 && sin_o > 1e-4 {
            let d = cos_phi(wi) * cos_phi(wo) + sin_phi(wi) * sin_phi(wo);
            max_cos = d.max(0.0);
        }
        let (sin_alpha, tan_beta) = if abs_cos_theta(wi) > abs_cos_theta(wo) {
            (sin_o, sin_i / abs_cos_theta(wi))
        } else {
            (sin_i, sin_o / abs_cos_theta(wo))
        };
        self.r * FRAC_1_PI * (self.a + self.b * max_cos * sin_alpha * tan_beta)
    }
}
