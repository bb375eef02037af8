//! STAGE 5 (shading): pbrt-v3's `SpotLight` — a point light limited to a cone around from→to, with its
//! falloff: full intensity inside `coneangle − conedeltaangle`, zero outside `coneangle`, and the quartic
//! of the cosine ramp between them.
//!
//! Depends only on glam and the shading `Spectrum`.

use glam::{Mat3A, Vec3A};

use crate::shading::Spectrum;

/// A spot light in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotLight {
    /// World position (the CTM applied to `from`).
    pub p: Vec3A,
    /// Intensity I·scale on the axis.
    pub i: Spectrum,
    /// Light ← world for directions (the CTM's inverse linear part).
    pub light_from_world: Mat3A,
    /// Unit axis `to − from` in light space.
    pub axis: Vec3A,
    /// cos(coneangle).
    pub cos_total: f32,
    /// cos(coneangle − conedeltaangle).
    pub cos_falloff_start: f32,
}

impl SpotLight {
    /// pbrt-v3 `Falloff` for world direction `w` leaving the light.
    #[inline]
    pub fn falloff(&self, w: Vec3A) -> f32 {
        let wl = (self.light_from_world * w).normalize_or_zero();
        let cos = wl.dot(self.axis);
        if cos < self.cos_total {
            return 0.0;
        }
        if cos >= self.cos_falloff_start {
            return 1.0;
        }
        let delta = (cos - self.cos_total) / (self.cos_falloff_start - self.cos_total);
        (delta * delta) * (delta * delta)
    }

    /// Incident radiance at `p` and the unit direction toward the light; `None` at the light itself.
    #[inline]
    pub fn li(&self, p: Vec3A) -> Option<(Spectrum, Vec3A)> {
        let d = self.p - p;
        let d2 = d.length_squared();
        if d2 <= 0.0 {
            return None;
        }
        let wi = d / d2.sqrt();
        Some((self.i * (self.falloff(-wi) / d2), wi))
    }

    /// pbrt-v3 `Power`: I·2π·(1 − (cos_falloff_start + cos_total)/2).
    pub fn power(&self) -> Spectrum {
        self.i * (2.0 * std::f32::consts::PI * (1.0 - 0.5 * (self.cos_falloff_start + self.cos_total)))
    }
}
