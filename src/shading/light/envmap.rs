//! STAGE 5 (shading): the texel grid of an environment map as pbrt-v3's `InfiniteAreaLight` keeps it — a
//! `MIPMap` level with repeat wrapping: resampled to power-of-two sides with pbrt-v3's Lanczos filter when
//! needed and looked up bilinearly at the finest level. It is the texture stage's [`MipMap`], so the
//! resampling and the lookup exist once.
//!
//! Depends on the shading `Spectrum` and `shading::texture::mipmap`; never on the scene or the renderer.

use crate::shading::Spectrum;
use crate::shading::texture::mipmap::{MipMap, Wrap};

/// A width×height grid of RGB texels, row 0 at the top (θ = 0).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMap {
    map: MipMap,
    mean: Spectrum,
}

impl EnvMap {
    /// A 1×1 map of constant `l`.
    pub fn constant(l: Spectrum) -> Self {
        EnvMap::new(1, 1, vec![l]).unwrap_or_else(|| unreachable!("a 1×1 map is valid"))
    }

    /// The map of `texels` (row-major, `width`×`height`), resampled to power-of-two sides as pbrt-v3 does;
    /// `None` for an empty map or a texel count that does not match.
    pub fn new(width: usize, height: usize, texels: Vec<Spectrum>) -> Option<Self> {
        let map = MipMap::new(width, height, texels.iter().map(|t| t.to_array()).collect(), Wrap::Repeat)?;
        let sum: glam::DVec3 = map.texels().iter().map(|t| glam::DVec3::from(t.map(f64::from))).sum();
        let m = sum / map.texels().len() as f64;
        Some(EnvMap { map, mean: Spectrum::new(m.x as f32, m.y as f32, m.z as f32) })
    }

    /// Number of columns (after resampling).
    pub fn width(&self) -> usize {
        self.map.size()[0]
    }

    /// Number of rows (after resampling).
    pub fn height(&self) -> usize {
        self.map.size()[1]
    }

    /// Bilinear lookup at (s, t) ∈ [0, 1]² with repeat wrapping (pbrt-v3 `MIPMap::triangle` at level 0).
    #[inline]
    pub fn lookup(&self, st: [f32; 2]) -> Spectrum {
        Spectrum::from(self.map.bilinear(st))
    }

    /// The mean texel (pbrt-v3's `Power` looks up the 1×1/2×1 MIP level, which is this mean).
    pub fn mean(&self) -> Spectrum {
        self.mean
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_lookup_hits_texel_centres_and_wraps() {
        let t = |v: f32| Spectrum::splat(v);
        let m = EnvMap::new(2, 2, vec![t(1.0), t(2.0), t(3.0), t(4.0)]).unwrap();
        assert_eq!(m.lookup([0.25, 0.25]), t(1.0));
        assert_eq!(m.lookup([0.75, 0.75]), t(4.0));
        // Halfway between the two columns of the top row; at s = 0 the left and right edges blend.
        assert!((m.lookup([0.5, 0.25]).x - 1.5).abs() < 1e-6);
        assert!((m.lookup([0.0, 0.25]).x - 1.5).abs() < 1e-6);
        assert!((m.mean().x - 2.5).abs() < 1e-6);
    }

    #[test]
    fn resampling_keeps_a_constant_map_constant() {
        let m = EnvMap::new(3, 5, vec![Spectrum::splat(0.7); 15]).unwrap();
        assert_eq!((m.width(), m.height()), (4, 8));
        for y in 0..8 {
            for x in 0..4 {
                let st = [(x as f32 + 0.5) / 4.0, (y as f32 + 0.5) / 8.0];
                assert!((m.lookup(st).x - 0.7).abs() < 1e-5);
            }
        }
        assert!(EnvMap::new(0, 3, vec![]).is_none());
    }
}
