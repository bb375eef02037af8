//! STAGE 5 (shading): the texel grid of an environment map as pbrt-v3's `InfiniteAreaLight` keeps it —
//! resampled to power-of-two sides with its Lanczos filter when needed (as its `MIPMap` does, negative
//! results clamped to 0), looked up bilinearly at the finest level with repeat wrapping.
//!
//! Depends only on the shading `Spectrum`; never on the scene or the renderer.

use crate::shading::Spectrum;

/// A width×height grid of RGB texels, row 0 at the top (θ = 0).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMap {
    width: usize,
    height: usize,
    texels: Vec<Spectrum>,
}

impl EnvMap {
    /// A 1×1 map of constant `l`.
    pub fn constant(l: Spectrum) -> Self {
        EnvMap { width: 1, height: 1, texels: vec![l] }
    }

    /// The map of `texels` (row-major, `width`×`height`, both ≥ 1), resampled to power-of-two sides
    /// as pbrt-v3 does.
    pub fn new(width: usize, height: usize, texels: Vec<Spectrum>) -> Self {
        debug_assert_eq!(texels.len(), width * height);
        if width.is_power_of_two() && height.is_power_of_two() {
            return EnvMap { width, height, texels };
        }
        let (w2, h2) = (width.next_power_of_two(), height.next_power_of_two());
        // Rows first (s), then columns (t), each with 4-tap Lanczos weights and repeat wrapping.
        let sw = resample_weights(width, w2);
        let mut rows = vec![Spectrum::ZERO; w2 * height];
        for t in 0..height {
            for (s, (first, w)) in sw.iter().enumerate() {
                let mut acc = Spectrum::ZERO;
                for (j, wj) in w.iter().enumerate() {
                    let o = (first + j as i64).rem_euclid(width as i64) as usize;
                    acc += *wj * texels[t * width + o];
                }
                rows[t * w2 + s] = acc;
            }
        }
        let tw = resample_weights(height, h2);
        let mut out = vec![Spectrum::ZERO; w2 * h2];
        for s in 0..w2 {
            for (t, (first, w)) in tw.iter().enumerate() {
                let mut acc = Spectrum::ZERO;
                for (j, wj) in w.iter().enumerate() {
                    let o = (first + j as i64).rem_euclid(height as i64) as usize;
                    acc += *wj * rows[o * w2 + s];
                }
                out[t * w2 + s] = acc.max(Spectrum::ZERO);
            }
        }
        EnvMap { width: w2, height: h2, texels: out }
    }

    /// Number of columns (after resampling).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Number of rows (after resampling).
    pub fn height(&self) -> usize {
        self.height
    }

    #[inline]
    fn texel(&self, s: i64, t: i64) -> Spectrum {
        let s = s.rem_euclid(self.width as i64) as usize;
        let t = t.rem_euclid(self.height as i64) as usize;
        self.texels[t * self.width + s]
    }

    /// Bilinear lookup at (s, t) ∈ [0, 1]² with repeat wrapping (pbrt-v3 `MIPMap::triangle` at level 0).
    #[inline]
    pub fn lookup(&self, st: [f32; 2]) -> Spectrum {
        let s = st[0] * self.width as f32 - 0.5;
        let t = st[1] * self.height as f32 - 0.5;
        let (s0, t0) = (s.floor(), t.floor());
        let (ds, dt) = (s - s0, t - t0);
        let (s0, t0) = (s0 as i64, t0 as i64);
        (1.0 - ds) * (1.0 - dt) * self.texel(s0, t0)
            + (1.0 - ds) * dt * self.texel(s0, t0 + 1)
            + ds * (1.0 - dt) * self.texel(s0 + 1, t0)
            + ds * dt * self.texel(s0 + 1, t0 + 1)
    }

    /// The mean texel (pbrt-v3's `Power` looks up the 1×1/2×1 MIP level, which is this mean).
    pub fn mean(&self) -> Spectrum {
        let sum: glam::DVec3 = self.texels.iter().map(|t| glam::DVec3::new(t.x as f64, t.y as f64, t.z as f64)).sum();
        let m = sum / self.texels.len() as f64;
        Spectrum::new(m.x as f32, m.y as f32, m.z as f32)
    }
}

/// Luminance of an RGB value (pbrt-v3 `RGBSpectrum::y`).
#[inline]
pub fn luminance(c: Spectrum) -> f32 {
    0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z
}

/// pbrt-v3's `MIPMap::resampleWeights`: for each new texel, the first old texel and 4 normalised Lanczos
/// weights (filter width 2, τ = 2).
fn resample_weights(old: usize, new: usize) -> Vec<(i64, [f32; 4])> {
    let filter_width = 2.0f32;
    (0..new)
        .map(|i| {
            let center = (i as f32 + 0.5) * old as f32 / new as f32;
            let first = ((center - filter_width) + 0.5).floor() as i64;
            let mut w = [0.0f32; 4];
            for (j, wj) in w.iter_mut().enumerate() {
                let pos = first as f32 + j as f32 + 0.5;
                *wj = lanczos((pos - center) / filter_width, 2.0);
            }
            let sum: f32 = w.iter().sum();
            (first, w.map(|x| x / sum))
        })
        .collect()
}

/// pbrt-v3's windowed sinc `Lanczos(x, τ)`.
fn lanczos(x: f32, tau: f32) -> f32 {
    let x = x.abs();
    if x < 1e-5 {
        return 1.0;
    }
    if x > 1.0 {
        return 0.0;
    }
    let x = x * std::f32::consts::PI;
    let s = (x * tau).sin() / (x * tau);
    s * x.sin() / x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_lookup_hits_texel_centres_and_wraps() {
        let t = |v: f32| Spectrum::splat(v);
        let m = EnvMap::new(2, 2, vec![t(1.0), t(2.0), t(3.0), t(4.0)]);
        assert_eq!(m.lookup([0.25, 0.25]), t(1.0));
        assert_eq!(m.lookup([0.75, 0.75]), t(4.0));
        // Halfway between the two columns of the top row; at s = 0 the left and right edges blend.
        assert!((m.lookup([0.5, 0.25]).x - 1.5).abs() < 1e-6);
        assert!((m.lookup([0.0, 0.25]).x - 1.5).abs() < 1e-6);
        assert!((m.mean().x - 2.5).abs() < 1e-6);
    }

    #[test]
    fn resampling_keeps_a_constant_map_constant() {
        let m = EnvMap::new(3, 5, vec![Spectrum::splat(0.7); 15]);
        assert_eq!((m.width(), m.height()), (4, 8));
        for y in 0..8 {
            for x in 0..4 {
                assert!((m.texel(x, y).x - 0.7).abs() < 1e-5);
            }
        }
    }
}
