//! STAGE 5 (shading): pbrt-v3's `BSDF` — up to eight lobes in the shading frame of one surface point, with
//! world-space queries (f, sample_f, pdf, ρ_hd) and the geometric-normal test that decides whether a pair
//! of directions is reflection or transmission.
//!
//! Fixed-size storage (no allocation per hit). Each lobe carries a scale (pbrt-v3's `ScaledBxDF`, used by
//! `mix`). Depends on [`super::bxdf`] and `sampling::Frame`; knows nothing of materials or textures.

use glam::Vec3A;

use super::Spectrum;
use super::bxdf::fresnel_blend::ONE_MINUS_EPSILON;
use super::bxdf::{Bxdf, BxdfFlags, LambertianReflection};
use crate::sampling::Frame;

/// pbrt-v3's `BSDF::MaxBxDFs`.
pub const MAX_LOBES: usize = 8;

/// A direction drawn from a BSDF (world space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// f(wo, wi) summed over the matching lobes (for a delta lobe: that lobe's value).
    pub f: Spectrum,
    /// The incident direction, unit length, world space.
    pub wi: Vec3A,
    /// Its density, averaged over the matching lobes as pbrt-v3 does (> 0).
    pub pdf: f32,
    /// The type of the lobe that was sampled.
    pub sampled: BxdfFlags,
}

/// The scattering at one surface point: lobes in a shading frame. Only the first `n` lobe slots are live
/// (a [`Bsdf::reset`] leaves the old ones in place), so equality compares those.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    /// Relative index of refraction across the surface (1 for opaque materials).
    pub eta: f32,
    ns: Vec3A,
    ng: Vec3A,
    ss: Vec3A,
    ts: Vec3A,
    n: usize,
    lobes: [Bxdf; MAX_LOBES],
    scales: [Spectrum; MAX_LOBES],
}

impl PartialEq for Bsdf {
    fn eq(&self, o: &Bsdf) -> bool {
        (self.eta, self.ns, self.ng, self.ss, self.ts, self.n) == (o.eta, o.ns, o.ng, o.ss, o.ts, o.n)
            && self.lobes[..self.n] == o.lobes[..o.n]
            && self.scales[..self.n] == o.scales[..o.n]
    }
}

const EMPTY: Bxdf = Bxdf::Lambertian(LambertianReflection { r: Spectrum::ZERO });

impl Bsdf {
    /// An empty BSDF at a point with geometric normal `ng`, shading normal `ns` (unit, same side) and
    /// ∂p/∂u `dpdu`: the frame is s = `dpdu` made orthogonal to `ns` and normalised (any tangent when that
    /// is degenerate), t = ns × s.
    pub fn new(ng: Vec3A, ns: Vec3A, dpdu: Vec3A, eta: f32) -> Self {
        let mut b = Bsdf {
            eta,
            ns,
            ng,
            ss: Vec3A::X,
            ts: Vec3A::Y,
            n: 0,
            lobes: [EMPTY; MAX_LOBES],
            scales: [Spectrum::ONE; MAX_LOBES],
        };
        b.reset(ng, ns, dpdu, eta);
        b
    }

    /// Makes this an empty BSDF at another point, exactly as [`Bsdf::new`] would, without rewriting the
    /// lobe storage: a path keeps one `Bsdf` and refills it at every vertex instead of building and moving
    /// an 848-byte value per hit (those copies were 6–7 % of a path tracer's time).
    #[inline]
    pub fn reset(&mut self, ng: Vec3A, ns: Vec3A, dpdu: Vec3A, eta: f32) {
        let tangent = dpdu - ns * ns.dot(dpdu);
        let len = tangent.length();
        let ss = if len > 1e-12 && len.is_finite() { tangent / len } else { Frame::from_normal(ns).s };
        (self.eta, self.ns, self.ng, self.ss, self.ts, self.n) = (eta, ns, ng, ss, ns.cross(ss), 0);
    }

    /// Adds a lobe with scale `scale`; returns false (and adds nothing) when all eight slots are taken.
    pub fn add_scaled(&mut self, b: Bxdf, scale: Spectrum) -> bool {
        if self.n == MAX_LOBES {
            return false;
        }
        self.lobes[self.n] = b;
        self.scales[self.n] = scale;
        self.n += 1;
        true
    }

    /// Adds a lobe at full weight; false when full.
    pub fn add(&mut self, b: Bxdf) -> bool {
        self.add_scaled(b, Spectrum::ONE)
    }

    /// Multiplies every lobe's scale by `s` (pbrt-v3's mix wraps each lobe in a `ScaledBxDF`).
    pub fn scale_all(&mut self, s: Spectrum) {
        for x in &mut self.scales[..self.n] {
            *x *= s;
        }
    }

    /// The lobes with their scales.
    pub fn lobes(&self) -> impl Iterator<Item = (&Bxdf, Spectrum)> {
        self.lobes[..self.n].iter().zip(self.scales[..self.n].iter().copied())
    }

    /// The shading normal.
    pub fn shading_normal(&self) -> Vec3A {
        self.ns
    }

    /// The geometric normal.
    pub fn geometric_normal(&self) -> Vec3A {
        self.ng
    }

    /// World → shading frame.
    #[inline]
    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.ss), v.dot(self.ts), v.dot(self.ns))
    }

    /// Shading frame → world.
    #[inline]
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.ss * v.x + self.ts * v.y + self.ns * v.z
    }

    /// Whether a lobe transmits (scatters to the side opposite the outgoing direction).
    #[inline]
    pub fn has_transmission(&self) -> bool {
        self.lobes[..self.n].iter().any(|b| b.flags().intersects(BxdfFlags::TRANSMISSION))
    }

    /// How many lobes match `flags`.
    pub fn num_components(&self, flags: BxdfFlags) -> usize {
        self.lobes[..self.n].iter().filter(|b| b.flags().matches(flags)).count()
    }

    /// f(wo, wi) over the lobes matching `flags`; reflection lobes when wo and wi are on the same side of the
    /// geometric normal, transmission lobes otherwise.
    pub fn f(&self, wo: Vec3A, wi: Vec3A, flags: BxdfFlags) -> Spectrum {
        let (wo_l, wi_l) = (self.to_local(wo), self.to_local(wi));
        if wo_l.z == 0.0 {
            return Spectrum::ZERO;
        }
        let reflect = wi.dot(self.ng) * wo.dot(self.ng) > 0.0;
        self.f_local(wo_l, wi_l, reflect, flags)
    }

    fn f_local(&self, wo: Vec3A, wi: Vec3A, reflect: bool, flags: BxdfFlags) -> Spectrum {
        let side = if reflect { BxdfFlags::REFLECTION } else { BxdfFlags::TRANSMISSION };
        let mut f = Spectrum::ZERO;
        for (b, s) in self.lobes() {
            let t = b.flags();
            if t.matches(flags) && t.intersects(side) {
                f += s * b.f(wo, wi);
            }
        }
        f
    }

    /// pbrt-v3's `BSDF::Sample_f`: picks one matching lobe with `u[0]` (then remapped to [0,1)), samples it,
    /// and for a non-delta lobe returns f and the pdf over all matching lobes. `None` when nothing matches or
    /// the lobe produced no direction. The returned f may still be black.
    #[inline]
    pub fn sample_f(&self, wo: Vec3A, u: [f32; 2], flags: BxdfFlags) -> Option<BsdfSample> {
        self.sample_f_toward(wo, u, flags, |_| Some(())).map(|(s, ())| s)
    }

    /// [`Bsdf::sample_f`] for a caller that only wants directions `keep` accepts (returning what it found
    /// there): a direction it refuses gives `None`, and a non-delta lobe's direction is shown to `keep`
    /// before f and the pdf are computed, so the refused ones cost only the drawing. The samples that come
    /// back are exactly those of `sample_f`.
    #[inline]
    pub fn sample_f_toward<T>(
        &self,
        wo: Vec3A,
        u: [f32; 2],
        flags: BxdfFlags,
        keep: impl FnOnce(Vec3A) -> Option<T>,
    ) -> Option<(BsdfSample, T)> {
        let matching = self.num_components(flags);
        if matching == 0 {
            return None;
        }
        let comp = ((u[0] * matching as f32).floor() as usize).min(matching - 1);
        let (idx, lobe) =
            self.lobes[..self.n].iter().enumerate().filter(|(_, b)| b.flags().matches(flags)).nth(comp)?;
        let u_remapped = [(u[0] * matching as f32 - comp as f32).min(ONE_MINUS_EPSILON), u[1]];
        let wo_l = self.to_local(wo);
        if wo_l.z == 0.0 {
            return None;
        }
        let specular = lobe.flags().intersects(BxdfFlags::SPECULAR);
        let (s, wi, kept) = if specular {
            let s = lobe.sample_f(wo_l, u_remapped)?;
            let wi = self.to_world(s.wi);
            (s, wi, keep(wi)?)
        } else {
            let d = lobe.draw(wo_l, u_remapped)?;
            let wi = self.to_world(d.wi);
            let kept = keep(wi)?;
            (lobe.complete(wo_l, d)?, wi, kept)
        };
        if s.pdf.is_nan() || s.pdf <= 0.0 {
            return None;
        }
        let mut pdf = s.pdf;
        let mut f = self.scales[idx] * s.f;
        if !specular && matching > 1 {
            for (j, b) in self.lobes[..self.n].iter().enumerate() {
                if j != idx && b.flags().matches(flags) {
                    pdf += b.pdf(wo_l, s.wi);
                }
            }
        }
        if matching > 1 {
            pdf /= matching as f32;
        }
        if !specular {
            let reflect = wi.dot(self.ng) * wo.dot(self.ng) > 0.0;
            if matching == 1 {
                // f_local over the one matching lobe: the lobe's own value (its sample_f returns f(wo, wi)),
                // or 0 when the geometric normal puts wi on the side the lobe does not scatter to.
                let side = if reflect { BxdfFlags::REFLECTION } else { BxdfFlags::TRANSMISSION };
                if !lobe.flags().intersects(side) {
                    f = Spectrum::ZERO;
                }
            } else {
                f = self.f_local(wo_l, s.wi, reflect, flags);
            }
        }
        Some((BsdfSample { f, wi, pdf, sampled: s.sampled }, kept))
    }

    /// Density of [`Bsdf::sample_f`] producing `wi`: the mean of the matching lobes' densities (delta lobes
    /// count as 0).
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A, flags: BxdfFlags) -> f32 {
        let (wo_l, wi_l) = (self.to_local(wo), self.to_local(wi));
        if self.n == 0 || wo_l.z == 0.0 {
            return 0.0;
        }
        let mut pdf = 0.0;
        let mut matching = 0;
        for b in &self.lobes[..self.n] {
            if b.flags().matches(flags) {
                matching += 1;
                pdf += b.pdf(wo_l, wi_l);
            }
        }
        if matching > 0 { pdf / matching as f32 } else { 0.0 }
    }

    /// pbrt-v3's `BSDF::rho(wo, …)` over all lobes: hemispherical-directional reflectance (reflection plus
    /// transmission) estimated from the sample points `u` (exact for Lambertian lobes).
    pub fn rho_hd(&self, wo: Vec3A, u: &[[f32; 2]]) -> Spectrum {
        let wo_l = self.to_local(wo);
        self.lobes().map(|(b, s)| s * b.rho_hd(wo_l, u)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reset_bsdf_equals_a_new_one_whatever_its_old_lobes() {
        let (ng, dpdu) = (Vec3A::Z, Vec3A::X);
        let mut used = Bsdf::new(ng, ng, dpdu, 1.0);
        used.add(Bxdf::Lambertian(LambertianReflection { r: Spectrum::splat(0.5) }));
        used.add_scaled(Bxdf::Lambertian(LambertianReflection { r: Spectrum::ONE }), Spectrum::splat(0.25));
        used.reset(ng, ng, dpdu, 1.5);
        assert_eq!(used, Bsdf::new(ng, ng, dpdu, 1.5));
        assert_eq!(used.lobes().count(), 0);
        let lobe = Bxdf::Lambertian(LambertianReflection { r: Spectrum::splat(0.2) });
        let (mut a, mut b) = (used, Bsdf::new(ng, ng, dpdu, 1.5));
        a.add(lobe);
        b.add(lobe);
        assert_eq!(a, b);
        let wo = Vec3A::new(0.3, 0.1, 0.9).normalize();
        let wi = Vec3A::new(-0.2, 0.4, 0.8).normalize();
        assert_eq!(a.f(wo, wi, BxdfFlags::ALL), b.f(wo, wi, BxdfFlags::ALL));
    }
}
