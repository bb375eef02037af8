//! STAGE 5 (shading): what a surface does with light — textures evaluated at a hit, materials turned into
//! BSDFs (pbrt-v3's BxDFs), and the light sources' sampling — the layer the per-pixel integrators and the
//! cache applications shade with.
//!
//! Depends on `scene` (the stored materials, textures, lights and the surface interaction at a hit) and
//! `sampling`; never on `render`, `placement` or `application`.

pub mod bsdf;
pub mod bxdf;
pub mod light;
pub mod lighting;
pub mod material;
pub mod texture;

/// A linear RGB colour (pbrt-v3's `RGBSpectrum`; the film keeps RGB).
pub type Spectrum = glam::Vec3A;

/// pbrt-v3's `RGBSpectrum::y`: the luminance of a linear RGB colour.
#[inline]
pub fn luminance(c: Spectrum) -> f32 {
    0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z
}
