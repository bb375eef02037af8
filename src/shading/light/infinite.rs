//! STAGE 5 (shading): pbrt-v3's `InfiniteAreaLight` — radiance from every direction, constant L·scale or an
//! environment map times L·scale in spherical coordinates of light space (θ from +z down the rows,
//! φ = atan2(y, x) across the columns), sampled from a piecewise-constant `Distribution2D` over a grid twice
//! the map's size weighted by sin θ, as pbrt-v3 does.
//!
//! Depends on the shading `Spectrum`, [`super::envmap`] and [`super::distribution`]; never on the scene.

use std::f32::consts::PI;

use glam::{Mat3A, Vec3A};

use super::distribution::Distribution2D;
use super::envmap::EnvMap;
use crate::shading::Spectrum;
use crate::shading::luminance;

/// An environment light.
#[derive(Clone, Debug, PartialEq)]
pub struct InfiniteLight {
    world_from_light: Mat3A,
    light_from_world: Mat3A,
    map: EnvMap,
    dist: Distribution2D,
    world_radius: f32,
}

/// pbrt-v3 `SphericalPhi` in [0, 2π).
#[inline]
fn spherical_phi(w: Vec3A) -> f32 {
    let p = w.y.atan2(w.x);
    if p < 0.0 { p + 2.0 * PI } else { p }
}

impl InfiniteLight {
    /// The light for `map` (already multiplied by L·scale), oriented by `world_from_light` (the CTM's
    /// linear part), in a world of bounding radius `world_radius`.
    pub fn new(map: EnvMap, world_from_light: Mat3A, world_radius: f32) -> Self {
        let (w, h) = (2 * map.width(), 2 * map.height());
        let mut img = vec![0.0f32; w * h];
        for v in 0..h {
            let vp = (v as f32 + 0.5) / h as f32;
            let sin_theta = (PI * (v as f32 + 0.5) / h as f32).sin();
            for u in 0..w {
                let up = (u as f32 + 0.5) / w as f32;
                img[u + v * w] = luminance(map.lookup([up, vp])) * sin_theta;
            }
        }
        let dist = Distribution2D::new(&img, w, h);
        InfiniteLight { world_from_light, light_from_world: world_from_light.inverse(), map, dist, world_radius }
    }

    /// The (s, t) map coordinates of world direction `d` (any length).
    #[inline]
    fn st(&self, d: Vec3A) -> Option<([f32; 2], f32)> {
        let w = (self.light_from_world * d).normalize_or_zero();
        if w == Vec3A::ZERO {
            return None;
        }
        let theta = w.z.clamp(-1.0, 1.0).acos();
        Some(([spherical_phi(w) / (2.0 * PI), theta / PI], theta.sin()))
    }

    /// Radiance arriving along −`d`, i.e. seen by a ray with direction `d` that escapes (pbrt-v3 `Le`).
    #[inline]
    pub fn le(&self, d: Vec3A) -> Spectrum {
        self.st(d).map_or(Spectrum::ZERO, |(st, _)| self.map.lookup(st))
    }

    /// A direction toward the light for sample `u`: (radiance, unit world direction, solid-angle pdf).
    #[inline]
    pub fn sample(&self, u: [f32; 2]) -> Option<(Spectrum, Vec3A, f32)> {
        let (uv, map_pdf) = self.dist.sample(u);
        if map_pdf == 0.0 {
            return None;
        }
        let (theta, phi) = (uv[1] * PI, uv[0] * 2.0 * PI);
        let (sin_t, cos_t) = theta.sin_cos();
        if sin_t == 0.0 {
            return None;
        }
        let (sin_p, cos_p) = phi.sin_cos();
        let wi = (self.world_from_light * Vec3A::new(sin_t * cos_p, sin_t * sin_p, cos_t)).normalize_or_zero();
        if wi == Vec3A::ZERO {
            return None;
        }
        let pdf = map_pdf / (2.0 * PI * PI * sin_t);
        Some((self.map.lookup(uv), wi, pdf))
    }

    /// The solid-angle pdf of [`InfiniteLight::sample`] for world direction `w`.
    #[inline]
    pub fn pdf(&self, w: Vec3A) -> f32 {
        match self.st(w) {
            Some((st, sin_t)) if sin_t > 0.0 => self.dist.pdf(st) / (2.0 * PI * PI * sin_t),
            _ => 0.0,
        }
    }

    /// pbrt-v3 `Power`: π r² times the map's mean.
    pub fn power(&self) -> Spectrum {
        PI * self.world_radius * self.world_radius * self.map.mean()
    }

    /// The map (resampled as pbrt-v3 does).
    pub fn map(&self) -> &EnvMap {
        &self.map
    }
}
