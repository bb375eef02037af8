//! STAGE 5 (shading): pbrt-v3's `PointLight` — intensity I·scale from one point, falling off as 1/d².
//!
//! Depends only on glam and the shading `Spectrum`; the dispatch in `light::mod` spawns its shadow ray.

use glam::Vec3A;

use crate::shading::Spectrum;

/// A point light in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// World position. pbrt-v3 adds `from` to the CTM's translation (its `Translate(from) * CTM`).
    pub p: Vec3A,
    /// Radiant intensity I·scale.
    pub i: Spectrum,
}

impl PointLight {
    /// Incident radiance at `p` and the unit direction toward the light; `None` at the light itself.
    #[inline]
    pub fn li(&self, p: Vec3A) -> Option<(Spectrum, Vec3A)> {
        let d = self.p - p;
        let d2 = d.length_squared();
        (d2 > 0.0).then(|| (self.i / d2, d / d2.sqrt()))
    }

    /// pbrt-v3 `Power`: 4π I.
    pub fn power(&self) -> Spectrum {
        4.0 * std::f32::consts::PI * self.i
    }
}
