//! STAGE 5 (shading): pbrt-v3's `FresnelBlend` (Ashikhmin–Shirley): a diffuse base under a glossy coat with
//! Schlick's Fresnel, sampled half by cosine and half by visible microfacet normals.
//!
//! Local shading frame; depends on [`super::distribution`], [`super::lambert`] and [`super::local`].

use std::f32::consts::PI;

use glam::Vec3A;

use super::Drawn;
use super::distribution::TrowbridgeReitz;
use super::lambert::cosine_sample;
use super::local::{abs_cos_theta, reflect, same_hemisphere};
use crate::shading::Spectrum;

/// The largest f32 below 1 (pbrt-v3's `OneMinusEpsilon`).
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Diffuse `rd` under a glossy layer of normal-incidence reflectance `rs`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FresnelBlend {
    /// Diffuse reflectance.
    pub rd: Spectrum,
    /// Specular reflectance at normal incidence.
    pub rs: Spectrum,
    /// Microfacet normals of the coat.
    pub distribution: TrowbridgeReitz,
}

impl FresnelBlend {
    /// Schlick's approximation Rs + (1 − cos)⁵ (1 − Rs).
    #[inline]
    fn schlick(&self, cos: f32) -> Spectrum {
        self.rs + pow5(1.0 - cos) * (Spectrum::ONE - self.rs)
    }

    /// The BSDF value.
    #[inline]
    pub fn f(&self, wo: Vec3A, wi: Vec3A) -> Spectrum {
        let diffuse = (28.0 / (23.0 * PI))
            * self.rd
            * (Spectrum::ONE - self.rs)
            * (1.0 - pow5(1.0 - 0.5 * abs_cos_theta(wi)))
            * (1.0 - pow5(1.0 - 0.5 * abs_cos_theta(wo)));
        let wh = wi + wo;
        if wh == Vec3A::ZERO {
            return Spectrum::ZERO;
        }
        let wh = wh.normalize();
        let spec = self.distribution.d(wh) / (4.0 * wi.dot(wh).abs() * abs_cos_theta(wi).max(abs_cos_theta(wo)))
            * self.schlick(wi.dot(wh));
        let v = diffuse + spec;
        if v.is_finite() { v } else { diffuse }
    }

    /// Half the samples cosine-distributed, half about visible microfacet normals.
    #[inline]
    pub fn draw(&self, wo: Vec3A, u: [f32; 2]) -> Option<Drawn> {
        let wi = if u[0] < 0.5 {
            cosine_sample(wo, [(2.0 * u[0]).min(ONE_MINUS_EPSILON), u[1]], true).0
        } else {
            let wh = self.distribution.sample_wh(wo, [(2.0 * (u[0] - 0.5)).min(ONE_MINUS_EPSILON), u[1]]);
            let wi = reflect(wo, wh);
            if !same_hemisphere(wo, wi) {
                return None;
            }
            wi
        };
        Some(Drawn::new(wi))
    }

    /// The average of the two sampling densities.
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if !same_hemisphere(wo, wi) {
            return 0.0;
        }
        let wh = (wo + wi).normalize();
        let pdf = 0.5 * (abs_cos_theta(wi) * std::f32::consts::FRAC_1_PI + self.distribution.reflected_pdf(wo, wh));
        if pdf.is_finite() { pdf } else { 0.0 }
    }
}

#[inline]
fn pow5(v: f32) -> f32 {
    (v * v) * (v * v) * v
}
