//! STAGE 5 (shading): pbrt-v3's `DistantLight` — radiance L·scale arriving from one direction
//! (`from − to` in light space), with the power of a disk the size of the scene's bounding sphere.
//!
//! Depends only on glam and the shading `Spectrum`.

use glam::Vec3A;

use crate::shading::Spectrum;

/// A directional light in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistantLight {
    /// Unit world direction toward the light.
    pub w: Vec3A,
    /// Radiance L·scale (the irradiance on a surface facing the light).
    pub l: Spectrum,
    /// Radius of the world's bounding sphere.
    pub world_radius: f32,
}

impl DistantLight {
    /// pbrt-v3 `Power`: L·π·r².
    pub fn power(&self) -> Spectrum {
        self.l * (std::f32::consts::PI * self.world_radius * self.world_radius)
    }
}
