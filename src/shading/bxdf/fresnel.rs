//! STAGE 5 (shading): Fresnel reflectance — dielectric, conductor and the constant 1 — as pbrt-v3's
//! `FrDielectric`, `FrConductor`, `FresnelDielectric`, `FresnelConductor` and `FresnelNoOp`.
//!
//! Depends only on the `Spectrum` type.

use crate::shading::Spectrum;

/// Unpolarised Fresnel reflectance of a dielectric interface for incident cosine `cos_i` (negative: from
/// inside), outside index `eta_i`, inside index `eta_t`; 1 at total internal reflection.
#[inline]
pub fn fr_dielectric(cos_i: f32, eta_i: f32, eta_t: f32) -> f32 {
    let mut cos_i = cos_i.clamp(-1.0, 1.0);
    let (mut ei, mut et) = (eta_i, eta_t);
    if cos_i <= 0.0 {
        std::mem::swap(&mut ei, &mut et);
        cos_i = cos_i.abs();
    }
    let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
    let sin_t = ei / et * sin_i;
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
    let parl = (et * cos_i - ei * cos_t) / (et * cos_i + ei * cos_t);
    let perp = (ei * cos_i - et * cos_t) / (ei * cos_i + et * cos_t);
    (parl * parl + perp * perp) / 2.0
}

/// Fresnel reflectance of a conductor with relative complex index `eta` + i`k` (already divided by the
/// outside index) at incident cosine `cos_i`.
#[inline]
pub fn fr_conductor(cos_i: f32, eta: Spectrum, k: Spectrum) -> Spectrum {
    let c = cos_i.clamp(-1.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let eta2 = eta * eta;
    let k2 = k * k;
    let t0 = eta2 - k2 - Spectrum::splat(s2);
    let a2b2 = sqrt3(t0 * t0 + 4.0 * eta2 * k2);
    let t1 = a2b2 + Spectrum::splat(c2);
    let a = sqrt3(0.5 * (a2b2 + t0));
    let t2 = 2.0 * c * a;
    let rs = (t1 - t2) / (t1 + t2);
    let t3 = c2 * a2b2 + Spectrum::splat(s2 * s2);
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4);
    0.5 * (rp + rs)
}

/// Componentwise square root of a non-negative spectrum (negative rounding residue gives 0).
#[inline]
fn sqrt3(v: Spectrum) -> Spectrum {
    Spectrum::new(v.x.max(0.0).sqrt(), v.y.max(0.0).sqrt(), v.z.max(0.0).sqrt())
}

/// Which Fresnel term a reflection lobe uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fresnel {
    /// Always 1 (a perfect mirror).
    NoOp,
    /// A dielectric with outside index `eta_i` and inside index `eta_t`.
    Dielectric {
        /// Index on the side of the shading normal.
        eta_i: f32,
        /// Index on the other side.
        eta_t: f32,
    },
    /// A conductor with complex index `eta` + i`k`, relative to the outside medium.
    Conductor {
        /// Real part.
        eta: Spectrum,
        /// Absorption.
        k: Spectrum,
    },
}

impl Fresnel {
    /// Reflectance at incident cosine `cos_i` (pbrt-v3's `Fresnel::Evaluate`: the conductor uses |cos_i|).
    #[inline]
    pub fn evaluate(&self, cos_i: f32) -> Spectrum {
        match *self {
            Fresnel::NoOp => Spectrum::ONE,
            Fresnel::Dielectric { eta_i, eta_t } => Spectrum::splat(fr_dielectric(cos_i, eta_i, eta_t)),
            Fresnel::Conductor { eta, k } => fr_conductor(cos_i.abs(), eta, k),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_matches_the_closed_form() {
        for eta in [1.33f32, 1.5, 2.4] {
            let r0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
            assert!((fr_dielectric(1.0, 1.0, eta) - r0).abs() < 1e-6);
            assert!((fr_dielectric(-1.0, 1.0, eta) - r0).abs() < 1e-6, "from inside");
            // A conductor with k = 0 is a dielectric: ((η−1)/(η+1))².
            let c = fr_conductor(1.0, Spectrum::splat(eta), Spectrum::ZERO);
            assert!((c.x - r0).abs() < 1e-5);
        }
        // |η + ik − 1|² / |η + ik + 1|² for a conductor.
        let (n, k) = (0.2f32, 3.0f32);
        let expect = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        assert!((fr_conductor(1.0, Spectrum::splat(n), Spectrum::splat(k)).x - expect).abs() < 1e-5);
    }

    #[test]
    fn grazing_and_total_internal_reflection_give_one() {
        assert!((fr_dielectric(1e-6, 1.0, 1.5) - 1.0).abs() < 1e-4);
        let critical = (1.0f32 - (1.0 / 1.5f32).powi(2)).sqrt();
        assert_eq!(fr_dielectric(-(critical - 0.01), 1.0, 1.5), 1.0);
        assert!(fr_dielectric(-(critical + 0.01), 1.0, 1.5) < 1.0);
    }
}
