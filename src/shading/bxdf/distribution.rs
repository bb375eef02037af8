//! STAGE 5 (shading): the Trowbridge–Reitz (GGX) microfacet distribution of pbrt-v3 (microfacet.{h,cpp}):
//! D, Smith's Λ, G1 and G, `RoughnessToAlpha`, and sampling of the visible normals (pbrt-v3's
//! `sampleVisibleArea = true` path: Heitz and d'Eon's slope sampling with pbrt-v3's fitted inverse).
//!
//! Works in the local shading frame; depends only on [`super::local`].

use std::f32::consts::PI;

use glam::Vec3A;

use super::local::{abs_cos_theta, cos_phi, cos_theta, cos2_phi, cos2_theta, sin_phi, sin2_phi, tan_theta, tan2_theta};

/// pbrt-v3's `TrowbridgeReitzDistribution::RoughnessToAlpha`: a user roughness in [0, 1] to α (roughness
/// below 10⁻³ is taken as 10⁻³; a NaN gives α for 10⁻³).
#[inline]
pub fn roughness_to_alpha(roughness: f32) -> f32 {
    let r = if roughness.is_nan() { 1e-3 } else { roughness.max(1e-3) };
    let x = r.ln();
    1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x + 0.000640711 * x * x * x * x
}

/// An anisotropic Trowbridge–Reitz distribution of microfacet normals, α ≥ 10⁻³ along each tangent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrowbridgeReitz {
    /// α along the first tangent (s).
    pub alpha_x: f32,
    /// α along the second tangent (t).
    pub alpha_y: f32,
}

impl TrowbridgeReitz {
    /// A distribution with widths α_x, α_y (each raised to at least 10⁻³, as pbrt-v3 does; NaN → 10⁻³).
    pub fn new(alpha_x: f32, alpha_y: f32) -> Self {
        let fix = |a: f32| if a.is_nan() { 1e-3 } else { a.max(1e-3) };
        TrowbridgeReitz { alpha_x: fix(alpha_x), alpha_y: fix(alpha_y) }
    }

    /// Differential area of microfacets with normal `wh` (per unit projected area).
    #[inline]
    pub fn d(&self, wh: Vec3A) -> f32 {
        let tan2 = tan2_theta(wh);
        if tan2.is_infinite() || tan2.is_nan() {
            return 0.0;
        }
        let cos4 = cos2_theta(wh) * cos2_theta(wh);
        let e = (cos2_phi(wh) / (self.alpha_x * self.alpha_x) + sin2_phi(wh) / (self.alpha_y * self.alpha_y)) * tan2;
        1.0 / (PI * self.alpha_x * self.alpha_y * cos4 * (1.0 + e) * (1.0 + e))
    }

    /// Smith's auxiliary function Λ(w).
    #[inline]
    pub fn lambda(&self, w: Vec3A) -> f32 {
        let abs_tan = tan_theta(w).abs();
        if abs_tan.is_infinite() || abs_tan.is_nan() {
            return 0.0;
        }
        let alpha = (cos2_phi(w) * self.alpha_x * self.alpha_x + sin2_phi(w) * self.alpha_y * self.alpha_y).sqrt();
        let a2t2 = (alpha * abs_tan) * (alpha * abs_tan);
        (-1.0 + (1.0 + a2t2).sqrt()) / 2.0
    }

    /// Masking G1(w).
    #[inline]
    pub fn g1(&self, w: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing G(wo, wi).
    #[inline]
    pub fn g(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// A microfacet normal visible from `wo`, on `wo`'s side of the surface.
    pub fn sample_wh(&self, wo: Vec3A, u: [f32; 2]) -> Vec3A {
        let flip = wo.z < 0.0;
        let wh = self.sample_visible(if flip { -wo } else { wo }, u);
        if flip { -wh } else { wh }
    }

    /// Density of [`TrowbridgeReitz::sample_wh`] with respect to solid angle of `wh`: D·G1(wo)·|wo·wh|/|cos θo|.
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wh: Vec3A) -> f32 {
        self.d(wh) * self.g1(wo) * wo.dot(wh).abs() / abs_cos_theta(wo)
    }

    /// [`TrowbridgeReitz::sample_wh`] as the microfacet lobes use it: `None` for `wo` in the surface plane
    /// or a normal facing away from `wo` (pbrt-v3 returns no sample then).
    #[inline]
    pub fn sample_facing_wh(&self, wo: Vec3A, u: [f32; 2]) -> Option<Vec3A> {
        if wo.z == 0.0 {
            return None;
        }
        let wh = self.sample_wh(wo, u);
        (wo.dot(wh) >= 0.0).then_some(wh)
    }

    /// Density of wi = reflect(wo, wh) when `wh` comes from [`TrowbridgeReitz::sample_wh`]: pdf(wo, wh) /
    /// (4 wo·wh), the reflection Jacobian.
    #[inline]
    pub fn reflected_pdf(&self, wo: Vec3A, wh: Vec3A) -> f32 {
        self.pdf(wo, wh) / (4.0 * wo.dot(wh))
    }

    /// Stretch, sample the slopes of the unit distribution, rotate and unstretch (wi in the upper hemisphere).
    fn sample_visible(&self, wi: Vec3A, u: [f32; 2]) -> Vec3A {
        let stretched = Vec3A::new(self.alpha_x * wi.x, self.alpha_y * wi.y, wi.z).normalize();
        let (sx, sy) = sample_slopes(cos_theta(stretched), u[0], u[1]);
        let (c, s) = (cos_phi(stretched), sin_phi(stretched));
        let rx = c * sx - s * sy;
        let ry = s * sx + c * sy;
        Vec3A::new(-self.alpha_x * rx, -self.alpha_y * ry, 1.0).normalize()
    }
}

/// Slopes of a visible normal of the unit-α distribution seen at cos θ (pbrt-v3's `TrowbridgeReitzSample11`,
/// including its rational fit for the second slope).
fn sample_slopes(cos_theta: f32, u1: f32, u2: f32) -> (f32, f32) {
    if cos_theta > 0.9999 {
        let r = (u1 / (1.0 - u1)).sqrt();
        let phi = 2.0 * PI * u2;
        return (r * phi.cos(), r * phi.sin());
    }
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let tan_theta = sin_theta / cos_theta;
    let a = 1.0 / tan_theta;
    let g1 = 2.0 / (1.0 + (1.0 + 1.0 / (a * a)).sqrt());
    let aa = 2.0 * u1 / g1 - 1.0;
    let tmp = (1.0 / (aa * aa - 1.0)).min(1e10);
    let b = tan_theta;
    let d = (b * b * tmp * tmp - (aa * aa - b * b) * tmp).max(0.0).sqrt();
    let x1 = b * tmp - d;
    let x2 = b * tmp + d;
    let slope_x = if aa < 0.0 || x2 > 1.0 / tan_theta { x1 } else { x2 };
    let (s, u2) = if u2 > 0.5 { (1.0, 2.0 * (u2 - 0.5)) } else { (-1.0, 2.0 * (0.5 - u2)) };
    let z =
        (u2 * (u2 * (u2 * 0.27385 - 0.73369) + 0.46341)) / (u2 * (u2 * (u2 * 0.093073 + 0.309420) - 1.0) + 0.597999);
    (slope_x, s * z * (1.0 + slope_x * slope_x).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ D(wh) cos θh dωh = 1 (projected microfacet area equals the macro-surface), by a fine midpoint rule.
    #[test]
    fn projected_area_is_one() {
        for (ax, ay) in [(0.05f32, 0.05f32), (0.3, 0.3), (0.8, 0.2)] {
            let dist = TrowbridgeReitz::new(ax, ay);
            let (nt, np) = (4000, 256);
            let mut sum = 0.0f64;
            for i in 0..nt {
                // Integrate in cos θ: uniform steps in z.
                let z = (i as f64 + 0.5) / nt as f64;
                let s = (1.0 - z * z).sqrt();
                for j in 0..np {
                    let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / np as f64;
                    let wh = Vec3A::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32);
                    sum += dist.d(wh) as f64 * z;
                }
            }
            let integral = sum * (1.0 / nt as f64) * (2.0 * std::f64::consts::PI / np as f64);
            assert!((integral - 1.0).abs() < 0.01, "α = ({ax}, {ay}): ∫D cos = {integral}");
        }
    }

    #[test]
    fn roughness_to_alpha_matches_pbrt_v3_values() {
        // pbrt-v3's polynomial evaluated by hand at r = 1 (x = 0) and r = 0.1 (x = −2.302585).
        assert!((roughness_to_alpha(1.0) - 1.62142).abs() < 1e-5);
        assert!((roughness_to_alpha(0.1) - 0.46176).abs() < 1e-3);
        assert_eq!(roughness_to_alpha(-1.0), roughness_to_alpha(1e-3));
        assert!(roughness_to_alpha(f32::NAN).is_finite());
    }
}
